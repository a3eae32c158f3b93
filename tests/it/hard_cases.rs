//! Hard cases for numerical stability, each checked against an expected physical answer (not
//! only "no NaN"), through real scenes: rays and photons traced by the library's own pieces.
//!
//! | case | expected answer |
//! |---|---|
//! | shadow rays at scales 1e-4, 1, 1e4 | floor radiance `rho/pi I cos / r^2` within 1%, no black pixel; a ray to a light below the floor is occluded |
//! | photons off a lone floor | no photon is ever stored a second time (nothing to bounce to) |
//! | secondary rays off a sphere | outward rays never hit it, inward rays hit another face |
//! | glass sphere | exit point and direction of Snell at both interfaces (f64 analytic) |
//! | TIR in a sphere | the ray stays inside, on the sphere, at the same angle |
//! | photons in a glass cube | trapped photons end at `max_bounces`; escaping power <= `3 (1 - c)` |
//! | eta = 1 sphere | the image equals the image without the sphere |
//! | coincident and nested faces | same image as one copy; a diameter ray is not bent |
//! | degenerate and needle triangles | never hit; the image equals the image without them |
//! | sphere light on a floor | `E = pi L a^3 / (rho^2 + a^2)^(3/2)` |
//! | zero and very bright lights | black image; 1e6 x brighter image |
//! | photons on kd-tree split planes, k > map | brute-force kNN; all photons, `E = sum / (pi r^2)` |
//!
//! Two cases found real bugs, since fixed: `spawned_origin_is_above_a_floor_in_a_coordinate_plane`
//! (a subnormal offset on planes at 0, now floored at 1e-30) and the 1e-4 glass sphere (an
//! absolute offset floor, now error bounds); `total_internal_reflection_along_shared_edges`
//! asserts Embree's robust mode and measures the fast modes' leak.
//!
//! Every rendered image has its NaN/Inf pixels counted, printed and asserted zero. Each case
//! prints one `summary |` line with its measured answer (also appended to
//! `$CARGO_TARGET_TMPDIR/hard_cases/summary.txt`): run with
//! `cargo test --release --test it hard_cases:: -- --nocapture | grep '^summary'`.
use crate::support as common;

use common::{relmse, Rng, CUBE};
use photon::accel::{Accel, AccelOptions, BackendKind, Hit};
use photon::bsdf::{BsdfSample, TransportMode};
use photon::camera::Camera;
use photon::imageio::RgbImage;
use photon::integrator::{IntegratorKind, RenderOutput};
use photon::interaction::SurfaceInteraction;
use photon::light::Receiver;
use photon::math::{spawn_origin, Ray, Vec2, Vec3};
use photon::photon::estimate::{irradiance_with, EstimateParams};
use photon::photon::trace::{self, TraceSettings};
use photon::photon::{Kernel, KnnResult, Photon, PhotonMap};
use photon::sampling::Pattern;
use photon::scene::{loader, Scene};
use std::f32::consts::PI;
use std::io::Write;
use std::sync::{Mutex, OnceLock};

// ---------------------------------------------------------------------------------------------
// Helpers

/// Writes `text` as `name.pbrt` under the test tmp dir and loads it.
fn scene(name: &str, text: &str) -> Scene {
    let path = common::write_scene("hard_cases", name, text);
    loader::load(&path).unwrap_or_else(|e| panic!("{name}: {e}"))
}

fn accel(scene: &Scene) -> Accel {
    Accel::build(scene, BackendKind::Embree, AccelOptions::default()).unwrap()
}

/// Renders `scene` as its file says (resolution, spp, integrator parameters) with `kind`.
fn render(scene: &Scene, kind: IntegratorKind) -> RenderOutput {
    common::render_scene(scene, kind, |_| {})
}

/// Renders and asserts that no pixel is NaN or infinite (count printed).
fn render_finite(name: &str, scene: &Scene, kind: IntegratorKind) -> RgbImage {
    let out = render(scene, kind);
    assert_eq!(nonfinite(name, &out.image), 0, "{name}: NaN/Inf pixels");
    out.image
}

/// Number of pixels with a NaN or infinite channel, printed with the image's name.
fn nonfinite(name: &str, img: &RgbImage) -> usize {
    let n = img.count_nonfinite();
    println!("{name}: {n} NaN/Inf pixels of {}", img.pixels.len());
    n
}

/// Prints one summary line and appends it to `summary.txt` (truncated once per run).
fn summary(line: String) {
    static FILE: OnceLock<Mutex<std::fs::File>> = OnceLock::new();
    let file = FILE.get_or_init(|| {
        Mutex::new(
            std::fs::File::create(common::target_dir("hard_cases").join("summary.txt")).unwrap(),
        )
    });
    println!("summary | {line}");
    let _ = writeln!(file.lock().unwrap(), "{line}");
}

/// One scattering event done as the integrators do it: closest hit, the hit point
/// interpolated from the triangle's vertices,
/// a BSDF sample in the shading frame (lobe chosen by `uc`), and the next ray leaving from the
/// hit point moved past its error bound (`spawn_origin`) to the side the new direction goes.
struct Step {
    hit: Hit,
    p: Vec3,
    sample: BsdfSample,
    next: Ray,
}

fn step(scene: &Scene, accel: &Accel, ray: &Ray, uc: f32) -> Option<Step> {
    let hit = accel.backend().intersect(ray)?;
    let mut si = SurfaceInteraction::new(scene, &hit, ray);
    let sample = si
        .bsdf(
            scene,
            photon::camera::Footprint::of_file(scene),
            photon::spectrum::Lambda::Rgb,
        )
        .sample(si.wo, uc, Vec2::splat(0.5), TransportMode::Radiance)?;
    Some(Step {
        hit,
        p: si.p,
        sample,
        next: si.spawn_ray(si.frame.to_world(sample.wi)),
    })
}

const RHO: f32 = 0.5;

// ---------------------------------------------------------------------------------------------
// Self-intersection at extreme scales

/// A floor quad at height `y0` (half size 5 s), a point light at `(0.4, y0 + 1.2 s, -0.3)`
/// (times `s`) with intensity `s^2` (so the irradiance does not depend on `s`), both rotated
/// by `tilt` degrees about the axis (1, 0, 0.5) through the origin, seen from `3 s` above.
fn scaled_floor(s: f32, y0: f32, tilt: f32, res: u32, integrator: &str) -> String {
    let h = 5.0 * s;
    let cam = y0 + 3.0 * s;
    let (lx, ly, lz) = (0.4 * s, y0 + 1.2 * s, -0.3 * s);
    let i = s * s;
    format!(
        r#"LookAt 0 {cam} 0  0 {y0} 0  0 0 1
Camera "perspective" "float fov" [ 70 ]
Film "rgb" "integer xresolution" [ {res} ] "integer yresolution" [ {res} ]
PixelFilter "box" "float xradius" [ 0.0001 ] "float yradius" [ 0.0001 ]
Sampler "independent" "integer pixelsamples" [ 1 ]
{integrator}
WorldBegin
Rotate {tilt} 1 0 0.5
Material "diffuse" "rgb reflectance" [ {RHO} {RHO} {RHO} ]
Shape "trianglemesh" "point3 P" [ -{h} {y0} -{h}  {h} {y0} -{h}  {h} {y0} {h}  -{h} {y0} {h} ] "integer indices" [ 0 1 2 0 2 3 ]
LightSource "point" "rgb I" [ {i} {i} {i} ] "point3 from" [ {lx} {ly} {lz} ]
"#
    )
}

/// The floor scenes of [`scaled_floor`] (scale, floor height, tilt): 1e-4, 1 and 1e4 with the
/// floor in the plane y = 0 (where Wächter-Binder offsets y by a fixed 1/65536), off it, and
/// tilted through the origin. (Before hit points were interpolated from the vertices instead
/// of `o + t d`, scale 1e4 at y = 0 had half its pixels black: `o + t d` is off by ~ulp(3e4)
/// = 2e-3 in y there.)
fn floor_cases() -> Vec<(f32, f32, f32)> {
    [1e-4f32, 1.0, 1e4]
        .into_iter()
        .flat_map(|s| [(s, 0.0, 0.0), (s, 0.37 * s, 0.0), (s, 0.0, 25.0)])
        .collect()
}

