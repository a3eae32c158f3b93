//! `photon converge SCENE --reference REF.exr`: error against time for each integrator and a
//! few photon-map settings. Every method renders at a series of wall-clock budgets (pass 1
//! included, see `integrator::render_for_time`); the result is a CSV (integrator, settings,
//! budget, seconds, spp, rays, photons, relMSE, RMSE, and the smaller budget whose image a
//! budget repeated, if any) and a log-log PNG plot of relMSE against seconds, one curve per
//! method, whose axes span the measured points. With `--denoise` each image is also denoised
//! (Open Image Denoise, feature `denoise`; guides from the render's `albedo`/`normal` layers
//! when it has them) and measured as the method `NAME+oidn`, whose seconds include the
//! denoiser's.
//!
//! Budgets are kept: the fixed-map photon mapper scales its photon counts down when a pilot
//! predicts that pass 1 would take more than half the budget
//! ([`crate::integrator::render_for_time`]), progressive passes shrink the last pass to what
//! fits, and each line prints the time taken beside the budget (a warning beyond
//! [`BUDGET_TOLERANCE`]). A budget that renders the very same image as a smaller one of the
//! same method (hashed pixels) is reported and left out of the plot and the trend, so that it
//! is not taken for a floor.
use super::job::{Job, Overrides};
use super::output::{kind_only, Outputs, Writer};
use super::{parse_resolution, ToolError};
use crate::accel::{Accel, BackendKind};
use crate::imageio::metrics::{compare, match_sizes, MaskOptions};
use crate::imageio::{read_exr, write_exr, ExrPixel, RgbImage};
use crate::integrator::{render_for_time, IntegratorKind, RenderSettings};
use crate::scene::Scene;
use plotters::coord::combinators::BindKeyPoints;
use plotters::prelude::*;
use std::path::{Path, PathBuf};

/// Options of `photon converge`.
#[derive(clap::Args, Clone, Debug)]
pub struct ConvergeOptions {
    /// The pbrt-v4 scene.
    pub scene: PathBuf,
    /// Reference EXR (box-filtered down to the render's size when an integer factor relates
    /// them).
    #[arg(long)]
    pub reference: PathBuf,
    /// Time budgets in seconds, comma-separated.
    #[arg(long, value_delimiter = ',', default_value = "1,2,4,8,16,32")]
    pub budgets: Vec<f64>,
    /// Render resolution WxH (default: the Film's).
    #[arg(long, value_parser = parse_resolution)]
    pub res: Option<(u32, u32)>,
    /// Output folder for converge.csv, converge.png and the last image of each method.
    #[arg(long, default_value = "converge")]
    pub out: PathBuf,
    /// Only these methods (names as in the CSV), comma-separated; default all.
    #[arg(long, value_delimiter = ',')]
    pub methods: Vec<String>,
    /// Also leave out pixels next to reference pixels brighter than this.
    #[arg(long)]
    pub mask_above: Option<f32>,
    #[arg(long, value_enum, default_value_t = BackendKind::Embree)]
    pub backend: BackendKind,
    #[arg(long, default_value_t = 0)]
    pub threads: usize,
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
    /// Also denoise each image (Open Image Denoise, feature `denoise`) and measure it as the
    /// curve `NAME+oidn` (seconds include the denoising).
    #[arg(long)]
    pub denoise: bool,
}

/// The suffix of a denoised method's name.
pub const DENOISED: &str = "+oidn";

/// One curve: an integrator with some settings.
pub struct Method {
    pub name: &'static str,
    pub kind: IntegratorKind,
    /// Changes to the scene's settings.
    pub adjust: fn(&mut RenderSettings, f64),
}

/// The methods compared by default.
pub fn methods() -> Vec<Method> {
    vec![
        Method {
            name: "photonmap",
            kind: IntegratorKind::Photonmap,
            adjust: |s, b| s.photon.scale_for_budget(b, 200_000),
        },
        Method {
            name: "photonmap-gather16",
            kind: IntegratorKind::Photonmap,
            adjust: |s, b| {
                s.photon.scale_for_budget(b, 200_000);
                s.photon.gather_samples = 16;
            },
        },
        Method {
            name: "photonmap-lookup30",
            kind: IntegratorKind::Photonmap,
            adjust: |s, b| {
                s.photon.scale_for_budget(b, 200_000);
                s.photon.global_lookup = 30;
                s.photon.caustic_lookup = 30;
            },
        },
        Method {
            name: "photonmap-photons4x",
            kind: IntegratorKind::Photonmap,
            adjust: |s, b| s.photon.scale_for_budget(b, 800_000),
        },
        Method {
            name: "progressive",
            kind: IntegratorKind::Photonmap,
            // Photons per pass stay at the file's counts: passes, not bigger maps, carry the
            // convergence (with 1.6M photons per pass, as the fixed maps get at long budgets,
            // a pass costs ~8x more and cornell-spheres reached only 0.00074 at 256 s).
            adjust: |s, _| s.photon.progressive = true,
        },
        Method {
            name: "path",
            kind: IntegratorKind::Path,
            adjust: |_, _| {},
        },
        Method {
            name: "bdpt",
            kind: IntegratorKind::Bdpt,
            adjust: |_, _| {},
        },
        Method {
            name: "vcm",
            kind: IntegratorKind::Vcm,
            adjust: |_, _| {},
        },
    ]
}

