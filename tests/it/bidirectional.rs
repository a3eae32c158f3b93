//! The bidirectional integrators (`vcm`, `bdpt`, `lighttracer`) against independent answers:
//! - the shared Cornell box, its glass-and-mirror variant and a room of coated spheres on
//!   rough metal against the path tracer (bpm too on the Cornell box): block
//!   means of 16 independent renders of each, every block within 4 standard errors (a 3%
//!   bias is caught: the test of the test);
//! - a white furnace (every wall emits and reflects): `Le / (1 - rho)` analytically;
//! - bit-identical images on 1 and 2 threads;
//! - a thin lens, and an environment light behind a portal (a room lit through its open ceiling) against the
//!   path tracer.
use crate::support as common;

use common::{render_with, CORNELL};
use photon::accel::BackendKind;
use photon::imageio::RgbImage;
use photon::integrator::vcm::{self, MergeRadius, Technique};
use photon::integrator::IntegratorKind;
use photon::math::Vec3;
use photon::scene::{loader, Scene};

const SPHERES: &str = "../shared/scenes/cornell-spheres/scene.pbrt";

/// Independent renders of each integrator (their spread gives each block's standard error).
const SEEDS: u64 = 16;

/// Blocks per side of the image the block means are taken over.
const BLOCKS: usize = 4;

/// The luminance-like mean (RGB average) of each of `BLOCKS x BLOCKS` blocks of a
/// `w x h` image.
fn block_means(pixels: &[[f32; 3]], w: usize, h: usize) -> Vec<f64> {
    let mut sums = [0.0f64; BLOCKS * BLOCKS];
    for (i, p) in pixels.iter().enumerate() {
        let (x, y) = (i % w, i / w);
        let b = (y * BLOCKS / h) * BLOCKS + x * BLOCKS / w;
        sums[b] += (p[0] + p[1] + p[2]) as f64 / 3.0;
    }
    let per = (w * h / (BLOCKS * BLOCKS)) as f64;
    sums.iter().map(|s| s / per).collect()
}

/// The merge radius of these tests: 0.003 of the scene's radius (half a pixel here), small
/// enough that VCM's bias (VCM is consistent, not unbiased) stays below these tests' noise:
/// at one pixel footprint (the default is two), 48x48 pixels are so large that a block next to the
/// light is 4.6% too bright at 4 spp.
const RADIUS: f32 = 0.003;

/// VCM's merging in these tests: the merge radius (of the scene's radius), whether it
/// merges at every vertex (`--all-merges`), and the light subpaths per pixel
/// (`--light-paths`; `None`: the pilot's choice).
#[derive(Clone, Copy)]
struct Merging(f32, bool, Option<f32>);

/// Renders `scene` with `kind` at `w x h`, `spp` samples, seed `seed`; VCM merging as
/// `merging` says.
fn render_small(
    scene: &Scene,
    kind: IntegratorKind,
    (w, h, spp): (u32, u32, u32),
    seed: u64,
    Merging(radius, all_merges, light_paths): Merging,
) -> RgbImage {
    let overrides = photon::tools::job::Overrides {
        res: Some((w, h)),
        spp: Some(spp),
        seed,
        merge_radius: Some(MergeRadius::Scene(radius)),
        all_merges,
        light_paths,
        ..Default::default()
    };
    let job = common::job(scene, kind, BackendKind::Embree).with(&overrides);
    let pool = job.pool().expect("thread pool");
    let (accel, _) = job.build(&pool).expect("accel builds");
    job.render(&accel, &pool, &|_, _| {}).image
}

/// Each block's mean over `seeds` renders of `kind` and its standard error (from the spread
/// between the seeds).
fn blocks(
    scene: &Scene,
    kind: IntegratorKind,
    (w, h, spp): (u32, u32, u32),
    seeds: u64,
    merging: Merging,
) -> Vec<(f64, f64)> {
    let runs: Vec<Vec<f64>> = (0..seeds)
        .map(|seed| {
            let image = render_small(scene, kind, (w, h, spp), 1000 + seed, merging);
            block_means(&image.pixels, w as usize, h as usize)
        })
        .collect();
    let n = seeds as f64;
    (0..BLOCKS * BLOCKS)
        .map(|b| {
            let mean = runs.iter().map(|r| r[b]).sum::<f64>() / n;
            let var = runs.iter().map(|r| (r[b] - mean).powi(2)).sum::<f64>() / (n - 1.0);
            (mean, (var / n).sqrt())
        })
        .collect()
}

