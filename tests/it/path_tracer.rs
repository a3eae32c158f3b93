//! The reference path tracer (`IntegratorKind::Path`) against independent answers:
//! - white furnace: inside a closed box whose walls all have diffuse albedo rho and all emit Le,
//!   radiance is the geometric series `Le (1 + rho + ... + rho^maxdepth)` everywhere
//!   (`Le / (1 - rho)` for a large `maxdepth`): checks energy, MIS weights, Russian roulette
//!   and pbrt-v4's depth convention analytically;
//! - the shared Cornell box against its Tungsten reference (relMSE, with and without the
//!   pixels next to the visible light);
//! - its `direct` component against the direct-lighting integrator (a different estimator:
//!   no MIS on diffuse surfaces);
//! - bit-identical images on 1 and 2 threads.
use crate::support as common;

use common::{render_with, CORNELL};
use photon::accel::BackendKind;
use photon::camera::Camera;
use photon::imageio::metrics::{compare, match_sizes, MaskOptions, Metrics};
use photon::imageio::{read_exr, RgbImage};
use photon::integrator::{IntegratorKind, RenderOutput};
use photon::math::{Vec2, Vec3};
use photon::scene::{loader, FilterDesc, Scene};
use std::path::{Path, PathBuf};

const CORNELL_REF: &str = "../shared/scenes/cornell-box/reference-tungsten.exr";

/// Renders `scene` with `kind` at `w x h`, `spp` samples, on `threads` threads (0 = all).
fn render(
    scene: &Scene,
    kind: IntegratorKind,
    backend: BackendKind,
    (w, h, spp): (u32, u32, u32),
    threads: usize,
) -> RenderOutput {
    render_with(scene, kind, backend, (w, h, spp), threads, 0)
}

/// The scene with a box pixel filter covering exactly one pixel (a pixel-area average, as a
/// box-downsampled reference is).
fn with_box_filter(mut scene: Scene) -> Scene {
    scene.filter = FilterDesc::Box {
        radius: Vec2::splat(0.5),
    };
    scene
}

// ---------------------------------------------------------------------------------------------
// White furnace

const LE: [f32; 3] = [1.0, 0.5, 2.0];
const RHO: [f32; 3] = [0.3, 0.5, 0.7];

/// A closed cube [-1, 1]^3 of albedo `RHO`, every wall a two-sided emitter of radiance `LE`,
/// seen from inside (camera off-centre, looking at an edge so several walls show); `inside`
/// is added to the world (e.g. a glass sphere) and `name` names the file.
fn furnace_scene(max_depth: u32, inside: &str, name: &str) -> PathBuf {
    let text = format!(
        r#"LookAt 0.2 -0.3 0.1  1 0.5 1  0 1 0
Camera "perspective" "float fov" [ 80 ]
Film "rgb" "integer xresolution" [ 24 ] "integer yresolution" [ 24 ]
PixelFilter "box" "float xradius" [ 0.5 ] "float yradius" [ 0.5 ]
Sampler "independent" "integer pixelsamples" [ 16 ]
Integrator "path" "integer maxdepth" [ {max_depth} ]
WorldBegin
AttributeBegin
  AreaLightSource "diffuse" "rgb L" [ {} {} {} ] "bool twosided" true
  Material "diffuse" "rgb reflectance" [ {} {} {} ]
  Shape "trianglemesh"
    "point3 P" [ -1 -1 -1  1 -1 -1  1 1 -1  -1 1 -1  -1 -1 1  1 -1 1  1 1 1  -1 1 1 ]
    "integer indices" [ 0 2 1  0 3 2   4 5 6  4 6 7   0 1 5  0 5 4
                        3 7 6  3 6 2   0 4 7  0 7 3   1 2 6  1 6 5 ]
AttributeEnd
{inside}
"#,
        LE[0], LE[1], LE[2], RHO[0], RHO[1], RHO[2]
    );
    common::write_scene("path_tracer", &format!("{name}-{max_depth}"), &text)
}