/// The hit point as the integrators compute it, interpolated from the triangle's vertices,
/// and its rounding-error bound.
fn hit_point(scene: &Scene, hit: &Hit) -> (Vec3, Vec3) {
    let mesh = &scene.meshes[hit.mesh as usize];
    (
        mesh.point(hit.prim, hit.u, hit.v),
        mesh.point_error(hit.prim, hit.u, hit.v),
    )
}

/// The origin of a ray leaving `hit` towards the side of `n`, as the integrators spawn it.
fn spawn(scene: &Scene, hit: &Hit, n: Vec3) -> Vec3 {
    let (p, err) = hit_point(scene, hit);
    spawn_origin(p, err, n)
}

/// One floor scene of [`scaled_floor`] under the direct integrator: every pixel's radiance is
/// `rho / pi * I cos / r^2` (1%), none is black (shadow acne), and at points where camera
/// rays hit the floor a shadow ray from the offset origin towards the light above is
/// unoccluded and one towards the mirror light below is occluded (by the floor). Returns the
/// failure, if any.
fn floor_case((s, y0, tilt): (f32, f32, f32), check_down: bool) -> Result<(), String> {
    const RES: u32 = 32;
    let sc = scene(
        &format!("scale_{s:e}_{y0:e}_{tilt}"),
        &scaled_floor(
            s,
            y0,
            tilt,
            RES,
            r#"Integrator "path" "integer maxdepth" [ 1 ]"#,
        ),
    );
    let out = render(&sc, IntegratorKind::Direct);
    let name = format!("floor scale {s:e}, y = {y0:e}, tilt {tilt}");
    let bad = nonfinite(&name, &out.image);
    let cam = Camera::new(&sc.camera, RES, RES);
    let photon::scene::Light::Point(photon::light::PointLight { pos: light, .. }) = sc.lights[0]
    else {
        unreachable!()
    };
    // The floor plane (world space, after the rotation), normal towards the camera.
    let floor = &sc.meshes[0];
    let p_floor = floor.positions[0].as_dvec3();
    let mut n = floor.geometric_normal(0, 0.3, 0.3).as_dvec3();
    if n.dot(cam.position().as_dvec3() - p_floor) < 0.0 {
        n = -n;
    }
    let below = light - (2.0 * n.dot(light.as_dvec3() - p_floor) * n).as_vec3();
    let acc = accel(&sc);
    let (mut worst, mut black, mut blocked_up, mut open_down) = (0.0f64, 0, 0, 0);
    let (mut sum_got, mut sum_want) = (0.0f64, 0.0f64);
    for y in 0..RES {
        for x in 0..RES {
            let r = cam.generate_ray(Vec2::new(x as f32 + 0.5, y as f32 + 0.5));
            // Analytic floor point and radiance (f64).
            let (o, d) = (r.o.as_dvec3(), r.d.as_dvec3());
            let pa = o + d * (n.dot(p_floor - o) / n.dot(d));
            let to = light.as_dvec3() - pa;
            let want = (RHO / PI) as f64 * (s * s) as f64 * n.dot(to) / to.length().powi(3);
            let got = out.image.pixels[(y * RES + x) as usize][0] as f64;
            black += usize::from(got == 0.0);
            worst = worst.max(((got - want) / want).abs());
            (sum_got, sum_want) = (sum_got + got, sum_want + want);
            // The integrators' hit point and offset, towards lights above and below.
            let hit = acc
                .backend()
                .intersect(&r)
                .expect("camera ray hits the floor");
            let o = spawn(&sc, &hit, n.as_vec3());
            blocked_up += usize::from(acc.backend().occluded(&Ray::segment(o, light - o, 1.0)));
            open_down += usize::from(!acc.backend().occluded(&Ray::segment(o, below - o, 1.0)));
        }
    }
    summary(format!(
        "{name}: radiance worst rel. error {worst:.2e} (expected < 1e-2), mean ratio {:.5} (expected 1), black pixels {black}/{}, up-shadow blocked {blocked_up}, down-shadow open {open_down}{} (expected 0, 0, 0), NaN {bad}",
        sum_got / sum_want,
        RES * RES,
        if check_down { "" } else { " (not checked here)" }
    ));
    if !check_down {
        open_down = 0;
    }
    if worst > 0.01 || black > 0 || blocked_up > 0 || open_down > 0 || bad > 0 {
        return Err(format!("{name}: worst {worst:.3}, black {black}, blocked {blocked_up}, open {open_down}, NaN {bad}"));
    }
    Ok(())
}

/// Direct-lit floors at scales 1e-4, 1 and 1e4, through the origin plane (where
/// Wächter-Binder falls back to a fixed epsilon) and off it: see [`floor_case`].
#[test]
fn shadow_rays_at_extreme_scales() {
    let failures: Vec<String> = floor_cases()
        .into_iter()
        .filter_map(|c| floor_case(c, !on_zero_plane(c)).err())
        .collect();
    assert!(failures.is_empty(), "{failures:#?}");
}

/// Floors lying exactly in the plane y = 0 (untilted).
fn on_zero_plane((_, y0, tilt): (f32, f32, f32)) -> bool {
    y0 == 0.0 && tilt == 0.0
}

/// On a floor lying exactly in y = 0 the point's error bound is 0 in y; `spawn_origin` must
/// still move it to a normal float above the plane (a subnormal is flushed to 0 by Embree),
/// so a ray from it through the floor (towards a light below) is occluded, at every scale.
/// (Before the 1e-30 floor in `spawn_origin`: 1024 of 1024 rays unoccluded.)
#[test]
fn spawned_origin_is_above_a_floor_in_a_coordinate_plane() {
    let failures: Vec<String> = floor_cases()
        .into_iter()
        .filter(|&c| on_zero_plane(c))
        .filter_map(|c| floor_case(c, true).err())
        .collect();
    assert!(failures.is_empty(), "{failures:#?}");
}

/// A photon reflected off a lone floor has nothing to hit: every stored photon is a direct
/// one. A reflected photon that re-hits the floor (origin pushed through it) would be stored
/// again as indirect. Likewise the photon mapper's indirect component must be exactly zero.
fn lone_floor_case((s, y0, tilt): (f32, f32, f32)) -> Result<(), String> {
    let sc = scene(
        &format!("lone_floor_{s:e}_{y0:e}_{tilt}"),
        &scaled_floor(
            s,
            y0,
            tilt,
            16,
            r#"Integrator "photonmap" "integer globalphotons" [ 20000 ] "integer gathersamples" [ 1 ]"#,
        ),
    );
    let acc = accel(&sc);
    let lights = sc.emitters();
    let settings = TraceSettings {
        global_photons: 20_000,
        caustic_photons: 0,
        max_bounces: 8,
        projection_maps: false,
        projection_resolution: 32,
        seed: 3,
        pattern: Pattern::Stratified,
        receiver_alpha: photon::photon::trace::RECEIVER_ALPHA,
        footprint: None,
        aimed: true,
        store_surfaceless_direct: true,
    };
    let maps = trace::trace(&sc, &acc, &lights, &settings);
    let global = maps.global.expect("photons on the floor");
    let indirect = global
        .photons()
        .iter()
        .filter(|p| !p.has(Photon::DIRECT))
        .count();
    let out = render(&sc, IntegratorKind::Photonmap);
    let bad = nonfinite(&format!("lone floor scale {s:e}"), &out.image);
    let ind = &out.components.iter().find(|c| c.0 == "indirect").unwrap().1;
    let ind_max = ind.pixels.iter().flatten().fold(0.0f32, |a, &b| a.max(b));
    summary(format!(
        "lone floor scale {s:e}, y = {y0:e}, tilt {tilt}: {indirect} of {} stored photons indirect, max indirect radiance {ind_max:e} (expected 0, 0), NaN {bad}",
        global.len()
    ));
    if indirect > 0 || ind_max > 0.0 || bad > 0 {
        return Err(format!(
            "scale {s:e} y0 {y0:e}: {indirect} indirect photons, indirect radiance {ind_max}, NaN {bad}"
        ));
    }
    Ok(())
}

