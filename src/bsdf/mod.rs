//! Scattering functions (BSDFs) for the materials a scene can name, in pbrt-v4's conventions.
//!
//! Everything works in the local shading frame (z = shading normal). `wo` points away from
//! the surface towards the viewer (or the previous path vertex), `wi` towards the light (or
//! the next vertex); both are unit vectors. Values are [`Spectrum`]s (RGB or four wavelengths).
//!
//! Each model is one file implementing the [`Bxdf`] interface (`bxdf.rs`); [`Bsdf`] is the
//! closed enum over them that integrators call (one dispatch per method). The materials of
//! a scene (`crate::material`) build them per hit:
//!
//! ```text
//! diffuse -> Diffuse          dielectric -> Dielectric (smooth or GGX)
//! conductor -> Conductor      thindielectric -> ThinDielectric
//! diffusetransmission -> DiffuseTransmission
//! coateddiffuse -> CoatedDiffuse = Layered<Dielectric, Diffuse>
//! coatedconductor -> CoatedConductor = Layered<Dielectric, Conductor>
//! ```
//!
//! The coated BSDFs ([`layered`]) are stochastic: `f` and `pdf` are deterministic Monte Carlo
//! estimates (random numbers hashed from the query), and their samples carry
//! `pdf_is_proportional` (use [`Bsdf::mis_pdf`] for multiple importance sampling).
//!
//! Delta lobes (smooth glass, mirrors) follow pbrt-v4: `f` is the Fresnel weight divided by
//! `|cos wi|` (and by `eta^2` for radiance through a refraction), `pdf` the discrete lobe
//! probability, so `f |cos wi| / pdf` is the path throughput weight; `f()` and `pdf()` are 0
//! for them.
mod bxdf;
pub mod conductor;
pub mod dielectric;
pub mod diffuse;
pub mod diffuse_transmission;
pub mod fresnel;
pub mod layered;
pub mod microfacet;
pub mod thin_dielectric;
mod warp;

#[cfg(test)]
pub(crate) mod testutil;

pub use bxdf::{BsdfSample, Bxdf, BxdfFlags, Lobes, TransportMode};
pub use conductor::Conductor;
pub use dielectric::Dielectric;
pub use diffuse::Diffuse;
pub use diffuse_transmission::DiffuseTransmission;
pub use layered::{CoatedConductor, CoatedDiffuse};
pub use microfacet::TrowbridgeReitz;
pub use thin_dielectric::ThinDielectric;

use crate::math::{Vec2, Vec3};
use crate::spectrum::Spectrum;

/// pbrt-v4's conductor from reflectance: k = 2 sqrt(r) / sqrt(1 - r), with r at most 1 - 1e-7
/// (so that k stays finite): its normal-incidence reflectance with eta = 1 is r.
pub fn k_from_reflectance(r: Spectrum) -> Spectrum {
    // In f64: 1 - 1e-7 is not representable in f32 (it would round to 1 - 1.19e-7).
    let f = |r: f32| {
        let r = (r as f64).clamp(0.0, 1.0 - 1e-7);
        (2.0 * r.sqrt() / (1.0 - r).sqrt()) as f32
    };
    r.map(f)
}

/// Calls `$call` on the model inside a [`Bsdf`] (one closed-enum dispatch per method).
macro_rules! dispatch {
    ($bsdf:expr, $b:ident => $call:expr) => {
        match $bsdf {
            Bsdf::Diffuse($b) => $call,
            Bsdf::Dielectric($b) => $call,
            Bsdf::Conductor($b) => $call,
            Bsdf::ThinDielectric($b) => $call,
            Bsdf::DiffuseTransmission($b) => $call,
            Bsdf::CoatedDiffuse($b) => $call,
            Bsdf::CoatedConductor($b) => $call,
        }
    };
}

/// The BSDF at a surface point (a closed set; no dynamic dispatch).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Bsdf {
    Diffuse(Diffuse),
    Dielectric(Dielectric),
    Conductor(Conductor),
    ThinDielectric(ThinDielectric),
    DiffuseTransmission(DiffuseTransmission),
    CoatedDiffuse(CoatedDiffuse),
    CoatedConductor(CoatedConductor),
}

