//! The 20 defects of issue 10 ("Hostile input and resources"), one test each (`case_NN_...`),
//! run through the `photon` binary under an address-space cap (`prlimit --as`) so that a
//! regression aborts or fails here instead of taking the machine's memory. Nothing here
//! asserts on timing: timeouts only catch hangs.
use crate::support as common;

use common::*;
use std::path::{Path, PathBuf};
use std::time::Duration;

const T: Duration = Duration::from_secs(120);

/// Writes `text` to `dir/name` and returns the path.
fn write(dir: &Path, name: &str, text: impl AsRef<[u8]>) -> PathBuf {
    let p = dir.join(name);
    std::fs::write(&p, text).unwrap();
    p
}

/// Renders `scene_text` (written to `dir/scene.pbrt`) with the tiny settings and `extra`.
fn render_text(dir: &Path, scene_text: &str, extra: &[&str], mem: u64) -> Run {
    let scene = write(dir, "scene.pbrt", scene_text);
    run_capped(render_args(&scene, dir, extra), mem, T)
}

#[test]
fn case_01_gather_samples_are_bounded() {
    let d = tmp_dir("c01");
    let big = small_scene("").replace(
        "WorldBegin",
        "Integrator \"photonmap\" \"integer gathersamples\" [ 1000000 ]\nWorldBegin",
    );
    let r = render_text(&d, &big, &[], GIB);
    assert_error(&r, &["scene.pbrt:4:", "gathersamples", "[1, 4096]"]);
    let r = render_text(&d, &small_scene(""), &["--gather-samples", "1000000"], GIB);
    assert_error(&r, &["--gather-samples"]);
    // The largest allowed count renders in bounded batches under a 1 GiB cap.
    let r = render_text(&d, &small_scene(""), &["--gather-samples", "4096"], GIB);
    assert_eq!(r.code, Some(0), "{}", r.describe());
    assert!(ray_count(&r.stdout, "secondary") > 100_000, "{}", r.stdout);
}

/// The number after `kind` in the "rendered in" line (`camera N, secondary N, shadow N`).
fn ray_count(stdout: &str, kind: &str) -> u64 {
    let line = stdout
        .lines()
        .find(|l| l.starts_with("rendered in"))
        .expect("a rendered line");
    let after = line
        .split(&format!("{kind} "))
        .nth(1)
        .expect("the ray kind");
    after
        .split(|c: char| !c.is_ascii_digit())
        .next()
        .and_then(|n| n.parse().ok())
        .expect("a count")
}

#[test]
fn case_02_many_small_spheres_fit_in_little_memory() {
    let d = tmp_dir("c02");
    let mut world = String::new();
    for i in 0..10_000 {
        let (x, z) = ((i % 100) as f32 * 0.02 - 1.0, (i / 100) as f32 * 0.02 - 1.0);
        world += &format!(
            "AttributeBegin Translate {x} 0.5 {z} Shape \"sphere\" \"float radius\" 0.005 AttributeEnd\n"
        );
    }
    let r = render_text(&d, &small_scene(&world), &[], GIB);
    assert_eq!(r.code, Some(0), "{}", r.describe());
    let tris: u64 = r
        .stdout
        .split(" triangles")
        .next()
        .and_then(|s| s.rsplit(' ').next())
        .and_then(|n| n.parse().ok())
        .expect("the triangle count is printed");
    // Each small sphere gets the smallest tessellation, not 16,128 triangles.
    assert!(tris < 10_000 * 600, "{tris} triangles");
}

#[test]
fn case_03_huge_emitter_is_an_error_not_a_panic() {
    let d = tmp_dir("c03");
    let text = r#"LookAt 0 0 5e15  0 0 0  0 1 0
Camera "perspective"
WorldBegin
AreaLightSource "diffuse" "rgb L" [ 1 1 1 ]
Shape "trianglemesh" "point3 P" [ -1e15 -1e15 0  1e15 -1e15 0  0 1e15 0 ]
"#;
    let r = render_text(&d, text, &[], GIB);
    assert_error(&r, &["scene.pbrt:2:8", "too large", "camera"]);
    let r = render_text(&d, &text.replace("5e15", "5"), &[], GIB);
    assert_error(&r, &["scene.pbrt:5:7", "too large", "vertex"]);
    // Inside the supported range, an emitter whose power overflows is an error too.
    let text = text
        .replace("5e15", "5e8")
        .replace("e15", "e9")
        .replace("[ 1 1 1 ]", "[ 1e20 1e20 1e20 ]");
    let r = render_text(&d, &text, &[], GIB);
    assert_error(&r, &["scene.pbrt:5:7", "power", "above the limit 1e30"]);
}

#[test]
fn case_04_devices_fifos_and_symlinks_are_not_replaced() {
    use std::os::unix::fs::FileTypeExt;
    let d = tmp_dir("c04");
    let scene = write(&d, "scene.pbrt", small_scene(""));
    let mut args = render_args(&scene, &d, &[]);
    let n = args.len();
    args[n - 1] = "/dev/null".into();
    let r = run_capped(&args, GIB, T);
    assert_eq!(r.code, Some(0), "{}", r.describe());
    assert!(std::fs::metadata("/dev/null")
        .unwrap()
        .file_type()
        .is_char_device());
    // With the PNG preview on, no `/dev/null.png` appears beside the device.
    let _ = std::fs::remove_file("/dev/null.png"); // left by an older photon, if any
    let no_png = args.iter().position(|a| a == "--no-png").unwrap();
    let mut with_png = args.clone();
    with_png.remove(no_png);
    let r = run_capped(&with_png, GIB, T);
    assert_eq!(r.code, Some(0), "{}", r.describe());
    assert!(!Path::new("/dev/null.png").exists());
    // A FIFO gets the EXR's bytes; it is still a FIFO afterwards.
    let fifo = d.join("pipe.exr");
    assert!(std::process::Command::new("mkfifo")
        .arg(&fifo)
        .status()
        .unwrap()
        .success());
    let reader = {
        let f = fifo.clone();
        std::thread::spawn(move || std::fs::read(f).unwrap())
    };
    args[n - 1] = fifo.clone().into();
    let r = run_capped(&args, GIB, T);
    assert_eq!(r.code, Some(0), "{}", r.describe());
    let bytes = reader.join().unwrap();
    assert_eq!(&bytes[..4], &[0x76, 0x2f, 0x31, 0x01], "EXR magic");
    assert!(std::fs::metadata(&fifo).unwrap().file_type().is_fifo());
    // A symlink stays a symlink; its target gets the image.
    write(&d, "target.exr", "old");
    std::os::unix::fs::symlink("target.exr", d.join("link.exr")).unwrap();
    args[n - 1] = d.join("link.exr").into();
    let r = run_capped(&args, GIB, T);
    assert_eq!(r.code, Some(0), "{}", r.describe());
    assert!(std::fs::symlink_metadata(d.join("link.exr"))
        .unwrap()
        .file_type()
        .is_symlink());
    assert!(photon::imageio::read_exr(&d.join("target.exr")).is_ok());
}

#[test]
fn case_05_huge_lookups_are_rejected() {
    let d = tmp_dir("c05");
    let text = small_scene("").replace(
        "WorldBegin",
        "Integrator \"photonmap\" \"integer causticlookup\" [ 2147483647 ]\nWorldBegin",
    );
    let r = render_text(&d, &text, &[], GIB);
    assert_error(&r, &["scene.pbrt:4:", "causticlookup", "[1, 100000]"]);
    for flag in ["--global-lookup", "--caustic-lookup"] {
        for v in ["2147483647", "18446744073709551615"] {
            let r = render_text(&d, &small_scene(""), &[flag, v], GIB);
            assert_error(&r, &[flag]);
        }
    }
    // The largest allowed lookup runs (buffers sized by the map, not by k).
    let r = render_text(&d, &small_scene(""), &["--global-lookup", "100000"], GIB);
    assert_eq!(r.code, Some(0), "{}", r.describe());
}

