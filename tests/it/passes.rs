//! Rendering in passes: any split of the passes merges to the same file bit for bit, `merge`
//! refuses parts of other renders and bad ranges, a render killed with -9 resumes from its
//! checkpoint to the uninterrupted image, SIGTERM keeps what was finished, and progressive
//! photon mapping falls below the fixed-map error floor.
use crate::support as common;
use common::photon;
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn tmp(name: &str) -> PathBuf {
    common::scratch("passes", name)
}

/// A small progressive render of the glass Cornell box (caustics, both maps, gathering).
const SMALL: [&str; 8] = [
    "--global-photons",
    "4000",
    "--caustic-photons",
    "4000",
    "--pass-spp",
    "2",
    "--progressive",
    "--no-png",
];

fn render(dir: &Path, out: &str, extra: &[&str]) -> Output {
    let res = if extra.contains(&"--res") {
        &[][..]
    } else {
        &["--res", "24x20"][..]
    };
    let o = photon()
        .args(["render", "scenes/cornell-glass.pbrt"])
        .args(SMALL)
        .args(res)
        .args(extra)
        .arg("-o")
        .arg(dir.join(out))
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    o
}

fn merge(dir: &Path, parts: &[&str], out: &str) -> Output {
    photon()
        .arg("merge")
        .args(parts.iter().map(|p| dir.join(p)))
        .arg("-o")
        .arg(dir.join(out))
        .arg("--no-png")
        .output()
        .unwrap()
}

fn bytes(p: PathBuf) -> Vec<u8> {
    std::fs::read(&p).unwrap_or_else(|e| panic!("{}: {e}", p.display()))
}

#[test]
fn any_split_merges_to_the_same_file() {
    let dir = tmp("split");
    render(&dir, "whole.exr", &["--passes", "0..6"]);
    let ok = merge(&dir, &["whole.exr"], "whole-merged.exr");
    assert!(
        ok.status.success(),
        "{}",
        String::from_utf8_lossy(&ok.stderr)
    );
    let reference = bytes(dir.join("whole-merged.exr"));
    // Splits of different shapes, thread counts and part orders.
    let splits: [&[(&str, &str)]; 3] = [
        &[("0..3", "1"), ("3..6", "2")],
        &[("4..6", "2"), ("0..1", "1"), ("1..4", "1")],
        &[
            ("0..1", "2"),
            ("1..2", "1"),
            ("2..3", "2"),
            ("3..4", "1"),
            ("4..5", "2"),
            ("5..6", "1"),
        ],
    ];
    for (i, split) in splits.iter().enumerate() {
        let names: Vec<String> = split.iter().map(|(r, _)| format!("s{i}-{r}.exr")).collect();
        for ((range, threads), name) in split.iter().zip(&names) {
            render(&dir, name, &["--passes", range, "--threads", threads]);
        }
        let refs: Vec<&str> = names.iter().map(|s| s.as_str()).collect();
        let out = format!("merged{i}.exr");
        let m = merge(&dir, &refs, &out);
        assert!(m.status.success(), "{}", String::from_utf8_lossy(&m.stderr));
        assert!(
            bytes(dir.join(&out)) == reference,
            "split {split:?} differs from 0..6"
        );
    }
    // The merged mean is an image: finite, not black.
    let img = photon::imageio::read_exr(&dir.join("merged0.exr")).unwrap();
    assert_eq!(img.count_nonfinite(), 0);
    let mean: f32 = img.pixels.iter().map(|p| p[0] + p[1] + p[2]).sum::<f32>() / 3.0;
    assert!(mean > 0.0);
}

