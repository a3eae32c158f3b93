//! Distant (directional) light: `LightSource "distant"`; irradiance on a surface facing it
//! is `L`.
use super::{scalar_power, LightSample};
use crate::math::Vec3;
use std::f32::consts::PI;

/// Power through the scene's bounding disc.
pub fn power(l: Vec3, radius: f32) -> f32 {
    PI * radius * radius * scalar_power(l)
}

pub fn sample(dir: Vec3, l: Vec3, p_ref: Vec3, center: Vec3, radius: f32) -> LightSample {
    let wi = -dir;
    let far = (p_ref - center).length() + 2.0 * radius;
    LightSample {
        li: l,
        wi,
        p: p_ref + wi * far,
        n: Vec3::ZERO,
        pdf: 1.0,
        delta: true,
    }
}
