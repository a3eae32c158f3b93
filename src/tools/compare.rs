//! `photon compare IMAGE.exr REFERENCE.exr`: error metrics of a render against a reference.
use super::output::{Outputs, Writer};
use super::ToolError;
use crate::imageio::metrics::{self, MaskOptions, Metrics};
use crate::imageio::{read_exr, write_png};
use std::path::{Path, PathBuf};

/// Options of `photon compare`.
#[derive(clap::Args, Clone, Debug)]
pub struct CompareOptions {
    /// The image to judge (EXR).
    pub image: PathBuf,
    /// The reference (EXR). Non-finite reference pixels are masked and counted.
    pub reference: PathBuf,
    /// Box-filter the larger image down to the smaller one's size (integer factors only).
    #[arg(long)]
    pub downsample: bool,
    /// Also leave out pixels next to reference pixels brighter than this (visible emitters).
    #[arg(long)]
    pub mask_above: Option<f32>,
    /// Write a false-colour relative-error image (log scale 1e-4 .. 1); planned before the
    /// images are read and written as `render`'s outputs are (a FIFO or device is written
    /// into, never replaced).
    #[arg(long)]
    pub error_png: Option<PathBuf>,
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
    let image = read_exr(&opts.image)?;
    let reference = read_exr(&opts.reference)?;
    let (image, reference) = if opts.downsample {
        metrics::match_sizes(image, reference).map_err(ToolError)?
    } else {
        (image, reference)
    };
    let mask = MaskOptions {
        mask_above: opts.mask_above,
    };
    let m = metrics::compare(&image, &reference, mask).map_err(ToolError)?;
    if let Some(out) = &error_png {
        let errors = metrics::error_image(&image, &reference, mask);
        let writer: Writer = Box::new(|tmp: &Path| {
            write_png(tmp, &errors, 0.0).map_err(|e| super::output::kind_only(&e))
        });
        out.commit(vec![writer])?;
    }
    if opts.json {
        say!("{}", to_json(&m));
    } else {
        say!("{}", summary(&m));
    }
    Ok(opts.max_relmse.is_none_or(|t| m.overall.relmse <= t))
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

/// The metrics as one line of JSON (non-finite numbers, such as an infinite PSNR, as `null`).
pub fn to_json(m: &Metrics) -> String {
    serde_json::json!({
        "overall": channel_json(&m.overall),
        "r": channel_json(&m.channels[0]),
        "g": channel_json(&m.channels[1]),
        "b": channel_json(&m.channels[2]),
        "pixels": m.pixels,
        "masked_nonfinite": m.masked_nonfinite,
        "masked_emitter": m.masked_emitter,
        "image_nonfinite": m.image_nonfinite,
    })
    .to_string()
}
