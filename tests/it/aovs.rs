//! Data channels beside the image (`--aov`, `Film "gbuffer"`) and the EXR header's metadata,
//! against what the scenes' geometry says they must be.
use crate::support::{assert_error, run_capped, TempDir};
use photon::imageio::{read_exr_channel, read_exr_layer};
use std::path::{Path, PathBuf};
use std::time::Duration;

/// The camera at the origin looking down +z (fov 90, `W`x`W` pixels); a diffuse plane at
/// z = 4 facing it over x in [-10, 0] (half of the view), uv = (x / 10 + 1, y / 20 + 0.5);
/// `extra` after WorldBegin.
fn plane_scene(film: &str, w: u32, extra: &str) -> String {
    format!(
        r#"Film "{film}" "integer xresolution" [ {w} ] "integer yresolution" [ {w} ]
Camera "perspective" "float fov" [ 90 ]
WorldBegin
LightSource "distant" "point3 from" [ 0 0 0 ] "point3 to" [ 0 0 1 ] "rgb L" [ 1 1 1 ]
Material "diffuse" "rgb reflectance" [ 0.25 0.5 0.75 ]
Shape "trianglemesh" "point3 P" [ -10 -10 4  0 -10 4  0 10 4  -10 10 4 ]
  "integer indices" [ 0 1 2 0 2 3 ] "point2 uv" [ 0 0  1 0  1 1  0 1 ]
{extra}
"#
    )
}

fn render(dir: &TempDir, name: &str, scene: &str, args: &[&str]) -> PathBuf {
    let file = dir.write(&format!("{name}.pbrt"), scene);
    let exr = dir.0.join(format!("{name}.exr"));
    let mut v: Vec<String> = vec!["render".into(), file.display().to_string()];
    v.extend(["--threads", "2", "--no-png", "-o"].map(String::from));
    v.push(exr.display().to_string());
    v.extend(args.iter().map(|s| s.to_string()));
    let r = run_capped(&v, 2 << 30, Duration::from_secs(120));
    assert_eq!(r.code, Some(0), "{}", r.describe());
    exr
}

fn channel(exr: &Path, name: &str) -> Vec<f32> {
    read_exr_channel(exr, name).unwrap_or_else(|e| panic!("{name}: {e}"))
}

/// The columns the plane covers entirely, and those it does not touch (the middle two
/// columns, where its edge lies, are left out), from the alpha channel's expected halves.
fn halves(w: usize, alpha: &[f32]) -> (Vec<usize>, Vec<usize>) {
    let left_covered = alpha[w / 4] > 0.5;
    let (a, b): (Vec<usize>, Vec<usize>) = (0..w)
        .filter(|&x| x + 1 < w / 2 || x > w / 2)
        .partition(|&x| (x < w / 2) == left_covered);
    (a, b)
}

#[test]
fn aov_channels_of_a_plane() {
    let dir = TempDir::new("aov-plane");
    let w = 16usize;
    let exr = render(
        &dir,
        "plane",
        &plane_scene("rgb", w as u32, ""),
        &[
            "--integrator",
            "path",
            "--spp",
            "4",
            "--aov",
            "alpha,albedo,normal",
            "--aov",
            "depth,position",
        ],
    );
    let a = channel(&exr, "A");
    let (covered, empty) = halves(w, &a);
    assert_eq!(covered.len(), w / 2 - 1);
    let albedo = read_exr_layer(&exr, "albedo").unwrap();
    let normal = read_exr_layer(&exr, "normal").unwrap();
    let (z, pz) = (channel(&exr, "Z"), channel(&exr, "P.Z"));
    for y in 0..w {
        for &x in &covered {
            let i = y * w + x;
            assert_eq!(a[i], 1.0, "alpha at {x},{y}");
            let want = [0.25, 0.5, 0.75];
            for (got, want) in albedo.pixels[i].iter().zip(want) {
                assert!((got - want).abs() < 1e-5, "albedo {:?}", albedo.pixels[i]);
            }
            let n = normal.pixels[i];
            assert!(
                n[0].abs() < 1e-6 && n[1].abs() < 1e-6 && (n[2].abs() - 1.0).abs() < 1e-6,
                "{n:?}"
            );
            assert!(
                (z[i] - 4.0).abs() < 1e-4 && (pz[i] - 4.0).abs() < 1e-4,
                "{} {}",
                z[i],
                pz[i]
            );
        }
        for &x in &empty {
            let i = y * w + x;
            assert_eq!(a[i], 0.0);
            assert_eq!(albedo.pixels[i], [0.0; 3]);
            assert_eq!(normal.pixels[i], [0.0; 3]);
            assert_eq!(z[i], f32::INFINITY);
        }
    }
}

