//! Helpers shared by the integration tests (a module that needs them says
//! `use crate::support as common;`).
//!
//! A seeded generator for test inputs ([`Rng`]); scene files under the target's temporary
//! directory ([`target_dir`], [`write_scene`], [`scratch`]) or a self-removing [`TempDir`];
//! in-process renders on the current thread pool ([`render_scene`]: the file's settings after a
//! tweak, on Embree; [`render_on`]: given settings on a given backend; [`render_with`]: a size,
//! seed and thread count) and their [`pixels`] and [`relmse`]; the shared [`CORNELL`] box and
//! the cube that several scenes are built around ([`CUBE`]); and
//! runs of the `photon` binary on hostile input: a run under an
//! address-space cap (`prlimit --as`) and a timeout, and the checks every such run must pass
//! (exit 0 or 2; on 2 exactly one stderr line that says where the problem is; no panic, no
//! signal death).
use std::ffi::OsString;
use std::io::Read;
use std::os::unix::process::ExitStatusExt;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::sync::atomic::{AtomicU32, Ordering};
use std::time::{Duration, Instant};

/// 1 GiB: the address-space cap of most runs (photon's own budget follows it).
pub const GIB: u64 = 1 << 30;

/// What a capped run did.
#[derive(Debug)]
pub struct Run {
    pub code: Option<i32>,
    pub signal: Option<i32>,
    pub stdout: String,
    pub stderr: String,
    pub timed_out: bool,
    pub seconds: f64,
}

impl Run {
    /// The run's outcome in one line, for assertion messages.
    pub fn describe(&self) -> String {
        let err: String = self.stderr.chars().take(600).collect();
        format!(
            "exit {:?} signal {:?} timed out {} after {:.1} s; stderr: {err}",
            self.code, self.signal, self.timed_out, self.seconds
        )
    }
}

/// A fresh directory under the target's temporary directory (for the hostile-input tests).
pub fn tmp_dir(name: &str) -> PathBuf {
    scratch("hostile", name)
}

