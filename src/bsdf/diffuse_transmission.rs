//! Lambertian reflection and Lambertian transmission (a lamp shade, a leaf; pbrt-v4's
//! `DiffuseTransmissionBxDF`): `f = R / pi` on the side of `wo`, `T / pi` on the other side.
//! Sampling chooses a side in proportion to the largest channel of `R` and of `T`, then a
//! cosine-weighted direction on it.
//!
//! ```text
//! Material "diffusetransmission" "rgb reflectance" [ 0.25 0.25 0.25 ]   # defaults 0.25
//!     "rgb transmittance" [ 0.25 0.25 0.25 ] "float scale" [ 1 ]        # scales both
//! ```
use super::{same_hemisphere, BsdfSample, Bxdf, BxdfFlags, Lobes, TransportMode};
use crate::math::{Vec2, Vec3};
use crate::sampling::warp::{cosine_hemisphere_pdf, square_to_cosine_hemisphere};
use crate::spectrum::Spectrum;
use std::f32::consts::FRAC_1_PI;

/// Lambertian reflection `reflectance` plus Lambertian transmission `transmittance`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DiffuseTransmission {
    pub reflectance: Spectrum,
    pub transmittance: Spectrum,
}

impl DiffuseTransmission {
    /// Both colours clamped to `[0, 1]` (NaN reads as 0), as pbrt-v4 does. Like pbrt-v4,
    /// nothing stops `R + T` from exceeding 1 (the albedo is `R + T`).
    pub fn new(r: Spectrum, t: Spectrum) -> Self {
        let clean = |v: Spectrum| {
            let c = |x: f32| if x.is_nan() { 0.0 } else { x.clamp(0.0, 1.0) };
            v.map(c)
        };
        DiffuseTransmission {
            reflectance: clean(r),
            transmittance: clean(t),
        }
    }

    fn probabilities(&self, lobes: Lobes) -> Option<(f32, f32)> {
        lobes.choose(
            self.reflectance.max_element(),
            self.transmittance.max_element(),
        )
    }
}

impl Bxdf for DiffuseTransmission {
    fn flags(&self) -> BxdfFlags {
        let mut f = BxdfFlags::default();
        if self.reflectance.max_element() > 0.0 {
            f = f | BxdfFlags::REFLECTION | BxdfFlags::DIFFUSE;
        }
        if self.transmittance.max_element() > 0.0 {
            f = f | BxdfFlags::TRANSMISSION | BxdfFlags::DIFFUSE;
        }
        f
    }

    /// `R / pi` on the side of `wo`, `T / pi` on the other side.
    fn f(&self, wo: Vec3, wi: Vec3, _: TransportMode) -> Spectrum {
        if same_hemisphere(wo, wi) {
            self.reflectance * FRAC_1_PI
        } else if wo.z * wi.z < 0.0 {
            self.transmittance * FRAC_1_PI
        } else {
            Spectrum::ZERO
        }
    }

