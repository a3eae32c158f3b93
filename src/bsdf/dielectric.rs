//! Smooth dielectric (glass, water): a delta reflection lobe and a delta refraction lobe,
//! chosen in proportion to the Fresnel reflectance `R` and transmittance `T = 1 - R`
//! (pbrt-v4's `DielectricBxDF` for a smooth interface).
//!
//! `eta` is interior over exterior; `wo.z > 0` means the ray arrives from the exterior
//! (entering), `wo.z < 0` from the interior (the relative index then becomes `1 / eta`).
use super::fresnel::{fr_dielectric, refract};
use super::{BsdfSample, TransportMode};
use crate::math::Vec3;

/// A smooth dielectric interface.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Dielectric {
    /// Relative index of refraction, interior / exterior (> 0).
    pub eta: f32,
}

impl Dielectric {
    /// An interface with relative index `eta`; a non-finite or non-positive value reads as 1
    /// (no interface: light passes straight through).
    pub fn new(eta: f32) -> Self {
        Dielectric {
            eta: if eta.is_finite() && eta > 0.0 {
                eta
            } else {
                1.0
            },
        }
    }

    /// Samples reflection (probability `R`) or refraction (probability `T`) with `uc`.
    ///
    /// - `wo`: unit direction towards the viewer (local frame);
    /// - `uc`: uniform in `[0, 1)`;
    /// - `mode`: `Radiance` divides refracted throughput by `etap^2`, `Importance` does not.
    ///
    /// The returned `f` is `R / |cos wi|` or `T / |cos wi|` (times `1 / etap^2` for radiance),
    /// `pdf` the discrete lobe probability.
    pub fn sample(&self, wo: Vec3, uc: f32, mode: TransportMode) -> Option<BsdfSample> {
        let r = fr_dielectric(wo.z, self.eta);
        let t = 1.0 - r;
        if uc < r || t <= 0.0 {
            let wi = Vec3::new(-wo.x, -wo.y, wo.z);
            return Some(BsdfSample {
                wi,
                f: Vec3::splat(r / wi.z.abs()),
                pdf: r,
                specular: true,
                transmission: false,
                eta: 1.0,
            });
        }
        let (wi, etap) = refract(wo, Vec3::Z, self.eta)?;
        let mut ft = t / wi.z.abs();
        if mode == TransportMode::Radiance {
            ft /= etap * etap;
        }
        Some(BsdfSample {
            wi,
            f: Vec3::splat(ft),
            pdf: t,
            specular: true,
            transmission: true,
            eta: etap,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bsdf::testutil::Rng;

    /// Unpolarised Fresnel reflectance from Hecht's s/p amplitude formulas (f64), with the
    /// indices written out: the ray goes from index `n1` into index `n2`.
    fn fresnel_reference(cos_i: f64, n1: f64, n2: f64) -> f64 {
        let sin_t = n1 / n2 * (1.0 - cos_i * cos_i).max(0.0).sqrt();
        if sin_t >= 1.0 {
            return 1.0;
        }
        let cos_t = (1.0 - sin_t * sin_t).sqrt();
        let rs = (n1 * cos_i - n2 * cos_t) / (n1 * cos_i + n2 * cos_t);
        let rp = (n2 * cos_i - n1 * cos_t) / (n2 * cos_i + n1 * cos_t);
        0.5 * (rs * rs + rp * rp)
    }

    #[test]
    fn lobe_frequencies_match_fresnel() {
        let eta = 1.5f32;
        let glass = Dielectric::new(eta);
        let mut rng = Rng::new(21);
        for (theta, inside) in [
            (0.0f32, false),
            (1.0, false),
            (1.45, false),
            (0.3, true),
            (0.7, true),
        ] {
            let z = if inside { -theta.cos() } else { theta.cos() };
            let wo = Vec3::new(theta.sin(), 0.0, z);
            let (n1, n2) = if inside {
                (eta as f64, 1.0)
            } else {
                (1.0, eta as f64)
            };
            let want_r = fresnel_reference(theta.cos() as f64, n1, n2);
            let n = 200_000;
            let mut reflected = 0u32;
            for _ in 0..n {
                let s = glass
                    .sample(wo, rng.f32(), TransportMode::Importance)
                    .unwrap();
                assert!(s.specular);
                if s.transmission {
                    assert!(s.wi.z * wo.z < 0.0);
                    assert!((s.pdf as f64 - (1.0 - want_r)).abs() < 1e-5);
                } else {
                    reflected += 1;
                    assert!(s.wi.z * wo.z > 0.0);
                    assert!((s.pdf as f64 - want_r).abs() < 1e-5);
                }
                // Every lobe has path weight 1 for importance (R/R, T/T).
                let w = s.f.x * s.wi.z.abs() / s.pdf;
                assert!((w - 1.0).abs() < 1e-4, "weight {w}");
            }
            let p = reflected as f64 / n as f64;
            let sigma = (want_r * (1.0 - want_r) / n as f64).sqrt().max(1e-9);
            println!("theta {theta} inside {inside}: reflect freq {p:.5}, R = {want_r:.5}");
            assert!((p - want_r).abs() <= 4.0 * sigma, "freq {p} vs R {want_r}");
        }
    }

    #[test]
    fn radiance_refraction_is_scaled_by_inverse_eta_squared() {
        let eta = 1.5f32;
        let glass = Dielectric::new(eta);
        // uc just below 1 always picks refraction when T > 0.
        for (wo, etap) in [
            (Vec3::new(0.6, 0.0, 0.8), eta),
            (Vec3::new(0.3, 0.0, -(1.0f32 - 0.09).sqrt()), 1.0 / eta),
        ] {
            let rad = glass.sample(wo, 0.9999, TransportMode::Radiance).unwrap();
            let imp = glass.sample(wo, 0.9999, TransportMode::Importance).unwrap();
            assert!(rad.transmission && imp.transmission);
            assert_eq!(rad.wi, imp.wi);
            assert!((rad.eta - etap).abs() < 1e-6);
            let w_rad = rad.f.x * rad.wi.z.abs() / rad.pdf;
            let w_imp = imp.f.x * imp.wi.z.abs() / imp.pdf;
            assert!((w_imp - 1.0).abs() < 1e-5, "importance weight {w_imp}");
            let want = 1.0 / (etap * etap);
            assert!(
                (w_rad - want).abs() < 1e-5,
                "radiance weight {w_rad} vs {want}"
            );
            // Snell on the sampled direction.
            let sin_i = wo.truncate().length();
            let sin_t = rad.wi.truncate().length();
            assert!((sin_t * etap - sin_i).abs() < 1e-5);
        }
    }

    #[test]
    fn total_internal_reflection_always_reflects() {
        let glass = Dielectric::new(1.5);
        let theta = 0.8f32; // beyond asin(1/1.5) = 0.7297
        let wo = Vec3::new(theta.sin(), 0.0, -theta.cos());
        for uc in [0.0f32, 0.5, 0.999_999] {
            let s = glass.sample(wo, uc, TransportMode::Radiance).unwrap();
            assert!(!s.transmission && s.pdf == 1.0);
            assert!((s.wi - Vec3::new(-wo.x, -wo.y, wo.z)).length() < 1e-7);
            assert!((s.f.x * s.wi.z.abs() - 1.0).abs() < 1e-6);
        }
    }

    #[test]
    fn eta_one_passes_straight_through() {
        let glass = Dielectric::new(1.0);
        let wo = Vec3::new(0.9999, 0.0, 0.01).normalize();
        let s = glass.sample(wo, 0.0, TransportMode::Radiance).unwrap();
        assert!(s.transmission && s.pdf == 1.0);
        assert!((s.wi + wo).length() < 1e-6);
        assert_eq!(Dielectric::new(f32::NAN).eta, 1.0);
        assert_eq!(Dielectric::new(-2.0).eta, 1.0);
    }
}