/// A fresh directory `group/name` under the target's temporary directory.
pub fn scratch(group: &str, name: &str) -> PathBuf {
    let dir = PathBuf::from(env!("CARGO_TARGET_TMPDIR"))
        .join(group)
        .join(name);
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// `group` under the target's temporary directory, created if missing and otherwise kept as it
/// is (the files of a group's tests accumulate there; [`scratch`] gives a fresh directory).
pub fn target_dir(group: &str) -> PathBuf {
    let dir = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join(group);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// Writes `text` as `name.pbrt` in [`target_dir`]`(group)` and returns its path.
pub fn write_scene(group: &str, name: &str, text: &str) -> PathBuf {
    let path = target_dir(group).join(format!("{name}.pbrt"));
    std::fs::write(&path, text).unwrap();
    path
}

/// A command running this build's `photon` binary.
pub fn photon() -> Command {
    Command::new(env!("CARGO_BIN_EXE_photon"))
}

/// Runs `photon ARGS` with its address space capped at `mem` bytes, killed after `timeout`.
pub fn run_capped<I, S>(args: I, mem: u64, timeout: Duration) -> Run
where
    I: IntoIterator<Item = S>,
    S: Into<OsString>,
{
    let mut cmd = Command::new("prlimit");
    cmd.arg(format!("--as={mem}"))
        .arg("--")
        .arg(env!("CARGO_BIN_EXE_photon"))
        .args(args.into_iter().map(Into::into))
        .env("RUST_BACKTRACE", "0")
        .stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped());
    let start = Instant::now();
    let mut child = cmd.spawn().expect("prlimit and photon run");
    let mut out_pipe = child.stdout.take().unwrap();
    let mut err_pipe = child.stderr.take().unwrap();
    let out_t = std::thread::spawn(move || {
        let mut s = Vec::new();
        let _ = out_pipe.read_to_end(&mut s);
        s
    });
    let err_t = std::thread::spawn(move || {
        let mut s = Vec::new();
        let _ = err_pipe.read_to_end(&mut s);
        s
    });
    let mut timed_out = false;
    let status = loop {
        if let Some(st) = child.try_wait().unwrap() {
            break st;
        }
        if start.elapsed() > timeout {
            timed_out = true;
            let _ = child.kill();
            break child.wait().unwrap();
        }
        std::thread::sleep(Duration::from_millis(5));
    };
    let text = |v: Vec<u8>| String::from_utf8_lossy(&v).into_owned();
    Run {
        code: status.code(),
        signal: status.signal(),
        stdout: text(out_t.join().unwrap()),
        stderr: text(err_t.join().unwrap()),
        timed_out,
        seconds: start.elapsed().as_secs_f64(),
    }
}

/// `photon render SCENE --res 8x8 --spp 1` with few photons, output in `out_dir`, plus `extra`.
/// A default given in `extra` is left out.
pub fn render_args(scene: &Path, out_dir: &Path, extra: &[&str]) -> Vec<OsString> {
    let mut v: Vec<OsString> = vec!["render".into(), scene.into()];
    for (flag, value) in [
        ("--res", "8x8"),
        ("--spp", "1"),
        ("--global-photons", "2000"),
        ("--caustic-photons", "2000"),
        ("--threads", "1"),
    ] {
        if !extra.contains(&flag) {
            v.push(flag.into());
            v.push(value.into());
        }
    }
    v.push("--no-png".into());
    v.push("-o".into());
    v.push(out_dir.join("out.exr").into());
    v.extend(extra.iter().map(OsString::from));
    v
}

/// Whether `line` says where the problem is: `file:line:col`, a command-line flag, or the
/// file (the scene file, or a main file that cannot be read).
pub fn has_location(line: &str) -> bool {
    has_file_line_col(line)
        || line.contains("'--")
        || line.starts_with("photon: -o ")
        || line.starts_with("photon: --")
        || line.contains(".pbrt: ")
        || line.contains(".exr: ")
        || line.contains("cannot read \"")
}

/// Whether `line` contains `:N:M:` (a `file:line:column`).
pub fn has_file_line_col(line: &str) -> bool {
    let b = line.as_bytes();
    (0..b.len()).any(|i| {
        let digits = |mut j: usize| {
            let s = j;
            while j < b.len() && b[j].is_ascii_digit() {
                j += 1;
            }
            (j > s).then_some(j)
        };
        b[i] == b':'
            && digits(i + 1)
                .filter(|&j| b.get(j) == Some(&b':'))
                .and_then(|j| digits(j + 1))
                .is_some_and(|k| b.get(k) == Some(&b':'))
    })
}

/// The checks of every hostile run: not killed by a signal, no timeout, no panic (101), exit
/// 0 or 2, and on 2 exactly one stderr line, with a location, no control bytes.
pub fn check_run(r: &Run) -> Result<(), String> {
    if r.timed_out {
        return Err(format!("timed out: {}", r.describe()));
    }
    if let Some(s) = r.signal {
        return Err(format!("killed by signal {s}: {}", r.describe()));
    }
    match r.code {
        Some(0) => Ok(()),
        Some(2) => {
            // Progress lines (a long run without a terminal) are not part of the error.
            let lines: Vec<&str> = (r.stderr.lines())
                .filter(|l| !l.starts_with("progress: "))
                .collect();
            if lines.len() != 1 {
                return Err(format!("{} stderr lines: {}", lines.len(), r.describe()));
            }
            if lines[0].chars().any(|c| c.is_control()) {
                return Err(format!("control characters: {}", r.describe()));
            }
            // One readable line (issue 22, case 19: lines of 599-1012 bytes).
            if lines[0].len() > 200 {
                return Err(format!("{} bytes: {}", lines[0].len(), r.describe()));
            }
            if !has_location(lines[0]) {
                return Err(format!("no location: {}", r.describe()));
            }
            Ok(())
        }
        _ => Err(format!("bad exit: {}", r.describe())),
    }
}

/// Asserts a run failed with exit 2 and one located line containing every one of `needles`.
pub fn assert_error(r: &Run, needles: &[&str]) {
    assert_eq!(r.code, Some(2), "{}", r.describe());
    check_run(r).unwrap_or_else(|e| panic!("{e}"));
    for n in needles {
        assert!(r.stderr.contains(n), "missing {n:?}: {}", r.describe());
    }
}

/// The repository's and the shared scenes (`scenes/*.pbrt`, `../shared/scenes/*/*.pbrt`).
pub fn all_scenes() -> Vec<PathBuf> {
    let mut v = Vec::new();
    for pattern_dir in ["scenes", "../shared/scenes"] {
        let Ok(rd) = std::fs::read_dir(pattern_dir) else {
            continue;
        };
        let mut entries: Vec<PathBuf> = rd.filter_map(|e| e.ok()).map(|e| e.path()).collect();
        entries.sort();
        for p in entries {
            if p.extension().is_some_and(|e| e == "pbrt") {
                v.push(p);
            } else if p.is_dir() {
                let mut inner: Vec<PathBuf> = std::fs::read_dir(&p)
                    .unwrap()
                    .filter_map(|e| e.ok())
                    .map(|e| e.path())
                    .filter(|q| q.extension().is_some_and(|e| e == "pbrt"))
                    .collect();
                inner.sort();
                v.extend(inner);
            }
        }
    }
    v
}

/// A small scene text (camera looking down -z at a floor and a back wall lit by a quad facing
/// down), with `world` appended after WorldBegin (on line 12).
pub fn small_scene(world: &str) -> String {
    format!(
        r#"LookAt 0 1 3.5  0 1 0  0 1 0
Camera "perspective" "float fov" [ 45 ]
Film "rgb" "integer xresolution" [ 8 ] "integer yresolution" [ 8 ]
WorldBegin
Material "diffuse" "rgb reflectance" [ 0.5 0.5 0.5 ]
Shape "trianglemesh" "point3 P" [ -1 0 -1  1 0 -1  1 0 1  -1 0 1 ] "integer indices" [ 0 1 2 0 2 3 ]
Shape "trianglemesh" "point3 P" [ -1 0 -1  -1 2 -1  1 2 -1  1 0 -1 ] "integer indices" [ 0 1 2 0 2 3 ]
AttributeBegin
AreaLightSource "diffuse" "rgb L" [ 5 5 5 ]
Shape "trianglemesh" "point3 P" [ -0.3 1.99 -0.3  0.3 1.99 -0.3  0.3 1.99 0.3  -0.3 1.99 0.3 ] "integer indices" [ 0 1 2 0 2 3 ]
AttributeEnd
{world}
"#
    )
}

/// A scratch directory under the system temp dir, removed when dropped.
pub struct TempDir(pub PathBuf);

impl TempDir {
    /// A fresh directory named after `prefix`, the process and a counter.
    pub fn new(prefix: &str) -> TempDir {
        static N: AtomicU32 = AtomicU32::new(0);
        let n = N.fetch_add(1, Ordering::SeqCst);
        let dir = std::env::temp_dir().join(format!("{prefix}-{}-{n}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).unwrap();
        TempDir(dir)
    }

    /// Writes `contents` to `name` (creating subdirectories) and returns its path.
    pub fn write(&self, name: &str, contents: impl AsRef<[u8]>) -> PathBuf {
        let p = self.0.join(name);
        std::fs::create_dir_all(p.parent().unwrap()).unwrap();
        std::fs::write(&p, contents).unwrap();
        p
    }
}

impl Drop for TempDir {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.0);
    }
}

/// SplitMix64: a small seeded generator for test inputs.
pub struct Rng(pub u64);

impl Rng {
    pub fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }

    /// Uniform in `0..n` (0 when `n` is 0).
    pub fn below(&mut self, n: usize) -> usize {
        (self.next_u64() % n.max(1) as u64) as usize
    }

    /// Uniform in [0, 1).
    pub fn f(&mut self) -> f32 {
        (self.next_u64() >> 40) as f32 / (1u64 << 24) as f32
    }

    pub fn range(&mut self, lo: f32, hi: f32) -> f32 {
        lo + (hi - lo) * self.f()
    }

    /// Uniform direction on the unit sphere.
    pub fn dir(&mut self) -> photon::math::Vec3 {
        let z = self.range(-1.0, 1.0);
        let phi = self.range(0.0, std::f32::consts::TAU);
        let r = (1.0 - z * z).max(0.0).sqrt();
        photon::math::Vec3::new(r * phi.cos(), r * phi.sin(), z)
    }
}