/// One measured point.
#[derive(Clone, Debug)]
pub struct Row {
    pub method: String,
    pub settings: String,
    pub budget: f64,
    pub seconds: f64,
    pub spp: u32,
    pub rays: u64,
    pub photons: u64,
    pub relmse: f64,
    pub rmse: f64,
    /// The smaller budget of the same method that rendered the very same image (bit for bit):
    /// such a point is no measurement of the larger budget, so it is left out of the plot and
    /// the trend (and would otherwise look like a floor).
    pub repeat_of: Option<f64>,
}

/// A measured time may exceed its budget by this factor (the last sample pass's estimate,
/// the mandatory first sample per pixel); beyond it `converge` warns.
pub const BUDGET_TOLERANCE: f64 = 1.1;

/// Runs every method at every budget; writes the CSV, the plot and the images.
pub fn run(opts: &ConvergeOptions) -> Result<bool, ToolError> {
    let overrides = Overrides {
        res: opts.res,
        seed: opts.seed,
        ..Default::default()
    };
    let mut job = Job::load(&opts.scene, None)?.with(&overrides);
    (job.backend, job.threads) = (opts.backend, opts.threads);
    if opts.denoise {
        crate::imageio::denoise::available().map_err(|e| ToolError(format!("--denoise: {e}")))?;
    }
    let reference = read_exr(&opts.reference)?;
    std::fs::create_dir_all(&opts.out)
        .map_err(|e| ToolError(format!("{}: {e}", opts.out.display())))?;
    let pool = job.pool()?;
    let (accel, _) = job.build(&pool)?;
    let (scene, base) = (&job.scene, &job.settings);
    let chosen: Vec<Method> = methods()
        .into_iter()
        .filter(|m| opts.methods.is_empty() || opts.methods.iter().any(|n| n == m.name))
        .collect();
    for m in &chosen {
        crate::integrator::check_scene(m.kind, scene)
            .map_err(|e| ToolError(format!("method {}: {e}", m.name)))?;
    }
    if chosen.is_empty() {
        let names: Vec<&str> = methods().iter().map(|m| m.name).collect();
        return Err(ToolError(format!(
            "no such method; known: {}",
            names.join(", ")
        )));
    }
    // Every output is planned (and refused: a directory, another user's link in a sticky
    // folder...) before any render; devices and FIFOs are written into, never replaced.
    let csv = opts.out.join("converge.csv");
    let png = opts.out.join("converge.png");
    let suffixes: &[&str] = if opts.denoise { &["", DENOISED] } else { &[""] };
    let exrs: Vec<PathBuf> = chosen
        .iter()
        .flat_map(|m| {
            suffixes
                .iter()
                .map(|x| opts.out.join(format!("{}{x}.exr", m.name)))
        })
        .collect();
    let mut files: Vec<(&str, &Path)> = vec![("--out", &csv), ("--out", &png)];
    files.extend(exrs.iter().map(|p| ("--out", p.as_path())));
    Outputs::plan_files(&files).map_err(ToolError)?;
    let mask = MaskOptions {
        mask_above: opts.mask_above,
    };
    let mut rows = Vec::new();
    for m in &chosen {
        // The image hashes of this method's budgets so far.
        let mut seen: Vec<(u64, f64)> = Vec::new();
        for &budget in &opts.budgets {
            let target = Target {
                reference: &reference,
                mask,
                out: &opts.out,
                denoise: opts.denoise,
            };
            let (measured, hash) = measure(scene, &accel, base, m, budget, &target, &pool)?;
            let repeat_of = seen.iter().find(|(h, _)| *h == hash).map(|&(_, b)| b);
            seen.push((hash, budget));
            for mut row in measured {
                row.repeat_of = repeat_of;
                let ratio = row.seconds / row.budget;
                say!(
                    "{:<22} budget {:>6.2} s: took {:>7.2} s ({:.2}x), {:>5} spp, relMSE {:.5}, RMSE {:.5}{}",
                    row.method,
                    row.budget,
                    row.seconds,
                    ratio,
                    row.spp,
                    row.relmse,
                    row.rmse,
                    if ratio > BUDGET_TOLERANCE {
                        format!(" (over budget by more than {BUDGET_TOLERANCE}x)")
                    } else {
                        String::new()
                    }
                );
                if let Some(b) = row.repeat_of {
                    say!(
                        "{:<22} budget {:>6.2} s rendered the same image as at {b} s: left out of the plot and the trend",
                        row.method,
                        row.budget
                    );
                }
                rows.push(row);
            }
        }
    }
    for line in trend_lines(&rows) {
        say!("{line}");
    }
    let title = scene_title(&opts.scene);
    let writers: Vec<Writer> = vec![
        Box::new(|tmp: &Path| std::fs::write(tmp, to_csv(&rows)).map_err(|e| e.to_string())),
        Box::new(|tmp: &Path| plot(&rows, tmp, &title).map_err(|e| e.to_string())),
    ];
    Outputs::plan_files(&[("--out", &csv), ("--out", &png)])
        .map_err(ToolError)?
        .commit(writers)?;
    say!("wrote {} and {}", csv.display(), png.display());
    Ok(true)
}