/// The largest block difference between `a` (scaled by `scale`) and `b`, in standard errors.
fn worst_sigma(a: &[(f64, f64)], b: &[(f64, f64)], scale: f64) -> f64 {
    a.iter()
        .zip(b)
        .map(|(&(ma, sa), &(mb, sb))| {
            let se = ((sa * scale).powi(2) + sb.powi(2)).sqrt().max(1e-12);
            (ma * scale - mb).abs() / se
        })
        .fold(0.0, f64::max)
}

fn agree_with_path(file: &str, kinds: &[(IntegratorKind, u32)], path_spp: u32) {
    agree_with_path_at(file, kinds, path_spp, Merging(RADIUS, false, None))
}

/// [`agree_with_path`] with VCM merging as `merging` says.
fn agree_with_path_at(
    file: &str,
    kinds: &[(IntegratorKind, u32)],
    path_spp: u32,
    merging: Merging,
) {
    let scene = loader::load(std::path::Path::new(file)).expect("scene loads");
    let (w, h) = (48, 48);
    let path = blocks(
        &scene,
        IntegratorKind::Path,
        (w, h, path_spp),
        SEEDS,
        merging,
    );
    for &(kind, spp) in kinds {
        let got = blocks(&scene, kind, (w, h, spp), SEEDS, merging);
        let worst = worst_sigma(&got, &path, 1.0);
        let rel: Vec<String> = got
            .iter()
            .zip(&path)
            .map(|(a, b)| {
                let sigma = (a.0 - b.0) / (a.1 * a.1 + b.1 * b.1).sqrt().max(1e-12);
                format!("{:.3} ({sigma:+.1})", a.0 / b.0)
            })
            .collect();
        println!("{file} {kind:?}: worst block {worst:.2} sigma; block ratios {rel:?}");
        assert!(
            worst < 4.0,
            "{kind:?} differs from path by {worst:.1} sigma in a block"
        );
        // The test of the test: 3% too dark is caught.
        let biased = worst_sigma(&got, &path, 0.97);
        assert!(
            biased > 4.0,
            "a 3% bias would pass ({biased:.1} sigma): too noisy"
        );
    }
}

/// Measured (48x48, 16 seeds): worst block bdpt 4 spp 1.66 sigma, lighttracer 16 spp 2.16,
/// vcm 4 spp 1.70 (glass and mirror: bdpt 1.83, vcm 1.69); every 3% darker image is caught.
#[test]
fn bidirectional_agree_with_path_on_the_cornell_box() {
    agree_with_path(
        CORNELL,
        &[
            (IntegratorKind::Bdpt, 4),
            (IntegratorKind::Lighttracer, 16),
            (IntegratorKind::Vcm, 4),
            (IntegratorKind::Bpm, 64),
        ],
        32,
    );
}

/// VCM merging at every vertex (`--all-merges`) against the path tracer. The radius is
/// small here, so merges take a small share: this checks their weights at diffuse
/// vertices, not the merges' own bias (`direct_light` checks merges of direct light).
#[test]
fn vcm_with_all_merges_agrees_with_path_on_the_cornell_box() {
    agree_with_path_at(
        CORNELL,
        &[(IntegratorKind::Vcm, 4)],
        32,
        Merging(RADIUS, true, None),
    );
}

/// VCM and bdpt with one light subpath per ten pixels (camera subpath k connecting to
/// light subpath k mod their number, light tracing and the weights counting that number)
/// against the path tracer.
#[test]
fn bidirectional_with_fewer_light_subpaths_agree_with_path() {
    agree_with_path_at(
        CORNELL,
        &[(IntegratorKind::Vcm, 4), (IntegratorKind::Bdpt, 4)],
        32,
        Merging(RADIUS, false, Some(0.1)),
    );
}

