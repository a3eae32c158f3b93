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
use super::{BsdfSample, Bxdf, BxdfFlags, Lobes, TransportMode};
use crate::math::{Vec2, Vec3};
use crate::spectrum::Spectrum;

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
}

impl Bxdf for ThinDielectric {
    /// Samples the mirror direction (probability `R'`) or the straight-through one with `uc`
    /// uniform in `[0, 1)`; `f` is `R' / |cos wi|` or `T' / |cos wi|`.
    fn sample(
        &self,
        wo: Vec3,
        uc: f32,
        _: Vec2,
        _: TransportMode,
        lobes: Lobes,
    ) -> Option<BsdfSample> {
        let (r, t) = self.reflect_transmit(wo.z);
        let (pr, pt) = lobes.choose(r, t)?;
        if uc < pr {
            let wi = Vec3::new(-wo.x, -wo.y, wo.z);
            return Some(BsdfSample::new(
                wi,
                Spectrum::splat(r / wi.z.abs()),
                pr,
                true,
                false,
                1.0,
            ));
        }
        let wi = -wo;
        Some(BsdfSample::new(
            wi,
            Spectrum::splat(t / wi.z.abs()),
            pt,
            true,
            true,
            1.0,
        ))
    }

    /// Both lobes are deltas: 0.
    fn f(&self, _: Vec3, _: Vec3, _: TransportMode) -> Spectrum {
        Spectrum::ZERO
    }

    fn pdf(&self, _: Vec3, _: Vec3, _: TransportMode, _: Lobes) -> f32 {
        0.0
    }

    fn flags(&self) -> BxdfFlags {
        BxdfFlags::REFLECTION | BxdfFlags::TRANSMISSION | BxdfFlags::SPECULAR
    }

    fn reflectance_estimate(&self) -> Spectrum {
        Spectrum::ONE
    }

    fn normal_reflectance(&self) -> Spectrum {
        Spectrum::splat(self.reflect_transmit(1.0).0)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bsdf::testutil::{spherical, Rng};
    use crate::bsdf::{Bsdf, TransportMode};
    use crate::math::Vec2;

    /// The sheet's reflectance by following the bounces one by one (energy bookkeeping, not
    /// the closed form): `r` is one interface's reflectance, the same from either side.
    fn bounce_by_bounce(r: f64) -> f64 {
        let t = 1.0 - r;
        let (mut reflected, mut inside) = (r, t);
        for _ in 0..10_000 {
            // Hits the far interface: t leaves, r comes back; then the near one.
            inside *= r;
            reflected += inside * t;
            inside *= r;
        }
        reflected
    }

    #[test]
    fn reflectance_sums_the_bounces_and_conserves_energy() {
        let sheet = ThinDielectric::new(1.5);
        for theta in [0.0f32, 0.4, 0.9, 1.3, 1.55] {
            let cos = theta.cos();
            let r1 = crate::bsdf::fresnel::fr_dielectric(cos, 1.5) as f64;
            let (r, t) = sheet.reflect_transmit(cos);
            let want = bounce_by_bounce(r1);
            println!("thin dielectric theta {theta}: R' {r:.6} (bounces {want:.6}), T' {t:.6}");
            assert!((r as f64 - want).abs() < 1e-6, "{r} vs {want}");
            assert_eq!(r + t, 1.0);
            // Same seen from below.
            assert_eq!(sheet.reflect_transmit(-cos), (r, t));
        }
    }

    #[test]
    fn white_furnace_and_lobe_frequencies() {
        // Every sample weighs exactly 1 (R'/R', T'/T'), so the albedo is 1; the lobes are
        // chosen with frequencies R' and T'.
        let b = Bsdf::ThinDielectric(ThinDielectric::new(1.5));
        let mut rng = Rng::new(31);
        for (theta, below) in [(0.2f32, false), (1.2, false), (0.7, true)] {
            let w = spherical(theta, 0.6);
            let wo = if below { Vec3::new(w.x, w.y, -w.z) } else { w };
            let (r, _) = ThinDielectric::new(1.5).reflect_transmit(wo.z);
            let n = 100_000;
            let mut reflected = 0;
            for _ in 0..n {
                let mode = TransportMode::Radiance;
                let s = b.sample(wo, rng.f32(), Vec2::ZERO, mode).unwrap();
                assert!(s.specular && s.eta == 1.0);
                assert!((s.f[0] * s.wi.z.abs() / s.pdf - 1.0).abs() < 1e-5);
                if s.transmission {
                    assert_eq!(s.wi, -wo);
                } else {
                    reflected += 1;
                    assert_eq!(s.wi, Vec3::new(-wo.x, -wo.y, wo.z));
                }
            }
            let freq = reflected as f64 / n as f64;
            let sigma = (r as f64 * (1.0 - r as f64) / n as f64).sqrt();
            assert!((freq - r as f64).abs() < 4.0 * sigma, "{freq} vs {r}");
            assert_eq!(b.f(wo, -wo, TransportMode::Radiance), Spectrum::ZERO);
            assert_eq!(b.pdf(wo, -wo), 0.0);
        }
        assert!(b.flags().is_specular_only());
    }

    /// Mitsuba 3's `thindielectric` (scenes/mitsuba/bsdfs.json): the probability of each lobe
    /// and its direction.
    #[test]
    fn matches_mitsuba() {
        let text = include_str!("../../scenes/mitsuba/bsdfs.json");
        let data: serde_json::Value = serde_json::from_str(text).unwrap();
        let v3 = |v: &serde_json::Value| {
            let a: Vec<f32> = (0..3).map(|i| v[i].as_f64().unwrap() as f32).collect();
            Vec3::new(a[0], a[1], a[2])
        };
        let rows = data["thindielectric"].as_array().unwrap();
        let mut worst = 0.0f64;
        for row in rows {
            let sheet = ThinDielectric::new(row["eta"].as_f64().unwrap() as f32);
            let wo = v3(&row["wo"]).normalize();
            let refl = sheet
                .sample(wo, 0.0, Vec2::ZERO, TransportMode::Radiance, Lobes::All)
                .unwrap();
            let trans = sheet
                .sample(
                    wo,
                    0.999_999,
                    Vec2::ZERO,
                    TransportMode::Radiance,
                    Lobes::All,
                )
                .unwrap();
            for (s, key) in [(refl, "reflect"), (trans, "transmit")] {
                let want = row[format!("{key}_pdf")].as_f64().unwrap();
                worst = worst.max((s.pdf as f64 - want).abs());
                assert!((s.pdf as f64 - want).abs() < 1e-6, "{row}: {key} {}", s.pdf);
                let wi = v3(&row[format!("{key}_wi")]);
                assert!((s.wi - wi).length() < 1e-6, "{row}: {key} {:?}", s.wi);
                let weight = row[format!("{key}_weight")].as_f64().unwrap();
                assert!((s.f[0] * s.wi.z.abs() / s.pdf - weight as f32).abs() < 1e-5);
            }
        }
        println!(
            "{} directions: worst lobe probability difference {worst:.2e}",
            rows.len()
        );
        assert!(rows.len() >= 10);
    }
}
