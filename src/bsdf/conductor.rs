//! Conductors (metals): a perfect mirror when the roughness is effectively zero, otherwise
//! the Torrance-Sparrow microfacet BRDF `D F G / (4 cos_o cos_i)` over an anisotropic
//! Trowbridge-Reitz distribution, sampled through the visible normals (pbrt-v4's
//! `ConductorBxDF`). The Fresnel term is the exact complex-index one, per RGB channel.
//!
//! Two-sided like pbrt: a `wo` below the surface sees the mirror image of the lobe.
use super::fresnel::{fr_complex, reflect};
use super::microfacet::TrowbridgeReitz;
use super::{same_hemisphere, BsdfSample, Bxdf, BxdfFlags, Lobes, TransportMode};
use crate::math::{Vec2, Vec3};
use crate::spectrum::Spectrum;

/// A smooth or rough conductor.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Conductor {
    /// Real part of the relative complex index, per channel.
    pub eta: Spectrum,
    /// Imaginary part (absorption) of the relative complex index, per channel.
    pub k: Spectrum,
    /// Microfacet distribution; smooth when both roughnesses are below 1e-3.
    pub distrib: TrowbridgeReitz,
}

impl Conductor {
    /// A conductor with complex index `eta + i k` and roughness `alpha_u` (local x),
    /// `alpha_v` (local y). Non-finite or negative index components read as 0 (`eta` as 1).
    pub fn new(eta: Spectrum, k: Spectrum, alpha_u: f32, alpha_v: f32) -> Self {
        let clean = |v: Spectrum, default: f32| {
            let c = |x: f32| {
                if x.is_finite() && x >= 0.0 {
                    x
                } else {
                    default
                }
            };
            v.map(c)
        };
        Conductor {
            eta: clean(eta, 1.0),
            k: clean(k, 0.0),
            distrib: TrowbridgeReitz::new(alpha_u, alpha_v),
        }
    }

    /// True for the perfect-mirror case (a delta lobe).
    pub fn is_smooth(&self) -> bool {
        self.distrib.effectively_smooth()
    }

    /// Fresnel reflectance for a microfacet at incident cosine `cos`.
    fn fresnel(&self, cos: f32) -> Spectrum {
        fr_complex(cos.abs(), self.eta, self.k)
    }
}

impl Bxdf for Conductor {
    fn flags(&self) -> BxdfFlags {
        if self.is_smooth() {
            BxdfFlags::REFLECTION | BxdfFlags::SPECULAR
        } else {
            BxdfFlags::REFLECTION | BxdfFlags::GLOSSY
        }
    }

    /// The microfacet BRDF value; 0 for the mirror and across the surface.
    fn f(&self, wo: Vec3, wi: Vec3, _: TransportMode) -> Spectrum {
        if self.is_smooth() || !same_hemisphere(wo, wi) {
            return Spectrum::ZERO;
        }
        let (cos_o, cos_i) = (wo.z.abs(), wi.z.abs());
        if cos_o == 0.0 || cos_i == 0.0 {
            return Spectrum::ZERO;
        }
        let wm = wi + wo;
        if wm.length_squared() == 0.0 {
            return Spectrum::ZERO;
        }
        let wm = wm.normalize();
        let d = &self.distrib;
        self.fresnel(wo.dot(wm)) * (d.d(wm) * d.g(wo, wi) / (4.0 * cos_i * cos_o))
    }

    /// Density of [`Self::sample`] for `wi` (solid angle); 0 for the mirror.
    fn pdf(&self, wo: Vec3, wi: Vec3, _: TransportMode, lobes: Lobes) -> f32 {
        if self.is_smooth() || !same_hemisphere(wo, wi) || lobes == Lobes::Transmission {
            return 0.0;
        }
        let wm = wo + wi;
        if wm.length_squared() == 0.0 {
            return 0.0;
        }
        let wm = wm.normalize();
        let wm = if wm.z < 0.0 { -wm } else { wm };
        let dot = wo.dot(wm).abs();
        if dot == 0.0 {
            return 0.0;
        }
        self.distrib.pdf(wo, wm) / (4.0 * dot)
    }