#[test]
fn case_06_resolutions_are_checked_against_the_budget() {
    let d = tmp_dir("c06");
    let r = render_text(&d, &small_scene(""), &["--res", "32768x32768"], 2 * GIB);
    assert_error(
        &r,
        &["--res", "needs ~125 GB", "film 125 GB", "over the limit of"],
    );
    let r = render_text(&d, &small_scene(""), &["--res", "40000x10"], GIB);
    assert_error(&r, &["--res"]);
    let text = small_scene("").replace(
        "\"integer xresolution\" [ 8 ]",
        "\"integer xresolution\" [ 2000000000 ]",
    );
    let scene = write(&d, "scene.pbrt", &text);
    let r = run_capped(["render".as_ref(), scene.as_os_str()], GIB, T);
    assert_error(&r, &["scene.pbrt:3:", "at most 32768"]);
    // Within the limits but over an explicit budget.
    let r = render_text(
        &d,
        &small_scene(""),
        &["--res", "4096x4096", "--max-memory", "1G"],
        2 * GIB,
    );
    assert_error(&r, &["over the limit of 1.1 GB (--max-memory)"]);
}

#[test]
fn case_07_photon_counts_are_checked_against_the_budget() {
    let d = tmp_dir("c07");
    let r = render_text(
        &d,
        &small_scene(""),
        &["--global-photons", "2000000000"],
        GIB,
    );
    assert_error(&r, &["--global-photons", "photon maps", "x 104 B"]);
    let r = render_text(
        &d,
        &small_scene(""),
        &["--global-photons", "9999999999"],
        GIB,
    );
    assert_error(&r, &["--global-photons"]);
    // `--time` sets its own counts (200k a map at 4 s): they are checked too and halved until
    // they fit (they went unchecked: a 32 s budget used 8x the file's counts, whatever the
    // memory), the file's counts being the floor. A glass sphere makes the scene need both
    // maps (a map the scene does not need is not counted).
    let glass = "Material \"dielectric\"\nShape \"sphere\" \"float radius\" 0.2\n";
    let few = small_scene(glass).replace(
        "WorldBegin",
        "Integrator \"photonmap\" \"integer globalphotons\" [ 10000 ] \"integer causticphotons\" [ 10000 ]\nWorldBegin",
    );
    let scene = write(&d, "few.pbrt", &few);
    let out = d.join("few.exr");
    let run = |extra: &[&str]| {
        let mut args: Vec<std::ffi::OsString> = vec!["render".into(), scene.clone().into()];
        // 32 MiB lies between the estimates of 100k + 100k (27.7 MB) and 200k + 200k photons
        // (35.0 MB) on two threads.
        let flags = ["--no-png", "--threads", "2", "--max-memory", "32M", "-o"];
        args.extend(flags.map(Into::into));
        args.push(out.clone().into());
        args.extend(extra.iter().map(Into::into));
        run_capped(args, GIB, T)
    };
    let r = run(&["--spp", "1"]);
    assert_eq!(
        r.code,
        Some(0),
        "the file's counts fit in 32M: {}",
        r.describe()
    );
    let r = run(&["--time", "4s"]);
    assert_eq!(r.code, Some(0), "{}", r.describe());
    let line =
        "time budget: 200000 + 200000 photons would not fit the memory budget: 100000 + 100000";
    assert!(r.stdout.contains(line), "{}", r.stdout);
    let text = small_scene("").replace(
        "WorldBegin",
        "Integrator \"photonmap\" \"integer globalphotons\" [ 2147483647 ]\nWorldBegin",
    );
    let scene = write(&d, "scene.pbrt", &text);
    let args: Vec<std::ffi::OsString> = vec![
        "render".into(),
        scene.into(),
        "--res".into(),
        "8x8".into(),
        "-o".into(),
        d.join("o.exr").into(),
    ];
    let r = run_capped(&args, GIB, T);
    assert_error(&r, &["scene.pbrt:4:", "needs ~"]);
}

#[test]
fn case_08_png_never_overwrites_the_exr() {
    let d = tmp_dir("c08");
    let scene = write(&d, "scene.pbrt", small_scene(""));
    let img = write(&d, "img.png", "precious");
    let r = run_capped(
        [
            "render".as_ref(),
            scene.as_os_str(),
            "-o".as_ref(),
            img.as_os_str(),
        ],
        GIB,
        T,
    );
    // `-o img.png` now asks for a PNG (pbrt-v4's rule): it replaces img.png with the
    // render, and no preview is written beside it.
    assert_eq!(r.code, Some(0), "{}", r.describe());
    assert!(std::fs::read(&img).unwrap().starts_with(b"\x89PNG"));
    std::fs::write(&img, "precious").unwrap();
    let exr = d.join("same.exr");
    let r = run_capped(
        [
            "render".as_ref(),
            scene.as_os_str(),
            "-o".as_ref(),
            exr.as_os_str(),
            "--png".as_ref(),
            exr.as_os_str(),
        ],
        GIB,
        T,
    );
    assert_error(&r, &["same file"]);
    assert_eq!(std::fs::read_to_string(&img).unwrap(), "precious");
    assert!(!exr.exists());
}

#[test]
fn case_10_light_values_must_be_finite_and_non_negative() {
    let d = tmp_dir("c10");
    let area = |params: &str| small_scene("").replace("\"rgb L\" [ 5 5 5 ]", params);
    for (params, needle) in [
        (
            "\"rgb L\" [ 1e30 1 1 ] \"float scale\" 1e30",
            "scene.pbrt:9:",
        ),
        ("\"rgb L\" [ 1 1 1 ] \"float scale\" 1e30", "scale"),
        ("\"rgb L\" [ 1 1 1 ] \"float power\" 3e38", "power"),
        ("\"rgb L\" [ -1 1 1 ]", "[0, 1e20]"),
        ("\"rgb L\" [ 1 1 1 ] \"float scale\" -1", "must be >= 0"),
        ("\"rgb L\" [ 1 1 1 ] \"float power\" -5", "power"),
    ] {
        let r = render_text(&d, &area(params), &[], GIB);
        assert_error(&r, &[needle]);
    }
    for light in [
        "LightSource \"point\" \"rgb I\" [ 1e30 1e30 1e30 ] \"float scale\" 1e30",
        "LightSource \"point\" \"rgb I\" [ -1 1 1 ]",
        "LightSource \"spot\" \"rgb I\" [ 1 1 1 ] \"float scale\" -2",
        "LightSource \"point\" \"float power\" 3e38",
        "LightSource \"distant\" \"rgb L\" [ 1 1 1 ] \"float scale\" 1e38",
    ] {
        let r = render_text(&d, &small_scene(light), &[], GIB);
        assert_error(&r, &["scene.pbrt:12:"]);
    }
}

/// The Cornell box with the whole scene (camera included) scaled by `s`.
fn scaled_cornell(s: f64) -> String {
    let src = std::fs::read_to_string("../shared/scenes/cornell-box/scene-v4.pbrt").unwrap();
    src.replacen(
        "Camera \"perspective\"",
        &format!("Scale {0:e} {0:e} {0:e}\nCamera \"perspective\"", 1.0 / s),
        1,
    )
    .replacen(
        "WorldBegin",
        &format!("WorldBegin\nScale {s:e} {s:e} {s:e}"),
        1,
    )
}

