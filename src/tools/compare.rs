//! `photon compare IMAGE REFERENCE`: error metrics of a render against a reference (relMSE,
//! RMSE, MAE, max, PSNR and the perceptual LDR-FLIP), and a false-colour relative-error PNG
//! with a legend (a colour bar with log-scale ticks from 1e-4 to 10).
//!
//! Both images may be EXR, PNG (8 or 16 bits, decoded from sRGB to linear) or PFM (linear):
//! the reader is chosen by extension, else by the file's first bytes
//! ([`crate::imageio::read_linear`]).
use super::output::{Outputs, Writer};
use super::ToolError;
use crate::imageio::metrics::{self, FlipOptions, MaskOptions, Metrics};
use crate::imageio::png::{encode_srgb8, write_png_rgb8};
use crate::imageio::{read_linear, RgbImage, Tonemap};
use crate::limits::MAX_EXPOSURE;
use std::path::{Path, PathBuf};

/// Options of `photon compare`.
#[derive(clap::Args, Clone, Debug)]
pub struct CompareOptions {
    /// The image to judge (EXR, PNG or PFM).
    pub image: PathBuf,
    /// The reference (EXR, PNG or PFM). Non-finite reference pixels are masked and counted.
    pub reference: PathBuf,
    /// Box-filter the larger image down to the smaller one's size (integer factors only).
    #[arg(long)]
    pub downsample: bool,
    /// Also leave out pixels next to reference pixels brighter than this (visible emitters).
    #[arg(long)]
    pub mask_above: Option<f32>,
    /// Write a false-colour relative-error image (log scale 1e-4 .. 1, legend below it);
    /// planned before the images are read and written as `render`'s outputs are (a FIFO or
    /// device is written into, never replaced).
    #[arg(long)]
    pub error_png: Option<PathBuf>,
    /// LDR-FLIP sees both images after this exposure in stops (nv-flip has no HDR-FLIP).
    #[arg(long, default_value_t = 0.0, allow_negative_numbers = true, value_parser = super::float_in(-MAX_EXPOSURE, MAX_EXPOSURE, false))]
    pub flip_exposure: f32,
    /// LDR-FLIP sees both images through this tone curve (`clamp`: the PNG preview's clip).
    #[arg(long, value_enum, default_value_t = Tonemap::Clamp)]
    pub flip_tonemap: Tonemap,
    /// Print the metrics as JSON instead of text.
    #[arg(long)]
    pub json: bool,
    /// Exit with code 1 when the overall relMSE exceeds this.
    #[arg(long)]
    pub max_relmse: Option<f64>,
}

/// Runs the comparison; `Ok(false)` when `--max-relmse` is exceeded.
pub fn run(opts: &CompareOptions) -> Result<bool, ToolError> {
    let error_png = match &opts.error_png {
        Some(p) => Some(Outputs::plan_files(&[("--error-png", p)]).map_err(ToolError)?),
        None => None,
    };
    let image = read_linear(&opts.image, None)?;
    let reference = read_linear(&opts.reference, None)?;
    let (image, reference) = if opts.downsample {
        metrics::match_sizes(image, reference).map_err(ToolError)?
    } else {
        (image, reference)
    };
    let mask = MaskOptions {
        mask_above: opts.mask_above,
    };
    let flip_opts = FlipOptions {
        exposure: opts.flip_exposure,
        tonemap: opts.flip_tonemap,
    };
    let (m, flip) = measure(&image, &reference, mask, flip_opts).map_err(ToolError)?;
    if let Some(out) = &error_png {
        let errors = metrics::error_image(&image, &reference, mask);
        let (w, h, bytes) = with_legend(&errors)?;
        let writer: Writer = Box::new(move |tmp: &Path| {
            write_png_rgb8(tmp, w, h, &bytes).map_err(|e| super::output::kind_only(&e))
        });
        out.commit(vec![writer])?;
    }
    if opts.json {
        say!("{}", to_json(&m, flip, flip_opts));
    } else {
        say!("{} | {}", summary(&m), flip_summary(flip, flip_opts));
    }
    Ok(opts.max_relmse.is_none_or(|t| m.overall.relmse <= t))
}

