//! Distant (directional) light: `LightSource "distant"`; irradiance on a surface facing it
//! is `L`.
use super::{scalar_power, Emission, LightSample};
use crate::math::{Frame, Vec2, Vec3};
use crate::sampling::warp::square_to_disk_concentric;
use std::f32::consts::PI;

/// `LightSource "distant"`: radiance `l` arriving along unit `dir` (the direction the light
/// travels, from `from` to `to`). Its photons and shadow-ray points lie outside the scene's
/// bounding sphere (`center`, `radius`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DistantLight {
    pub dir: Vec3,
    pub l: Vec3,
}

impl DistantLight {
    /// Power through the scene's bounding disc.
    pub fn power(&self, radius: f32) -> f32 {
        PI * radius * radius * scalar_power(self.l)
    }

    pub fn sample(&self, p_ref: Vec3, center: Vec3, radius: f32) -> LightSample {
        let wi = -self.dir;
        let far = (p_ref - center).length() + 2.0 * radius;
        LightSample {
            li: self.l,
            wi,
            p: p_ref + wi * far,
            n: Vec3::ZERO,
            err: Vec3::ZERO,
            pdf: 1.0,
            delta: true,
        }
    }

    /// A photon from a uniform point of the disc of radius `radius` that faces the light,
    /// centred on the scene and placed outside it; flux `L pi radius^2`.
    pub fn emit(&self, center: Vec3, radius: f32, u_pos: Vec2) -> Emission {
        let dir = self.dir;
        let d = square_to_disk_concentric(u_pos) * radius;
        let frame = Frame::from_normal(dir);
        let p = center - dir * (2.0 * radius) + frame.s * d.x + frame.t * d.y;
        Emission {
            p,
            n: Vec3::ZERO,
            err: Vec3::ZERO,
            dir,
            flux: self.l * (PI * radius * radius),
        }
    }
}