#[test]
fn case_11_the_cornell_box_renders_the_same_at_every_supported_scale() {
    // Sample for sample: with the photon-guided gather, rounding at 1e-8 changes a guide's
    // k-nearest set by a photon here and there, which moves some gather samples to other
    // cells (same expectation, other noise: relMSE 9e-3 at 2 spp), so the images are compared
    // with the cosine gather; the guided renders must still succeed at every scale. The same
    // rounding moves an estimate's fill across `thinfill` here and there (a gather hit passed
    // on instead of read: relMSE 6e-4 - 1.6e-3 against scale 1), so the exact comparison
    // turns that off too, and the renders with it must succeed and agree within noise.
    let d = tmp_dir("c11");
    let render = |s: f64| {
        let scene = write(&d, &format!("s{s:e}.pbrt"), scaled_cornell(s));
        let out = d.join(format!("s{s:e}.exr"));
        let args: Vec<std::ffi::OsString> = vec![
            "render".into(),
            scene.into(),
            "--res".into(),
            "24x24".into(),
            "--spp".into(),
            "2".into(),
            "--global-photons".into(),
            "20000".into(),
            "--no-guided-gather".into(),
            "--thin-fill".into(),
            "0".into(),
            "--no-png".into(),
            "-o".into(),
            out.clone().into(),
        ];
        let r = run_capped(&args, 2 * GIB, T);
        let guided: Vec<_> = args[..args.len() - 6]
            .iter()
            .cloned()
            .chain(["--no-png".into(), "-o".into(), d.join("guided.exr").into()])
            .collect();
        let g = run_capped(&guided, 2 * GIB, T);
        assert_eq!(g.code, r.code, "guided, scale {s:e}: {}", g.describe());
        let thin = d.join(format!("thin{s:e}.exr"));
        let thin_args: Vec<_> = args[..args.len() - 5]
            .iter()
            .cloned()
            .chain(["--no-png".into(), "-o".into(), thin.clone().into()])
            .collect();
        let t = run_capped(&thin_args, 2 * GIB, T);
        assert_eq!(t.code, r.code, "thin fill, scale {s:e}: {}", t.describe());
        (r, out, thin)
    };
    let (r, base, thin_base) = render(1.0);
    assert_eq!(r.code, Some(0), "{}", r.describe());
    let base = photon::imageio::read_exr(&base).unwrap();
    let thin_base = photon::imageio::read_exr(&thin_base).unwrap();
    for s in [1e-8, 1e-6, 1e-4, 1e4, 1e6, 1e8] {
        let (r, out, thin) = render(s);
        assert_eq!(r.code, Some(0), "scale {s:e}: {}", r.describe());
        let img = photon::imageio::read_exr(&out).unwrap();
        let m = photon::imageio::metrics::compare(&img, &base, Default::default()).unwrap();
        let thin = photon::imageio::read_exr(&thin).unwrap();
        let t = photon::imageio::metrics::compare(&thin, &thin_base, Default::default()).unwrap();
        println!(
            "scale {s:e}: relMSE {:.2e} against scale 1 ({:.2e} passing thin points on)",
            m.overall.relmse, t.overall.relmse
        );
        assert!(
            m.overall.relmse < 1e-3,
            "scale {s:e}: relMSE {}",
            m.overall.relmse
        );
        // Renders of other seeds (7-10) differ from scale 1 by relMSE 15-25 here.
        assert!(
            t.overall.relmse < 5e-3,
            "scale {s:e}, thin points passed on: relMSE {}",
            t.overall.relmse
        );
    }
    for (s, needle) in [
        (1e-10, "too small"),
        (1e10, "too large"),
        (1e20, "too large"),
    ] {
        let (r, _, _) = render(s);
        assert_error(&r, &[needle]);
        assert!(!r.stderr.contains("coincide"), "{}", r.describe());
    }
}

#[test]
fn case_12_non_finite_vertices_are_located() {
    let d = tmp_dir("c12");
    let tri = "Shape \"trianglemesh\" \"point3 P\" [ 0 0 0  1 0 0  0 1 0 ]";
    for xf in [
        "Transform [ 0 0 0 0  0 0 0 0  0 0 0 0  0 0 0 0 ]",
        "Transform [ 1 0 0 0  0 1 0 0  0 0 1 0  0 0 0 0 ]",
        "Translate 3e38 0 0\nTranslate 3e38 0 0",
    ] {
        let world = format!("AttributeBegin\n{xf}\n{tri}\nAttributeEnd");
        let r = render_text(&d, &small_scene(&world), &[], GIB);
        let line = 12 + 1 + xf.lines().count();
        assert_error(&r, &[&format!("scene.pbrt:{line}:7"), "not finite"]);
    }
}

#[test]
fn case_13_messages_are_one_short_escaped_line() {
    let d = tmp_dir("c13");
    let long = "x".repeat(1 << 20);
    let r = render_text(&d, &small_scene(&format!("Shape \"{long}\"")), &[], GIB);
    assert_error(&r, &["scene.pbrt:12:"]);
    assert!(r.stderr.len() < 1000, "{} bytes", r.stderr.len());
    let r = render_text(&d, &small_scene(&format!("Bogus{long}")), &[], GIB);
    assert_error(&r, &["…"]);
    assert!(r.stderr.len() < 1000, "{} bytes", r.stderr.len());
    let r = render_text(&d, &small_scene("Shape \"a\0b\x1b[31m\""), &[], GIB);
    assert_error(&r, &["a\\u{0}b\\u{1b}[31m"]);
    // A file that is not a scene is not quoted.
    write(&d, "passwd", "root:x:0:0:root:/root:/bin/bash\n");
    let r = render_text(&d, &small_scene("Include \"passwd\""), &[], GIB);
    assert_error(&r, &["passwd:1:1", "not a pbrt-v4 scene"]);
    assert!(!r.stderr.contains("root"), "{}", r.describe());
    // Non-UTF-8 bytes in the main file have a line and column.
    let mut bytes = small_scene("").into_bytes();
    bytes.extend(b"Shape \"tri\xffangle\"\n");
    let scene = write(&d, "latin.pbrt", &bytes);
    let r = run_capped(render_args(&scene, &d, &[]), GIB, T);
    assert_error(&r, &["latin.pbrt:13:11", "0xff"]);
}

#[test]
fn case_14_endless_inputs_are_capped() {
    let d = tmp_dir("c14");
    let r = render_text(&d, &small_scene("Include \"/dev/zero\""), &[], GIB);
    assert_error(
        &r,
        &["scene.pbrt:12:1", "/dev/zero", "larger than the limit"],
    );
    let r = run_capped(render_args(Path::new("/dev/zero"), &d, &[]), GIB, T);
    assert_error(&r, &["/dev/zero", "larger than the limit"]);
    let world = "Shape \"plymesh\" \"string filename\" \"/dev/zero\"";
    let r = render_text(&d, &small_scene(world), &[], GIB);
    assert_error(&r, &["scene.pbrt:12:7", "/dev/zero"]);
}

#[test]
fn case_15_radii_and_exposure_must_be_finite_and_positive() {
    let d = tmp_dir("c15");
    for (flag, v) in [
        ("--global-radius", "NaN"),
        ("--global-radius", "-1"),
        ("--caustic-radius", "0"),
        ("--caustic-radius", "inf"),
        ("--exposure", "NaN"),
        ("--exposure", "1e9"),
    ] {
        let r = render_text(&d, &small_scene(""), &[flag, v], GIB);
        assert_error(&r, &[flag]);
    }
    for p in ["\"float globalradius\" -1", "\"float causticradius\" 0"] {
        let text = small_scene("").replace(
            "WorldBegin",
            &format!("Integrator \"photonmap\" {p}\nWorldBegin"),
        );
        let r = render_text(&d, &text, &[], GIB);
        assert_error(&r, &["scene.pbrt:4:", "(0, 4]"]);
    }
    for (p, msg) in [
        (
            "\"float glossyalpha\" -0.5",
            "\"glossyalpha\" must be in [0, inf]",
        ),
        ("\"float glossyalpha\" NaN", "expected a number"),
    ] {
        let text = small_scene("").replace(
            "WorldBegin",
            &format!("Integrator \"photonmap\" {p}\nWorldBegin"),
        );
        let r = render_text(&d, &text, &[], GIB);
        assert_error(&r, &["scene.pbrt:4:", msg]);
    }
}

#[test]
fn case_16_the_output_directory_is_checked_before_rendering() {
    let d = tmp_dir("c16");
    let scene = write(&d, "scene.pbrt", small_scene(""));
    let mut args = render_args(&scene, &d, &[]);
    let n = args.len();
    args[n - 1] = d.join("missing/out.exr").into();
    let r = run_capped(&args, GIB, T);
    assert_error(&r, &["-o ", "cannot write in directory"]);
    assert!(!r.stdout.contains("rendered in"), "{}", r.stdout);
}

