//! Materials: what a surface is made of, one file per pbrt-v4 material. Each model owns its
//! parameters, reads them from the `Material` / `MakeNamedMaterial` parameter list with the
//! texture table ([`MaterialModel::create`]), says which lobes its BSDF may have anywhere on
//! the surface ([`MaterialModel::flags`], what the photon-map rules decide by), and builds its
//! [`Bsdf`] at a hit ([`MaterialModel::bsdf`]). Adding a material is one file, one
//! [`MaterialKind`] line and one row of [`NAMES`].
//!
//! ```text
//! Material "diffuse" "rgb reflectance" [ 0.8 0.8 0.8 ]                  # default 0.5
//! Material "dielectric" "float eta" 1.5 "float roughness" 0.01           # default smooth
//! Material "thindielectric" "float eta" 1.5
//! Material "diffusetransmission" "rgb reflectance" [ 0.25 0.25 0.25 ]
//!     "rgb transmittance" [ 0.25 0.25 0.25 ] "float scale" 1             # defaults
//! Material "coateddiffuse" "rgb reflectance" [ 0.5 0.5 0.5 ] "float roughness" 0
//!     "float thickness" 0.01 "float eta" 1.5 "rgb albedo" [ 0 0 0 ] "float g" 0
//!     "integer maxdepth" 10 "integer nsamples" 1                         # defaults
//! Material "coatedconductor" "float interface.roughness" 0 "float interface.eta" 1.5
//!     "spectrum conductor.eta" "metal-Cu-eta" "spectrum conductor.k" "metal-Cu-k"
//!     "float conductor.roughness" 0 "float thickness" 0.01 ...           # defaults
//! Material "conductor" "spectrum eta" "metal-Au-eta" "spectrum k" "metal-Au-k"
//!     "float roughness" 0.1 "bool remaproughness" true                    # alpha = sqrt(0.1)
//! Material "conductor" "rgb reflectance" [ 0.9 0.6 0.3 ]                 # eta 1, k from r
//! Material "diffuse" "texture reflectance" "wood" "texture displacement" "bumps"
//! Material "conductor" "texture roughness" "scratches" "texture reflectance" "tint"
//! Material "mix" "string materials" [ "wood" "paint" ] "texture amount" "wear"
//! ```
//!
//! - Parameters pbrt-v4 lets be textures may be: diffuse `reflectance`; conductor `eta`, `k`,
//!   `reflectance`, `roughness`, `uroughness`, `vroughness`; dielectric roughness;
//!   diffusetransmission `reflectance`, `transmittance`; coateddiffuse `reflectance`,
//!   roughness, `thickness`, `albedo`, `g`; coatedconductor `interface.`/`conductor.`
//!   roughness, `conductor.eta`, `conductor.k`, `reflectance`, `thickness`, `albedo`, `g`; and
//!   every material's `displacement` (a float texture: bump mapping). A `"texture"` value
//!   names a texture defined earlier in the right namespace (spectrum for colours, float for
//!   the others).
//! - The shared parts (roughness, a conductor's index, a coat, reflectances, a dielectric's
//!   index) and their rules are in [`parts`]; each model's file lists its own parameters.
//! - RGB reflectances must lie in [0, 1] (pbrt-v4 rejects others too). Parameters a model
//!   does not read are errors at their location.
mod coated_conductor;
mod coated_diffuse;
mod conductor;
mod dielectric;
mod diffuse;
mod diffuse_transmission;
mod mix;
pub mod parts;
pub mod spectra;
mod thin_dielectric;

pub use coated_conductor::CoatedConductorMaterial;
pub use coated_diffuse::CoatedDiffuseMaterial;
pub use conductor::ConductorMaterial;
pub use dielectric::DielectricMaterial;
pub use diffuse::DiffuseMaterial;
pub use diffuse_transmission::DiffuseTransmissionMaterial;
pub use mix::MixMaterial;
pub use parts::{Coat, Metal, Roughness};
pub use thin_dielectric::ThinDielectricMaterial;

use crate::bsdf::{Bsdf, BxdfFlags};
use crate::params::{Loc, ParamSet, SceneError};
use crate::texture::{Tex, TexCoord, Textures};
use std::collections::HashMap;

