//! Image I/O: linear float images in memory, OpenEXR through OpenEXRCore ([`exr`]), 8-bit sRGB
//! PNG through the `image` crate ([`png`]) after a tone curve ([`tonemap`]), the decoding of
//! texture and environment-map files into linear texels and PFM reading and writing
//! ([`decode`]), error metrics against a reference ([`metrics`]) and the Open Image Denoise
//! denoiser ([`denoise`], feature `denoise`).
//!
//! Every writer goes through [`write_atomically`]: the image is written to a temporary file in
//! the destination's directory and renamed over the destination only once it is complete, so a
//! failed write never leaves a half-written image over a good one.
//!
//! ```no_run
//! use photon::imageio::{read_exr, write_exr, write_png, ExrPixel, RgbImage};
//! use std::path::Path;
//! let mut img = RgbImage::new(64, 32);
//! img.set(3, 4, [1.0, 0.5, 0.25]);
//! let albedo = RgbImage::new(64, 32);
//! write_exr(Path::new("out.exr"), &img, &[("albedo", &albedo)], ExrPixel::Half)?;
//! write_png(Path::new("out.png"), &img, 0.0)?;
//! let back = read_exr(Path::new("out.exr"))?;
//! # Ok::<(), photon::imageio::ImageError>(())
//! ```
pub mod decode;
pub mod denoise;
pub mod exr;
pub mod metrics;
pub mod png;
pub mod tonemap;

pub use decode::{read_linear, write_pfm};
pub use exr::{
    read_exr, read_exr_attributes, read_exr_channel, read_exr_channel_list, read_exr_layer,
    read_exr_named, read_exr_size, read_exr_uint_layer, write_exr, write_exr_channels,
    write_exr_with, ExrAttr, ExrChannel, ExrCompression, ExrExtra, ExrLayout, ExrPixel, ExrSamples,
    ExrStored,
};
pub use png::{write_png, write_png_tonemapped};
pub use tonemap::Tonemap;

use std::fmt;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};

/// A linear RGB float image, row-major from the top-left pixel.
#[derive(Clone, Debug, PartialEq)]
pub struct RgbImage {
    pub width: usize,
    pub height: usize,
    pub pixels: Vec<[f32; 3]>,
}

impl RgbImage {
    pub fn new(width: usize, height: usize) -> Self {
        RgbImage {
            width,
            height,
            pixels: vec![[0.0; 3]; width * height],
        }
    }

    /// True when `pixels` holds exactly `width * height` entries (the fields are public, so a
    /// caller can break this; readers and writers check it).
    pub fn is_consistent(&self) -> bool {
        self.width.checked_mul(self.height) == Some(self.pixels.len())
    }

    /// The pixel at column `x`, row `y` (row 0 at the top), or `None` outside the image.
    pub fn get(&self, x: usize, y: usize) -> Option<[f32; 3]> {
        self.index(x, y).and_then(|i| self.pixels.get(i).copied())
    }

    /// Sets the pixel at column `x`, row `y` to `rgb`. Returns false (and changes nothing) when
    /// `(x, y)` is outside the image.
    pub fn set(&mut self, x: usize, y: usize, rgb: [f32; 3]) -> bool {
        match self.index(x, y).and_then(|i| self.pixels.get_mut(i)) {
            Some(p) => {
                *p = rgb;
                true
            }
            None => false,
        }
    }

    /// Number of pixels with at least one NaN or infinite channel.
    pub fn count_nonfinite(&self) -> usize {
        self.pixels
            .iter()
            .filter(|p| p.iter().any(|c| !c.is_finite()))
            .count()
    }

    /// Box-filters the image down by an integer `factor`: each output pixel is the mean of a
    /// `factor` x `factor` block (accumulated in f64). `None` unless `factor` is at least 1 and
    /// divides both the width and the height (and the image is consistent).
    pub fn downsample_box(&self, factor: usize) -> Option<RgbImage> {
        if factor == 0
            || !self.width.is_multiple_of(factor)
            || !self.height.is_multiple_of(factor)
            || !self.is_consistent()
        {
            return None;
        }
        let (w, h) = (self.width / factor, self.height / factor);
        let norm = 1.0 / (factor * factor) as f64;
        let mut out = RgbImage::new(w, h);
        for (i, px) in out.pixels.iter_mut().enumerate() {
            let (ox, oy) = (i % w, i / w);
            let mut sum = [0.0f64; 3];
            for y in oy * factor..(oy + 1) * factor {
                let row = &self.pixels[y * self.width + ox * factor..][..factor];
                for p in row {
                    for c in 0..3 {
                        sum[c] += f64::from(p[c]);
                    }
                }
            }
            *px = sum.map(|s| (s * norm) as f32);
        }
        Some(out)
    }

