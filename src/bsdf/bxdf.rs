//! The interface every scattering model implements (pbrt-v4's `base/bxdf.h`): [`Bxdf`] with
//! uniform `f / sample / pdf / flags / reflectance_estimate` signatures, the sample it returns,
//! the lobe flags integrators decide by, the transport mode and the lobe restriction a
//! sampler may be given. Each model lives in its own file of `bsdf/` and implements [`Bxdf`];
//! [`super::Bsdf`] is the closed enum that dispatches to them in the hot loops.
use crate::math::{Vec2, Vec3};
use crate::spectrum::Spectrum;

/// One scattering model in its local shading frame (z = shading normal; `wo` towards the
/// viewer or previous vertex, `wi` towards the light or next vertex; unit vectors).
///
/// Delta lobes follow pbrt-v4: `f` and `pdf` are 0 for them, and a sample of one carries the
/// Fresnel weight over `|cos wi|` as `f` and the discrete lobe probability as `pdf`.
pub trait Bxdf {
    /// Every lobe the model has.
    fn flags(&self) -> BxdfFlags;

    /// The value for the pair `(wo, wi)`; 0 for delta lobes. `mode` matters for refraction
    /// (radiance is scaled by `1 / eta^2`) and for the layered models.
    fn f(&self, wo: Vec3, wi: Vec3, mode: TransportMode) -> Spectrum;

    /// An incident direction for `wo` among `lobes`: `uc` (uniform in `[0,1)`) picks the lobe,
    /// `u` (uniform in `[0,1)^2`) the direction within it. May return a sample that is not
    /// `BsdfSample::is_valid`; callers filter.
    fn sample(
        &self,
        wo: Vec3,
        uc: f32,
        u: Vec2,
        mode: TransportMode,
        lobes: Lobes,
    ) -> Option<BsdfSample>;

    /// The solid-angle density with which [`Self::sample`] restricted to `lobes` picks `wi`;
    /// 0 for delta lobes.
    fn pdf(&self, wo: Vec3, wi: Vec3, mode: TransportMode, lobes: Lobes) -> f32;

    /// A rough albedo for Russian roulette.
    fn reflectance_estimate(&self) -> Spectrum;

    /// The fraction of light arriving along the normal that is reflected back to its side
    /// (Fresnel at normal incidence for interfaces): what a coat over this model passes on.
    fn normal_reflectance(&self) -> Spectrum;
}

/// What a path carries: radiance (camera paths) or importance (photons). Only refraction
/// through a delta interface differs: radiance is scaled by `1 / eta^2`, importance is not.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum TransportMode {
    Radiance,
    Importance,
}

impl TransportMode {
    /// The adjoint mode (pbrt-v4's `!mode`): what a path traced from the other end carries.
    pub fn flip(self) -> TransportMode {
        match self {
            TransportMode::Radiance => TransportMode::Importance,
            TransportMode::Importance => TransportMode::Radiance,
        }
    }
}

/// Which lobes a sampling routine may choose (pbrt-v4's `BxDFReflTransFlags`); the layered
/// BSDF restricts its interfaces to one side. The pdf of a restricted sampler is the density
/// of that restricted choice.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Lobes {
    All,
    Reflection,
    Transmission,
}

impl Lobes {
    /// Probabilities of choosing reflection and transmission, given their weights `r`, `t`;
    /// `None` when nothing may be chosen.
    pub(crate) fn choose(self, r: f32, t: f32) -> Option<(f32, f32)> {
        let pr = if self == Lobes::Transmission { 0.0 } else { r };
        let pt = if self == Lobes::Reflection { 0.0 } else { t };
        let sum = pr + pt;
        (sum > 0.0).then(|| (pr / sum, pt / sum))
    }
}

/// One sampled scattering direction.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BsdfSample {
    /// Sampled unit direction (local frame).
    pub wi: Vec3,
    /// BSDF value for `(wo, wi)` (for a delta lobe: Fresnel / |cos wi|, see the module docs).
    pub f: Spectrum,
    /// Solid-angle density of `wi`, or the discrete lobe probability for a delta lobe.
    pub pdf: f32,
    /// A delta lobe (mirror reflection or refraction).
    pub specular: bool,
    /// `wi` is on the other side of the surface from `wo`.
    pub transmission: bool,
    /// Relative index of refraction crossed (`eta` entering, `1/eta` leaving); 1 for
    /// reflection.
    pub eta: f32,
    /// `pdf` is only proportional to the density of `wi` (the layered BSDF returns the
    /// density of one random-walk path; `f / pdf` is still the right throughput weight, and
    /// [`super::Bsdf::pdf`] gives the density for multiple importance sampling).
    pub pdf_is_proportional: bool,
    /// The GGX alpha (the smaller of the two) of the lobe that produced the sample: 0 for a
    /// delta lobe, infinity for a diffuse lobe or a walk through a coat's layer. The photon
    /// tracer calls a bounce sharp below `glossyalpha` and glossy while finite.
    pub lobe_alpha: f32,
}

