//! A deterministic mutation fuzzer over the repository's and the shared scenes and PLY files.
//!
//! Each case takes one seed file (a scene, one PLY of a scene that uses it, the header of such
//! a PLY, one of the image files of a generated textured scene: PNG, TGA, RGBA-half EXR, PFM
//! and an EXR environment map, or a partial image of a progressive render), applies one to
//! three mutations chosen by a hash of the case number (byte flips, token swaps, numbers
//! replaced by extremes such as 1e38, -0, NaN, huge integers, truncation, duplication of a
//! run of lines; for binary files also header words set to extremes; for partial images also
//! forged `photon.*` attributes and sum words, or a layer left out) and runs `photon render` on
//! it at 8x8 pixels, 1 spp and a few hundred photons (a partial image: `photon merge`, or
//! `render --resume`) under a 1 GiB address-space cap and a timeout. Every run must exit 0 or 2; on 2 with
//! exactly one stderr line that says where the problem is; never a panic (101), an abort or
//! another signal, or a hang. Failing inputs are kept in `target/tmp/fuzz/failures/`.
//!
//! `cargo test --release --test it fuzz::` runs [`CASES`] cases; the long run,
//! `PHOTON_FUZZ_SECONDS=3600 cargo test --release --test it fuzz::long -- --ignored`, keeps going with
//! new case numbers for that many seconds (default one hour).
use crate::support as common;

use common::*;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::Mutex;
use std::time::{Duration, Instant};

/// Cases of the normal run.
const CASES: u64 = 2000;
/// Case numbers of the long run start here (it never repeats the normal run's).
const LONG_RUN_FIRST_CASE: u64 = 1 << 32;

