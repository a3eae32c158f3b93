//! `AreaLightSource` and `LightSource`: pbrt-v4's diffuse area light and its point, spot and
//! distant lights, with RGB radiometric values.
//!
//! ```text
//! AreaLightSource "diffuse" "rgb L" [ 17 12 4 ] "bool twosided" false "float scale" 1
//! LightSource "point" "rgb I" [ 10 10 10 ] "point3 from" [ 0 2 0 ] "float power" 100
//! LightSource "spot" "point3 from" [0 5 0] "point3 to" [0 0 0] "float coneangle" 30 "float conedeltaangle" 5
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
//!   cos_end = cos(coneangle), cos_start = cos(coneangle - conedeltaangle).
//!
//! Every `L`/`I` component and `scale` must be finite and >= 0 and `power` in (0, 1e30]; the
//! value after `scale` and `power` at most [`MAX_LIGHT_VALUE`] (1e20) and a light's power,
//! computed in f64 (an emitter's area can overflow f32), at most [`MAX_LIGHT_POWER`] (1e30 W):
//! otherwise an error at the parameter (NaN/Inf pixels or a silently dropped light before).
//! Point and spot lights must lie within the supported coordinates (see `extent`).
//!
//! `from`/`to` go through the CTM; a distant light's `dir` is the direction light travels
//! (`to - from`, transformed as a vector).
//!
//! `L` and `I` may be a blackbody, `"blackbody L" [ 3000 ]` (kelvin), on every light here: as in
//! pbrt-v4 its luminance is 1 before `scale`, `power` and `illuminance`, which then act as
//! for an RGB value; the colour is pbrt-v4's `cie1931` film's sRGB of it (see
//! [`super::blackbody`]). Distant `illuminance`, sampled spectra and other light types are
//! unsupported.
//!
//! `LightSource "infinite"` (see [`crate::light::EnvMap`]):
//!
//! ```text
//! LightSource "infinite" "rgb L" [ 0.4 0.45 0.5 ] "float illuminance" 3
//! Rotate -90 1 0 0
//! LightSource "infinite" "string filename" "sky.exr" "float scale" 1.5
//! ```
//! - `L` (`rgb`, `blackbody`, or a constant `spectrum`) or `filename`, not both; neither:
//!   `L` = (1, 1, 1).
//!   pbrt-v4 scales a light's spectrum to one nit, so a constant spectrum is an equal-energy
//!   white of luminance 1 whatever its value: in sRGB (1.2048, 0.9483, 0.9088).
//! - `filename`: a square image (EXR, PFM; PNG and others decode as sRGB) in pbrt-v4's
//!   equal-area octahedral parameterisation (non-square: an error, as in pbrt-v4). Texels must
//!   be finite; negative ones count as 0.
//! - `scale` multiplies. `illuminance` E (> 0) rescales so that a surface facing the light's
//!   +z (before the CTM) receives illuminance E from the upper hemisphere. A constant `L` is
//!   multiplied by `E / pi`, as pbrt-v4 does (its RGB value is not normalised: `L` (2, 2, 2)
//!   gives 2E); an image by `E / E_map`, `E_map` the sum over the texels whose centre is above
//!   the horizon of `luminance * cos(theta) * 4 pi / N`. pbrt-v4 weighs those texels `2 pi / N`
//!   (half their solid angle), which makes its image lights twice as bright as asked and twice
//!   as bright as a constant `L` with the same `illuminance`; photon follows the integral.
//! - The CTM's linear part orients the map: a rotation, possibly with a uniform scale or a
//!   mirror; anything else (it would not preserve solid angle) is an error.
//! - `portal`: 4 world-space points forming a rectangle (pbrt-v4's test). It is not only a
//!   sampling hint: pbrt-v4's `PortalImageInfiniteLight::Le` is zero for a ray that does not
//!   leave through the portal, so photon gives light only to such rays (camera, gather and
//!   shadow rays by their origin and direction, photons by their line), but samples the whole
//!   map as without a portal (directions outside it are wasted samples). With a constant `L`,
//!   pbrt-v4 does not normalise it to one nit (see `portal_l_factor`); `illuminance` with a
//!   portal is an error.

