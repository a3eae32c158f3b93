//! `Material`, `MakeNamedMaterial`: the diffuse, dielectric and conductor materials with
//! pbrt-v4's parameters and defaults.
//!
//! ```text
//! Material "diffuse" "rgb reflectance" [ 0.8 0.8 0.8 ]                  # default 0.5
//! Material "dielectric" "float eta" 1.5                                  # smooth only
//! Material "conductor" "spectrum eta" "metal-Au-eta" "spectrum k" "metal-Au-k"
//!     "float roughness" 0.1 "bool remaproughness" true                    # alpha = sqrt(0.1)
//! Material "conductor" "rgb reflectance" [ 0.9 0.6 0.3 ]                 # eta 1, k from r
//! Material "diffuse" "texture reflectance" "wood" "texture displacement" "bumps"
//! Material "conductor" "texture roughness" "scratches" "texture reflectance" "tint"
//! ```
//!
//! - Parameters pbrt-v4 lets be textures may be: diffuse `reflectance`; conductor `eta`, `k`,
//!   `reflectance`, `roughness`, `uroughness`, `vroughness`; and every material's
//!   `displacement` (a float texture: bump mapping). A `"texture"` value names a texture defined
//!   earlier in the right namespace (spectrum for colours, float for the others).
//! - conductor `eta`/`k`: RGB, or pbrt-v4's named spectra `metal-{Ag,Al,Au,Cu,CuZn,MgO,TiO2}-
//!   {eta,k}` (with or without brackets) as the RGB values of [`super::spectra`]; default
//!   copper. `reflectance` r instead gives pbrt-v4's
//!   eta = 1, k = 2 sqrt(r) / sqrt(1 - r) (r clamped to 1 - 1e-7 so k stays finite); giving
//!   both is an error, as in pbrt-v4.
//! - conductor roughness: `uroughness`/`vroughness`, each defaulting to `roughness` (0);
//!   `remaproughness` (default true) maps roughness to Trowbridge-Reitz alpha = sqrt(roughness)
//!   as pbrt-v4's `RoughnessToAlpha` does.
//! - dielectric `eta`: a float, or a `spectrum` that is constant (one number, or
//!   wavelength-value pairs with one value) or a named glass (`glass-BK7`, `glass-BAF10`,
//!   `glass-FK51A`, `glass-LASF9`, `glass-F5`, `glass-F10`, `glass-F11`: its index at 550 nm,
//!   see [`super::spectra`]); roughness other than 0 is unsupported.
//! - RGB reflectances must lie in [0, 1] (pbrt-v4 rejects others too).

use super::params::{ParamSet, ParamType};
use super::spectra::{self, CU_ETA, CU_K};
use super::textures::texture_param;
use crate::math::Vec3;
use crate::scene::{Loc, Material, MaterialKind, Metal, Roughness, SceneError};
use crate::texture::{Tex, Textures};

/// Builds material `ty` from `params` (all of which must be used); `loc` is where the type is
/// named; `textures` are those defined so far.
pub fn make_material(
    ty: &str,
    params: &mut ParamSet,
    loc: &Loc,
    textures: &Textures,
) -> Result<Material, SceneError> {
    let kind = match ty {
        "diffuse" => MaterialKind::Diffuse {
            reflectance: albedo(params, "reflectance", Vec3::splat(0.5), textures)?,
        },
        "dielectric" => dielectric(params)?,
        "conductor" => conductor(params, textures)?,
        other => {
            return Err(SceneError::at(
                loc,
                format!("unsupported material type \"{other}\""),
            ))
        }
    };
    let displacement = match params.peek("displacement") {
        Some(_) => Some(tex(params, "displacement", false, 0.0, textures)?),
        None => None,
    };
    params.check_unused()?;
    Ok(Material { kind, displacement })
}

/// A parameter that may be a texture: `spectrum` (RGB) or float, `default` when absent.
fn tex(
    params: &mut ParamSet,
    name: &str,
    spectrum: bool,
    default: f32,
    textures: &Textures,
) -> Result<Tex, SceneError> {
    let t = texture_param(params, name, spectrum, default, textures)?;
    Ok(match *t {
        crate::texture::Texture::Constant(v) => Tex::Const(v),
        _ => Tex::Map(t),
    })
}

/// Whether `name` is given as a `"texture"`.
fn is_texture(params: &ParamSet, name: &str) -> bool {
    params.peek(name).map(|p| p.ty) == Some(ParamType::Texture)
}

/// A reflectance: a spectrum texture (values clamped to [0, 1] per hit, as pbrt-v4 does), or an
/// RGB checked to lie in [0, 1].
fn albedo(
    params: &mut ParamSet,
    name: &str,
    default: Vec3,
    textures: &Textures,
) -> Result<Tex, SceneError> {
    if is_texture(params, name) {
        return tex(params, name, true, 0.0, textures);
    }
    let r = params.get_rgb(name, default)?;
    if r.min_element() < 0.0 || r.max_element() > 1.0 {
        let p = params
            .peek(name)
            .expect("an out-of-range value came from the file");
        return Err(p.err("reflectance values must lie in [0, 1]"));
    }
    Ok(r.into())
}