/// The shared Cornell box (pbrt-v4 file), relative to the crate root.
pub const CORNELL: &str = "../shared/scenes/cornell-box/scene-v4.pbrt";

/// The six faces of the cube [-1, 1]^3 as a pbrt-v4 `trianglemesh`, wound so their normals
/// point outwards.
pub const CUBE: &str = r#"Shape "trianglemesh" "point3 P" [
  -1 -1 -1  1 -1 -1  1 1 -1  -1 1 -1
  -1 -1 1  1 -1 1  1 1 1  -1 1 1 ]
  "integer indices" [ 0 2 1 0 3 2  4 5 6 4 6 7  0 1 5 0 5 4  3 7 6 3 6 2  0 4 7 0 7 3  1 2 6 1 6 5 ]"#;

/// Renders `scene` with `kind` on `backend` at `w x h`, `spp` samples, sample streams of run
/// `seed`, on `threads` threads (0 = all).
pub fn render_with(
    scene: &photon::scene::Scene,
    kind: photon::integrator::IntegratorKind,
    backend: photon::accel::BackendKind,
    (w, h, spp): (u32, u32, u32),
    threads: usize,
    seed: u64,
) -> photon::integrator::RenderOutput {
    let overrides = photon::tools::job::Overrides {
        res: Some((w, h)),
        spp: Some(spp),
        seed,
        ..Default::default()
    };
    let mut job = job(scene, kind, backend).with(&overrides);
    job.threads = threads;
    let pool = job.pool().expect("thread pool");
    let (accel, _) = job.build(&pool).expect("accel builds");
    job.render(&accel, &pool, &|_, _| {})
}

