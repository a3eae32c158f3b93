//! `dielectric`: glass, smooth or rough (pbrt-v4's `DielectricMaterial`).
//!
//! ```text
//! Material "dielectric" "float eta" 1.5 "float roughness" 0.01     # default smooth
//! ```
//! `eta` (1.5) as in [`super::parts`]; smooth wherever the Trowbridge-Reitz alpha is below
//! 1e-3; `eta` 1 is no interface at all (light passes straight through).
use super::parts::{dielectric_eta, microfacet_lobe, roughness, Roughness};
use super::{MaterialContext, MaterialModel};
use crate::bsdf::{Bsdf, BxdfFlags, Dielectric};
use crate::params::{Loc, ParamSet, SceneError};
use crate::texture::{Tex, TexCoord};

#[derive(Clone, Debug, PartialEq)]
pub struct DielectricMaterial {
    pub eta: f32,
    pub roughness: Roughness,
}

impl MaterialModel for DielectricMaterial {
    fn create(params: &mut ParamSet, _: &Loc, cx: &MaterialContext) -> Result<Self, SceneError> {
        Ok(DielectricMaterial {
            eta: dielectric_eta(params, "eta")?,
            roughness: roughness(params, "", cx.textures)?,
        })
    }

    fn flags(&self) -> BxdfFlags {
        use BxdfFlags as F;
        if self.eta == 1.0 {
            return F::TRANSMISSION | F::SPECULAR; // no interface: straight through
        }
        F::REFLECTION | F::TRANSMISSION | microfacet_lobe(&self.roughness)
    }

    fn bsdf(&self, tc: &TexCoord) -> Bsdf {
        let (au, av) = self.roughness.eval(tc);
        Bsdf::Dielectric(Dielectric::rough(self.eta, au, av))
    }

    fn for_each_texture(&self, f: &mut dyn FnMut(&Tex)) {
        self.roughness.for_each_texture(f)
    }

    fn has_sharp_lobe(&self, min_alpha: f32) -> bool {
        self.eta != 1.0 && self.roughness.narrower_than(min_alpha) || self.flags().has_specular()
    }
}