/// A floor lit and seen through a glass slab, the light reaching it through the glass too
/// (L S S D S S E): every merge VCM can make here is at the floor seen through the glass,
/// so its default rule (merges only at vertices whose neighbour towards the camera is purely
/// specular, `vcm::merges_at`) must give the image of `--all-merges` (to rounding: the
/// light subpaths add a merge's terms once their next surface is known). Weights that drop
/// the pending terms of a light vertex followed by the glass differ by far more.
#[test]
fn vcm_merges_through_glass_as_all_merges_do() {
    let text = format!(
        r#"LookAt 0 1.5 0  0 0 0  0 0 1
Camera "perspective" "float fov" [ 40 ]
Film "rgb" "integer xresolution" [ 32 ] "integer yresolution" [ 32 ]
Integrator "path" "integer maxdepth" [ 8 ]
WorldBegin
AttributeBegin
  AreaLightSource "diffuse" "rgb L" [ 6 6 6 ]
  Shape "trianglemesh" "point3 P" [ -0.8 2.2 -0.8  0.8 2.2 -0.8  0.8 2.2 0.8  -0.8 2.2 0.8 ]
    "integer indices" [ 0 1 2 0 2 3 ]
AttributeEnd
AttributeBegin
  Material "diffuse" "rgb reflectance" [ 0.6 0.5 0.4 ]
  Shape "trianglemesh" "point3 P" [ -3 0 -3  3 0 -3  3 0 3  -3 0 3 ]
    "integer indices" [ 0 2 1 0 3 2 ]
AttributeEnd
AttributeBegin
  Material "dielectric" "float eta" [ 1.5 ]
  Translate 0 0.4 0
  Scale 2.5 0.1 2.5
  {cube}
AttributeEnd
"#,
        cube = common::CUBE
    );
    let file = common::write_scene("bidirectional", "glass-slab", &text);
    let scene = loader::load(&file).expect("scene loads");
    let render = |all_merges: bool| {
        let overrides = photon::tools::job::Overrides {
            spp: Some(8),
            seed: 3,
            merge_radius: Some(MergeRadius::Scene(0.03)),
            all_merges,
            // As many light subpaths for both (the pilot's choice depends on the weights).
            light_paths: Some(1.0),
            ..Default::default()
        };
        let job = common::job(&scene, IntegratorKind::Vcm, BackendKind::Embree).with(&overrides);
        let pool = job.pool().expect("thread pool");
        let (accel, _) = job.build(&pool).expect("accel builds");
        job.render(&accel, &pool, &|_, _| {}).image
    };
    let (sds, all) = (render(false), render(true));
    let worst = worst_relative(&sds, &all);
    let sum: f64 = all.pixels.iter().flatten().map(|&v| v as f64).sum();
    println!("SDS rule against all merges: worst relative pixel difference {worst:.2e}");
    assert!(sum > 0.0, "the floor is lit");
    assert!(
        worst < 1e-4,
        "SDS merges differ from all merges by {worst:.2e}"
    );
}

/// The largest difference of a channel between `a` and `b`, relative to `b`'s (at least
/// 1e-3).
fn worst_relative(a: &RgbImage, b: &RgbImage) -> f64 {
    a.pixels
        .iter()
        .flatten()
        .zip(b.pixels.iter().flatten())
        .map(|(&x, &y)| (x - y).abs() as f64 / (y.abs() as f64).max(1e-3))
        .fold(0.0, f64::max)
}

/// A panel 0.02 above a floor, in the shadow of a black blocker out of view, under a
/// distant light: nothing lights the panel's top (the floor is below its plane, the blocker
/// is black), so its image is exactly black, while the floor around it is lit. Merging with
/// a radius of 0.3 (fifteen times the gap) must not take the floor's light vertices for the
/// panel's: before they had to lie on the camera vertex's surface, bpm's panel was lit
/// within the merge radius of its edges.
#[test]
fn merges_stay_on_their_surface() {
    let text = r#"LookAt 0 3 0  0 0 0  0 0 1
Camera "perspective" "float fov" [ 40 ]
Film "rgb" "integer xresolution" [ 32 ] "integer yresolution" [ 32 ]
WorldBegin
LightSource "distant" "point3 from" [ 2 1 0 ] "point3 to" [ 0 0 0 ] "rgb L" [ 3 3 3 ]
Material "diffuse" "rgb reflectance" [ 0.5 0.5 0.5 ]
Shape "trianglemesh" "point3 P" [ -3 0 -3  3 0 -3  3 0 3  -3 0 3 ] "integer indices" [ 0 2 1 0 3 2 ]
Shape "trianglemesh" "point3 P" [ -0.5 0.02 -0.5  0.5 0.02 -0.5  0.5 0.02 0.5  -0.5 0.02 0.5 ]
  "integer indices" [ 0 2 1 0 3 2 ]
Material "diffuse" "rgb reflectance" [ 0 0 0 ]
Shape "trianglemesh" "point3 P" [ 1.44 1 -0.52  2.48 1 -0.52  2.48 1 0.52  1.44 1 0.52 ]
  "integer indices" [ 0 2 1 0 3 2 ]
"#;
    let file = common::write_scene("bidirectional", "panel-above-floor", text);
    let scene = loader::load(&file).expect("scene loads");
    // 0.3 in scene units (of the scene's bounding sphere's radius, about 4.3).
    let (lo, hi) = scene.bounds();
    let radius = 0.3 / ((hi - lo).length() / 2.0);
    let image = render_small(
        &scene,
        IntegratorKind::Bpm,
        (32, 32, 4),
        7,
        Merging(radius, false, None),
    );
    let mean = |x0: usize, x1: usize, y0: usize, y1: usize| {
        let mut sum = 0.0f64;
        for y in y0..y1 {
            for x in x0..x1 {
                sum += image.pixels[y * 32 + x]
                    .iter()
                    .map(|&v| v as f64)
                    .sum::<f64>()
                    / 3.0;
            }
        }
        sum / ((x1 - x0) * (y1 - y0)) as f64
    };
    // Pixels 10..22 see the panel within 0.41 of its centre (the path tracer: exactly 0
    // there, 0.0008 over 9..23, whose pixels straddle its edges); 0..4 see the lit floor.
    let (panel, floor) = (mean(10, 22, 10, 22), mean(0, 32, 0, 4));
    println!("bpm, merge radius 0.3: panel {panel:.5}, floor {floor:.4}");
    assert!(floor > 0.1, "the floor is lit: {floor}");
    assert!(
        panel < 0.002 * floor,
        "the panel took the floor's light: {panel} against the floor's {floor}"
    );
}

