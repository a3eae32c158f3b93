//! `diffusetransmission`: Lambertian reflection and transmission, a lamp shade or a leaf
//! (pbrt-v4's `DiffuseTransmissionMaterial`).
//!
//! ```text
//! Material "diffusetransmission" "rgb reflectance" [ 0.25 0.25 0.25 ]   # defaults 0.25
//!     "rgb transmittance" [ 0.25 0.25 0.25 ] "float scale" [ 1 ]        # scales both
//! ```
//! `scale` (1) is a float >= 0; the scaled colours are clamped to [0, 1] per hit as pbrt-v4
//! does.
use super::parts::{albedo, float_in, is_zero};
use super::{MaterialContext, MaterialModel};
use crate::bsdf::{Bsdf, BxdfFlags, DiffuseTransmission};
use crate::math::Vec3;
use crate::params::{Loc, ParamSet, SceneError};
use crate::texture::{Tex, TexCoord};

#[derive(Clone, Debug, PartialEq)]
pub struct DiffuseTransmissionMaterial {
    pub reflectance: Tex,
    pub transmittance: Tex,
    pub scale: f32,
}

impl MaterialModel for DiffuseTransmissionMaterial {
    fn create(params: &mut ParamSet, _: &Loc, cx: &MaterialContext) -> Result<Self, SceneError> {
        let t = cx.textures;
        Ok(DiffuseTransmissionMaterial {
            reflectance: albedo(params, "reflectance", Vec3::splat(0.25), t)?,
            transmittance: albedo(params, "transmittance", Vec3::splat(0.25), t)?,
            scale: float_in(params, "scale", 1.0, 0.0, f32::MAX)?,
        })
    }

    fn flags(&self) -> BxdfFlags {
        use BxdfFlags as F;
        let mut f = F::default();
        if self.scale > 0.0 && !is_zero(&self.reflectance) {
            f = f | F::REFLECTION | F::DIFFUSE;
        }
        if self.scale > 0.0 && !is_zero(&self.transmittance) {
            f = f | F::TRANSMISSION | F::DIFFUSE;
        }
        f
    }

    fn bsdf(&self, tc: &TexCoord) -> Bsdf {
        Bsdf::DiffuseTransmission(DiffuseTransmission::new(
            tc.lambda.albedo(self.reflectance.eval(tc)) * self.scale,
            tc.lambda.albedo(self.transmittance.eval(tc)) * self.scale,
        ))
    }

    fn for_each_texture(&self, f: &mut dyn FnMut(&Tex)) {
        f(&self.reflectance);
        f(&self.transmittance);
    }

    fn is_black(&self) -> bool {
        self.scale <= 0.0 || (is_zero(&self.reflectance) && is_zero(&self.transmittance))
    }
}