/// The render job of `scene` (borrowed) with `kind` on `backend`, at the file's settings.
pub fn job(
    scene: &photon::scene::Scene,
    kind: photon::integrator::IntegratorKind,
    backend: photon::accel::BackendKind,
) -> photon::tools::job::Job<'_> {
    let mut job = photon::tools::job::Job::borrowing(scene).expect("integrator settings");
    (job.integrator, job.backend) = (kind, backend);
    job
}

/// The render settings of `scene` as its file gives them, after `tweak`.
pub fn scene_settings(
    scene: &photon::scene::Scene,
    tweak: impl FnOnce(&mut photon::integrator::RenderSettings),
) -> photon::integrator::RenderSettings {
    let mut settings =
        photon::integrator::RenderSettings::from_scene(scene).expect("integrator settings");
    tweak(&mut settings);
    settings
}

/// Renders `scene` with `kind` and `settings` on `backend`, on the current thread pool.
pub fn render_on(
    scene: &photon::scene::Scene,
    kind: photon::integrator::IntegratorKind,
    backend: photon::accel::BackendKind,
    settings: &photon::integrator::RenderSettings,
) -> photon::integrator::RenderOutput {
    use photon::accel::{Accel, AccelOptions};
    let accel = Accel::build(scene, backend, AccelOptions::default()).expect("accel builds");
    photon::integrator::render(scene, &accel, settings, kind, &|_, _| {})
}

/// Renders `scene` with `kind` on Embree, on the current thread pool, at the file's settings
/// after `tweak` (`|_| {}` for none).
pub fn render_scene(
    scene: &photon::scene::Scene,
    kind: photon::integrator::IntegratorKind,
    tweak: impl FnOnce(&mut photon::integrator::RenderSettings),
) -> photon::integrator::RenderOutput {
    let settings = scene_settings(scene, tweak);
    render_on(scene, kind, photon::accel::BackendKind::Embree, &settings)
}

/// The pixels of `image` in row-major order.
pub fn pixels(image: &photon::imageio::RgbImage) -> Vec<photon::math::Vec3> {
    let pixels = image.pixels.iter();
    pixels.map(|p| photon::math::Vec3::from_array(*p)).collect()
}

/// relMSE of `image` against `reference` over all pixels (`photon::imageio::metrics`, default
/// mask options).
pub fn relmse(image: &photon::imageio::RgbImage, reference: &photon::imageio::RgbImage) -> f64 {
    use photon::imageio::metrics::{compare, MaskOptions};
    compare(image, reference, MaskOptions::default())
        .expect("images of one size")
        .overall
        .relmse
}

/// Renders the repository's `scene` (a path relative to the crate root) with the default
/// integrator at `res` (`WxH`) and `spp` into `dir/name`, asserting success; returns the EXR.
#[allow(dead_code)]
pub fn render_repo_scene(scene: &str, res: &str, spp: u32, dir: &TempDir, name: &str) -> PathBuf {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
    let out = dir.0.join(name);
    let run = photon()
        .args([
            "render",
            "--res",
            res,
            "--spp",
            &spp.to_string(),
            "--no-png",
            "-o",
        ])
        .arg(&out)
        .arg(root.join(scene))
        .output()
        .unwrap();
    assert!(
        run.status.success(),
        "{}",
        String::from_utf8_lossy(&run.stderr)
    );
    out
}