/// Without a purely specular surface VCM makes no merge by default, and its weights count
/// none: its image is bdpt's (Cornell box, 32x32, 4 spp; to rounding).
#[test]
fn vcm_without_specular_surfaces_is_bdpt() {
    let scene = loader::load(std::path::Path::new(CORNELL)).expect("scene loads");
    let vcm = render_small(
        &scene,
        IntegratorKind::Vcm,
        (32, 32, 4),
        5,
        Merging(RADIUS, false, None),
    );
    let bdpt = render_small(
        &scene,
        IntegratorKind::Bdpt,
        (32, 32, 4),
        5,
        Merging(RADIUS, false, None),
    );
    let worst = worst_relative(&vcm, &bdpt);
    println!("vcm against bdpt on the Cornell box: worst relative pixel difference {worst:.2e}");
    assert!(worst < 1e-5, "vcm differs from bdpt by {worst:.2e}");
}

/// Glass and mirror spheres: caustics (light tracing and merging find them, connections
/// cannot through the glass) and specular chains seen from the camera. The light tracer is
/// left out: it cannot see anything through a mirror. 16 spp: the pilot keeps a light
/// subpath per three pixels here, and at 4 spp bdpt's caustics, from light tracing alone,
/// were heavy-tailed enough that the seeds' spread understated a block's error (-4.1
/// sigma at 0.965, where 1024 spp gave 0.996 with as many light subpaths as pixels and
/// 0.996 with a tenth of them).
#[test]
fn bidirectional_agree_with_path_through_glass_and_mirror() {
    agree_with_path(
        SPHERES,
        &[(IntegratorKind::Bdpt, 16), (IntegratorKind::Vcm, 16)],
        64,
    );
}

/// Coated materials (a rough coated-diffuse and a rough coated-conductor sphere, whose BSDFs
/// are stochastic estimates) and a rough metal floor in a closed room lit by a small light:
/// the MIS weights use those estimates, so only the expectation is checked.
#[test]
fn bidirectional_agree_with_path_on_coated_and_rough_surfaces() {
    let text = format!(
        r#"LookAt 0 0.2 -0.9  0 -0.2 0.5  0 1 0
Camera "perspective" "float fov" [ 70 ]
Film "rgb" "integer xresolution" [ 48 ] "integer yresolution" [ 48 ]
Integrator "path" "integer maxdepth" [ 6 ]
WorldBegin
AttributeBegin
  Material "diffuse" "rgb reflectance" [ 0.6 0.5 0.4 ]
  ReverseOrientation
  {cube}
AttributeEnd
AttributeBegin
  AreaLightSource "diffuse" "rgb L" [ 8 8 8 ]
  Shape "trianglemesh" "point3 P" [ -0.4 0.99 0.0  0.4 0.99 0.0  0.4 0.99 0.8  -0.4 0.99 0.8 ]
    "integer indices" [ 0 1 2 0 2 3 ]
AttributeEnd
AttributeBegin
  Material "coateddiffuse" "rgb reflectance" [ 0.2 0.5 0.8 ] "float roughness" [ 0.15 ]
  Translate -0.4 -0.65 0.4
  Shape "sphere" "float radius" [ 0.35 ]
AttributeEnd
AttributeBegin
  Material "coatedconductor" "float interface.roughness" [ 0.05 ] "float conductor.roughness" [ 0.3 ]
  Translate 0.4 -0.65 0.5
  Shape "sphere" "float radius" [ 0.35 ]
AttributeEnd
AttributeBegin
  Material "conductor" "float roughness" [ 0.2 ]
  Shape "trianglemesh" "point3 P" [ -1 -0.999 -1  1 -0.999 -1  1 -0.999 1  -1 -0.999 1 ]
    "integer indices" [ 0 2 1 0 3 2 ]
AttributeEnd
"#,
        cube = common::CUBE
    );
    let path = common::write_scene("bidirectional", "coated", &text);
    agree_with_path(
        path.to_str().unwrap(),
        &[(IntegratorKind::Bdpt, 16), (IntegratorKind::Vcm, 16)],
        128,
    );
}