    /// `uc` uniform in `[0, 1)` picks the side, `u` in `[0, 1)^2` the direction.
    fn sample(
        &self,
        wo: Vec3,
        uc: f32,
        u: Vec2,
        mode: TransportMode,
        lobes: Lobes,
    ) -> Option<BsdfSample> {
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
            self.f(wo, wi, mode),
            pdf,
            false,
            !reflect,
            1.0,
        ))
    }

    fn pdf(&self, wo: Vec3, wi: Vec3, _: TransportMode, lobes: Lobes) -> f32 {
        let Some((pr, pt)) = self.probabilities(lobes) else {
            return 0.0;
        };
        let side = if same_hemisphere(wo, wi) { pr } else { pt };
        side * cosine_hemisphere_pdf(wi.z.abs())
    }

    fn reflectance_estimate(&self) -> Spectrum {
        self.reflectance + self.transmittance
    }

    fn normal_reflectance(&self) -> Spectrum {
        self.reflectance
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bsdf::testutil::{chi2_sampler, sampled_albedo, spherical, Rng, SphereBins};
    use std::f32::consts::PI;

    fn wos() -> [Vec3; 4] {
        let (a, b) = (spherical(0.3, 0.2), spherical(1.3, 2.0));
        [a, b, -a, Vec3::new(b.x, b.y, -b.z)]
    }

    #[test]
    fn white_furnace_gives_r_plus_t() {
        let mut rng = Rng::new(41);
        let (r, t) = (Vec3::new(0.2, 0.5, 0.7), Vec3::new(0.8, 0.3, 0.0));
        let b = DiffuseTransmission::new(Spectrum::from_rgb(r), Spectrum::from_rgb(t));
        for wo in wos() {
            for c in 0..3 {
                let (m, se, _) = sampled_albedo(
                    100_000,
                    || {
                        b.sample(
                            wo,
                            rng.f32(),
                            rng.vec2(),
                            TransportMode::Radiance,
                            Lobes::All,
                        )
                    },
                    c,
                );
                let want = (r[c] + t[c]) as f64;
                println!("diffuse transmission furnace channel {c} wo {wo:?}: {m:.5} +- {se:.5} (R + T = {want})");
                assert!((m - want).abs() < 4.0 * se + 1e-6, "{m} vs {want}");
            }
        }
        // A lossless one: R + T = 1 in every channel gives albedo 1, sample by sample.
        let lossless = DiffuseTransmission::new(Spectrum::splat(0.3), Spectrum::splat(0.7));
        for _ in 0..1000 {
            let s = lossless
                .sample(
                    wos()[1],
                    rng.f32(),
                    rng.vec2(),
                    TransportMode::Radiance,
                    Lobes::All,
                )
                .unwrap();
            assert!((s.f[0] * s.wi.z.abs() / s.pdf - 1.0).abs() < 1e-5);
        }
    }

    #[test]
    fn chi_square_reciprocity_and_consistency() {
        let mut rng = Rng::new(42);
        let b = DiffuseTransmission::new(
            Spectrum::from_rgb(Vec3::new(0.2, 0.6, 0.1)),
            Spectrum::from_rgb(Vec3::new(0.5, 0.1, 0.3)),
        );
        let bins = SphereBins { n_z: 20, n_phi: 40 };
        for wo in wos() {
            println!("diffuse transmission wo {wo:?}:");
            let p = chi2_sampler(
                200_000,
                bins,
                || {
                    b.sample(
                        wo,
                        rng.f32(),
                        rng.vec2(),
                        TransportMode::Radiance,
                        Lobes::All,
                    )
                    .map(|s| s.wi)
                },
                |wi| b.pdf(wo, wi, TransportMode::Radiance, Lobes::All) as f64,
            );
            assert!(p > 0.01 / 4.0, "p = {p}");
            for _ in 0..1000 {
                let s = b
                    .sample(
                        wo,
                        rng.f32(),
                        rng.vec2(),
                        TransportMode::Radiance,
                        Lobes::All,
                    )
                    .unwrap();
                assert_eq!(s.f, b.f(wo, s.wi, TransportMode::Radiance));
                assert!(
                    (s.pdf - b.pdf(wo, s.wi, TransportMode::Radiance, Lobes::All)).abs() < 1e-6
                );
                assert_eq!(s.transmission, s.wi.z * wo.z < 0.0);
                assert_eq!(
                    b.f(wo, s.wi, TransportMode::Radiance),
                    b.f(s.wi, wo, TransportMode::Radiance)
                );
            }
        }
        let up = spherical(0.5, 1.0);
        let down = -spherical(0.2, 3.0);
        assert_eq!(b.f(up, down, TransportMode::Radiance), b.transmittance / PI);
        assert_eq!(
            b.f(up, spherical(1.0, 0.0), TransportMode::Radiance),
            b.reflectance / PI
        );
        let f = b.flags();
        assert!(f.has_diffuse() && f.contains(BxdfFlags::REFLECTION | BxdfFlags::TRANSMISSION));
        let t_only = DiffuseTransmission::new(Spectrum::ZERO, Spectrum::ONE).flags();
        assert!(!t_only.contains(BxdfFlags::REFLECTION) && t_only.has_diffuse());
    }
}
