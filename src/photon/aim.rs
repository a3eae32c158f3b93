//! Aimed global photons of the lights without a surface (distant and infinite lights).
//!
//! Such a light sends its photons from a disc that covers the whole scene, and where the
//! camera looks at a small part of a large scene (a room lit by the sun through its windows,
//! inside a wide ground: Bitterli's classroom) nearly all of them land where no estimate
//! reads them: in tests/it/windows.rs the window's 1.9 m^2 across the sun's direction is 1 in
//! 3000 of the 5650 m^2 disc over the ground. [`region_of_interest`]
//! finds the sphere around what the camera sees (its first hits and one diffuse bounce from
//! each), and such a light then draws a photon's origin from a mixture: with probability
//! `share` uniform on the disc that sphere casts, else uniform on the whole disc; its flux
//! divides by the mixture's density at the origin ([`crate::light::Lights::emit`]), so the
//! maps stay unbiased everywhere while the region gets `share (R / r)^2` times the photons.
use crate::accel::{Accel, RayKind};
use crate::camera::Camera;
use crate::math::{Frame, Ray, Vec2, Vec3};
use crate::sampling::warp::square_to_cosine_hemisphere;
use crate::scene::Scene;

pub use crate::light::Aim;

/// Probe rays per side of the camera grid.
const PROBES: u32 = 32;

/// Share of the photons aimed at the region when it is small enough to aim at.
pub const SHARE: f32 = 0.75;

/// The region must be at most this fraction of the scene's radius to be aimed at (larger,
/// aiming gains less than 4x in photon density).
const MAX_RADIUS_FRACTION: f32 = 0.5;

/// The sphere around what the camera sees (see the module docs), given the scene's bounding
/// sphere `(center, radius)`: `None` when it is not much smaller than the scene or the camera
/// sees nothing. The probe hits' bounds leave out the farthest 2% on each axis (a gather ray
/// that grazes the ground far outside) and grow by 10% of their diagonal.
pub fn region_of_interest(scene: &Scene, accel: &Accel, scene_bounds: (Vec3, f32)) -> Option<Aim> {
    let camera = Camera::new(
        &scene.camera,
        scene.film.xres.max(1),
        scene.film.yres.max(1),
    );
    let (w, h) = (scene.film.xres.max(1) as f32, scene.film.yres.max(1) as f32);
    let eps = 1e-4 * scene_bounds.1;
    let mut points = Vec::new();
    for j in 0..PROBES {
        for i in 0..PROBES {
            let u = Vec2::new(
                (i as f32 + 0.5) / PROBES as f32,
                (j as f32 + 0.5) / PROBES as f32,
            );
            let ray = camera.generate_ray(Vec2::new(u.x * w, u.y * h));
            let Some(hit) = accel.intersect(RayKind::Photon, &ray) else {
                continue;
            };
            let p = ray.o + ray.d * hit.t;
            points.push(p);
            let n = if hit.ng.dot(ray.d) < 0.0 {
                hit.ng
            } else {
                -hit.ng
            };
            // One diffuse bounce, its direction from a rotated grid of the same cell.
            let v = Vec2::new(
                ((j as f32 + 0.5) / PROBES as f32 + u.x * 0.618_034).fract(),
                ((i as f32 + 0.5) / PROBES as f32 + u.y * 0.381_966).fract(),
            );
            let d = Frame::from_normal(n.normalize()).to_world(square_to_cosine_hemisphere(v));
            let bounce = Ray::new(p + n * eps, d);
            if let Some(b) = accel.intersect(RayKind::Photon, &bounce) {
                points.push(bounce.o + bounce.d * b.t);
            }
        }
    }
    if points.len() < 16 {
        return None;
    }
    let (lo, hi) = trimmed_bounds(&mut points, 0.02);
    let half = (hi - lo) * 0.5;
    let center = (lo + hi) * 0.5;
    let radius = (half.length() * 1.1).max(eps);
    (radius <= MAX_RADIUS_FRACTION * scene_bounds.1).then_some(Aim {
        center,
        radius,
        share: SHARE,
    })
}

/// Per axis, the `trim` and `1 - trim` quantiles of `points` (reordered).
fn trimmed_bounds(points: &mut [Vec3], trim: f32) -> (Vec3, Vec3) {
    let n = points.len();
    let lo_i = ((n as f32 * trim) as usize).min(n - 1);
    let hi_i = n - 1 - lo_i;
    let mut lo = Vec3::ZERO;
    let mut hi = Vec3::ZERO;
    for axis in 0..3 {
        let mut v: Vec<f32> = points.iter().map(|p| p[axis]).collect();
        v.sort_by(f32::total_cmp);
        lo[axis] = v[lo_i];
        hi[axis] = v[hi_i];
    }
    (lo, hi)
}