/// A room open at the top, lit by a constant environment through a portal over the opening:
/// light subpaths that miss the portal carry nothing, and escaped camera rays see the sky only
/// through it.
#[test]
fn bidirectional_agree_with_path_under_a_portal_sky() {
    let text = r#"LookAt 0 0 -0.9  0 -0.5 1  0 1 0
Camera "perspective" "float fov" [ 70 ]
Film "rgb" "integer xresolution" [ 48 ] "integer yresolution" [ 48 ]
Integrator "path" "integer maxdepth" [ 5 ]
WorldBegin
LightSource "infinite" "rgb L" [ 2 2 2 ] "point3 portal" [ -1 1 -1  1 1 -1  1 1 1  -1 1 1 ]
Material "diffuse" "rgb reflectance" [ 0.6 0.5 0.4 ]
Shape "trianglemesh" "point3 P" [
  -1 -1 -1  1 -1 -1  1 1 -1  -1 1 -1
  -1 -1 1  1 -1 1  1 1 1  -1 1 1 ]
  "integer indices" [ 0 2 1 0 3 2  4 5 6 4 6 7  0 1 5 0 5 4  0 4 7 0 7 3  1 2 6 1 6 5 ]
"#;
    let path = common::write_scene("bidirectional", "portal", text);
    agree_with_path(
        path.to_str().unwrap(),
        &[(IntegratorKind::Bdpt, 8), (IntegratorKind::Vcm, 8)],
        64,
    );
}

