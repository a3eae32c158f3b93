//! The `photon` binary: outputs, exit codes, one-line errors, and that a failed render never
//! replaces a good image.
use crate::support as common;
use common::photon;
use std::path::{Path, PathBuf};

fn tmp(name: &str) -> PathBuf {
    common::scratch("cli", name)
}

#[test]
fn render_writes_exr_and_png_with_layers() {
    let dir = tmp("render");
    let exr = dir.join("out.exr");
    let out = photon()
        .args([
            "render",
            "scenes/cornell-glass.pbrt",
            "--res",
            "32x24",
            "--spp",
            "2",
            "-o",
        ])
        .arg(&exr)
        .output()
        .unwrap();
    let stdout = String::from_utf8_lossy(&out.stdout);
    println!("{stdout}");
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(stdout.contains("triangles") && stdout.contains("Mrays/s"));
    let img = photon::imageio::read_exr(&exr).unwrap();
    assert_eq!((img.width, img.height), (32, 24));
    for layer in ["direct", "specular", "caustic", "indirect"] {
        let l = photon::imageio::read_exr_layer(&exr, layer).unwrap();
        assert_eq!(l.width, 32);
    }
    assert!(dir.join("out.png").exists());
    // No temporary files are left behind.
    let names: Vec<_> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().file_name())
        .collect();
    assert_eq!(names.len(), 2, "{names:?}");
}

/// The EXR's RGB is the sum of its four component layers.
#[test]
fn components_sum_to_the_image() {
    let dir = tmp("components");
    let exr = dir.join("c.exr");
    let st = photon()
        .args([
            "render",
            "../shared/scenes/cornell-spheres/scene.pbrt",
            "--res",
            "32x32",
            "--spp",
            "4",
            "--no-png",
            "-o",
        ])
        .arg(&exr)
        .status()
        .unwrap();
    assert!(st.success());
    let img = photon::imageio::read_exr(&exr).unwrap();
    let layers: Vec<_> = ["direct", "specular", "caustic", "indirect"]
        .iter()
        .map(|l| photon::imageio::read_exr_layer(&exr, l).unwrap())
        .collect();
    let mut specular_sum = 0.0;
    for i in 0..img.pixels.len() {
        for c in 0..3 {
            let sum: f32 = layers.iter().map(|l| l.pixels[i][c]).sum();
            let want = img.pixels[i][c];
            assert!(
                (sum - want).abs() <= 1e-5 * want.abs().max(1.0),
                "pixel {i}: {sum} vs {want}"
            );
        }
        specular_sum += layers[1].pixels[i][0];
    }
    assert!(
        specular_sum > 0.0,
        "the mirror and glass spheres show specular light"
    );
}

fn expect_error(args: &[&str], needle: &str) -> String {
    let out = photon().args(args).output().unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr).to_string();
    assert_eq!(out.status.code(), Some(2), "args {args:?}: {stderr}");
    assert_eq!(stderr.trim().lines().count(), 1, "one line: {stderr}");
    assert!(
        stderr.contains(needle),
        "{stderr:?} should mention {needle:?}"
    );
    stderr
}

#[test]
fn bad_input_is_one_line_and_exit_2() {
    let dir = tmp("errors");
    let bad = dir.join("bad.pbrt");
    std::fs::write(
        &bad,
        "WorldBegin\nShape \"trianglemesh\" \"point3 P\" [ 0 0 0 1 0 0 0 1 0 ]\n  Frobnicate 3\n",
    )
    .unwrap();
    expect_error(&["render", bad.to_str().unwrap()], "bad.pbrt:3:3");
    expect_error(&["render", "no/such/scene.pbrt"], "no/such/scene.pbrt");
    let bad_param = dir.join("param.pbrt");
    std::fs::write(
        &bad_param,
        "Camera \"perspective\" \"float fov\" [ 45 ] \"float fnord\" [ 1 ]\nWorldBegin\n",
    )
    .unwrap();
    expect_error(&["render", bad_param.to_str().unwrap()], "fnord");
}

/// A render that fails leaves an existing image untouched.
#[test]
fn failed_render_keeps_the_good_image() {
    let dir = tmp("keep");
    let exr = dir.join("good.exr");
    std::fs::write(&exr, b"precious").unwrap();
    let bad = dir.join("bad.pbrt");
    std::fs::write(
        &bad,
        "WorldBegin\nShape \"sphere\" \"float radius\" [ oops ]\n",
    )
    .unwrap();
    let st = photon()
        .args(["render", bad.to_str().unwrap(), "-o"])
        .arg(&exr)
        .status()
        .unwrap();
    assert_eq!(st.code(), Some(2));
    assert_eq!(std::fs::read(&exr).unwrap(), b"precious");
    assert!(Path::new(&exr).exists());
}