/// A material: its scattering model and an optional bump map.
#[derive(Clone, Debug, PartialEq)]
pub struct Material {
    pub kind: MaterialKind,
    /// `"texture displacement"`: a float texture of heights along the shading normal (pbrt-v4's
    /// bump mapping, see [`crate::interaction::SurfaceInteraction::bsdf`]).
    pub displacement: Option<Tex>,
    /// pbrt-v4's `interface` material: no surface at all, only the boundary between the media
    /// of the shape's `MediumInterface`; rays pass straight through (`kind` is then a black
    /// diffuse stand-in that only integrators refusing such scenes would see).
    pub interface: bool,
}

impl From<MaterialKind> for Material {
    fn from(kind: MaterialKind) -> Material {
        Material {
            kind,
            displacement: None,
            interface: false,
        }
    }
}

/// Deepest chain of `mix` materials accepted (a mix of a mix of ...); hits resolve the chain
/// in at most this many steps.
pub const MAX_MIX_DEPTH: usize = 64;

/// What a material may refer to when it is created: the textures and the named materials
/// defined before it.
pub struct MaterialContext<'a> {
    pub textures: &'a Textures,
    pub named: &'a HashMap<String, u32>,
    pub materials: &'a [Material],
}

/// One material model (pbrt-v4's `Material` interface, as far as photon needs it).
pub trait MaterialModel: Sized {
    /// The model from its parameters (each one it reads is marked used); `loc` is where the
    /// material's type is named.
    fn create(params: &mut ParamSet, loc: &Loc, cx: &MaterialContext) -> Result<Self, SceneError>;

    /// Every lobe the BSDF may have somewhere on the surface (the union over its textures'
    /// values).
    fn flags(&self) -> BxdfFlags;

    /// The BSDF at a hit whose texture coordinates are `tc` (bad texture values sanitised as
    /// pbrt-v4 does).
    fn bsdf(&self, tc: &TexCoord) -> Bsdf;

    /// Calls `f` on every colour and float parameter (constant or texture), without
    /// allocating (it runs for every hit that builds a BSDF).
    fn for_each_texture(&self, f: &mut dyn FnMut(&Tex));

    /// Whether the BSDF may somewhere have a sharp lobe: a delta one, or a single microfacet
    /// lobe narrower than `min_alpha` (GGX alpha). Caustic photons are aimed at such objects
    /// and go on through them (see `photon::trace::is_sharp_bounce`).
    fn has_sharp_lobe(&self, _min_alpha: f32) -> bool {
        self.flags().has_specular()
    }

    /// Whether the surface reflects nothing anywhere: no photon map is needed for it.
    fn is_black(&self) -> bool {
        false
    }
}

/// The closed set of material models (pbrt-v4 names and defaults); see each model's file.
#[derive(Clone, Debug, PartialEq)]
pub enum MaterialKind {
    Diffuse(DiffuseMaterial),
    Dielectric(DielectricMaterial),
    Conductor(ConductorMaterial),
    ThinDielectric(ThinDielectricMaterial),
    DiffuseTransmission(DiffuseTransmissionMaterial),
    CoatedDiffuse(CoatedDiffuseMaterial),
    CoatedConductor(CoatedConductorMaterial),
    Mix(MixMaterial),
}

impl MaterialKind {
    /// The mean of the first colour that is not grey among the model's reflectance-like
    /// parameters (reflectances, transmittances, a coat's albedo; a conductor's index or
    /// reflectance colours only its Fresnel term and does not count), if any: where two such
    /// factors multiply along a path, RGB rendering differs from spectral
    /// ([`crate::spectrum`]).
    pub fn coloured_albedo(&self) -> Option<crate::math::Vec3> {
        let pick = |ts: &[&Tex]| ts.iter().find(|t| !t.is_grey()).map(|t| t.mean());
        match self {
            MaterialKind::Diffuse(m) => pick(&[&m.reflectance]),
            MaterialKind::DiffuseTransmission(m) => pick(&[&m.reflectance, &m.transmittance]),
            MaterialKind::CoatedDiffuse(m) => pick(&[&m.reflectance, &m.coat.albedo]),
            MaterialKind::CoatedConductor(m) => pick(&[&m.coat.albedo]),
            MaterialKind::Dielectric(_)
            | MaterialKind::Conductor(_)
            | MaterialKind::ThinDielectric(_)
            | MaterialKind::Mix(_) => None,
        }
    }
}

