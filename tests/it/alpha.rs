//! Shape `alpha` cut-outs on both backends, checked against answers computed here:
//! - a checkerboard (and an image) alpha screen stops exactly its closed fraction of a grid of
//!   rays (the fraction counted from the pattern, not from the renderer), for single rays and
//!   8-wide packets on Embree (also `--robust`) and obvhs; a triangle without uv takes
//!   pbrt-v4's default uv (b1 + b2, b2);
//! - a floor under that screen, lit by a distant light, shows E = L cos(theta) times the open
//!   fraction in a direct-lighting render;
//! - alpha 0 hides a shape from every ray (the photon-mapped image is the same as without it);
//! - alpha 0.5 stops about half of rays of differing origins (binomial bound), the very same
//!   rays on both backends; rejected hits let traversal reach the next surface;
//! - bad `alpha` parameters are errors at their `file:line:column`; alpha enters the scene hash
//!   and the memory estimate.
use crate::support as common;

use common::TempDir;
use photon::accel::{alpha_keeps, ray_hash, Accel, AccelOptions, BackendKind, Hit, RayKind};
use photon::integrator::{IntegratorKind, RenderSettings};
use photon::math::{Ray, Vec3};
use photon::scene::{loader, Scene};
use photon::texture::Texture;
use std::f32::consts::PI;

/// A camera looking straight down from `(0, 0.5, 0)` (fov 90: it sees the floor square
/// [-0.5, 0.5]^2), `res`^2 pixels of `spp` (x 1) stratified samples, then `world`.
fn scene_text(res: u32, spp: u32, world: &str) -> String {
    format!(
        r#"LookAt 0 0.5 0  0 0 0  0 0 1
Camera "perspective" "float fov" [ 90 ]
Film "rgb" "integer xresolution" [ {res} ] "integer yresolution" [ {res} ]
PixelFilter "box" "float xradius" [ 0.0001 ] "float yradius" [ 0.0001 ]
Sampler "stratified" "integer xsamples" [ {spp} ] "integer ysamples" [ 1 ] "bool jitter" true
Integrator "photonmap" "integer globalphotons" [ 20000 ] "integer causticphotons" [ 0 ]
WorldBegin
{world}
"#
    )
}

/// The floor, y = 0, [-3, 3]^2, reflectance 0.5.
const FLOOR: &str = r#"Material "diffuse" "rgb reflectance" [ 0.5 0.5 0.5 ]
Shape "trianglemesh" "point3 P" [ -3 0 -3  3 0 -3  3 0 3  -3 0 3 ] "integer indices" [ 0 1 2 0 2 3 ]"#;

/// A horizontal quad at height `y` over [-2, 2]^2 with uv = ((x + 2) / 4, (z + 2) / 4) and the
/// shape parameters `extra` (its alpha).
fn screen(y: f32, extra: &str) -> String {
    format!(
        r#"Shape "trianglemesh" "point3 P" [ -2 {y} -2  2 {y} -2  2 {y} 2  -2 {y} 2 ]
    "point2 uv" [ 0 0  1 0  1 1  0 1 ] "integer indices" [ 0 1 2 0 2 3 ] {extra}"#
    )
}

/// A 40 x 40 checkerboard of alpha 1 / 0 (cells 0.1 wide on the screen); `(s, t) = 40 (u, v)`.
const CHECKS: &str = r#"Texture "checks" "float" "checkerboard" "float uscale" [ 40 ] "float vscale" [ 40 ] "float tex1" [ 1 ] "float tex2" [ 0 ]"#;

/// The 4 x 4 image of [`write_mask`]: 0 where the mask is open (5 of 16 texels), row 0 on top.
const MASK: [[u8; 4]; 4] = [
    [0, 255, 255, 255],
    [255, 0, 255, 0],
    [255, 255, 255, 255],
    [0, 255, 0, 255],
];

/// Writes [`MASK`] as a grey PNG.
fn write_mask(dir: &TempDir) {
    let bytes: Vec<u8> = MASK.iter().flatten().flat_map(|&b| [b, b, b]).collect();
    let img = image::RgbImage::from_raw(4, 4, bytes).unwrap();
    img.save(dir.0.join("mask.png")).unwrap();
}