    fn index(&self, x: usize, y: usize) -> Option<usize> {
        (x < self.width && y < self.height).then(|| y * self.width + x)
    }
}

/// What went wrong in an image read or write.
#[derive(Debug)]
pub enum ImageErrorKind {
    /// A file-system operation failed (create, rename, remove...).
    Io(std::io::Error),
    /// OpenEXRCore returned an error: the failing call, the code's name and the library's message.
    Exr {
        call: &'static str,
        code: String,
        message: String,
    },
    /// The `image` crate failed to encode or write.
    Png(String),
    /// The input is not something this module handles (bad sizes, missing channels, ...).
    Invalid(String),
}

/// An image I/O error; its `Display` is one line naming the file.
#[derive(Debug)]
pub struct ImageError {
    /// The file being read or written (the final destination, not the temporary file).
    pub path: PathBuf,
    pub kind: ImageErrorKind,
}

impl ImageError {
    /// An [`ImageErrorKind::Invalid`] error about `path`.
    pub fn invalid(path: &Path, what: impl Into<String>) -> Self {
        ImageError {
            path: path.to_path_buf(),
            kind: ImageErrorKind::Invalid(what.into()),
        }
    }

    /// An [`ImageErrorKind::Io`] error about `path`.
    pub fn io(path: &Path, err: std::io::Error) -> Self {
        ImageError {
            path: path.to_path_buf(),
            kind: ImageErrorKind::Io(err),
        }
    }
}

impl fmt::Display for ImageError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let p = self.path.display();
        match &self.kind {
            ImageErrorKind::Io(e) => write!(f, "{p}: {e}"),
            ImageErrorKind::Exr {
                call,
                code,
                message,
            } => write!(f, "{p}: OpenEXR {call} failed: {code}: {message}"),
            ImageErrorKind::Png(m) => write!(f, "{p}: PNG: {m}"),
            ImageErrorKind::Invalid(m) => write!(f, "{p}: {m}"),
        }
    }
}

impl std::error::Error for ImageError {
    fn source(&self) -> Option<&(dyn std::error::Error + 'static)> {
        match &self.kind {
            ImageErrorKind::Io(e) => Some(e),
            _ => None,
        }
    }
}

/// Writes `path` atomically: `write(tmp)` must create and fill the temporary file `tmp` (in the
/// same directory as `path`, same extension, hidden name); on success `tmp` is renamed over
/// `path`, on failure `tmp` is removed and `path` is left as it was.
///
/// Errors returned by `write` should name `path` (the destination), not `tmp`.
pub fn write_atomically<F>(path: &Path, write: F) -> Result<(), ImageError>
where
    F: FnOnce(&Path) -> Result<(), ImageError>,
{
    let tmp = temp_path_for(path)?;
    let result =
        write(&tmp).and_then(|()| std::fs::rename(&tmp, path).map_err(|e| ImageError::io(path, e)));
    if result.is_err() {
        // The file may not exist (the writer failed before creating it): nothing to report.
        let _ = std::fs::remove_file(&tmp);
    }
    result
}

/// A fresh temporary name next to `path`: `.<name>.<pid>-<n>.tmp.<ext>`.
fn temp_path_for(path: &Path) -> Result<PathBuf, ImageError> {
    static COUNTER: AtomicU64 = AtomicU64::new(0);
    let name = path
        .file_name()
        .ok_or_else(|| ImageError::invalid(path, "output path has no file name"))?;
    let n = COUNTER.fetch_add(1, Ordering::Relaxed);
    let mut tmp_name = format!(".{}.{}-{n}.tmp", name.to_string_lossy(), std::process::id());
    if let Some(ext) = path.extension() {
        tmp_name.push('.');
        tmp_name.push_str(&ext.to_string_lossy());
    }
    Ok(path.with_file_name(tmp_name))
}