/// A room lit by the sun and a sky through a window, inside a ground 60 m wide: the distant
/// and infinite lights aim 95% of their light subpaths at the room (the photon tracer's
/// mixture, `photon::aim`), so every emission density of the MIS weights is the
/// mixture's. Measured (16 seeds): worst block 2.23 sigma; with the camera side's light
/// samples and escaped rays still weighing by the whole disc's density, blocks came out
/// 0.95-1.52x (34 sigma). Without specular surfaces VCM is bdpt (no merges), so bdpt stands
/// for both.
#[test]
fn bidirectional_agree_with_path_in_a_room_lit_through_a_window() {
    let text = r#"LookAt 1.5 1.3 -1.5  -1 0.9 1  0 1 0
Camera "perspective" "float fov" [ 75 ]
Film "rgb" "integer xresolution" [ 48 ] "integer yresolution" [ 48 ]
Integrator "path" "integer maxdepth" [ 5 ]
WorldBegin
LightSource "distant" "point3 from" [ -1 0.8 0.4 ] "point3 to" [ 0 0 0 ] "rgb L" [ 5 5 5 ]
LightSource "infinite" "rgb L" [ 0.4 0.45 0.55 ]
Material "diffuse" "rgb reflectance" [ 0.3 0.3 0.3 ]
Shape "trianglemesh" "point3 P" [ -30 -0.01 -30  30 -0.01 -30  30 -0.01 30  -30 -0.01 30 ]
  "integer indices" [ 0 2 1 0 3 2 ]
Material "diffuse" "rgb reflectance" [ 0.7 0.65 0.6 ]
Shape "trianglemesh" "point3 P" [ -2 0 -2  2 0 -2  2 0 2  -2 0 2 ] "integer indices" [ 0 2 1 0 3 2 ]
Shape "trianglemesh" "point3 P" [ -2 2.5 -2  2 2.5 -2  2 2.5 2  -2 2.5 2 ] "integer indices" [ 0 1 2 0 2 3 ]
Shape "trianglemesh" "point3 P" [ -2 0 2  2 0 2  2 2.5 2  -2 2.5 2 ] "integer indices" [ 0 1 2 0 2 3 ]
Shape "trianglemesh" "point3 P" [ -2 0 -2  2 0 -2  2 2.5 -2  -2 2.5 -2 ] "integer indices" [ 0 2 1 0 3 2 ]
Shape "trianglemesh" "point3 P" [ 2 0 -2  2 0 2  2 2.5 2  2 2.5 -2 ] "integer indices" [ 0 2 1 0 3 2 ]
Shape "trianglemesh" "point3 P" [ -2 0 -2  -2 0 2  -2 0.8 2  -2 0.8 -2
                                  -2 2 -2  -2 2 2  -2 2.5 2  -2 2.5 -2
                                  -2 0.8 -2  -2 0.8 -1  -2 2 -1  -2 2 -2
                                  -2 0.8 1  -2 0.8 2  -2 2 2  -2 2 1 ]
  "integer indices" [ 0 1 2 0 2 3  4 5 6 4 6 7  8 9 10 8 10 11  12 13 14 12 14 15 ]
"#;
    let path = common::write_scene("bidirectional", "window", text);
    let dir = common::TempDir::new("bidirectional-window");
    let out = dir.0.join("aim.exr");
    let run = common::photon()
        .args(["render", path.to_str().unwrap(), "--integrator", "vcm"])
        .args(["--spp", "1", "--stats", "--no-png", "-o"])
        .arg(&out)
        .output()
        .expect("photon runs");
    let stdout = String::from_utf8_lossy(&run.stdout);
    assert!(run.status.success(), "{stdout}");
    assert!(
        stdout.contains("aim 95% of their light subpaths"),
        "the window room should aim: {stdout}"
    );
    agree_with_path(path.to_str().unwrap(), &[(IntegratorKind::Bdpt, 8)], 64);
}

/// A closed cube whose walls all reflect (albedo `rho`) and emit `Le` (two-sided): every pixel
/// sees `Le / (1 - rho)` with a large `maxdepth`. Every technique of the MIS sum meets here
/// (emission hit, light sample, connections, merges, light tracing).
#[test]
fn white_furnace_for_every_bidirectional_integrator() {
    let (le, rho) = (Vec3::new(1.0, 0.5, 2.0), Vec3::new(0.3, 0.5, 0.7));
    let text = format!(
        r#"LookAt 0.2 -0.3 0.1  1 0.5 1  0 1 0
Camera "perspective" "float fov" [ 80 ]
Film "rgb" "integer xresolution" [ 16 ] "integer yresolution" [ 16 ]
PixelFilter "box" "float xradius" [ 0.5 ] "float yradius" [ 0.5 ]
Integrator "path" "integer maxdepth" [ 100 ]
WorldBegin
AttributeBegin
  AreaLightSource "diffuse" "rgb L" [ {} {} {} ] "bool twosided" true
  Material "diffuse" "rgb reflectance" [ {} {} {} ]
  {}
AttributeEnd
"#,
        le.x,
        le.y,
        le.z,
        rho.x,
        rho.y,
        rho.z,
        common::CUBE
    );
    let path = common::write_scene("bidirectional", "furnace", &text);
    let scene = loader::load(&path).expect("furnace loads");
    let want = le / (Vec3::ONE - rho);
    for (kind, spp) in [
        (IntegratorKind::Bdpt, 64),
        (IntegratorKind::Vcm, 64),
        (IntegratorKind::Lighttracer, 1024),
        (IntegratorKind::Bpm, 512),
    ] {
        let out = render_with(&scene, kind, BackendKind::Embree, (16, 16, spp), 0, 7);
        let px: Vec<Vec3> = out
            .image
            .pixels
            .iter()
            .map(|p| Vec3::from_array(*p))
            .collect();
        let n = px.len() as f32;
        let mean = px.iter().copied().sum::<Vec3>() / n;
        // Every pixel has the same expected value: their spread gives the mean's error.
        let var = px.iter().map(|p| (*p - mean) * (*p - mean)).sum::<Vec3>() / (n - 1.0);
        let se = (var / n).powf(0.5);
        let sigmas = ((mean - want).abs() / se).max_element();
        let rel_se = (se / want).max_element();
        println!(
            "furnace {kind:?} {spp} spp: mean {mean} want {want}, {sigmas:.2} sigma \
             (standard error {:.2}%)",
            100.0 * rel_se
        );
        assert!(sigmas < 4.0, "{kind:?}: furnace mean {mean}, want {want}");
        assert!(rel_se < 0.005, "{kind:?}: too noisy to tell a 2% error");
    }
}