/// Behind a mirror the guides are those of the wall it reflects (a conductor of reflectance
/// 1 reflects all light at every angle), while the gbuffer's first-hit albedo is the mirror's.
#[test]
fn guides_follow_a_mirror() {
    let dir = TempDir::new("aov-mirror");
    let scene = r#"Film "gbuffer" "integer xresolution" [ 12 ] "integer yresolution" [ 12 ]
Camera "perspective" "float fov" [ 40 ]
WorldBegin
LightSource "distant" "point3 from" [ 0 0 0 ] "point3 to" [ 0 0 1 ] "rgb L" [ 1 1 1 ]
AttributeBegin
Material "conductor" "rgb reflectance" [ 1 1 1 ] "float roughness" [ 0 ]
Shape "trianglemesh" "point3 P" [ 3.5 -10 0.5  -6 -10 10  -6 10 10  3.5 10 0.5 ]
  "integer indices" [ 0 1 2 0 2 3 ]
AttributeEnd
Material "diffuse" "rgb reflectance" [ 0.6 0.3 0.1 ]
Shape "trianglemesh" "point3 P" [ -8 -50 -50  -8 50 -50  -8 50 50  -8 -50 50 ]
  "integer indices" [ 0 1 2 0 2 3 ]
"#;
    let exr = render(
        &dir,
        "mirror",
        scene,
        &[
            "--integrator",
            "path",
            "--spp",
            "4",
            "--aov",
            "albedo,normal",
        ],
    );
    let albedo = read_exr_layer(&exr, "albedo").unwrap();
    let normal = read_exr_layer(&exr, "normal").unwrap();
    let first = read_exr_layer(&exr, "Albedo").unwrap();
    for i in 0..albedo.pixels.len() {
        let (a, n, f) = (albedo.pixels[i], normal.pixels[i], first.pixels[i]);
        for (c, want) in [0.6, 0.3, 0.1].into_iter().enumerate() {
            assert!(
                (a[c] - want).abs() < 2e-3 * want.max(0.1),
                "guide albedo {a:?}"
            );
            assert!((f[c] - 1.0).abs() < 2e-3, "first-hit albedo {f:?}");
        }
        assert!(
            (n[0].abs() - 1.0).abs() < 1e-5 && n[1].abs() < 1e-5,
            "wall normal {n:?}"
        );
    }
}