/// Photons and gather rays leave a lone floor at scales 1e-4, 1, 1e4: see [`lone_floor_case`].
#[test]
fn photons_leave_a_lone_floor_at_extreme_scales() {
    let failures: Vec<String> = floor_cases()
        .into_iter()
        .filter_map(|c| lone_floor_case(c).err())
        .collect();
    assert!(failures.is_empty(), "{failures:#?}");
}

/// A tessellated sphere of radius `r` at `c`, made of `material`.
fn sphere_scene(name: &str, c: Vec3, r: f32, material: &str) -> Scene {
    scene(
        name,
        &format!(
            "Camera \"perspective\"\nWorldBegin\n{material}\nTranslate {} {} {}\nShape \"sphere\" \"float radius\" [ {r} ]\n",
            c.x, c.y, c.z
        ),
    )
}

/// Rays leaving a (convex, tessellated) sphere from the hit points of rays shot at it: into
/// the outer half-space of the hit face they never hit the sphere again; into the inner one
/// they hit a different face. At three scales, centred at the origin and off it.
#[test]
fn secondary_rays_leave_a_sphere() {
    let mut failures = Vec::new();
    for s in [1e-4f32, 1.0, 1e4] {
        for c in [Vec3::ZERO, Vec3::new(3.0, 2.0, 1.5) * s] {
            let sc = sphere_scene(
                "sphere",
                c,
                s,
                r#"Material "diffuse" "rgb reflectance" [ 0.5 0.5 0.5 ]"#,
            );
            let acc = accel(&sc);
            let mut rng = Rng(0x9e37_79b9 + s.to_bits() as u64);
            let (mut n, mut rehit, mut missed_in, mut same_face) = (0, 0, 0, 0);
            for _ in 0..4000 {
                let from = c + rng.dir() * (4.0 * s);
                let to = c + rng.dir() * (0.9 * s);
                let ray = Ray::new(from, (to - from).normalize());
                let Some(hit) = acc.backend().intersect(&ray) else {
                    continue;
                };
                n += 1;
                let ng = hit.ng;
                // Outward: a direction in the face's outer half-space.
                let mut w = rng.dir();
                if w.dot(ng) < 0.0 {
                    w = -w;
                }
                let out = Ray::new(spawn(&sc, &hit, ng), w);
                rehit += usize::from(acc.backend().intersect(&out).is_some());
                let inw = Ray::new(spawn(&sc, &hit, -ng), -w);
                match acc.backend().intersect(&inw) {
                    None => missed_in += 1,
                    Some(h) => same_face += usize::from(h.prim == hit.prim),
                }
            }
            summary(format!(
                "sphere scale {s:e} at {c}: {n} hits; outward rays re-hitting {rehit}, inward rays missing {missed_in}, inward rays hitting their own face {same_face} (expected 0, 0, 0)"
            ));
            if rehit + missed_in + same_face > 0 || n < 1000 {
                failures.push(format!(
                    "scale {s:e} c {c}: rehit {rehit}, missed {missed_in}, same face {same_face}"
                ));
            }
        }
    }
    assert!(failures.is_empty(), "{failures:#?}");
}

// ---------------------------------------------------------------------------------------------
// Dielectrics: Snell, TIR, trapped photons, eta = 1

/// Refracts unit `d` at unit normal `n` (facing `d`'s origin side) from index `n1` into `n2`
/// (f64, textbook form). `None` for total internal reflection.
fn refract64(d: [f64; 3], n: [f64; 3], n1: f64, n2: f64) -> Option<[f64; 3]> {
    let cos_i = -(d[0] * n[0] + d[1] * n[1] + d[2] * n[2]);
    let eta = n1 / n2;
    let k = 1.0 - eta * eta * (1.0 - cos_i * cos_i);
    if k < 0.0 {
        return None;
    }
    let a = eta * cos_i - k.sqrt();
    Some(std::array::from_fn(|i| eta * d[i] + a * n[i]))
}

/// Far intersection of the line `o + t d` (unit `d`) with the sphere `(c, r)`, all f64:
/// `(entry, exit)` distances, or `None` when it misses.
fn sphere_hits64(o: [f64; 3], d: [f64; 3], c: [f64; 3], r: f64) -> Option<(f64, f64)> {
    let oc: [f64; 3] = std::array::from_fn(|i| o[i] - c[i]);
    let b = oc[0] * d[0] + oc[1] * d[1] + oc[2] * d[2];
    let q = oc[0] * oc[0] + oc[1] * oc[1] + oc[2] * oc[2] - r * r;
    let disc = b * b - q;
    (disc >= 0.0).then(|| (-b - disc.sqrt(), -b + disc.sqrt()))
}

/// The analytic path through a glass sphere: (entry point, exit point, exit direction).
fn snell_through_sphere(o: Vec3, d: Vec3, c: Vec3, r: f32, eta: f64) -> [[f64; 3]; 3] {
    let (o, d, c, r) = (
        o.as_dvec3().to_array(),
        d.as_dvec3().normalize().to_array(),
        c.as_dvec3().to_array(),
        r as f64,
    );
    let at =
        |o: [f64; 3], d: [f64; 3], t: f64| -> [f64; 3] { std::array::from_fn(|i| o[i] + t * d[i]) };
    let normal = |p: [f64; 3]| -> [f64; 3] { std::array::from_fn(|i| (p[i] - c[i]) / r) };
    let (t0, _) = sphere_hits64(o, d, c, r).expect("ray hits the sphere");
    let p0 = at(o, d, t0);
    let d1 = refract64(d, normal(p0), 1.0, eta).expect("entering refracts");
    let (_, t1) = sphere_hits64(p0, d1, c, r).unwrap();
    let p1 = at(p0, d1, t1);
    let n1 = normal(p1).map(|x| -x);
    let d2 = refract64(d1, n1, eta, 1.0).expect("no TIR on the way out of a sphere");
    [p0, p1, d2]
}

fn dist64(a: [f64; 3], b: Vec3) -> f64 {
    (glam::DVec3::from_array(a) - b.as_dvec3()).length()
}

/// Rays through a glass sphere (eta 1.5, radius `s`, centre `c`), refraction chosen at both
/// interfaces: they enter and exit at the analytic Snell points (f64) with the analytic
/// direction, from normal incidence (no bend) to grazing (impact parameter 0.999 R). A ray's
/// mirror lobe at entry and the exit ray leave for good. The tessellation (16128 flat faces)
/// limits the agreement: measured at scale 1 and 1e4, 1.8e-3 R and 1.9e-3 rad up to
/// b = 0.95 R, 1.6e-2 R and 2.1e-2 rad at grazing b = 0.999 R (ill-conditioned there).
fn glass_case(s: f32, c: Vec3, tol: [f64; 4]) -> Result<(), String> {
    let sc = sphere_scene(
        "glass",
        c,
        s,
        r#"Material "dielectric" "float eta" [ 1.5 ]"#,
    );
    let acc = accel(&sc);
    let mut worst = [(0.0f64, 0.0f64); 2]; // (point, direction): b <= 0.95, b = 0.999
    let mut errors = Vec::new();
    for b in [0.0f32, 0.3, 0.7, 0.95, 0.999] {
        for phi in [0.1f32, 1.3, 2.9, 4.4] {
            let off = Vec3::new(phi.cos(), phi.sin(), 0.0) * (b * s);
            let o = c + off + Vec3::new(0.0, 0.0, -5.0 * s);
            let ray = Ray::new(o, Vec3::Z);
            let want = snell_through_sphere(o, Vec3::Z, c, s, 1.5);
            // uc just below 1 picks refraction whenever T > 0.
            let Some(a) = step(&sc, &acc, &ray, 0.999_999) else {
                errors.push(format!("b {b}: missed the sphere"));
                continue;
            };
            let Some(e) = step(&sc, &acc, &a.next, 0.999_999) else {
                errors.push(format!("b {b}: no exit"));
                continue;
            };
            if !a.sample.transmission || !e.sample.transmission || e.hit.prim == a.hit.prim {
                errors.push(format!(
                    "b {b}: not refracted in and out of different faces"
                ));
            }
            if accel_hits(&acc, &e.next)
                || step(&sc, &acc, &ray, 0.0)
                    .is_some_and(|m| !m.sample.transmission && accel_hits(&acc, &m.next))
            {
                errors.push(format!("b {b}: a leaving ray re-hits the sphere"));
            }
            let dp = dist64(want[0], a.p).max(dist64(want[1], e.p)) / s as f64;
            let dd = dist64(want[2], e.next.d.normalize());
            let w = &mut worst[usize::from(b > 0.95)];
            *w = (w.0.max(dp), w.1.max(dd));
        }
    }
    summary(format!(
        "glass sphere radius {s:e} at {c}: worst entry/exit point error {:.2e} R, exit direction error {:.2e} rad for b <= 0.95 R (expected < 2.5e-3, 2.5e-3); {:.2e} R, {:.2e} rad at b = 0.999 R (expected < 2.5e-2, 3e-2)",
        worst[0].0, worst[0].1, worst[1].0, worst[1].1
    ));
    if worst[0].0 > tol[0] || worst[0].1 > tol[1] || worst[1].0 > tol[2] || worst[1].1 > tol[3] {
        errors.push(format!("radius {s:e} at {c}: errors {worst:?}"));
    }
    if errors.is_empty() {
        Ok(())
    } else {
        Err(errors.join("; "))
    }
}