/// `dielectric`: `eta` and (zero) roughness.
fn dielectric(params: &mut ParamSet) -> Result<MaterialKind, SceneError> {
    let eta = match params.peek("eta").map(|p| p.ty) {
        Some(ParamType::Spectrum) => constant_spectrum(params, "eta")?,
        _ => params.get_float("eta", 1.5)?,
    };
    if eta.is_nan() || eta <= 0.0 {
        let p = params.peek("eta").expect("a bad eta came from the file");
        return Err(p.err("eta must be positive"));
    }
    for name in ["roughness", "uroughness", "vroughness"] {
        if params.get_float(name, 0.0)? != 0.0 {
            let p = params
                .peek(name)
                .expect("a nonzero roughness came from the file");
            return Err(p.err("rough dielectrics are not supported (roughness must be 0)"));
        }
    }
    params.get_bool("remaproughness", true)?;
    Ok(MaterialKind::Dielectric { eta })
}

/// The value of a `spectrum` parameter that is one number, constant wavelength-value pairs or
/// a named glass (its index at 550 nm).
fn constant_spectrum(params: &mut ParamSet, name: &str) -> Result<f32, SceneError> {
    let p = params.get_param(name).expect("caller checked it exists");
    let Some(v) = p.floats() else {
        return match p.strings() {
            Some([s]) => spectra::glass(s).ok_or_else(|| {
                p.err(format!(
                    "named spectrum \"{s}\" is not supported here (a glass-* name is)"
                ))
            }),
            _ => Err(p.err("expected one named spectrum")),
        };
    };
    match v {
        [x] => Ok(*x),
        [_, x, rest @ ..] if v.len() % 2 == 0 && rest.chunks(2).all(|c| c[1] == *x) => Ok(*x),
        _ => Err(p.err("only a constant spectrum is supported here")),
    }
}

/// `conductor`: eta/k or reflectance, and roughness.
fn conductor(params: &mut ParamSet, textures: &Textures) -> Result<MaterialKind, SceneError> {
    let metal = if params.peek("reflectance").is_some() {
        if let Some(p) = params.peek("eta").or_else(|| params.peek("k")) {
            return Err(
                p.err("a conductor takes either \"reflectance\" or \"eta\"/\"k\", not both")
            );
        }
        Metal::Reflectance(albedo(params, "reflectance", Vec3::ZERO, textures)?)
    } else {
        Metal::EtaK {
            eta: metal(params, "eta", CU_ETA, textures)?,
            k: metal(params, "k", CU_K, textures)?,
        }
    };
    let roughness = roughness(params, textures)?;
    Ok(MaterialKind::Conductor { metal, roughness })
}

/// A conductor's `eta` or `k`: RGB, a spectrum texture, or a named metal spectrum, or
/// `default`.
fn metal(
    params: &mut ParamSet,
    name: &str,
    default: Vec3,
    textures: &Textures,
) -> Result<Tex, SceneError> {
    if is_texture(params, name) {
        return tex(params, name, true, 0.0, textures);
    }
    if params.peek(name).map(|p| p.ty) != Some(ParamType::Spectrum) {
        return Ok(params.get_rgb(name, default)?.into());
    }
    let p = params.get_param(name).expect("just peeked");
    match p.strings() {
        Some([s]) => spectra::metal(s)
            .map(Tex::Const)
            .ok_or_else(|| p.err(spectra::unsupported(s))),
        _ => Err(p.err(
            "expected one named spectrum metal-{Ag,Al,Au,Cu,CuZn,MgO,TiO2}-{eta,k} \
             (sampled spectra are not supported)",
        )),
    }
}

/// Conductor roughness: `uroughness`/`vroughness`, each defaulting to `roughness` (0); floats
/// or float textures; constants must not be negative.
fn roughness(params: &mut ParamSet, textures: &Textures) -> Result<Roughness, SceneError> {
    for name in ["uroughness", "vroughness", "roughness"] {
        if let Some(p) = params.peek(name) {
            if p.floats()
                .is_some_and(|f| f.first().is_some_and(|&x| x < 0.0))
            {
                return Err(p.err("roughness must not be negative"));
            }
        }
    }
    // pbrt-v4 reads `roughness` only for a missing u or v (else it is an unused parameter).
    let given = |params: &ParamSet, n: &str| params.peek(n).is_some();
    let both = if given(params, "uroughness") && given(params, "vroughness") {
        Tex::from(0.0)
    } else {
        tex(params, "roughness", false, 0.0, textures)?
    };
    let mut one = |name: &str| match given(params, name) {
        true => tex(params, name, false, 0.0, textures),
        false => Ok(both.clone()),
    };
    let u = one("uroughness")?;
    let v = one("vroughness")?;
    let remap = params.get_bool("remaproughness", true)?;
    Ok(Roughness { u, v, remap })
}