/// `Film "gbuffer"`: positions and normals in camera space, uv, and the depth slopes of a
/// plane tilted by 30 degrees against the closed form.
#[test]
fn gbuffer_channels_of_planes() {
    let dir = TempDir::new("aov-gbuffer");
    let w = 16usize;
    let exr = render(
        &dir,
        "flat",
        &plane_scene("gbuffer", w as u32, ""),
        &["--integrator", "path", "--spp", "4", "--aov", "alpha"],
    );
    let a = channel(&exr, "A");
    let (covered, _) = halves(w, &a);
    let [px, py, pz, u, v, nz, dzdx, dzdy] =
        ["P.X", "P.Y", "P.Z", "u", "v", "N.Z", "dzdx", "dzdy"].map(|c| channel(&exr, c));
    let albedo = read_exr_layer(&exr, "Albedo").unwrap();
    for y in 0..w {
        for &x in &covered {
            let i = y * w + x;
            assert!((pz[i] - 4.0).abs() < 1e-4, "P.Z {}", pz[i]);
            // The uv the mesh interpolates, against the position the pass averaged.
            assert!(
                (u[i] - (px[i] / 10.0 + 1.0)).abs() < 1e-4,
                "u {} at x {}",
                u[i],
                px[i]
            );
            assert!(
                (v[i] - (py[i] / 20.0 + 0.5)).abs() < 1e-4,
                "v {} at y {}",
                v[i],
                py[i]
            );
            assert!((nz[i].abs() - 1.0).abs() < 1e-6);
            assert!(dzdx[i] < 1e-5 && dzdy[i] < 1e-5, "{} {}", dzdx[i], dzdy[i]);
            assert!((albedo.pixels[i][1] - 0.5).abs() < 1e-5);
        }
    }
    // The plane z = 4 + x tan(30 deg): along a row, z(s) = 4 / (1 - s t) at the screen
    // coordinate s = x / z of the pixel centre, and dzdx is z's change to the next pixel.
    let t = 30f32.to_radians().tan();
    let (x0, x1) = (-4.0f32, 1.2f32);
    let tilted = format!(
        r#"Film "gbuffer" "integer xresolution" [ {w} ] "integer yresolution" [ {w} ]
Camera "perspective" "float fov" [ 90 ]
WorldBegin
LightSource "distant" "point3 from" [ 0 0 0 ] "point3 to" [ 0 0 1 ] "rgb L" [ 1 1 1 ]
Material "diffuse"
Shape "trianglemesh" "point3 P" [ {x0} -10 {z0}  {x1} -10 {z1}  {x1} 10 {z1}  {x0} 10 {z0} ]
  "integer indices" [ 0 1 2 0 2 3 ]
"#,
        z0 = 4.0 + x0 * t,
        z1 = 4.0 + x1 * t
    );
    let exr = render(
        &dir,
        "tilted",
        &tilted,
        &["--integrator", "path", "--spp", "1"],
    );
    let dzdx = channel(&exr, "dzdx");
    let z = |s: f32| 4.0 / (1.0 - s * t);
    let step = 2.0 / w as f32;
    let y = w / 2;
    let mut checked = 0;
    for x in 0..w {
        let i = y * w + x;
        if dzdx[i] == 0.0 {
            continue; // off the plane
        }
        // Raster x grows with camera x or against it: one of the two must hold everywhere.
        let s_up = -1.0 + (x as f32 + 0.5) * step;
        let s_down = -s_up;
        let up = (z(s_up + step) - z(s_up)).abs();
        let down = (z(s_down - step) - z(s_down)).abs();
        let err = ((dzdx[i] - up) / up)
            .abs()
            .min(((dzdx[i] - down) / down).abs());
        assert!(
            err < 2e-3,
            "dzdx {} at column {x}: expected {up} or {down}",
            dzdx[i]
        );
        checked += 1;
    }
    assert!(checked >= 4, "{checked} columns on the tilted plane");
}

/// The gbuffer's `Variance` is each pixel's sample variance: over 24 seeds, the variance of
/// the 8-sample pixel means matches Variance / 8 (independent samples).
#[test]
fn gbuffer_variance_matches_the_spread_of_means() {
    let dir = TempDir::new("aov-variance");
    let light = r#"AttributeBegin
AreaLightSource "diffuse" "rgb L" [ 4 4 4 ]
Shape "trianglemesh" "point3 P" [ -6 -1 1  -3 -1 1  -3 1 1  -6 1 1 ] "integer indices" [ 0 2 1 0 3 2 ]
AttributeEnd"#;
    let scene = plane_scene("gbuffer", 8, light);
    let (mut means, mut predicted) = (Vec::new(), vec![0f64; 64]);
    let seeds = 24;
    for seed in 0..seeds {
        let exr = render(
            &dir,
            &format!("s{seed}"),
            &scene,
            &[
                "--integrator",
                "path",
                "--spp",
                "8",
                "--pattern",
                "independent",
                "--seed",
                &seed.to_string(),
            ],
        );
        let img = photon::imageio::read_exr(&exr).unwrap();
        means.push(img.pixels.iter().map(|p| p[1] as f64).collect::<Vec<_>>());
        for (p, v) in predicted.iter_mut().zip(channel(&exr, "Variance.G")) {
            *p += v as f64 / 8.0 / seeds as f64;
        }
    }
    let (mut emp, mut pred) = (0.0, 0.0);
    for i in 0..64 {
        let m = means.iter().map(|s| s[i]).sum::<f64>() / seeds as f64;
        emp += means.iter().map(|s| (s[i] - m).powi(2)).sum::<f64>() / (seeds - 1) as f64;
        pred += predicted[i];
    }
    assert!(pred > 0.0, "no variance recorded");
    let ratio = emp / pred;
    println!("variance of means {emp:.4e}, Variance / spp {pred:.4e}, ratio {ratio:.3}");
    assert!((0.75..1.33).contains(&ratio), "ratio {ratio}");
}