/// True when `a` and `b` are strictly on the same side of the surface.
pub(crate) fn same_hemisphere(a: Vec3, b: Vec3) -> bool {
    a.z * b.z > 0.0
}

impl Bsdf {
    /// BSDF value for the pair `(wo, wi)`; 0 for delta lobes. `mode` matters for refraction
    /// through a rough dielectric (radiance is scaled by `1 / eta'^2`) and for the layered
    /// BSDFs; the coated BSDFs' value is a deterministic Monte Carlo estimate.
    pub fn f(&self, wo: Vec3, wi: Vec3, mode: TransportMode) -> Spectrum {
        if wo.z == 0.0 {
            return Spectrum::ZERO;
        }
        dispatch!(self, b => b.f(wo, wi, mode))
    }

    /// Solid-angle density with which [`Self::sample`] picks `wi`; 0 for delta lobes. For the
    /// coated BSDFs, pbrt-v4's stochastic estimate of it (see [`layered`]).
    pub fn pdf(&self, wo: Vec3, wi: Vec3) -> f32 {
        if wo.z == 0.0 {
            return 0.0;
        }
        let mode = TransportMode::Radiance; // no density here depends on it
        dispatch!(self, b => b.pdf(wo, wi, mode, Lobes::All))
    }

    /// Samples an incident direction for `wo`.
    ///
    /// - `uc`: uniform in `[0,1)`, picks the lobe (dielectric reflection vs refraction);
    /// - `u`: uniform in `[0,1)^2`, picks the direction within a lobe;
    /// - `mode`: radiance or importance transport.
    ///
    /// `None` when nothing can be sampled (grazing `wo`, black surface, a microfacet
    /// reflection leaving through the surface), never a sample with zero `f` or `pdf`.
    pub fn sample(&self, wo: Vec3, uc: f32, u: Vec2, mode: TransportMode) -> Option<BsdfSample> {
        if wo.z == 0.0 || !wo.is_finite() {
            return None;
        }
        let s = dispatch!(self, b => b.sample(wo, uc, u, mode, Lobes::All))?;
        s.is_valid().then_some(s)
    }

    /// The density to weigh a sample `s` of this BSDF by in multiple importance sampling: 0
    /// for a delta lobe, [`Self::pdf`] when the sample's own pdf is only proportional (the
    /// coated BSDFs: the light-sampling side uses [`Self::pdf`] too, so the weights still sum
    /// to one), else the sample's pdf.
    pub fn mis_pdf(&self, wo: Vec3, s: &BsdfSample) -> f32 {
        if s.specular {
            0.0
        } else if s.pdf_is_proportional {
            self.pdf(wo, s.wi)
        } else {
            s.pdf
        }
    }

    /// The lobes this BSDF has.
    pub fn flags(&self) -> BxdfFlags {
        dispatch!(self, b => b.flags())
    }

    /// The smaller GGX alpha of a single rough microfacet lobe (a rough conductor or
    /// dielectric), `None` for every other BSDF: what decides where photons are stored on
    /// glossy surfaces (see `photon::trace::is_receiver`). The coated BSDFs are left out: their
    /// `f` is a random walk, too costly to evaluate once per photon of an estimate.
    pub fn glossy_alpha(&self) -> Option<f32> {
        let d = match self {
            Bsdf::Conductor(c) if !c.is_smooth() => c.distrib,
            Bsdf::Dielectric(d) if !d.is_smooth() => d.distrib,
            _ => return None,
        };
        Some(d.alpha_x().min(d.alpha_y()))
    }

    /// Whether the photon mapper splits this BSDF into a traced coat and a body estimated from
    /// photons ([`Self::f_coat`] + [`Self::f_body`]): a coated surface with a diffuse part (a
    /// `coateddiffuse`, or a `coatedconductor` whose slab scatters). Other BSDFs are one part.
    pub fn has_coat(&self) -> bool {
        match self {
            Bsdf::CoatedDiffuse(_) => true,
            Bsdf::CoatedConductor(b) => b.flags().has_diffuse(),
            _ => false,
        }
    }

    /// One Lambertian reflection lobe (`f` the same for every pair on the side of `wo`): the
    /// photon estimates can use irradiance times `f` towards the normal.
    pub fn is_lambertian(&self) -> bool {
        matches!(self, Bsdf::Diffuse(_))
    }