fn accel_hits(acc: &Accel, ray: &Ray) -> bool {
    acc.backend().intersect(ray).is_some()
}

/// Glass spheres of radius 1 and 1e4 refract at the analytic points: see [`glass_case`].
#[test]
fn glass_sphere_refracts_at_the_analytic_points() {
    let failures: Vec<String> = [1.0f32, 1e4]
        .into_iter()
        .flat_map(|s| {
            [
                (s, Vec3::new(0.5, -0.2, 0.3) * s),
                (s, Vec3::new(3.0, 2.0, 1.5) * s),
            ]
        })
        .filter_map(|(s, c)| glass_case(s, c, TESSELLATION_TOL).err())
        .collect();
    assert!(failures.is_empty(), "{failures:#?}");
}

/// Tolerances of [`glass_case`] set by the tessellation: point and direction errors for
/// b <= 0.95 R, then at b = 0.999 R.
const TESSELLATION_TOL: [f64; 4] = [2.5e-3, 2.5e-3, 2.5e-2, 3e-2];

/// A glass sphere of radius 1e-4 near the origin refracts like a large one (the spawned
/// origin moves by its error bound, ~1e-11 here). At (1, 1, 1) its vertices are only known to
/// ulp(1) = 1.2e-7 = 0.12% of R, and the offset is a few times that: measured 2.3e-2 R and
/// 5.2e-2 rad (b <= 0.95), 3.4e-2 R and 0.15 rad at grazing; the tolerances there (5e-2 R,
/// 0.1 rad; 0.1 R, 0.3 rad) still catch an offset that ignores the object's size
/// (Wächter-Binder's 256 ulps gave 0.26 R and 0.51 rad).
#[test]
fn small_glass_sphere_refracts_at_the_analytic_points() {
    let s = 1e-4f32;
    let failures: Vec<String> = [
        (Vec3::new(0.5, -0.2, 0.3) * s, TESSELLATION_TOL),
        (Vec3::ONE, [5e-2, 0.1, 0.1, 0.3]),
    ]
    .into_iter()
    .filter_map(|(c, tol)| glass_case(s, c, tol).err())
    .collect();
    assert!(failures.is_empty(), "{failures:#?}");
}

/// Follows a ray inside a glass sphere `(c, r)` that meets the surface at angle `theta` from
/// the normal, in the plane `z = c.z + plane_z`, for 40 bounces with lobe sample `uc`.
/// Returns the worst `||p - c| - r| / r` and worst `|cos - cos theta|`, or why it escaped.
fn tir_run(
    sc: &Scene,
    acc: &Accel,
    (c, r): (Vec3, f32),
    theta: f32,
    plane_z: f32,
    uc: f32,
) -> Result<(f32, f32), String> {
    // A chord at distance r sin(theta) from the centre meets the sphere at angle theta; in
    // the plane z = c.z + plane_z the circle has radius rc and the chord distance must be
    // rc sin(theta) there.
    let rc = (r * r - plane_z * plane_z).sqrt();
    let p0 = c + Vec3::new(0.0, -rc * theta.sin(), plane_z);
    let mut ray = Ray::new(p0, Vec3::X);
    // Angle with the 3D normal: cos = (rc / r) cos(theta) for a ray in that plane.
    let want_cos = rc / r * theta.cos();
    let (mut worst_r, mut worst_cos) = (0.0f32, 0.0f32);
    for bounce in 0..40 {
        let Some(st) = step(sc, acc, &ray, uc) else {
            return Err(format!(
                "escaped (no hit) at bounce {bounce} from {:?} along {:?}",
                ray.o, ray.d
            ));
        };
        if st.sample.transmission {
            return Err(format!("refracted out at bounce {bounce}"));
        }
        let rn = (st.p - c).length();
        worst_r = worst_r.max((rn - r).abs() / r);
        let cos = ray.d.normalize().dot((st.p - c) / rn);
        worst_cos = worst_cos.max((cos - want_cos).abs());
        ray = st.next;
    }
    Ok((worst_r, worst_cos))
}

/// Runs [`tir_run`] for TIR angles (critical + 0.05 rad, 60 and 80 degrees with refraction
/// preferred; exactly critical with lobe sample 0.5, where R = 1 too) on `backends`, in the
/// plane `z = c.z + plane_z`. Returns the failures.
fn tir_cases(backends: &[(&str, BackendKind, bool)], plane_z: f32) -> Vec<String> {
    let eta = 1.5f32;
    let crit = (1.0 / eta).asin();
    let sphere = (Vec3::new(0.2, 0.1, -0.3), 1.0f32);
    let sc = sphere_scene(
        "tir",
        sphere.0,
        sphere.1,
        r#"Material "dielectric" "float eta" [ 1.5 ]"#,
    );
    let mut lines = Vec::new();
    let mut failures = Vec::new();
    for &(label, kind, robust) in backends {
        let acc = Accel::build(&sc, kind, AccelOptions { robust }).unwrap();
        for (name, theta, uc) in [
            ("critical + 0.05 rad", crit + 0.05, 0.999_999f32),
            ("60 deg", 60f32.to_radians(), 0.999_999),
            ("80 deg", 80f32.to_radians(), 0.999_999),
            ("critical", crit, 0.5),
        ] {
            match tir_run(&sc, &acc, sphere, theta, plane_z, uc) {
                Ok((wr, wc)) => {
                    lines.push(format!(
                        "{label} {name}: ||p-c|-R| <= {wr:.1e} R, |dcos| <= {wc:.1e}"
                    ));
                    if wr > 1e-3 || wc > 0.01 {
                        failures.push(format!("{label} {name}: {wr} {wc}"));
                    }
                }
                Err(e) => {
                    lines.push(format!("{label} {name}: {e}"));
                    failures.push(format!("{label} {name}: {e}"));
                }
            }
        }
    }
    summary(format!(
        "TIR in a glass sphere, 40 bounces, chord plane z = c.z + {plane_z}: {}",
        lines.join("; ")
    ));
    failures
}

const ALL_BACKENDS: [(&str, BackendKind, bool); 3] = [
    ("embree", BackendKind::Embree, false),
    ("embree robust", BackendKind::Embree, true),
    ("obvhs", BackendKind::Obvhs, false),
];

/// A ray inside a glass sphere meeting the surface at the critical angle or beyond is totally
/// reflected at every bounce: it stays on the sphere (|p - c| = R, 6e-4 R tessellation) at
/// the same angle for 40 bounces, never escaping, on both backends.
#[test]
fn total_internal_reflection_in_a_sphere() {
    let failures = tir_cases(&ALL_BACKENDS, 0.123);
    assert!(failures.is_empty(), "{failures:#?}");
}