#[test]
fn case_17_ply_files_are_read_strictly() {
    let d = tmp_dir("c17");
    let header = |fmt: &str, faces: usize, extra_prop: &str| {
        format!(
            "ply\nformat {fmt}\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n{extra_prop}element face {faces}\nproperty list uchar int vertex_indices\nend_header\n"
        )
    };
    let body = "0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n3 0 2 1\n";
    let world = "Shape \"plymesh\" \"string filename\" \"m.ply\"";
    for (ply, needle) in [
        (
            header("ascii 1.0", 1, "") + body,
            "lines after the last element",
        ),
        (
            header("ascii 1.0", 2, "") + &body.replace("3 0 2 1", "3 0 2 1 7"),
            "5 values on its line, the header declares 4",
        ),
        (header("ascii 2.0", 2, "") + body, "version 2.0"),
        (
            header("ascii 1.0", 2, "property float x\n") + body,
            "property \"x\" twice",
        ),
    ] {
        write(&d, "m.ply", ply);
        let r = render_text(&d, &small_scene(world), &[], GIB);
        assert_error(&r, &["scene.pbrt:12:7", "m.ply", needle]);
    }
    let mut bin = header("binary_little_endian 1.0", 1, "").into_bytes();
    for v in [[0f32, 0., 0.], [1., 0., 0.], [0., 1., 0.]] {
        bin.extend(v.iter().flat_map(|c| c.to_le_bytes()));
    }
    for _ in 0..2 {
        bin.push(3);
        bin.extend([0i32, 1, 2].iter().flat_map(|c| c.to_le_bytes()));
    }
    write(&d, "m.ply", &bin);
    let r = render_text(&d, &small_scene(world), &[], GIB);
    assert_error(&r, &["m.ply", "13 bytes after the last element"]);
    let mut ok = header("binary_little_endian 1.0", 2, "").into_bytes();
    ok.extend(&bin[ok.len()..]);
    write(&d, "m.ply", &ok);
    let r = render_text(&d, &small_scene(world), &[], GIB);
    assert_eq!(r.code, Some(0), "{}", r.describe());
}

#[test]
fn case_18_light_samples_and_threads_are_bounded() {
    let d = tmp_dir("c18");
    let r = render_text(&d, &small_scene(""), &["--light-samples", "10000000"], GIB);
    assert_error(&r, &["--light-samples", "1..=4096"]);
    let r = render_text(&d, &small_scene(""), &["--threads", "100000"], GIB);
    assert_error(&r, &["--threads", "0..=1024"]);
    let r = render_text(&d, &small_scene(""), &["--light-samples", "4096"], GIB);
    assert_eq!(r.code, Some(0), "{}", r.describe());
    // 8x8 pixels x 4096 shadow rays, traced in batches of 16384.
    assert!(ray_count(&r.stdout, "shadow") > 100_000, "{}", r.stdout);
}

#[test]
fn case_19_mirror_sphere_at_depth_limits() {
    let d = tmp_dir("c19");
    // The camera inside a closed mirror sphere of reflectance 1; the light is outside.
    let text = r#"LookAt 0 0 0  0 0 1  0 1 0
Camera "perspective" "float fov" [ 60 ]
Film "rgb" "integer xresolution" [ 8 ] "integer yresolution" [ 8 ]
Integrator "path" "integer maxdepth" [ MAXDEPTH ]
WorldBegin
LightSource "point" "rgb I" [ 100 100 100 ] "point3 from" [ 0 0 5 ]
Material "conductor" "rgb reflectance" [ 1 1 1 ]
Shape "sphere" "float radius" 1
Material "diffuse"
Shape "trianglemesh" "point3 P" [ -3 -2 -3  3 -2 -3  3 -2 3 ] "integer indices" [ 0 1 2 ]
"#;
    let r = render_text(&d, &text.replace("MAXDEPTH", "10000"), &[], GIB);
    assert_error(&r, &["scene.pbrt:4:", "maxdepth", "0..=1000"]);
    for integrator in ["photonmap", "path", "direct"] {
        let args = ["--integrator", integrator];
        let r = render_text(&d, &text.replace("MAXDEPTH", "1000"), &args, GIB);
        assert_eq!(r.code, Some(0), "{}", r.describe());
        let img = photon::imageio::read_exr(&d.join("out.exr")).unwrap();
        let max = img.pixels.iter().flatten().fold(0.0f32, |a, &b| a.max(b));
        assert_eq!(
            max, 0.0,
            "{integrator}: light leaked into the closed mirror sphere"
        );
    }
}

#[test]
fn case_20_backends_agree_to_noise_level() {
    // The README promises the same image to noise level from Embree and obvhs (not
    // bit-identical): relMSE below 2e-3 at 16x16 pixels' worth of low-spp noise.
    let d = tmp_dir("c20");
    let scene = Path::new("../shared/scenes/cornell-spheres/scene.pbrt");
    let mut imgs = Vec::new();
    for backend in ["embree", "obvhs"] {
        let out = d.join(format!("{backend}.exr"));
        let args: Vec<std::ffi::OsString> = vec![
            "render".into(),
            scene.into(),
            "--res".into(),
            "32x32".into(),
            "--spp".into(),
            "4".into(),
            "--backend".into(),
            backend.into(),
            "--no-png".into(),
            "-o".into(),
            out.clone().into(),
        ];
        let r = run_capped(&args, 4 * GIB, T);
        assert_eq!(r.code, Some(0), "{}", r.describe());
        imgs.push(photon::imageio::read_exr(&out).unwrap());
    }
    let m = photon::imageio::metrics::compare(&imgs[1], &imgs[0], Default::default()).unwrap();
    println!(
        "cornell-spheres 32x32 4 spp: relMSE obvhs vs Embree {:.2e}",
        m.overall.relmse
    );
    assert!(m.overall.relmse < 2e-3, "relMSE {}", m.overall.relmse);
}

/// The numbers of the `memory:` line a render prints: (estimate, peak resident), in bytes.
fn memory_line(stdout: &str) -> (u64, u64) {
    let line = stdout
        .lines()
        .find(|l| l.starts_with("memory: estimated "))
        .expect("a memory line");
    let nums: Vec<u64> = line
        .split_whitespace()
        .filter_map(|w| w.parse().ok())
        .collect();
    (nums[0], nums[1])
}

/// The memory model against the measured peak (VmHWM) of real renders: never below it, and
/// within a factor 1.5 above it for the film (measured constants), 2 for the photon maps (sized
/// by a pilot trace with a margin).
#[test]
fn resource_model_bounds_the_measured_peak() {
    let d = tmp_dir("model");
    let scene = Path::new("../shared/scenes/cornell-box/scene-v4.pbrt");
    let run = |extra: &[&str]| {
        let mut args: Vec<std::ffi::OsString> = vec![
            "render".into(),
            scene.into(),
            "--spp".into(),
            "1".into(),
            "--threads".into(),
            "2".into(),
            "-o".into(),
            d.join("m.exr").into(),
            "--png".into(),
            d.join("m.png").into(),
        ];
        args.extend(extra.iter().map(Into::into));
        let r = run_capped(&args, 4 * GIB, T);
        assert_eq!(r.code, Some(0), "{}", r.describe());
        memory_line(&r.stdout)
    };
    let (est, peak) = run(&["--res", "2048x2048", "--integrator", "direct"]);
    println!("film 2048x2048: estimate {est}, peak {peak}");
    assert!(
        peak <= est && (est as f64) < 1.5 * peak as f64,
        "{est} vs {peak}"
    );
    let (est, peak) = run(&["--res", "16x16", "--global-photons", "3000000"]);
    println!("3M photons: estimate {est}, peak {peak}");
    assert!(
        peak <= est && (est as f64) < 2.0 * peak as f64,
        "{est} vs {peak}"
    );
}

// Issue 22 ("Hostile input III"): graphs of textures and materials.

/// `Texture` lines defining `n` textures `t1..tn` of `class` (after a constant `t0`), each
/// naming the one before it in `params` (`{prev}` stands for its name).
fn texture_chain(n: usize, class: &str, params: &str) -> String {
    let mut s = String::from("Texture \"t0\" \"float\" \"constant\" \"float value\" 0.5\n");
    for i in 1..=n {
        let p = params.replace("{prev}", &format!("t{}", i - 1));
        s += &format!("Texture \"t{i}\" \"float\" \"{class}\" {p}\n");
    }
    s
}

