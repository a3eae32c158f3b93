//! `Texture "name" "spectrum"|"float" CLASS params`: builds a [`Texture`] (see
//! [`crate::texture`] for the classes and lookup rules) and reads image files once each.
//!
//! ```text
//! Texture "wood" "spectrum" "imagemap" "string filename" "textures/wood.png"
//!     "string wrap" "clamp" "float uscale" 4 "float vscale" 4
//! Texture "mask" "float" "imagemap" "string filename" "mask.tga" "string encoding" "gamma 2.2"
//! Texture "checks" "spectrum" "checkerboard" "rgb tex1" [ 1 1 1 ] "texture tex2" "wood"
//! Texture "dim" "spectrum" "scale" "texture tex" "wood" "texture scale" "mask"
//! Texture "m" "spectrum" "mix" "texture tex1" "wood" "rgb tex2" [ 0 0 1 ] "float amount" 0.3
//! Texture "one" "float" "constant" "float value" 1
//! ```
//!
//! Spectrum and float textures are separate namespaces, as in pbrt-v4; a texture-valued
//! parameter (`tex`, `tex1`, `tex2`, `scale`, `amount`) takes a `"texture"` name defined earlier
//! or a value (`rgb` for spectrum textures, `float` for float ones and for `scale`/`amount`).
//! Image files are PNG, TGA, JPEG, EXR and PFM (decoded by [`crate::imageio::decode`]), paths
//! relative to the main file's directory; each (file, encoding) is decoded once, and its MIP
//! pyramid built once when a `trilinear` texture reads it. Only the `uv` mapping and 2D
//! checkerboards are supported.

use super::params::ParamSet;
use super::LoadBudget;
use crate::math::Vec2;
use crate::scene::{clip_for_message, Loc, SceneError};
use crate::texture::{
    texture_param, value, Encoding, Filter, Image, ImageMap, Pyramid, Texture, Textures, UvMapping,
    Wrap,
};
use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::sync::Arc;

/// Decoded images by file and encoding, shared by every texture that reads them, with their
/// MIP pyramid once a trilinear texture asked for it.
pub type ImageCache = HashMap<(PathBuf, String), (Arc<Image>, Option<Arc<Pyramid>>)>;

/// Everything building a texture needs besides its parameters.
pub struct TextureContext<'a> {
    pub textures: &'a Textures,
    pub images: &'a mut ImageCache,
    pub base_dir: &'a Path,
    /// What decoded images may allocate.
    pub budget: &'a super::LoadBudget,
    /// Notes on what was accepted but read otherwise than written (`file:line:col: ...`).
    pub notes: &'a mut Vec<String>,
}

/// Builds texture `class` of kind `kind` (`spectrum` or `float`) from `params` (which the
/// caller checks for unused ones); `at` is where the class is named.
pub fn make_texture(
    kind: &str,
    class: &str,
    params: &mut ParamSet,
    at: &Loc,
    cx: &mut TextureContext,
) -> Result<Texture, SceneError> {
    let spectrum = match kind {
        "spectrum" => true,
        "float" => false,
        other => {
            return Err(SceneError::at(
                at,
                format!("texture type must be \"spectrum\" or \"float\", not \"{other}\""),
            ))
        }
    };
    Ok(match class {
        "constant" => Texture::Constant(value(params, "value", spectrum, 1.0)?),
        "scale" => Texture::Scale {
            tex: texture_param(params, "tex", spectrum, 1.0, cx.textures)?,
            scale: texture_param(params, "scale", false, 1.0, cx.textures)?,
        },
        "mix" => Texture::Mix {
            tex1: texture_param(params, "tex1", spectrum, 0.0, cx.textures)?,
            tex2: texture_param(params, "tex2", spectrum, 1.0, cx.textures)?,
            amount: texture_param(params, "amount", false, 0.5, cx.textures)?,
        },
        "checkerboard" => {
            if params.get_int("dimension", 2)? != 2 {
                let p = params.peek("dimension").expect("given");
                return Err(p.err("only 2D checkerboards are supported"));
            }
            Texture::Checkerboard {
                mapping: uv_mapping(params)?,
                tex1: texture_param(params, "tex1", spectrum, 1.0, cx.textures)?,
                tex2: texture_param(params, "tex2", spectrum, 0.0, cx.textures)?,
            }
        }
        "imagemap" => Texture::Image(image_map(params, at, !spectrum, cx)?),
        other => {
            return Err(SceneError::at(
                at,
                format!("unsupported texture class \"{other}\""),
            ))
        }
    })
}