/// Calls `$call` on the model inside a [`MaterialKind`].
macro_rules! dispatch {
    ($kind:expr, $m:ident => $call:expr) => {
        match $kind {
            MaterialKind::Diffuse($m) => $call,
            MaterialKind::Dielectric($m) => $call,
            MaterialKind::Conductor($m) => $call,
            MaterialKind::ThinDielectric($m) => $call,
            MaterialKind::DiffuseTransmission($m) => $call,
            MaterialKind::CoatedDiffuse($m) => $call,
            MaterialKind::CoatedConductor($m) => $call,
            MaterialKind::Mix($m) => $call,
        }
    };
}

/// A constructor of one model from its parameters.
type Create = fn(&mut ParamSet, &Loc, &MaterialContext) -> Result<MaterialKind, SceneError>;

/// The material names a scene may use, and the model each makes.
pub const NAMES: [(&str, Create); 8] = [
    ("diffuse", |p, l, c| {
        Ok(MaterialKind::Diffuse(MaterialModel::create(p, l, c)?))
    }),
    ("dielectric", |p, l, c| {
        Ok(MaterialKind::Dielectric(MaterialModel::create(p, l, c)?))
    }),
    ("conductor", |p, l, c| {
        Ok(MaterialKind::Conductor(MaterialModel::create(p, l, c)?))
    }),
    ("thindielectric", |p, l, c| {
        Ok(MaterialKind::ThinDielectric(MaterialModel::create(
            p, l, c,
        )?))
    }),
    ("diffusetransmission", |p, l, c| {
        Ok(MaterialKind::DiffuseTransmission(MaterialModel::create(
            p, l, c,
        )?))
    }),
    ("coateddiffuse", |p, l, c| {
        Ok(MaterialKind::CoatedDiffuse(MaterialModel::create(p, l, c)?))
    }),
    ("coatedconductor", |p, l, c| {
        Ok(MaterialKind::CoatedConductor(MaterialModel::create(
            p, l, c,
        )?))
    }),
    ("mix", |p, l, c| {
        Ok(MaterialKind::Mix(MaterialModel::create(p, l, c)?))
    }),
];

/// Builds material `ty` from `params` (all of which must be used, `displacement` included);
/// `loc` is where the type is named.
pub fn create(
    ty: &str,
    params: &mut ParamSet,
    loc: &Loc,
    cx: &MaterialContext,
) -> Result<Material, SceneError> {
    if ty == "interface" {
        params.check_unused()?;
        let black = DiffuseMaterial {
            reflectance: Tex::from(crate::math::Vec3::ZERO),
        };
        return Ok(Material {
            interface: true,
            ..Material::from(MaterialKind::Diffuse(black))
        });
    }
    let Some((_, create)) = NAMES.iter().find(|(name, _)| *name == ty) else {
        return Err(SceneError::at(
            loc,
            format!("unsupported material type \"{ty}\""),
        ));
    };
    let kind = create(params, loc, cx)?;
    // pbrt-v4's MixMaterial has no displacement of its own.
    let displacement = match params.peek("displacement") {
        Some(_) if !matches!(kind, MaterialKind::Mix(_)) => {
            Some(parts::tex(params, "displacement", false, 0.0, cx.textures)?)
        }
        _ => None,
    };
    params.check_unused()?;
    Ok(Material {
        kind,
        displacement,
        interface: false,
    })
}

impl MaterialKind {
    /// Every lobe the BSDF may have somewhere on a surface of this material (the union over
    /// its textures' values): what the photon-map rules read to decide which maps a scene
    /// needs.
    pub fn flags(&self) -> BxdfFlags {
        dispatch!(self, m => m.flags())
    }

    /// See [`MaterialModel::has_sharp_lobe`].
    pub fn has_sharp_lobe(&self, min_alpha: f32) -> bool {
        dispatch!(self, m => m.has_sharp_lobe(min_alpha))
    }

    /// See [`MaterialModel::is_black`].
    pub fn is_black(&self) -> bool {
        dispatch!(self, m => m.is_black())
    }

