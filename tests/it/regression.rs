//! Image regression tests, one per shared scene, in the style of Mitsuba's render tests: render
//! with the default integrator (the photon mapper) at low resolution and few samples, compare
//! with the scene's independent reference by relMSE (`photon::imageio::metrics::compare`,
//! the reference box-filtered down by an integer factor), and fail above a threshold measured
//! on this renderer (value and margin stated at each test). Also reported: the error without
//! the pixels next to visible emitters (`MaskOptions::mask_above`), where a pixel-filter
//! mismatch alone dominates.
//!
//! Renders use a one-pixel box filter (a pixel-area average, as the box-downsampled reference
//! is) and the scene's own integrator parameters otherwise. On failure the render, the
//! reference and the error image go to `target/regression/<scene>/` (EXR + PNG) for a person
//! to look at.
use photon::accel::{Accel, AccelOptions, BackendKind};
use photon::imageio::metrics::{compare, error_image, match_sizes, MaskOptions, Metrics};
use photon::imageio::{read_exr, write_exr, write_png, ExrPixel, RgbImage};
use photon::integrator::{self, IntegratorKind, RenderSettings};
use photon::math::Vec2;
use photon::scene::{loader, FilterDesc};
use std::path::{Path, PathBuf};

/// One regression case.
struct Case {
    /// Folder name under `../shared/scenes/` and `target/regression/`.
    name: &'static str,
    scene: &'static str,
    reference: &'static str,
    /// Render size and samples per pixel.
    width: u32,
    height: u32,
    spp: u32,
    /// Reference pixels brighter than this (and their neighbours) are left out of the masked
    /// error: the visible emitters.
    mask_above: f32,
    /// Thresholds on relMSE over all pixels and without those next to emitters.
    max_all: f64,
    max_masked: f64,
}

/// Renders the case, compares, writes the images on failure and returns the two metrics.
fn run(case: &Case) -> (Metrics, Metrics) {
    let mut scene = loader::load(Path::new(case.scene)).expect("scene loads");
    scene.filter = FilterDesc::Box {
        radius: Vec2::splat(0.5),
    };
    let accel = Accel::build(&scene, BackendKind::Embree, AccelOptions::default()).unwrap();
    let mut settings = RenderSettings::from_scene(&scene).expect("settings");
    (settings.width, settings.height, settings.spp) = (case.width, case.height, case.spp);
    let out = integrator::render(
        &scene,
        &accel,
        &settings,
        IntegratorKind::default(),
        &|_, _| {},
    );
    let nonfinite = out.image.count_nonfinite();
    let reference = read_exr(Path::new(case.reference)).expect("reference reads");
    let (img, reference) = match_sizes(out.image, reference).expect("sizes match");
    let all = compare(&img, &reference, MaskOptions::default()).unwrap();
    let mask = MaskOptions {
        mask_above: Some(case.mask_above),
    };
    let masked = compare(&img, &reference, mask).unwrap();
    println!(
        "{}: {}x{} {} spp, {:.2} s: relMSE {:.5} (all pixels, threshold {}), {:.5} without {} pixels next to emitters (threshold {}); NaN/Inf pixels {nonfinite}",
        case.name,
        case.width,
        case.height,
        case.spp,
        out.seconds,
        all.overall.relmse,
        case.max_all,
        masked.overall.relmse,
        masked.masked_emitter,
        case.max_masked
    );
    let pass = all.overall.relmse <= case.max_all
        && masked.overall.relmse <= case.max_masked
        && nonfinite == 0;
    if !pass {
        let dir = write_failure(case.name, &img, &reference, mask);
        println!(
            "{}: wrote render, reference and error images to {}",
            case.name,
            dir.display()
        );
    }
    assert_eq!(nonfinite, 0, "{}: NaN/Inf pixels", case.name);
    assert!(
        all.overall.relmse <= case.max_all,
        "{}: relMSE {} above {}",
        case.name,
        all.overall.relmse,
        case.max_all
    );
    assert!(
        masked.overall.relmse <= case.max_masked,
        "{}: relMSE without emitters {} above {}",
        case.name,
        masked.overall.relmse,
        case.max_masked
    );
    (all, masked)
}

