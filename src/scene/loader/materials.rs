//! `Material`, `MakeNamedMaterial`: the diffuse, dielectric and conductor materials with
//! pbrt-v4's parameters and defaults.
//!
//! ```text
//! Material "diffuse" "rgb reflectance" [ 0.8 0.8 0.8 ]                  # default 0.5
//! Material "dielectric" "float eta" 1.5                                  # smooth only
//! Material "conductor" "spectrum eta" "metal-Au-eta" "spectrum k" "metal-Au-k"
//!     "float roughness" 0.1 "bool remaproughness" true                    # alpha = sqrt(0.1)
//! Material "conductor" "rgb reflectance" [ 0.9 0.6 0.3 ]                 # eta 1, k from r
//! ```
//!
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
use crate::math::Vec3;
use crate::scene::{Loc, Material, SceneError};

/// Builds material `ty` from `params` (all of which must be used); `loc` is where the type is
/// named.
pub fn make_material(ty: &str, params: &mut ParamSet, loc: &Loc) -> Result<Material, SceneError> {
    let m = match ty {
        "diffuse" => Material::Diffuse {
            reflectance: albedo(params, "reflectance", Vec3::splat(0.5))?,
        },
        "dielectric" => dielectric(params)?,
        "conductor" => conductor(params)?,
        other => {
            return Err(SceneError::at(
                loc,
                format!("unsupported material type \"{other}\""),
            ))
        }
    };
    params.check_unused()?;
    Ok(m)
}

/// An RGB reflectance, checked to lie in [0, 1].
fn albedo(params: &mut ParamSet, name: &str, default: Vec3) -> Result<Vec3, SceneError> {
    let r = params.get_rgb(name, default)?;
    if r.min_element() < 0.0 || r.max_element() > 1.0 {
        let p = params
            .peek(name)
            .expect("an out-of-range value came from the file");
        return Err(p.err("reflectance values must lie in [0, 1]"));
    }
    Ok(r)
}

/// `dielectric`: `eta` and (zero) roughness.
fn dielectric(params: &mut ParamSet) -> Result<Material, SceneError> {
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
    Ok(Material::Dielectric { eta })
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
fn conductor(params: &mut ParamSet) -> Result<Material, SceneError> {
    let (eta, k) = match params.get_rgb_opt("reflectance")? {
        Some(r) => {
            if let Some(p) = params.peek("eta").or_else(|| params.peek("k")) {
                return Err(
                    p.err("a conductor takes either \"reflectance\" or \"eta\"/\"k\", not both")
                );
            }
            if r.min_element() < 0.0 || r.max_element() > 1.0 {
                let p = params.peek("reflectance").expect("given");
                return Err(p.err("reflectance values must lie in [0, 1]"));
            }
            (Vec3::ONE, k_from_reflectance(r))
        }
        None => (metal(params, "eta", CU_ETA)?, metal(params, "k", CU_K)?),
    };
    let (alpha_u, alpha_v) = roughness(params)?;
    Ok(Material::Conductor {
        eta,
        k,
        alpha_u,
        alpha_v,
    })
}

/// pbrt-v4's conductor from reflectance: k = 2 sqrt(r) / sqrt(1 - r), with r at most 1 - 1e-7.
pub fn k_from_reflectance(r: Vec3) -> Vec3 {
    // In f64: 1 - 1e-7 is not representable in f32 (it would round to 1 - 1.19e-7).
    let f = |r: f32| {
        let r = (r as f64).clamp(0.0, 1.0 - 1e-7);
        (2.0 * r.sqrt() / (1.0 - r).sqrt()) as f32
    };
    Vec3::new(f(r.x), f(r.y), f(r.z))
}

/// A conductor's `eta` or `k`: RGB, or a named metal spectrum, or `default`.
fn metal(params: &mut ParamSet, name: &str, default: Vec3) -> Result<Vec3, SceneError> {
    if params.peek(name).map(|p| p.ty) != Some(ParamType::Spectrum) {
        return params.get_rgb(name, default);
    }
    let p = params.get_param(name).expect("just peeked");
    match p.strings() {
        Some([s]) => spectra::metal(s).ok_or_else(|| p.err(spectra::unsupported(s))),
        _ => Err(p.err(
            "expected one named spectrum metal-{Ag,Al,Au,Cu,CuZn,MgO,TiO2}-{eta,k} \
             (sampled spectra are not supported)",
        )),
    }
}

/// Conductor roughness as Trowbridge-Reitz alphas `(alpha_u, alpha_v)`.
fn roughness(params: &mut ParamSet) -> Result<(f32, f32), SceneError> {
    let u = params.get_float_opt("uroughness")?;
    let v = params.get_float_opt("vroughness")?;
    let both = if u.is_none() || v.is_none() {
        params.get_float("roughness", 0.0)?
    } else {
        0.0
    };
    let (u, v) = (u.unwrap_or(both), v.unwrap_or(both));
    if u < 0.0 || v < 0.0 {
        let name = ["uroughness", "vroughness", "roughness"]
            .into_iter()
            .find(|n| {
                params
                    .peek(n)
                    .and_then(|p| p.floats())
                    .is_some_and(|f| f[0] < 0.0)
            })
            .unwrap_or("roughness");
        let p = params
            .peek(name)
            .expect("a negative roughness came from the file");
        return Err(p.err("roughness must not be negative"));
    }
    if params.get_bool("remaproughness", true)? {
        Ok((u.sqrt(), v.sqrt()))
    } else {
        Ok((u, v))
    }
}