fn load_world(dir: &TempDir, res: u32, spp: u32, world: &str) -> Scene {
    let path = dir.write("scene.pbrt", scene_text(res, spp, world));
    loader::load(&path).unwrap_or_else(|e| panic!("{e}"))
}

fn both(scene: &Scene) -> [(BackendKind, Accel); 2] {
    [BackendKind::Embree, BackendKind::Obvhs]
        .map(|k| (k, Accel::build(scene, k, AccelOptions::default()).unwrap()))
}

/// [`both`] plus Embree in robust mode (`--robust`).
fn all_three(scene: &Scene) -> Vec<(String, Accel)> {
    let robust = AccelOptions { robust: true };
    let mut v: Vec<(String, Accel)> = both(scene)
        .into_iter()
        .map(|(k, a)| (k.to_string(), a))
        .collect();
    let accel = Accel::build(scene, BackendKind::Embree, robust).unwrap();
    v.push(("embree --robust".into(), accel));
    v
}

/// A unit direction towards the distant light (tilted, so the shadow is shifted).
fn light_dir() -> Vec3 {
    Vec3::new(0.3, 1.0, -0.2).normalize()
}

/// 160 x 160 rays along [`light_dir`] from y = 0.5 that cross the plane y = 1 at
/// `x, z = -1 + (i + 1/2) / 80`: 8 per 0.1-wide cell in each axis over 20 cells (a whole
/// number of periods of both patterns), never nearer than 1/160 to a cell edge.
fn grid_rays() -> Vec<Ray> {
    let d = light_dir();
    let n = 160;
    let mut rays = Vec::with_capacity(n * n);
    for i in 0..n {
        for j in 0..n {
            let at = |k: usize| -1.0 + (k as f32 + 0.5) / 80.0;
            let cross = Vec3::new(at(i), 1.0, at(j));
            rays.push(Ray::new(cross - d * (0.5 / d.y), d));
        }
    }
    rays
}

/// Occlusion and closest hit of every ray, singly and in batches (Embree: 8-wide packets).
fn answers(accel: &Accel, rays: &[Ray]) -> (Vec<bool>, Vec<Option<Hit>>) {
    let k = RayKind::Shadow;
    let single_occ: Vec<bool> = rays.iter().map(|r| accel.occluded(k, r)).collect();
    let single_hit: Vec<Option<Hit>> = rays.iter().map(|r| accel.intersect(k, r)).collect();
    let mut occ = vec![false; rays.len()];
    let mut hit = vec![None; rays.len()];
    accel.occluded_batch(k, rays, &mut occ);
    accel.intersect_batch(k, rays, &mut hit);
    assert_eq!(occ, single_occ, "{}: packets and single rays", accel.kind());
    assert_eq!(hit, single_hit, "{}: packets and single rays", accel.kind());
    (occ, hit)
}

/// Checks that exactly `closed` of the grid rays are stopped by the screen (mesh 1) on both
/// backends, and that each closest hit is the screen exactly when the ray is occluded.
fn assert_grid_blocked(scene: &Scene, closed: usize, what: &str) {
    let rays = grid_rays();
    for (kind, accel) in all_three(scene) {
        let (occ, hit) = answers(&accel, &rays);
        let blocked = occ.iter().filter(|&&o| o).count();
        println!(
            "{what} ({kind}): {blocked} of {} rays blocked, expected {closed}",
            rays.len()
        );
        assert_eq!(blocked, closed, "{what} ({kind})");
        for (o, h) in occ.iter().zip(&hit) {
            assert_eq!(*o, h.is_some_and(|h| h.mesh == 1), "{what} ({kind})");
        }
    }
}

