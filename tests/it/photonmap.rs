//! The photon mapper against analytic answers and an independent reference:
//! - furnace: inside a closed box whose walls have albedo rho and all emit Le, radiance is
//!   Le / (1 - rho) everywhere;
//! - Russian + RGB roulette are unbiased: the power a diffuse floor reflects is rho_c times the
//!   power it receives, per channel;
//! - caustic focus: a glass ball (n = 1.5, radius R) under a distant light focuses at
//!   f = n R / (2 (n - 1)) from its centre;
//! - the shared Cornell box against its Tungsten reference.
use crate::support as common;

use common::CUBE;
use photon::accel::{Accel, AccelOptions, BackendKind};
use photon::imageio::metrics::{compare, match_sizes, MaskOptions};
use photon::imageio::read_exr;
use photon::integrator::{IntegratorKind, RenderOutput, RenderSettings};
use photon::math::Vec3;
use photon::photon::estimate::{irradiance_with, EstimateParams};
use photon::photon::trace::{self, TraceSettings};
use photon::photon::{KnnResult, Photon};
use photon::sampling::Pattern;
use photon::scene::{loader, Scene};
use std::path::{Path, PathBuf};

fn write_scene(name: &str, text: &str) -> PathBuf {
    common::write_scene("photonmap", name, text)
}

fn render(scene: &Scene, settings: &RenderSettings) -> RenderOutput {
    common::render_on(
        scene,
        IntegratorKind::Photonmap,
        BackendKind::Embree,
        settings,
    )
}

fn trace_settings(global: u64, caustic: u64, projection_maps: bool) -> TraceSettings {
    TraceSettings {
        global_photons: global,
        caustic_photons: caustic,
        max_bounces: 64,
        projection_maps,
        projection_resolution: 64,
        seed: 7,
        pattern: Pattern::Stratified,
        receiver_alpha: photon::photon::trace::RECEIVER_ALPHA,
        footprint: None,
        aimed: true,
        store_surfaceless_direct: true,
    }
}

#[test]
fn furnace_radiance_is_le_over_one_minus_rho() {
    let (rho, le) = (0.5f32, 1.0f32);
    let text = format!(
        r#"LookAt 0 0 0  0 0 1  0 1 0
Camera "perspective" "float fov" [ 90 ]
Film "rgb" "integer xresolution" [ 32 ] "integer yresolution" [ 32 ]
Sampler "stratified" "integer xsamples" [ 2 ] "integer ysamples" [ 2 ]
PixelFilter "box"
Integrator "photonmap" "integer globalphotons" [ 200000 ] "integer maxdepth" [ 5 ] "integer gathersamples" [ 64 ]
    "integer maxphotonbounces" [ 64 ]
WorldBegin
Material "diffuse" "rgb reflectance" [ {rho} {rho} {rho} ]
AreaLightSource "diffuse" "rgb L" [ {le} {le} {le} ]
ReverseOrientation
{CUBE}
"#
    );
    // Le / (1 - rho) is the whole series of bounces: photons follow it to 64 bounces (0.5^64 is
    // nothing) instead of the maxdepth 5 they would otherwise keep to.
    let scene = loader::load(&write_scene("furnace", &text)).unwrap();
    // The inward normals: every wall emits into the box.
    let n = scene.meshes[0].geometric_normal(0, 0.3, 0.3);
    assert!(
        n.dot(Vec3::new(0.0, 0.0, 1.0)) > 0.99,
        "back wall z=-1 faces +z: {n}"
    );
    let mut settings = RenderSettings::from_scene(&scene).unwrap();
    (settings.spp, settings.light_samples) = (4, 1);
    let out = render(&scene, &settings);
    let want = le / (1.0 - rho);
    let vals: Vec<f32> = out.image.pixels.iter().flatten().copied().collect();
    let mean = vals.iter().sum::<f32>() / vals.len() as f32;
    let within = vals
        .iter()
        .filter(|v| ((*v - want) / want).abs() < 0.05)
        .count() as f32
        / vals.len() as f32;
    let indirect = &out
        .components
        .iter()
        .find(|(n, _)| *n == "indirect")
        .unwrap()
        .1;
    let ind_mean = indirect.pixels.iter().map(|p| p[0]).sum::<f32>() / indirect.pixels.len() as f32;
    println!(
        "furnace: expected {want}, mean {mean:.4} ({:+.2}%), {:.1}% of pixels within 5%; indirect (final gather) {ind_mean:.4} (expected {})",
        100.0 * (mean / want - 1.0),
        100.0 * within,
        rho * rho * le / (1.0 - rho)
    );
    assert!((mean / want - 1.0).abs() < 0.02, "mean {mean} vs {want}");
    // Without final gathering the indirect part is read off the global map directly (only its
    // photons that took a diffuse bounce): rho^2 Le / (1 - rho) on average, noisier per pixel.
    let mut direct_look = settings.clone();
    direct_look.photon.final_gather = false;
    let out = render(&scene, &direct_look);
    let indirect = &out
        .components
        .iter()
        .find(|(n, _)| *n == "indirect")
        .unwrap()
        .1;
    let look = indirect.pixels.iter().map(|p| p[0]).sum::<f32>() / indirect.pixels.len() as f32;
    let want_ind = rho * rho * le / (1.0 - rho);
    println!(
        "furnace, global map looked at directly: indirect mean {look:.4} (expected {want_ind})"
    );
    assert!(
        (look / want_ind - 1.0).abs() < 0.05,
        "direct look at the global map: {look}"
    );
    assert!(
        within > 0.99,
        "only {:.1}% of pixels within 5%",
        100.0 * within
    );
    // The photon-guided gather is unbiased: the same answer, and (Laplace smoothing towards the
    // cosine where the photons say light is even) no more spread. Without the smoothing 90.8%
    // of the pixels were within 5%.
    let mut guided = settings.clone();
    guided.photon.guided_gather = true;
    let out = render(&scene, &guided);
    let vals: Vec<f32> = out.image.pixels.iter().flatten().copied().collect();
    let g_mean = vals.iter().sum::<f32>() / vals.len() as f32;
    let g_within = vals
        .iter()
        .filter(|v| ((*v - want) / want).abs() < 0.05)
        .count() as f32
        / vals.len() as f32;
    println!(
        "furnace, guided gather: mean {g_mean:.4} ({:+.2}%), {:.1}% of pixels within 5%",
        100.0 * (g_mean / want - 1.0),
        100.0 * g_within
    );
    assert!((g_mean / want - 1.0).abs() < 0.02, "guided mean {g_mean}");
    assert!(
        g_within > 0.99,
        "guided: {:.1}% within 5%",
        100.0 * g_within
    );
}

