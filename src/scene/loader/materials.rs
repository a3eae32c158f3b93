//! `Material`, `MakeNamedMaterial`: the diffuse, dielectric, thin dielectric, conductor,
//! diffuse-transmission and coated materials with pbrt-v4's parameters and defaults.
//!
//! ```text
//! Material "diffuse" "rgb reflectance" [ 0.8 0.8 0.8 ]                  # default 0.5
//! Material "dielectric" "float eta" 1.5 "float roughness" 0.01           # default smooth
//! Material "thindielectric" "float eta" 1.5
//! Material "diffusetransmission" "rgb reflectance" [ 0.25 0.25 0.25 ]
//!     "rgb transmittance" [ 0.25 0.25 0.25 ] "float scale" 1             # defaults
//! Material "coateddiffuse" "rgb reflectance" [ 0.5 0.5 0.5 ] "float roughness" 0
//!     "float thickness" 0.01 "float eta" 1.5 "rgb albedo" [ 0 0 0 ] "float g" 0
//!     "integer maxdepth" 10 "integer nsamples" 1                         # defaults
//! Material "coatedconductor" "float interface.roughness" 0 "float interface.eta" 1.5
//!     "spectrum conductor.eta" "metal-Cu-eta" "spectrum conductor.k" "metal-Cu-k"
//!     "float conductor.roughness" 0 "float thickness" 0.01 ...           # defaults
//! Material "conductor" "spectrum eta" "metal-Au-eta" "spectrum k" "metal-Au-k"
//!     "float roughness" 0.1 "bool remaproughness" true                    # alpha = sqrt(0.1)
//! Material "conductor" "rgb reflectance" [ 0.9 0.6 0.3 ]                 # eta 1, k from r
//! Material "diffuse" "texture reflectance" "wood" "texture displacement" "bumps"
//! Material "conductor" "texture roughness" "scratches" "texture reflectance" "tint"
//! Material "mix" "string materials" [ "wood" "paint" ] "texture amount" "wear"
//! ```
//!
//! - Parameters pbrt-v4 lets be textures may be: diffuse `reflectance`; conductor `eta`, `k`,
//!   `reflectance`, `roughness`, `uroughness`, `vroughness`; dielectric roughness;
//!   diffusetransmission `reflectance`, `transmittance`; coateddiffuse `reflectance`,
//!   roughness, `thickness`, `albedo`, `g`; coatedconductor `interface.`/`conductor.`
//!   roughness, `conductor.eta`, `conductor.k`, `reflectance`, `thickness`, `albedo`, `g`; and
//!   every material's `displacement` (a float texture: bump mapping). A `"texture"` value names a texture defined
//!   earlier in the right namespace (spectrum for colours, float for the others).
//! - conductor `eta`/`k`: RGB, or pbrt-v4's named spectra `metal-{Ag,Al,Au,Cu,CuZn,MgO,TiO2}-
//!   {eta,k}` (with or without brackets) as the RGB values of [`super::spectra`]; default
//!   copper. `reflectance` r instead gives pbrt-v4's
//!   eta = 1, k = 2 sqrt(r) / sqrt(1 - r) (r clamped to 1 - 1e-7 so k stays finite); giving
//!   both is an error, as in pbrt-v4.
//! - conductor roughness: `uroughness`/`vroughness`, each defaulting to `roughness` (0);
//!   `remaproughness` (default true) maps roughness to Trowbridge-Reitz alpha = sqrt(roughness)
//!   as pbrt-v4's `RoughnessToAlpha` does.
//! - dielectric, thindielectric and coateddiffuse `eta`, coatedconductor `interface.eta`: a
//!   float, or a `spectrum` that is constant (one number, or wavelength-value pairs with one
//!   value) or a named glass (`glass-BK7`, `glass-BAF10`, `glass-FK51A`, `glass-LASF9`,
//!   `glass-F5`, `glass-F10`, `glass-F11`: its index at 550 nm, see [`super::spectra`]).
//! - roughness of every microfacet part as the conductor's (`interface.` and `conductor.`
//!   prefixes for coatedconductor; one `remaproughness` for both).
//! - coats: `thickness` (0.01) and `g` (0, in [-1, 1]) floats or float textures, `albedo`
//!   (0) a reflectance, `maxdepth` 0..=1000 (10), `nsamples` 1..=1024 (1); coatedconductor
//!   takes `conductor.eta`/`conductor.k` (default copper) or `reflectance`, not both.
//! - diffusetransmission `scale` (1) is a float >= 0; the scaled colours are clamped to
//!   [0, 1] per hit as pbrt-v4 does.
//! - RGB reflectances must lie in [0, 1] (pbrt-v4 rejects others too).

