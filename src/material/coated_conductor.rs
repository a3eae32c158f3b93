//! `coatedconductor`: a dielectric coat over a conductor, with an optional scattering slab
//! between them (pbrt-v4's `CoatedConductorMaterial`; the BSDF is [`crate::bsdf::layered`]).
//!
//! ```text
//! Material "coatedconductor" "float interface.roughness" 0 "float interface.eta" 1.5
//!     "spectrum conductor.eta" "metal-Cu-eta" "spectrum conductor.k" "metal-Cu-k"
//!     "float conductor.roughness" 0 "float thickness" 0.01 ...           # defaults
//! ```
//! `conductor.eta`/`conductor.k` (default copper) or `reflectance`, not both, as given in the
//! file, relative to the outside: the BSDF divides them by the coat's index, as pbrt-v4 does.
//! Roughnesses `interface.` and `conductor.` and the [`Coat`] as in [`super::parts`].
use super::parts::{coat, coated_bxdf, conductor_bxdf, is_zero, metal_index, metal_textures};
use super::parts::{microfacet_lobe, roughness, Coat, Metal, Roughness};
use super::{MaterialContext, MaterialModel};
use crate::bsdf::{Bsdf, BxdfFlags};
use crate::params::{Loc, ParamSet, SceneError};
use crate::texture::{Tex, TexCoord};

#[derive(Clone, Debug, PartialEq)]
pub struct CoatedConductorMaterial {
    /// The coat's roughness.
    pub interface: Roughness,
    pub coat: Coat,
    pub metal: Metal,
    /// The conductor's roughness.
    pub roughness: Roughness,
}

impl MaterialModel for CoatedConductorMaterial {
    fn create(params: &mut ParamSet, _: &Loc, cx: &MaterialContext) -> Result<Self, SceneError> {
        let t = cx.textures;
        Ok(CoatedConductorMaterial {
            interface: roughness(params, "interface.", t)?,
            coat: coat(params, "interface.eta", t)?,
            metal: metal_index(params, "conductor.", t)?,
            roughness: roughness(params, "conductor.", t)?,
        })
    }

    /// pbrt-v4's `LayeredBxDF::Flags`: reflection, specular when the coat is smooth, diffuse
    /// when the slab scatters (`albedo`), else glossy when the coat or the base is rough.
    fn flags(&self) -> BxdfFlags {
        use BxdfFlags as F;
        let (top, base) = (
            microfacet_lobe(&self.interface),
            microfacet_lobe(&self.roughness),
        );
        let mut f = F::REFLECTION | (top & F::SPECULAR);
        if !is_zero(&self.coat.albedo) {
            f = f | F::DIFFUSE;
        }
        if is_zero(&self.coat.albedo) || self.coat.albedo.constant().is_none() {
            f = f | ((top | base) & F::GLOSSY);
        }
        f
    }

    fn bsdf(&self, tc: &TexCoord) -> Bsdf {
        // pbrt-v4: the base's index is relative to the coat's medium.
        let base = conductor_bxdf(&self.metal, &self.roughness, self.coat.eta, tc);
        Bsdf::CoatedConductor(coated_bxdf(&self.coat, &self.interface, base, tc))
    }

    fn for_each_texture(&self, f: &mut dyn FnMut(&Tex)) {
        metal_textures(&self.metal, f);
        self.interface.for_each_texture(f);
        self.roughness.for_each_texture(f);
        self.coat.for_each_texture(f);
    }
}