/// What a case mutates.
#[derive(Clone, Debug)]
enum Target {
    /// The scene file.
    Scene,
    /// One PLY file of the scene; `header_only`: only its header's text.
    Ply { path: PathBuf, header_only: bool },
    /// One image file (by name) of the generated textured scene ([`TEXTURED`]).
    Image(&'static str),
    /// The partial image of a progressive render (merged, or resumed).
    Partial,
}

/// A seed: a scene file and what of it a case mutates.
#[derive(Clone, Debug)]
struct Seed {
    scene: PathBuf,
    target: Target,
}

/// A scene using every image format photon reads as textures and an environment map.
const TEXTURED: &str = r#"LookAt 0 1 3.5  0 1 0  0 1 0
Camera "perspective" "float fov" [ 45 ]
Film "rgb" "integer xresolution" [ 8 ] "integer yresolution" [ 8 ]
WorldBegin
LightSource "infinite" "string filename" "env.exr"
Texture "png" "spectrum" "imagemap" "string filename" "tex.png"
Texture "tga" "spectrum" "imagemap" "string filename" "tex.tga" "string filter" "trilinear"
Texture "exr" "float" "imagemap" "string filename" "tex.exr"
Texture "pfm" "spectrum" "imagemap" "string filename" "tex.pfm"
Texture "mix" "spectrum" "mix" "texture tex1" "png" "texture tex2" "tga" "texture amount" "exr"
Material "diffuse" "texture reflectance" "mix"
Shape "trianglemesh" "point3 P" [ -1 0 -1  1 0 -1  1 0 1  -1 0 1 ] "integer indices" [ 0 1 2 0 2 3 ] "point2 uv" [ 0 0 1 0 1 1 0 1 ]
Material "diffuse" "texture reflectance" "pfm"
Shape "sphere" "float radius" 0.5
"#;

/// The image files of [`TEXTURED`], written into `dir` (small, every format's common layout:
/// 8-bit RGB PNG, 8-bit RGBA TGA, RGBA half EXR, colour PFM, a square EXR environment).
fn write_textured(dir: &Path) {
    use photon::imageio::{write_exr_channels, ExrChannel, ExrCompression, ExrLayout};
    use photon::imageio::{ExrSamples, ExrStored};
    std::fs::write(dir.join("scene.pbrt"), TEXTURED).unwrap();
    let rgb: Vec<u8> = (0..16 * 16 * 3).map(|i| (i * 37 % 256) as u8).collect();
    image::save_buffer(dir.join("tex.png"), &rgb, 16, 16, image::ColorType::Rgb8).unwrap();
    let rgba: Vec<u8> = (0..8 * 8 * 4).map(|i| (i * 53 % 256) as u8).collect();
    image::save_buffer(dir.join("tex.tga"), &rgba, 8, 8, image::ColorType::Rgba8).unwrap();
    let plane: Vec<f32> = (0..64).map(|i| i as f32 / 64.0).collect();
    let exr = |name: &str, channels: &[&str]| {
        let ch: Vec<ExrChannel> = channels
            .iter()
            .map(|name| ExrChannel {
                name,
                stored: ExrStored::Half,
                samples: ExrSamples::F32(&plane),
            })
            .collect();
        let layout = ExrLayout {
            compression: ExrCompression::Zip,
            tile: None,
        };
        write_exr_channels(&dir.join(name), 8, 8, &ch, layout).unwrap();
    };
    exr("tex.exr", &["R", "G", "B", "A"]);
    exr("env.exr", &["R", "G", "B", "A"]);
    let mut pfm = b"PF\n4 4\n-1\n".to_vec();
    for i in 0..48 {
        pfm.extend_from_slice(&(i as f32 / 48.0).to_le_bytes());
    }
    std::fs::write(dir.join("tex.pfm"), pfm).unwrap();
}

/// The image files [`write_textured`] writes.
const IMAGES: [&str; 5] = ["tex.png", "tex.tga", "tex.exr", "tex.pfm", "env.exr"];

/// The scene partial-image cases resume (and whose part they merge).
const PARTIAL_SCENE: &str = "scenes/cornell-glass.pbrt";

/// Arguments of the progressive render that wrote the seed part (and of a resume).
fn partial_args(scene: &Path, passes: &str) -> Vec<String> {
    let scene = scene.display().to_string();
    [
        "render",
        &scene,
        "--res",
        "8x8",
        "--progressive",
        "--pass-spp",
        "1",
        "--passes",
        passes,
        "--global-photons",
        "300",
        "--caustic-photons",
        "300",
        "--threads",
        "1",
        "--no-png",
    ]
    .iter()
    .map(|s| s.to_string())
    .collect()
}

/// The seed partial image (written once per run into `root`).
fn seed_part(root: &Path) -> PathBuf {
    static ONCE: std::sync::Once = std::sync::Once::new();
    let part = root.join("seed-part.exr");
    ONCE.call_once(|| {
        std::fs::create_dir_all(root).unwrap();
        let mut args = partial_args(Path::new(PARTIAL_SCENE), "0..2");
        args.extend(["-o".to_string(), part.display().to_string()]);
        let out = photon().args(&args).output().unwrap();
        assert!(out.status.success(), "{out:?}");
    });
    part
}

/// The scenes; each PLY file of every scene directory with a `meshes/` folder, whole and its
/// header alone; each image of the textured scene; the partial image.
fn seeds() -> Vec<Seed> {
    let mut v = Vec::new();
    for scene in all_scenes() {
        v.push(Seed {
            scene: scene.clone(),
            target: Target::Scene,
        });
        let meshes = scene.parent().unwrap().join("meshes");
        if let Ok(rd) = std::fs::read_dir(&meshes) {
            let mut plys: Vec<PathBuf> = rd
                .filter_map(|e| e.ok())
                .map(|e| e.path())
                .filter(|p| p.extension().is_some_and(|e| e == "ply"))
                .collect();
            plys.sort();
            for p in plys {
                for header_only in [false, true] {
                    v.push(Seed {
                        scene: scene.clone(),
                        target: Target::Ply {
                            path: p.clone(),
                            header_only,
                        },
                    });
                }
            }
        }
    }
    for image in IMAGES {
        v.push(Seed {
            scene: PathBuf::from("textured.pbrt"),
            target: Target::Image(image),
        });
    }
    for _ in 0..3 {
        v.push(Seed {
            scene: PathBuf::from(PARTIAL_SCENE),
            target: Target::Partial,
        });
    }
    assert!(v.len() >= 3, "seed files found: {v:?}");
    v
}

/// Number tokens substituted by [`mutate`].
const EXTREMES: [&str; 14] = [
    "1e38",
    "-1e38",
    "3.4e38",
    "-0",
    "0",
    "NaN",
    "inf",
    "1e-45",
    "2147483647",
    "-2147483648",
    "4294967296",
    "99999999999999999999",
    "1e-30",
    "-1",
];

/// Byte ranges of the whitespace-separated tokens of `b`.
fn tokens(b: &[u8]) -> Vec<(usize, usize)> {
    let mut v = Vec::new();
    let mut i = 0;
    while i < b.len() {
        while i < b.len() && b[i].is_ascii_whitespace() {
            i += 1;
        }
        let s = i;
        while i < b.len() && !b[i].is_ascii_whitespace() {
            i += 1;
        }
        if i > s {
            v.push((s, i));
        }
    }
    v
}

/// One mutation of `b`, chosen by `rng`.
fn mutate(b: &mut Vec<u8>, rng: &mut Rng) {
    if b.is_empty() {
        b.extend(b"WorldBegin");
        return;
    }
    match rng.below(6) {
        0 => {
            let i = rng.below(b.len());
            b[i] = rng.next_u64() as u8;
        }
        1 => {
            let t = tokens(b);
            if t.len() >= 2 {
                let (x, y) = (t[rng.below(t.len())], t[rng.below(t.len())]);
                let (a, c) = if x.0 <= y.0 { (x, y) } else { (y, x) };
                if a.1 <= c.0 {
                    let mut out = b[..a.0].to_vec();
                    out.extend_from_slice(&b[c.0..c.1]);
                    out.extend_from_slice(&b[a.1..c.0]);
                    out.extend_from_slice(&b[a.0..a.1]);
                    out.extend_from_slice(&b[c.1..]);
                    *b = out;
                }
            }
        }
        2 | 3 => {
            let nums: Vec<(usize, usize)> = tokens(b)
                .into_iter()
                .filter(|&(s, _)| b[s].is_ascii_digit() || b[s] == b'-' || b[s] == b'.')
                .collect();
            if let Some(&(s, e)) = nums.get(rng.below(nums.len())) {
                let x = EXTREMES[rng.below(EXTREMES.len())];
                b.splice(s..e, x.bytes());
            }
        }
        4 => {
            let cut = rng.below(b.len());
            b.truncate(cut);
        }
        _ => {
            let lines: Vec<usize> = std::iter::once(0)
                .chain(
                    b.iter()
                        .enumerate()
                        .filter(|(_, &c)| c == b'\n')
                        .map(|(i, _)| i + 1),
                )
                .collect();
            let a = lines[rng.below(lines.len())];
            let z = lines[rng.below(lines.len())].max(a);
            let copies = 1 + rng.below(3);
            let run = b[a..z].to_vec();
            for _ in 0..copies {
                b.splice(a..a, run.iter().copied());
            }
        }
    }
}

/// Words written over a binary file's header by [`mutate_binary`].
const EXTREME_WORDS: [u32; 8] = [0, 1, 0x7fff_ffff, 0x8000_0000, 0xffff_ffff, 16000, 65535, 3];

/// One mutation of a binary file: [`mutate`]'s, or a little-endian or big-endian word of its
/// first 128 bytes (where the headers are) set to an extreme.
fn mutate_binary(b: &mut Vec<u8>, rng: &mut Rng) {
    if b.len() < 8 || rng.below(2) == 0 {
        return mutate(b, rng);
    }
    let at = rng.below(b.len().min(128) - 4);
    let w = EXTREME_WORDS[rng.below(EXTREME_WORDS.len())];
    let bytes = if rng.below(2) == 0 {
        w.to_le_bytes()
    } else {
        w.to_be_bytes()
    };
    b[at..at + 4].copy_from_slice(&bytes);
}

/// Mutates only the header of a PLY file (up to `end_header`).
fn mutate_ply_header(b: &mut Vec<u8>, rng: &mut Rng) {
    let Some(end) = b.windows(10).position(|w| w == b"end_header") else {
        return mutate(b, rng);
    };
    let mut header = b[..end].to_vec();
    mutate(&mut header, rng);
    b.splice(..end, header);
}

/// A forged copy of partial image `src` at `dst`: a `photon.*` attribute's value mutated as
/// text, or sum words set to extremes, or a layer left out.
fn forge_partial(src: &Path, dst: &Path, rng: &mut Rng) {
    let forged = common::forge_partial(src, dst, |(attrs, layers)| match rng.below(3) {
        0 => {
            let k = rng.below(attrs.len());
            let mut v = attrs[k].1.clone().into_bytes();
            mutate(&mut v, rng);
            attrs[k].1 = String::from_utf8_lossy(&v).replace('\0', "");
        }
        1 => {
            let l = rng.below(layers.len());
            let words = &mut layers[l].1;
            let p = rng.below(words.len());
            words[p][rng.below(3)] = EXTREME_WORDS[rng.below(EXTREME_WORDS.len())];
        }
        _ => {
            layers.remove(rng.below(layers.len()));
        }
    });
    // A forged value the writer refuses leaves the copy unforged.
    if forged.is_err() {
        std::fs::copy(src, dst).unwrap();
    }
}

/// Builds case `n` in `dir` (scene, its meshes or images, one file mutated); returns the
/// arguments of the photon run.
fn build_case(n: u64, seeds: &[Seed], dir: &Path, root: &Path) -> Vec<std::ffi::OsString> {
    let mut rng = Rng(n.wrapping_mul(0x2545_f491_4f6c_dd1d) ^ 0x5eed);
    let seed = &seeds[rng.below(seeds.len())];
    let _ = std::fs::remove_dir_all(dir);
    std::fs::create_dir_all(dir.join("meshes")).unwrap();
    let photons = ["--global-photons", "300", "--caustic-photons", "300"];
    let scene = dir.join("scene.pbrt");
    let mutations = 1 + rng.below(3);
    match &seed.target {
        Target::Image(name) => {
            write_textured(dir);
            let path = dir.join(name);
            let mut bytes = std::fs::read(&path).unwrap();
            for _ in 0..mutations {
                mutate_binary(&mut bytes, &mut rng);
            }
            std::fs::write(&path, &bytes).unwrap();
            return render_args(&scene, dir, &photons);
        }
        Target::Partial => {
            let part = dir.join("part.exr");
            let src = seed_part(root);
            if rng.below(2) == 0 {
                forge_partial(&src, &part, &mut rng);
            } else {
                let mut bytes = std::fs::read(&src).unwrap();
                for _ in 0..mutations {
                    mutate_binary(&mut bytes, &mut rng);
                }
                std::fs::write(&part, &bytes).unwrap();
            }
            let out = dir.join("out.exr").into_os_string();
            if rng.below(2) == 0 {
                let merge = ["merge".into(), part.into_os_string(), "-o".into(), out];
                return merge.into_iter().chain(["--no-png".into()]).collect();
            }
            let mut args: Vec<std::ffi::OsString> = partial_args(&seed.scene, "0..3")
                .into_iter()
                .map(Into::into)
                .collect();
            args.extend(["--resume".into(), part.into_os_string(), "-o".into(), out]);
            return args;
        }
        Target::Scene | Target::Ply { .. } => {}
    }
    let src_dir = seed.scene.parent().unwrap();
    if let Ok(rd) = std::fs::read_dir(src_dir.join("meshes")) {
        for e in rd.filter_map(|e| e.ok()) {
            std::fs::copy(e.path(), dir.join("meshes").join(e.file_name())).unwrap();
        }
    }
    std::fs::copy(&seed.scene, &scene).unwrap();
    let (target, header_only) = match &seed.target {
        Target::Ply { path, header_only } => (
            dir.join("meshes").join(path.file_name().unwrap()),
            *header_only,
        ),
        _ => (scene.clone(), false),
    };
    let mut bytes = std::fs::read(&target).unwrap();
    for _ in 0..mutations {
        if header_only {
            mutate_ply_header(&mut bytes, &mut rng);
        } else {
            mutate(&mut bytes, &mut rng);
        }
    }
    std::fs::write(&target, &bytes).unwrap();
    render_args(&scene, dir, &photons)
}

/// Runs case `n`; `Err` describes a failure (and keeps its files).
fn run_case(n: u64, seeds: &[Seed], root: &Path) -> Result<i32, String> {
    let dir = root.join(format!("work-{n}"));
    let args = build_case(n, seeds, &dir, root);
    let r = run_capped(&args, GIB, Duration::from_secs(120));
    match check_run(&r) {
        Ok(()) => {
            let _ = std::fs::remove_dir_all(&dir);
            Ok(r.code.unwrap_or(-1))
        }
        Err(e) => {
            let keep = root.join("failures").join(format!("case-{n}"));
            let _ = std::fs::remove_dir_all(&keep);
            let _ = std::fs::create_dir_all(keep.parent().unwrap());
            let _ = std::fs::rename(&dir, &keep);
            Err(format!("case {n} ({}): {e}", keep.display()))
        }
    }
}

/// Runs cases `first..` on all cores until `done(count, elapsed)`; returns (exit-code
/// histogram [ok, 2], failures).
fn fuzz(first: u64, done: impl Fn(u64, Duration) -> bool + Sync) -> ([u64; 2], Vec<String>) {
    let seeds = seeds();
    let root = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("fuzz");
    let next = AtomicU64::new(first);
    let ok = AtomicU64::new(0);
    let err2 = AtomicU64::new(0);
    let failures = Mutex::new(Vec::new());
    let start = Instant::now();
    let workers = std::thread::available_parallelism()
        .map_or(2, |n| n.get())
        .max(2);
    std::thread::scope(|s| {
        for _ in 0..workers {
            s.spawn(|| loop {
                let n = next.fetch_add(1, Ordering::Relaxed);
                if done(n - first, start.elapsed()) {
                    break;
                }
                match run_case(n, &seeds, &root) {
                    Ok(0) => ok.fetch_add(1, Ordering::Relaxed),
                    Ok(_) => err2.fetch_add(1, Ordering::Relaxed),
                    Err(e) => {
                        eprintln!("{e}");
                        failures.lock().unwrap().push(e);
                        0
                    }
                };
            });
        }
    });
    let hist = [ok.into_inner(), err2.into_inner()];
    (hist, failures.into_inner().unwrap())
}

#[test]
fn mutated_scenes_and_plys_exit_cleanly() {
    let t = Instant::now();
    let (hist, failures) = fuzz(0, |n, _| n >= CASES);
    println!(
        "{CASES} cases in {:.1} s: {} rendered, {} rejected with one located line, {} failures",
        t.elapsed().as_secs_f64(),
        hist[0],
        hist[1],
        failures.len()
    );
    assert!(failures.is_empty(), "{}", failures.join("\n"));
    // The mutations must exercise both outcomes.
    assert!(hist[0] > CASES / 20 && hist[1] > CASES / 20, "{hist:?}");
}

#[test]
#[ignore = "long run: PHOTON_FUZZ_SECONDS (default 3600)"]
fn long_fuzz_run() {
    let secs: u64 = std::env::var("PHOTON_FUZZ_SECONDS")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(3600);
    let budget = Duration::from_secs(secs);
    let t = Instant::now();
    let (hist, failures) = fuzz(LONG_RUN_FIRST_CASE, |_, e| e >= budget);
    println!(
        "long run {:.0} s: {} cases, {} rendered, {} rejected with one located line, {} failures",
        t.elapsed().as_secs_f64(),
        hist[0] + hist[1] + failures.len() as u64,
        hist[0],
        hist[1],
        failures.len()
    );
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}
