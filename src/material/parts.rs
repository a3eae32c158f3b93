//! The parts several materials share, with the rules for reading them:
//!
//! - reflectances (`albedo`): an RGB in [0, 1] or a spectrum texture (clamped per hit);
//! - a conductor's index ([`Metal`]): `eta`/`k` as RGB, pbrt-v4's named spectra
//!   `metal-{Ag,Al,Au,Cu,CuZn,MgO,TiO2}-{eta,k}` (with or without brackets, as the RGB values
//!   of [`super::spectra`]; default copper) or textures; or `reflectance` r, giving pbrt-v4's
//!   eta = 1, k = 2 sqrt(r) / sqrt(1 - r) (r clamped to 1 - 1e-7 so k stays finite); giving
//!   both is an error, as in pbrt-v4;
//! - microfacet [`Roughness`]: `uroughness`/`vroughness`, each defaulting to `roughness` (0),
//!   floats or float textures; `remaproughness` (default true) maps roughness to
//!   Trowbridge-Reitz alpha = sqrt(roughness) as pbrt-v4's `RoughnessToAlpha` does; prefixed
//!   `interface.`/`conductor.` for coatedconductor (one `remaproughness` for both);
//! - a dielectric's index (`eta`, coatedconductor's `interface.eta`): a float, or a `spectrum`
//!   that is constant (one number, or wavelength-value pairs with one value) or a named glass
//!   (`glass-BK7`, `glass-BAF10`, `glass-FK51A`, `glass-LASF9`, `glass-F5`, `glass-F10`,
//!   `glass-F11`: its index at 550 nm, see [`super::spectra`]), positive and finite;
//! - a [`Coat`]: `thickness` (0.01) and `g` (0, in [-1, 1]) floats or float textures, `albedo`
//!   (0) a reflectance, `maxdepth` 0..=1000 (10), `nsamples` 1..=1024 (1).
use super::spectra::{self, CU_ETA, CU_K};
use crate::bsdf::{
    k_from_reflectance, layered, Bxdf, BxdfFlags, Conductor, Dielectric, TrowbridgeReitz,
};
use crate::math::Vec3;
use crate::params::{ParamSet, ParamType, SceneError};
use crate::spectrum::Spectrum;
use crate::texture::{texture_param, Tex, TexCoord, Textures};

/// A reflectance texture at `tc`, clamped to [0, 1] as pbrt-v4 does, at the lookup's wavelengths.
pub fn unit(t: &Tex, tc: &TexCoord) -> Spectrum {
    tc.lambda.albedo(t.eval(tc).clamp(Vec3::ZERO, Vec3::ONE))
}

/// The coat and slab of `coateddiffuse` and `coatedconductor` (pbrt-v4's defaults: `eta` 1.5,
/// `thickness` 0.01, `albedo` 0, `g` 0, `maxdepth` 10, `nsamples` 1).
#[derive(Clone, Debug, PartialEq)]
pub struct Coat {
    pub eta: f32,
    pub thickness: Tex,
    pub albedo: Tex,
    pub g: Tex,
    pub max_depth: u32,
    pub n_samples: u32,
}

impl Coat {
    pub fn for_each_texture(&self, f: &mut dyn FnMut(&Tex)) {
        f(&self.thickness);
        f(&self.albedo);
        f(&self.g);
    }
}

/// A conductor's complex index of refraction: `eta` and `k` (RGB, named spectra or textures),
/// or pbrt-v4's `reflectance` r, per hit: eta = 1, k = 2 sqrt(r) / sqrt(1 - r).
#[derive(Clone, Debug, PartialEq)]
pub enum Metal {
    EtaK { eta: Tex, k: Tex },
    Reflectance(Tex),
}

/// Microfacet roughness in u and v (`uroughness`, `vroughness`, each defaulting to
/// `roughness`); with `remap` (pbrt-v4's `remaproughness`, default true) the Trowbridge-Reitz
/// alpha is sqrt(roughness), else the roughness itself. Alpha 0 is a perfect mirror.
#[derive(Clone, Debug, PartialEq)]
pub struct Roughness {
    pub u: Tex,
    pub v: Tex,
    pub remap: bool,
}

impl Roughness {
    /// A constant roughness (`alpha_u`, `alpha_v` as given, not remapped).
    pub fn alphas(alpha_u: f32, alpha_v: f32) -> Roughness {
        Roughness {
            u: alpha_u.into(),
            v: alpha_v.into(),
            remap: false,
        }
    }

