//! Spot light: `LightSource "spot"`; pbrt-v4's smoothstep falloff between the cone angle
//! (`cos_falloff_end`, zero) and `coneangle - conedeltaangle` (`cos_falloff_start`, full).
use super::{scalar_power, Emission, LightSample};
use crate::math::{Frame, Vec2, Vec3};
use crate::sampling::warp::square_to_uniform_cone;
use std::f32::consts::PI;

pub fn smoothstep(a: f32, b: f32, x: f32) -> f32 {
    if a == b {
        return if x < a { 0.0 } else { 1.0 };
    }
    let t = ((x - a) / (b - a)).clamp(0.0, 1.0);
    t * t * (3.0 - 2.0 * t)
}

/// pbrt-v4's spot power: `I 2 pi ((1 - cos_start) + (cos_start - cos_end) / 2)`.
pub fn power(intensity: Vec3, cos_start: f32, cos_end: f32) -> f32 {
    scalar_power(intensity) * 2.0 * PI * ((1.0 - cos_start) + (cos_start - cos_end) / 2.0)
}

/// Intensity scale towards unit direction `w` (from the light).
pub fn falloff(dir: Vec3, w: Vec3, cos_start: f32, cos_end: f32) -> f32 {
    smoothstep(cos_end, cos_start, dir.dot(w))
}

pub fn sample(
    pos: Vec3,
    dir: Vec3,
    intensity: Vec3,
    cos_start: f32,
    cos_end: f32,
    p_ref: Vec3,
) -> Option<LightSample> {
    let to = pos - p_ref;
    let d2 = to.length_squared();
    if d2 <= 0.0 {
        return None;
    }
    let wi = to / d2.sqrt();
    let li = intensity * falloff(dir, -wi, cos_start, cos_end) / d2;
    Some(LightSample {
        li,
        wi,
        p: pos,
        n: Vec3::ZERO,
        err: Vec3::ZERO,
        pdf: 1.0,
        delta: true,
    })
}

/// A photon uniform in the cone of half-angle `acos(cos_end)`, weighted by the falloff; flux
/// `I falloff 2 pi (1 - cos_end)`.
pub fn emit(
    pos: Vec3,
    dir: Vec3,
    intensity: Vec3,
    cos_start: f32,
    cos_end: f32,
    u_dir: Vec2,
) -> Option<Emission> {
    let w = Frame::from_normal(dir).to_world(square_to_uniform_cone(u_dir, cos_end));
    let flux = intensity * (falloff(dir, w, cos_start, cos_end) * 2.0 * PI * (1.0 - cos_end));
    (flux.max_element() > 0.0).then_some(Emission {
        p: pos,
        n: Vec3::ZERO,
        err: Vec3::ZERO,
        dir: w,
        flux,
    })
}