/// A floor of reflectance rho under a point light, inside a black (rho = 0) diffuse box that
/// catches what the floor reflects: reflected / received power = rho per channel.
#[test]
fn roulette_is_unbiased_per_channel() {
    let rho = Vec3::new(0.8, 0.4, 0.1);
    let text = format!(
        r#"Camera "perspective"
WorldBegin
AttributeBegin
  Material "diffuse" "rgb reflectance" [ 0 0 0 ]
  Scale 4 4 4
  {CUBE}
AttributeEnd
Material "diffuse" "rgb reflectance" [ {} {} {} ]
Shape "trianglemesh" "point3 P" [ -2 -1 -2  2 -1 -2  2 -1 2  -2 -1 2 ] "integer indices" [ 0 2 1 0 3 2 ]
LightSource "point" "rgb I" [ 1 1 1 ] "point3 from" [ 0 1 0 ]
"#,
        rho.x, rho.y, rho.z
    );
    let scene = loader::load(&write_scene("roulette", &text)).unwrap();
    let accel = Accel::build(&scene, BackendKind::Embree, AccelOptions::default()).unwrap();
    let lights = scene.emitters();
    let maps = trace::trace(&scene, &accel, &lights, &trace_settings(400_000, 0, false));
    let global = maps.global.expect("global map");
    let (mut received, mut reflected) = (Vec3::ZERO, Vec3::ZERO);
    let (mut n_refl, mut sq) = (0usize, Vec3::ZERO);
    for ph in global.photons() {
        let on_floor =
            (ph.pos().y + 1.0).abs() < 1e-3 && ph.pos().x.abs() < 2.0 && ph.pos().z.abs() < 2.0;
        if ph.has(Photon::DIRECT) && on_floor {
            received += ph.power();
        } else if !ph.has(Photon::DIRECT) {
            reflected += ph.power();
            sq += ph.power() * ph.power();
            n_refl += 1;
        }
    }
    let ratio = reflected / received;
    // Standard error of the reflected sum (photons are i.i.d. up to stratification).
    let sigma = Vec3::new(sq.x.sqrt(), sq.y.sqrt(), sq.z.sqrt()) / received;
    println!("roulette: reflected/received = {ratio:?} (rho {rho:?}, 1 sigma {sigma:?}, {n_refl} photons)");
    for c in 0..3 {
        assert!(
            (ratio[c] - rho[c]).abs() < 4.0 * sigma[c] + 1e-3,
            "channel {c}: {} vs {}",
            ratio[c],
            rho[c]
        );
    }
}

