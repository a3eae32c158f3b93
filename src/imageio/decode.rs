//! Decoding image files into linear RGB texels for textures and environment maps: OpenEXR
//! through [`super::exr`], PFM here, PNG, TGA, JPEG, TIFF... through the `image` crate. Every
//! size a header declares is checked against [`crate::limits::MAX_IMAGE_PIXELS`] and the
//! decode's peak reserved in the loader's [`LoadBudget`] before anything is decoded.
//!
//! The format is chosen by the file's extension (`.exr`, `.pfm`, `.png`), else by its first
//! bytes ([`detect_format`]). [`read_linear`] reads the images the tools take (EXR, PNG as
//! sRGB, PFM) into an [`RgbImage`]; [`write_pfm`] writes a PFM, as pbrt-v4 does.
use super::{write_atomically, ImageError, RgbImage};
use crate::limits::LoadBudget;
use crate::math::Vec3;
use std::path::Path;

/// An image file's format, as [`detect_format`] tells it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum FileFormat {
    Exr,
    Png,
    Pfm,
    /// Anything else (left to the `image` crate, which guesses from the content too).
    Other,
}

impl FileFormat {
    /// The format of a name's extension (`None` for an extension this module does not know).
    pub fn from_extension(path: &Path) -> Option<FileFormat> {
        let ext = path.extension()?.to_string_lossy().to_ascii_lowercase();
        match ext.as_str() {
            "exr" => Some(FileFormat::Exr),
            "png" => Some(FileFormat::Png),
            "pfm" => Some(FileFormat::Pfm),
            _ => None,
        }
    }

    /// The format of a file starting with `head` (its first 4 bytes or fewer): OpenEXR's magic
    /// `76 2f 31 01`, PNG's `89 'P' 'N' 'G'`, PFM's `PF` or `Pf` and a white space.
    pub fn from_magic(head: &[u8]) -> FileFormat {
        match head {
            [0x76, 0x2f, 0x31, 0x01, ..] => FileFormat::Exr,
            [0x89, b'P', b'N', b'G', ..] => FileFormat::Png,
            [b'P', b'F' | b'f', c, ..] if c.is_ascii_whitespace() => FileFormat::Pfm,
            _ => FileFormat::Other,
        }
    }
}

/// The format of `path`: by its extension when that is `.exr`, `.png` or `.pfm` (any case),
/// else by its first bytes ([`FileFormat::from_magic`]; a file that cannot be read is
/// [`FileFormat::Other`], for the decoder to report).
pub fn detect_format(path: &Path) -> FileFormat {
    if let Some(f) = FileFormat::from_extension(path) {
        return f;
    }
    use std::io::Read;
    let mut head = Vec::with_capacity(4);
    match std::fs::File::open(path) {
        Ok(f) => match f.take(4).read_to_end(&mut head) {
            Ok(_) => FileFormat::from_magic(&head),
            Err(_) => FileFormat::Other,
        },
        Err(_) => FileFormat::Other,
    }
}

/// Reads an EXR (its RGB, or the layer `layer`), a PNG (8 or 16 bits, decoded as sRGB) or a
/// PFM (linear) into a linear image; the format by [`detect_format`]. Errors are one line
/// naming the file: any other format, a layer asked of a PNG or PFM, a decoding error.
pub fn read_linear(path: &Path, layer: Option<&str>) -> Result<RgbImage, ImageError> {
    let format = detect_format(path);
    if let (Some(layer), FileFormat::Png | FileFormat::Pfm) = (layer, format) {
        return Err(ImageError::invalid(
            path,
            format!(
                "a {} file has no layers (asked for layer \"{layer}\"; only EXR files have them)",
                if format == FileFormat::Png {
                    "PNG"
                } else {
                    "PFM"
                }
            ),
        ));
    }
    match format {
        FileFormat::Exr => match layer {
            Some(l) => super::read_exr_layer(path, l),
            None => super::read_exr(path),
        },
        FileFormat::Png | FileFormat::Pfm => {
            let budget = LoadBudget::new(crate::limits::default_budget().bytes);
            let srgb = |v: f32| crate::texture::Encoding::Srgb.decode(v);
            let t = read_image(path, &srgb, &budget).map_err(|m| ImageError::invalid(path, m))?;
            Ok(RgbImage {
                width: t.width,
                height: t.height,
                pixels: t.texels.iter().map(Vec3::to_array).collect(),
            })
        }
        FileFormat::Other => Err(ImageError::invalid(
            path,
            "not an EXR, PNG or PFM image (neither by its extension nor by its first bytes)",
        )),
    }
}

/// Decoded linear RGB texels, row 0 at the top.
pub struct Texels {
    pub width: usize,
    pub height: usize,
    pub texels: Vec<Vec3>,
}

impl std::fmt::Debug for Texels {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "Texels {}x{}", self.width, self.height)
    }
}