/// `Le (1 + rho + ... + rho^max_depth)`: emission after 0..=max_depth bounces.
fn furnace_expected(max_depth: u32) -> Vec3 {
    let (le, rho) = (Vec3::from_array(LE), Vec3::from_array(RHO));
    le * (Vec3::ONE - rho.powf(max_depth as f32 + 1.0)) / (Vec3::ONE - rho)
}

/// The furnace's errors: the image mean's relative error (worst channel), the worst pixel's
/// relative error, and the relative RMS deviation of the pixels (every pixel has the same
/// expected value, so this is the per-pixel noise).
struct FurnaceErrors {
    mean: f32,
    worst: f32,
    rms: f32,
}

/// Renders the furnace with `max_depth` at `spp` on `backend` and measures its errors.
fn furnace_errors(max_depth: u32, spp: u32, backend: BackendKind) -> FurnaceErrors {
    let scene = furnace_scene(max_depth, "", "furnace");
    furnace_errors_of(&scene, max_depth, spp, backend, &|_| true)
}

/// Renders the furnace scene at `path` (maximum depth `max_depth`) and measures the errors of
/// the pixels `i` (row-major index) for which `keep(i)`.
fn furnace_errors_of(
    path: &Path,
    max_depth: u32,
    spp: u32,
    backend: BackendKind,
    keep: &dyn Fn(usize) -> bool,
) -> FurnaceErrors {
    let scene = loader::load(path).expect("furnace loads");
    let out = render(&scene, IntegratorKind::Path, backend, (24, 24, spp), 0);
    let want = furnace_expected(max_depth);
    let rel: Vec<Vec3> = (out.image.pixels.iter().enumerate())
        .filter(|(i, _)| keep(*i))
        .map(|(_, p)| (Vec3::from_array(*p) - want) / want)
        .collect();
    let n = rel.len() as f32;
    let e = FurnaceErrors {
        mean: (rel.iter().copied().sum::<Vec3>() / n).abs().max_element(),
        worst: rel
            .iter()
            .map(|r| r.abs().max_element())
            .fold(0.0, f32::max),
        rms: (rel.iter().map(|r| r.length_squared()).sum::<f32>() / (3.0 * n)).sqrt(),
    };
    println!(
        "furnace maxdepth {max_depth} ({backend}, {spp} spp, {n} pixels): expected {want}, \
         mean rel. error {:.2e}, worst pixel {:.2e}, rms {:.2e}",
        e.mean, e.worst, e.rms
    );
    e
}

/// maxdepth 200: `Le / (1 - rho)` (rho^201 < 1e-31), Russian roulette active from bounce 4.
/// Measured at 512 spp: mean within 6e-4, per-pixel noise (rms) 1.0e-2, worst pixel 5.6e-2;
/// the per-pixel tolerance 0.1 is about 10 sigma (roulette makes the tail heavy).
#[test]
fn white_furnace_converges_to_le_over_one_minus_rho() {
    let e = furnace_errors(200, 512, BackendKind::Embree);
    assert!(e.mean < 0.01, "mean off by {}", e.mean);
    assert!(e.worst < 0.1, "a pixel is off by {}", e.worst);
}

/// Small depths check the depth convention exactly: maxdepth 0 sees only Le, 2 adds
/// `rho Le + rho^2 Le` (no roulette yet), 5 has roulette on bounces 4 and 5. Measured at
/// 256 spp: means within 4e-4, per-pixel rms at most 5e-3, worst pixel 2.3e-2; tolerance 0.05
/// (10 sigma). An off-by-one depth would move the mean by 5% (maxdepth 5) to 30% (maxdepth 1).
#[test]
fn white_furnace_depth_convention() {
    for (depth, backend) in [
        (0, BackendKind::Embree),
        (1, BackendKind::Obvhs),
        (2, BackendKind::Embree),
        (5, BackendKind::Obvhs),
    ] {
        let e = furnace_errors(depth, 256, backend);
        assert!(e.mean < 0.01, "maxdepth {depth}: mean off by {}", e.mean);
        assert!(
            e.worst < 0.05,
            "maxdepth {depth}: a pixel is off by {}",
            e.worst
        );
    }
}