/// 10,000 nested `scale` textures overflowed the stack (rc 134): the texture 65 deep (`t64`,
/// over `t63` ... `t0`) is refused where it is defined.
#[test]
fn issue22_case_02_deep_texture_chains_are_refused_where_defined() {
    let d = tmp_dir("i22c02");
    let chain = texture_chain(10_000, "scale", "\"texture tex\" \"{prev}\"");
    let world = format!(
        "{chain}Material \"conductor\" \"texture roughness\" \"t10000\"\n\
         Shape \"sphere\" \"float radius\" 0.3\n"
    );
    let r = render_text(&d, &small_scene(&world), &[], GIB);
    assert_error(
        &r,
        &[
            "scene.pbrt:76:",
            "\"t64\"",
            "65 textures deep",
            "at most 64",
        ],
    );
    // 64 deep renders.
    let chain = texture_chain(63, "scale", "\"texture tex\" \"{prev}\"");
    let world = format!(
        "{chain}Material \"conductor\" \"texture roughness\" \"t63\"\n\
         Shape \"sphere\" \"float radius\" 0.3\n"
    );
    let r = render_text(&d, &small_scene(&world), &[], GIB);
    assert_eq!(r.code, Some(0), "{}", r.describe());
}

/// 40 `mix` textures each naming the previous one twice (3.4 kB) ran forever in `render` and
/// `check` (2^40 visits); the one whose lookup would pass 10,000 evaluations is refused, and
/// `check` says the same.
#[test]
fn issue22_case_13_doubling_texture_graphs_are_refused() {
    let d = tmp_dir("i22c13");
    let chain = texture_chain(
        40,
        "mix",
        "\"texture tex1\" \"{prev}\" \"texture tex2\" \"{prev}\"",
    );
    let world = format!(
        "{chain}Material \"conductor\" \"texture roughness\" \"t40\"\n\
         Shape \"sphere\" \"float radius\" 0.3\n"
    );
    let r = render_text(&d, &small_scene(&world), &[], GIB);
    // t_k's lookup evaluates 3 (2^k - 1) + 2^k textures (tex1, tex2 and a constant amount at
    // each level): t12, 12286, is the first past 10,000.
    assert_error(
        &r,
        &[
            "scene.pbrt:24:",
            "\"t12\"",
            "12286 textures",
            "at most 10000",
        ],
    );
    let scene = d.join("scene.pbrt");
    let c = run_capped(["check".as_ref(), scene.as_os_str()], GIB, T);
    assert_eq!(c.code, Some(2), "{}", c.describe());
    assert!(c.stdout.contains("\"t12\""), "{}", c.describe());
}

/// More than 64 nested `mix` materials rendered black without a word: the 65th is refused at
/// its `materials` parameter; one naming the previous twice at each of 64 levels loads at once
/// (the depth is found in linear time).
#[test]
fn issue22_case_20_mix_materials_nest_at_most_64_deep() {
    let d = tmp_dir("i22c20");
    let mixes = |n: usize| {
        let mut s = String::from(
            "MakeNamedMaterial \"m0\" \"string type\" \"diffuse\" \"rgb reflectance\" [ 0.5 0.5 0.5 ]\n",
        );
        for i in 1..=n {
            s += &format!(
                "MakeNamedMaterial \"m{i}\" \"string type\" \"mix\" \"string materials\" [ \"m{p}\" \"m{p}\" ]\n",
                p = i - 1
            );
        }
        s + &format!("NamedMaterial \"m{n}\"\nShape \"sphere\" \"float radius\" 0.3\n")
    };
    let r = render_text(&d, &small_scene(&mixes(65)), &[], GIB);
    assert_error(
        &r,
        &["scene.pbrt:77:45", "nests 65 mix materials", "at most 64"],
    );
    let r = render_text(&d, &small_scene(&mixes(64)), &[], GIB);
    assert_eq!(r.code, Some(0), "{}", r.describe());
}

/// A PNG holding a header (IHDR `w` x `h`, 8-bit RGB), an IDAT of no pixels and IEND: what a
/// decoder learns before it allocates, and a truncated file past that.
fn png_header_only(w: u32, h: u32) -> Vec<u8> {
    let chunk = |ty: &[u8], data: &[u8]| {
        let mut crc = flate2::Crc::new();
        crc.update(ty);
        crc.update(data);
        let mut c = (data.len() as u32).to_be_bytes().to_vec();
        c.extend_from_slice(ty);
        c.extend_from_slice(data);
        c.extend_from_slice(&crc.sum().to_be_bytes());
        c
    };
    let mut ihdr = w.to_be_bytes().to_vec();
    ihdr.extend_from_slice(&h.to_be_bytes());
    ihdr.extend_from_slice(&[8, 2, 0, 0, 0]);
    let mut png = b"\x89PNG\r\n\x1a\n".to_vec();
    png.extend(chunk(b"IHDR", &ihdr));
    png.extend(chunk(
        b"IDAT",
        &[0x78, 0x9c, 0x03, 0x00, 0x00, 0x00, 0x00, 0x01],
    ));
    png.extend(chunk(b"IEND", &[]));
    png
}

/// A 16000x16000 PNG texture was decoded (6.1 GB) before the memory check, which then
/// estimated 3.1 GB; under a 2 GB address-space cap the image crate panicked (issue 22,
/// cases 4 and 15). The header's size is now reserved against the budget first: the error
/// names the texture and the decode's peak, and nothing is allocated.
#[test]
fn issue22_case_04_15_image_sizes_are_reserved_before_decoding() {
    let d = tmp_dir("i22c04");
    std::fs::write(d.join("big.png"), png_header_only(16000, 16000)).unwrap();
    let world = "Texture \"t\" \"spectrum\" \"imagemap\" \"string filename\" \"big.png\"\n\
                 Material \"diffuse\" \"texture reflectance\" \"t\"\n\
                 Shape \"sphere\" \"float radius\" 0.3\n";
    // 16000^2 x (3 bytes decoded + 12 converted + 12 texels) = 6.9 GB.
    let r = render_text(&d, &small_scene(world), &["--max-memory", "1G"], 2 * GIB);
    assert_error(
        &r,
        &[
            "scene.pbrt:12:",
            "big.png",
            "decoding it needs 6.9 GB",
            "--max-memory",
        ],
    );
    // Under the cap alone (default budget: 80% of what the cap leaves), the same.
    let r = render_text(&d, &small_scene(world), &[], 2 * GIB);
    assert_error(&r, &["big.png", "decoding it needs 6.9 GB"]);
}

/// Instancing (issue 22, case 16): 20,000 instances of a 20,000-triangle object allocated
/// 6.9 GB in the parser before being refused; each copy is now reserved first, so the
/// instance that passes `--max-memory` is the error. One million one-triangle instances were
/// estimated at 194 MB and peaked at 932 MB: each mesh's own cost is in the estimate now.
#[test]
fn issue22_case_16_instances_are_in_the_memory_model() {
    let d = tmp_dir("i22c16");
    let mut object = String::from("ObjectBegin \"big\"\nShape \"trianglemesh\" \"point3 P\" [");
    for i in 0..20_000 {
        let x = (i % 200) as f32 * 0.001;
        let y = (i / 200) as f32 * 0.001;
        object += &format!(" {x} {y} 0 {} {y} 0 {x} {} 0", x + 0.001, y + 0.001);
    }
    object += " ] \"integer indices\" [";
    for i in 0..60_000 {
        object += &format!(" {i}");
    }
    object += " ]\nObjectEnd\n";
    for i in 0..20_000 {
        object += &format!(
            "AttributeBegin Translate {} 0 -3 ObjectInstance \"big\" AttributeEnd\n",
            i as f32 * 1e-4
        );
    }
    let r = render_text(&d, &small_scene(&object), &["--max-memory", "400M"], GIB);
    assert_error(&r, &["a copy of object \"big\"", "--max-memory"]);

    let mut many = String::from(
        "ObjectBegin \"o\"\nShape \"trianglemesh\" \"point3 P\" [ 0 0 0 0.001 0 0 0 0.001 0 ] \"integer indices\" [ 0 1 2 ]\nObjectEnd\n",
    );
    for i in 0..1_000_000 {
        many += &format!(
            "AttributeBegin Translate {} {} -3 ObjectInstance \"o\" AttributeEnd\n",
            (i % 1000) as f32 * 1e-3 - 0.5,
            (i / 1000) as f32 * 1e-3
        );
    }
    let r = render_text(&d, &small_scene(&many), &["--max-memory", "400M"], 2 * GIB);
    assert_error(&r, &["a copy of object \"o\"", "--max-memory"]);
    let r = render_text(&d, &small_scene(&many), &[], 3 * GIB);
    assert_eq!(r.code, Some(0), "{}", r.describe());
    let memory = r
        .stdout
        .lines()
        .find(|l| l.starts_with("memory:"))
        .expect("a memory line");
    let number = |key: &str| -> f64 {
        let after = memory.split(key).nth(1).expect(key);
        after.trim().split(' ').next().unwrap().parse().unwrap()
    };
    let (estimate, peak) = (number("estimated"), number("peak resident"));
    let ratio = estimate / peak;
    assert!(
        (0.7..=2.0).contains(&ratio),
        "estimate/peak {ratio:.2}: {memory}"
    );
}