    /// The index of a coat's dielectric interface; `None` without a coat.
    pub fn coat_eta(&self) -> Option<f32> {
        match self {
            Bsdf::CoatedDiffuse(b) => Some(b.top.eta),
            Bsdf::CoatedConductor(b) => Some(b.top.eta),
            _ => None,
        }
    }

    /// The coat's reflection (exact): 0 without a coat ([`Self::has_coat`]).
    pub fn f_coat(&self, wo: Vec3, wi: Vec3, mode: TransportMode) -> Spectrum {
        match self {
            Bsdf::CoatedDiffuse(b) => b.f_coat(wo, wi, mode),
            Bsdf::CoatedConductor(b) if self.has_coat() => b.f_coat(wo, wi, mode),
            _ => Spectrum::ZERO,
        }
    }

    /// What is below the coat (a stochastic estimate, the rest of [`Self::f`]); the whole
    /// BSDF without a coat.
    pub fn f_body(&self, wo: Vec3, wi: Vec3, mode: TransportMode) -> Spectrum {
        if wo.z == 0.0 {
            return Spectrum::ZERO;
        }
        match self {
            Bsdf::CoatedDiffuse(b) => b.f_body(wo, wi, mode),
            Bsdf::CoatedConductor(b) if self.has_coat() => b.f_body(wo, wi, mode),
            _ => self.f(wo, wi, mode),
        }
    }

    /// A sample of the coat's reflection alone; `None` without a coat.
    pub fn sample_coat(
        &self,
        wo: Vec3,
        uc: f32,
        u: Vec2,
        mode: TransportMode,
    ) -> Option<BsdfSample> {
        if wo.z == 0.0 || !wo.is_finite() {
            return None;
        }
        match self {
            Bsdf::CoatedDiffuse(b) => b.sample_coat(wo, uc, u, mode),
            Bsdf::CoatedConductor(b) if self.has_coat() => b.sample_coat(wo, uc, u, mode),
            _ => None,
        }
        .filter(BsdfSample::is_valid)
    }

    /// The density of [`Self::sample_coat`] (0 for a smooth coat or without one).
    pub fn pdf_coat(&self, wo: Vec3, wi: Vec3) -> f32 {
        match self {
            Bsdf::CoatedDiffuse(b) => b.pdf_coat(wo, wi),
            Bsdf::CoatedConductor(b) if self.has_coat() => b.pdf_coat(wo, wi),
            _ => 0.0,
        }
    }

