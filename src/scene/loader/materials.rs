//! `Material`, `MakeNamedMaterial`: the diffuse, dielectric, thin dielectric, conductor,
//! diffuse-transmission and coated materials with pbrt-v4's parameters and defaults.
//!
//! ```text
//! Material "diffuse" "rgb reflectance" [ 0.8 0.8 0.8 ]                  # default 0.5
//! Material "dielectric" "float eta" 1.5 "float roughness" 0.01           # default smooth
//! Material "thindielectric" "float eta" 1.5
//! Material "conductor" "spectrum eta" "metal-Au-eta" "spectrum k" "metal-Au-k"
//!     "float roughness" 0.1 "bool remaproughness" true                    # alpha = sqrt(0.1)
//! Material "conductor" "rgb reflectance" [ 0.9 0.6 0.3 ]                 # eta 1, k from r
//! Material "diffusetransmission" "rgb reflectance" [ 0.25 0.25 0.25 ]
//!     "rgb transmittance" [ 0.25 0.25 0.25 ] "float scale" 1             # defaults
//! Material "coateddiffuse" "rgb reflectance" [ 0.5 0.5 0.5 ] "float roughness" 0
//!     "float thickness" 0.01 "float eta" 1.5 "rgb albedo" [ 0 0 0 ] "float g" 0
//!     "integer maxdepth" 10 "integer nsamples" 1                         # defaults
//! Material "coatedconductor" "float interface.roughness" 0 "float interface.eta" 1.5
//!     "spectrum conductor.eta" "metal-Cu-eta" "spectrum conductor.k" "metal-Cu-k"
//!     "float conductor.roughness" 0 "float thickness" 0.01 ...           # defaults
//! ```
//!
//! - roughness (dielectric, conductor, `coateddiffuse`, and `interface.`/`conductor.` of
//!   `coatedconductor`): `uroughness`/`vroughness`, each defaulting to `roughness` (0);
//!   `remaproughness` (default true) applies to all of a material's roughnesses.
//! - coats: `thickness` >= 0 (0.01), `albedo` RGB in [0, 1] (0), `g` in [-1, 1] (0),
//!   `maxdepth` 0..=1000 (10), `nsamples` 1..=1024 (1); `coatedconductor` takes
//!   `conductor.eta`/`conductor.k` (default copper) or `reflectance`, not both.
//! - `diffusetransmission`: `reflectance` and `transmittance` in [0, 1], multiplied by `scale`
//!   (>= 0) and clamped to [0, 1] as pbrt-v4 does.
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
use crate::scene::{Coat, Loc, Material, SceneError};