#[test]
fn merge_refuses_parts_of_other_renders_and_bad_ranges() {
    let dir = tmp("refuse");
    render(&dir, "a.exr", &["--passes", "0..2"]);
    render(&dir, "b.exr", &["--passes", "2..4"]);
    render(&dir, "seed.exr", &["--passes", "2..4", "--seed", "7"]);
    render(&dir, "res.exr", &["--passes", "2..4", "--res", "20x20"]);
    render(&dir, "set.exr", &["--passes", "2..4", "--alpha", "0.5"]);
    render(&dir, "c.exr", &["--passes", "1..3"]);
    render(&dir, "d.exr", &["--passes", "5..6"]);
    let scene = photon()
        .args([
            "render",
            "scenes/cornell-glass.pbrt",
            "--integrator",
            "path",
        ])
        .args(["--res", "24x20", "--passes", "2..4", "--no-png", "-o"])
        .arg(dir.join("other.exr"))
        .output()
        .unwrap();
    assert!(scene.status.success());
    let ok = merge(&dir, &["b.exr", "a.exr"], "ok.exr");
    assert!(
        ok.status.success(),
        "{}",
        String::from_utf8_lossy(&ok.stderr)
    );
    for (part, field) in [
        ("seed.exr", "seed differs"),
        ("res.exr", "resolution differs"),
        ("set.exr", "settings differs"),
        ("other.exr", "settings differs"),
        ("c.exr", "overlap"),
        ("d.exr", "passes 2..5 are missing"),
    ] {
        let o = merge(&dir, &["a.exr", part], "bad.exr");
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{part}: {err}");
        assert!(err.contains(field), "{part}: {err}");
        assert_eq!(err.trim().lines().count(), 1, "{err}");
        assert!(!dir.join("bad.exr").exists());
    }
    // A file that is no partial image.
    let plain = dir.join("plain.exr");
    photon::imageio::write_exr(
        &plain,
        &photon::imageio::RgbImage::new(2, 2),
        &[],
        photon::imageio::ExrPixel::Float,
    )
    .unwrap();
    let o = merge(&dir, &["a.exr", "plain.exr"], "bad.exr");
    assert_eq!(o.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&o.stderr).contains("not a partial image"));
    // Resuming with other settings names the field.
    let o = photon()
        .args(["render", "scenes/cornell-glass.pbrt", "--res", "24x20"])
        .args(SMALL)
        .args(["--passes", "0..4", "--seed", "3", "--resume"])
        .arg(dir.join("a.exr"))
        .arg("-o")
        .arg(dir.join("r.exr"))
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&o.stderr).contains("another seed"));
}

/// Passes recorded in a partial image's `photon.passes` attribute.
fn passes_of(p: &Path) -> (u64, u64) {
    let attrs = photon::imageio::read_exr_attributes(p).unwrap();
    let v = &attrs.iter().find(|(k, _)| k == "photon.passes").unwrap().1;
    let (a, b) = v.split_once("..").unwrap();
    (a.parse().unwrap(), b.parse().unwrap())
}

/// Starts a long render with a checkpoint after every pass and waits for `passes` of them.
fn start_and_wait(dir: &Path, ckpt: &Path, passes: u64) -> std::process::Child {
    let child = photon()
        .args(["render", "scenes/cornell-glass.pbrt", "--res", "24x20"])
        .args(SMALL)
        .args(["--passes", "0..400", "--every", "1ms", "--checkpoint"])
        .arg(ckpt)
        .arg("-o")
        .arg(dir.join("never.exr"))
        .stdout(std::process::Stdio::null())
        .stderr(std::process::Stdio::null())
        .spawn()
        .unwrap();
    let t = std::time::Instant::now();
    while !(ckpt.exists() && passes_of(ckpt).1 >= passes) {
        assert!(t.elapsed().as_secs() < 120, "no checkpoint");
        std::thread::sleep(std::time::Duration::from_millis(20));
    }
    child
}

#[test]
fn resume_after_kill_9_gives_the_uninterrupted_image() {
    let dir = tmp("kill9");
    let ckpt = dir.join("ckpt.exr");
    let mut child = start_and_wait(&dir, &ckpt, 3);
    child.kill().unwrap(); // SIGKILL: no chance to clean up
    child.wait().unwrap();
    let (_, done) = passes_of(&ckpt);
    assert!((3..400).contains(&done), "{done}");
    let end = (done + 2).to_string();
    let range = format!("0..{end}");
    let ck = ckpt.to_str().unwrap();
    render(&dir, "resumed.exr", &["--passes", &range, "--resume", ck]);
    render(&dir, "straight.exr", &["--passes", &range]);
    assert_eq!(passes_of(&dir.join("resumed.exr")), (0, done + 2));
    assert!(bytes(dir.join("resumed.exr")) == bytes(dir.join("straight.exr")));
    assert!(!dir.join("never.exr").exists());
}