/// The metrics of `image` against `reference` ([`metrics::compare`]) and their mean LDR-FLIP
/// ([`metrics::flip`]): what `photon compare` reports (and the Python module's `compare`).
pub fn measure(
    image: &RgbImage,
    reference: &RgbImage,
    mask: MaskOptions,
    flip: FlipOptions,
) -> Result<(Metrics, f64), String> {
    let m = metrics::compare(image, reference, mask)?;
    Ok((m, metrics::flip(image, reference, flip)?))
}

/// The FLIP part of the text output: the mean and how both images were shown to it.
pub fn flip_summary(flip: f64, opts: FlipOptions) -> String {
    format!(
        "LDR-FLIP {flip:.6} (both images tone-mapped alike: exposure {} stops, {}, sRGB 8-bit)",
        opts.exposure,
        opts.tonemap.name()
    )
}

/// The `"flip"` object of the JSON output.
fn flip_json(flip: f64, opts: FlipOptions) -> serde_json::Value {
    serde_json::json!({
        "mean": flip,
        "kind": "LDR-FLIP",
        "exposure": opts.exposure,
        "tonemap": opts.tonemap.name(),
        "pixels_per_degree": nv_flip::DEFAULT_PIXELS_PER_DEGREE,
    })
}

/// Width of the error PNG's legend at least (a narrower image is padded on the right).
pub const LEGEND_WIDTH: usize = 360;
/// Height of the legend strip below the error image.
pub const LEGEND_HEIGHT: usize = 60;
/// The legend's colour bar: left and right margins, top and bottom rows in the strip.
pub const BAR_MARGIN: usize = 20;
pub const BAR_TOP: usize = 20;
pub const BAR_BOTTOM: usize = 36;
/// The bar runs over `log10 e` from -4 to 1 ([`metrics::error_colour`]'s whole range).
const DECADES: (i32, i32) = (-4, 1);

/// The column of the bar (in the legend of an image `width` wide) where `log10 e` is `d`.
pub fn bar_column(width: usize, d: f64) -> usize {
    let (lo, hi) = DECADES;
    // A whole number of columns per decade: each tick falls on its decade's exact colour.
    let decades = (hi - lo) as usize;
    let per_decade = ((width - 2 * BAR_MARGIN - 1) / decades) as f64;
    BAR_MARGIN + ((d - lo as f64) * per_decade).round() as usize
}

/// The 8-bit sRGB pixels of the error image `errors` with the legend below it: a white strip,
/// a title, the colour bar from 1e-4 to 10 with a tick and a label at each decade. Returns the
/// width, the height and the RGB bytes.
pub fn with_legend(errors: &RgbImage) -> Result<(usize, usize, Vec<u8>), ToolError> {
    let w = errors.width.max(LEGEND_WIDTH);
    let h = errors.height + LEGEND_HEIGHT;
    let mut bytes = vec![255u8; w * h * 3];
    let rgb8 = |c: [f32; 3]| c.map(|v| encode_srgb8(v, 1.0));
    for (y, row) in errors.pixels.chunks(errors.width.max(1)).enumerate() {
        for (x, p) in row.iter().enumerate() {
            bytes[(y * w + x) * 3..][..3].copy_from_slice(&rgb8(*p));
        }
    }
    let top = errors.height;
    let (lo, hi) = DECADES;
    let (x0, x1) = (bar_column(w, lo as f64), bar_column(w, hi as f64));
    let mut put =
        |x: usize, y: usize, c: [u8; 3]| bytes[((top + y) * w + x) * 3..][..3].copy_from_slice(&c);
    for x in x0..=x1 {
        let d = lo as f64 + (x - x0) as f64 * (hi - lo) as f64 / (x1 - x0) as f64;
        let c = rgb8(metrics::error_colour(10f64.powf(d)));
        for y in BAR_TOP..BAR_BOTTOM {
            put(x, y, c);
        }
    }
    for d in lo..=hi {
        for y in BAR_BOTTOM..BAR_BOTTOM + 4 {
            put(bar_column(w, d as f64), y, [0, 0, 0]);
        }
    }
    draw_legend_text(&mut bytes, w, h, top).map_err(|e| {
        ToolError(format!(
            "--error-png: drawing the legend's text failed: {e}"
        ))
    })?;
    Ok((w, h, bytes))
}