/// Each photon-map setting is declared once (issue 16): the README's table is the generated
/// one, and the file and the command line refuse the same out-of-range values (the file:
/// located at the parameter; the flag: named) before anything is loaded beyond the file.
#[test]
fn photon_settings_have_one_range_in_the_file_and_on_the_command_line() {
    let readme = std::fs::read_to_string("README.md").unwrap();
    let table = photon::integrator::settings::markdown_table();
    assert!(
        readme.contains(&table),
        "README.md's photon-mapper table differs from settings::markdown_table():\n{table}"
    );
    let dir = tmp("settings");
    let cases = [
        (
            "globallookup",
            "integer",
            "0",
            "global-lookup",
            "[1, 100000]",
        ),
        (
            "gathersamples",
            "integer",
            "0",
            "gather-samples",
            "[1, 4096]",
        ),
        ("globalradius", "float", "0", "global-radius", "(0, 4]"),
        ("glossyalpha", "float", "-1", "glossy-alpha", "[0, inf]"),
        (
            "maxphotonbounces",
            "integer",
            "1001",
            "max-photon-bounces",
            "[0, 1000]",
        ),
    ];
    for (key, ty, value, flag, range) in cases {
        let scene = dir.join(format!("{key}.pbrt"));
        std::fs::write(
            &scene,
            format!("Integrator \"photonmap\" \"{ty} {key}\" [ {value} ]\nWorldBegin\n"),
        )
        .unwrap();
        let err = expect_error(&["render", scene.to_str().unwrap()], range);
        assert!(err.contains(&format!("{key}.pbrt:1:")), "{err}");
        let flag = format!("--{flag}");
        expect_error(
            &["render", "scenes/cornell-glass.pbrt", &flag, value],
            range,
        );
    }
    expect_error(
        &["render", "scenes/cornell-glass.pbrt", "--alpha", "2"],
        "(0, 1)",
    );
}

/// `photon render ... | head -1`: standard output closed after the first line. The banner's
/// later lines are lost, the render is not (it panicked with exit 101 on the EPIPE and wrote
/// nothing).
#[test]
fn a_closed_standard_output_does_not_stop_the_render() {
    use std::process::Stdio;
    let dir = tmp("closed-stdout");
    let exr = dir.join("out.exr");
    let mut child = photon()
        .args([
            "render",
            "scenes/cornell-glass.pbrt",
            "--res",
            "16x12",
            "--spp",
            "1",
        ])
        .args(["--threads", "1", "-o"])
        .arg(&exr)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("photon runs");
    drop(child.stdout.take()); // the reader is gone before the first line
    let out = child.wait_with_output().expect("photon finishes");
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(0), "stderr: {stderr}");
    assert!(exr.is_file(), "no image written");
}

#[test]
fn pbrt_v4_habits_a_bare_scene_outfile_and_nthreads() {
    let dir = tmp("pbrt-habits");
    // `photon SCENE.pbrt --outfile X --nthreads N` is `photon render ...`, bit for bit.
    let render = |args: &[&str], out: &Path| {
        let r = photon()
            .args(args)
            .arg(out)
            .args(["--res", "16x12", "--spp", "1", "--no-png"])
            .output()
            .unwrap();
        assert!(r.status.success(), "{}", String::from_utf8_lossy(&r.stderr));
        common::exr_image_bits(out)
    };
    let habits = render(
        &["scenes/cornell-glass.pbrt", "--nthreads", "1", "--outfile"],
        &dir.join("habits.exr"),
    );
    let ours = render(
        &[
            "render",
            "scenes/cornell-glass.pbrt",
            "--threads",
            "2",
            "-o",
        ],
        &dir.join("ours.exr"),
    );
    assert!(habits == ours, "the two renders differ");
    // Anything else that is no subcommand stays an error.
    expect_error(&["frobnicate"], "unrecognized subcommand");
}