    /// The BSDF at `tc`. A `mix` is resolved to one of its materials first
    /// ([`crate::interaction::SurfaceInteraction::bsdf`]); one that reaches here reflects
    /// nothing.
    pub fn bsdf(&self, tc: &TexCoord) -> Bsdf {
        dispatch!(self, m => m.bsdf(tc))
    }

    /// See [`MaterialModel::for_each_texture`].
    pub fn for_each_texture(&self, f: &mut dyn FnMut(&Tex)) {
        dispatch!(self, m => m.for_each_texture(f))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bsdf::TransportMode;
    use crate::math::Vec3;
    use crate::spectrum::Spectrum;

    #[test]
    fn material_mapping_and_flags() {
        let tc = TexCoord::default();
        let diffuse = MaterialKind::Diffuse(DiffuseMaterial {
            reflectance: Vec3::new(0.1, 0.2, 0.3).into(),
        })
        .bsdf(&tc);
        let f = diffuse.flags();
        assert!(f.has_diffuse() && !f.has_specular() && !f.has_glossy() && f.has_non_specular());
        assert!(f.contains(BxdfFlags::REFLECTION) && !f.contains(BxdfFlags::TRANSMISSION));
        assert_eq!(
            diffuse.reflectance_estimate(),
            Spectrum::from_rgb(Vec3::new(0.1, 0.2, 0.3))
        );

        let glass = MaterialKind::Dielectric(DielectricMaterial {
            eta: 1.5,
            roughness: Roughness::alphas(0.0, 0.0),
        })
        .bsdf(&tc);
        let f = glass.flags();
        assert!(f.is_specular_only() && !f.has_diffuse() && !f.has_glossy());
        assert!(f.contains(BxdfFlags::REFLECTION | BxdfFlags::TRANSMISSION));
        assert_eq!(glass.reflectance_estimate(), Spectrum::ONE);
        let wo = Vec3::new(0.6, 0.0, 0.8);
        assert_eq!(
            glass.f(wo, Vec3::new(-0.6, 0.0, 0.8), TransportMode::Radiance),
            Spectrum::ZERO
        );
        assert_eq!(glass.pdf(wo, Vec3::new(-0.6, 0.0, 0.8)), 0.0);

        // pbrt-v4's "reflectance" conductor: eta = 1, k = 2 sqrt(r) / sqrt(1 - r) gives a
        // normal-incidence reflectance of exactly r.
        let r = Vec3::new(0.9, 0.6, 0.3);
        let k = Vec3::new(
            2.0 * r.x.sqrt() / (1.0 - r.x).sqrt(),
            2.0 * r.y.sqrt() / (1.0 - r.y).sqrt(),
            2.0 * r.z.sqrt() / (1.0 - r.z).sqrt(),
        );
        for (a, smooth) in [(0.0f32, true), (5e-4, true), (0.2, false)] {
            let eta_k = MaterialKind::Conductor(ConductorMaterial {
                metal: Metal::EtaK {
                    eta: Vec3::ONE.into(),
                    k: k.into(),
                },
                roughness: Roughness::alphas(a, a),
            });
            let b = eta_k.bsdf(&tc);
            assert_eq!(b.flags(), eta_k.flags(), "constant parameters: exact flags");
            // The same conductor given by reflectance, with roughness remapped (sqrt).
            let by_r = MaterialKind::Conductor(ConductorMaterial {
                metal: Metal::Reflectance(r.into()),
                roughness: Roughness {
                    u: (a * a).into(),
                    v: (a * a).into(),
                    remap: true,
                },
            });
            let b2 = by_r.bsdf(&tc);
            assert!(
                (b2.reflectance_estimate() - Spectrum::from_rgb(r))
                    .abs()
                    .max_element()
                    < 1e-5
            );
            assert_eq!(b2.flags(), b.flags());
            assert_eq!(b.flags().is_specular_only(), smooth);
            assert_eq!(b.flags().has_glossy(), !smooth);
            assert!(!b.flags().has_diffuse());
            assert!(
                (b.reflectance_estimate() - Spectrum::from_rgb(r))
                    .abs()
                    .max_element()
                    < 1e-5
            );
        }
    }
}
