//! A thin dielectric sheet (a window pane; pbrt-v4's `ThinDielectricBxDF`): two parallel
//! smooth interfaces so close together that light leaves where it entered. Summing the
//! bounces inside the sheet, the reflectance is `R' = R + T^2 R / (1 - R^2)` and the
//! transmittance `T' = 1 - R'` (`R` the Fresnel reflectance of one interface, `T = 1 - R`);
//! transmitted light keeps its direction (`wi = -wo`), so nothing is bent and no `1 / eta^2`
//! scaling applies. Both lobes are deltas.
//!
//! ```text
//! Material "thindielectric" "float eta" [ 1.5 ]
//! ```
use super::fresnel::fr_dielectric;
use super::{BsdfSample, Lobes};
use crate::math::Vec3;

/// A thin dielectric sheet of relative index `eta`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ThinDielectric {
    /// Relative index of refraction of the sheet (> 0).
    pub eta: f32,
}

impl ThinDielectric {
    /// A sheet of relative index `eta`; a non-finite or non-positive value reads as 1.
    pub fn new(eta: f32) -> Self {
        ThinDielectric {
            eta: if eta.is_finite() && eta > 0.0 {
                eta
            } else {
                1.0
            },
        }
    }

    /// Reflectance and transmittance of the sheet seen at cosine `cos` (inter-reflections
    /// summed).
    pub fn reflect_transmit(&self, cos: f32) -> (f32, f32) {
        let r = fr_dielectric(cos.abs(), self.eta);
        if r >= 1.0 {
            return (1.0, 0.0);
        }
        let t = 1.0 - r;
        let r = r + t * t * r / (1.0 - r * r);
        (r, 1.0 - r)
    }

    /// Samples the mirror direction (probability `R'`) or the straight-through one with `uc`
    /// uniform in `[0, 1)`; `f` is `R' / |cos wi|` or `T' / |cos wi|`.
    pub fn sample(&self, wo: Vec3, uc: f32, lobes: Lobes) -> Option<BsdfSample> {
        let (r, t) = self.reflect_transmit(wo.z);
        let (pr, pt) = lobes.choose(r, t)?;
        if uc < pr {
            let wi = Vec3::new(-wo.x, -wo.y, wo.z);
            return Some(BsdfSample::new(
                wi,
                Vec3::splat(r / wi.z.abs()),
                pr,
                true,
                false,
                1.0,
            ));
        }
        let wi = -wo;
        Some(BsdfSample::new(
            wi,
            Vec3::splat(t / wi.z.abs()),
            pt,
            true,
            true,
            1.0,
        ))
    }
}