#[test]
fn check_takes_folders_of_scenes() {
    let dir = tmp("check-folder");
    let sub = dir.join("sub");
    std::fs::create_dir_all(&sub).unwrap();
    let scene = "WorldBegin\nInclude \"geometry.pbrt\"\n";
    std::fs::write(dir.join("a.pbrt"), scene).unwrap();
    std::fs::write(sub.join("b.pbrt"), "WorldBegin\nShape \"frob\"\n").unwrap();
    // Included by a.pbrt, no WorldBegin: not a scene of its own.
    std::fs::write(dir.join("geometry.pbrt"), "Shape \"sphere\"\n").unwrap();
    std::fs::write(dir.join("notes.txt"), "WorldBegin").unwrap();
    let r = photon().arg("check").arg(&dir).output().unwrap();
    let out = String::from_utf8_lossy(&r.stdout);
    let lines: Vec<&str> = out.lines().filter(|l| !l.starts_with(' ')).collect();
    assert_eq!(lines.len(), 2, "{out}");
    assert!(lines[0].contains("a.pbrt: ok"), "{out}");
    assert!(lines[1].contains("b.pbrt: 1 problem"), "{out}");
    assert_eq!(r.status.code(), Some(2));
    let err = String::from_utf8_lossy(&r.stderr);
    assert!(err.contains("1 of 2 scenes have problems"), "{err}");
    let empty = dir.join("empty");
    std::fs::create_dir_all(&empty).unwrap();
    let r = photon().arg("check").arg(&empty).output().unwrap();
    let err = String::from_utf8_lossy(&r.stderr);
    assert!(err.contains("no scene file"), "{err}");
    assert_eq!(r.status.code(), Some(2));
}

/// Renders `scenes/cornell-glass.pbrt` at 16x12, 1 spp, with `args` and `-o out`: stdout and
/// stderr (the run must succeed).
fn habit(args: &[&str], out: &Path) -> (String, String) {
    let r = photon()
        .args(["scenes/cornell-glass.pbrt", "--res", "16x12", "--spp", "1"])
        .args(args)
        .arg("-o")
        .arg(out)
        .output()
        .unwrap();
    let (o, e) = (
        String::from_utf8_lossy(&r.stdout).into_owned(),
        String::from_utf8_lossy(&r.stderr).into_owned(),
    );
    assert!(r.status.success(), "{args:?}: {e}");
    (o, e)
}

/// `-o` picks the format by extension as pbrt-v4 does: a PNG alone (the pixels of the EXR
/// render's preview), a PFM alone (the EXR's values exactly), and an unknown extension is a
/// one-line error naming -o.
#[test]
fn output_format_follows_the_extension() {
    let dir = tmp("formats");
    habit(&[], &dir.join("ref.exr"));
    habit(&[], &dir.join("only.png"));
    habit(&[], &dir.join("only.pfm"));
    let mut names: Vec<String> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    names.sort();
    assert_eq!(names, ["only.pfm", "only.png", "ref.exr", "ref.png"]);
    let png = |p: &str| image::open(dir.join(p)).unwrap().to_rgb8().into_raw();
    assert!(
        png("only.png") == png("ref.png"),
        "-o x.png differs from the preview"
    );
    let exr = photon::imageio::read_exr(&dir.join("ref.exr")).unwrap();
    let bytes = std::fs::read(dir.join("only.pfm")).unwrap();
    let pfm = photon::imageio::decode::read_pfm(&bytes).unwrap();
    assert_eq!((pfm.width, pfm.height), (16, 12));
    for (a, b) in pfm.texels.iter().zip(&exr.pixels) {
        assert_eq!(a.to_array(), *b);
    }
    let r = photon()
        .args(["scenes/cornell-glass.pbrt", "--res", "8x8", "-o"])
        .arg(dir.join("x.tiff"))
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&r.stderr);
    assert_eq!(r.status.code(), Some(2));
    assert!(
        err.trim().lines().count() == 1 && err.contains("-o ") && err.contains("\".tiff\""),
        "{err}"
    );
    // Renders in passes write partial images: EXR only.
    let r = photon()
        .args(["scenes/cornell-glass.pbrt", "--passes", "2", "-o"])
        .arg(dir.join("p.png"))
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&r.stderr);
    assert_eq!(r.status.code(), Some(2));
    assert!(err.contains("a partial image"), "{err}");
}

