//! The few square-to-domain warps the BSDFs sample with (private to `bsdf`; the renderer's
//! general warps live in `sampling::warp`).
use crate::math::{Vec2, Vec3};
use std::f32::consts::{FRAC_PI_2, FRAC_PI_4, PI};

/// Concentric (Shirley-Chiu) map of `u` in `[0,1)^2` onto the unit disc, area-preserving.
pub(crate) fn square_to_uniform_disk_concentric(u: Vec2) -> Vec2 {
    let o = 2.0 * u - Vec2::ONE;
    if o.x == 0.0 && o.y == 0.0 {
        return Vec2::ZERO;
    }
    let (r, theta) = if o.x.abs() > o.y.abs() {
        (o.x, FRAC_PI_4 * (o.y / o.x))
    } else {
        (o.y, FRAC_PI_2 - FRAC_PI_4 * (o.x / o.y))
    };
    r * Vec2::new(theta.cos(), theta.sin())
}

/// Polar map of `u` in `[0,1)^2` onto the unit disc (`r = sqrt(u.x)`, `phi = 2 pi u.y`):
/// the one pbrt-v4's visible-normal sampling uses.
pub(crate) fn square_to_uniform_disk_polar(u: Vec2) -> Vec2 {
    let r = u.x.max(0.0).sqrt();
    let phi = 2.0 * PI * u.y;
    Vec2::new(r * phi.cos(), r * phi.sin())
}

/// Cosine-weighted direction about +z (Malley's method); density `cos(theta) / pi`.
pub(crate) fn square_to_cosine_hemisphere(u: Vec2) -> Vec3 {
    let d = square_to_uniform_disk_concentric(u);
    let z = (1.0 - d.length_squared()).max(0.0).sqrt();
    Vec3::new(d.x, d.y, z)
}

/// Density of [`square_to_cosine_hemisphere`] for a direction with cosine `cos_theta`.
pub(crate) fn cosine_hemisphere_pdf(cos_theta: f32) -> f32 {
    cos_theta.max(0.0) / PI
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn disks_stay_in_the_unit_disk_and_cover_it_uniformly() {
        // Fraction of points within radius 0.5 must be 1/4 for a uniform disc.
        let n = 200;
        for warp in [
            square_to_uniform_disk_concentric,
            square_to_uniform_disk_polar,
        ] {
            let mut inside = 0;
            for i in 0..n {
                for j in 0..n {
                    let u = Vec2::new((i as f32 + 0.5) / n as f32, (j as f32 + 0.5) / n as f32);
                    let p = warp(u);
                    assert!(p.length() <= 1.0 + 1e-6);
                    inside += (p.length() < 0.5) as u32;
                }
            }
            let frac = inside as f32 / (n * n) as f32;
            assert!((frac - 0.25).abs() < 2e-3, "{frac}");
        }
    }
}
