//! Lambertian reflection, two-sided: it reflects on whichever side `wo` is (pbrt-v4's
//! `DiffuseBxDF` with `SameHemisphere`), sampled by cosine-weighted hemisphere sampling.
use super::{same_hemisphere, BsdfSample, Bxdf, BxdfFlags, Lobes, TransportMode};
use crate::math::{Vec2, Vec3};
use crate::sampling::warp::{cosine_hemisphere_pdf, square_to_cosine_hemisphere};
use crate::spectrum::Spectrum;
use std::f32::consts::FRAC_1_PI;

/// A Lambertian reflector.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Diffuse {
    /// Directional-hemispherical reflectance per channel, in `[0, 1]`.
    pub reflectance: Spectrum,
}

impl Diffuse {
    /// A Lambertian BRDF with reflectance `r` (clamped to `[0, 1]`; NaN reads as 0).
    pub fn new(r: Spectrum) -> Self {
        let clean = |x: f32| if x.is_nan() { 0.0 } else { x.clamp(0.0, 1.0) };
        Diffuse {
            reflectance: r.map(clean),
        }
    }
}

impl Bxdf for Diffuse {
    fn flags(&self) -> BxdfFlags {
        BxdfFlags::REFLECTION | BxdfFlags::DIFFUSE
    }

    /// `R / pi` when `wo` and `wi` are on the same side, else 0.
    fn f(&self, wo: Vec3, wi: Vec3, _: TransportMode) -> Spectrum {
        if same_hemisphere(wo, wi) {
            self.reflectance * FRAC_1_PI
        } else {
            Spectrum::ZERO
        }
    }

    /// Cosine-weighted direction on the side of `wo`; `u` uniform in `[0,1)^2`.
    /// `None` for a black surface (nothing to sample) or when only transmission may be chosen.
    fn sample(
        &self,
        wo: Vec3,
        _: f32,
        u: Vec2,
        _: TransportMode,
        lobes: Lobes,
    ) -> Option<BsdfSample> {
        if self.reflectance.is_black() || lobes == Lobes::Transmission {
            return None;
        }
        let mut wi = square_to_cosine_hemisphere(u);
        if wo.z < 0.0 {
            wi.z = -wi.z;
        }
        Some(BsdfSample {
            wi,
            f: self.reflectance * FRAC_1_PI,
            pdf: cosine_hemisphere_pdf(wi.z.abs()),
            specular: false,
            transmission: false,
            eta: 1.0,
            pdf_is_proportional: false,
            lobe_alpha: f32::INFINITY,
        })
    }

    /// `|cos(wi)| / pi` on the side of `wo`, else 0.
    fn pdf(&self, wo: Vec3, wi: Vec3, _: TransportMode, lobes: Lobes) -> f32 {
        if same_hemisphere(wo, wi) && lobes != Lobes::Transmission {
            cosine_hemisphere_pdf(wi.z.abs())
        } else {
            0.0
        }
    }

    fn reflectance_estimate(&self) -> Spectrum {
        self.reflectance
    }

    fn normal_reflectance(&self) -> Spectrum {
        self.reflectance
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bsdf::testutil::{mean_and_stderr, Rng};
    use std::f32::consts::PI;

    const R: Vec3 = Vec3::new(0.2, 0.5, 0.9);

    #[test]
    fn sampled_pdf_matches_pdf_and_cosine_law() {
        let b = Diffuse::new(Spectrum::from_rgb(R));
        let mut rng = Rng::new(11);
        let n = 200_000;
        for wo in [
            Vec3::new(0.3, 0.1, 0.9).normalize(),
            Vec3::new(0.3, 0.1, -0.9).normalize(),
        ] {
            let mut above_half = 0u32;
            let mut cos_sum = 0.0f64;
            for _ in 0..n {
                let s = b
                    .sample(wo, 0.0, rng.vec2(), TransportMode::Radiance, Lobes::All)
                    .unwrap();
                assert!(s.wi.z * wo.z > 0.0, "sample on the wrong side");
                assert!((s.wi.length() - 1.0).abs() < 1e-5);
                let want = s.wi.z.abs() / PI;
                assert!(
                    (s.pdf - want).abs() < 1e-6
                        && (b.pdf(wo, s.wi, TransportMode::Radiance, Lobes::All) - s.pdf).abs()
                            < 1e-6
                );
                assert_eq!(s.f, b.f(wo, s.wi, TransportMode::Radiance));
                above_half += (s.wi.z.abs() > 0.5) as u32;
                cos_sum += s.wi.z.abs() as f64;
            }
            // Cosine-weighted: P(cos > 1/2) = 3/4, E[cos] = 2/3.
            let p = above_half as f64 / n as f64;
            let sigma = (0.75f64 * 0.25 / n as f64).sqrt();
            assert!((p - 0.75).abs() < 4.0 * sigma, "P(cos > 0.5) = {p}");
            let mean_cos = cos_sum / n as f64;
            let sigma = ((0.5 - 4.0 / 9.0) / n as f64).sqrt(); // Var[cos] = 1/2 - 4/9
            assert!(
                (mean_cos - 2.0 / 3.0).abs() < 4.0 * sigma,
                "E[cos] = {mean_cos}"
            );
        }
    }

    #[test]
    fn hemispherical_integral_is_the_reflectance() {
        // Uniform hemisphere sampling, independent of the BSDF's own sampler.
        let b = Diffuse::new(Spectrum::from_rgb(R));
        let mut rng = Rng::new(5);
        let wo = Vec3::new(-0.4, 0.2, 0.5).normalize();
        let xs: Vec<[f64; 3]> = (0..400_000)
            .map(|_| {
                let wi = rng.hemisphere();
                let v = b.f(wo, wi, TransportMode::Radiance) * wi.z * (2.0 * PI);
                [v[0] as f64, v[1] as f64, v[2] as f64]
            })
            .collect();
        for c in 0..3 {
            let col: Vec<f64> = xs.iter().map(|x| x[c]).collect();
            let (mean, se) = mean_and_stderr(&col);
            println!(
                "Lambertian channel {c}: integral f cos = {mean:.5} +- {se:.5}, R = {}",
                R[c]
            );
            assert!(
                (mean - R[c] as f64).abs() < 3.0 * se,
                "{mean} +- {se} vs {}",
                R[c]
            );
        }
        // Opposite sides never connect.
        assert_eq!(b.f(wo, -wo, TransportMode::Radiance), Spectrum::ZERO);
        assert_eq!(b.pdf(wo, -wo, TransportMode::Radiance, Lobes::All), 0.0);
    }

    #[test]
    fn black_and_bad_reflectance() {
        assert!(Diffuse::new(Spectrum::ZERO)
            .sample(
                Vec3::Z,
                0.0,
                Vec2::splat(0.5),
                TransportMode::Radiance,
                Lobes::All
            )
            .is_none());
        let d = Diffuse::new(Spectrum::from_rgb(Vec3::new(f32::NAN, 2.0, -1.0)));
        assert_eq!(d.reflectance, Spectrum::from_rgb(Vec3::new(0.0, 1.0, 0.0)));
    }
}