/// Deepest texture graph accepted (a texture naming one that names another ... `n` deep):
/// lookups recurse this deep.
pub const MAX_TEXTURE_DEPTH: u32 = 64;
/// Most textures one lookup may evaluate, counting a texture each time it is reached: a
/// texture named twice by the next one doubles the work at every step.
pub const MAX_TEXTURE_LOOKUPS: u64 = 10_000;

/// What one lookup of `t` costs: textures evaluated (with repetition, saturating) and depth.
/// `known` holds the cost of named textures by address (their `Arc`'s pointer), so that the
/// cost of a graph whose parts are shared is found in time linear in its definitions.
pub fn lookup_work(t: &Texture, known: &HashMap<usize, (u64, u32)>) -> (u64, u32) {
    let children: Vec<&Arc<Texture>> = match t {
        Texture::Constant(_) | Texture::Image(_) => vec![],
        Texture::Checkerboard { tex1, tex2, .. } => vec![tex1, tex2],
        Texture::Scale { tex, scale } => vec![tex, scale],
        Texture::Mix { tex1, tex2, amount } => vec![tex1, tex2, amount],
    };
    children.iter().fold((1, 1), |(n, d), c| {
        let (cn, cd) = known
            .get(&(Arc::as_ptr(c) as usize))
            .copied()
            .unwrap_or_else(|| lookup_work(c, known));
        (n.saturating_add(cn), d.max(cd.saturating_add(1)))
    })
}

/// `mapping "uv"` with `uscale`, `vscale`, `udelta`, `vdelta`.
fn uv_mapping(params: &mut ParamSet) -> Result<UvMapping, SceneError> {
    let mapping = params.get_string("mapping", "uv")?;
    if mapping != "uv" {
        let p = params.peek("mapping").expect("given");
        return Err(p.err(format!("unsupported texture mapping \"{mapping}\"")));
    }
    Ok(UvMapping {
        scale: Vec2::new(
            params.get_float("uscale", 1.0)?,
            params.get_float("vscale", 1.0)?,
        ),
        delta: Vec2::new(
            params.get_float("udelta", 0.0)?,
            params.get_float("vdelta", 0.0)?,
        ),
    })
}

/// A string parameter parsed by `parse`, with `what` naming the accepted values on error.
fn choice<T>(
    params: &mut ParamSet,
    name: &str,
    default: &str,
    parse: impl Fn(&str) -> Option<T>,
    what: &str,
) -> Result<T, SceneError> {
    let s = params.get_string(name, default)?;
    parse(&s).ok_or_else(|| {
        let p = params.peek(name).expect("a bad value came from the file");
        p.err(format!("\"{s}\" is not {what}"))
    })
}