/// Luminance ratio of `image` to `reference` (row-major `w` wide) over the whole image and
/// over each block of an `n x n` grid, row by row.
#[allow(dead_code)]
pub fn block_ratios(
    image: &[photon::math::Vec3],
    reference: &[photon::math::Vec3],
    w: usize,
    n: usize,
) -> (f64, Vec<f64>) {
    let h = image.len() / w;
    let lum = |v: &photon::math::Vec3| (v.x + v.y + v.z) as f64 / 3.0;
    let mean = image.iter().map(lum).sum::<f64>() / reference.iter().map(lum).sum::<f64>();
    let mut blocks = vec![];
    for by in 0..n {
        for bx in 0..n {
            let (mut s, mut r) = (0.0, 0.0);
            for y in by * h / n..(by + 1) * h / n {
                for x in bx * w / n..(bx + 1) * w / n {
                    s += lum(&image[y * w + x]);
                    r += lum(&reference[y * w + x]);
                }
            }
            blocks.push(s / r);
        }
    }
    (mean, blocks)
}

/// The photon mapper against our path tracer on one scene: `scene(integrator, spp)` is
/// written into `dir` and rendered with `path_spp` and `photonmap_spp` samples; returns the
/// mean luminance ratio and the smallest and largest ratio of the 4x4 blocks (32 px wide
/// images), after printing them.
#[allow(dead_code)]
pub fn photonmap_against_path(
    dir: &TempDir,
    scene: impl Fn(&str, u32) -> String,
    path_spp: u32,
    photonmap_spp: u32,
) -> (f64, f64, f64) {
    use photon::integrator::IntegratorKind;
    let path = dir.write("path.pbrt", scene("path", path_spp));
    let reference = render_file(&path, IntegratorKind::Path);
    let pm = dir.write("pm.pbrt", scene("photonmap", photonmap_spp));
    let image = render_file(&pm, IntegratorKind::Photonmap);
    let (mean, blocks) = block_ratios(&image, &reference, 32, 4);
    let (lo, hi) = blocks
        .iter()
        .fold((f64::MAX, 0.0f64), |(lo, hi), &b| (lo.min(b), hi.max(b)));
    println!("mean ratio {mean:.4}, blocks {lo:.3}..{hi:.3}: {blocks:.3?}");
    (mean, lo, hi)
}

/// The pixels of the scene file at `path` rendered with `kind` and the file's own settings
/// (Embree).
#[allow(dead_code)]
pub fn render_file(
    path: &Path,
    kind: photon::integrator::IntegratorKind,
) -> Vec<photon::math::Vec3> {
    let scene = photon::scene::loader::load(path).unwrap_or_else(|e| panic!("{e}"));
    pixels(&render_scene(&scene, kind, |_| {}).image)
}

/// Makes a FIFO at `path` (with `mkfifo`).
pub fn mkfifo(path: &Path) {
    let ok = Command::new("mkfifo").arg(path).status().unwrap().success();
    assert!(ok, "mkfifo {}", path.display());
}

/// Whether `path` is a FIFO (not followed if it is a symlink).
pub fn is_fifo(path: &Path) -> bool {
    use std::os::unix::fs::FileTypeExt;
    std::fs::symlink_metadata(path).is_ok_and(|m| m.file_type().is_fifo())
}

/// Reads the FIFO `path` to its end in a thread; the bytes arrive on the channel. A test waits
/// with `recv_timeout` (a writer that never comes leaves the thread blocked, not the test).
pub fn fifo_reader(path: &Path) -> std::sync::mpsc::Receiver<Vec<u8>> {
    let (tx, rx) = std::sync::mpsc::channel();
    let p = path.to_path_buf();
    std::thread::spawn(move || {
        if let Ok(bytes) = std::fs::read(p) {
            let _ = tx.send(bytes);
        }
    });
    rx
}

/// The files in the system's temporary directory whose names start with `prefix`.
pub fn temp_files_starting_with(prefix: &str) -> Vec<PathBuf> {
    let mut v: Vec<PathBuf> = std::fs::read_dir(std::env::temp_dir())
        .unwrap()
        .filter_map(|e| e.ok())
        .filter(|e| e.file_name().to_string_lossy().starts_with(prefix))
        .map(|e| e.path())
        .collect();
    v.sort();
    v
}