/// What a measured image is compared with and where it goes.
struct Target<'a> {
    reference: &'a crate::imageio::RgbImage,
    mask: MaskOptions,
    out: &'a Path,
    /// Also denoise the image and measure that too (`--denoise`).
    denoise: bool,
}

/// Renders one method at one budget and measures its error, and with `--denoise` the
/// denoised image's too (a second row, `NAME+oidn`).
fn measure(
    scene: &Scene,
    accel: &Accel,
    base: &RenderSettings,
    m: &Method,
    budget: f64,
    target: &Target,
    pool: &rayon::ThreadPool,
) -> Result<(Vec<Row>, u64), ToolError> {
    let mut s = base.clone();
    (m.adjust)(&mut s, budget);
    let (img, spp) = pool.install(|| {
        render_for_time(
            scene,
            accel,
            &s,
            m.kind,
            budget,
            crate::integrator::UNOBSERVED,
        )
    });
    let photons = img.photons_emitted;
    let hash = image_hash(&img.image);
    // The counts the render used (a time budget may have scaled them down).
    let scaled = img
        .notes
        .iter()
        .any(|note| note.starts_with("time budget: photons scaled"));
    let fitted = |n: u64| {
        if scaled {
            format!("{n} scaled to fit the budget")
        } else {
            n.to_string()
        }
    };
    let settings = match m.kind {
        IntegratorKind::Photonmap if s.photon.progressive => format!(
            "progressive global {} caustic {} per pass lookup {}/{} gather {}",
            s.photon.trace.global_photons,
            s.photon.trace.caustic_photons,
            s.photon.global_lookup,
            s.photon.caustic_lookup,
            s.photon.gather_samples
        ),
        IntegratorKind::Photonmap => format!(
            "global {} caustic {} (emitted {}) lookup {}/{} gather {}",
            s.photon.trace.global_photons,
            s.photon.trace.caustic_photons,
            fitted(photons),
            s.photon.global_lookup,
            s.photon.caustic_lookup,
            s.photon.gather_samples
        ),
        _ => format!("maxdepth {}", s.max_depth),
    };
    let row = |method: String, image: &RgbImage, seconds: f64| -> Result<Row, ToolError> {
        let (a, r) = match_sizes(image.clone(), target.reference.clone()).map_err(ToolError)?;
        let metrics = compare(&a, &r, target.mask).map_err(ToolError)?;
        let exr = target.out.join(format!("{method}.exr"));
        let writer: Writer = Box::new(|tmp: &Path| {
            write_exr(tmp, image, &[], ExrPixel::Half).map_err(|e| kind_only(&e))
        });
        Outputs::plan_files(&[("--out", &exr)])
            .map_err(ToolError)?
            .commit(vec![writer])?;
        Ok(Row {
            method,
            settings: settings.clone(),
            budget,
            seconds,
            spp,
            rays: img.counters.total(),
            photons,
            relmse: metrics.overall.relmse,
            rmse: metrics.overall.rmse,
            repeat_of: None,
        })
    };
    let mut rows = vec![row(m.name.to_string(), &img.image, img.seconds)?];
    if target.denoise {
        let layers: Vec<(&str, &RgbImage)> = img.components.iter().map(|(n, i)| (*n, i)).collect();
        let channels = super::denoise::layer_channels(&layers);
        let done =
            super::denoise::denoise_image(&img.image, &super::denoise::views(&channels), true)
                .map_err(|e| ToolError(format!("--denoise: {e}")))?;
        let name = format!("{}{DENOISED}", m.name);
        rows.push(row(name, &done.image, img.seconds + done.seconds)?);
    }
    Ok((rows, hash))
}