/// pbrt-v4's header attributes, read back by OpenEXR's own `exrheader`.
#[test]
fn exr_metadata() {
    let dir = TempDir::new("aov-meta");
    let exr = render(
        &dir,
        "meta",
        &plane_scene("rgb", 8, ""),
        &["--integrator", "path", "--spp", "3", "--seed", "7"],
    );
    let out = std::process::Command::new("exrheader")
        .arg(&exr)
        .output()
        .unwrap();
    let text = String::from_utf8_lossy(&out.stdout);
    for needle in [
        "samplesPerPixel (type int): 3",
        "renderTimeSeconds (type float)",
        "integrator (type string): \"path\"",
        "seed (type string): \"7\"",
        "white (0.3127 0.329)",
    ] {
        assert!(text.contains(needle), "{needle} not in\n{text}");
    }
    let matrix = |name: &str| -> [[f64; 4]; 4] {
        let at = text.find(&format!("{name} (type m44f):")).expect(name);
        let nums: Vec<f64> = text[at..]
            .lines()
            .skip(1)
            .take(4)
            .flat_map(|l| {
                l.split(|c: char| c.is_whitespace() || c == '(' || c == ')')
                    .filter(|t| !t.is_empty())
                    .map(|t| t.parse::<f64>().unwrap())
                    .collect::<Vec<_>>()
            })
            .collect();
        std::array::from_fn(|r| std::array::from_fn(|c| nums[r * 4 + c]))
    };
    let cam = matrix("worldToCamera");
    for r in 0..4 {
        for c in 0..4 {
            assert_eq!(
                cam[r][c],
                if r == c { 1.0 } else { 0.0 },
                "identity camera: {cam:?}"
            );
        }
    }
    // fov 90: the point (4, 0, 4) lies on the screen's edge (x / z = 1), NDC x = 1; (0, 0, 4)
    // at the centre (0.5, 0.5).
    let ndc = matrix("worldToNDC");
    let apply = |p: [f64; 3]| {
        let v: Vec<f64> = (0..4)
            .map(|r| ndc[r][0] * p[0] + ndc[r][1] * p[1] + ndc[r][2] * p[2] + ndc[r][3])
            .collect();
        [v[0] / v[3], v[1] / v[3]]
    };
    let [x, y] = apply([4.0, 0.0, 4.0]);
    assert!((x - 1.0).abs() < 1e-5 && (y - 0.5).abs() < 1e-5, "{x} {y}");
    let [x, y] = apply([0.0, 0.0, 4.0]);
    assert!((x - 0.5).abs() < 1e-5 && (y - 0.5).abs() < 1e-5, "{x} {y}");
}

#[test]
fn aov_flag_errors() {
    let dir = TempDir::new("aov-errors");
    let scene = dir
        .write("s.pbrt", plane_scene("rgb", 8, ""))
        .display()
        .to_string();
    let png = dir.0.join("x.png").display().to_string();
    let run = |args: &[&str]| run_capped(args, 1 << 30, Duration::from_secs(60));
    let r = run(&["render", &scene, "--aov", "alpha", "-o", &png]);
    assert_error(&r, &["--aov", "EXR"]);
    assert!(!Path::new(&png).exists());
    let r = run(&["render", &scene, "--aov", "alpha", "--passes", "2"]);
    assert_error(&r, &["--aov", "passes"]);
    let r = run(&["render", &scene, "--aov", "shininess"]);
    assert_eq!(r.code, Some(2), "{}", r.describe());
    assert!(r.stderr.contains("shininess"), "{}", r.describe());
}