/// PLY files (issue 22, cases 17 and 22): a `.ply.gz` declaring 3 vertices and a face followed
/// by zeros was decompressed whole (3 GiB) before the data were found too long; it now stops
/// at what the header declares. A vertex element with `nx ny` but no `nz` dropped its normals
/// without a word; it is an error naming the properties.
#[test]
fn issue22_case_17_22_ply_files_are_read_as_declared() {
    use std::io::Write;
    let d = tmp_dir("i22c17");
    let header = "ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty float x\n\
                  property float y\nproperty float z\nelement face 1\n\
                  property list uchar int vertex_indices\nend_header\n";
    let mut body: Vec<u8> = header.as_bytes().to_vec();
    for v in [0.0f32, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0] {
        body.extend_from_slice(&v.to_le_bytes());
    }
    body.push(3);
    for i in [0i32, 1, 2] {
        body.extend_from_slice(&i.to_le_bytes());
    }
    let gz = |name: &str, zeros: usize| {
        let f = std::fs::File::create(d.join(name)).unwrap();
        let mut e = flate2::write::GzEncoder::new(f, flate2::Compression::fast());
        e.write_all(&body).unwrap();
        e.write_all(&vec![0u8; zeros]).unwrap();
        e.finish().unwrap();
    };
    gz("ok.ply.gz", 0);
    gz("bomb.ply.gz", 64 << 20);
    let shape = |f: &str| format!("Shape \"plymesh\" \"string filename\" \"{f}\"\n");
    let r = render_text(&d, &small_scene(&shape("ok.ply.gz")), &[], GIB);
    assert_eq!(r.code, Some(0), "{}", r.describe());
    let r = render_text(&d, &small_scene(&shape("bomb.ply.gz")), &[], GIB);
    assert_error(
        &r,
        &[
            "bomb.ply.gz",
            "decompresses to more than its header declares",
        ],
    );

    let ascii = "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n\
                 property float z\nproperty float nx\nproperty float ny\nelement face 1\n\
                 property list uchar int vertex_indices\nend_header\n\
                 0 0 0 0 1\n1 0 0 0 1\n0 1 0 0 1\n3 0 1 2\n";
    std::fs::write(d.join("nonz.ply"), ascii).unwrap();
    let r = render_text(&d, &small_scene(&shape("nonz.ply")), &[], GIB);
    assert_error(&r, &["nonz.ply", "has nx, ny but not all of nx, ny, nz"]);
}

/// Error lines of 599-1012 bytes (issue 22, case 19): a PLY of NUL bytes, a 65,000-character
/// parameter name, merge's missing-layer error and resume's settings mismatch. Each is now one
/// line of at most 200 bytes ([`check_run`] checks every error line of these tests so).
#[test]
fn issue22_case_19_every_error_is_one_short_line() {
    let d = tmp_dir("i22c19");
    std::fs::write(d.join("nul.ply"), vec![0u8; 1000]).unwrap();
    let r = render_text(
        &d,
        &small_scene("Shape \"plymesh\" \"string filename\" \"nul.ply\"\n"),
        &[],
        GIB,
    );
    assert_error(&r, &["nul.ply"]);
    let long = "a".repeat(65_000);
    let r = render_text(
        &d,
        &small_scene(&format!("Shape \"sphere\" \"float {long}\" 1\n")),
        &[],
        GIB,
    );
    assert_error(&r, &["scene.pbrt:12:"]);

    // A part without its sum layers, and a resume with other settings.
    let scene = write(&d, "scene.pbrt", small_scene(""));
    let part = d.join("part.exr");
    let mut args = render_args(&scene, &d, &["--progressive", "--passes", "0..1"]);
    let o = args.iter().position(|a| a == "-o").unwrap();
    args[o + 1] = part.clone().into();
    let r = run_capped(args, GIB, T);
    assert_eq!(r.code, Some(0), "{}", r.describe());
    let attrs = photon::imageio::read_exr_attributes(&part).unwrap();
    let attrs: Vec<(&str, &str)> = attrs
        .iter()
        .filter(|(k, _)| k.starts_with("photon."))
        .map(|(k, v)| (k.as_str(), v.as_str()))
        .collect();
    let rgb = photon::imageio::read_exr(&part).unwrap();
    let extra = photon::imageio::ExrExtra {
        uint_layers: &[],
        attributes: &attrs,
        ..Default::default()
    };
    let bare = d.join("bare.exr");
    photon::imageio::write_exr_with(&bare, &rgb, &[], photon::imageio::ExrPixel::Float, extra)
        .unwrap();
    let merged = d.join("merged.exr");
    let r = run_capped(
        [
            "merge".as_ref(),
            bare.as_os_str(),
            "-o".as_ref(),
            merged.as_os_str(),
            "--no-png".as_ref(),
        ],
        GIB,
        T,
    );
    assert_error(&r, &["bare.exr", "sum.direct"]);
    let mut args = render_args(&scene, &d, &["--progressive", "--passes", "0..2"]);
    args.extend([
        "--resume".into(),
        part.clone().into(),
        "--pass-spp".into(),
        "3".into(),
    ]);
    let r = run_capped(args, GIB, T);
    assert_error(&r, &["part.exr"]);
}

/// The path in "saved to PATH instead" of a message on stderr.
fn saved_path(stderr: &str) -> PathBuf {
    let after = stderr
        .split("saved to ")
        .nth(1)
        .unwrap_or_else(|| panic!("no \"saved to\" in {stderr:?}"));
    PathBuf::from(after.split(" instead").next().unwrap())
}

/// `-o` through a symlink was followed by photon itself (it reads the link and renames over
/// its target), so the kernel's protected-symlink rule could not help in a shared sticky
/// folder such as /tmp: another user's link there sent the image wherever it pointed. Such a
/// link (in a sticky directory, owned by another uid) is refused; the same link owned by this
/// process's user is followed as before.
#[test]
fn issue22_case_07_other_users_symlinks_in_sticky_dirs_are_refused() {
    use std::os::unix::fs::{MetadataExt, PermissionsExt};
    let d = tmp_dir("i22c07");
    let scene = write(&d, "scene.pbrt", small_scene(""));
    let sticky = d.join("sticky");
    std::fs::create_dir(&sticky).unwrap();
    std::fs::set_permissions(&sticky, std::fs::Permissions::from_mode(0o1777)).unwrap();
    let victim = write(&d, "victim.exr", "precious");
    let link = sticky.join("out.exr");
    std::os::unix::fs::symlink(&victim, &link).unwrap();
    std::os::unix::fs::lchown(&link, Some(65534), Some(65534)).unwrap();
    let mut args = render_args(&scene, &d, &[]);
    let n = args.len();
    args[n - 1] = link.clone().into();
    let r = run_capped(&args, GIB, T);
    assert_error(&r, &["-o ", "sticky/out.exr", "symlink", "uid 65534"]);
    assert!(!r.stdout.contains("rendered in"), "{}", r.stdout);
    assert_eq!(std::fs::read_to_string(&victim).unwrap(), "precious");
    assert!(std::fs::symlink_metadata(&link)
        .unwrap()
        .file_type()
        .is_symlink());
    // Owned by this process's user, the link is followed: its target gets the image.
    let me = std::fs::metadata(&scene).unwrap().uid();
    std::os::unix::fs::lchown(&link, Some(me), None).unwrap();
    let r = run_capped(&args, GIB, T);
    assert_eq!(r.code, Some(0), "{}", r.describe());
    assert!(photon::imageio::read_exr(&victim).is_ok());
}