/// A 64-bit hash of an image's pixel bits.
fn image_hash(img: &crate::imageio::RgbImage) -> u64 {
    img.pixels.iter().flatten().fold(
        crate::sampling::mix64(img.width as u64 ^ ((img.height as u64) << 32)),
        |h, v| crate::sampling::mix64(h ^ v.to_bits() as u64),
    )
}

/// Per method: the least-squares slope of log relMSE against log seconds over the upper half
/// of its budgets (two points at least), and whether its curve has a floor (the last doubling
/// of time gained less than 15%). Points that repeat a smaller budget's image
/// ([`Row::repeat_of`]) are left out: they measure nothing new.
pub fn trend_lines(rows: &[Row]) -> Vec<String> {
    let mut names: Vec<&str> = rows.iter().map(|r| r.method.as_str()).collect();
    names.dedup();
    names
        .into_iter()
        .filter_map(|name| {
            let pts: Vec<(f64, f64)> = rows
                .iter()
                .filter(|r| {
                    r.method == name && r.repeat_of.is_none() && r.relmse > 0.0 && r.seconds > 0.0
                })
                .map(|r| (r.seconds.ln(), r.relmse.ln()))
                .collect();
            // (Two points are a tail of their own.)
            let tail = &pts[(pts.len() / 2).min(pts.len().saturating_sub(2))..];
            if tail.len() < 2 {
                return None;
            }
            let n = tail.len() as f64;
            let (mx, my) = tail.iter().fold((0.0, 0.0), |(a, b), p| (a + p.0 / n, b + p.1 / n));
            let sxy: f64 = tail.iter().map(|p| (p.0 - mx) * (p.1 - my)).sum();
            let sxx: f64 = tail.iter().map(|p| (p.0 - mx).powi(2)).sum();
            let slope = sxy / sxx.max(1e-12);
            let [.., a, b] = pts[..] else { return None };
            let gain = (a.1 - b.1).exp(); // relMSE ratio over the last step
            let floor = if gain < 1.15 {
                format!("FLOOR: the last step gained only {:.0}%", 100.0 * (gain - 1.0))
            } else {
                format!("still falling ({:.2}x over the last step)", gain)
            };
            Some(format!(
                "{name}: relMSE ~ t^{slope:.2} over the upper half of the budgets; {floor}; best {:.5}",
                pts.iter().map(|p| p.1.exp()).fold(f64::INFINITY, f64::min)
            ))
        })
        .collect()
}

/// The rows as CSV with a header line (`same_image_as_budget_s`: [`Row::repeat_of`]).
pub fn to_csv(rows: &[Row]) -> String {
    let mut s = String::from(
        "integrator,settings,budget_s,seconds,spp,rays,photons,relmse,rmse,same_image_as_budget_s\n",
    );
    for r in rows {
        s += &format!(
            "{},{},{},{:.3},{},{},{},{:.6e},{:.6e},{}\n",
            r.method,
            r.settings,
            r.budget,
            r.seconds,
            r.spp,
            r.rays,
            r.photons,
            r.relmse,
            r.rmse,
            r.repeat_of.map_or(String::new(), |b| b.to_string())
        );
    }
    s
}

fn scene_title(path: &Path) -> String {
    path.parent()
        .and_then(|p| p.file_name())
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_else(|| path.display().to_string())
}

/// The range of a log axis over positive `values`: their minimum and maximum, widened by 4% of
/// the span in log space on each side (so the end points' dots are drawn whole), or by a
/// factor 1.25 each way when all values are equal. `(1, 10)` when there is no positive value.
pub fn log_axis(values: impl IntoIterator<Item = f64>) -> (f64, f64) {
    let (lo, hi) = values
        .into_iter()
        .filter(|v| v.is_finite() && *v > 0.0)
        .fold((f64::INFINITY, 0.0f64), |(a, b), v| (a.min(v), b.max(v)));
    if hi <= 0.0 {
        return (1.0, 10.0);
    }
    let span = (hi / lo).ln();
    if span <= 0.0 {
        return (lo / 1.25, hi * 1.25);
    }
    let pad = (0.04 * span).exp();
    (lo / pad, hi * pad)
}

