//! `AreaLightSource` and `LightSource`: pbrt-v4's diffuse area light and its point, spot and
//! distant lights, with RGB radiometric values.
//!
//! ```text
//! AreaLightSource "diffuse" "rgb L" [ 17 12 4 ] "bool twosided" false "float scale" 1
//! LightSource "point" "rgb I" [ 10 10 10 ] "point3 from" [ 0 2 0 ] "float power" 100
//! LightSource "spot" "point3 from" [0 5 0] "point3 to" [0 0 0] "float coneangle" 30 "float conedelta" 5
//! LightSource "distant" "rgb L" [ 3 3 3 ] "point3 from" [0 1 0] "point3 to" [0 0 0]
//! ```
//!
//! `scale` multiplies the value. `power` (when > 0) rescales as pbrt-v4 does, where
//! pbrt divides by the spectrum's photometric factor: for an RGB value pbrt takes that factor
//! from the colour space's illuminant only, so here it is 1 and the RGB value itself is scaled
//! (an RGB (2,2,2) with power P emits 2P, exactly as in pbrt-v4):
//! - area: L *= power / (pi * (twosided ? 2 : 1) * area), with the area of the whole shape
//!   (pbrt-v4 uses each triangle's own area, making a mesh emit `power` per triangle; we use
//!   the mesh's total, 4 pi r^2 for a sphere, so the shape emits `power`);
//! - point: I *= power / (4 pi);
//! - spot: I *= power / (2 pi (1 - (cos_start + cos_end) / 2)), pbrt-v4's k_e, with
//!   cos_end = cos(coneangle), cos_start = cos(coneangle - conedelta).
//!
//! `from`/`to` go through the CTM; a distant light's `dir` is the direction light travels
//! (`to - from`, transformed as a vector). Distant `illuminance`, spectra and blackbodies, and
//! other light types are unsupported.

use super::params::ParamSet;
use super::shapes::xform_point;
use crate::math::{Mat3, Mat4, Vec3};
use crate::scene::{Light, Loc, SceneError};
use std::f32::consts::PI;

/// An `AreaLightSource "diffuse"` waiting for the shapes it applies to.
#[derive(Clone, Debug, PartialEq)]
pub struct AreaSpec {
    /// Radiance, already times `scale`.
    pub l: Vec3,
    pub two_sided: bool,
    /// `power` when given and positive.
    pub power: Option<f32>,
}

impl AreaSpec {
    /// The radiance for a shape of surface `area`.
    pub fn radiance(&self, area: f32) -> Result<Vec3, String> {
        let Some(power) = self.power else {
            return Ok(self.l);
        };
        if area.is_nan() || area <= 0.0 {
            return Err("\"power\" given for an area light on a shape of zero area".to_string());
        }
        let sides = if self.two_sided { 2.0 } else { 1.0 };
        Ok(self.l * (power / (PI * sides * area)))
    }
}

/// Reads `scale` and `power` (as `Some` only when positive).
fn scale_power(params: &mut ParamSet) -> Result<(f32, Option<f32>), SceneError> {
    let scale = params.get_float("scale", 1.0)?;
    let power = params.get_float_opt("power")?.filter(|&p| p > 0.0);
    Ok((scale, power))
}

/// `AreaLightSource "diffuse"`: `L`, `scale`, `twosided`, `power`.
pub fn area_light(ty: &str, params: &mut ParamSet, loc: &Loc) -> Result<AreaSpec, SceneError> {
    if ty != "diffuse" {
        return Err(SceneError::at(
            loc,
            format!("unsupported area light type \"{ty}\""),
        ));
    }
    let l = params.get_rgb("L", Vec3::ONE)?;
    let two_sided = params.get_bool("twosided", false)?;
    let (scale, power) = scale_power(params)?;
    params.check_unused()?;
    Ok(AreaSpec {
        l: l * scale,
        two_sided,
        power,
    })
}

/// `LightSource "point" | "spot" | "distant"` under the CTM `ctm`.
pub fn light_source(
    ty: &str,
    params: &mut ParamSet,
    loc: &Loc,
    ctm: &Mat4,
) -> Result<Light, SceneError> {
    let light = match ty {
        "point" => point(params, ctm)?,
        "spot" => spot(params, loc, ctm)?,
        "distant" => distant(params, loc, ctm)?,
        other => {
            return Err(SceneError::at(
                loc,
                format!("unsupported light type \"{other}\""),
            ))
        }
    };
    params.check_unused()?;
    Ok(light)
}

fn point(params: &mut ParamSet, ctm: &Mat4) -> Result<Light, SceneError> {
    let i = params.get_rgb("I", Vec3::ONE)?;
    let (scale, power) = scale_power(params)?;
    let from = params.get_point3("from", Vec3::ZERO)?;
    let k = power.map_or(1.0, |p| p / (4.0 * PI));
    Ok(Light::Point {
        pos: xform_point(ctm, from),
        intensity: i * scale * k,
    })
}

/// `to - from` through the CTM's linear part, normalised; an error when it vanishes.
fn direction(from: Vec3, to: Vec3, ctm: &Mat4, loc: &Loc) -> Result<Vec3, SceneError> {
    let d = Mat3::from_mat4(*ctm) * (to - from);
    let n = d.normalize_or_zero();
    if n == Vec3::ZERO {
        return Err(SceneError::at(loc, "\"from\" and \"to\" give no direction"));
    }
    Ok(n)
}

fn spot(params: &mut ParamSet, loc: &Loc, ctm: &Mat4) -> Result<Light, SceneError> {
    let i = params.get_rgb("I", Vec3::ONE)?;
    let (scale, power) = scale_power(params)?;
    let from = params.get_point3("from", Vec3::ZERO)?;
    let to = params.get_point3("to", Vec3::Z)?;
    let cone = params.get_float("coneangle", 30.0)?;
    let delta = params.get_float("conedelta", 5.0)?;
    let cos_end = cone.to_radians().cos();
    let cos_start = (cone - delta).to_radians().cos();
    let k = match power {
        Some(p) => p / (2.0 * PI * (1.0 - 0.5 * (cos_start + cos_end))),
        None => 1.0,
    };
    Ok(Light::Spot {
        pos: xform_point(ctm, from),
        dir: direction(from, to, ctm, loc)?,
        intensity: i * scale * k,
        cos_falloff_start: cos_start,
        cos_falloff_end: cos_end,
    })
}

fn distant(params: &mut ParamSet, loc: &Loc, ctm: &Mat4) -> Result<Light, SceneError> {
    let l = params.get_rgb("L", Vec3::ONE)?;
    let scale = params.get_float("scale", 1.0)?;
    if params.get_float_opt("illuminance")?.is_some() {
        let p = params.peek("illuminance").expect("just read");
        return Err(p.err("\"illuminance\" is not supported"));
    }
    let from = params.get_point3("from", Vec3::ZERO)?;
    let to = params.get_point3("to", Vec3::Z)?;
    Ok(Light::Distant {
        dir: direction(from, to, ctm, loc)?,
        l: l * scale,
    })
}
