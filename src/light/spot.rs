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

/// `LightSource "spot"`: like a point light, inside a cone around unit `dir`, with pbrt-v4's
/// smoothstep falloff from `cos_falloff_start` (full) to `cos_falloff_end` (zero).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SpotLight {
    pub pos: Vec3,
    pub dir: Vec3,
    pub intensity: Vec3,
    pub cos_falloff_start: f32,
    pub cos_falloff_end: f32,
}

impl SpotLight {
    /// pbrt-v4's spot power: `I 2 pi ((1 - cos_start) + (cos_start - cos_end) / 2)`.
    pub fn power(&self) -> f32 {
        let (s, e) = (self.cos_falloff_start, self.cos_falloff_end);
        scalar_power(self.intensity) * 2.0 * PI * ((1.0 - s) + (s - e) / 2.0)
    }

    /// Intensity scale towards unit direction `w` (from the light).
    pub fn falloff(&self, w: Vec3) -> f32 {
        smoothstep(
            self.cos_falloff_end,
            self.cos_falloff_start,
            self.dir.dot(w),
        )
    }

    pub fn sample(&self, p_ref: Vec3) -> Option<LightSample> {
        super::point::delta_sample(self.pos, p_ref, |wi, d2| {
            self.intensity * self.falloff(-wi) / d2
        })
    }

    /// A photon uniform in the cone of half-angle `acos(cos_end)`, weighted by the falloff;
    /// flux `I falloff 2 pi (1 - cos_end)`.
    pub fn emit(&self, u_dir: Vec2) -> Option<Emission> {
        let cos_end = self.cos_falloff_end;
        let w = Frame::from_normal(self.dir).to_world(square_to_uniform_cone(u_dir, cos_end));
        let flux = self.intensity * (self.falloff(w) * 2.0 * PI * (1.0 - cos_end));
        (flux.max_element() > 0.0).then_some(Emission {
            p: self.pos,
            n: Vec3::ZERO,
            err: Vec3::ZERO,
            dir: w,
            flux,
        })
    }
}
