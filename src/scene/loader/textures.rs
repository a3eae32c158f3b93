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
//! Image files are PNG, TGA, JPEG (through the `image` crate), EXR (through
//! [`crate::imageio`]) and PFM ([`read_pfm`]), paths relative to the main file's directory; each (file, encoding) is
//! decoded once, and its MIP pyramid built once when a `trilinear` texture reads it. Only the `uv` mapping and 2D checkerboards are supported.

use super::params::ParamSet;
use super::LoadBudget;
use crate::math::{Vec2, Vec3};
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

/// Reads an image file into linear RGB: EXR through [`crate::imageio`], PFM here, others
/// through the `image` crate; integer images are decoded with `encoding`, float ones (EXR,
/// PFM, float TIFF...) are taken as linear. The size in the file's header is checked against
/// [`crate::limits::MAX_IMAGE_PIXELS`] and the decode's peak (file or decoder buffer,
/// converted copy, texels) reserved in `budget` before anything is decoded; the texels (12
/// bytes each) stay reserved.
pub fn read_image(path: &Path, encoding: Encoding, budget: &LoadBudget) -> Result<Image, String> {
    let ext = |x: &str| path.extension().is_some_and(|e| e.eq_ignore_ascii_case(x));
    let too_many = |w: u64, h: u64| {
        (w.saturating_mul(h) > crate::limits::MAX_IMAGE_PIXELS).then(|| {
            format!(
                "{w}x{h} pixels is more than the {} an image may have",
                crate::limits::MAX_IMAGE_PIXELS
            )
        })
    };
    if ext("pfm") {
        // A colour PFM holds 12 bytes per pixel after a short header: the file, then texels.
        let cap = crate::limits::MAX_IMAGE_PIXELS * 12 + 4096;
        let len = std::fs::metadata(path).map_or(0, |m| m.len().min(cap));
        budget.reserve(2 * len, "decoding it")?;
        let image = super::read_capped(path, cap)
            .map_err(|e| e.to_string())
            .and_then(|bytes| read_pfm(&bytes));
        // The file's bytes are gone; on an error the texels' share too.
        budget.release(if image.is_ok() { len } else { 2 * len });
        return image;
    }
    if ext("exr") {
        let (w, h) = crate::imageio::read_exr_size(path).map_err(|e| e.to_string())?;
        let (w, h) = (w as u64, h as u64);
        // The decoded image, then the texels copied from it.
        budget.reserve(w * h * 24, "decoding it")?;
        let im = crate::imageio::read_exr(path).map_err(|e| {
            budget.release(w * h * 24);
            e.to_string()
        })?;
        budget.release(w * h * 12);
        return Ok(Image {
            width: im.width,
            height: im.height,
            texels: im.pixels.into_iter().map(Vec3::from_array).collect(),
        });
    }
    // The header first: nothing is decoded before the size is checked and reserved.
    let mut reader = image::ImageReader::open(path).map_err(|e| e.to_string())?;
    reader.no_limits(); // the budget below is the limit
    use image::ImageDecoder;
    let decoder = reader.into_decoder().map_err(|e| e.to_string())?;
    let (w, h) = decoder.dimensions();
    let (w, h) = (w as u64, h as u64);
    if let Some(m) = too_many(w, h) {
        return Err(m);
    }
    // The decoder's buffer, the f32 RGB copy, the texels.
    let native = decoder.color_type().bytes_per_pixel() as u64;
    let peak = w * h * (native + 12 + 12);
    budget.reserve(peak, "decoding it")?;
    let dynamic = image::DynamicImage::from_decoder(decoder).map_err(|e| {
        budget.release(peak);
        e.to_string()
    })?;
    let linear = matches!(
        dynamic,
        image::DynamicImage::ImageRgb32F(_) | image::DynamicImage::ImageRgba32F(_)
    );
    let rgb = dynamic.to_rgb32f();
    let decode = |v: f32| if linear { v } else { encoding.decode(v) };
    let image = Image {
        width: rgb.width() as usize,
        height: rgb.height() as usize,
        texels: rgb
            .pixels()
            .map(|p| Vec3::new(decode(p[0]), decode(p[1]), decode(p[2])))
            .collect(),
    };
    budget.release(peak - w * h * 12);
    Ok(image)
}

