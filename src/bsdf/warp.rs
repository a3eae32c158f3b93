//! The polar disc warp of pbrt-v4's visible-normal sampling (private to `bsdf`; the
//! renderer's general warps, which the BSDFs use too, live in `sampling::warp`).
use crate::math::Vec2;
use std::f32::consts::PI;

/// Polar map of `u` in `[0,1)^2` onto the unit disc (`r = sqrt(u.x)`, `phi = 2 pi u.y`):
/// the one pbrt-v4's visible-normal sampling uses.
pub(crate) fn square_to_uniform_disk_polar(u: Vec2) -> Vec2 {
    let r = u.x.max(0.0).sqrt();
    let phi = 2.0 * PI * u.y;
    Vec2::new(r * phi.cos(), r * phi.sin())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn disks_stay_in_the_unit_disk_and_cover_it_uniformly() {
        // Fraction of points within radius 0.5 must be 1/4 for a uniform disc.
        let n = 200;
        for warp in [
            crate::sampling::warp::square_to_disk_concentric,
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