/// `imagemap`: the image (read once per file and encoding), mapping, wrap, filter, scale,
/// invert.
fn image_map(
    params: &mut ParamSet,
    at: &Loc,
    float: bool,
    cx: &mut TextureContext,
) -> Result<ImageMap, SceneError> {
    let Some(name) = params.get_string_opt("filename")? else {
        return Err(SceneError::at(at, "imagemap needs \"string filename\""));
    };
    let path = cx.base_dir.join(&name);
    let encoding_name = image_encoding(params, &path, cx.notes)?;
    let Some(encoding) = Encoding::from_name(&encoding_name) else {
        let p = params
            .peek("encoding")
            .expect("a bad encoding came from the file");
        return Err(p.err(format!(
            "\"{encoding_name}\" is not an encoding (sRGB, linear, gamma G)"
        )));
    };
    let wrap = choice(
        params,
        "wrap",
        "repeat",
        Wrap::from_name,
        "repeat, clamp or black",
    )?;
    let filter = choice(
        params,
        "filter",
        "bilinear",
        |s| match s {
            "point" => Some(Filter::Point),
            "bilinear" => Some(Filter::Bilinear),
            "trilinear" | "ewa" => Some(Filter::Trilinear),
            _ => None,
        },
        "point, bilinear, trilinear or ewa",
    )?;
    params.get_float("maxanisotropy", 8.0)?;
    let mapping = uv_mapping(params)?;
    let scale = params.get_float("scale", 1.0)?;
    let invert = params.get_bool("invert", false)?;
    let key = (path.clone(), encoding_name);
    if !cx.images.contains_key(&key) {
        let im = Arc::new(read_image(&path, encoding, cx.budget).map_err(|m| {
            SceneError::at(
                at,
                format!("imagemap \"{}\": {m}", clip_for_message(&name, 60)),
            )
        })?);
        cx.images.insert(key.clone(), (im, None));
    }
    let (image, pyramid) = cx.images.get_mut(&key).expect("inserted above");
    if filter == Filter::Trilinear && pyramid.is_none() {
        let texels = Pyramid::texel_count(image.width, image.height) as u64;
        cx.budget
            .reserve(texels * 12, "its MIP pyramid")
            .map_err(|m| {
                SceneError::at(
                    at,
                    format!("imagemap \"{}\": {m}", clip_for_message(&name, 60)),
                )
            })?;
        *pyramid = Some(Arc::new(Pyramid::build(image)));
    }
    let (image, pyramid) = (image.clone(), pyramid.clone());
    Ok(ImageMap {
        image,
        mapping,
        wrap,
        filter,
        scale,
        invert,
        float,
        pyramid: pyramid.filter(|_| filter == Filter::Trilinear),
    })
}

/// The encoding an `imagemap` decodes its file with, by pbrt-v4's rules (`Image::Read`): a PNG
/// uses `"string encoding"` (default `sRGB`); the 8-bit formats pbrt-v4 reads through stb
/// (TGA, JPEG, BMP, ...) are always sRGB, whatever `encoding` says (a note says so when it
/// says otherwise); float images (EXR, PFM) are linear and the parameter is read but moot.
fn image_encoding(
    params: &mut ParamSet,
    path: &Path,
    notes: &mut Vec<String>,
) -> Result<String, SceneError> {
    let ext = path
        .extension()
        .map(|e| e.to_string_lossy().to_ascii_lowercase())
        .unwrap_or_default();
    match ext.as_str() {
        "png" => params.get_string("encoding", "sRGB"),
        "exr" | "pfm" => params.get_string("encoding", "linear"),
        _ => {
            let given = params.get_string("encoding", "sRGB")?;
            if given != "sRGB" {
                let at = params.loc("encoding").expect("given when not the default");
                notes.push(format!(
                    "{at}: \"encoding\" \"{}\" ignored: pbrt-v4 decodes 8-bit {} images as sRGB",
                    crate::scene::clip_for_message(&given, 40),
                    ext.to_ascii_uppercase()
                ));
            }
            Ok("sRGB".to_string())
        }
    }
}

/// Reads an image file into linear RGB ([`crate::imageio::decode::read_image`]: sizes checked
/// and reserved in `budget` before decoding), integer images decoded with `encoding`.
pub fn read_image(path: &Path, encoding: Encoding, budget: &LoadBudget) -> Result<Image, String> {
    let t = crate::imageio::decode::read_image(path, &|v| encoding.decode(v), budget)?;
    Ok(Image {
        width: t.width,
        height: t.height,
        texels: t.texels,
    })
}
