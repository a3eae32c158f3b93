//! Distant (directional) light: `LightSource "distant"`; irradiance on a surface facing it
//! is `L`.
use super::{scalar_power, Emission, LightSample};
use crate::math::{Frame, Vec2, Vec3};
use crate::sampling::warp::square_to_disk_concentric;
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
        err: Vec3::ZERO,
        pdf: 1.0,
        delta: true,
    }
}

/// A photon from a uniform point of the disc of radius `radius` that faces the light, centred
/// on the scene and placed outside it; flux `L pi radius^2`.
pub fn emit(dir: Vec3, l: Vec3, center: Vec3, radius: f32, u_pos: Vec2) -> Emission {
    let d = square_to_disk_concentric(u_pos) * radius;
    let frame = Frame::from_normal(dir);
    let p = center - dir * (2.0 * radius) + frame.s * d.x + frame.t * d.y;
    Emission {
        p,
        n: Vec3::ZERO,
        err: Vec3::ZERO,
        dir,
        flux: l * (PI * radius * radius),
    }
}
