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
        std::fs::read(out).unwrap()
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
