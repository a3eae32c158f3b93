//! `photon render` in passes (`--progressive`, `--passes A..B`, `--checkpoint`, `--resume`):
//! renders a range of independent passes (see `integrator::passes`) and writes the partial
//! image (exact per-pixel sums plus the mean so far), checkpointing as it goes and on
//! SIGINT/SIGTERM, so that nothing rendered is lost and `photon merge` can sum the parts.
use super::output::{OutputError, Outputs, Writer};
use super::render::RenderOptions;
use super::ToolError;
use crate::accel::Accel;
use crate::integrator::passes::{progress_note, render_passes, Partial, PartialHeader};
use crate::integrator::{RenderOutput, RenderSettings};
use crate::limits::MAX_PASSES;
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

/// Renders in passes and writes the partial image (and the PNG of its mean) to `outputs`.
pub fn run(
    opts: &RenderOptions,
    scene: &Scene,
    accel: &Accel,
    settings: &RenderSettings,
    pool: &rayon::ThreadPool,
    (outputs, checkpoint): (&Outputs, Option<&Outputs>),
    display: Option<&super::display::Display>,
) -> Result<(), ToolError> {
    crate::interrupt::install();
    let po = &opts.passes;
    let kind = opts.integrator;
    let header = PartialHeader::new(scene, settings, kind, &backend_name(opts));
    let start_pass = po.passes.as_ref().map_or(0, |r| r.start);
    let mut acc = match &po.resume {
        Some(file) => {
            let p = Partial::read(file).map_err(|e| ToolError(format!("--resume {e}")))?;
            check_same_render(file, &p.header, &header)?;
            if p.passes.start != start_pass {
                return Err(ToolError(format!(
                    "{}: holds passes {}..{}, which do not start at pass {start_pass}",
                    file.display(),
                    p.passes.start,
                    p.passes.end
                )));
            }
            say!(
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
    let until_budget = po.passes.is_none() && opts.time.is_some();
    let end = pass_end(opts, settings);
    say!(
        "passes: {}..{} of {} spp each, {} photon maps{}",
        acc.passes.end,
        if until_budget {
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
    let mut warned = String::new();
    let (mut longest, mut last) = (0f64, 0f64);
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
                    if let Some(d) = display.filter(|d| d.watching()) {
                        use crate::integrator::Observer;
                        let (image, layers) = acc.mean();
                        d.image(&image, &layers, acc.passes.end - 1);
                    }
                    let now = t0.elapsed().as_secs_f64();
                    longest = longest.max(now - last);
                    last = now;
                    let k = acc.passes.end;
                    let of = match until_budget {
                        true => String::new(),
                        false => format!("/{end}"),
                    };
                    let eta = pass_eta(now, k - first, end - k, opts.time);
                    if !opts.quiet {
                        say_err!(
                            "pass {k}{of} done: {:.3} s, of which photon tracing {:.1}% and map building {:.1}%; {eta}",
                            out.seconds,
                            100.0 * out.photon_seconds / out.seconds.max(1e-9),
                            100.0 * out.map_build_seconds / out.seconds.max(1e-9)
                        );
                    }
                    if let Some(c) = checkpoint {
                        if last_checkpoint.elapsed().as_secs_f64() >= po.every {
                            match write_partial(c, acc) {
                                // Stop; the finished passes are saved below.
                                Err(OutputError::Interrupted(_)) => return false,
                                Err(OutputError::Bad(e)) => warn_once(&mut warned, &e),
                                Ok(()) => warned.clear(),
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
    report(settings, &acc, &totals, t0.elapsed().as_secs_f64());

    // A signal stopped the render: the finished passes are saved all the same (a second
    // signal while writing aborts the writes and removes their temporaries).
    let signal = crate::interrupt::take();
    if let Some(sig) = signal {
        say_err!(
            "photon: {} received: keeping passes {}..{}",
            sig.name(),
            acc.passes.start,
            acc.passes.end
        );
    }
    let saved = save(&acc, checkpoint, outputs, opts.exposure, &mut warned);
    if let Some(sig) = signal {
        crate::interrupt::raise(sig);
    }
    saved
}

/// What is left after `done` passes in `elapsed` seconds with `left` to go (or until the
/// time budget `budget`): `eta 12s` or `budget left 12s`.
fn pass_eta(elapsed: f64, done: u64, left: u64, budget: Option<f64>) -> String {
    let per_pass = elapsed / done.max(1) as f64;
    let eta = left as f64 * per_pass;
    match budget {
        Some(b) if b - elapsed < eta => {
            format!("budget left {}", crate::progress::seconds(b - elapsed))
        }
        _ => format!("eta {}", crate::progress::seconds(eta)),
    }
}

/// Where the passes stop: the range's end, else the file's samples per pixel in passes, else
/// (with `--time`: the budget stops them) the limit.
pub fn pass_end(opts: &RenderOptions, settings: &RenderSettings) -> u64 {
    let start = opts.passes.passes.as_ref().map_or(0, |r| r.start);
    match (&opts.passes.passes, opts.time) {
        (Some(r), _) => r.end,
        (None, Some(_)) => MAX_PASSES,
        (None, None) => start + settings.spp.div_ceil(settings.pass_spp.max(1)).max(1) as u64,
    }
}

/// Renders the passes of `opts` (`--passes`, `--progressive`, with `--time` or without) in
/// memory, for callers that keep the image (the Python module): the mean of the passes, as
/// `photon render` writes it, with the notes of a render in passes. `observer` sees the mean
/// after each pass; a SIGINT/SIGTERM flag stops after the pass in progress. `--checkpoint` and
/// `--resume` (files) are the command line's.
pub fn render_in_memory(
    opts: &RenderOptions,
    scene: &Scene,
    accel: &Accel,
    settings: &RenderSettings,
    pool: &rayon::ThreadPool,
    observer: &dyn crate::integrator::Observer,
) -> RenderOutput {
    let kind = opts.integrator;
    let header = PartialHeader::new(scene, settings, kind, &backend_name(opts));
    let start = opts.passes.passes.as_ref().map_or(0, |r| r.start);
    let mut acc = Partial::new(header, start);
    let t0 = Instant::now();
    let mut totals = RenderOutput::empty();
    let mut longest = 0f64;
    let mut last = 0f64;
    pool.install(|| {
        let range = start..pass_end(opts, settings);
        render_passes(
            scene,
            accel,
            settings,
            kind,
            range,
            &mut acc,
            &mut |acc, out| {
                totals.add_counts(out);
                let (image, layers) = acc.mean();
                observer.image(&image, &layers, acc.passes.end - 1);
                let now = t0.elapsed().as_secs_f64();
                (longest, last) = (longest.max(now - last), now);
                let in_budget = opts.time.is_none_or(|b| now + longest <= b);
                in_budget && crate::interrupt::requested().is_none()
            },
        )
    });
    (totals.image, totals.components) = acc.mean();
    totals.seconds = t0.elapsed().as_secs_f64();
    totals.notes.push(progress_note(settings, &acc));
    totals
}

/// The checkpoint's plan (checked before any work): refused when it is one of the other
/// outputs, or when it already holds a file and `--resume` is not given (it would be replaced
/// by a render that starts over; an empty file, a device or a FIFO is no checkpoint).
pub fn plan_checkpoint(
    po: &super::render::PassOptions,
    outputs: &Outputs,
) -> Result<Option<Outputs>, ToolError> {
    let Some(c) = po.checkpoint.as_deref() else {
        return Ok(None);
    };
    let mut all: Vec<(&str, &Path)> = outputs
        .files
        .iter()
        .map(|f| (f.flag.as_str(), f.shown.as_path()))
        .collect();
    all.push(("--checkpoint", c));
    Outputs::plan_files(&all).map_err(ToolError)?;
    let plan = Outputs::plan_files(&[("--checkpoint", c)]).map_err(ToolError)?;
    let held = std::fs::metadata(&plan.files[0].dest).is_ok_and(|m| m.is_file() && m.len() > 0);
    if held && po.resume.is_none() {
        return Err(ToolError(format!(
            "--checkpoint {}: a checkpoint already exists there: pass --resume {} to continue it, or remove it",
            c.display(),
            c.display()
        )));
    }
    Ok(Some(plan))
}

/// Prints a failed checkpoint write as a one-line warning, unless it is the one printed last.
fn warn_once(last: &mut String, e: &str) {
    if last != e {
        say_err!("photon: warning: {e}; the render goes on without this checkpoint");
        *last = e.to_string();
    }
}

/// The statistics lines of a render in passes.
fn report(settings: &RenderSettings, acc: &Partial, totals: &RenderOutput, seconds: f64) {
    for note in &totals.notes {
        say!("{note}");
    }
    say!("{}", progress_note(settings, acc));
    let rays = totals.counters.total();
    say!(
        "rendered in {seconds:.3} s: {rays} rays ({:.2} Mrays/s), {} photons emitted; per-pass overhead: photon tracing {:.1}%, map building {:.1}% of the time",
        rays as f64 / seconds.max(1e-9) / 1e6,
        totals.photons_emitted,
        100.0 * totals.photon_seconds / seconds.max(1e-9),
        100.0 * totals.map_build_seconds / seconds.max(1e-9)
    );
}

/// Writes the checkpoint (if any) and the outputs: the partial image and the PNG of its mean.
fn save(
    acc: &Partial,
    checkpoint: Option<&Outputs>,
    outputs: &Outputs,
    exposure: f32,
    warned: &mut String,
) -> Result<(), ToolError> {
    if acc.passes.is_empty() {
        say_err!("photon: no pass finished: nothing written");
        return Ok(());
    }
    if let Some(c) = checkpoint {
        // A failure is a warning: the outputs below hold the same passes.
        match write_partial(c, acc) {
            Err(OutputError::Bad(e)) => warn_once(warned, &e),
            Err(e) => return Err(e.into()),
            Ok(()) => say!("wrote checkpoint {}", c.files[0].shown.display()),
        }
    }
    let mean = acc.mean().0;
    let mut writers: Vec<Writer> = vec![Box::new(|tmp: &Path| {
        acc.write(tmp).map_err(|e| super::output::kind_only(&e))
    })];
    if outputs.files.len() > 1 {
        writers.push(Box::new(|tmp: &Path| {
            crate::imageio::write_png(tmp, &mean, exposure)
                .map_err(|e| super::output::kind_only(&e))
        }));
    }
    outputs.commit(writers)?;
    for f in &outputs.files {
        say!(
            "wrote {} (passes {}..{})",
            f.shown.display(),
            acc.passes.start,
            acc.passes.end
        );
    }
    Ok(())
}

/// Writes `acc` as the one planned file of `plan` (a checkpoint: no fallback, see `output`).
fn write_partial(plan: &Outputs, acc: &Partial) -> Result<(), OutputError> {
    plan.commit_without_fallback(vec![Box::new(|tmp: &Path| {
        acc.write(tmp).map_err(|e| super::output::kind_only(&e))
    })])
}
