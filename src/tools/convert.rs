//! `photon convert IN -o OUT`: reads an EXR (its RGB or a `--layer`), PNG (decoded from sRGB to
//! linear) or PFM, optionally crops it, and writes it in the format of OUT's extension: `.png`
//! as 8-bit sRGB after an exposure and a tone curve ([`crate::imageio::tonemap`] documents the
//! curves), `.exr` (32-bit float) or `.pfm` linear, untouched by exposure or tone curve. The
//! output is planned before anything is read and replaced only once it is complete
//! ([`super::output`]).
//!
//! ```text
//! photon convert render.exr -o render.png --exposure 1 --tonemap aces
//! photon convert render.exr -o albedo.pfm --layer albedo --crop 0,64,32,96
//! ```
use super::output::{kind_only, Outputs, Writer};
use super::ToolError;
use crate::imageio::decode::{self, FileFormat};
use crate::imageio::{read_linear, write_exr, write_png_tonemapped, ExrPixel, RgbImage, Tonemap};
use crate::limits::MAX_EXPOSURE;
use std::path::{Path, PathBuf};

/// Options of `photon convert`.
#[derive(clap::Args, Clone, Debug)]
pub struct ConvertOptions {
    /// The image to read: EXR, PNG (taken as sRGB) or PFM, by extension, else by content.
    pub input: PathBuf,
    /// The image to write; its extension picks the format: `.png` (8-bit sRGB, tone-mapped),
    /// `.exr` (32-bit float, linear) or `.pfm` (linear).
    #[arg(short = 'o', long = "output")]
    pub output: PathBuf,
    /// Exposure in stops before the tone curve (PNG output only: EXR and PFM stay linear).
    #[arg(long, allow_negative_numbers = true, value_parser = super::float_in(-MAX_EXPOSURE, MAX_EXPOSURE, false))]
    pub exposure: Option<f32>,
    /// Tone curve of PNG output (EXR and PFM stay linear): `clamp` clips at 1 as the render's
    /// preview does (the default), `aces` is Narkowicz's ACES fit, `filmic` Reinhard extended
    /// with white at 4.
    #[arg(long, value_enum)]
    pub tonemap: Option<Tonemap>,
    /// Keep the pixels x0 <= x < x1, y0 <= y < y1 (row 0 at the top).
    #[arg(long, value_parser = parse_crop, value_name = "x0,x1,y0,y1")]
    pub crop: Option<Crop>,
    /// Read the EXR layer NAME (channels NAME.R, NAME.G, NAME.B) instead of the RGB image.
    #[arg(long, value_name = "NAME")]
    pub layer: Option<String>,
}

/// Pixel bounds of `--crop`, half-open: columns `x0..x1`, rows `y0..y1`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Crop {
    pub x0: usize,
    pub x1: usize,
    pub y0: usize,
    pub y1: usize,
}

/// Parses `x0,x1,y0,y1` (non-negative integers, `x0 < x1`, `y0 < y1`).
pub fn parse_crop(s: &str) -> Result<Crop, String> {
    let v: Vec<&str> = s.split(',').map(str::trim).collect();
    if v.len() != 4 {
        return Err(format!("expected x0,x1,y0,y1, got {s:?}"));
    }
    let mut n = [0usize; 4];
    for (slot, text) in n.iter_mut().zip(&v) {
        *slot = text
            .parse()
            .map_err(|_| format!("{text:?} is not a pixel index in {s:?}"))?;
    }
    let [x0, x1, y0, y1] = n;
    if x0 >= x1 || y0 >= y1 {
        return Err(format!(
            "empty crop {s:?}: need x0 < x1 and y0 < y1 (half-open bounds)"
        ));
    }
    Ok(Crop { x0, x1, y0, y1 })
}

