//! `photon merge PART.exr... -o OUT.exr`: sums partial images (from `photon render --passes`)
//! into the final image. The parts must come from one render (same scene, seed, resolution
//! and settings: the error names the field that differs) and their pass ranges must tile
//! `[0, N)` (the error lists overlaps and missing ranges). The sums are exact, so any split of
//! the passes merges to the same file, bit for bit; the output is itself a partial image of
//! passes `0..N` (it can be merged further or resumed). The outputs are planned before the
//! parts are read and written as `render`'s are (`super::output`: a FIFO or device is written
//! into, never replaced).
use super::output::{Outputs, Writer};
use super::ToolError;
use crate::integrator::passes::{merge, Partial};
use std::path::{Path, PathBuf};

/// Options of `photon merge`.
#[derive(clap::Args, Clone, Debug)]
pub struct MergeOptions {
    /// Partial images written by `photon render --passes A..B`.
    #[arg(required = true)]
    pub parts: Vec<PathBuf>,
    /// The merged EXR.
    #[arg(short, long)]
    pub output: PathBuf,
    /// PNG preview (default: the EXR path with .png).
    #[arg(long)]
    pub png: Option<PathBuf>,
    /// Skip the PNG preview.
    #[arg(long)]
    pub no_png: bool,
    /// PNG exposure in stops.
    #[arg(long, default_value_t = 0.0)]
    pub exposure: f32,
}

pub fn run(opts: &MergeOptions) -> Result<(), ToolError> {
    let png = match opts.no_png {
        true => None,
        false => (opts.png.clone()).or_else(|| super::output::default_png(&opts.output)),
    };
    let outputs = Outputs::plan(&opts.output, png.as_deref()).map_err(ToolError)?;
    let parts = opts
        .parts
        .iter()
        .map(|p| Ok((p.clone(), Partial::read(p).map_err(ToolError)?)))
        .collect::<Result<Vec<_>, ToolError>>()?;
    let merged = merge(&parts).map_err(ToolError)?;
    let mean = merged.mean().0;
    let mut writers: Vec<Writer> = vec![Box::new(|tmp: &Path| {
        merged.write(tmp).map_err(|e| super::output::kind_only(&e))
    })];
    if png.is_some() {
        writers.push(Box::new(|tmp: &Path| {
            crate::imageio::write_png(tmp, &mean, opts.exposure)
                .map_err(|e| super::output::kind_only(&e))
        }));
    }
    outputs.commit(writers)?;
    say!(
        "merged {} parts: passes {}..{} -> {}",
        parts.len(),
        merged.passes.start,
        merged.passes.end,
        opts.output.display()
    );
    if let Some(png) = &png {
        say!("wrote {}", png.display());
    }
    Ok(())
}