/// Decodes a PFM image (`PF` colour or `Pf` grey; width height; scale, negative for
/// little-endian, whose magnitude multiplies the values as in pbrt-v4; rows of f32 from the
/// bottom up) into rows from the top down.
pub fn read_pfm(bytes: &[u8]) -> Result<Image, String> {
    // The header is three whitespace-separated lines: magic, "width height", scale.
    let mut fields = Vec::new();
    let mut pos = 0;
    while fields.len() < 4 {
        while pos < bytes.len() && bytes[pos].is_ascii_whitespace() {
            pos += 1;
        }
        let start = pos;
        while pos < bytes.len() && !bytes[pos].is_ascii_whitespace() {
            pos += 1;
        }
        if start == pos {
            return Err("truncated PFM header".to_string());
        }
        fields.push(String::from_utf8_lossy(&bytes[start..pos]).into_owned());
    }
    let pixels = &bytes[(pos + 1).min(bytes.len())..];
    let channels = match fields[0].as_str() {
        "PF" => 3,
        "Pf" => 1,
        other => return Err(format!("not a PFM file (magic \"{other}\")")),
    };
    let dim = |s: &str| s.parse::<usize>().ok().filter(|&v| v > 0);
    let (Some(w), Some(h)) = (dim(&fields[1]), dim(&fields[2])) else {
        return Err(format!("bad PFM size \"{} {}\"", fields[1], fields[2]));
    };
    let scale: f32 = fields[3]
        .parse()
        .map_err(|_| format!("bad PFM scale \"{}\"", fields[3]))?;
    let want = w.checked_mul(h).and_then(|n| n.checked_mul(4 * channels));
    if want != Some(pixels.len()) {
        return Err(format!(
            "PFM of {w}x{h}x{channels} needs {} bytes of pixels, the file has {}",
            w.saturating_mul(h).saturating_mul(4 * channels),
            pixels.len()
        ));
    }
    // pbrt-v4 multiplies the values by |scale| when it is not 1.
    let factor = if scale.is_finite() && scale != 0.0 {
        scale.abs()
    } else {
        1.0
    };
    let value = |b: &[u8]| {
        let b = [b[0], b[1], b[2], b[3]];
        factor
            * if scale < 0.0 {
                f32::from_le_bytes(b)
            } else {
                f32::from_be_bytes(b)
            }
    };
    let texels = (0..h)
        .rev()
        .flat_map(|row| (0..w).map(move |x| (row * w + x) * channels * 4))
        .map(|at| {
            let c = |i: usize| value(&pixels[at + 4 * i..]);
            match channels {
                3 => Vec3::new(c(0), c(1), c(2)),
                _ => Vec3::splat(c(0)),
            }
        })
        .collect();
    Ok(Image {
        width: w,
        height: h,
        texels,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pfm_rows_run_bottom_up_in_either_byte_order() {
        // 1x2 colour image: bottom row (1, 2, 3), top row (4, 5, 6).
        let values = [1.0f32, 2.0, 3.0, 4.0, 5.0, 6.0];
        let mut le = b"PF\n1 2\n-1.0\n".to_vec();
        le.extend(values.iter().flat_map(|v| v.to_le_bytes()));
        let mut be = b"PF\n1 2\n1.0\n".to_vec();
        be.extend(values.iter().flat_map(|v| v.to_be_bytes()));
        for bytes in [le, be] {
            let im = read_pfm(&bytes).unwrap();
            assert_eq!((im.width, im.height), (1, 2));
            assert_eq!(
                im.texels,
                vec![Vec3::new(4.0, 5.0, 6.0), Vec3::new(1.0, 2.0, 3.0)]
            );
        }
        let mut scaled = b"PF\n1 1\n-2.5\n".to_vec();
        scaled.extend([1.0f32, 2.0, 4.0].iter().flat_map(|v| v.to_le_bytes()));
        assert_eq!(
            read_pfm(&scaled).unwrap().texels,
            vec![Vec3::new(2.5, 5.0, 10.0)]
        );
        let mut grey = b"Pf 2 1 -1\n".to_vec();
        grey.extend([0.5f32, 0.25].iter().flat_map(|v| v.to_le_bytes()));
        assert_eq!(
            read_pfm(&grey).unwrap().texels,
            vec![Vec3::splat(0.5), Vec3::splat(0.25)]
        );
        assert!(read_pfm(b"PF\n100000 100000\n-1\n\0\0")
            .unwrap_err()
            .contains("needs"));
        assert!(read_pfm(b"P6\n1 1\n255\n...")
            .unwrap_err()
            .contains("magic"));
        assert!(read_pfm(b"PF\n1").unwrap_err().contains("truncated"));
    }
}