#[test]
fn checkerboard_screen_blocks_exactly_its_closed_fraction() {
    let dir = TempDir::new("photon-alpha");
    let world = format!(
        "{FLOOR}\n{CHECKS}\n{}",
        screen(1.0, r#""texture alpha" "checks""#)
    );
    let scene = load_world(&dir, 8, 1, &world);
    // Half the cells are closed (floor(s) + floor(t) even): 12800 of 25600.
    assert_grid_blocked(&scene, 160 * 160 / 2, "checkerboard");
}

#[test]
fn image_mask_blocks_exactly_its_closed_fraction() {
    let dir = TempDir::new("photon-alpha");
    write_mask(&dir);
    // 10 repeats of the 4-texel image across u: texels 0.1 wide on the screen, as the checks.
    let world = format!(
        "{FLOOR}\nTexture \"mask\" \"float\" \"imagemap\" \"string filename\" \"mask.png\" \
         \"string filter\" \"point\" \"float uscale\" [ 10 ] \"float vscale\" [ 10 ]\n{}",
        screen(1.0, r#""texture alpha" "mask""#)
    );
    let scene = load_world(&dir, 8, 1, &world);
    let open = MASK.iter().flatten().filter(|&&b| b == 0).count();
    assert_eq!(open, 5);
    assert_grid_blocked(&scene, 160 * 160 * (16 - open) / 16, "image mask");
}

/// The mean of the rendered image (all of it sees the floor) and its expected value without
/// any screen: rho / pi L cos(theta) for the distant light of [`light_dir`] with L = 1.
fn floor_render(dir: &TempDir, screen_alpha: &str, kind: BackendKind) -> (f64, f64) {
    let d = light_dir();
    let world = format!(
        "{FLOOR}\n{CHECKS}\n{}\nLightSource \"distant\" \"rgb L\" [ 1 1 1 ] \"point3 from\" [ {} {} {} ] \"point3 to\" [ 0 0 0 ]",
        screen(1.0, screen_alpha),
        d.x,
        d.y,
        d.z
    );
    let scene = load_world(dir, 40, 16, &world);
    let settings = common::scene_settings(&scene, |_| {});
    let out = common::render_on(&scene, IntegratorKind::Direct, kind, &settings);
    let px = &out.image.pixels;
    let mean = px.iter().map(|p| p[1] as f64).sum::<f64>() / px.len() as f64;
    (mean, 0.5 / PI as f64 * d.y as f64)
}

#[test]
fn floor_under_the_checkerboard_gets_half_the_irradiance() {
    // The camera sees [-0.5, 0.5]^2 of the floor, 5 periods of the (shifted) shadow pattern in
    // each axis, so the open fraction of what it sees is exactly 1/2; pixels cover equal floor
    // areas. Error: 16 stratified samples per pixel along the cell edges only.
    let dir = TempDir::new("photon-alpha");
    for kind in [BackendKind::Embree, BackendKind::Obvhs] {
        let (mean, unshadowed) = floor_render(&dir, r#""texture alpha" "checks""#, kind);
        let rel = mean / (0.5 * unshadowed) - 1.0;
        println!(
            "checkerboard shadow ({kind}): mean {mean:.5}, expected {:.5} ({rel:+.2e})",
            0.5 * unshadowed
        );
        assert!(rel.abs() < 2e-3, "{kind}: {rel}");
        // Without alpha the screen is opaque: no direct light at all.
        let (dark, _) = floor_render(&dir, "", kind);
        assert_eq!(dark, 0.0, "{kind}");
    }
}

#[test]
fn floor_under_a_half_transparent_screen_gets_half_the_irradiance() {
    // Every shadow ray starts elsewhere, so each passes with probability 1/2 independently:
    // 25600 of them, relative standard deviation 1 / sqrt(25600) = 0.00625; bound 5 sigma.
    let dir = TempDir::new("photon-alpha");
    for kind in [BackendKind::Embree, BackendKind::Obvhs] {
        let (mean, unshadowed) = floor_render(&dir, r#""float alpha" [ 0.5 ]"#, kind);
        let rel = mean / (0.5 * unshadowed) - 1.0;
        println!(
            "alpha 0.5 shadow ({kind}): mean {mean:.5}, expected {:.5} ({rel:+.2e})",
            0.5 * unshadowed
        );
        assert!(rel.abs() < 5.0 * 0.00625, "{kind}: {rel}");
    }
}

/// Rays from random points of the floor region (y in (0.01, 0.9)) to random directions of the
/// upper hemisphere that cross the screen at y = 1 (a hash of the index: reproducible).
fn random_up_rays(n: usize) -> Vec<Ray> {
    let u = |i: usize, k: u64| photon::sampling::to_unit(photon::sampling::hash(&[i as u64, k]));
    (0..n)
        .map(|i| {
            let o = Vec3::new(u(i, 0) - 0.5, 0.01 + 0.89 * u(i, 1), u(i, 2) - 0.5);
            let d = Vec3::new(u(i, 3) - 0.5, 1.0, u(i, 4) - 0.5);
            Ray::new(o, d)
        })
        .collect()
}

#[test]
fn alpha_half_stops_half_the_rays_and_the_same_rays_on_both_backends() {
    let dir = TempDir::new("photon-alpha");
    let scene = load_world(
        &dir,
        8,
        1,
        &format!("{FLOOR}\n{}", screen(1.0, r#""float alpha" 0.5"#)),
    );
    let n = 20_000;
    let rays = random_up_rays(n);
    let [(_, embree), (_, obvhs)] = both(&scene);
    let (occ_e, hit_e) = answers(&embree, &rays);
    let (occ_o, hit_o) = answers(&obvhs, &rays);
    assert_eq!(occ_e, occ_o, "the same rays are stopped on both backends");
    let mesh = |h: &[Option<Hit>]| h.iter().map(|h| h.map(|h| h.mesh)).collect::<Vec<_>>();
    assert_eq!(mesh(&hit_e), mesh(&hit_o));
    // The decision is pbrt-v4's: blocked exactly when hash(o, d) <= 1/2 (computed here from
    // the ray alone, not from any backend).
    for (r, &o) in rays.iter().zip(&occ_e) {
        assert_eq!(o, ray_hash(r.o, r.d) <= 0.5);
    }
    let blocked = occ_e.iter().filter(|&&o| o).count() as f64 / n as f64;
    let sigma = (0.25 / n as f64).sqrt();
    println!("alpha 0.5: {blocked:.4} of {n} rays blocked (sigma {sigma:.4})");
    assert!((blocked - 0.5).abs() < 5.0 * sigma, "{blocked}");
}

#[test]
fn alpha_keeps_follows_pbrt() {
    let (o, d) = (Vec3::new(0.1, 0.2, 0.3), Vec3::Y);
    assert!(alpha_keeps(1.0, o, d) && alpha_keeps(7.0, o, d) && alpha_keeps(f32::NAN, o, d));
    assert!(!alpha_keeps(0.0, o, d) && !alpha_keeps(-1.0, o, d));
    // In between: kept exactly when the ray's hash is at most a.
    let u = ray_hash(o, d);
    assert!(alpha_keeps(u, o, d) && alpha_keeps((u + 0.01).min(0.999), o, d));
    assert!(u <= 0.01 || !alpha_keeps(u - 0.01, o, d));
    // The hash is uniform: mean 1/2, 4 quarters alike (20000 rays; 5 sigma bounds).
    let rays = random_up_rays(20_000);
    let hs: Vec<f32> = rays.iter().map(|r| ray_hash(r.o, r.d)).collect();
    let mean = hs.iter().map(|&h| h as f64).sum::<f64>() / hs.len() as f64;
    assert!(
        (mean - 0.5).abs() < 5.0 * (1.0 / 12.0 / 20_000.0f64).sqrt(),
        "{mean}"
    );
    for q in 0..4 {
        let lo = q as f32 / 4.0;
        let c = hs.iter().filter(|&&h| h >= lo && h < lo + 0.25).count() as f64;
        assert!(
            (c - 5000.0).abs() < 5.0 * (20_000.0 * 0.25 * 0.75f64).sqrt(),
            "{q}: {c}"
        );
    }
}

#[test]
fn rejected_hits_let_traversal_reach_the_next_surface() {
    let dir = TempDir::new("photon-alpha");
    // Mesh 1: alpha 0 at y = 1; mesh 2: opaque at y = 2; mesh 3: opaque at y = 3.
    let world = format!(
        "{FLOOR}\n{}\n{}\n{}",
        screen(1.0, r#""float alpha" 0"#),
        screen(2.0, ""),
        screen(3.0, "")
    );
    let scene = load_world(&dir, 8, 1, &world);
    let rays = random_up_rays(2000);
    for (kind, accel) in all_three(&scene) {
        let (occ, hit) = answers(&accel, &rays);
        for (r, (o, h)) in rays.iter().zip(occ.iter().zip(&hit)) {
            let h = h.expect("every ray reaches y = 2");
            assert_eq!(h.mesh, 2, "{kind}: the opaque quad behind the cut-out");
            let t = (2.0 - r.o.y) / r.d.y;
            assert!((h.t - t).abs() <= 1e-5 * t, "{kind}: t {} vs {t}", h.t);
            assert!(o, "{kind}");
        }
        // With only the alpha-0 quad in the way, a ray ending before y = 2 is not occluded.
        let short: Vec<Ray> = rays
            .iter()
            .map(|r| Ray::segment(r.o, r.d, (1.5 - r.o.y) / r.d.y))
            .collect();
        let (occ, hit) = answers(&accel, &short);
        assert!(
            occ.iter().all(|&o| !o) && hit.iter().all(|h| h.is_none()),
            "{kind}"
        );
    }
}

#[test]
fn stacked_half_alpha_layers_share_the_ray_hash_as_in_pbrt() {
    // pbrt-v4 hashes the ray (o, d), not the surface: a ray passes two layers of alpha 0.5
    // together or is stopped by the first; it never stops at the second.
    let dir = TempDir::new("photon-alpha");
    let world = format!(
        "{}\n{}",
        screen(1.0, r#""float alpha" 0.5"#),
        screen(2.0, r#""float alpha" 0.5"#)
    );
    let scene = load_world(&dir, 8, 1, &format!("{FLOOR}\n{world}"));
    let rays = random_up_rays(4000);
    for (kind, accel) in both(&scene) {
        let (_, hit) = answers(&accel, &rays);
        let first = hit
            .iter()
            .filter(|h| h.is_some_and(|h| h.mesh == 1))
            .count();
        let none = hit.iter().filter(|h| h.is_none()).count();
        println!("{kind}: {first} stopped by the first layer, {none} through both");
        assert_eq!(
            first + none,
            rays.len(),
            "{kind}: none stops at the second layer"
        );
        assert!(first > 1800 && none > 1800, "{kind}");
    }
}

#[test]
fn batches_with_inactive_lanes_match_single_rays() {
    let dir = TempDir::new("photon-alpha");
    let world = format!(
        "{FLOOR}\n{CHECKS}\n{}",
        screen(1.0, r#""texture alpha" "checks""#)
    );
    let scene = load_world(&dir, 8, 1, &world);
    let mut rays = random_up_rays(61);
    // Lanes Embree never sees: empty interval, NaN direction, zero direction.
    rays[3] = Ray::segment(rays[3].o, rays[3].d, -1.0);
    rays[9].d = Vec3::new(f32::NAN, 1.0, 0.0);
    rays[10].d = Vec3::ZERO;
    for (kind, accel) in both(&scene) {
        let (occ, hit) = answers(&accel, &rays); // asserts batch == single
        assert!(!occ[3] && !occ[9] && !occ[10] && hit[3].is_none(), "{kind}");
        assert!(occ.iter().any(|&o| o) && occ.iter().filter(|&&o| !o).count() > 3);
    }
}

/// Renders `scene` with the photon mapper (camera, shadow, gather and photon rays) at 24^2.
fn photon_render(scene: &Scene, kind: BackendKind) -> Vec<[f32; 3]> {
    let settings = common::scene_settings(scene, |s| (s.width, s.height, s.spp) = (24, 24, 2));
    common::render_on(scene, IntegratorKind::Photonmap, kind, &settings)
        .image
        .pixels
}

#[test]
fn alpha_zero_is_invisible_to_every_ray() {
    // The small Cornell-like scene with, last, a quad across the middle of the box (inside its
    // bounds, so the scene's size and the photon radii do not change). With alpha 0 the
    // photon-mapped image is the image without the quad, pixel for pixel; opaque, it is not.
    let quad = |extra: &str| {
        format!(
            "Shape \"trianglemesh\" \"point3 P\" [ -0.9 0.2 0.5  0.9 0.2 0.5  0.9 1.8 -0.5  -0.9 1.8 -0.5 ] \
             \"integer indices\" [ 0 1 2 0 2 3 ] {extra}"
        )
    };
    let dir = TempDir::new("photon-alpha");
    let load = |world: &str| {
        let p = dir.write("scene.pbrt", common::small_scene(world));
        loader::load(&p).unwrap_or_else(|e| panic!("{e}"))
    };
    let without = load("");
    let hidden = load(&quad("\"float alpha\" 0"));
    let opaque = load(&quad(""));
    assert_eq!(without.bounds(), hidden.bounds());
    for kind in [BackendKind::Embree, BackendKind::Obvhs] {
        let base = photon_render(&without, kind);
        assert_eq!(
            photon_render(&hidden, kind),
            base,
            "{kind}: alpha 0 changes the image"
        );
        assert_ne!(
            photon_render(&opaque, kind),
            base,
            "{kind}: the quad is in view"
        );
    }
}

#[test]
fn alpha_parameters_load_as_pbrt_reads_them() {
    let dir = TempDir::new("photon-alpha");
    let world = format!(
        "{CHECKS}\n{}\n{}\n{}\nObjectBegin \"o\"\n{}\nObjectEnd\nObjectInstance \"o\"\n\
         Shape \"sphere\" \"float radius\" 0.5 \"texture alpha\" \"checks\"",
        screen(1.0, r#""float alpha" 1"#),
        screen(2.0, r#""float alpha" [ 0.25 ]"#),
        // Bracketed, as pbrt-v4-scenes' sanmiguel leaves write it.
        screen(3.0, r#""texture alpha" [ "checks" ]"#),
        screen(4.0, r#""float alpha" 0"#),
    );
    let s = load_world(&dir, 8, 1, &world);
    let checks = s.textures.float.get("checks").unwrap();
    let m = &s.meshes;
    assert!(m[0].alpha.is_none(), "alpha 1 is no alpha");
    assert_eq!(
        m[1].alpha.as_deref(),
        Some(&Texture::Constant(Vec3::splat(0.25)))
    );
    assert!(std::sync::Arc::ptr_eq(m[2].alpha.as_ref().unwrap(), checks));
    assert_eq!(
        m[3].alpha.as_deref(),
        Some(&Texture::Constant(Vec3::ZERO)),
        "instance"
    );
    assert!(m[4].sphere.is_some() && m[4].indices.len() > 100);
    assert!(
        std::sync::Arc::ptr_eq(m[4].alpha.as_ref().unwrap(), checks),
        "sphere"
    );
}

#[test]
fn bad_alpha_is_an_error_at_its_location() {
    let dir = TempDir::new("photon-alpha");
    let cases: [(&str, &str, &str); 7] = [
        (r#""float alpha" -0.5"#, "alpha -0.5 is outside [0, 1]", ""),
        (r#""float alpha" 1.5"#, "alpha 1.5 is outside [0, 1]", ""),
        (
            r#""texture alpha" "nope""#,
            "unknown float texture \"nope\"",
            "",
        ),
        (
            r#""texture alpha" "rgbchecks""#,
            "unknown float texture \"rgbchecks\" (\"rgbchecks\" is a spectrum texture)",
            "Texture \"rgbchecks\" \"spectrum\" \"checkerboard\"\n",
        ),
        (
            r#""rgb alpha" [ 0.5 0.5 0.5 ]"#,
            "wrong type, expected float",
            "",
        ),
        (
            r#""float alpha" [ 0.5 0.5 ]"#,
            "expected 1 value, got 2",
            "",
        ),
        (
            r#""float alpha" 0.5"#,
            "alpha other than 0 on an emitting shape (AreaLightSource) is not supported",
            "AreaLightSource \"diffuse\" \"rgb L\" [ 1 1 1 ]\n",
        ),
    ];
    for (param, msg, before) in cases {
        // Line 8 is the one after WorldBegin; `before` adds one line; the parameter follows
        // the shape's P and uv lists on the shape's second line, after 4 spaces and the rest.
        let text = format!("{before}{}", screen(1.0, param));
        let path = dir.write("scene.pbrt", scene_text(8, 1, &text));
        let e = loader::load(&path).expect_err(param).to_string();
        let line = 9 + before.lines().count();
        let col = 4
            + "\"point2 uv\" [ 0 0  1 0  1 1  0 1 ] \"integer indices\" [ 0 1 2 0 2 3 ] ".len()
            + 1;
        let want = format!("{}:{line}:{col}: ", path.display());
        println!("{e}");
        assert!(
            e.starts_with(&want) && e.contains(msg),
            "{e}\nwant {want}...{msg}"
        );
    }
    // Through the binary: one line, exit code 2.
    let path = dir.write(
        "bad.pbrt",
        scene_text(8, 1, &screen(1.0, r#""texture alpha" "nope""#)),
    );
    let run = common::run_capped(
        common::render_args(&path, &dir.0, &[]),
        4 * common::GIB,
        std::time::Duration::from_secs(60),
    );
    common::assert_error(&run, &["bad.pbrt:9:", "unknown float texture \"nope\""]);
    assert!(!dir.0.join("out.exr").exists());
}

#[test]
fn memory_estimate_counts_the_alpha_masks() {
    // The screen's copy for the backend: 2 triangles x 12 bytes of indices, 4 uvs x 8 bytes.
    let dir = TempDir::new("photon-alpha");
    let with = load_world(
        &dir,
        8,
        1,
        &format!("{FLOOR}\n{}", screen(1.0, r#""float alpha" 0.5"#)),
    );
    let without = load_world(&dir, 8, 1, &format!("{FLOOR}\n{}", screen(1.0, "")));
    assert_eq!(photon::memory::alpha_mask_bytes(&with), 2 * 12 + 4 * 8);
    assert_eq!(photon::memory::alpha_mask_bytes(&without), 0);
    let settings = RenderSettings::from_scene(&with).unwrap();
    let kinds = (IntegratorKind::Direct, BackendKind::Embree);
    let e = photon::memory::estimate(&with, &settings, kinds, 1, None);
    assert!(e.parts.contains(&("alpha masks", 56)), "{:?}", e.parts);
}

#[test]
fn alpha_is_part_of_the_scene_hash() {
    // Partial images of scenes that differ only in alpha must not merge.
    let dir = TempDir::new("photon-alpha");
    let hash = |alpha: &str| {
        load_world(&dir, 8, 1, &format!("{FLOOR}\n{}", screen(1.0, alpha))).content_hash()
    };
    let (none, half, quarter) = (
        hash(""),
        hash(r#""float alpha" 0.5"#),
        hash(r#""float alpha" 0.25"#),
    );
    assert!(none != half && half != quarter && none != quarter);
    assert_eq!(hash(r#""float alpha" 1"#), none, "alpha 1 is no alpha");
}

#[test]
fn a_triangle_without_uv_uses_pbrts_default_uv() {
    // pbrt-v4 gives a triangle without "point2 uv" the vertex uvs (0, 0), (1, 0), (1, 1), so
    // the hit at barycentrics (b1, b2) has uv (b1 + b2, b2). The triangle (0,1,0) (1,1,0)
    // (0,1,1) is hit at (x, 1, z) with b1 = x, b2 = z; a checkerboard with uscale 2 is closed
    // (tex1 = 1) where floor(2 (x + z)) + floor(z) is even, i.e. where x + z < 1/2.
    let dir = TempDir::new("photon-alpha");
    let world = format!(
        "{FLOOR}\nTexture \"half\" \"float\" \"checkerboard\" \"float uscale\" [ 2 ] \
         \"float tex1\" [ 1 ] \"float tex2\" [ 0 ]\n\
         Shape \"trianglemesh\" \"point3 P\" [ 0 1 0  1 1 0  0 1 1 ] \"texture alpha\" \"half\""
    );
    let scene = load_world(&dir, 8, 1, &world);
    let mut rays = Vec::new();
    let mut closed = Vec::new();
    for i in 0..40 {
        for j in 0..40 {
            let (x, z) = ((i as f32 + 0.5) / 40.0, (j as f32 + 0.5) / 40.0);
            if x + z < 0.97 && (x + z - 0.5).abs() > 0.01 {
                rays.push(Ray::new(Vec3::new(x, 0.5, z), Vec3::Y));
                closed.push(x + z < 0.5);
            }
        }
    }
    for (kind, accel) in all_three(&scene) {
        let (occ, _) = answers(&accel, &rays);
        assert_eq!(occ, closed, "{kind}");
    }
    // The interaction sees the same uv.
    let h = both(&scene)[1].1.intersect(
        RayKind::Camera,
        &Ray::new(Vec3::new(0.2, 0.5, 0.1), Vec3::Y),
    );
    let si = photon::interaction::SurfaceInteraction::new(
        &scene,
        &h.unwrap(),
        &Ray::new(Vec3::ZERO, Vec3::Y),
    );
    assert!(
        (si.uv - photon::math::Vec2::new(0.3, 0.1))
            .abs()
            .max_element()
            < 1e-6,
        "{}",
        si.uv
    );
}