    /// The Trowbridge-Reitz alphas at `tc` (negative texture values count as 0).
    pub fn eval(&self, tc: &TexCoord) -> (f32, f32) {
        (
            self.alpha(self.u.eval_float(tc)),
            self.alpha(self.v.eval_float(tc)),
        )
    }

    /// Whether the alphas may somewhere be below `min_alpha` (a textured roughness may).
    pub fn narrower_than(&self, min_alpha: f32) -> bool {
        self.constant().is_none_or(|(u, v)| u.min(v) < min_alpha)
    }

    /// Calls `f` on the u and v textures.
    pub fn for_each_texture(&self, f: &mut dyn FnMut(&Tex)) {
        f(&self.u);
        f(&self.v);
    }

    /// The alphas when they are the same everywhere.
    pub fn constant(&self) -> Option<(f32, f32)> {
        let (u, v) = (self.u.constant()?, self.v.constant()?);
        Some((self.alpha(u.x), self.alpha(v.x)))
    }

    fn alpha(&self, roughness: f32) -> f32 {
        let r = roughness.max(0.0);
        if self.remap {
            r.sqrt()
        } else {
            r
        }
    }
}

/// Calls `f` on the textures of a conductor's index.
pub fn metal_textures(m: &Metal, f: &mut dyn FnMut(&Tex)) {
    match m {
        Metal::EtaK { eta, k } => {
            f(eta);
            f(k);
        }
        Metal::Reflectance(r) => f(r),
    }
}

/// The specular and/or glossy lobe of a microfacet surface whose roughness may vary.
pub fn microfacet_lobe(r: &Roughness) -> BxdfFlags {
    match r.constant() {
        Some((u, v)) if TrowbridgeReitz::new(u, v).effectively_smooth() => BxdfFlags::SPECULAR,
        Some(_) => BxdfFlags::GLOSSY,
        None => BxdfFlags::SPECULAR | BxdfFlags::GLOSSY,
    }
}

/// Whether a texture is the constant 0 (black everywhere).
pub fn is_zero(t: &Tex) -> bool {
    t.constant().is_some_and(|v| v.max_element() <= 0.0)
}

/// A conductor's BSDF at `tc`, its index divided by `outside` (the index of the medium above
/// it: 1, or a coat's).
pub fn conductor_bxdf(
    metal: &Metal,
    roughness: &Roughness,
    outside: f32,
    tc: &TexCoord,
) -> Conductor {
    let (eta, k) = match metal {
        Metal::EtaK { eta, k } => (
            tc.lambda.unbounded(eta.eval(tc)),
            tc.lambda.unbounded(k.eval(tc)),
        ),
        Metal::Reflectance(r) => (Spectrum::ONE, k_from_reflectance(unit(r, tc))),
    };
    let e = if outside > 0.0 { outside } else { 1.0 };
    let (au, av) = roughness.eval(tc);
    Conductor::new(eta / e, k / e, au, av)
}

/// The layered BSDF at `tc` of a coat of `roughness` over `base`.
pub fn coated_bxdf<B: Bxdf + Copy>(
    c: &Coat,
    roughness: &Roughness,
    base: B,
    tc: &TexCoord,
) -> layered::Layered<Dielectric, B> {
    let (au, av) = roughness.eval(tc);
    let top = Dielectric::rough(c.eta, au, av);
    let (thickness, g) = (c.thickness.eval_float(tc), c.g.eval_float(tc));
    let albedo = unit(&c.albedo, tc);
    layered::Layered::new(top, base, thickness, albedo, g, c.max_depth, c.n_samples)
}

/// A parameter that may be a texture: `spectrum` (RGB) or float, `default` when absent.
pub fn tex(
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
pub fn is_texture(params: &ParamSet, name: &str) -> bool {
    params.peek(name).map(|p| p.ty) == Some(ParamType::Texture)
}

/// A reflectance: a spectrum texture (values clamped to [0, 1] per hit, as pbrt-v4 does), or an
/// RGB checked to lie in [0, 1].
pub fn albedo(
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
pub fn dielectric_eta(params: &mut ParamSet, name: &str) -> Result<f32, SceneError> {
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
pub fn float_in(
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
pub fn int_in(
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
pub fn float_tex_in(
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
pub fn coat(
    params: &mut ParamSet,
    eta_name: &str,
    textures: &Textures,
) -> Result<Coat, SceneError> {
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

/// A conductor's index: `reflectance`, or `{prefix}eta`/`{prefix}k` (default copper).
pub fn metal_index(
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
pub fn roughness(
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