/// The same in the sphere's equatorial plane, where the ray runs exactly along the ring of
/// edges shared by two rows of triangles. Embree's robust mode keeps it inside, and that is
/// asserted. Embree's default mode and obvhs (neither watertight: a Woop et al. 2013 triangle
/// test alone did not stop it, the box tests are not conservative to the last ulp either, and
/// it self-hit near t = 0 without pbrt's t error bound) let it slip out after a few bounces:
/// measured and printed here as a known limitation of the fast modes, so scenes
/// where such rays matter should render with `--robust`. (Rays exactly along a shared edge are
/// rare in renders.)
#[test]
fn total_internal_reflection_along_shared_edges() {
    let robust = [("embree robust", BackendKind::Embree, true)];
    let failures = tir_cases(&robust, 0.0);
    assert!(failures.is_empty(), "{failures:#?}");
    let fast = [ALL_BACKENDS[0], ALL_BACKENDS[2]];
    let leaks = tir_cases(&fast, 0.0);
    summary(format!("TIR along shared edges, fast modes (known limitation, not asserted): {} of 8 runs escape: {leaks:?}", leaks.len()));
}

/// A point light at the centre of a glass cube (eta 1.5) inside a black diffuse box. A photon
/// whose direction has every |d_i| < c = sqrt(1 - 1/eta^2) is totally reflected at every face
/// forever (reflections only flip signs); with an isotropic light that happens with
/// probability 1 - 3 (1 - c) = 0.236 (no two |d_i| can exceed c together). The trace must
/// still return, those photons using exactly `max_bounces` rays; the power reaching the black
/// box is at most the escapable 3 (1 - c) = 0.764 of the emitted power.
#[test]
fn photons_trapped_in_a_glass_cube_terminate() {
    let sc = scene(
        "glass_cube",
        &format!(
            r#"Camera "perspective"
WorldBegin
AttributeBegin
  Material "diffuse" "rgb reflectance" [ 0 0 0 ]
  Scale 4 4 4
  {CUBE}
AttributeEnd
Material "dielectric" "float eta" [ 1.5 ]
{CUBE}
LightSource "point" "rgb I" [ 1 1 1 ] "point3 from" [ 0.01 0.02 0.03 ]
"#
        ),
    );
    let acc = accel(&sc);
    let lights = sc.emitters();
    let max_bounces = 200u32;
    let n = 20_000u64;
    let settings = TraceSettings {
        global_photons: n,
        caustic_photons: 0,
        max_bounces,
        projection_maps: false,
        projection_resolution: 32,
        seed: 11,
        pattern: Pattern::Stratified,
        receiver_alpha: photon::photon::trace::RECEIVER_ALPHA,
        footprint: None,
        aimed: true,
        store_surfaceless_direct: true,
    };
    let t = std::time::Instant::now();
    let maps = trace::trace(&sc, &acc, &lights, &settings);
    let secs = t.elapsed().as_secs_f64();
    let escaped: f64 = maps.global.as_ref().map_or(0.0, |g| {
        g.photons().iter().map(|p| p.power().x as f64).sum()
    });
    let fraction = escaped / (4.0 * std::f64::consts::PI);
    let c = (1.0 - 1.0 / 2.25f64).sqrt();
    let escapable = 3.0 * (1.0 - c);
    let rays_per_photon = maps.stats.rays as f64 / n as f64;
    // Each photon's power is 4 pi / n; binomial noise of the escaped fraction.
    let sigma = (escapable * (1.0 - escapable) / n as f64).sqrt();
    summary(format!(
        "glass cube, {n} photons, max_bounces {max_bounces}: trace {secs:.2} s, escaped power fraction {fraction:.4} (expected <= {escapable:.4}), rays/photon {rays_per_photon:.1} (trapped fraction {:.4} x {max_bounces} = {:.1} at least)",
        1.0 - escapable,
        (1.0 - escapable) * max_bounces as f64
    ));
    assert!(maps.stats.rays <= n * max_bounces as u64);
    assert!(
        rays_per_photon >= (1.0 - escapable - 4.0 * sigma) * max_bounces as f64,
        "trapped photons did not bounce to the limit: {rays_per_photon}"
    );
    assert!(
        fraction <= escapable + 4.0 * sigma,
        "{fraction} > {escapable}"
    );
    assert!(
        fraction > escapable - 0.03,
        "{fraction} far below {escapable}"
    );
    assert!(secs < 20.0, "trace took {secs} s");
}

/// A wall lit by a point light, seen past a sphere: `sphere` is the sphere's material (or
/// nothing). The sphere does not lie between the wall and the light.
fn wall_scene(name: &str, sphere: &str, integrator: &str) -> Scene {
    scene(
        name,
        &format!(
            r#"LookAt 0 0 4  0 0 0  0 1 0
Camera "perspective" "float fov" [ 40 ]
Film "rgb" "integer xresolution" [ 32 ] "integer yresolution" [ 32 ]
PixelFilter "box" "float xradius" [ 0.5 ] "float yradius" [ 0.5 ]
Sampler "independent" "integer pixelsamples" [ 4 ]
{integrator}
WorldBegin
Material "diffuse" "rgb reflectance" [ 0.7 0.5 0.3 ]
Shape "trianglemesh" "point3 P" [ -3 -3 0  3 -3 0  3 3 0  -3 3 0 ] "integer indices" [ 0 1 2 0 2 3 ]
LightSource "point" "rgb I" [ 2 2 2 ] "point3 from" [ 0.4 0.6 1.0 ]
{sphere}
"#
        ),
    )
}

/// An eta = 1 "glass" sphere is no interface: the image through it equals the image without
/// it (direct integrator; and the photon mapper, which also traces it as a caustic object).
#[test]
fn eta_one_sphere_is_invisible() {
    let sphere = |eta: f32| {
        format!(
            "AttributeBegin\nMaterial \"dielectric\" \"float eta\" [ {eta} ]\nTranslate 0.1 0 2.2\nShape \"sphere\" \"float radius\" [ 0.5 ]\nAttributeEnd"
        )
    };
    let direct = r#"Integrator "path" "integer maxdepth" [ 5 ]"#;
    let pm = r#"Integrator "photonmap" "integer maxdepth" [ 5 ] "integer globalphotons" [ 20000 ] "integer causticphotons" [ 20000 ]"#;
    let mut line = Vec::new();
    for (integ, kind, tol) in [
        (direct, IntegratorKind::Direct, 1e-8),
        (pm, IntegratorKind::Photonmap, 1e-3),
    ] {
        let without = render_finite("wall", &wall_scene("wall", "", integ), kind);
        let with = render_finite(
            "wall + eta 1 sphere",
            &wall_scene("wall_eta1", &sphere(1.0), integ),
            kind,
        );
        let glass = render_finite(
            "wall + eta 1.5 sphere",
            &wall_scene("wall_eta15", &sphere(1.5), integ),
            kind,
        );
        let (e1, e15) = (relmse(&with, &without), relmse(&glass, &without));
        line.push(format!(
            "{kind:?}: relMSE eta=1 vs none {e1:.2e} (expected ~0, < {tol:e}), eta=1.5 vs none {e15:.2e} (a visible sphere)"
        ));
        assert!(e1 < tol, "{kind:?}: eta 1 sphere visible: {e1}");
        assert!(
            e15 > 100.0 * e1.max(1e-9),
            "{kind:?}: glass sphere not visible"
        );
    }
    summary(format!("eta = 1 sphere: {}", line.join("; ")));
}

// ---------------------------------------------------------------------------------------------
// Coincident, nested, degenerate geometry; lights touching geometry; light power extremes

