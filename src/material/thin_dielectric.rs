//! `thindielectric`: a thin sheet of glass, a window pane (pbrt-v4's `ThinDielectricMaterial`).
//!
//! ```text
//! Material "thindielectric" "float eta" 1.5
//! ```
//! `eta` (1.5) as in [`super::parts`].
use super::parts::dielectric_eta;
use super::{MaterialContext, MaterialModel};
use crate::bsdf::{Bsdf, BxdfFlags, ThinDielectric};
use crate::params::{Loc, ParamSet, SceneError};
use crate::texture::{Tex, TexCoord};

#[derive(Clone, Debug, PartialEq)]
pub struct ThinDielectricMaterial {
    pub eta: f32,
}

impl MaterialModel for ThinDielectricMaterial {
    fn create(params: &mut ParamSet, _: &Loc, _: &MaterialContext) -> Result<Self, SceneError> {
        Ok(ThinDielectricMaterial {
            eta: dielectric_eta(params, "eta")?,
        })
    }

    fn flags(&self) -> BxdfFlags {
        BxdfFlags::REFLECTION | BxdfFlags::TRANSMISSION | BxdfFlags::SPECULAR
    }

    fn bsdf(&self, _: &TexCoord) -> Bsdf {
        Bsdf::ThinDielectric(ThinDielectric::new(self.eta))
    }

    fn for_each_texture(&self, _: &mut dyn FnMut(&Tex)) {}
}