/// A checkpoint write that failed (disk full: `/dev/full`) stopped the render with exit 2 and
/// dropped every finished pass; `-o` was never written. It is a one-line warning now and the
/// render writes its image.
#[test]
fn issue22_case_08_a_failing_checkpoint_is_a_warning() {
    let d = tmp_dir("i22c08");
    let extra = [
        "--passes",
        "0..3",
        "--checkpoint",
        "/dev/full",
        "--every",
        "1ms",
    ];
    let r = render_text(&d, &small_scene(""), &extra, GIB);
    assert_eq!(r.code, Some(0), "{}", r.describe());
    let warnings: Vec<&str> = r.stderr.lines().filter(|l| l.contains("warning")).collect();
    assert!(!warnings.is_empty(), "{}", r.describe());
    for w in warnings {
        assert!(
            w.starts_with("photon: warning: --checkpoint /dev/full: "),
            "{w}"
        );
    }
    let p = photon::integrator::passes::Partial::read(&d.join("out.exr")).unwrap();
    assert_eq!(p.passes, 0..3);
}

/// A render given an existing checkpoint without `--resume` replaced it silently (passes 0..12
/// became 0..2): it is refused before any work, and `--resume` continues it.
#[test]
fn issue22_case_09_an_existing_checkpoint_needs_resume() {
    let d = tmp_dir("i22c09");
    let ck = d.join("ck.exr");
    let ck_s = ck.to_str().unwrap();
    let r = render_text(
        &d,
        &small_scene(""),
        &["--passes", "0..2", "--checkpoint", ck_s],
        GIB,
    );
    assert_eq!(r.code, Some(0), "{}", r.describe());
    let before = std::fs::read(&ck).unwrap();
    let r = render_text(
        &d,
        &small_scene(""),
        &["--passes", "0..1", "--checkpoint", ck_s],
        GIB,
    );
    assert_error(&r, &["--checkpoint ", "ck.exr", "already", "--resume"]);
    assert!(!r.stdout.contains("rendered in"), "{}", r.stdout);
    assert_eq!(
        std::fs::read(&ck).unwrap(),
        before,
        "the checkpoint is kept"
    );
    let r = render_text(
        &d,
        &small_scene(""),
        &["--passes", "0..3", "--checkpoint", ck_s, "--resume", ck_s],
        GIB,
    );
    assert_eq!(r.code, Some(0), "{}", r.describe());
    let p = photon::integrator::passes::Partial::read(&ck).unwrap();
    assert_eq!(p.passes, 0..3);
}

/// When `-o` could not be written at the end (disk full; its folder removed during the
/// render) the finished image was discarded. It is saved to a fallback file, named in one line
/// on stderr, and the exit code is 2.
#[test]
fn issue22_case_10_an_unwritable_destination_keeps_the_image_elsewhere() {
    let d = tmp_dir("i22c10");
    let scene = write(&d, "scene.pbrt", small_scene(""));
    let mut args = render_args(&scene, &d, &[]);
    let n = args.len();
    args[n - 1] = "/dev/full".into();
    let r = run_capped(&args, GIB, T);
    assert_error(&r, &["-o /dev/full: ", "saved to "]);
    let saved = saved_path(&r.stderr);
    let image = photon::imageio::read_exr(&saved);
    let _ = std::fs::remove_file(&saved);
    assert_eq!(image.unwrap().width, 8);
    // The folder of -o removed while the render writes its checkpoint into a FIFO (the test
    // reads the FIFO only once the folder is gone; at 128x128 the checkpoint is far larger
    // than a pipe's buffer, so the render waits for it).
    let sub = d.join("sub");
    std::fs::create_dir(&sub).unwrap();
    let fifo = d.join("ck.fifo");
    mkfifo(&fifo);
    let (f, s) = (fifo.clone(), sub.clone());
    let reader = std::thread::spawn(move || {
        use std::io::Read;
        let mut pipe = std::fs::File::open(f).unwrap();
        std::fs::remove_dir_all(s).unwrap();
        let mut bytes = Vec::new();
        pipe.read_to_end(&mut bytes).unwrap();
    });
    let fifo_s = fifo.to_str().unwrap();
    let extra = [
        "--res",
        "128x128",
        "--passes",
        "0..1",
        "--checkpoint",
        fifo_s,
    ];
    let args = render_args(&scene, &sub, &extra);
    let r = run_capped(&args, GIB, T);
    // Besides the "pass 1/1 done" progress line, one error line.
    assert_eq!(r.code, Some(2), "{}", r.describe());
    let lines: Vec<&str> = r
        .stderr
        .lines()
        .filter(|l| !l.starts_with("pass "))
        .collect();
    assert_eq!(lines.len(), 1, "{}", r.describe());
    assert!(lines[0].starts_with("photon: -o ") && lines[0].contains("sub/out.exr: "));
    reader.join().unwrap();
    let saved = saved_path(&r.stderr);
    let part = photon::integrator::passes::Partial::read(&saved);
    let _ = std::fs::remove_file(&saved);
    assert_eq!(part.unwrap().passes, 0..1);
}

/// `merge -o`, `merge --png` and `compare --error-png` replaced a FIFO or a device with a
/// regular file (as root, `-o /dev/null` replaced /dev/null): they are planned and written as
/// `render`'s outputs, so a FIFO gets the bytes and stays a FIFO.
#[test]
fn issue22_case_11_merge_and_compare_write_into_fifos() {
    let d = tmp_dir("i22c11");
    let scene = write(&d, "scene.pbrt", small_scene(""));
    let r = run_capped(render_args(&scene, &d, &["--passes", "0..1"]), GIB, T);
    assert_eq!(r.code, Some(0), "{}", r.describe());
    let part = d.join("out.exr");
    let got = |rx: std::sync::mpsc::Receiver<Vec<u8>>, r: &Run| {
        rx.recv_timeout(Duration::from_secs(30))
            .unwrap_or_else(|_| panic!("nothing written into the FIFO: {}", r.describe()))
    };
    // merge -o FIFO.
    let fifo = d.join("merged.fifo");
    mkfifo(&fifo);
    let rx = fifo_reader(&fifo);
    let args: Vec<&std::ffi::OsStr> = vec![
        "merge".as_ref(),
        part.as_os_str(),
        "--no-png".as_ref(),
        "-o".as_ref(),
        fifo.as_os_str(),
    ];
    let r = run_capped(&args, GIB, T);
    assert_eq!(r.code, Some(0), "{}", r.describe());
    assert!(is_fifo(&fifo), "merge -o replaced the FIFO");
    assert_eq!(&got(rx, &r)[..4], &[0x76, 0x2f, 0x31, 0x01], "EXR magic");
    // merge --png FIFO.
    let png = d.join("png.fifo");
    mkfifo(&png);
    let rx = fifo_reader(&png);
    let merged = d.join("merged.exr");
    let args: Vec<&std::ffi::OsStr> = vec![
        "merge".as_ref(),
        part.as_os_str(),
        "-o".as_ref(),
        merged.as_os_str(),
        "--png".as_ref(),
        png.as_os_str(),
    ];
    let r = run_capped(&args, GIB, T);
    assert_eq!(r.code, Some(0), "{}", r.describe());
    assert!(is_fifo(&png), "merge --png replaced the FIFO");
    assert_eq!(&got(rx, &r)[1..4], b"PNG");
    // compare --error-png FIFO.
    let err = d.join("error.fifo");
    mkfifo(&err);
    let rx = fifo_reader(&err);
    let args: Vec<&std::ffi::OsStr> = vec![
        "compare".as_ref(),
        merged.as_os_str(),
        part.as_os_str(),
        "--error-png".as_ref(),
        err.as_os_str(),
    ];
    let r = run_capped(&args, GIB, T);
    assert_eq!(r.code, Some(0), "{}", r.describe());
    assert!(is_fifo(&err), "compare --error-png replaced the FIFO");
    assert_eq!(&got(rx, &r)[1..4], b"PNG");
    // A directory for merge -o is refused before the parts are read, as for render.
    let args: Vec<&std::ffi::OsStr> = vec![
        "merge".as_ref(),
        "missing.exr".as_ref(),
        "-o".as_ref(),
        d.as_os_str(),
    ];
    assert_error(&run_capped(&args, GIB, T), &["-o ", "is a directory"]);
}