/// `image` cut to `crop`, or a one-line error naming `--crop` when it reaches outside.
pub fn crop(image: &RgbImage, c: Crop) -> Result<RgbImage, String> {
    if c.x1 > image.width || c.y1 > image.height {
        return Err(format!(
            "--crop {},{},{},{}: reaches outside the {}x{} image (bounds are half-open: x1 <= {}, y1 <= {})",
            c.x0, c.x1, c.y0, c.y1, image.width, image.height, image.width, image.height
        ));
    }
    let (w, h) = (c.x1 - c.x0, c.y1 - c.y0);
    let mut pixels = Vec::with_capacity(w * h);
    for y in c.y0..c.y1 {
        pixels.extend_from_slice(&image.pixels[y * image.width + c.x0..][..w]);
    }
    Ok(RgbImage {
        width: w,
        height: h,
        pixels,
    })
}

/// Runs the conversion.
pub fn run(opts: &ConvertOptions) -> Result<(), ToolError> {
    let out = &opts.output;
    let format = FileFormat::from_extension(out).ok_or_else(|| {
        ToolError(format!(
            "-o {}: unknown output format: name a .png, .exr or .pfm file",
            out.display()
        ))
    })?;
    if format != FileFormat::Png {
        let kind = if format == FileFormat::Exr {
            "EXR"
        } else {
            "PFM"
        };
        let flag = match (opts.exposure, opts.tonemap) {
            (Some(_), _) => Some("--exposure"),
            (None, Some(_)) => Some("--tonemap"),
            _ => None,
        };
        if let Some(flag) = flag {
            return Err(ToolError(format!(
                "{flag} applies to PNG output only: -o {} is {kind}, which stays linear",
                out.display()
            )));
        }
    }
    let planned = Outputs::plan_files(&[("-o", out.as_path())]).map_err(ToolError)?;
    let image = read_linear(&opts.input, opts.layer.as_deref())?;
    let image = match opts.crop {
        Some(c) => {
            crop(&image, c).map_err(|m| ToolError(format!("{m} ({})", opts.input.display())))?
        }
        None => image,
    };
    let (exposure, tonemap) = (
        opts.exposure.unwrap_or(0.0),
        opts.tonemap.unwrap_or_default(),
    );
    let image = &image;
    let writer: Writer = Box::new(move |tmp: &Path| {
        match format {
            FileFormat::Png => write_png_tonemapped(tmp, image, exposure, tonemap),
            FileFormat::Exr => write_exr(tmp, image, &[], ExrPixel::Float),
            _ => decode::write_pfm(tmp, image),
        }
        .map_err(|e| kind_only(&e))
    });
    planned.commit(vec![writer])?;
    let how = match format {
        FileFormat::Png => format!("8-bit sRGB, exposure {exposure} stops, {}", tonemap.name()),
        FileFormat::Exr => "EXR, 32-bit float, linear".to_string(),
        _ => "PFM, linear".to_string(),
    };
    say!(
        "{}: {}x{} ({how})",
        out.display(),
        image.width,
        image.height
    );
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn crops_are_parsed_and_checked() {
        let c = parse_crop("1, 3,0,2").unwrap();
        assert_eq!((c.x0, c.x1, c.y0, c.y1), (1, 3, 0, 2));
        assert!(parse_crop("1,3,0").unwrap_err().contains("x0,x1,y0,y1"));
        assert!(parse_crop("3,1,0,2").unwrap_err().contains("empty"));
        assert!(parse_crop("1,3,-1,2").unwrap_err().contains("not a pixel"));
        let mut image = RgbImage::new(4, 3);
        for (i, p) in image.pixels.iter_mut().enumerate() {
            *p = [i as f32; 3];
        }
        let cut = crop(&image, c).unwrap();
        assert_eq!((cut.width, cut.height), (2, 2));
        assert_eq!(cut.pixels, vec![[1.0; 3], [2.0; 3], [5.0; 3], [6.0; 3]]);
        let e = crop(&image, parse_crop("0,5,0,1").unwrap()).unwrap_err();
        assert!(
            e.starts_with("--crop 0,5,0,1: reaches outside the 4x3"),
            "{e}"
        );
    }
}
