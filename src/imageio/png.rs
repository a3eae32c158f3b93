//! 8-bit sRGB PNG output through the `image` crate, for previews of linear renders.
//!
//! Each linear value is scaled by `2^exposure_stops`, clamped to [0, 1] (NaN becomes 0),
//! encoded with the exact piecewise sRGB OETF and rounded to 8 bits; [`write_png_tonemapped`]
//! applies one of [`super::tonemap`]'s curves instead of the clip.
use super::tonemap::Tonemap;
use super::{write_atomically, ImageError, ImageErrorKind, RgbImage};
use std::path::Path;

/// The sRGB OETF (IEC 61966-2-1) of a linear value in [0, 1]: `12.92 v` up to 0.0031308,
/// `1.055 v^(1/2.4) - 0.055` above.
pub fn srgb_oetf(v: f32) -> f32 {
    if v <= 0.003_130_8 {
        12.92 * v
    } else {
        1.055 * v.powf(1.0 / 2.4) - 0.055
    }
}

/// One linear sample to an 8-bit sRGB code value, after multiplying by `scale`.
pub fn encode_srgb8(v: f32, scale: f32) -> u8 {
    let x = v * scale;
    // NaN fails `x > 0` and becomes 0 (`clamp` would keep it).
    let x = if x > 0.0 { x.min(1.0) } else { 0.0 };
    (srgb_oetf(x) * 255.0).round() as u8
}

/// Writes `rgb` to `path` as an 8-bit sRGB PNG after scaling by `2^exposure_stops`.
///
/// Written to a temporary file next to `path` and renamed over it only on success.
/// Errors: inconsistent image size, sizes beyond `u32`, encoder or file-system failures.
pub fn write_png(path: &Path, rgb: &RgbImage, exposure_stops: f32) -> Result<(), ImageError> {
    write_png_tonemapped(path, rgb, exposure_stops, Tonemap::Clamp)
}

/// [`write_png`] with the tone curve `tonemap` ([`super::tonemap`]) after the exposure
/// (`Tonemap::Clamp` is `write_png`).
pub fn write_png_tonemapped(
    path: &Path,
    rgb: &RgbImage,
    exposure_stops: f32,
    tonemap: Tonemap,
) -> Result<(), ImageError> {
    if !rgb.is_consistent() {
        return Err(ImageError::invalid(
            path,
            format!(
                "cannot write a {}x{} image holding {} pixels",
                rgb.width,
                rgb.height,
                rgb.pixels.len()
            ),
        ));
    }
    let bytes = super::tonemap::to_srgb8(&rgb.pixels, exposure_stops, tonemap);
    write_png_rgb8(path, rgb.width, rgb.height, &bytes)
}

/// Writes tightly packed 8-bit RGB `bytes` (`width * height * 3`, rows from the top) to `path`
/// as a PNG, atomically ([`write_atomically`]).
pub fn write_png_rgb8(
    path: &Path,
    width: usize,
    height: usize,
    bytes: &[u8],
) -> Result<(), ImageError> {
    let size = (u32::try_from(width), u32::try_from(height));
    let (Ok(w), Ok(h)) = size else {
        return Err(ImageError::invalid(path, "image too large for PNG"));
    };
    if w == 0
        || h == 0
        || width.checked_mul(height).and_then(|n| n.checked_mul(3)) != Some(bytes.len())
    {
        return Err(ImageError::invalid(
            path,
            format!(
                "cannot write a {width}x{height} image from {} bytes",
                bytes.len()
            ),
        ));
    }
    write_atomically(path, |tmp| {
        image::save_buffer_with_format(
            tmp,
            bytes,
            w,
            h,
            image::ExtendedColorType::Rgb8,
            image::ImageFormat::Png,
        )
        .map_err(|e| ImageError {
            path: path.to_path_buf(),
            kind: ImageErrorKind::Png(e.to_string()),
        })
    })
}