/// A `photon` run in the background (stdin null, stdout and stderr piped), for tests that act
/// while it runs: wait for a line on stdout, send a signal, then collect the [`Run`].
pub struct Background {
    child: std::process::Child,
    lines: std::io::Lines<std::io::BufReader<std::process::ChildStdout>>,
    stdout: String,
    stderr: std::thread::JoinHandle<Vec<u8>>,
    start: Instant,
}

impl Background {
    /// Starts `photon ARGS`.
    pub fn start<I, S>(args: I) -> Background
    where
        I: IntoIterator<Item = S>,
        S: Into<OsString>,
    {
        use std::io::BufRead;
        let mut child = photon()
            .args(args.into_iter().map(Into::into))
            .env("RUST_BACKTRACE", "0")
            .stdin(Stdio::null())
            .stdout(Stdio::piped())
            .stderr(Stdio::piped())
            .spawn()
            .expect("photon runs");
        let lines = std::io::BufReader::new(child.stdout.take().unwrap()).lines();
        let mut err_pipe = child.stderr.take().unwrap();
        let stderr = std::thread::spawn(move || {
            let mut s = Vec::new();
            let _ = err_pipe.read_to_end(&mut s);
            s
        });
        Background {
            child,
            lines,
            stdout: String::new(),
            stderr,
            start: Instant::now(),
        }
    }

    pub fn pid(&self) -> u32 {
        self.child.id()
    }

    /// Reads stdout until a line starting with `prefix`; false when stdout ends first.
    pub fn wait_for_line(&mut self, prefix: &str) -> bool {
        for line in self.lines.by_ref() {
            let Ok(line) = line else { return false };
            self.stdout += &line;
            self.stdout.push('\n');
            if line.starts_with(prefix) {
                return true;
            }
        }
        false
    }

    /// Sends signal `name` (`TERM`, `INT`) with `kill`.
    pub fn signal(&self, name: &str) {
        let ok = Command::new("kill")
            .arg(format!("-{name}"))
            .arg(self.pid().to_string())
            .status()
            .unwrap()
            .success();
        assert!(ok, "kill -{name}");
    }

    /// Waits for the process (killed after `timeout`) and collects what it printed.
    pub fn finish(mut self, timeout: Duration) -> Run {
        let mut lines = self.lines;
        let rest = std::thread::spawn(move || {
            let mut s = String::new();
            for l in lines.by_ref().map_while(Result::ok) {
                s += &l;
                s.push('\n');
            }
            s
        });
        let mut timed_out = false;
        let status = loop {
            if let Some(st) = self.child.try_wait().unwrap() {
                break st;
            }
            if self.start.elapsed() > timeout {
                timed_out = true;
                let _ = self.child.kill();
                break self.child.wait().unwrap();
            }
            std::thread::sleep(Duration::from_millis(5));
        };
        Run {
            code: status.code(),
            signal: status.signal(),
            stdout: self.stdout + &rest.join().unwrap(),
            stderr: String::from_utf8_lossy(&self.stderr.join().unwrap()).into_owned(),
            timed_out,
            seconds: self.start.elapsed().as_secs_f64(),
        }
    }
}

/// The `photon.*` attributes and the `sum.<component>.hi/lo` layers of a partial image.
pub type PartialParts = (Vec<(String, String)>, Vec<(String, Vec<[u32; 3]>)>);

/// Writes a forged copy of partial image `src` to `dst`: its attributes and sum layers passed
/// through `edit` (which may change, add or drop any); the RGB image is copied. The writer's
/// error (a NUL in a value, say) is returned.
pub fn forge_partial(
    src: &Path,
    dst: &Path,
    edit: impl FnOnce(&mut PartialParts),
) -> Result<(), photon::imageio::ImageError> {
    use photon::imageio::{read_exr, read_exr_attributes, read_exr_uint_layer, write_exr_with};
    let rgb = read_exr(src)?;
    let mut attrs = read_exr_attributes(src)?;
    attrs.retain(|(k, _)| k.starts_with("photon."));
    let mut layers = Vec::new();
    for c in photon::film::Component::NAMES {
        for half in ["hi", "lo"] {
            let name = format!("sum.{c}.{half}");
            let words = read_exr_uint_layer(src, &name)?.2;
            layers.push((name, words));
        }
    }
    let mut parts = (attrs, layers);
    edit(&mut parts);
    let (attrs, layers) = parts;
    let uint: Vec<(&str, &[[u32; 3]])> = layers.iter().map(|(n, w)| (n.as_str(), &w[..])).collect();
    let attributes: Vec<(&str, &str)> = attrs
        .iter()
        .map(|(k, v)| (k.as_str(), v.as_str()))
        .collect();
    let extra = photon::imageio::ExrExtra {
        uint_layers: &uint,
        attributes: &attributes,
        ..Default::default()
    };
    write_exr_with(dst, &rgb, &[], photon::imageio::ExrPixel::Float, extra)
}