use super::params::{ParamSet, ParamType};
use super::spectra::{self, CU_ETA, CU_K};
use super::textures::texture_param;
use crate::math::Vec3;
use crate::scene::{Coat, Loc, Material, MaterialKind, Metal, Roughness, SceneError};
use crate::texture::{Tex, Textures};
use std::collections::HashMap;

/// Builds material `ty` from `params` (all of which must be used); `loc` is where the type is
/// named; `textures` are those defined so far.
/// What a material may refer to: the textures and the named materials defined before it.
pub struct MaterialContext<'a> {
    pub textures: &'a Textures,
    pub named: &'a std::collections::HashMap<String, u32>,
    pub materials: &'a [Material],
}

pub fn make_material(
    ty: &str,
    params: &mut ParamSet,
    loc: &Loc,
    cx: &MaterialContext,
) -> Result<Material, SceneError> {
    let textures = cx.textures;
    if ty == "mix" {
        let kind = mix(params, loc, cx)?;
        params.check_unused()?;
        return Ok(Material {
            kind,
            displacement: None,
        });
    }
    let kind =
        match ty {
            "diffuse" => MaterialKind::Diffuse {
                reflectance: albedo(params, "reflectance", Vec3::splat(0.5), textures)?,
            },
            "dielectric" => MaterialKind::Dielectric {
                eta: dielectric_eta(params, "eta")?,
                roughness: roughness(params, "", textures)?,
            },
            "thindielectric" => MaterialKind::ThinDielectric {
                eta: dielectric_eta(params, "eta")?,
            },
            "conductor" => conductor(params, textures)?,
            "diffusetransmission" => MaterialKind::DiffuseTransmission {
                reflectance: albedo(params, "reflectance", Vec3::splat(0.25), textures)?,
                transmittance: albedo(params, "transmittance", Vec3::splat(0.25), textures)?,
                scale: float_in(params, "scale", 1.0, 0.0, f32::MAX)?,
            },
            "coateddiffuse" => MaterialKind::CoatedDiffuse {
                reflectance: albedo(params, "reflectance", Vec3::splat(0.5), textures)?,
                roughness: roughness(params, "", textures)?,
                coat: coat(params, "eta", textures)?,
            },
            "coatedconductor" => MaterialKind::CoatedConductor {
                interface: roughness(params, "interface.", textures)?,
                coat: coat(params, "interface.eta", textures)?,
                metal: metal_index(params, "conductor.", textures)?,
                roughness: roughness(params, "conductor.", textures)?,
            },
            "interface" => return Err(SceneError::at(
                loc,
                "material \"interface\" only bounds participating media, which photon does not \
                 support (MakeNamedMedium and MediumInterface are errors too)",
            )),
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

/// `mix`: `"string materials" [ "a" "b" ]` (named materials defined earlier) and `amount`
/// (float or float texture, default 0.5: the probability of the second).
fn mix(params: &mut ParamSet, loc: &Loc, cx: &MaterialContext) -> Result<MaterialKind, SceneError> {
    let Some(p) = params.get_param("materials") else {
        return Err(SceneError::at(
            loc,
            "mix needs \"string materials\" naming two materials",
        ));
    };
    let names: Vec<String> = match p.strings() {
        Some(v) if v.len() == 2 => v.to_vec(),
        _ => return Err(p.err("expected two material names")),
    };
    let mut materials = [0u32; 2];
    let mut flags = crate::bsdf::BxdfFlags::default();
    for (i, name) in names.iter().enumerate() {
        let Some(&idx) = cx.named.get(name) else {
            return Err(p.err(format!("unknown named material \"{name}\"")));
        };
        materials[i] = idx;
        flags = flags | cx.materials[idx as usize].kind.flags();
    }
    let depth = 1 + materials
        .iter()
        .map(|&m| mix_depth(cx.materials, m, &mut HashMap::new()))
        .max()
        .unwrap_or(0);
    if depth > crate::scene::MAX_MIX_DEPTH {
        return Err(p.err(format!(
            "this mix nests {depth} mix materials (at most {})",
            crate::scene::MAX_MIX_DEPTH
        )));
    }
    let amount = tex(params, "amount", false, 0.5, cx.textures)?;
    Ok(MaterialKind::Mix {
        materials,
        amount,
        flags,
    })
}

/// How many `mix` materials deep material `m` nests (0 for any other material); `memo` keeps
/// each material's depth so that a mix naming the same mix twice at every level costs linear
/// time. Mixes name materials defined before them, so the recursion ends (and was checked to
/// be at most [`crate::scene::MAX_MIX_DEPTH`] deep when each was made).
fn mix_depth(materials: &[Material], m: u32, memo: &mut HashMap<u32, usize>) -> usize {
    if let Some(&d) = memo.get(&m) {
        return d;
    }
    let d = match &materials[m as usize].kind {
        MaterialKind::Mix { materials: two, .. } => {
            1 + two
                .iter()
                .map(|&c| mix_depth(materials, c, memo))
                .max()
                .unwrap_or(0)
        }
        _ => 0,
    };
    memo.insert(m, d);
    d
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

/// A dielectric's index `name`: a float or a constant spectrum (default 1.5), positive and
/// finite.
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

/// A float parameter that may be a texture; a constant must lie in `[lo, hi]`.
fn float_tex_in(
    params: &mut ParamSet,
    name: &str,
    default: f32,
    (lo, hi): (f32, f32),
    textures: &Textures,
) -> Result<Tex, SceneError> {
    if is_texture(params, name) {
        return tex(params, name, false, default, textures);
    }
    Ok(float_in(params, name, default, lo, hi)?.into())
}

/// The coat and slab of a coated material, its index read from `eta_name`.
fn coat(params: &mut ParamSet, eta_name: &str, textures: &Textures) -> Result<Coat, SceneError> {
    Ok(Coat {
        eta: dielectric_eta(params, eta_name)?,
        thickness: float_tex_in(params, "thickness", 0.01, (0.0, f32::MAX), textures)?,
        albedo: albedo(params, "albedo", Vec3::ZERO, textures)?,
        g: float_tex_in(params, "g", 0.0, (-1.0, 1.0), textures)?,
        max_depth: int_in(params, "maxdepth", 10, 0, 1000)?,
        n_samples: int_in(params, "nsamples", 1, 1, 1024)?,
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
fn conductor(params: &mut ParamSet, textures: &Textures) -> Result<MaterialKind, SceneError> {
    let metal = metal_index(params, "", textures)?;
    let roughness = roughness(params, "", textures)?;
    Ok(MaterialKind::Conductor { metal, roughness })
}

/// A conductor's index: `reflectance`, or `{prefix}eta`/`{prefix}k` (default copper).
fn metal_index(
    params: &mut ParamSet,
    prefix: &str,
    textures: &Textures,
) -> Result<Metal, SceneError> {
    let (eta, k) = (format!("{prefix}eta"), format!("{prefix}k"));
    if params.peek("reflectance").is_some() {
        if let Some(p) = params.peek(&eta).or_else(|| params.peek(&k)) {
            return Err(p.err(format!(
                "a conductor takes either \"reflectance\" or \"{eta}\"/\"{k}\", not both"
            )));
        }
        return Ok(Metal::Reflectance(albedo(
            params,
            "reflectance",
            Vec3::ZERO,
            textures,
        )?));
    }
    Ok(Metal::EtaK {
        eta: metal(params, &eta, CU_ETA, textures)?,
        k: metal(params, &k, CU_K, textures)?,
    })
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

/// Microfacet roughness: `{prefix}uroughness`/`{prefix}vroughness`, each defaulting to
/// `{prefix}roughness` (0); floats or float textures; constants must be finite and not
/// negative; `remaproughness` (true) as pbrt-v4.
fn roughness(
    params: &mut ParamSet,
    prefix: &str,
    textures: &Textures,
) -> Result<Roughness, SceneError> {
    let [un, vn, both_n] =
        ["uroughness", "vroughness", "roughness"].map(|n| format!("{prefix}{n}"));
    for name in [&un, &vn, &both_n] {
        if let Some(p) = params.peek(name) {
            if p.floats()
                .is_some_and(|f| f.first().is_some_and(|&x| !(x >= 0.0 && x.is_finite())))
            {
                return Err(p.err("roughness must be finite and not negative"));
            }
        }
    }
    // pbrt-v4 reads `roughness` only for a missing u or v (else it is an unused parameter).
    let given = |params: &ParamSet, n: &str| params.peek(n).is_some();
    let both = if given(params, &un) && given(params, &vn) {
        Tex::from(0.0)
    } else {
        tex(params, &both_n, false, 0.0, textures)?
    };
    let mut one = |name: &str| match given(params, name) {
        true => tex(params, name, false, 0.0, textures),
        false => Ok(both.clone()),
    };
    let u = one(&un)?;
    let v = one(&vn)?;
    let remap = params.get_bool("remaproughness", true)?;
    Ok(Roughness { u, v, remap })
}