/// Two identical copies of a surface render like one: a floor quad given twice, a glass sphere
/// given twice. Nested glass spheres (R = 1 inside R = 2) do not bend a ray along a diameter:
/// it crosses the four interfaces at -2, -1, 1, 2 and leaves along its direction.
#[test]
fn coincident_and_nested_faces() {
    let floor = "Shape \"trianglemesh\" \"point3 P\" [ -3 -3 0  3 -3 0  3 3 0  -3 3 0 ] \"integer indices\" [ 0 1 2 0 2 3 ]";
    let glass = "AttributeBegin\nMaterial \"dielectric\" \"float eta\" [ 1.5 ]\nTranslate 0.1 0 2.2\nShape \"sphere\" \"float radius\" [ 0.5 ]\nAttributeEnd";
    let direct = r#"Integrator "path" "integer maxdepth" [ 8 ]"#;
    let pm = r#"Integrator "photonmap" "integer maxdepth" [ 8 ] "integer globalphotons" [ 20000 ] "integer causticphotons" [ 20000 ]"#;
    let one = render_finite(
        "one sphere",
        &wall_scene("one", glass, direct),
        IntegratorKind::Direct,
    );
    let two = render_finite(
        "coincident spheres + floors",
        &wall_scene("two", &format!("{glass}\n{glass}\n{floor}"), direct),
        IntegratorKind::Direct,
    );
    let e_direct = relmse(&two, &one);
    let one_pm = render_finite(
        "one sphere (photonmap)",
        &wall_scene("one_pm", glass, pm),
        IntegratorKind::Photonmap,
    );
    let two_pm = render_finite(
        "coincident (photonmap)",
        &wall_scene("two_pm", &format!("{glass}\n{glass}\n{floor}"), pm),
        IntegratorKind::Photonmap,
    );
    let e_pm = relmse(&two_pm, &one_pm);

    // Nested spheres.
    let nested = |r: f32| {
        format!("AttributeBegin\nMaterial \"dielectric\" \"float eta\" [ 1.5 ]\nShape \"sphere\" \"float radius\" [ {r} ]\nAttributeEnd")
    };
    let sc = scene(
        "nested",
        &format!(
            "Camera \"perspective\"\nWorldBegin\n{}\n{}\n",
            nested(2.0),
            nested(1.0)
        ),
    );
    // A ray 1e-6 off the axis (its exit bend is ~0.8 x that offset): the axis itself passes exactly through the tessellation's pole
    // vertices, where Embree's default (non-robust) kernels may miss (seen on an AVX2 EPYC:
    // the inner sphere's entry at z = -1 was skipped); the robust flag must cross there too.
    let crossings = |acc: &Accel, x: f32| {
        let mut ray = Ray::new(Vec3::new(x, 0.0, -5.0), Vec3::Z);
        let mut zs = Vec::new();
        while let Some(st) = step(&sc, acc, &ray, 0.999_999) {
            zs.push(st.p.z);
            ray = st.next;
            assert!(zs.len() < 10, "endless");
        }
        (zs, ray)
    };
    let robust = Accel::build(&sc, BackendKind::Embree, AccelOptions { robust: true }).unwrap();
    let (on_axis, _) = crossings(&robust, 0.0);
    assert_eq!(on_axis.len(), 4, "robust crossings on the axis {on_axis:?}");
    let acc = accel(&sc);
    let (zs, ray) = crossings(&acc, 1e-6);
    let bend = (ray.d.normalize() - Vec3::Z).length();
    let want = [-2.0f32, -1.0, 1.0, 2.0];
    let z_err = zs
        .iter()
        .zip(want)
        .map(|(z, w)| (z - w).abs())
        .fold(0.0f32, f32::max);
    let nested_img = render_finite(
        "nested spheres (photonmap)",
        &scene(
            "nested_render",
            &format!(
                r#"LookAt 0 1 6  0 0 0  0 1 0
Camera "perspective" "float fov" [ 40 ]
Film "rgb" "integer xresolution" [ 24 ] "integer yresolution" [ 24 ]
Sampler "independent" "integer pixelsamples" [ 2 ]
{pm}
WorldBegin
Material "diffuse" "rgb reflectance" [ 0.5 0.5 0.5 ]
Shape "trianglemesh" "point3 P" [ -9 -2 -9  9 -2 -9  9 -2 9  -9 -2 9 ] "integer indices" [ 0 2 1 0 3 2 ]
LightSource "point" "rgb I" [ 20 20 20 ] "point3 from" [ 1 5 1 ]
{}
{}
"#,
                nested(1.0),
                nested(0.5)
            ),
        ),
        IntegratorKind::Photonmap,
    );
    summary(format!(
        "coincident faces: relMSE two copies vs one {e_direct:.2e} (direct), {e_pm:.2e} (photonmap) (expected ~0); nested spheres: diameter ray crossings at z = {zs:?} (expected [-2, -1, 1, 2], max error {z_err:.1e}), exit bend {bend:.1e}; nested render NaN {}",
        nested_img.count_nonfinite()
    ));
    assert!(
        e_direct < 1e-8,
        "coincident copies differ (direct): {e_direct}"
    );
    assert!(e_pm < 2e-3, "coincident copies differ (photonmap): {e_pm}");
    assert_eq!(zs.len(), 4, "crossings {zs:?}");
    assert!(z_err < 1e-3 && bend < 1e-5, "{zs:?} bend {bend}");
}

/// Zero-area triangles (a repeated vertex, three collinear points) and a needle 1e-7 wide, as
/// plain geometry and as area lights, between a lit floor and its point light: camera rays
/// aimed at them do not hit them, and the images equal the images without them.
#[test]
fn degenerate_and_needle_triangles() {
    let base = |extra: &str, integ: &str| {
        format!(
            r#"LookAt 0.3 3 0.2  0 0 0  0 0 1
Camera "perspective" "float fov" [ 60 ]
Film "rgb" "integer xresolution" [ 24 ] "integer yresolution" [ 24 ]
PixelFilter "box" "float xradius" [ 0.5 ] "float yradius" [ 0.5 ]
Sampler "independent" "integer pixelsamples" [ 4 ]
{integ}
WorldBegin
Material "diffuse" "rgb reflectance" [ 0.5 0.5 0.5 ]
Shape "trianglemesh" "point3 P" [ -5 0 -5  5 0 -5  5 0 5  -5 0 5 ] "integer indices" [ 0 1 2 0 2 3 ]
AttributeBegin
  Material "diffuse" "rgb reflectance" [ 0.5 0.5 0.5 ]
  Shape "trianglemesh" "point3 P" [ -2 -0.01 -2  2 -0.01 -2  2 3 -2  -2 3 -2 ] "integer indices" [ 0 2 1 0 3 2 ]
AttributeEnd
LightSource "point" "rgb I" [ 5 5 5 ] "point3 from" [ 0 2 0 ]
{extra}
"#
        )
    };
    let degenerate = r#"
Shape "trianglemesh" "point3 P" [ 0 1 0  0.5 1 0  0.5 1 0 ] "integer indices" [ 0 1 2 ]
Shape "trianglemesh" "point3 P" [ -0.5 1 0.2  0 1 0.2  0.5 1 0.2 ] "integer indices" [ 0 1 2 ]
Shape "trianglemesh" "point3 P" [ -0.5 0.8 -0.1  0.5 0.8 -0.1  0 0.8 -0.0999999 ] "integer indices" [ 0 1 2 ]
AttributeBegin
  AreaLightSource "diffuse" "rgb L" [ 100 100 100 ]
  Shape "trianglemesh" "point3 P" [ 0 1.5 0  0.3 1.5 0  0.3 1.5 0 ] "integer indices" [ 0 1 2 ]
AttributeEnd
AttributeBegin
  AreaLightSource "diffuse" "rgb L" [ 100 100 100 ]
  Shape "trianglemesh" "point3 P" [ -0.5 1.2 0.3  0.5 1.2 0.3  0 1.2 0.3000001 ] "integer indices" [ 0 1 2 ]
AttributeEnd
"#;
    let direct = r#"Integrator "path" "integer maxdepth" [ 3 ]"#;
    let pm = r#"Integrator "photonmap" "integer maxdepth" [ 3 ] "integer globalphotons" [ 20000 ]"#;
    let sc = scene("degenerate", &base(degenerate, direct));
    // Camera rays aimed at points of the degenerate triangles never report them.
    let acc = accel(&sc);
    let cam = Vec3::new(0.3, 3.0, 0.2);
    let (mut hits_degenerate, mut hits_needle, mut bad_normal) = (0, 0, 0);
    for m in 2..sc.meshes.len() {
        let mesh = &sc.meshes[m];
        for a in 0..3 {
            for b in 0..3 {
                let target = mesh.positions[a] * 0.5 + mesh.positions[b] * 0.5;
                let Some(h) = acc.backend().intersect(&Ray::new(cam, target - cam)) else {
                    continue;
                };
                if h.mesh < 2 {
                    continue;
                }
                // Needles have an area (5e-8): exactly aimed rays may hit them, but then with
                // a finite unit normal.
                if sc.meshes[h.mesh as usize].area(h.prim) > 0.0 {
                    hits_needle += 1;
                    bad_normal += usize::from(!h.ng.is_normalized());
                } else {
                    hits_degenerate += 1;
                }
            }
        }
    }
    let mut lines = Vec::new();
    for (integ, kind, tol) in [
        (direct, IntegratorKind::Direct, 1e-6),
        (pm, IntegratorKind::Photonmap, 1e-3),
    ] {
        let with = render_finite(
            "degenerate",
            &scene("degenerate_r", &base(degenerate, integ)),
            kind,
        );
        let without = render_finite("clean", &scene("clean", &base("", integ)), kind);
        let e = relmse(&with, &without);
        lines.push(format!("{kind:?} relMSE vs clean {e:.2e} (tol {tol:e})"));
        assert!(
            e < tol,
            "{kind:?}: degenerate triangles change the image: {e}"
        );
    }
    summary(format!(
        "degenerate/needle triangles: {hits_degenerate} hits on zero-area ones (expected 0), {hits_needle} exactly aimed hits on needles ({bad_normal} without a unit normal, expected 0); {}",
        lines.join(", ")
    ));
    assert_eq!((hits_degenerate, bad_normal), (0, 0));
}