    /// Samples the mirror direction, or a visible microfacet normal and the reflection about
    /// it; `u` uniform in `[0,1)^2`. `None` when the reflection leaves through the surface
    /// or only transmission may be chosen.
    fn sample(
        &self,
        wo: Vec3,
        _: f32,
        u: Vec2,
        _: TransportMode,
        lobes: Lobes,
    ) -> Option<BsdfSample> {
        if lobes == Lobes::Transmission {
            return None;
        }
        if self.is_smooth() {
            let wi = Vec3::new(-wo.x, -wo.y, wo.z);
            let cos = wi.z.abs();
            return Some(BsdfSample {
                wi,
                f: self.fresnel(cos) / cos,
                pdf: 1.0,
                specular: true,
                transmission: false,
                eta: 1.0,
                pdf_is_proportional: false,
                lobe_alpha: 0.0,
            });
        }
        if wo.z == 0.0 {
            return None;
        }
        let wm = self.distrib.sample_wm(wo, u);
        let wi = reflect(wo, wm);
        if !same_hemisphere(wo, wi) {
            return None;
        }
        let dot = wo.dot(wm).abs();
        let pdf = self.distrib.pdf(wo, wm) / (4.0 * dot);
        let (cos_o, cos_i) = (wo.z.abs(), wi.z.abs());
        if cos_i == 0.0 || dot == 0.0 {
            return None;
        }
        let d = &self.distrib;
        let f = self.fresnel(dot) * (d.d(wm) * d.g(wo, wi) / (4.0 * cos_i * cos_o));
        Some(BsdfSample {
            wi,
            f,
            pdf,
            specular: false,
            transmission: false,
            eta: 1.0,
            pdf_is_proportional: false,
            lobe_alpha: d.alpha_x().min(d.alpha_y()),
        })
    }

    fn reflectance_estimate(&self) -> Spectrum {
        self.normal_reflectance()
    }

