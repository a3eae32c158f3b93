//! Lambertian reflection and Lambertian transmission (a lamp shade, a leaf; pbrt-v4's
//! `DiffuseTransmissionBxDF`): `f = R / pi` on the side of `wo`, `T / pi` on the other side.
//! Sampling chooses a side in proportion to the largest channel of `R` and of `T`, then a
//! cosine-weighted direction on it.
//!
//! ```text
//! Material "diffusetransmission" "rgb reflectance" [ 0.25 0.25 0.25 ]   # defaults 0.25
//!     "rgb transmittance" [ 0.25 0.25 0.25 ] "float scale" [ 1 ]        # scales both
//! ```
use super::{same_hemisphere, BsdfSample, BxdfFlags, Lobes};
use crate::math::{Vec2, Vec3};
use crate::sampling::warp::{cosine_hemisphere_pdf, square_to_cosine_hemisphere};
use std::f32::consts::FRAC_1_PI;

/// Lambertian reflection `reflectance` plus Lambertian transmission `transmittance`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DiffuseTransmission {
    pub reflectance: Vec3,
    pub transmittance: Vec3,
}

impl DiffuseTransmission {
    /// Both colours clamped to `[0, 1]` (NaN reads as 0), as pbrt-v4 does. Like pbrt-v4,
    /// nothing stops `R + T` from exceeding 1 (the albedo is `R + T`).
    pub fn new(r: Vec3, t: Vec3) -> Self {
        let clean = |v: Vec3| {
            let c = |x: f32| if x.is_nan() { 0.0 } else { x.clamp(0.0, 1.0) };
            Vec3::new(c(v.x), c(v.y), c(v.z))
        };
        DiffuseTransmission {
            reflectance: clean(r),
            transmittance: clean(t),
        }
    }

    pub fn flags(&self) -> BxdfFlags {
        let mut f = BxdfFlags::default();
        if self.reflectance.max_element() > 0.0 {
            f = f | BxdfFlags::REFLECTION | BxdfFlags::DIFFUSE;
        }
        if self.transmittance.max_element() > 0.0 {
            f = f | BxdfFlags::TRANSMISSION | BxdfFlags::DIFFUSE;
        }
        f
    }

    pub fn f(&self, wo: Vec3, wi: Vec3) -> Vec3 {
        if same_hemisphere(wo, wi) {
            self.reflectance * FRAC_1_PI
        } else if wo.z * wi.z < 0.0 {
            self.transmittance * FRAC_1_PI
        } else {
            Vec3::ZERO
        }
    }

    fn probabilities(&self, lobes: Lobes) -> Option<(f32, f32)> {
        lobes.choose(
            self.reflectance.max_element(),
            self.transmittance.max_element(),
        )
    }

    pub fn pdf(&self, wo: Vec3, wi: Vec3, lobes: Lobes) -> f32 {
        let Some((pr, pt)) = self.probabilities(lobes) else {
            return 0.0;
        };
        let side = if same_hemisphere(wo, wi) { pr } else { pt };
        side * cosine_hemisphere_pdf(wi.z.abs())
    }

    /// `uc` uniform in `[0, 1)` picks the side, `u` in `[0, 1)^2` the direction.
    pub fn sample(&self, wo: Vec3, uc: f32, u: Vec2, lobes: Lobes) -> Option<BsdfSample> {
        let (pr, pt) = self.probabilities(lobes)?;
        let mut wi = square_to_cosine_hemisphere(u);
        let reflect = uc < pr;
        // Reflection stays on the side of wo, transmission goes to the other one.
        if (wo.z < 0.0) == reflect {
            wi.z = -wi.z;
        }
        let p = if reflect { pr } else { pt };
        let pdf = p * cosine_hemisphere_pdf(wi.z.abs());
        Some(BsdfSample::new(
            wi,
            self.f(wo, wi),
            pdf,
            false,
            !reflect,
            1.0,
        ))
    }
}