/// The light subpaths' splats reach the film in a fixed order: the same image on 1 and 2
/// threads, bit for bit.
#[test]
fn same_image_on_one_and_two_threads() {
    let scene = loader::load(std::path::Path::new(SPHERES)).expect("scene loads");
    for kind in [
        IntegratorKind::Vcm,
        IntegratorKind::Bdpt,
        IntegratorKind::Lighttracer,
    ] {
        let one = render_with(&scene, kind, BackendKind::Embree, (40, 30, 2), 1, 3);
        let two = render_with(&scene, kind, BackendKind::Embree, (40, 30, 2), 2, 3);
        assert!(
            one.image.pixels == two.image.pixels,
            "{kind:?} depends on threads"
        );
        let other = render_with(&scene, kind, BackendKind::Embree, (40, 30, 2), 2, 4);
        assert!(
            one.image.pixels != other.image.pixels,
            "{kind:?} ignores the seed"
        );
    }
}

/// A thin lens (the shared Cornell box with a lens of radius 0.1 focused on the back wall):
/// light vertices connect to a point of the lens drawn for each, camera subpaths start on it.
#[test]
fn bidirectional_agree_with_path_through_a_thin_lens() {
    let text = std::fs::read_to_string(CORNELL).unwrap().replacen(
        "Camera \"perspective\"",
        "Camera \"perspective\" \"float lensradius\" [ 0.1 ] \"float focaldistance\" [ 7.8 ]",
        1,
    );
    assert!(text.contains("lensradius"));
    let path = common::write_scene("bidirectional", "lens", &text);
    agree_with_path(
        path.to_str().unwrap(),
        &[
            (IntegratorKind::Bdpt, 4),
            (IntegratorKind::Lighttracer, 16),
            (IntegratorKind::Vcm, 4),
        ],
        32,
    );
}

/// VCM in passes: any split of the passes over processes (and thread counts) merges to the
/// same file as the whole range, bit for bit (each pass continues the radius schedule from
/// the passes before it, whichever process renders it).
#[test]
fn vcm_passes_split_and_merge_exactly() {
    let dir = common::scratch("bidirectional", "passes");
    let render = |range: &str, threads: &str, out: &str| {
        let o = common::photon()
            .args(["render", "scenes/cornell-glass.pbrt", "--integrator", "vcm"])
            .args([
                "--res",
                "24x20",
                "--pass-spp",
                "2",
                "--no-png",
                "--passes",
                range,
            ])
            .args(["--threads", threads, "-o"])
            .arg(dir.join(out))
            .output()
            .unwrap();
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    };
    let merge = |parts: &[&str], out: &str| {
        let o = common::photon()
            .arg("merge")
            .args(parts.iter().map(|p| dir.join(p)))
            .arg("-o")
            .arg(dir.join(out))
            .arg("--no-png")
            .output()
            .unwrap();
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        std::fs::read(dir.join(out)).unwrap()
    };
    render("0..4", "2", "whole.exr");
    let whole = merge(&["whole.exr"], "whole-merged.exr");
    render("0..1", "1", "a.exr");
    render("1..3", "2", "b.exr");
    render("3..4", "1", "c.exr");
    assert!(merge(&["c.exr", "a.exr", "b.exr"], "split.exr") == whole);
    // The test of the test: another seed gives another file.
    let o = common::photon()
        .args([
            "render",
            "scenes/cornell-glass.pbrt",
            "--integrator",
            "vcm",
            "--seed",
            "9",
        ])
        .args([
            "--res",
            "24x20",
            "--pass-spp",
            "2",
            "--no-png",
            "--passes",
            "0..4",
            "-o",
        ])
        .arg(dir.join("other.exr"))
        .output()
        .unwrap();
    assert!(o.status.success());
    assert!(merge(&["other.exr"], "other-merged.exr") != whole);
}