/// A spherical area light (radius a, radiance L) resting on a diffuse floor, touching it at
/// the origin. The sphere lies entirely above every floor point's horizon, so `E(rho) = pi L sin^2(alpha) cos(theta) = pi L a^3 / (rho^2 + a^2)^1.5`
/// at distance rho from the contact point; the floor's radiance is `rho_d / pi E`.
#[test]
fn sphere_light_touching_the_floor() {
    let a = 0.5f32;
    let l = 1.0f32;
    let text = |integ: &str, spp: u32| {
        format!(
            r#"LookAt 0.4 6 0.3  0 0 0  0 0 1
Camera "perspective" "float fov" [ 40 ]
Film "rgb" "integer xresolution" [ 32 ] "integer yresolution" [ 32 ]
PixelFilter "box" "float xradius" [ 0.0001 ] "float yradius" [ 0.0001 ]
Sampler "independent" "integer pixelsamples" [ {spp} ]
{integ}
WorldBegin
Material "diffuse" "rgb reflectance" [ {RHO} {RHO} {RHO} ]
Shape "trianglemesh" "point3 P" [ -20 0 -20  20 0 -20  20 0 20  -20 0 20 ] "integer indices" [ 0 1 2 0 2 3 ]
AttributeBegin
  AreaLightSource "diffuse" "rgb L" [ {l} {l} {l} ]
  Translate 0 {a} 0
  Shape "sphere" "float radius" [ {a} ]
AttributeEnd
"#
        )
    };
    let sc = scene(
        "sphere_light",
        &text(r#"Integrator "path" "integer maxdepth" [ 1 ]"#, 2048),
    );
    let img = render_finite("sphere light (direct)", &sc, IntegratorKind::Direct);
    let cam = Camera::new(&sc.camera, 32, 32);
    let centre = Vec3::new(0.0, a, 0.0);
    let (mut sum_got, mut sum_want, mut n, mut near) = (0.0f64, 0.0f64, 0, 0);
    let mut worst_ring = 0.0f64;
    // Rings of distance from the contact point: per-ring mean ratio.
    let mut rings = [(0.0f64, 0.0f64); 4];
    for y in 0..32u32 {
        for x in 0..32u32 {
            let r = cam.generate_ray(Vec2::new(x as f32 + 0.5, y as f32 + 0.5));
            // Skip pixels whose ray meets the sphere (with a margin for the tessellation).
            let oc = r.o - centre;
            let b = oc.dot(r.d);
            if b * b - (oc.length_squared() - (a * 1.01).powi(2)) >= 0.0 {
                continue;
            }
            let p = r.at(-r.o.y / r.d.y);
            let rho = (p.x * p.x + p.z * p.z).sqrt();
            let e = PI * l * a.powi(3) / (rho * rho + a * a).powf(1.5);
            let want = (RHO / PI * e) as f64;
            let got = img.pixels[(y * 32 + x) as usize][0] as f64;
            sum_got += got;
            sum_want += want;
            n += 1;
            near += usize::from(rho < 1.0);
            let ring = ((rho / 0.75) as usize).min(3);
            rings[ring].0 += got;
            rings[ring].1 += want;
        }
    }
    for (g, w) in rings {
        if w > 0.0 {
            worst_ring = worst_ring.max((g / w - 1.0).abs());
        }
    }
    let ratio = sum_got / sum_want;
    let pm = scene(
        "sphere_light_pm",
        &text(
            r#"Integrator "photonmap" "integer maxdepth" [ 3 ] "integer globalphotons" [ 20000 ]"#,
            4,
        ),
    );
    let pm_img = render_finite("sphere light (photonmap)", &pm, IntegratorKind::Photonmap);
    summary(format!(
        "sphere light touching the floor: {n} floor pixels ({near} with rho < 1), mean radiance / analytic {ratio:.4} (expected 1), worst ring ratio error {worst_ring:.3}; NaN direct {} photonmap {}",
        img.count_nonfinite(),
        pm_img.count_nonfinite()
    ));
    assert!(n > 500 && near > 10);
    // Measured at 2048 spp: mean 0.9993, worst ring 0.6% (64 spp gave 6.5%: noise).
    assert!((ratio - 1.0).abs() < 0.01, "mean ratio {ratio}");
    assert!(worst_ring < 0.02, "ring error {worst_ring}");
}

/// Next-event samples of a sphere light (radius a, radiance 1, resting on the floor as in
/// [`sphere_light_touching_the_floor`]) seen from floor points at distance rho from the
/// contact: the estimate of the irradiance `sum L cos / pdf` against `pi a^3 / (rho^2 +
/// a^2)^1.5`, its spread per sample against area sampling's (`Lights::sample_light`, which
/// the bidirectional integrators keep), and the density `Lights::pdf_area` gives a hit on the
/// point drawn (what MIS weighs a BSDF sample with) against the sample's own.
#[test]
fn sphere_light_is_sampled_by_the_cone_it_subtends() {
    let a = 0.5f32;
    let sc = scene(
        "sphere_cone",
        &format!(
            r#"LookAt 0 6 0.1  0 0 0  0 0 1
Camera "perspective"
WorldBegin
AttributeBegin
  AreaLightSource "diffuse" "rgb L" [ 1 1 1 ]
  Translate 0 {a} 0
  Shape "sphere" "float radius" [ {a} ]
AttributeEnd
"#
        ),
    );
    let lights = sc.emitters();
    let mut rng = Rng(11);
    let mut lines = vec![];
    for rho in [0.2f32, 1.0, 4.0] {
        let p = Vec3::new(rho, 0.0, 0.0);
        let want = (PI * a.powi(3) / (rho * rho + a * a).powf(1.5)) as f64;
        let n = 1 << 14;
        let mut stats = |cone: bool| {
            let (mut sum, mut sum2) = (0.0f64, 0.0f64);
            for _ in 0..n {
                let u = Vec2::new(rng.f(), rng.f());
                let s = if cone {
                    lights.sample(&sc.meshes, Receiver::new(p, Vec3::Y), 0.5, u)
                } else {
                    lights.sample_light(&sc.meshes, 0, 1.0, p, u)
                };
                let Some(s) = s else { continue };
                if cone {
                    let pdf = lights.pdf_area(0, Receiver::new(p, Vec3::Y), s.p, s.n);
                    assert!((pdf / s.pdf - 1.0).abs() < 1e-3, "pdf {pdf} vs {}", s.pdf);
                    assert!(((s.p - Vec3::new(0.0, a, 0.0)).length() / a - 1.0).abs() < 1e-4);
                }
                let v = (s.li.x * s.wi.y.max(0.0) / s.pdf) as f64;
                sum += v;
                sum2 += v * v;
            }
            let mean = sum / n as f64;
            let std = (sum2 / n as f64 - mean * mean).max(0.0).sqrt();
            (mean / want, std / mean)
        };
        let (cone_ratio, cone_spread) = stats(true);
        let (area_ratio, area_spread) = stats(false);
        lines.push(format!(
            "rho {rho}: cone {cone_ratio:.4} (spread {cone_spread:.3}), area {area_ratio:.4} (spread {area_spread:.3})"
        ));
        // The tessellation's area is 0.05% short; the cone is the analytic sphere's.
        assert!(
            (cone_ratio - 1.0).abs() < 0.01,
            "rho {rho}: cone mean {cone_ratio}"
        );
        assert!(
            (area_ratio - 1.0).abs() < 0.03,
            "rho {rho}: area mean {area_ratio}"
        );
        assert!(
            cone_spread < 0.5 * area_spread,
            "rho {rho}: cone spread {cone_spread}, area {area_spread}"
        );
    }
    summary(format!(
        "sphere light next-event samples: {}",
        lines.join("; ")
    ));
}

/// A closed diffuse box lit by a quad light of radiance `l` (photon mapper).
fn lit_box(name: &str, l: f32) -> Scene {
    scene(
        name,
        &format!(
            r#"LookAt 0 0 -0.9  0 0 1  0 1 0
Camera "perspective" "float fov" [ 80 ]
Film "rgb" "integer xresolution" [ 24 ] "integer yresolution" [ 24 ]
Sampler "independent" "integer pixelsamples" [ 2 ]
Integrator "photonmap" "integer globalphotons" [ 20000 ] "integer maxdepth" [ 5 ]
WorldBegin
AttributeBegin
  Material "diffuse" "rgb reflectance" [ 0.6 0.5 0.4 ]
  ReverseOrientation
  {CUBE}
AttributeEnd
AttributeBegin
  AreaLightSource "diffuse" "rgb L" [ {l} {l} {l} ]
  Shape "trianglemesh" "point3 P" [ -0.3 0.99 -0.3  0.3 0.99 -0.3  0.3 0.99 0.3  -0.3 0.99 0.3 ] "integer indices" [ 0 1 2 0 2 3 ]
AttributeEnd
"#
        ),
    )
}

/// Light transport is linear: a light of zero radiance gives an exactly black image (no NaN
/// from 0/0 power normalisations), a light 1e6 times brighter an image 1e6 times brighter.
#[test]
fn zero_and_very_bright_lights() {
    let base = render_finite("box L=1", &lit_box("box1", 1.0), IntegratorKind::Photonmap);
    let zero = render_finite("box L=0", &lit_box("box0", 0.0), IntegratorKind::Photonmap);
    let bright = render_finite(
        "box L=1e6",
        &lit_box("box1e6", 1e6),
        IntegratorKind::Photonmap,
    );
    let zero_max = zero
        .pixels
        .iter()
        .flatten()
        .fold(0.0f32, |a, &b| a.max(b.abs()));
    let (mut worst, mut sum_b, mut sum_1) = (0.0f64, 0.0f64, 0.0f64);
    for (b, o) in bright.pixels.iter().zip(&base.pixels) {
        for c in 0..3 {
            if o[c] > 0.0 {
                worst = worst.max((b[c] as f64 / (1e6 * o[c] as f64) - 1.0).abs());
            }
            sum_b += b[c] as f64;
            sum_1 += o[c] as f64;
        }
    }
    let mean_ratio = sum_b / sum_1;
    summary(format!(
        "zero / bright light: max |pixel| at L=0 {zero_max:e} (expected 0); image(1e6 L) / image(L) mean {mean_ratio:.6e} (expected 1e6), worst pixel deviation {worst:.1e}"
    ));
    assert_eq!(zero_max, 0.0);
    assert!(
        (mean_ratio / 1e6 - 1.0).abs() < 1e-3,
        "mean ratio {mean_ratio}"
    );
    assert!(worst < 1e-2, "worst pixel ratio deviation {worst}");
}

// ---------------------------------------------------------------------------------------------
// Photon map: split planes, k beyond the map

/// Photons on an integer grid of a plane (every coordinate a kd-tree split value, many equal
/// distances): the k nearest found equal brute force (as sorted distance lists, since ties may
/// pick either photon); asking for more photons than the map holds returns all of them, and
/// the box-kernel irradiance is then the total power over pi r^2. A render whose global map is
/// smaller than its lookup count stays finite.
#[test]
fn photons_on_split_planes_and_k_beyond_the_map() {
    let mut photons = Vec::new();
    for x in 0..16 {
        for z in 0..16 {
            let p = Vec3::new(x as f32, 0.0, z as f32);
            photons.push(Photon::new(p, Vec3::splat(0.25), -Vec3::Y, 0));
        }
    }
    let map = PhotonMap::new(&photons).unwrap();
    let mut buf = KnnResult::new();
    let mut mismatches = 0;
    let queries: Vec<Vec3> = (0..50)
        .map(|i| {
            Vec3::new(
                (i % 16) as f32,
                0.0,
                ((i * 7) % 16) as f32 + 0.5 * (i % 2) as f32,
            )
        })
        .collect();
    for &q in &queries {
        for k in [1usize, 4, 5, 9, 13, 21] {
            map.knn(q, k, f32::INFINITY, &mut buf);
            let mut got: Vec<f32> = buf.neighbors().iter().map(|n| n.d2).collect();
            got.sort_by(f32::total_cmp);
            let mut all: Vec<f32> = photons
                .iter()
                .map(|p| (p.pos() - q).length_squared())
                .collect();
            all.sort_by(f32::total_cmp);
            mismatches += usize::from(got != all[..k]);
        }
    }
    // k beyond the map.
    let r = 40.0f32;
    map.knn(Vec3::new(7.5, 0.0, 7.5), 10_000, r * r, &mut buf);
    let found = buf.len();
    let mut params = EstimateParams::new(10_000, r * r);
    params.kernel = Kernel::Box;
    params.disc_fraction = 1.0;
    let (e, used, r2) = irradiance_with(&map, Vec3::new(7.5, 0.0, 7.5), Vec3::Y, &params, &mut buf);
    let want = 256.0 * 0.25 / (PI * r * r);
    let e_err = (e.x - want).abs() / want;

    // A render with 200 global photons and lookups of 1000.
    let sc = scene(
        "k_beyond_map",
        &format!(
            r#"LookAt 0 0 -0.9  0 0 1  0 1 0
Camera "perspective" "float fov" [ 80 ]
Film "rgb" "integer xresolution" [ 16 ] "integer yresolution" [ 16 ]
Sampler "independent" "integer pixelsamples" [ 2 ]
Integrator "photonmap" "integer globalphotons" [ 200 ] "integer globallookup" [ 1000 ] "bool finalgather" [ false ]
WorldBegin
Material "diffuse" "rgb reflectance" [ 0.5 0.5 0.5 ]
ReverseOrientation
{CUBE}
LightSource "point" "rgb I" [ 1 1 1 ] "point3 from" [ 0 0.5 0 ]
"#
        ),
    );
    let img = render_finite("k beyond map", &sc, IntegratorKind::Photonmap);
    let lit = img.pixels.iter().filter(|p| p[0] > 0.0).count();
    summary(format!(
        "grid photons on split planes: {mismatches} kNN mismatches vs brute force (expected 0); k = 10000 > 256 photons: found {found}, used {used} (expected 256), r^2 {r2} (expected {}), E {:.6} vs {want:.6} (rel. err {e_err:.1e}); render with 200 photons and k = 1000: NaN {}, {lit} lit pixels",
        r * r,
        e.x,
        img.count_nonfinite()
    ));
    assert_eq!(mismatches, 0);
    assert_eq!((found, used), (256, 256));
    assert_eq!(r2, r * r);
    assert!(e_err < 1e-3, "E {} vs {want}", e.x);
    assert!(lit > 0);
}
