//! `photon render` in passes (`--progressive`, `--passes A..B`, `--checkpoint`, `--resume`):
//! renders a range of independent passes (see `integrator::passes`) and writes the partial
//! image (exact per-pixel sums plus the mean so far), checkpointing as it goes and on
//! SIGINT/SIGTERM, so that nothing rendered is lost and `photon merge` can sum the parts.
use super::render::RenderOptions;
use super::ToolError;
use crate::accel::Accel;
use crate::integrator::passes::{progress_note, render_passes, Partial, PartialHeader};
use crate::integrator::{RenderOutput, RenderSettings};
use crate::scene::Scene;
use std::path::Path;
use std::time::Instant;

/// The backend as recorded in partial images (parts from different backends differ at noise
/// level, so they are not merged).
fn backend_name(opts: &RenderOptions) -> String {
    format!(
        "{}{}",
        opts.backend,
        if opts.robust { " robust" } else { "" }
    )
}

/// Checks that `resumed` is a part of the render `header` describes; names the field.
pub fn check_same_render(
    file: &Path,
    resumed: &PartialHeader,
    header: &PartialHeader,
) -> Result<(), ToolError> {
    let field = if resumed.scene != header.scene {
        "scene"
    } else if resumed.seed != header.seed {
        "seed"
    } else if (resumed.width, resumed.height) != (header.width, header.height) {
        "resolution"
    } else if resumed.settings != header.settings {
        "settings"
    } else {
        return Ok(());
    };
    Err(ToolError(format!(
        "{}: cannot resume: it is a render with another {field} (file: {}; now: {})",
        file.display(),
        describe_field(resumed, field),
        describe_field(header, field)
    )))
}

fn describe_field(h: &PartialHeader, field: &str) -> String {
    match field {
        "scene" => h.scene.clone(),
        "seed" => h.seed.to_string(),
        "resolution" => format!("{}x{}", h.width, h.height),
        _ => h.settings.clone(),
    }
}

/// Renders in passes and writes the partial image to `exr` (and the mean to `png`).
pub fn run(
    opts: &RenderOptions,
    scene: &Scene,
    accel: &Accel,
    settings: &RenderSettings,
    pool: &rayon::ThreadPool,
    exr: &Path,
    png: Option<&Path>,
) -> Result<(), ToolError> {
    crate::interrupt::install();
    let po = &opts.passes;
    let kind = opts.integrator;
    let header = PartialHeader::new(scene, settings, kind, &backend_name(opts));
    let start_pass = po.passes.as_ref().map_or(0, |r| r.start);
    let mut acc = match &po.resume {
        Some(file) => {
            let p = Partial::read(file).map_err(ToolError)?;
            check_same_render(file, &p.header, &header)?;
            if p.passes.start != start_pass {
                return Err(ToolError(format!(
                    "{}: holds passes {}..{}, which do not start at pass {start_pass}",
                    file.display(),
                    p.passes.start,
                    p.passes.end
                )));
            }
            println!(
                "resuming {}: passes {}..{} done",
                file.display(),
                p.passes.start,
                p.passes.end
            );
            p
        }
        None => Partial::new(header, start_pass),
    };
    // Where to stop: the range's end, else the file's samples per pixel in passes, else
    // (with --time) when the budget is spent.
    let pass_spp = settings.pass_spp.max(1);
    let end = match (&po.passes, opts.time) {
        (Some(r), _) => r.end,
        (None, Some(_)) => u64::MAX,
        (None, None) => start_pass + settings.spp.div_ceil(pass_spp).max(1) as u64,
    };
    println!(
        "passes: {}..{} of {} spp each, {} photon maps{}",
        acc.passes.end,
        if end == u64::MAX {
            "(until the time budget)".to_string()
        } else {
            end.to_string()
        },
        pass_spp,
        if settings.photon.progressive {
            "fresh progressive"
        } else {
            "Jensen's fixed"
        },
        po.checkpoint.as_ref().map_or(String::new(), |c| format!(
            ", checkpoint {} every {:.0} s",
            c.display(),
            po.every
        ))
    );

    let t0 = Instant::now();
    let mut totals = RenderOutput::empty();
    let mut last_checkpoint = Instant::now();
    let mut checkpoint_error = None;
    let mut longest = 0f64;
    let mut last = 0f64;
    if acc.passes.end < end {
        let first = acc.passes.end;
        pool.install(|| {
            render_passes(
                scene,
                accel,
                settings,
                kind,
                first..end,
                &mut acc,
                &mut |acc, out| {
                    totals.add_counts(out);
                    let now = t0.elapsed().as_secs_f64();
                    longest = longest.max(now - last);
                    last = now;
                    eprintln!(
                    "pass {} done: {:.3} s, of which photon tracing {:.1}% and map building {:.1}%",
                    acc.passes.end - 1,
                    out.seconds,
                    100.0 * out.photon_seconds / out.seconds.max(1e-9),
                    100.0 * out.map_build_seconds / out.seconds.max(1e-9)
                );
                    if let Some(c) = &po.checkpoint {
                        if last_checkpoint.elapsed().as_secs_f64() >= po.every {
                            if let Err(e) = acc.write(c) {
                                checkpoint_error = Some(e);
                                return false;
                            }
                            last_checkpoint = Instant::now();
                        }
                    }
                    let in_budget = opts.time.is_none_or(|b| now + longest <= b);
                    in_budget && crate::interrupt::requested().is_none()
                },
            )
        });
    }
    if let Some(e) = checkpoint_error {
        return Err(ToolError(format!("checkpoint: {e}")));
    }
    let seconds = t0.elapsed().as_secs_f64();
    for note in &totals.notes {
        println!("{note}");
    }
    println!("{}", progress_note(settings, &acc));
    let rays = totals.counters.total();
    println!(
        "rendered in {seconds:.3} s: {rays} rays ({:.2} Mrays/s), {} photons emitted; per-pass overhead: photon tracing {:.1}%, map building {:.1}% of the time",
        rays as f64 / seconds.max(1e-9) / 1e6,
        totals.photons_emitted,
        100.0 * totals.photon_seconds / seconds.max(1e-9),
        100.0 * totals.map_build_seconds / seconds.max(1e-9)
    );
    if let Some(sig) = crate::interrupt::requested() {
        eprintln!(
            "photon: {} received: keeping passes {}..{}",
            sig.name(),
            acc.passes.start,
            acc.passes.end
        );
    }
    // Outputs: the checkpoint (if any), the partial image and the PNG of the mean.
    if acc.passes.is_empty() {
        eprintln!("photon: no pass finished: nothing written");
        return Ok(());
    }
    if let Some(c) = &po.checkpoint {
        acc.write(c)?;
        println!("wrote checkpoint {}", c.display());
    }
    acc.write(exr)?;
    println!(
        "wrote {} (passes {}..{})",
        exr.display(),
        acc.passes.start,
        acc.passes.end
    );
    if let Some(png) = png {
        crate::imageio::write_png(png, &acc.mean().0, opts.exposure)?;
        println!("wrote {}", png.display());
    }
    Ok(())
}