/// A lossless glass sphere (IOR 1.5) in the furnace changes nothing outside it: the radiance
/// field in the air stays `Le / (1 - rho)` in every direction, so pixels seeing the sphere
/// (through refractions, total internal reflection, the `1 / eta^2` radiance scaling and back)
/// show the same value. Measured at 512 spp over the 128 pixels that see the sphere: mean
/// within 2e-4, rms 1.5e-2, worst 6.7e-2 (tolerance 0.1, about 7 sigma).
#[test]
fn white_furnace_with_a_glass_sphere() {
    let glass = r#"AttributeBegin
  Material "dielectric" "float eta" [ 1.5 ]
  Translate 0.6 0.3 0.6
  Shape "sphere" "float radius" [ 0.35 ]
AttributeEnd"#;
    let path = furnace_scene(200, glass, "furnace-glass");
    // Judge only the pixels whose centre sees the sphere (the filter is one pixel wide, so
    // pixels at the silhouette mix sphere and wall: both have the same expected value).
    let scene = loader::load(&path).expect("furnace loads");
    let cam = Camera::new(&scene.camera, 24, 24);
    let (c, r) = (Vec3::new(0.6, 0.3, 0.6), 0.35f32);
    let sees_sphere = |i: usize| {
        let ray = cam.generate_ray(Vec2::new((i % 24) as f32 + 0.5, (i / 24) as f32 + 0.5));
        let (d, oc) = (ray.d.normalize(), ray.o - c);
        let b = oc.dot(d);
        b < 0.0 && b * b - (oc.length_squared() - r * r) > 0.0
    };
    let covered = (0..24 * 24).filter(|&i| sees_sphere(i)).count();
    println!("glass sphere covers {covered} of 576 pixels");
    assert!(covered > 100, "sphere covers only {covered} pixels");
    let e = furnace_errors_of(&path, 200, 512, BackendKind::Embree, &sees_sphere);
    assert!(e.mean < 0.01, "mean off by {}", e.mean);
    assert!(e.worst < 0.1, "a pixel is off by {}", e.worst);
}

// ---------------------------------------------------------------------------------------------
// Cornell box against Tungsten

/// The Tungsten reference (1024^2) box-filtered to the size of `image`, and the errors of
/// `image` against it without and with the pixels next to the visible light (reference above
/// 10; the light's radiance is 17 12 4 beside walls below 1).
fn cornell_errors(image: RgbImage) -> (Metrics, Metrics) {
    let reference = read_exr(Path::new(CORNELL_REF)).expect("reference loads");
    let (image, reference) = match_sizes(image, reference).expect("integer factor");
    let all = compare(&image, &reference, MaskOptions::default()).expect("same size");
    let masked = compare(
        &image,
        &reference,
        MaskOptions {
            mask_above: Some(10.0),
        },
    )
    .expect("same size");
    (all, masked)
}

/// 128x128 at 128 spp with a box filter of one pixel (the reference is a box-downsampled 1024^2
/// render, so a pixel-area average matches it; the scene's triangle filter would blur the
/// light's edge, see shared/README). Measured (Embree, seed 0, ~3 s on 2 cores): relMSE
/// 1.85e-3 overall, 9.27e-4 without the pixels next to the light; thresholds are 1.5x those.
#[test]
fn cornell_box_matches_tungsten() {
    let scene = with_box_filter(loader::load(Path::new(CORNELL)).expect("scene loads"));
    let t = std::time::Instant::now();
    let out = render(
        &scene,
        IntegratorKind::Path,
        BackendKind::Embree,
        (128, 128, 128),
        0,
    );
    let secs = t.elapsed().as_secs_f64();
    assert_eq!(out.image.count_nonfinite(), 0);
    let (all, masked) = cornell_errors(out.image);
    println!(
        "cornell-box 128x128 128 spp ({secs:.2} s): relMSE {:.3e} (R/G/B {:.2e}/{:.2e}/{:.2e}); \
         without {} pixels next to the light {:.3e}",
        all.overall.relmse,
        all.channels[0].relmse,
        all.channels[1].relmse,
        all.channels[2].relmse,
        masked.masked_emitter,
        masked.overall.relmse
    );
    assert!(
        all.overall.relmse < 1.5 * 1.85e-3,
        "relMSE {}",
        all.overall.relmse
    );
    assert!(
        masked.overall.relmse < 1.5 * 9.27e-4,
        "relMSE without the light's edge {}",
        masked.overall.relmse
    );
}