/// The legend's title and tick labels, drawn with plotters (its `ttf` fonts) into `bytes`.
fn draw_legend_text(bytes: &mut [u8], w: usize, h: usize, top: usize) -> Result<(), String> {
    use plotters::prelude::*;
    use plotters::style::text_anchor::{HPos, Pos, VPos};
    let err = |e: &dyn std::fmt::Display| e.to_string();
    let root = BitMapBackend::with_buffer(bytes, (w as u32, h as u32)).into_drawing_area();
    let style = ("sans-serif", 12).into_font().color(&BLACK);
    let title = "relMSE per pixel (log scale; grey: masked)";
    root.draw(&Text::new(
        title,
        (BAR_MARGIN as i32, top as i32 + 4),
        style.clone(),
    ))
    .map_err(|e| err(&e))?;
    let centred = style.pos(Pos::new(HPos::Center, VPos::Top));
    let (lo, hi) = DECADES;
    for d in lo..=hi {
        let label = match d {
            -4 => "1e-4".to_string(),
            -3 => "1e-3".to_string(),
            _ => format!("{}", 10f64.powi(d)),
        };
        let at = (
            bar_column(w, d as f64) as i32,
            (top + BAR_BOTTOM + 5) as i32,
        );
        root.draw(&Text::new(label, at, centred.clone()))
            .map_err(|e| err(&e))?;
    }
    root.present().map_err(|e| err(&e))
}

/// One line: the overall metrics and what was masked.
pub fn summary(m: &Metrics) -> String {
    let o = &m.overall;
    format!(
        "relMSE {:.6} RMSE {:.6} MAE {:.6} max {:.4} PSNR {:.2} dB | relMSE R/G/B {:.6}/{:.6}/{:.6} | {} px, masked: {} non-finite ref, {} near emitters; {} non-finite in image",
        o.relmse,
        o.rmse,
        o.mae,
        o.max_abs,
        o.psnr,
        m.channels[0].relmse,
        m.channels[1].relmse,
        m.channels[2].relmse,
        m.pixels,
        m.masked_nonfinite,
        m.masked_emitter,
        m.image_nonfinite
    )
}

fn channel_json(c: &metrics::ChannelError) -> serde_json::Value {
    serde_json::json!({
        "relmse": c.relmse,
        "rmse": c.rmse,
        "mae": c.mae,
        "max_abs": c.max_abs,
        "psnr": c.psnr,
    })
}

/// The metrics and the FLIP mean `flip` (seen through `opts`) as one line of JSON (non-finite
/// numbers, such as an infinite PSNR, as `null`): `photon compare --json`.
pub fn to_json(m: &Metrics, flip: f64, opts: FlipOptions) -> String {
    serde_json::json!({
        "overall": channel_json(&m.overall),
        "r": channel_json(&m.channels[0]),
        "g": channel_json(&m.channels[1]),
        "b": channel_json(&m.channels[2]),
        "pixels": m.pixels,
        "masked_nonfinite": m.masked_nonfinite,
        "masked_emitter": m.masked_emitter,
        "image_nonfinite": m.image_nonfinite,
        "flip": flip_json(flip, opts),
    })
    .to_string()
}