/// `--cropwindow` and `--pixelbounds` (pbrt-v4's flags) render that part of the image: the
/// pixels of the full render there, bit for bit (every pixel has its own sample stream), and
/// the same part given either way; the film's `pixelbounds` does the same.
#[test]
fn cropwindow_and_pixelbounds() {
    let dir = tmp("crop");
    let path = ["--integrator", "path", "--no-png"];
    habit(&path, &dir.join("full.exr"));
    let with = |extra: &[&str], name: &str| {
        let args: Vec<&str> = path.iter().chain(extra).copied().collect();
        habit(&args, &dir.join(name));
        photon::imageio::read_exr(&dir.join(name)).unwrap()
    };
    let full = photon::imageio::read_exr(&dir.join("full.exr")).unwrap();
    let crop = with(&["--cropwindow", "0.25,0.75,0.5,1"], "crop.exr");
    let bounds = with(&["--pixelbounds", "4,12,6,12"], "bounds.exr");
    assert_eq!((crop.width, crop.height), (8, 6));
    assert_eq!(crop, bounds);
    for y in 0..6 {
        for x in 0..8 {
            assert_eq!(crop.get(x, y), full.get(x + 4, y + 6), "pixel {x},{y}");
        }
    }
    // In the file: Film "integer pixelbounds" (it wins over a cropwindow, as in pbrt-v4).
    let scene = std::fs::read_to_string("scenes/cornell-glass.pbrt").unwrap();
    let film = "Film \"rgb\" \"integer pixelbounds\" [4 12 6 12] \"float cropwindow\" [0 1 0 1]";
    let scene = scene.replacen("Film \"rgb\"", film, 1);
    assert!(scene.contains(film), "the scene has a Film \"rgb\"");
    let file = dir.join("pb.pbrt");
    std::fs::write(&file, scene).unwrap();
    let r = photon()
        .arg(&file)
        .args([
            "--res",
            "16x12",
            "--spp",
            "1",
            "--integrator",
            "path",
            "--no-png",
            "-o",
        ])
        .arg(dir.join("file.exr"))
        .output()
        .unwrap();
    assert!(r.status.success(), "{}", String::from_utf8_lossy(&r.stderr));
    let from_file = photon::imageio::read_exr(&dir.join("file.exr")).unwrap();
    assert_eq!(from_file, bounds);
    for bad in ["4,2,0,1", "1,2,3", "a,b,c,d"] {
        expect_error(
            &["render", "scenes/cornell-glass.pbrt", "--pixelbounds", bad],
            "--pixelbounds",
        );
    }
}

/// `--quick` (a quarter of the resolution, 1 spp), `--quiet` (nothing on stdout), and the
/// uniform on/off flags: `--no-x` is `--x=false`, the last given wins.
#[test]
fn quick_quiet_and_negated_flags() {
    let dir = tmp("quick");
    let (out, _) = habit(
        &["--quick", "--res", "64x48", "--spp", "16"],
        &dir.join("q.exr"),
    );
    assert!(out.contains("render: 16x12, 1 spp"), "{out}");
    let (out, err) = habit(&["--quiet"], &dir.join("quiet.exr"));
    assert!(out.is_empty() && err.is_empty(), "{out}{err}");
    assert!(dir.join("quiet.exr").exists());
    let image = |args: &[&str], name: &str| {
        habit(args, &dir.join(name));
        common::exr_image_bits(&dir.join(name))
    };
    let on = image(&[], "on.exr");
    let off = image(&["--final-gather=false"], "off.exr");
    assert!(on != off, "final gathering changes the image");
    assert!(image(&["--no-final-gather"], "no.exr") == off);
    assert!(image(&["--final-gather", "--no-final-gather"], "no2.exr") == off);
    assert!(image(&["--no-final-gather", "--final-gather"], "yes.exr") == on);
    let (out, _) = habit(&["--passes", "1", "--progressive"], &dir.join("p.exr"));
    assert!(out.contains("fresh progressive"), "{out}");
    let (out, _) = habit(
        &["--passes", "1", "--progressive", "--no-progressive"],
        &dir.join("p.exr"),
    );
    assert!(out.contains("Jensen's fixed"), "{out}");
}

/// Without a terminal, progress comes as plain `progress: ` lines (every second with `-v`),
/// with k/N and an ETA; passes say k/N and what is left.
#[test]
fn progress_lines_without_a_terminal() {
    let dir = tmp("progress");
    let r = photon()
        .args([
            "scenes/cornell-glass.pbrt",
            "--res",
            "128x128",
            "--spp",
            "64",
        ])
        .args(["--global-photons", "1000000", "-v", "--no-png", "-o"])
        .arg(dir.join("v.exr"))
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&r.stderr);
    assert!(r.status.success(), "{err}");
    let lines: Vec<&str> = err.lines().collect();
    assert!(
        !lines.is_empty(),
        "no progress line in a run of over a second"
    );
    for l in &lines {
        assert!(
            l.starts_with("progress: ") && l.contains("%), ") && l.contains(" eta "),
            "{l}"
        );
    }
    let (_, err) = habit(&["--passes", "2", "--no-png"], &dir.join("p.exr"));
    assert!(
        err.contains("pass 1/2 done") && err.contains("pass 2/2 done"),
        "{err}"
    );
    assert!(err.contains("; eta "), "{err}");
}