/// Tick positions for a log axis over `[lo, hi]`: the powers of ten inside it; with fewer
/// than three of them, also 2x and 5x each power (1, 2, 5, 10, 20, ...); with fewer than two
/// ticks still, every integer multiple 1..9 of each power.
pub fn log_ticks(lo: f64, hi: f64) -> Vec<f64> {
    if !(lo > 0.0 && hi > lo && hi.is_finite()) {
        return Vec::new();
    }
    let ticks = |mult: &[f64]| -> Vec<f64> {
        let (e0, e1) = (lo.log10().floor() as i32, hi.log10().ceil() as i32);
        (e0..=e1)
            .flat_map(|e| mult.iter().map(move |m| m * 10f64.powi(e)))
            // A little slack: a tick that rounding puts just outside the ends stays.
            .filter(|&t| t >= lo * (1.0 - 1e-9) && t <= hi * (1.0 + 1e-9))
            .collect()
    };
    let decades = ticks(&[1.0]);
    if decades.len() >= 3 {
        return decades;
    }
    let some = ticks(&[1.0, 2.0, 5.0]);
    if some.len() >= 2 {
        return some;
    }
    ticks(&[1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0, 8.0, 9.0])
}

/// A tick's label: plain for 0.01..1000 (`0.5`, `2`, `300`), else `1e-4` style.
fn tick_label(v: f64) -> String {
    if (0.01..1000.0).contains(&v) {
        let s = format!("{v:.2}");
        s.trim_end_matches('0').trim_end_matches('.').to_string()
    } else {
        let s = format!("{v:.0e}");
        s
    }
}

/// A log-log plot of relMSE against seconds, one curve per method, its axes spanning the
/// data ([`log_axis`]) with ticks at decades ([`log_ticks`]).
pub fn plot(rows: &[Row], path: &Path, title: &str) -> Result<(), ToolError> {
    let err = |e: &dyn std::fmt::Display| ToolError(format!("{}: plot: {e}", path.display()));
    let pos = |v: f64| v.is_finite() && v > 0.0;
    let pts: Vec<&Row> = rows
        .iter()
        .filter(|r| r.repeat_of.is_none() && pos(r.seconds) && pos(r.relmse))
        .collect();
    if pts.is_empty() {
        return Err(ToolError(format!("{}: nothing to plot", path.display())));
    }
    let (x0, x1) = log_axis(pts.iter().map(|r| r.seconds));
    let (y0, y1) = log_axis(pts.iter().map(|r| r.relmse));
    let tmp = path.with_extension("tmp.png");
    {
        let root = BitMapBackend::new(&tmp, (900, 600)).into_drawing_area();
        root.fill(&WHITE).map_err(|e| err(&e))?;
        let mut chart = ChartBuilder::on(&root)
            .caption(format!("{title}: relMSE against time"), ("sans-serif", 22))
            .margin(12)
            .x_label_area_size(45)
            .y_label_area_size(70)
            .build_cartesian_2d(
                (x0..x1).log_scale().with_key_points(log_ticks(x0, x1)),
                (y0..y1).log_scale().with_key_points(log_ticks(y0, y1)),
            )
            .map_err(|e| err(&e))?;
        chart
            .configure_mesh()
            .x_desc("seconds (wall clock, pass 1 included)")
            .y_desc("relMSE")
            .x_label_formatter(&|v| tick_label(*v))
            .y_label_formatter(&|v| tick_label(*v))
            .draw()
            .map_err(|e| err(&e))?;
        let mut names: Vec<&str> = Vec::new();
        for r in &pts {
            if !names.contains(&r.method.as_str()) {
                names.push(&r.method);
            }
        }
        for (i, name) in names.iter().enumerate() {
            let color = Palette99::pick(i).to_rgba();
            let mut series: Vec<(f64, f64)> = pts
                .iter()
                .filter(|r| r.method == *name)
                .map(|r| (r.seconds, r.relmse))
                .collect();
            series.sort_by(|a, b| a.0.total_cmp(&b.0));
            chart
                .draw_series(LineSeries::new(series.clone(), color.stroke_width(2)))
                .map_err(|e| err(&e))?
                .label(*name)
                .legend(move |(x, y)| {
                    PathElement::new(vec![(x, y), (x + 20, y)], color.stroke_width(2))
                });
            chart
                .draw_series(series.iter().map(|&p| Circle::new(p, 3, color.filled())))
                .map_err(|e| err(&e))?;
        }
        chart
            .configure_series_labels()
            .background_style(WHITE.mix(0.85))
            .border_style(BLACK)
            .draw()
            .map_err(|e| err(&e))?;
        root.present().map_err(|e| err(&e))?;
    }
    std::fs::rename(&tmp, path).map_err(|e| ToolError(format!("{}: {e}", path.display())))
}
