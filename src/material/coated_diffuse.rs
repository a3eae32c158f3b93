//! `coateddiffuse`: a dielectric coat over a Lambertian base, with an optional scattering
//! slab between them (pbrt-v4's `CoatedDiffuseMaterial`; the BSDF is [`crate::bsdf::layered`]).
//!
//! ```text
//! Material "coateddiffuse" "rgb reflectance" [ 0.5 0.5 0.5 ] "float roughness" 0
//!     "float thickness" 0.01 "float eta" 1.5 "rgb albedo" [ 0 0 0 ] "float g" 0
//!     "integer maxdepth" 10 "integer nsamples" 1                         # defaults
//! ```
//! The coat's roughness and [`Coat`] as in [`super::parts`].
use super::parts::{albedo, coat, coated_bxdf, microfacet_lobe, roughness, unit};
use super::parts::{Coat, Roughness};
use super::{MaterialContext, MaterialModel};
use crate::bsdf::{Bsdf, BxdfFlags, Diffuse};
use crate::math::Vec3;
use crate::params::{Loc, ParamSet, SceneError};
use crate::texture::{Tex, TexCoord};

#[derive(Clone, Debug, PartialEq)]
pub struct CoatedDiffuseMaterial {
    pub reflectance: Tex,
    /// The coat's roughness.
    pub roughness: Roughness,
    pub coat: Coat,
}

impl MaterialModel for CoatedDiffuseMaterial {
    fn create(params: &mut ParamSet, _: &Loc, cx: &MaterialContext) -> Result<Self, SceneError> {
        let t = cx.textures;
        Ok(CoatedDiffuseMaterial {
            reflectance: albedo(params, "reflectance", Vec3::splat(0.5), t)?,
            roughness: roughness(params, "", t)?,
            coat: coat(params, "eta", t)?,
        })
    }

    /// pbrt-v4's `LayeredBxDF::Flags`: reflection, diffuse (the base is), specular when the
    /// coat is smooth.
    fn flags(&self) -> BxdfFlags {
        use BxdfFlags as F;
        F::REFLECTION | F::DIFFUSE | (microfacet_lobe(&self.roughness) & F::SPECULAR)
    }

    fn bsdf(&self, tc: &TexCoord) -> Bsdf {
        let base = Diffuse::new(unit(&self.reflectance, tc));
        Bsdf::CoatedDiffuse(coated_bxdf(&self.coat, &self.roughness, base, tc))
    }

    fn for_each_texture(&self, f: &mut dyn FnMut(&Tex)) {
        f(&self.reflectance);
        self.roughness.for_each_texture(f);
        self.coat.for_each_texture(f);
    }
}
