//! Texture-valued parameters of materials and textures: a `"texture"` naming one defined
//! earlier in the right namespace (spectrum for colours, float for the rest), or a value.
//!
//! ```text
//! Material "diffuse" "texture reflectance" "wood"     # a spectrum texture
//! Material "conductor" "float roughness" 0.1          # a constant
//! ```
use super::{Texture, Textures};
use crate::math::Vec3;
use crate::params::{ParamSet, ParamType, SceneError};
use std::sync::Arc;

/// A constant value: `rgb` for a spectrum texture, `float` otherwise (splatted).
pub fn value(
    params: &mut ParamSet,
    name: &str,
    spectrum: bool,
    default: f32,
) -> Result<Vec3, SceneError> {
    if spectrum {
        params.get_rgb(name, Vec3::splat(default))
    } else {
        Ok(Vec3::splat(params.get_float(name, default)?))
    }
}

/// A texture-valued parameter: a `"texture"` name of the right namespace, or a value.
pub fn texture_param(
    params: &mut ParamSet,
    name: &str,
    spectrum: bool,
    default: f32,
    textures: &Textures,
) -> Result<Arc<Texture>, SceneError> {
    match named_texture(params, name, spectrum, textures)? {
        Some(t) => Ok(t),
        None => Ok(Arc::new(Texture::Constant(value(
            params, name, spectrum, default,
        )?))),
    }
}

/// The texture a `"texture name" "tex"` parameter names in the spectrum or float namespace, or
/// `None` (nothing read) when parameter `name` is absent or not texture-typed. A name that is
/// not defined in that namespace is an error at the parameter (which says when the name is a
/// texture of the other kind).
pub fn named_texture(
    params: &mut ParamSet,
    name: &str,
    spectrum: bool,
    textures: &Textures,
) -> Result<Option<Arc<Texture>>, SceneError> {
    if params.peek(name).map(|p| p.ty) != Some(ParamType::Texture) {
        return Ok(None);
    }
    let p = params.get_param(name).expect("just peeked");
    let Some([tex]) = p.strings() else {
        return Err(p.err("expected one texture name"));
    };
    let (map, other, kind, other_kind) = if spectrum {
        (&textures.spectrum, &textures.float, "spectrum", "float")
    } else {
        (&textures.float, &textures.spectrum, "float", "spectrum")
    };
    if let Some(t) = map.get(tex) {
        return Ok(Some(t.clone()));
    }
    let hint = if other.contains_key(tex) {
        format!(" (\"{tex}\" is a {other_kind} texture)")
    } else {
        String::new()
    };
    Err(p.err(format!("unknown {kind} texture \"{tex}\"{hint}")))
}