use super::params::{ParamSet, ParamType};
use super::shapes::xform_point;
use crate::light::{EnvMap, Portal};
use crate::math::{Mat3, Mat4, Vec3};
use crate::scene::{Light, Loc, SceneError};
use crate::texture::{Encoding, Image};
use std::path::Path;
use std::sync::Arc;

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
    /// The radiance for a shape of surface `area` (computed in f64: a large emitter's area can
    /// overflow f32), checked so that the light's value and power stay in range.
    pub fn radiance(&self, area: f64) -> Result<Vec3, String> {
        let sides = if self.two_sided { 2.0 } else { 1.0 };
        let l = match self.power {
            None => self.l,
            Some(_) if area.is_nan() || area <= 0.0 => {
                return Err("\"power\" given for an area light on a shape of zero area".to_string())
            }
            Some(power) => {
                let k = power as f64 / (std::f64::consts::PI * sides * area);
                let big = self.l.max_element() as f64 * k;
                if big > MAX_LIGHT_VALUE as f64 {
                    return Err(format!(
                        "\"power\" on a shape of area {area:e} makes its radiance {big:e}, above the limit {MAX_LIGHT_VALUE:e}"
                    ));
                }
                self.l * k as f32
            }
        };
        let power = std::f64::consts::PI * sides * area * l.max_element() as f64;
        if power.is_nan() || power > MAX_LIGHT_POWER {
            return Err(format!(
                "the emitter's power {power:e} (area {area:e}) is above the limit {MAX_LIGHT_POWER:e}"
            ));
        }
        Ok(l)
    }
}

/// Largest radiance or intensity component a light may have (after `scale` and `power`):
/// beyond it sums of a few hundred photons or samples overflow f32.
pub const MAX_LIGHT_VALUE: f32 = 1e20;
/// Largest power (W) of one light, computed in f64: photon powers and irradiance estimates
/// must stay finite in f32.
pub const MAX_LIGHT_POWER: f64 = 1e30;

/// A light value (`L`, `I`) as RGB: an `rgb` as given, or a `blackbody` temperature as pbrt-v4's
/// blackbody of luminance 1 ([`super::blackbody`]); every component finite, >= 0 and at most
/// [`MAX_LIGHT_VALUE`]; errors at the parameter.
fn light_rgb(params: &mut ParamSet, name: &str) -> Result<Vec3, SceneError> {
    let v = match params.peek(name) {
        Some(p) if p.ty == ParamType::Blackbody => blackbody(params, name)?,
        _ => params.get_rgb(name, Vec3::ONE)?,
    };
    if v.cmpge(Vec3::ZERO).all() && v.max_element() <= MAX_LIGHT_VALUE {
        return Ok(v);
    }
    let p = params.peek(name).expect("a bad value came from the file");
    Err(p.err(format!(
        "each component must be in [0, {MAX_LIGHT_VALUE:e}], got [{} {} {}]",
        v.x, v.y, v.z
    )))
}

/// An emitted radiance `name` that defaults to none (a medium's `Le`): as [`light_rgb`]
/// reads a light's value (an `rgb` as given, a `blackbody` of luminance 1), or `None`.
pub fn emission_rgb(params: &mut ParamSet, name: &str) -> Result<Option<Vec3>, SceneError> {
    if params.peek(name).is_none() {
        return Ok(None);
    }
    light_rgb(params, name).map(Some)
}

/// The RGB of `"blackbody name" [ T ]`: T must be finite and > 0 (kelvin).
fn blackbody(params: &mut ParamSet, name: &str) -> Result<Vec3, SceneError> {
    let t = params.get_blackbody(name)?.expect("peeked");
    crate::spectrum::blackbody::rgb(t as f64).ok_or_else(|| {
        let p = params.peek(name).expect("peeked");
        p.err(format!(
            "the temperature must be finite and > 0 (kelvin), got {t}"
        ))
    })
}

/// The product `value * k` (from `scale` or `power`), checked against [`MAX_LIGHT_VALUE`];
/// errors at parameter `name`.
fn scaled(
    params: &ParamSet,
    name: &str,
    loc: &Loc,
    value: Vec3,
    k: f64,
) -> Result<Vec3, SceneError> {
    let big = value.max_element() as f64 * k;
    if big <= MAX_LIGHT_VALUE as f64 {
        return Ok(value * k as f32);
    }
    let msg = format!("makes the light's value {big:e}, above the limit {MAX_LIGHT_VALUE:e}");
    Err(match params.peek(name) {
        Some(p) => p.err(msg),
        None => SceneError::at(loc, msg),
    })
}