/// `--merge-radius` takes a fraction of the scene's radius or a number of pixels; anything
/// else is refused in one line naming the flag.
#[test]
fn merge_radius_flag_is_checked() {
    assert_eq!(MergeRadius::parse("2px"), Ok(MergeRadius::Pixels(2.0)));
    assert_eq!(MergeRadius::parse("0.003"), Ok(MergeRadius::Scene(0.003)));
    let dir = common::scratch("bidirectional", "flag");
    for bad in ["0", "2cm", "2000px", "-1px", "1.5", "nan"] {
        let out = common::photon()
            .args(["render", "scenes/cornell-glass.pbrt", "--integrator", "vcm"])
            .args(["--res", "8x8", "--spp", "1", "--merge-radius", bad, "-o"])
            .arg(dir.join("x.exr"))
            .output()
            .unwrap();
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{bad}: {err}");
        assert!(err.contains("--merge-radius"), "{bad}: {err}");
    }
}

/// The light subpaths' share chosen by the pilot (`vcm::light_fraction`) of `text` with
/// `kind`, and of the same file with `--light-paths 0.5` (the flag wins).
fn light_fraction_of(name: &str, text: &str, kind: Technique) -> (f32, f32) {
    let file = common::write_scene("bidirectional", name, text);
    let scene = loader::load(&file).expect("scene loads");
    let job = common::job(&scene, IntegratorKind::Vcm, BackendKind::Embree);
    let pool = job.pool().expect("thread pool");
    let (accel, _) = job.build(&pool).expect("accel builds");
    let lights = scene.emitters();
    let chosen = pool.install(|| vcm::light_fraction(&scene, &accel, &lights, &job.settings, kind));
    let mut s = job.settings.clone();
    s.vcm.light_paths = Some(0.5);
    let given = vcm::light_fraction(&scene, &accel, &lights, &s, kind);
    (chosen, given)
}

/// A diffuse floor under a uniform sky: BSDF sampling takes the sky, and no path has a
/// second surface, so light tracing, connections and merges carry none of the image and
/// the pilot keeps the fewest light subpaths (1/16 of the pixels). A floor lit through a
/// glass sphere by a small light high above, seen from above: the caustic under the sphere,
/// seen through the sphere, is the merges' (no light sample passes the glass), so the pilot
/// keeps more light subpaths. `lighttracer` and `bpm` always trace one per pixel.
#[test]
fn the_pilot_keeps_light_subpaths_where_their_techniques_count() {
    let floor = r#"LookAt 0 3 0  0 0 0  0 0 1
Camera "perspective" "float fov" [ 40 ]
Film "rgb" "integer xresolution" [ 64 ] "integer yresolution" [ 64 ]
WorldBegin
LightSource "infinite" "rgb L" [ 1 1 1 ]
Material "diffuse" "rgb reflectance" [ 0.5 0.5 0.5 ]
Shape "trianglemesh" "point3 P" [ -9 0 -9  9 0 -9  9 0 9  -9 0 9 ] "integer indices" [ 0 2 1 0 3 2 ]
"#;
    let (sky, given) = light_fraction_of("pilot-sky", floor, Technique::Vcm);
    println!("floor under a uniform sky: {sky}");
    assert_eq!(sky, 1.0 / 16.0);
    assert_eq!(given, 0.5);
    let (bdpt, _) = light_fraction_of("pilot-sky", floor, Technique::Bdpt);
    assert_eq!(bdpt, 1.0 / 16.0);
    for t in [Technique::LightTracer, Technique::Bpm] {
        assert_eq!(light_fraction_of("pilot-sky", floor, t).0, 1.0);
    }
    let caustic = r#"LookAt 0 3 0  0 0 0  0 0 1
Camera "perspective" "float fov" [ 40 ]
Film "rgb" "integer xresolution" [ 64 ] "integer yresolution" [ 64 ]
WorldBegin
AttributeBegin
  AreaLightSource "diffuse" "rgb L" [ 400 400 400 ]
  Translate 0 6 0
  Shape "sphere" "float radius" [ 0.05 ]
AttributeEnd
Material "diffuse" "rgb reflectance" [ 0.5 0.5 0.5 ]
Shape "trianglemesh" "point3 P" [ -2 0 -2  2 0 -2  2 0 2  -2 0 2 ] "integer indices" [ 0 2 1 0 3 2 ]
AttributeBegin
  Material "dielectric" "float eta" [ 1.5 ]
  Translate 0 0.8 0
  Shape "sphere" "float radius" [ 0.6 ]
AttributeEnd
"#;
    let (glass, _) = light_fraction_of("pilot-caustic", caustic, Technique::Vcm);
    println!("caustic under a glass sphere: {glass}");
    assert!(glass >= 0.25, "{glass}");
}