/// An ordinary render stopped by SIGTERM exited 143 without a word and without its finished
/// tiles. It says so in one line and saves the finished tiles (the others black) beside the
/// other fallbacks, leaving `-o` as it was (a stopped render never replaces an output).
#[test]
fn issue22_case_12_an_interrupted_render_keeps_its_finished_tiles() {
    let d = tmp_dir("i22c12");
    // A sky, so that every finished tile has light in it (the corners see past the walls: a
    // stop with only the first tiles finished left an all-black image).
    let sky = r#"LightSource "infinite" "rgb L" [ 0.2 0.2 0.2 ]"#;
    let scene = write(&d, "scene.pbrt", small_scene(sky));
    let out = write(&d, "out.exr", "old");
    let extra = ["--res", "256x256", "--spp", "1024", "--integrator", "path"];
    // Not a timing assertion: stopped after 3 s, long enough for some of the 256 tiles to
    // finish and far from all; on a loaded machine none may have, then again after 12, 30 s.
    let mut r = None;
    for wait in [3, 12, 30] {
        let mut bg = Background::start(render_args(&scene, &d, &extra));
        assert!(bg.wait_for_line("render:"));
        std::thread::sleep(Duration::from_secs(wait));
        bg.signal("TERM");
        let got = bg.finish(T);
        let none = got.stderr.contains(" 0 of 256 tiles");
        r = Some(got);
        if !none {
            break;
        }
        let _ = std::fs::remove_file(saved_path(&r.as_ref().unwrap().stderr));
    }
    let r = r.unwrap();
    assert_eq!(r.code, Some(143), "{}", r.describe());
    let lines: Vec<&str> = (r.stderr.lines())
        .filter(|l| !l.starts_with("progress: "))
        .collect();
    assert_eq!(lines.len(), 1, "{}", r.describe());
    assert!(lines[0].contains("SIGTERM") && lines[0].contains(" of 256 tiles"));
    assert_eq!(std::fs::read(&out).unwrap(), b"old");
    let saved = saved_path(&r.stderr);
    let image = photon::imageio::read_exr(&saved);
    let _ = std::fs::remove_file(&saved);
    let image = image.unwrap();
    assert_eq!((image.width, image.height), (256, 256));
    assert!(image.pixels.iter().any(|p| p[0] > 0.0), "finished tiles");
}

/// `--passes` with a pass number near 1e13 (or such a range forged in a `--resume` file) hung
/// in the radius schedule and ignored SIGTERM: pass numbers are bounded (at most 2^20 passes)
/// with a located error; and `-o` naming a FIFO nobody reads ignored SIGTERM and left its
/// temporary EXR in the temporary directory.
#[test]
fn issue22_case_14_pass_ranges_are_bounded_and_fifo_writes_interruptible() {
    let d = tmp_dir("i22c14");
    let huge = ["--passes", "10000000000000..10000000000001"];
    let r = render_text(&d, &small_scene(""), &huge, GIB);
    assert_error(&r, &["--passes", "1048576"]);
    // A partial image claiming passes 0..1e13, resumed: refused, naming the file.
    let r = render_text(&d, &small_scene(""), &["--passes", "0..1"], GIB);
    assert_eq!(r.code, Some(0), "{}", r.describe());
    let mut p = photon::integrator::passes::Partial::read(&d.join("out.exr")).unwrap();
    p.passes = 0..10_000_000_000_000;
    let forged = d.join("forged.exr");
    p.write(&forged).unwrap();
    let extra = ["--progressive", "--resume", forged.to_str().unwrap()];
    let r = render_text(&d, &small_scene(""), &extra, GIB);
    assert_error(&r, &["--resume ", "forged.exr", "1048576"]);
    // -o FIFO without a reader, then SIGTERM.
    let fifo = d.join("pipe.exr");
    mkfifo(&fifo);
    let scene = d.join("scene.pbrt");
    let mut args = render_args(&scene, &d, &[]);
    let n = args.len();
    args[n - 1] = fifo.clone().into();
    let mut bg = Background::start(&args);
    let prefix = format!("photon-{}-", bg.pid());
    assert!(bg.wait_for_line("rendered in"));
    bg.signal("TERM");
    let r = bg.finish(Duration::from_secs(60));
    assert_eq!(r.code, Some(143), "{}", r.describe());
    assert!(r.stderr.contains("SIGTERM"), "{}", r.describe());
    assert!(is_fifo(&fifo));
    assert_eq!(temp_files_starting_with(&prefix), Vec::<PathBuf>::new());
}

/// A render blocked opening a FIFO (`--png` here) ignored SIGINT: the open is interruptible,
/// the temporaries are removed, nothing is replaced (not `-o` either), exit 130.
#[test]
fn issue22_case_23_opening_a_fifo_is_interruptible() {
    let d = tmp_dir("i22c23");
    let scene = write(&d, "scene.pbrt", small_scene(""));
    let out = write(&d, "out.exr", "old");
    let fifo = d.join("preview.png");
    mkfifo(&fifo);
    let mut args = render_args(&scene, &d, &[]);
    args.retain(|a| a != "--no-png");
    args.extend(["--png".into(), fifo.clone().into()]);
    let mut bg = Background::start(&args);
    let prefix = format!("photon-{}-", bg.pid());
    assert!(bg.wait_for_line("rendered in"));
    bg.signal("INT");
    let r = bg.finish(Duration::from_secs(60));
    assert_eq!(r.code, Some(130), "{}", r.describe());
    assert!(r.stderr.contains("SIGINT"), "{}", r.describe());
    assert!(is_fifo(&fifo));
    assert_eq!(std::fs::read(&out).unwrap(), b"old");
    assert_eq!(temp_files_starting_with(&prefix), Vec::<PathBuf>::new());
    let mut names: Vec<String> = std::fs::read_dir(&d)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    names.sort();
    assert_eq!(names, ["out.exr", "preview.png", "scene.pbrt"]);
}

/// `bench --csv`/`--json` were written with `fs::write` after the whole benchmark, outside the
/// output planner (a bad destination was found only at the end, a regular file was truncated
/// in place): they are planned before the work like every other output, so a directory is
/// refused at once.
#[test]
fn issue22_case_11_bench_outputs_are_planned_before_the_work() {
    let d = tmp_dir("i22c11b");
    let args: Vec<&std::ffi::OsStr> = vec!["bench".as_ref(), "--csv".as_ref(), d.as_os_str()];
    let r = run_capped(&args, 4 * GIB, T);
    assert_error(&r, &["--csv ", "is a directory"]);
    assert!(!r.stdout.contains("plan:"), "{}", r.stdout);
}

/// `converge` wrote its CSV, plot and images with its own temporary-and-rename, outside the
/// output planner (issue 22, case 11: every subcommand's outputs through one planner): a
/// `converge.csv` that is a directory is now refused before the first render, naming it.
#[test]
fn issue22_case_11_converge_outputs_are_planned_before_the_work() {
    let d = tmp_dir("i22c11conv");
    let scene = write(&d, "scene.pbrt", small_scene(""));
    let reference = d.join("ref.exr");
    photon::imageio::write_exr(
        &reference,
        &photon::imageio::RgbImage::new(8, 8),
        &[],
        photon::imageio::ExrPixel::Float,
    )
    .unwrap();
    let out = d.join("out");
    std::fs::create_dir_all(out.join("converge.csv")).unwrap();
    let args: Vec<&std::ffi::OsStr> = vec![
        "converge".as_ref(),
        scene.as_os_str(),
        "--reference".as_ref(),
        reference.as_os_str(),
        "--budgets".as_ref(),
        "0.2".as_ref(),
        "--methods".as_ref(),
        "path".as_ref(),
        "--out".as_ref(),
        out.as_os_str(),
    ];
    let r = run_capped(&args, 4 * GIB, T);
    assert_error(&r, &["--out ", "converge.csv", "directory"]);
    assert!(!r.stdout.contains("budget"), "rendered first: {}", r.stdout);
}

/// `--pass-spp` took up to 2^32-1 and `--time 1e300s` was accepted while `--spp` is capped at
/// 2^20 (issue 22, case 18): both are refused by their parsers, naming the flag and the range.
#[test]
fn issue22_case_18_pass_spp_and_durations_are_capped() {
    let d = tmp_dir("i22c18");
    for (flag, value, range) in [
        ("--pass-spp", "4294967295", "1..=1048576"),
        ("--time", "1e300s", "at most 31536000 s"),
        ("--every", "1e300s", "at most 31536000 s"),
    ] {
        let r = render_text(&d, &small_scene(""), &["--progressive", flag, value], GIB);
        assert_error(&r, &[flag, range]);
    }
}