/// Writes `render`, `reference` and `error` (per-pixel relMSE false colour) as EXR and PNG
/// under `target/regression/<name>/`; returns that folder.
fn write_failure(name: &str, img: &RgbImage, reference: &RgbImage, mask: MaskOptions) -> PathBuf {
    let dir = PathBuf::from("target/regression").join(name);
    std::fs::create_dir_all(&dir).expect("output folder");
    let err = error_image(img, reference, mask);
    for (stem, image) in [("render", img), ("reference", reference), ("error", &err)] {
        write_exr(
            &dir.join(format!("{stem}.exr")),
            image,
            &[],
            ExrPixel::Float,
        )
        .unwrap();
        write_png(&dir.join(format!("{stem}.png")), image, 0.0).unwrap();
    }
    dir
}

/// Bitterli's Cornell box vs Tungsten (1024^2 box-filtered to 128^2), 16 spp, ~0.9 s.
/// Measured relMSE 0.00292 (all pixels) and 0.00171 without the 143 pixels next to the light;
/// thresholds 1.5x that. (At 4 spp: 0.0150 / 0.0106, final-gather noise.)
#[test]
fn cornell_box() {
    run(&Case {
        name: "cornell-box",
        scene: "../shared/scenes/cornell-box/scene-v4.pbrt",
        reference: "../shared/scenes/cornell-box/reference-tungsten.exr",
        width: 128,
        height: 128,
        spp: 16,
        mask_above: 5.0,
        max_all: 0.0045,
        max_masked: 0.0026,
    });
}

/// Veach's MIS scene vs Tungsten (1280x720 box-filtered to 160x90), 64 spp, ~1.5 s.
/// Measured relMSE 2.06 (all pixels) and 1.10 without the 684 pixels next to the lights
/// (4 spp: 49.8 / 50.0; 16 spp: 5.2 / 1.45): fireflies on the glossy plates and the wall from
/// the tiny, very bright lights dominate, and the reference's microfacet model may differ
/// (the path tracer gives 3.65 / 2.77 at 64 spp too). Thresholds 1.5x the measurement: a
/// guard against gross regressions (NaN, missing lights, broken MIS), not against a few
/// percent of bias: checked once, 1 spp fails (8.84 / 8.63) but an image 10% too bright
/// passes (2.56 / 1.39). (The two Cornell tests fail on both: 0.0057 / 0.0045 and
/// 0.0139 / 0.0123 at 1.1x; 0.057 / 0.056 and 0.149 / 0.141 at 1 spp.)
#[test]
fn veach_mis() {
    run(&Case {
        name: "veach-mis",
        scene: "../shared/scenes/veach-mis/scene-v4.pbrt",
        reference: "../shared/scenes/veach-mis/reference-tungsten.exr",
        width: 160,
        height: 90,
        spp: 64,
        mask_above: 5.0,
        max_all: 3.1,
        max_masked: 1.65,
    });
}

/// The caustics scene vs its Mitsuba 3 reference (256^2 box-filtered to 128^2), 16 spp,
/// ~1.1 s. Measured relMSE 0.00892 (all pixels) and 0.00763 without the 257 pixels next to
/// the light; thresholds 1.5x that.
#[test]
fn cornell_spheres() {
    run(&Case {
        name: "cornell-spheres",
        scene: "../shared/scenes/cornell-spheres/scene.pbrt",
        reference: "../shared/scenes/cornell-spheres/reference.exr",
        width: 128,
        height: 128,
        spp: 16,
        mask_above: 5.0,
        max_all: 0.0135,
        max_masked: 0.0115,
    });
}