impl BsdfSample {
    /// A sample with `pdf_is_proportional` false.
    /// `wi` is on the other side of the surface from `wo` when `wi.z * wo.z < 0`; the caller
    /// says so in `transmission`.
    pub(crate) fn new(
        wi: Vec3,
        f: Spectrum,
        pdf: f32,
        specular: bool,
        transmission: bool,
        eta: f32,
    ) -> BsdfSample {
        BsdfSample {
            wi,
            f,
            pdf,
            specular,
            transmission,
            eta,
            pdf_is_proportional: false,
            lobe_alpha: if specular { 0.0 } else { f32::INFINITY },
        }
    }

    /// The same sample, produced by a microfacet lobe of GGX alpha `a` (when not a delta one).
    pub(crate) fn with_alpha(self, a: f32) -> BsdfSample {
        BsdfSample {
            lobe_alpha: if self.specular { 0.0 } else { a },
            ..self
        }
    }

    /// True for a usable sample: positive finite pdf, non-zero finite f, `wi` off the surface.
    pub(crate) fn is_valid(&self) -> bool {
        self.pdf > 0.0
            && self.pdf.is_finite()
            && self.wi.z != 0.0
            && self.f.is_finite()
            && self.f.max_element() > 0.0
    }
}

/// What lobes a BSDF has, as pbrt-v4's `BxDFFlags`: reflection and/or transmission, each
/// diffuse, glossy or specular (delta). Integrators and the photon tracer decide from these
/// alone where photons are stored (diffuse lobes), where light is sampled (any non-delta
/// lobe), and what is traced onwards (specular and glossy lobes), so a new material never
/// touches them.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct BxdfFlags(u8);

impl BxdfFlags {
    pub const REFLECTION: BxdfFlags = BxdfFlags(1);
    pub const TRANSMISSION: BxdfFlags = BxdfFlags(2);
    pub const DIFFUSE: BxdfFlags = BxdfFlags(4);
    pub const GLOSSY: BxdfFlags = BxdfFlags(8);
    pub const SPECULAR: BxdfFlags = BxdfFlags(16);

    pub const fn union(self, other: BxdfFlags) -> BxdfFlags {
        BxdfFlags(self.0 | other.0)
    }

    pub fn contains(self, other: BxdfFlags) -> bool {
        self.0 & other.0 == other.0
    }

    /// A Lambertian (diffuse) lobe: photons are stored and gathered here.
    pub fn has_diffuse(self) -> bool {
        self.contains(BxdfFlags::DIFFUSE)
    }

    /// A lobe on the far side of the surface (light passes through).
    pub fn has_transmission(self) -> bool {
        self.contains(BxdfFlags::TRANSMISSION)
    }

    /// A rough, non-Lambertian lobe: direct lighting uses MIS with BSDF sampling.
    pub fn has_glossy(self) -> bool {
        self.contains(BxdfFlags::GLOSSY)
    }

    /// A delta lobe (mirror, smooth glass).
    pub fn has_specular(self) -> bool {
        self.contains(BxdfFlags::SPECULAR)
    }

    /// A lobe that light sampling can reach (diffuse or glossy).
    pub fn has_non_specular(self) -> bool {
        self.has_diffuse() || self.has_glossy()
    }

    /// Only delta lobes.
    pub fn is_specular_only(self) -> bool {
        self.has_specular() && !self.has_non_specular()
    }
}

impl std::ops::BitOr for BxdfFlags {
    type Output = BxdfFlags;
    fn bitor(self, other: BxdfFlags) -> BxdfFlags {
        self.union(other)
    }
}

impl std::ops::BitAnd for BxdfFlags {
    type Output = BxdfFlags;
    fn bitand(self, other: BxdfFlags) -> BxdfFlags {
        BxdfFlags(self.0 & other.0)
    }
}