/// Reads `scale` (finite, >= 0) and `power` (finite and > 0 when given).
fn scale_power(params: &mut ParamSet) -> Result<(f32, Option<f32>), SceneError> {
    let scale = params.get_float("scale", 1.0)?;
    if scale.is_nan() || scale < 0.0 {
        let p = params.peek("scale").expect("given");
        return Err(p.err(format!("must be >= 0, got {scale}")));
    }
    let power = params.get_float_opt("power")?;
    if let Some(pw) = power {
        if pw.is_nan() || pw <= 0.0 || pw as f64 > MAX_LIGHT_POWER {
            let p = params.peek("power").expect("given");
            return Err(p.err(format!("must be in (0, {MAX_LIGHT_POWER:e}], got {pw}")));
        }
    }
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
    let l = light_rgb(params, "L")?;
    let two_sided = params.get_bool("twosided", false)?;
    let (scale, power) = scale_power(params)?;
    let l = scaled(params, "scale", loc, l, scale as f64)?;
    params.check_unused()?;
    Ok(AreaSpec {
        l,
        two_sided,
        power,
    })
}

/// `LightSource "point" | "spot" | "distant" | "infinite"` under the CTM `ctm`; image files
/// are relative to `base_dir`.
pub fn light_source(
    ty: &str,
    params: &mut ParamSet,
    loc: &Loc,
    ctm: &Mat4,
    files: (&Path, &super::LoadBudget),
) -> Result<Light, SceneError> {
    let light = match ty {
        "point" => point(params, loc, ctm)?,
        "spot" => spot(params, loc, ctm)?,
        "distant" => distant(params, loc, ctm)?,
        "infinite" => infinite(params, loc, ctm, files)?,
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

/// `I * scale`, rescaled by `k(power)` when `power` is given, checked against the limits; a
/// delta light's power is `solid_angle * I`.
fn intensity(params: &mut ParamSet, loc: &Loc, solid_angle: f64) -> Result<Vec3, SceneError> {
    let i = light_rgb(params, "I")?;
    let (scale, power) = scale_power(params)?;
    let i = scaled(params, "scale", loc, i, scale as f64)?;
    let i = match power {
        Some(p) => scaled(params, "power", loc, i, p as f64 / solid_angle)?,
        None => i,
    };
    let total = solid_angle * i.max_element() as f64;
    if total > MAX_LIGHT_POWER {
        return Err(SceneError::at(
            loc,
            format!("the light's power {total:e} is above the limit {MAX_LIGHT_POWER:e}"),
        ));
    }
    Ok(i)
}

/// The light position `from` through the CTM, which must be finite.
fn position(params: &mut ParamSet, loc: &Loc, ctm: &Mat4) -> Result<Vec3, SceneError> {
    let from = params.get_point3("from", Vec3::ZERO)?;
    let p = xform_point(ctm, from);
    let max = super::extent::MAX_COORDINATE;
    if !p.is_finite() || p.abs().max_element() > max {
        return Err(SceneError::at(
            loc,
            format!("the scene is too large: the light is at {p} after the current transform (photon supports coordinates up to {max:e}; scale the scene down)"),
        ));
    }
    Ok(p)
}

fn point(params: &mut ParamSet, loc: &Loc, ctm: &Mat4) -> Result<Light, SceneError> {
    let intensity = intensity(params, loc, 4.0 * std::f64::consts::PI)?;
    Ok(Light::Point(crate::light::PointLight {
        pos: position(params, loc, ctm)?,
        intensity,
    }))
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
    let cone = params.get_float("coneangle", 30.0)?;
    let delta = params.get_float("conedeltaangle", 5.0)?;
    let cos_end = cone.to_radians().cos();
    let cos_start = (cone - delta).to_radians().cos();
    let solid_angle = 2.0 * std::f64::consts::PI * (1.0 - 0.5 * (cos_start + cos_end)) as f64;
    let intensity = intensity(params, loc, solid_angle)?;
    let from = params.get_point3("from", Vec3::ZERO)?;
    let to = params.get_point3("to", Vec3::Z)?;
    Ok(Light::Spot(crate::light::SpotLight {
        pos: position(params, loc, ctm)?,
        dir: direction(from, to, ctm, loc)?,
        intensity,
        cos_falloff_start: cos_start,
        cos_falloff_end: cos_end,
    }))
}

fn distant(params: &mut ParamSet, loc: &Loc, ctm: &Mat4) -> Result<Light, SceneError> {
    let l = light_rgb(params, "L")?;
    let scale = params.get_float("scale", 1.0)?;
    if scale.is_nan() || scale < 0.0 {
        let p = params.peek("scale").expect("given");
        return Err(p.err(format!("must be >= 0, got {scale}")));
    }
    let l = scaled(params, "scale", loc, l, scale as f64)?;
    if params.get_float_opt("illuminance")?.is_some() {
        let p = params.peek("illuminance").expect("just read");
        return Err(p.err("\"illuminance\" is not supported"));
    }
    let from = params.get_point3("from", Vec3::ZERO)?;
    let to = params.get_point3("to", Vec3::Z)?;
    Ok(Light::Distant(crate::light::DistantLight {
        dir: direction(from, to, ctm, loc)?,
        l,
    }))
}

/// sRGB of an equal-energy spectrum of luminance 1 (XYZ (1, 1, 1)): a constant `spectrum L`.
const EQUAL_ENERGY_RGB: Vec3 = Vec3::new(1.204_784_3, 0.948_300_8, 0.908_842_7);

/// `LightSource "infinite"`: `L` or `filename`, `scale`, `illuminance`, oriented by the CTM.
fn infinite(
    params: &mut ParamSet,
    loc: &Loc,
    ctm: &Mat4,
    (base_dir, budget): (&Path, &super::LoadBudget),
) -> Result<Light, SceneError> {
    let portal = portal(params)?;
    let scale = params.get_float("scale", 1.0)?;
    if !(scale.is_finite() && scale >= 0.0) {
        let p = params.peek("scale").expect("given");
        return Err(p.err(format!("must be finite and >= 0, got {scale}")));
    }
    let illuminance = params.get_float_opt("illuminance")?;
    if let Some(e) = illuminance {
        if !(e.is_finite() && e as f64 <= MAX_LIGHT_VALUE as f64) {
            let p = params.peek("illuminance").expect("given");
            return Err(p.err(format!(
                "must be finite and at most {MAX_LIGHT_VALUE:e}, got {e}"
            )));
        }
    }
    // pbrt-v4 ignores a non-positive illuminance.
    let illuminance = illuminance.filter(|&e| e > 0.0);
    if let (Some(_), Some(_)) = (illuminance, portal) {
        let p = params.peek("illuminance").expect("given");
        return Err(p.err("\"illuminance\" with a \"portal\" is not supported"));
    }
    let filename = params.get_string_opt("filename")?;
    if let (Some(_), Some(p)) = (&filename, params.peek("L")) {
        return Err(p.err("an infinite light takes \"L\" or \"filename\", not both"));
    }
    let map = match filename {
        Some(name) => {
            let rotation = light_rotation(ctm, loc)?;
            let image = env_image(&base_dir.join(&name), loc, budget)?;
            let k = match illuminance {
                Some(e) => {
                    let upper = EnvMap::upper_illuminance(&image);
                    if upper <= 0.0 {
                        let p = params.peek("illuminance").expect("given");
                        return Err(
                            p.err("the image is black above the horizon: no illuminance to scale")
                        );
                    }
                    e as f64 / upper
                }
                None => 1.0,
            };
            let big = image
                .texels
                .iter()
                .fold(0.0f32, |m, t| m.max(t.max_element()));
            let k = scaled(params, "scale", loc, Vec3::splat(big), scale as f64 * k)?;
            let k = if big > 0.0 { k.x / big } else { 0.0 };
            EnvMap::new(image, k, rotation)
        }
        None => {
            let unnormalised = match portal {
                Some(_) => portal_l_factor(params),
                None => 1.0,
            };
            let l = infinite_l(params)?;
            let k = scale as f64
                * unnormalised
                * illuminance.map_or(1.0, |e| e as f64 / std::f64::consts::PI);
            EnvMap::constant(scaled(params, "scale", loc, l, k)?)
        }
    };
    let map = match portal {
        Some(p) => map.with_portal(p),
        None => map,
    };
    Ok(Light::Infinite { map: Arc::new(map) })
}

/// `"point3 portal"`: 4 world-space points (not moved by the CTM, as in pbrt-v4) forming a
/// rectangle.
fn portal(params: &mut ParamSet) -> Result<Option<Portal>, SceneError> {
    let Some(points) = params.get_point3s("portal")? else {
        return Ok(None);
    };
    let p = params.peek("portal").expect("just read");
    let Ok(corners) = <[Vec3; 4]>::try_from(points.as_slice()) else {
        return Err(p.err(format!("expected 4 points, got {}", points.len())));
    };
    Portal::new(corners).map(Some).map_err(|m| p.err(m))
}

/// pbrt-v4's portal light turns a constant `L` into RGB by `SpectrumToXYZ`, without the
/// one-nit normalisation of its other lights: relative to photon's luminance-1 value, a
/// blackbody's luminance is that of Planck's law normalised to its peak, a constant spectrum's
/// its value; an `rgb` is unchanged.
fn portal_l_factor(params: &ParamSet) -> f64 {
    let Some(p) = params.peek("L") else {
        return 1.0;
    };
    let first = p.floats().and_then(|v| v.first().copied());
    match (p.ty, first) {
        (ParamType::Blackbody, Some(t)) => {
            crate::spectrum::blackbody::peak_normalized_luminance(t as f64).unwrap_or(1.0)
        }
        (ParamType::Spectrum, _) => p
            .floats()
            .and_then(|v| v.get(1).copied())
            .map_or(1.0, |c| c as f64),
        _ => 1.0,
    }
}

/// An infinite light's constant `L`: `rgb` (each component in range), `blackbody`, a constant `spectrum`
/// (pbrt-v4's one-nit equal-energy white), or (1, 1, 1).
fn infinite_l(params: &mut ParamSet) -> Result<Vec3, SceneError> {
    let Some(p) = params.peek("L") else {
        return Ok(Vec3::ONE);
    };
    if p.ty != ParamType::Spectrum {
        return light_rgb(params, "L");
    }
    let p = params.get_param("L").expect("just peeked");
    let constant = match p.floats() {
        Some(v) if v.len() >= 2 && v.len() % 2 == 0 => {
            let x = v[1];
            x > 0.0 && x.is_finite() && v.chunks(2).all(|c| c[1] == x)
        }
        _ => false,
    };
    if constant {
        Ok(EQUAL_ENERGY_RGB)
    } else {
        Err(p.err(
            "only a constant positive spectrum (wavelength, value pairs of one value) or an rgb is supported here",
        ))
    }
}

/// The rotation (possibly with a mirror) the CTM's linear part makes after taking out a
/// uniform scale; an error for a singular, sheared or non-uniformly scaled CTM.
fn light_rotation(ctm: &Mat4, loc: &Loc) -> Result<Mat3, SceneError> {
    let m = Mat3::from_mat4(*ctm);
    let s = m.determinant().abs().cbrt();
    let r = m * (1.0 / s);
    let off = (r.transpose() * r - Mat3::IDENTITY)
        .to_cols_array()
        .iter()
        .fold(0.0f32, |a, v| a.max(v.abs()));
    if s.is_finite() && s > 0.0 && off <= 1e-3 {
        return Ok(r);
    }
    Err(SceneError::at(
        loc,
        "an infinite light's transform must be a rotation (with at most a uniform scale or a mirror)",
    ))
}

/// Reads an environment image: square, every texel finite.
fn env_image(path: &Path, loc: &Loc, budget: &super::LoadBudget) -> Result<Image, SceneError> {
    let err = |m: String| {
        SceneError::at(
            loc,
            format!(
                "infinite light \"{}\": {m}",
                path.file_name().unwrap_or_default().to_string_lossy()
            ),
        )
    };
    let image = super::textures::read_image(path, Encoding::Srgb, budget).map_err(err)?;
    if image.width != image.height {
        return Err(err(format!(
            "the image is {}x{}, not square: not an equal-area environment map",
            image.width, image.height
        )));
    }
    if let Some(i) = image.texels.iter().position(|t| !t.is_finite()) {
        let (x, y) = (i % image.width, i / image.width);
        return Err(err(format!("texel ({x}, {y}) is not finite")));
    }
    Ok(image)
}