/// The `direct` component (emitters seen directly, plus one scattering at the first hit, with
/// MIS) has the same expectation as the direct integrator's (light samples only on diffuse
/// surfaces); the components sum to the image and `indirect` is not empty.
#[test]
fn cornell_direct_component_matches_direct_integrator() {
    let scene = with_box_filter(loader::load(Path::new(CORNELL)).expect("scene loads"));
    let size = (64, 64, 64);
    let path = render(&scene, IntegratorKind::Path, BackendKind::Embree, size, 0);
    // Another seed, so that the two estimates are independent (with the same streams the
    // light samples at the first hit would coincide).
    let direct = render_with(
        &scene,
        IntegratorKind::Direct,
        BackendKind::Embree,
        size,
        0,
        1,
    );
    let layer = |out: &RenderOutput, name: &str| -> RgbImage {
        let (_, img) = out.components.iter().find(|(n, _)| *n == name).expect(name);
        img.clone()
    };
    let (pd, pi) = (layer(&path, "direct"), layer(&path, "indirect"));
    // The pixels next to the visible light are left out: there the fraction of samples that
    // hit the light swings both images (over six seeds relMSE 1.3e-4 .. 3.3e-3 with them, and
    // 8.3e-5 .. 9.5e-5 without the 64 pixels within a pixel of the light).
    let mask = MaskOptions {
        mask_above: Some(2.0),
    };
    let m = compare(&pd, &layer(&direct, "direct"), mask).expect("sizes");
    println!(
        "cornell 64x64 64 spp: path 'direct' vs direct integrator relMSE {:.2e} ({} pixels by the light left out)",
        m.overall.relmse, m.masked_emitter
    );
    // Noise of both; 1.6x margin over the worst of six seeds.
    assert!(
        m.masked_emitter < 100,
        "{} pixels left out",
        m.masked_emitter
    );
    assert!(m.overall.relmse < 1.5e-4, "direct components differ: {m:?}");
    for ((img, d), i) in path.image.pixels.iter().zip(&pd.pixels).zip(&pi.pixels) {
        for c in 0..3 {
            assert!((img[c] - d[c] - i[c]).abs() <= 1e-5 * img[c].abs().max(1.0));
        }
    }
    let sum = |img: &RgbImage| img.pixels.iter().flatten().map(|&v| v as f64).sum::<f64>();
    let share = sum(&pi) / sum(&path.image);
    println!("indirect share of the image: {share:.3}");
    assert!(share > 0.2 && share < 0.8, "indirect share {share}");
}

/// Sampling is keyed by pixel, sample and dimension: 1 and 2 threads give identical images.
#[test]
fn path_image_does_not_depend_on_thread_count() {
    let scene = loader::load(Path::new(CORNELL)).expect("scene loads");
    let one = render(
        &scene,
        IntegratorKind::Path,
        BackendKind::Embree,
        (40, 32, 4),
        1,
    );
    let two = render(
        &scene,
        IntegratorKind::Path,
        BackendKind::Embree,
        (40, 32, 4),
        2,
    );
    assert!(one.image.pixels.iter().any(|p| p[0] > 0.0));
    assert_eq!(one.image, two.image);
    for ((_, a), (_, b)) in one.components.iter().zip(&two.components) {
        assert_eq!(a, b);
    }
}