/// Caustic irradiance on the axis of a glass ball lit by a distant light, at distance `d`
/// below its centre, for receiving planes at several distances.
fn ball_focus(projection_maps: bool) -> (f32, Vec<(f32, f32)>, f64) {
    let (n, r) = (1.5f32, 1.0f32);
    let f = n * r / (2.0 * (n - 1.0));
    let mut profile = Vec::new();
    let mut eff = 0.0;
    for k in 0..9 {
        let d = f * (0.8 + 0.05 * k as f32);
        let text = format!(
            r#"Camera "perspective"
WorldBegin
Material "dielectric" "float eta" [ {n} ]
Shape "sphere" "float radius" [ {r} ]
Material "diffuse" "rgb reflectance" [ 0.5 0.5 0.5 ]
Shape "trianglemesh" "point3 P" [ -3 -{d} -3  3 -{d} -3  3 -{d} 3  -3 -{d} 3 ] "integer indices" [ 0 2 1 0 3 2 ]
LightSource "distant" "rgb L" [ 1 1 1 ] "point3 from" [ 0 1 0 ] "point3 to" [ 0 0 0 ]
"#
        );
        let scene = loader::load(&write_scene("ball", &text)).unwrap();
        let accel = Accel::build(&scene, BackendKind::Embree, AccelOptions::default()).unwrap();
        let lights = scene.emitters();
        let maps = trace::trace(
            &scene,
            &accel,
            &lights,
            &trace_settings(0, 300_000, projection_maps),
        );
        eff = maps.stats.caustic_efficiency;
        let caustic = maps.caustic.expect("caustic map");
        let mut params = EstimateParams::new(100, 0.05 * 0.05);
        params.min_photons = 1;
        let (e, _, _) = irradiance_with(
            &caustic,
            Vec3::new(0.0, -d, 0.0),
            Vec3::Y,
            &params,
            &mut KnnResult::new(),
        );
        profile.push((d, e.x));
    }
    (f, profile, eff)
}

#[test]
fn glass_ball_focuses_at_the_paraxial_focus() {
    for pm in [true, false] {
        let (f, profile, eff) = ball_focus(pm);
        let peak = profile
            .iter()
            .copied()
            .fold((0.0, 0.0), |a, b| if b.1 > a.1 { b } else { a });
        println!("projection maps {pm}: caustic efficiency {:.1}%, on-axis caustic irradiance by distance: {profile:?}; peak at {:.3} (f = {f})", 100.0 * eff, peak.0);
        assert!(
            (peak.0 - f).abs() <= 0.05 * f + 1e-4,
            "peak at {} not at f = {f}",
            peak.0
        );
    }
}

/// The shared Cornell box (Tungsten reference, 1024^2 box-downsampled to 128^2). The scene's
/// triangle filter differs from the reference's box-downsampling at the light's edge, so the
/// error is also checked without pixels next to the light (`mask_above`).
#[test]
fn cornell_box_matches_tungsten() {
    let scene = loader::load(Path::new("../shared/scenes/cornell-box/scene-v4.pbrt")).unwrap();
    let mut settings = RenderSettings::from_scene(&scene).unwrap();
    (settings.width, settings.height, settings.spp) = (128, 128, 16);
    let out = render(&scene, &settings);
    let reference = read_exr(Path::new(
        "../shared/scenes/cornell-box/reference-tungsten.exr",
    ))
    .unwrap();
    let (img, reference) = match_sizes(out.image.clone(), reference).unwrap();
    let all = compare(&img, &reference, MaskOptions::default()).unwrap();
    let masked = compare(
        &img,
        &reference,
        MaskOptions {
            mask_above: Some(5.0),
        },
    )
    .unwrap();
    println!(
        "cornell-box 128x128, 16 spp x 2 gather rays, {:.2} s: relMSE {:.5} (all pixels), {:.5} without {} pixels next to the light",
        out.seconds, all.overall.relmse, masked.overall.relmse, masked.masked_emitter
    );
    if masked.overall.relmse > 0.0035 {
        let dir = PathBuf::from("target/test-failures");
        std::fs::create_dir_all(&dir).unwrap();
        photon::imageio::write_exr(
            &dir.join("cornell-box.exr"),
            &img,
            &[],
            photon::imageio::ExrPixel::Float,
        )
        .unwrap();
        photon::imageio::write_png(
            &dir.join("cornell-box-error.png"),
            &photon::imageio::metrics::error_image(
                &img,
                &reference,
                MaskOptions {
                    mask_above: Some(5.0),
                },
            ),
            0.0,
        )
        .unwrap();
    }
    // Measured 0.00185 (masked) and 0.22 (all pixels: the scene's triangle filter against the
    // box-downsampled reference at the light's edge); thresholds leave ~1.9x and ~2.2x margin
    // for other seeds and platforms, and fail if e.g. the indirect component is dropped.
    assert!(
        masked.overall.relmse < 0.0035,
        "relMSE {}",
        masked.overall.relmse
    );
    assert!(all.overall.relmse < 0.5, "relMSE {}", all.overall.relmse);
}