    /// Fresnel reflectance at normal incidence.
    fn normal_reflectance(&self) -> Spectrum {
        self.fresnel(1.0)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bsdf::testutil::{integrate_normals, mean_and_stderr, spherical, Rng};
    use std::f64::consts::PI;

    const ALPHAS: [(f32, f32); 6] = [
        (0.05, 0.05),
        (0.1, 0.1),
        (0.3, 0.3),
        (1.0, 1.0),
        (0.05, 0.3),
        (0.5, 0.1),
    ];
    const GOLD_ETA: Spectrum = Spectrum(glam::Vec4::new(0.143, 0.374, 1.442, 0.374));
    const GOLD_K: Spectrum = Spectrum(glam::Vec4::new(3.983, 2.385, 1.603, 2.385));

    /// Directional albedo `integral f(wo, wi) cos_i dwi` (green channel) by quadrature over
    /// the half vectors (`dwi = 4 |wo.wm| dwm`), without using the sampler or `pdf`.
    fn albedo_quadrature(c: &Conductor, wo: Vec3) -> f64 {
        let d = c.distrib;
        integrate_normals(d.alpha_x().min(d.alpha_y()), 3000, 512, |wm| {
            let wi = reflect(wo, wm);
            if wi.z <= 0.0 {
                return 0.0;
            }
            let f = c.f(wo, wi.normalize(), TransportMode::Radiance)[1] as f64;
            f * wi.z as f64 * 4.0 * wo.dot(wm).abs() as f64
        })
    }

    /// Monte Carlo albedo `E[f cos / pdf]` with the BSDF's own sampler (green channel), and
    /// the per-sample consistency of `sample` with `f` and `pdf`.
    fn albedo_sampled(c: &Conductor, wo: Vec3, n: usize, rng: &mut Rng) -> (f64, f64, f64) {
        let mut max_weight = 0.0f64;
        let xs: Vec<f64> = (0..n)
            .map(|_| {
                let Some(s) = c.sample(wo, 0.0, rng.vec2(), TransportMode::Radiance, Lobes::All)
                else {
                    return 0.0;
                };
                assert!(s.wi.z * wo.z > 0.0 && !s.specular && s.pdf > 0.0);
                let pdf = c.pdf(wo, s.wi, TransportMode::Radiance, Lobes::All);
                assert!((pdf - s.pdf).abs() <= 1e-3 * s.pdf, "{pdf} vs {}", s.pdf);
                let f = c.f(wo, s.wi, TransportMode::Radiance);
                assert!((f - s.f).abs().max_element() <= 1e-3 * s.f.max_element());
                let w = (s.f[1] * s.wi.z.abs() / s.pdf) as f64;
                max_weight = max_weight.max(w);
                w
            })
            .collect();
        let (m, se) = mean_and_stderr(&xs);
        (m, se, max_weight)
    }

    #[test]
    fn sampled_albedo_matches_quadrature() {
        let mut rng = Rng::new(99);
        for &(ax, ay) in &ALPHAS {
            let c = Conductor::new(GOLD_ETA, GOLD_K, ax, ay);
            for (theta, phi) in [(0.1f32, 0.0f32), (0.8, 1.0), (1.3, 2.5)] {
                let wo = spherical(theta, phi);
                let want = albedo_quadrature(&c, wo);
                let (mean, se, _) = albedo_sampled(&c, wo, 100_000, &mut rng);
                println!(
                    "gold alpha ({ax}, {ay}) theta_o {theta}: quadrature {want:.5}, sampled {mean:.5} +- {se:.5}"
                );
                assert!(
                    (mean - want).abs() < 3.0 * se + 1e-3,
                    "alpha ({ax},{ay}) theta {theta}: sampled {mean} +- {se} vs {want}"
                );
            }
        }
    }

    #[test]
    fn perfect_reflector_gains_no_energy() {
        // eta = 1, k huge: F = 1 to within 1e-3 at every angle that matters.
        let mut rng = Rng::new(4);
        let k = Spectrum::splat(1e4);
        assert!(fr_complex(0.05, Spectrum::ONE, k).min_element() > 0.999);
        for &(ax, ay) in &ALPHAS {
            let c = Conductor::new(Spectrum::ONE, k, ax, ay);
            for theta in [0.0f32, 0.5, 1.0, 1.4] {
                let wo = spherical(theta, 0.4);
                let quad = albedo_quadrature(&c, wo);
                let (mean, se, max_w) = albedo_sampled(&c, wo, 50_000, &mut rng);
                println!(
                    "white furnace alpha ({ax}, {ay}) theta_o {theta}: albedo {quad:.5} (sampled {mean:.5} +- {se:.5}), max weight {max_w:.5}"
                );
                // Each sample's weight is F G / G1 <= 1; so is the albedo.
                assert!(max_w <= 1.0 + 1e-4, "weight {max_w}");
                assert!(quad <= 1.0 + 2e-3, "albedo {quad}");
                // Close to 1 when smooth-ish; the loss left is GGX's long tail reflecting
                // below the horizon plus shadowing (single scattering only).
                if ax.max(ay) <= 0.05 && theta <= 1.0 {
                    assert!(quad > 0.99, "smooth-ish albedo only {quad}");
                }
                if ax.max(ay) <= 0.1 && theta <= 0.5 {
                    assert!(quad > 0.98, "smooth-ish albedo only {quad}");
                }
            }
        }
    }

    #[test]
    fn white_furnace_alpha_one_normal_incidence_is_one_minus_ln2() {
        // alpha = 1, wo = z, F = 1: the visible normals are D cos = cos / pi, wi = reflect at
        // 2 theta_m, weight G / G1 = 1 / (1 + Lambda(wi)) = 2 cos(2 theta_m) / (1 + cos(2 theta_m))
        // for theta_m < pi/4; with u = cos(2 theta_m) the albedo is int_0^1 u / (1 + u) du
        // = 1 - ln 2.
        let want = 1.0 - std::f64::consts::LN_2;
        let c = Conductor::new(Spectrum::ONE, Spectrum::splat(1e4), 1.0, 1.0);
        let quad = albedo_quadrature(&c, Vec3::Z);
        let (mean, se, _) = albedo_sampled(&c, Vec3::Z, 200_000, &mut Rng::new(12));
        println!("alpha 1 furnace: 1 - ln 2 = {want:.5}, quadrature {quad:.5}, sampled {mean:.5} +- {se:.5}");
        assert!((quad - want).abs() < 1e-3, "{quad}");
        assert!((mean - want).abs() < 3.0 * se, "{mean} +- {se}");
    }

    #[test]
    fn pdf_integrates_to_at_most_one() {
        for &(ax, ay) in &[(0.1f32, 0.1f32), (0.3, 0.3), (1.0, 1.0), (0.5, 0.1)] {
            let c = Conductor::new(GOLD_ETA, GOLD_K, ax, ay);
            for theta in [0.2f32, 1.0, 1.4] {
                let wo = spherical(theta, 0.3);
                // Midpoint rule over the upper hemisphere of wi.
                let (nt, np) = (1500, 1500);
                let mut sum = 0.0f64;
                for i in 0..nt {
                    let t = (i as f64 + 0.5) / nt as f64 * PI / 2.0;
                    let jac = t.sin() * (PI / 2.0 / nt as f64) * (2.0 * PI / np as f64);
                    for j in 0..np {
                        let p = (j as f64 + 0.5) / np as f64 * 2.0 * PI;
                        sum += c.pdf(
                            wo,
                            spherical(t as f32, p as f32),
                            TransportMode::Radiance,
                            Lobes::All,
                        ) as f64
                            * jac;
                    }
                }
                // The same mass from the normals' side: visible normals whose reflection stays
                // above the surface.
                let d = c.distrib;
                let kept = integrate_normals(ax.min(ay), 3000, 512, |wm| {
                    if reflect(wo, wm).z > 0.0 {
                        d.pdf(wo, wm) as f64
                    } else {
                        0.0
                    }
                });
                println!("alpha ({ax}, {ay}) theta_o {theta}: integral pdf = {sum:.5} (normals: {kept:.5})");
                assert!(sum <= 1.0 + 2e-3, "{sum}");
                assert!((sum - kept).abs() < 5e-3, "{sum} vs {kept}");
            }
            // Nothing below the surface.
            let mut rng = Rng::new(1);
            for _ in 0..1000 {
                let wi = rng.sphere();
                let wi = Vec3::new(wi.x, wi.y, -wi.z.abs());
                assert_eq!(c.pdf(Vec3::Z, wi, TransportMode::Radiance, Lobes::All), 0.0);
                assert_eq!(c.f(Vec3::Z, wi, TransportMode::Radiance), Spectrum::ZERO);
            }
        }
    }

    #[test]
    fn reciprocity_and_two_sidedness() {
        let mut rng = Rng::new(8);
        for &(ax, ay) in &ALPHAS {
            let c = Conductor::new(GOLD_ETA, GOLD_K, ax, ay);
            for _ in 0..5000 {
                let wo = rng.hemisphere();
                let wi = rng.hemisphere();
                let a = c.f(wo, wi, TransportMode::Radiance);
                let b = c.f(wi, wo, TransportMode::Radiance);
                assert!(
                    (a - b).abs().max_element() <= 1e-4 * a.max_element().max(1e-3),
                    "{a:?} vs {b:?}"
                );
                // Seen from below, the lobe is the mirror image.
                let flip = |v: Vec3| Vec3::new(v.x, v.y, -v.z);
                let m = c.f(flip(wo), flip(wi), TransportMode::Radiance);
                assert!((a - m).abs().max_element() <= 1e-5 * a.max_element().max(1e-3));
                assert!(
                    (c.pdf(wo, wi, TransportMode::Radiance, Lobes::All)
                        - c.pdf(flip(wo), flip(wi), TransportMode::Radiance, Lobes::All))
                    .abs()
                        <= 1e-4 * c.pdf(wo, wi, TransportMode::Radiance, Lobes::All).max(1e-3)
                );
            }
            let below = Vec3::new(0.3, -0.2, -0.9).normalize();
            for _ in 0..100 {
                if let Some(s) =
                    c.sample(below, 0.0, rng.vec2(), TransportMode::Radiance, Lobes::All)
                {
                    assert!(s.wi.z < 0.0);
                }
            }
        }
    }

    #[test]
    fn microfacet_brdf_matches_closed_form_at_normal_incidence() {
        // wo = wi = z: wm = z, D = 1 / (pi ax ay), G = 1, so f = F(1) / (4 pi ax ay).
        let (ax, ay) = (0.2f32, 0.4f32);
        let c = Conductor::new(GOLD_ETA, GOLD_K, ax, ay);
        let want = fr_complex(1.0, GOLD_ETA, GOLD_K) / (4.0 * std::f32::consts::PI * ax * ay);
        let got = c.f(Vec3::Z, Vec3::Z, TransportMode::Radiance);
        assert!((got - want).abs().max_element() < 1e-5 * want.max_element());
    }

    /// Mitsuba 3's `roughconductor` (GGX, visible normals, gold) at fixed pairs
    /// (scenes/mitsuba/bsdfs.json, scripts/mitsuba_bsdfs.py), per channel; Mitsuba's separable
    /// masking is converted to the height-correlated one from its own G1 values (see
    /// `rough_dielectric_matches_mitsuba`).
    #[test]
    fn rough_conductor_matches_mitsuba() {
        let text = include_str!("../../scenes/mitsuba/bsdfs.json");
        let data: serde_json::Value = serde_json::from_str(text).unwrap();
        let v3 = |v: &serde_json::Value| {
            let a: Vec<f32> = (0..3).map(|i| v[i].as_f64().unwrap() as f32).collect();
            Vec3::new(a[0], a[1], a[2])
        };
        let rows = data["roughconductor"].as_array().unwrap();
        let (mut worst_f, mut worst_pdf) = (0.0f64, 0.0f64);
        for r in rows {
            let num = |k: &str| r[k].as_f64().unwrap();
            let c = Conductor::new(
                Spectrum::from_rgb(v3(&r["eta"])),
                Spectrum::from_rgb(v3(&r["k"])),
                num("alpha_u") as f32,
                num("alpha_v") as f32,
            );
            let (wo, wi) = (v3(&r["wo"]).normalize(), v3(&r["wi"]).normalize());
            let (g1o, g1i) = (num("g1_wo"), num("g1_wi"));
            let g_hc = 1.0 / (1.0 / g1o + 1.0 / g1i - 1.0);
            let got = c.f(wo, wi, TransportMode::Radiance) * wi.z;
            for ch in 0..3 {
                let want = r["f_cos"][ch].as_f64().unwrap() / (g1o * g1i) * g_hc;
                let rel = (got[ch] as f64 - want).abs() / want.abs().max(1e-4);
                worst_f = worst_f.max(rel);
                assert!(
                    rel < 2e-3,
                    "{r}: channel {ch}: {} vs Mitsuba {want}",
                    got[ch]
                );
            }
            let pdf = c.pdf(wo, wi, TransportMode::Radiance, Lobes::All) as f64;
            let rel = (pdf - num("pdf")).abs() / num("pdf").max(1e-4);
            worst_pdf = worst_pdf.max(rel);
            assert!(rel < 2e-3, "{r}: pdf {pdf} vs Mitsuba {}", num("pdf"));
        }
        println!(
            "{} pairs: worst relative difference f {worst_f:.2e}, pdf {worst_pdf:.2e}",
            rows.len()
        );
        assert!(rows.len() >= 30);
    }
}