#[test]
fn sigterm_writes_the_checkpoint_and_the_image_and_exits_143() {
    let dir = tmp("sigterm");
    let ckpt = dir.join("ckpt.exr");
    let child = start_and_wait(&dir, &ckpt, 2);
    let pid = child.id().to_string();
    assert!(Command::new("kill")
        .args(["-TERM", &pid])
        .status()
        .unwrap()
        .success());
    let out = child.wait_with_output().unwrap();
    assert_eq!(out.status.code(), Some(143));
    // Both files hold the same finished passes (at least the two seen), none cut short.
    let (a, b) = passes_of(&dir.join("never.exr"));
    assert_eq!((a, b), passes_of(&ckpt));
    assert!((2..400).contains(&b));
    let names: Vec<_> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().file_name())
        .collect();
    assert_eq!(names.len(), 2, "temporary files left: {names:?}");
}

/// relMSE of a render of the shared `cornell-spheres` at 64x64 (reference box-downsampled).
fn spheres_relmse(dir: &Path, name: &str, extra: &[&str]) -> f64 {
    let out = dir.join(name);
    let o = photon()
        .args([
            "render",
            "../shared/scenes/cornell-spheres/scene.pbrt",
            "--res",
            "64x64",
        ])
        .args([
            "--pass-spp",
            "1",
            "--global-photons",
            "5000",
            "--caustic-photons",
            "5000",
        ])
        .args(["--no-final-gather", "--no-png", "-o"])
        .arg(&out)
        .args(extra)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let img = photon::imageio::read_exr(&out).unwrap();
    let reference =
        photon::imageio::read_exr(Path::new("../shared/scenes/cornell-spheres/reference.exr"))
            .unwrap();
    let (a, r) = photon::imageio::metrics::match_sizes(img, reference).unwrap();
    let m = photon::imageio::metrics::compare(&a, &r, Default::default()).unwrap();
    m.overall.relmse
}

/// With few photons (5000 per map) and the global map looked at directly, Jensen's fixed
/// maps stop improving: their error at 256 passes is about their error at 64 (the bias
/// floor). Progressive passes, at the same photon count per pass, fall well below that floor.
/// Measured: fixed 0.0288 (16 passes), 0.0241 (64), 0.0229 (256); progressive 0.0104 (16),
/// 0.0037 (64). (Before the global lookups' radius was cut to the map's own typical radius
/// the floor was higher and came sooner: fixed 0.0485 (16), 0.0445 (64).)
#[test]
fn progressive_falls_below_the_fixed_map_floor() {
    let dir = tmp("floor");
    let fixed64 = spheres_relmse(&dir, "f64.exr", &["--passes", "64"]);
    let fixed256 = spheres_relmse(&dir, "f256.exr", &["--passes", "256"]);
    let prog16 = spheres_relmse(&dir, "p16.exr", &["--passes", "16", "--progressive"]);
    let prog64 = spheres_relmse(&dir, "p64.exr", &["--passes", "64", "--progressive"]);
    println!("fixed {fixed64:.5} / {fixed256:.5}, progressive {prog16:.5} / {prog64:.5}");
    assert!(
        fixed256 > 0.85 * fixed64,
        "the fixed maps have no floor here: {fixed64} -> {fixed256}"
    );
    assert!(
        prog64 < 0.2 * fixed256,
        "progressive {prog64} vs floor {fixed256}"
    );
    assert!(
        prog64 < 0.6 * prog16,
        "progressive stopped falling: {prog16} -> {prog64}"
    );
}

/// `--progressive --time` renders passes for the budget (an ordinary image, not a partial
/// one); the statistics give the passes and samples.
#[test]
fn progressive_time_budget_renders_an_ordinary_image() {
    let dir = tmp("time");
    let out = dir.join("t.exr");
    let o = photon()
        .args([
            "render",
            "scenes/cornell-glass.pbrt",
            "--res",
            "24x20",
            "--progressive",
        ])
        .args([
            "--time",
            "1.5",
            "--global-photons",
            "4000",
            "--caustic-photons",
            "4000",
        ])
        .args(["--no-png", "-o"])
        .arg(&out)
        .output()
        .unwrap();
    let stdout = String::from_utf8_lossy(&o.stdout);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert!(stdout.contains("progressive: "), "{stdout}");
    let attrs = photon::imageio::read_exr_attributes(&out).unwrap();
    assert!(
        attrs.iter().all(|(k, _)| !k.starts_with("photon.")),
        "{attrs:?}"
    );
    let img = photon::imageio::read_exr(&out).unwrap();
    assert_eq!(img.count_nonfinite(), 0);
    assert!(img.pixels.iter().any(|p| p[0] > 0.0));
}