/// Renders `path` with the direct-lighting integrator on `backend` and returns, per pixel in
/// row-major order, the rendered value and the point of the plane y = 0 that the ray through
/// the pixel's centre meets (scenes that look at a floor).
pub fn render_floor(
    path: &Path,
    backend: photon::accel::BackendKind,
) -> (
    photon::scene::Scene,
    Vec<(photon::math::Vec3, photon::math::Vec3)>,
) {
    let kind = photon::integrator::IntegratorKind::Direct;
    render_floor_with(path, backend, kind, |_| {})
}

/// [`render_floor`] with integrator `kind` and the file's settings changed by `tweak`.
pub fn render_floor_with(
    path: &Path,
    backend: photon::accel::BackendKind,
    kind: photon::integrator::IntegratorKind,
    tweak: impl FnOnce(&mut photon::integrator::RenderSettings),
) -> (
    photon::scene::Scene,
    Vec<(photon::math::Vec3, photon::math::Vec3)>,
) {
    use photon::math::{Vec2, Vec3};
    let scene = photon::scene::loader::load(path).unwrap_or_else(|e| panic!("{e}"));
    let settings = scene_settings(&scene, tweak);
    let out = render_on(&scene, kind, backend, &settings);
    let cam = photon::camera::Camera::new(&scene.camera, settings.width, settings.height);
    let mut px = Vec::new();
    for y in 0..settings.height {
        for x in 0..settings.width {
            let ray = cam.generate_ray(Vec2::new(x as f32 + 0.5, y as f32 + 0.5));
            let p = ray.at(-ray.o.y / ray.d.y);
            let v = out.image.pixels[(y * settings.width + x) as usize];
            px.push((Vec3::from_array(v), p));
        }
    }
    (scene, px)
}

/// The six walls of a closed room 4 x 2.5 x 4 (x, z in [-2, 2], y in [0, 2.5]), facing in,
/// for scenes written with `format!` (`{room}` after `WorldBegin` and a `Material`).
pub const CLOSED_ROOM: &str = r#"Shape "trianglemesh" "point3 P" [ -2 0 -2  2 0 -2  2 0 2  -2 0 2 ] "integer indices" [ 0 2 1 0 3 2 ]
Shape "trianglemesh" "point3 P" [ -2 2.5 -2  2 2.5 -2  2 2.5 2  -2 2.5 2 ] "integer indices" [ 0 1 2 0 2 3 ]
Shape "trianglemesh" "point3 P" [ -2 0 2  2 0 2  2 2.5 2  -2 2.5 2 ] "integer indices" [ 0 1 2 0 2 3 ]
Shape "trianglemesh" "point3 P" [ -2 0 -2  2 0 -2  2 2.5 -2  -2 2.5 -2 ] "integer indices" [ 0 2 1 0 3 2 ]
Shape "trianglemesh" "point3 P" [ 2 0 -2  2 0 2  2 2.5 2  2 2.5 -2 ] "integer indices" [ 0 2 1 0 3 2 ]
Shape "trianglemesh" "point3 P" [ -2 0 -2  -2 0 2  -2 2.5 2  -2 2.5 -2 ] "integer indices" [ 0 1 2 0 2 3 ]
"#;

/// The image of a render's EXR as bits: R, G, B and the four component layers, pixel by
/// pixel (the header, with its render time, left out), for "same image" comparisons.
pub fn exr_image_bits(path: &Path) -> Vec<u32> {
    let mut bits = Vec::new();
    let mut add = |img: photon::imageio::RgbImage| {
        bits.extend(img.pixels.iter().flatten().map(|v| v.to_bits()));
    };
    add(photon::imageio::read_exr(path).unwrap_or_else(|e| panic!("{e}")));
    for layer in photon::film::Component::NAMES {
        add(photon::imageio::read_exr_layer(path, layer).unwrap_or_else(|e| panic!("{e}")));
    }
    bits
}