    /// A rough albedo for Russian roulette: the diffuse reflectance, 1 for (thin) dielectrics,
    /// the normal-incidence Fresnel reflectance for a conductor, `R + T` for diffuse
    /// transmission, and for a coat its normal-incidence reflectance plus the rest times the
    /// base's estimate.
    pub fn reflectance_estimate(&self) -> Spectrum {
        dispatch!(self, b => b.reflectance_estimate())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn smooth_conductor_mirror_sample() {
        let eta = Vec3::new(0.2, 0.9, 1.1);
        let k = Vec3::new(3.9, 2.4, 2.0);
        let b = Bsdf::Conductor(Conductor::new(
            Spectrum::from_rgb(eta),
            Spectrum::from_rgb(k),
            0.0,
            0.0,
        ));
        for wo in [Vec3::new(0.6, 0.0, 0.8), Vec3::new(0.0, 0.28, -0.96)] {
            let s = b
                .sample(wo, 0.3, Vec2::splat(0.4), TransportMode::Radiance)
                .unwrap();
            assert!(s.specular && !s.transmission && s.pdf == 1.0 && s.eta == 1.0);
            assert!((s.wi - Vec3::new(-wo.x, -wo.y, wo.z)).length() < 1e-7);
            let weight = s.f * s.wi.z.abs() / s.pdf;
            let want =
                fresnel::fr_complex(wo.z.abs(), Spectrum::from_rgb(eta), Spectrum::from_rgb(k));
            assert!((weight - want).abs().max_element() < 1e-6);
            assert_eq!(b.f(wo, s.wi, TransportMode::Radiance), Spectrum::ZERO);
            assert_eq!(b.pdf(wo, s.wi), 0.0);
        }
    }

    #[test]
    fn degenerate_inputs_give_no_sample() {
        let all = [
            Bsdf::Diffuse(Diffuse::new(Spectrum::splat(0.5))),
            Bsdf::Dielectric(Dielectric::new(1.5)),
            Bsdf::Conductor(Conductor::new(
                Spectrum::ONE,
                Spectrum::splat(3.0),
                0.0,
                0.0,
            )),
            Bsdf::Conductor(Conductor::new(
                Spectrum::ONE,
                Spectrum::splat(3.0),
                0.3,
                0.3,
            )),
        ];
        for b in all {
            let grazing = Vec3::X;
            assert!(b
                .sample(grazing, 0.5, Vec2::splat(0.5), TransportMode::Radiance)
                .is_none());
            assert_eq!(
                b.f(grazing, Vec3::Z, TransportMode::Radiance),
                Spectrum::ZERO
            );
            let nan = Vec3::new(f32::NAN, 0.0, 1.0);
            assert!(b
                .sample(nan, 0.5, Vec2::splat(0.5), TransportMode::Radiance)
                .is_none());
        }
    }

    /// Every model, with ordinary and extreme parameters, at random and grazing directions:
    /// f and pdf are finite and non-negative, samples are valid or None (never NaN).
    #[test]
    fn no_nan_anywhere() {
        use crate::bsdf::testutil::Rng;
        let mut rng = Rng::new(61);
        let coat = |eta: f32, a: f32, thick: f32, albedo: f32, g: f32| {
            layered::Layered::new(
                Dielectric::rough(eta, a, a),
                Diffuse::new(Spectrum::splat(0.7)),
                thick,
                Spectrum::splat(albedo),
                g,
                10,
                1,
            )
        };
        let mut all = vec![];
        for eta in [1.0f32, 1.0001, 1.5, 3.0, 0.7] {
            for a in [0.0f32, 1e-4, 0.02, 0.5, 2.0] {
                all.push(Bsdf::Dielectric(Dielectric::rough(eta, a, a * 0.5)));
                all.push(Bsdf::CoatedDiffuse(coat(eta, a, 0.01, 0.5, 0.3)));
                all.push(Bsdf::CoatedConductor(layered::Layered::new(
                    Dielectric::rough(eta, a, a),
                    Conductor::new(Spectrum::splat(0.2), Spectrum::splat(3.0), a, 0.3),
                    1e-3,
                    Spectrum::ZERO,
                    0.0,
                    10,
                    1,
                )));
            }
            all.push(Bsdf::ThinDielectric(ThinDielectric::new(eta)));
        }
        all.push(Bsdf::CoatedDiffuse(coat(1.5, 0.1, 0.0, 1.0, 0.99)));
        all.push(Bsdf::CoatedDiffuse(coat(1.5, 0.1, 1e6, 1.0, -0.99)));
        all.push(Bsdf::DiffuseTransmission(DiffuseTransmission::new(
            Spectrum::ONE,
            Spectrum::ZERO,
        )));
        all.push(Bsdf::DiffuseTransmission(DiffuseTransmission::new(
            Spectrum::ZERO,
            Spectrum::ZERO,
        )));
        let grazing = [
            Vec3::new(1.0, 0.0, 1e-7).normalize(),
            Vec3::new(0.0, 1.0, -1e-7).normalize(),
            Vec3::Z,
            -Vec3::Z,
        ];
        for b in &all {
            for i in 0..400 {
                let wo = if i < 4 { grazing[i] } else { rng.sphere() };
                let wi = if i % 7 == 0 {
                    grazing[i % 4]
                } else {
                    rng.sphere()
                };
                for mode in [TransportMode::Radiance, TransportMode::Importance] {
                    let f = b.f(wo, wi, mode);
                    assert!(
                        f.is_finite() && f.min_element() >= 0.0,
                        "{b:?} f {f:?} at {wo:?} {wi:?}"
                    );
                    if let Some(s) = b.sample(wo, rng.f32(), rng.vec2(), mode) {
                        assert!(s.is_valid(), "{b:?}: {s:?}");
                        let m = b.mis_pdf(wo, &s);
                        assert!(m.is_finite() && m >= 0.0, "{b:?}: mis pdf {m}");
                    }
                }
                let p = b.pdf(wo, wi);
                assert!(p.is_finite() && p >= 0.0, "{b:?} pdf {p} at {wo:?} {wi:?}");
            }
        }
    }
}