/// Reads an image file into linear RGB: EXR through [`super::exr`], PFM here, others through
/// the `image` crate; integer images are decoded with `decode_integer` (the texture's encoding), float ones (EXR,
/// PFM, float TIFF...) are taken as linear. The size in the file's header is checked against
/// [`crate::limits::MAX_IMAGE_PIXELS`] and the decode's peak (file or decoder buffer,
/// converted copy, texels) reserved in `budget` before anything is decoded; the texels (12
/// bytes each) stay reserved.
pub fn read_image(
    path: &Path,
    decode_integer: &dyn Fn(f32) -> f32,
    budget: &LoadBudget,
) -> Result<Texels, String> {
    let format = detect_format(path);
    let too_many = |w: u64, h: u64| {
        (w.saturating_mul(h) > crate::limits::MAX_IMAGE_PIXELS).then(|| {
            format!(
                "{w}x{h} pixels is more than the {} an image may have",
                crate::limits::MAX_IMAGE_PIXELS
            )
        })
    };
    if format == FileFormat::Pfm {
        // A colour PFM holds 12 bytes per pixel after a short header: the file, then texels.
        let cap = crate::limits::MAX_IMAGE_PIXELS * 12 + 4096;
        let len = std::fs::metadata(path).map_or(0, |m| m.len().min(cap));
        budget.reserve(2 * len, "decoding it")?;
        let image = crate::limits::read_capped(path, cap)
            .map_err(|e| e.to_string())
            .and_then(|bytes| read_pfm(&bytes));
        // The file's bytes are gone; on an error the texels' share too.
        budget.release(if image.is_ok() { len } else { 2 * len });
        return image;
    }
    if format == FileFormat::Exr {
        let (w, h) = super::read_exr_size(path).map_err(|e| e.to_string())?;
        let (w, h) = (w as u64, h as u64);
        // The decoded image, then the texels copied from it.
        budget.reserve(w * h * 24, "decoding it")?;
        let im = super::read_exr(path).map_err(|e| {
            budget.release(w * h * 24);
            e.to_string()
        })?;
        budget.release(w * h * 12);
        return Ok(Texels {
            width: im.width,
            height: im.height,
            texels: im.pixels.into_iter().map(Vec3::from_array).collect(),
        });
    }
    // The header first: nothing is decoded before the size is checked and reserved.
    let mut reader = image::ImageReader::open(path).map_err(|e| e.to_string())?;
    if FileFormat::from_extension(path).is_none() {
        // No extension the crate knows for sure: let it look at the content.
        reader = reader.with_guessed_format().map_err(|e| e.to_string())?;
    }
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
    let decode = |v: f32| if linear { v } else { decode_integer(v) };
    let image = Texels {
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
pub fn read_pfm(bytes: &[u8]) -> Result<Texels, String> {
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
    Ok(Texels {
        width: w,
        height: h,
        texels,
    })
}

/// A PFM file of `image`: `PF`, the size, scale `-1` (little-endian, values as they are), then
/// the rows of f32 RGB from the bottom up, as [`read_pfm`] reads them back bit for bit.
pub fn encode_pfm(image: &RgbImage) -> Vec<u8> {
    let mut bytes = format!("PF\n{} {}\n-1\n", image.width, image.height).into_bytes();
    bytes.reserve(image.pixels.len() * 12);
    if image.width > 0 {
        for row in image.pixels.chunks(image.width).rev() {
            for p in row {
                for c in p {
                    bytes.extend_from_slice(&c.to_le_bytes());
                }
            }
        }
    }
    bytes
}

/// Writes `image` to `path` as a PFM ([`encode_pfm`]), atomically ([`write_atomically`]).
pub fn write_pfm(path: &Path, image: &RgbImage) -> Result<(), ImageError> {
    if !image.is_consistent() || image.width == 0 || image.height == 0 {
        return Err(ImageError::invalid(
            path,
            format!(
                "cannot write a {}x{} image holding {} pixels",
                image.width,
                image.height,
                image.pixels.len()
            ),
        ));
    }
    let bytes = encode_pfm(image);
    write_atomically(path, |tmp| {
        std::fs::write(tmp, &bytes).map_err(|e| ImageError::io(path, e))
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

    #[test]
    fn pfm_written_reads_back_bit_for_bit() {
        let image = RgbImage {
            width: 3,
            height: 2,
            pixels: (0..6)
                .map(|i| [i as f32 * 0.1, -1.5e-7 * i as f32, 1e30 / (i + 1) as f32])
                .collect(),
        };
        let back = read_pfm(&encode_pfm(&image)).unwrap();
        assert_eq!((back.width, back.height), (3, 2));
        let pixels: Vec<[f32; 3]> = back.texels.iter().map(|t| t.to_array()).collect();
        assert_eq!(pixels, image.pixels);
    }

    #[test]
    fn formats_by_extension_then_by_magic() {
        assert_eq!(
            FileFormat::from_extension(Path::new("a.EXR")),
            Some(FileFormat::Exr)
        );
        assert_eq!(FileFormat::from_extension(Path::new("a.tga")), None);
        assert_eq!(
            FileFormat::from_magic(&[0x76, 0x2f, 0x31, 0x01]),
            FileFormat::Exr
        );
        assert_eq!(FileFormat::from_magic(b"\x89PNG"), FileFormat::Png);
        assert_eq!(FileFormat::from_magic(b"Pf\n1"), FileFormat::Pfm);
        assert_eq!(FileFormat::from_magic(b"PFX"), FileFormat::Other);
        assert_eq!(FileFormat::from_magic(b"P"), FileFormat::Other);
    }
}
