//! `conductor`: a metal, a mirror when smooth (pbrt-v4's `ConductorMaterial`).
//!
//! ```text
//! Material "conductor" "spectrum eta" "metal-Au-eta" "spectrum k" "metal-Au-k"
//!     "float roughness" 0.1 "bool remaproughness" true                    # alpha = sqrt(0.1)
//! Material "conductor" "rgb reflectance" [ 0.9 0.6 0.3 ]                 # eta 1, k from r
//! ```
//! The index ([`Metal`]: `eta`/`k`, default copper, or `reflectance`) and the roughness as in
//! [`super::parts`].
use super::parts::{conductor_bxdf, metal_index, metal_textures, microfacet_lobe, roughness};
use super::parts::{Metal, Roughness};
use super::{MaterialContext, MaterialModel};
use crate::bsdf::{Bsdf, BxdfFlags};
use crate::params::{Loc, ParamSet, SceneError};
use crate::texture::{Tex, TexCoord};

#[derive(Clone, Debug, PartialEq)]
pub struct ConductorMaterial {
    pub metal: Metal,
    pub roughness: Roughness,
}

impl MaterialModel for ConductorMaterial {
    fn create(params: &mut ParamSet, _: &Loc, cx: &MaterialContext) -> Result<Self, SceneError> {
        let metal = metal_index(params, "", cx.textures)?;
        let roughness = roughness(params, "", cx.textures)?;
        Ok(ConductorMaterial { metal, roughness })
    }

    fn flags(&self) -> BxdfFlags {
        BxdfFlags::REFLECTION | microfacet_lobe(&self.roughness)
    }

    fn bsdf(&self, tc: &TexCoord) -> Bsdf {
        Bsdf::Conductor(conductor_bxdf(&self.metal, &self.roughness, 1.0, tc))
    }

    fn for_each_texture(&self, f: &mut dyn FnMut(&Tex)) {
        metal_textures(&self.metal, f);
        self.roughness.for_each_texture(f);
    }

    fn has_sharp_lobe(&self, min_alpha: f32) -> bool {
        self.roughness.narrower_than(min_alpha)
    }
}
