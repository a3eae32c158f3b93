//! Distant (directional) light: `LightSource "distant"`; irradiance on a surface facing it
//! is `L`.
use super::{scalar_power, Emission, LightSample};
use crate::math::Vec3;
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

    /// A photon leaving `p` (outside the scene, see [`super::Lights::emit_aimed`]), drawn
    /// with density `1 / area` over the plane facing the light; flux `L area`.
    pub fn emit(&self, p: Vec3, area: f32) -> Emission {
        Emission {
            p,
            n: Vec3::ZERO,
            err: Vec3::ZERO,
            dir: self.dir,
            flux: self.l * area,
        }
    }
}
