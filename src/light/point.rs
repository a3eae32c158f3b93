//! Isotropic point light: `LightSource "point"`; irradiance `E = I cos(theta) / r^2`.
use super::{scalar_power, Emission, LightSample};
use crate::math::{Vec2, Vec3};
use crate::sampling::warp::square_to_uniform_sphere;
use std::f32::consts::PI;

/// `LightSource "point"`: intensity `intensity` (W/sr) at `pos`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PointLight {
    pub pos: Vec3,
    pub intensity: Vec3,
}

impl PointLight {
    pub fn power(&self) -> f32 {
        4.0 * PI * scalar_power(self.intensity)
    }

    pub fn sample(&self, p_ref: Vec3) -> Option<LightSample> {
        delta_sample(self.pos, p_ref, |_, d2| self.intensity / d2)
    }

    /// A photon in a uniform direction; flux `4 pi I`.
    pub fn emit(&self, u_dir: Vec2) -> Emission {
        Emission {
            p: self.pos,
            n: Vec3::ZERO,
            err: Vec3::ZERO,
            dir: square_to_uniform_sphere(u_dir),
            flux: self.intensity * (4.0 * PI),
        }
    }
}

/// The sample of a point-like light at `pos` seen from `p_ref` (none at the light itself):
/// `li(wi, d2)` is what arrives along unit `wi` from distance squared `d2`.
pub(super) fn delta_sample(
    pos: Vec3,
    p_ref: Vec3,
    li: impl Fn(Vec3, f32) -> Vec3,
) -> Option<LightSample> {
    let to = pos - p_ref;
    let d2 = to.length_squared();
    if d2 <= 0.0 {
        return None;
    }
    let wi = to / d2.sqrt();
    Some(LightSample {
        li: li(wi, d2),
        wi,
        p: pos,
        n: Vec3::ZERO,
        err: Vec3::ZERO,
        pdf: 1.0,
        delta: true,
    })
}