/// Builds material `ty` from `params` (all of which must be used); `loc` is where the type is
/// named.
pub fn make_material(ty: &str, params: &mut ParamSet, loc: &Loc) -> Result<Material, SceneError> {
    let m = match ty {
        "diffuse" => Material::Diffuse {
            reflectance: albedo(params, "reflectance", Vec3::splat(0.5))?,
        },
        "dielectric" => dielectric(params)?,
        "thindielectric" => Material::ThinDielectric {
            eta: dielectric_eta(params, "eta")?,
        },
        "conductor" => conductor(params)?,
        "diffusetransmission" => diffuse_transmission(params)?,
        "coateddiffuse" => coated_diffuse(params)?,
        "coatedconductor" => coated_conductor(params)?,
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

/// `dielectric`: `eta` and roughness.
fn dielectric(params: &mut ParamSet) -> Result<Material, SceneError> {
    let eta = dielectric_eta(params, "eta")?;
    let rough = roughness_pair(params, "")?;
    let (alpha_u, alpha_v) = remap(params, rough)?;
    Ok(Material::Dielectric {
        eta,
        alpha_u,
        alpha_v,
    })
}

/// A dielectric's index `name`: a float or a constant spectrum (default 1.5), positive.
fn dielectric_eta(params: &mut ParamSet, name: &str) -> Result<f32, SceneError> {
    let eta = match params.peek(name).map(|p| p.ty) {
        Some(ParamType::Spectrum) => constant_spectrum(params, name)?,
        _ => params.get_float(name, 1.5)?,
    };
    if eta.is_nan() || eta <= 0.0 || eta.is_infinite() {
        let p = params.peek(name).expect("a bad eta came from the file");
        return Err(p.err(format!("{name} must be positive and finite")));
    }
    Ok(eta)
}

/// A float parameter that must lie in `[lo, hi]`.
fn float_in(
    params: &mut ParamSet,
    name: &str,
    default: f32,
    lo: f32,
    hi: f32,
) -> Result<f32, SceneError> {
    let v = params.get_float(name, default)?;
    if !(lo..=hi).contains(&v) {
        let p = params
            .peek(name)
            .expect("an out-of-range value came from the file");
        return Err(p.err(format!("{name} must lie in [{lo}, {hi}]")));
    }
    Ok(v)
}

/// An integer parameter that must lie in `[lo, hi]`.
fn int_in(
    params: &mut ParamSet,
    name: &str,
    default: i32,
    lo: i32,
    hi: i32,
) -> Result<u32, SceneError> {
    let v = params.get_int(name, default)?;
    if !(lo..=hi).contains(&v) {
        let p = params
            .peek(name)
            .expect("an out-of-range value came from the file");
        return Err(p.err(format!("{name} must lie in {lo}..={hi}")));
    }
    Ok(v as u32)
}

/// `diffusetransmission`: `reflectance`, `transmittance` (0.25 each) times `scale` (1).
fn diffuse_transmission(params: &mut ParamSet) -> Result<Material, SceneError> {
    let r = albedo(params, "reflectance", Vec3::splat(0.25))?;
    let t = albedo(params, "transmittance", Vec3::splat(0.25))?;
    let scale = float_in(params, "scale", 1.0, 0.0, f32::MAX)?;
    Ok(Material::DiffuseTransmission {
        reflectance: (r * scale).min(Vec3::ONE),
        transmittance: (t * scale).min(Vec3::ONE),
    })
}

/// The slab of a coat (`thickness`, `albedo`, `g`, `maxdepth`, `nsamples`) under an interface
/// of index `eta` and (not yet remapped) roughness `rough`.
fn coat(params: &mut ParamSet, eta: f32, rough: (f32, f32)) -> Result<Coat, SceneError> {
    let thickness = float_in(params, "thickness", 0.01, 0.0, f32::MAX)?;
    let albedo = albedo(params, "albedo", Vec3::ZERO)?;
    let g = float_in(params, "g", 0.0, -1.0, 1.0)?;
    let max_depth = int_in(params, "maxdepth", 10, 0, 1000)?;
    let n_samples = int_in(params, "nsamples", 1, 1, 1024)?;
    let (alpha_u, alpha_v) = remap(params, rough)?;
    Ok(Coat {
        eta,
        alpha_u,
        alpha_v,
        thickness,
        albedo,
        g,
        max_depth,
        n_samples,
    })
}

/// `coateddiffuse`: a coat over a Lambertian `reflectance` (0.5).
fn coated_diffuse(params: &mut ParamSet) -> Result<Material, SceneError> {
    let reflectance = albedo(params, "reflectance", Vec3::splat(0.5))?;
    let eta = dielectric_eta(params, "eta")?;
    let rough = roughness_pair(params, "")?;
    let coat = coat(params, eta, rough)?;
    Ok(Material::CoatedDiffuse { reflectance, coat })
}

/// `coatedconductor`: an `interface.` coat over a `conductor.` base (or `reflectance`).
fn coated_conductor(params: &mut ParamSet) -> Result<Material, SceneError> {
    let eta = dielectric_eta(params, "interface.eta")?;
    let rough = roughness_pair(params, "interface.")?;
    let (ce, ck) = conductor_index(params, "conductor.")?;
    let base_rough = roughness_pair(params, "conductor.")?;
    let remap_on = params.get_bool("remaproughness", true)?;
    let (alpha_u, alpha_v) = if remap_on {
        (base_rough.0.sqrt(), base_rough.1.sqrt())
    } else {
        base_rough
    };
    let coat = coat(params, eta, rough)?;
    Ok(Material::CoatedConductor {
        coat,
        eta: ce,
        k: ck,
        alpha_u,
        alpha_v,
    })
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
    let (eta, k) = conductor_index(params, "")?;
    let rough = roughness_pair(params, "")?;
    let (alpha_u, alpha_v) = remap(params, rough)?;
    Ok(Material::Conductor {
        eta,
        k,
        alpha_u,
        alpha_v,
    })
}

/// A conductor's complex index: `reflectance`, or `{prefix}eta`/`{prefix}k` (default copper).
fn conductor_index(params: &mut ParamSet, prefix: &str) -> Result<(Vec3, Vec3), SceneError> {
    let (eta_name, k_name) = (format!("{prefix}eta"), format!("{prefix}k"));
    match params.get_rgb_opt("reflectance")? {
        Some(r) => {
            if let Some(p) = params.peek(&eta_name).or_else(|| params.peek(&k_name)) {
                return Err(p.err(format!(
                    "a conductor takes either \"reflectance\" or \"{eta_name}\"/\"{k_name}\", not both"
                )));
            }
            if r.min_element() < 0.0 || r.max_element() > 1.0 {
                let p = params.peek("reflectance").expect("given");
                return Err(p.err("reflectance values must lie in [0, 1]"));
            }
            Ok((Vec3::ONE, k_from_reflectance(r)))
        }
        None => Ok((
            metal(params, &eta_name, CU_ETA)?,
            metal(params, &k_name, CU_K)?,
        )),
    }
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

/// Roughness `({prefix}uroughness, {prefix}vroughness)`, each defaulting to
/// `{prefix}roughness` (0), not yet remapped; negative values are errors.
fn roughness_pair(params: &mut ParamSet, prefix: &str) -> Result<(f32, f32), SceneError> {
    let names = [
        format!("{prefix}uroughness"),
        format!("{prefix}vroughness"),
        format!("{prefix}roughness"),
    ];
    let u = params.get_float_opt(&names[0])?;
    let v = params.get_float_opt(&names[1])?;
    let both = if u.is_none() || v.is_none() {
        params.get_float(&names[2], 0.0)?
    } else {
        0.0
    };
    let (u, v) = (u.unwrap_or(both), v.unwrap_or(both));
    if u >= 0.0 && v >= 0.0 && u.is_finite() && v.is_finite() {
        return Ok((u, v));
    }
    let bad = names
        .iter()
        .filter_map(|n| params.peek(n))
        .find(|p| {
            p.floats()
                .is_some_and(|f| !(f[0] >= 0.0 && f[0].is_finite()))
        })
        .expect("a bad roughness came from the file");
    Err(bad.err("roughness must be finite and not negative"))
}

/// Trowbridge-Reitz alphas from roughness: `sqrt` when `remaproughness` (default true) is set,
/// as pbrt-v4's `RoughnessToAlpha`.
fn remap(params: &mut ParamSet, (u, v): (f32, f32)) -> Result<(f32, f32), SceneError> {
    if params.get_bool("remaproughness", true)? {
        Ok((u.sqrt(), v.sqrt()))
    } else {
        Ok((u, v))
    }
}