/// Writes a copy of partial image `src` to `dst` with attribute `key` set to `value` and each
/// sum word passed through `word` (layer name, word): a forged part.
fn forge(src: &Path, dst: &Path, key: &str, value: &str, word: &dyn Fn(&str, u32) -> u32) {
    common::forge_partial(src, dst, |(attrs, layers)| {
        for (_, v) in attrs.iter_mut().filter(|(k, _)| k == key) {
            *v = value.to_string();
        }
        for (name, words) in layers.iter_mut() {
            for p in words.iter_mut() {
                *p = p.map(|x| word(name, x));
            }
        }
    })
    .unwrap();
}

/// Forged parts (issue 22, cases 3 and 21): a `photon.resolution` of 400000x600000 made
/// `merge` and `--resume` abort on a 960 GB allocation; a negative sum was merged as if
/// photon had written it; two sums whose total leaves the i64 range saturated silently. Each is
/// now a one-line error naming the file (or the pixel).
#[test]
fn merge_refuses_forged_sizes_negative_and_overflowing_sums() {
    let dir = tmp("forged");
    render(&dir, "a.exr", &["--passes", "0..1", "--res", "8x6"]);
    render(&dir, "b.exr", &["--passes", "1..2", "--res", "8x6"]);
    let (a, b) = (dir.join("a.exr"), dir.join("b.exr"));
    let keep = |_: &str, x: u32| x;
    let stderr = |o: &Output| String::from_utf8_lossy(&o.stderr).into_owned();

    forge(
        &a,
        &dir.join("huge.exr"),
        "photon.resolution",
        "400000x600000",
        &keep,
    );
    let o = merge(&dir, &["huge.exr", "b.exr"], "m.exr");
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert!(
        stderr(&o).contains("huge.exr: photon.resolution 400000x600000"),
        "{}",
        stderr(&o)
    );
    let o = photon()
        .args(["render", "scenes/cornell-glass.pbrt", "--resume"])
        .arg(dir.join("huge.exr"))
        .args(SMALL)
        .args(["--res", "8x6", "--passes", "0..3", "-o"])
        .arg(dir.join("r.exr"))
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert!(
        stderr(&o).contains("photon.resolution 400000x600000"),
        "{}",
        stderr(&o)
    );

    // The file's own size must agree too: a smaller forged resolution.
    forge(
        &a,
        &dir.join("small.exr"),
        "photon.resolution",
        "4x3",
        &keep,
    );
    let o = merge(&dir, &["small.exr", "b.exr"], "m.exr");
    assert!(
        stderr(&o).contains("the image is 8x6, photon.resolution says 4x3"),
        "{}",
        stderr(&o)
    );

    let negative = |n: &str, x: u32| {
        if n == "sum.direct.hi" {
            x | 0x8000_0000
        } else {
            x
        }
    };
    forge(
        &a,
        &dir.join("neg.exr"),
        "photon.format",
        "photon-partial-1",
        &negative,
    );
    let o = merge(&dir, &["neg.exr", "b.exr"], "m.exr");
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert!(
        stderr(&o).contains("neg.exr: sum.direct is negative at pixel (0, 0)"),
        "{}",
        stderr(&o)
    );

    let big = |n: &str, x: u32| {
        if n == "sum.indirect.hi" {
            0x7fff_ffff
        } else {
            x
        }
    };
    forge(
        &a,
        &dir.join("big-a.exr"),
        "photon.format",
        "photon-partial-1",
        &big,
    );
    forge(
        &b,
        &dir.join("big-b.exr"),
        "photon.format",
        "photon-partial-1",
        &big,
    );
    let o = merge(&dir, &["big-a.exr", "big-b.exr"], "m.exr");
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert!(
        stderr(&o).contains("the sum at pixel (0, 0) overflows"),
        "{}",
        stderr(&o)
    );
    assert!(!dir.join("m.exr").exists());
}
