//! Isotropic point light: `LightSource "point"`; irradiance `E = I cos(theta) / r^2`.
use super::{scalar_power, Emission, LightSample};
use crate::math::{Vec2, Vec3};
use crate::sampling::warp::square_to_uniform_sphere;
use std::f32::consts::PI;

pub fn power(intensity: Vec3) -> f32 {
    4.0 * PI * scalar_power(intensity)
}

pub fn sample(pos: Vec3, intensity: Vec3, p_ref: Vec3) -> Option<LightSample> {
    let to = pos - p_ref;
    let d2 = to.length_squared();
    if d2 <= 0.0 {
        return None;
    }
    let wi = to / d2.sqrt();
    Some(LightSample {
        li: intensity / d2,
        wi,
        p: pos,
        n: Vec3::ZERO,
        err: Vec3::ZERO,
        pdf: 1.0,
        delta: true,
    })
}

/// A photon in a uniform direction; flux `4 pi I`.
pub fn emit(pos: Vec3, intensity: Vec3, u_dir: Vec2) -> Emission {
    Emission {
        p: pos,
        n: Vec3::ZERO,
        err: Vec3::ZERO,
        dir: square_to_uniform_sphere(u_dir),
        flux: intensity * (4.0 * PI),
    }
}
