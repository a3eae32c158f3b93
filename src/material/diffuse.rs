//! `diffuse`: Lambertian reflection (pbrt-v4's `DiffuseMaterial`).
//!
//! ```text
//! Material "diffuse" "rgb reflectance" [ 0.8 0.8 0.8 ]     # default 0.5; or a texture
//! ```
use super::parts::{albedo, is_zero, unit};
use super::{MaterialContext, MaterialModel};
use crate::bsdf::{Bsdf, BxdfFlags, Diffuse};
use crate::math::Vec3;
use crate::params::{Loc, ParamSet, SceneError};
use crate::texture::{Tex, TexCoord};

#[derive(Clone, Debug, PartialEq)]
pub struct DiffuseMaterial {
    pub reflectance: Tex,
}

impl MaterialModel for DiffuseMaterial {
    fn create(params: &mut ParamSet, _: &Loc, cx: &MaterialContext) -> Result<Self, SceneError> {
        Ok(DiffuseMaterial {
            reflectance: albedo(params, "reflectance", Vec3::splat(0.5), cx.textures)?,
        })
    }

    fn flags(&self) -> BxdfFlags {
        BxdfFlags::REFLECTION | BxdfFlags::DIFFUSE
    }

    fn bsdf(&self, tc: &TexCoord) -> Bsdf {
        Bsdf::Diffuse(Diffuse::new(unit(&self.reflectance, tc)))
    }

    fn for_each_texture(&self, f: &mut dyn FnMut(&Tex)) {
        f(&self.reflectance)
    }

    fn is_black(&self) -> bool {
        is_zero(&self.reflectance)
    }
}
