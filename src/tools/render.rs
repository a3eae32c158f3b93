//! `photon render SCENE`: load, build the accelerator, render, write EXR + PNG, print stats.
use super::job::{Job, Overrides};
use super::output::Outputs;
use super::{float_in, parse_resolution, usize_in, ToolError};
use crate::accel::{Accel, BackendKind, RayKind};
use crate::imageio::{self, ExrPixel};
use crate::integrator::aov::Aov;
use crate::integrator::{self, IntegratorKind, RenderSettings};
use crate::limits::{MAX_DEPTH, MAX_EXPOSURE, MAX_LIGHT_SAMPLES, MAX_PASSES, MAX_SPP, MAX_THREADS};
use crate::sampling::Pattern;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering::Relaxed};
use std::time::Instant;

/// Options of `photon render`.
#[derive(clap::Args, Clone, Debug)]
pub struct RenderOptions {
    /// The pbrt-v4 scene file.
    pub scene: PathBuf,
    /// Output image, in the format its extension names: `.exr` (linear RGB plus layers
    /// direct/specular/caustic/indirect, and a PNG preview beside it), `.png` (8-bit sRGB
    /// only), `.pfm` (linear RGB only). Default: the Film's filename with .exr, else the
    /// scene's name. `--outfile` is pbrt-v4's name for it. Renders in passes write EXR.
    #[arg(short, long, visible_alias = "outfile")]
    pub output: Option<PathBuf>,
    /// PNG preview (sRGB). Default: the EXR path with .png (none when -o is a PNG or PFM).
    #[arg(long)]
    pub png: Option<PathBuf>,
    /// Skip the PNG preview.
    #[arg(long)]
    pub no_png: bool,
    /// Render for this wall-clock budget instead of a fixed sample count (e.g. `10s`, `2.5`,
    /// `1m`): samples per pixel and photon counts are chosen to fit it.
    #[arg(long, value_parser = parse_duration)]
    pub time: Option<f64>,
    /// Samples per pixel (default: the Sampler's pixelsamples).
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..=MAX_SPP as i64))]
    pub spp: Option<u32>,
    /// Resolution WxH (default: the Film's).
    #[arg(long, value_parser = parse_resolution)]
    pub res: Option<(u32, u32)>,
    /// Render only this part of the image, `x0,x1,y0,y1` as fractions (pbrt-v4's flag; the
    /// film's `cropwindow` otherwise). The image written is the crop's size.
    #[arg(long, value_name = "X0,X1,Y0,Y1", allow_hyphen_values = true,
          value_parser = |s: &str| crate::film::Crop::parse(s, false))]
    pub cropwindow: Option<crate::film::Crop>,
    /// Render only the pixels `[x0, x1) x [y0, y1)` (pbrt-v4's flag; wins over --cropwindow).
    #[arg(long, value_name = "X0,X1,Y0,Y1",
          value_parser = |s: &str| crate::film::Crop::parse(s, true))]
    pub pixelbounds: Option<crate::film::Crop>,
    /// pbrt-v4's quick look: a quarter of the resolution on each axis and one sample per
    /// pixel (after --res and --spp).
    #[arg(long)]
    pub quick: bool,
    /// Ray-query backend.
    #[arg(long, value_enum, default_value_t = BackendKind::Embree)]
    pub backend: BackendKind,
    /// Embree's robust scene flag.
    #[arg(long)]
    pub robust: bool,
    /// Worker threads (0 = all cores).
    #[arg(long, visible_alias = "nthreads", default_value_t = 0, value_parser = usize_in(0, MAX_THREADS))]
    pub threads: usize,
    /// Seed of every sample stream.
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
    /// Stratification of each pixel's samples.
    #[arg(long, value_enum, default_value_t = Pattern::Stratified)]
    pub pattern: Pattern,
    /// The integrator (whatever the file asks for).
    #[arg(long, value_enum, default_value_t = IntegratorKind::Photonmap)]
    pub integrator: IntegratorKind,
    /// Maximum bounces (default: the Integrator's maxdepth, else 5).
    #[arg(long, value_parser = clap::value_parser!(u32).range(0..=MAX_DEPTH as i64))]
    pub max_depth: Option<u32>,
    /// Shadow rays per shading point.
    #[arg(long, default_value_t = 1, value_parser = clap::value_parser!(u32).range(1..=MAX_LIGHT_SAMPLES as i64))]
    pub light_samples: u32,
    /// Write half floats instead of 32-bit floats.
    #[arg(long)]
    pub half: bool,
    /// Denoise the image with Intel Open Image Denoise before writing it (feature `denoise`),
    /// guided by the render's `albedo` and `normal` layers when it has them; an EXR keeps the
    /// noisy beauty as layer `noisy`. Not with renders in passes: denoise the merged image
    /// with `photon denoise`.
    #[arg(long)]
    pub denoise: bool,
    /// Print nothing but errors and warnings (pbrt-v4's flag): no banner, no statistics, no
    /// progress.
    #[arg(long, short)]
    pub quiet: bool,
    /// Progress as a plain line every second, even on a terminal (without a terminal: every
    /// 5 s; on a terminal: a bar per stage).
    #[arg(long, short)]
    pub verbose: bool,
    /// Split the wall time into ray queries, photon lookups, shading, photon tracing and map
    /// building.
    #[arg(long)]
    pub stats: bool,
    /// PNG exposure in stops.
    #[arg(long, default_value_t = 0.0, allow_negative_numbers = true, value_parser = float_in(-MAX_EXPOSURE, MAX_EXPOSURE, false))]
    pub exposure: f32,
    /// Memory budget (e.g. `8G`, `512M`): a render whose estimate exceeds it stops before it
    /// starts (default: 80% of physical memory, or of what an address-space limit leaves).
    #[arg(long, value_parser = crate::limits::parse_size)]
    pub max_memory: Option<u64>,
    /// Live preview: send the image to the tev viewer listening at HOST:PORT as tiles finish
    /// or passes are added (pbrt-v4's flag); the render never waits for the viewer.
    #[arg(long, value_name = "HOST:PORT", value_parser = super::display::parse_server)]
    pub display_server: Option<String>,
    /// VCM's initial merge radius: `Npx` pixel footprints (default 2px), or a fraction of
    /// the radius of the scene's bounding sphere (`0.003`); it shrinks with the samples by
    /// `--alpha` (default 0.75 for VCM).
    #[arg(long, allow_hyphen_values = true, value_parser = crate::integrator::vcm::MergeRadius::parse)]
    pub merge_radius: Option<crate::integrator::vcm::MergeRadius>,
    /// VCM merges at every non-delta vertex, as Georgiev et al. do; by default only at
    /// vertices seen through a purely specular surface (paths no connection samples).
    #[arg(long)]
    pub all_merges: bool,
    /// VCM's and bdpt's light subpaths per iteration as a fraction of the pixels, in (0, 1]
    /// (camera subpath k connects to light subpath k mod their number); default: chosen by a
    /// pilot iteration from the share of the image that light tracing, connections and
    /// merges carry (twice it, at least 1/16).
    #[arg(long, value_parser = super::float_in(0.0, 1.0, true))]
    pub light_paths: Option<f32>,
    /// Data channels to write beside the image (EXR only), comma-separated or repeated:
    /// `alpha` (A), `albedo` and `normal` (the denoiser's guides, at the first surface that is
    /// not a mirror or smooth glass), `depth` (Z, camera space), `position` (P, world space).
    /// `Film "gbuffer"` adds pbrt-v4's channels.
    #[arg(long, value_enum, value_delimiter = ',', value_name = "NAME,...")]
    pub aov: Vec<Aov>,
    /// Render spectrally as pbrt-v4 does: each camera sample at four wavelengths, the
    /// scene's RGB colours uplifted to spectra (Jakob-Hanika), the film through the CIE 1931
    /// observer. Saturated colours after several bounces then match pbrt-v4 (RGB rendering
    /// is several percent off there), at the price of colour noise (2-3x the error where RGB
    /// is right). `auto` decides by how much light saturated colours may scatter twice
    /// (`integrator::coloured_share`); the default is RGB, with a note when `auto` would
    /// choose spectral. Path, photonmap and direct only, scenes without media. `--spectral`
    /// alone is `on`.
    #[arg(long, value_enum, num_args = 0..=1, require_equals = true,
          default_value_t = integrator::Spectral::Off, default_missing_value = "on")]
    pub spectral: integrator::Spectral,
    #[command(flatten)]
    pub photon: crate::integrator::settings::PhotonOverrides,
    #[command(flatten)]
    pub passes: PassOptions,
}

/// Rendering in independent passes (see `integrator::passes`).
#[derive(clap::Args, Clone, Debug, Default)]
pub struct PassOptions {
    /// Progressive photon mapping: fresh photon maps every pass, radii shrinking by the
    /// Knaus-Zwicker schedule (also `Integrator "photonmap" "bool progressive" [ true ]`).
    #[arg(long)]
    pub progressive: bool,
    /// The radius schedule's alpha, in (0, 1) (default 2/3).
    #[arg(long, value_parser = crate::integrator::settings::parser::<f32>(
        Some(crate::integrator::settings::ALPHA)))]
    pub alpha: Option<f32>,
    /// Render only passes A..B (half-open, as in Rust) and write a partial image that
    /// `photon merge` sums with the other parts; `N` means 0..N; B at most 2^20. Default
    /// with --progressive: enough passes for the file's samples per pixel.
    #[arg(long, value_parser = parse_pass_range)]
    pub passes: Option<std::ops::Range<u64>>,
    /// Samples per pixel of each pass (default: `"integer passspp"`, else 4).
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..=MAX_SPP as i64))]
    pub pass_spp: Option<u32>,
    /// Write the partial image to FILE as the render goes (atomically), at most every
    /// --every; on SIGINT/SIGTERM it is written before exiting. A write that fails is a
    /// warning (the render goes on). An existing FILE is refused unless --resume is given.
    #[arg(long)]
    pub checkpoint: Option<PathBuf>,
    /// Time between checkpoints (e.g. 30s, 5m).
    #[arg(long, value_parser = parse_duration, default_value = "5m")]
    pub every: f64,
    /// Continue the render saved in FILE (a checkpoint or partial image of the same scene and
    /// settings) from its last pass.
    #[arg(long)]
    pub resume: Option<PathBuf>,
}

impl PassOptions {
    /// True when the render runs in deterministic passes and writes a partial image (with
    /// `--time` and no other pass option, `--progressive` renders for the budget instead).
    pub fn active(&self, timed: bool) -> bool {
        (self.progressive && !timed)
            || self.passes.is_some()
            || self.checkpoint.is_some()
            || self.resume.is_some()
    }
}

/// Parses `A..B` (passes A to B-1) or `N` (0..N).
pub fn parse_pass_range(s: &str) -> Result<std::ops::Range<u64>, String> {
    let num = |t: &str| {
        t.trim()
            .parse::<u64>()
            .map_err(|_| format!("expected A..B or N (pass numbers), got {s:?}"))
    };
    let r = match s.split_once("..") {
        Some((a, b)) => num(a)?..num(b)?,
        None => 0..num(s)?,
    };
    if r.start >= r.end {
        return Err(format!(
            "empty pass range {s:?} (A..B renders passes A to B-1)"
        ));
    }
    if r.end > MAX_PASSES {
        return Err(format!(
            "pass range {s:?} goes beyond the limit of {MAX_PASSES} passes"
        ));
    }
    Ok(r)
}

/// Where the EXR goes when `-o` is not given.
fn default_output(film_filename: Option<&str>, scene: &Path) -> PathBuf {
    let stem = film_filename
        .and_then(|f| Path::new(f).file_stem().map(|s| s.to_owned()))
        .or_else(|| scene.file_stem().map(|s| s.to_owned()))
        .unwrap_or_else(|| "render".into());
    PathBuf::from(stem).with_extension("exr")
}

impl RenderOptions {
    /// The overrides of the file's settings this command line gives.
    pub fn overrides(&self) -> Overrides {
        Overrides {
            res: self.res,
            spp: self.spp,
            max_depth: self.max_depth,
            seed: self.seed,
            pattern: self.pattern,
            light_samples: Some(self.light_samples),
            photon: self.photon.clone(),
            alpha: self.passes.alpha,
            merge_radius: self.merge_radius,
            all_merges: self.all_merges,
            light_paths: self.light_paths,
            progressive: self.passes.progressive,
            pass_spp: self.passes.pass_spp,
            crop: self.pixelbounds.or(self.cropwindow),
            quick: self.quick,
            aovs: match self.denoise {
                // The denoiser's guides.
                true => [&self.aov[..], &[Aov::Albedo, Aov::Normal]].concat(),
                false => self.aov.clone(),
            },
            spectral: Some(self.spectral),
        }
    }
}

/// A render ready to go: its thread pool, accelerator and memory estimate (see [`prepare`]).
pub struct Prepared {
    pub pool: rayon::ThreadPool,
    pub accel: Accel,
    /// Seconds the accelerator took to build.
    pub build_s: f64,
    /// The memory model of the render, checked against the budget.
    pub estimate: crate::memory::Estimate,
    budget: crate::limits::Budget,
    cli: crate::memory::FromCli,
}

/// Takes `opts`' integrator, backend, threads and preview into `job` (whose settings already
/// have `opts`' overrides: [`Job::with`]).
pub fn configure(job: &mut Job, opts: &RenderOptions) {
    (job.integrator, job.backend, job.threads) = (opts.integrator, opts.backend, opts.threads);
    job.accel.robust = opts.robust;
    job.preview = opts.display_server.is_some();
}

/// Everything a render does before it renders: checks the memory model without the photon
/// maps, builds the accelerator, measures pass 1 with a pilot trace and checks again with
/// the photon maps. `photon render` and the Python module both start here.
pub fn prepare(job: &mut Job, opts: &RenderOptions) -> Result<Prepared, ToolError> {
    integrator::check_scene(job.integrator, &job.scene).map_err(ToolError)?;
    job.resolve_spectral();
    integrator::check_spectral(job.integrator, &job.settings, &job.scene).map_err(ToolError)?;
    let cli = opts.overrides().from_cli();
    let budget = crate::limits::Budget::resolve(opts.max_memory);
    job.check_memory(&job.settings, &budget, cli)
        .map_err(ToolError)?;
    let pool = job.pool()?;
    let (accel, build_s) = job.build(&pool)?;
    job.pilot(&accel, &pool);
    let estimate = job
        .check_memory(&job.settings, &budget, cli)
        .map_err(ToolError)?;
    Ok(Prepared {
        pool,
        accel,
        build_s,
        estimate,
        budget,
        cli,
    })
}

/// Renders `job` as `prepared` for `opts` (not in passes: see [`PassOptions::active`]): for
/// `--time` passes until the budget is spent, with photon maps grown to fit it (and the memory
/// budget: `prepared.estimate` follows), else the file's samples. Notes about the budget join
/// the output's notes. A SIGINT/SIGTERM flag ([`crate::interrupt`]) stops it early: the caller
/// checks the flag and treats the image as incomplete.
pub fn render_image(
    job: &Job,
    prepared: &mut Prepared,
    opts: &RenderOptions,
    observer: &dyn integrator::Observer,
) -> Result<integrator::RenderOutput, ToolError> {
    let (scene, accel, pool) = (&job.scene, &prepared.accel, &prepared.pool);
    let mut settings = job.settings.clone();
    let Some(budget) = opts.time else {
        return Ok(
            pool.install(|| integrator::render(scene, accel, &settings, opts.integrator, observer))
        );
    };
    let mut notes = Vec::new();
    // Fixed maps grow with the budget; progressive passes keep the file's counts.
    let given = opts.photon.global_photons.is_some() || opts.photon.caustic_photons.is_some();
    // In a scene whose media need tracking the photon mapper builds its volume map alone.
    let photonmap =
        opts.integrator == IntegratorKind::Photonmap && job.scene.media_need_tracking.is_none();
    if photonmap && !given && !settings.photon.progressive {
        // The budget's counts, halved until the memory estimate fits; the file's counts
        // (already checked) are the floor.
        let check = |s: &RenderSettings| job.check_memory(s, &prepared.budget, prepared.cli);
        let t = &settings.photon.trace;
        let file = (t.global_photons, t.caustic_photons);
        settings.photon.scale_for_budget(budget, 200_000);
        let t = &settings.photon.trace;
        let wanted = (t.global_photons, t.caustic_photons);
        while check(&settings).is_err() {
            let t = &mut settings.photon.trace;
            if t.global_photons <= file.0 && t.caustic_photons <= file.1 {
                (t.global_photons, t.caustic_photons) = file;
                break;
            }
            t.global_photons = (t.global_photons / 2).max(file.0);
            t.caustic_photons = (t.caustic_photons / 2).max(file.1);
        }
        prepared.estimate = check(&settings).map_err(|e| ToolError(format!("--time: {e}")))?;
        let t = &settings.photon.trace;
        if (t.global_photons, t.caustic_photons) != wanted {
            notes.push(format!(
                "time budget: {} + {} photons would not fit the memory budget: {} + {}",
                wanted.0, wanted.1, t.global_photons, t.caustic_photons
            ));
        }
    }
    let (mut out, spp) = pool.install(|| {
        integrator::render_for_time(scene, accel, &settings, opts.integrator, budget, observer)
    });
    notes.push(if photonmap {
        format!(
            "time budget {budget:.2} s: {spp} spp, {} + {} photons",
            settings.photon.trace.global_photons, settings.photon.trace.caustic_photons
        )
    } else {
        format!("time budget {budget:.2} s: {spp} spp")
    });
    notes.append(&mut out.notes);
    out.notes = notes;
    Ok(out)
}

pub fn run(opts: &RenderOptions) -> Result<(), ToolError> {
    super::set_quiet(opts.quiet);
    let _progress =
        super::progress::Reporter::start(super::progress::Mode::pick(opts.quiet, opts.verbose));
    // Load and validate everything before any work is done.
    let mut job = Job::load(&opts.scene, opts.max_memory)?.with(&opts.overrides());
    configure(&mut job, opts);
    let exr = opts
        .output
        .clone()
        .unwrap_or_else(|| default_output(job.scene.film.filename.as_deref(), &opts.scene));
    let format = super::output::ImageFormat::of("-o", &exr).map_err(ToolError)?;
    let png = match opts.no_png {
        true => None,
        false => opts.png.clone().or_else(|| match format {
            super::output::ImageFormat::Exr => super::output::default_png(&exr),
            _ => None,
        }),
    };
    if !opts.aov.is_empty() {
        if format != super::output::ImageFormat::Exr {
            let name = exr.display();
            return Err(ToolError(format!(
                "--aov: data channels need an EXR image (-o {name} is not one)"
            )));
        }
        if opts.passes.active(opts.time.is_some()) {
            return Err(ToolError(
                "--aov: renders in passes write partial images, without data channels".into(),
            ));
        }
    }
    let outputs = match opts.passes.active(opts.time.is_some()) {
        true => Outputs::plan(&exr, png.as_deref()),
        false => Outputs::plan_image(&exr, png.as_deref()),
    }
    .map_err(ToolError)?;
    if opts.denoise {
        check_denoise(opts)?;
    }
    let checkpoint = super::render_passes::plan_checkpoint(&opts.passes, &outputs)?;
    let mut prepared = prepare(&mut job, opts)?;
    let threads = prepared.pool.current_num_threads();
    banner(opts, &job, prepared.build_s, threads);
    let display = opts.display_server.as_deref().map(|server| {
        let (w, h) = job.settings.image_size();
        let name = outputs.files[0].shown.file_name().unwrap_or_default();
        super::display::Display::start(server, &name.to_string_lossy(), w, h)
    });
    if opts.passes.active(opts.time.is_some()) {
        let outs = (&outputs, checkpoint.as_ref());
        let (scene, p) = (&job.scene, &prepared);
        let ran = super::render_passes::run(
            opts,
            scene,
            &p.accel,
            &job.settings,
            &p.pool,
            outs,
            display.as_ref(),
        );
        if let Some(d) = display {
            d.finish();
        }
        return ran;
    }

    // SIGINT/SIGTERM from here on stop the render: the tiles (or, with --time, the passes)
    // finished are kept in a fallback file and -o is left as it was (see `stopped`).
    crate::interrupt::install();
    let mut watch = Watch {
        tiles: [AtomicU64::new(0), AtomicU64::new(0)],
        display,
    };
    let out = render_image(&job, &mut prepared, opts, &watch);
    crate::progress::end();
    if let Some(d) = watch.display.take() {
        d.finish();
    }
    let out = out?;
    let pixel = if opts.half {
        ExrPixel::Half
    } else {
        ExrPixel::Float
    };
    let mut layers: Vec<(&str, &imageio::RgbImage)> =
        out.components.iter().map(|(n, i)| (*n, i)).collect();
    if let Some(sig) = crate::interrupt::take() {
        let tiles = &watch.tiles;
        let done = match opts.time {
            Some(_) => None,
            None => Some((tiles[0].load(Relaxed), tiles[1].load(Relaxed))),
        };
        let extra = imageio::ExrExtra::default();
        let writers = outputs.render_writers(&out.image, &layers, pixel, opts.exposure, extra);
        let message = stopped(sig, done, &outputs, writers);
        crate::interrupt::raise(sig);
        return Err(ToolError(message));
    }
    // The data channels (a pass of their own) and the header's metadata.
    let settings = &job.settings;
    let data = match settings.aovs.is_empty() || outputs.format != super::output::ImageFormat::Exr {
        true => Vec::new(),
        false => prepared
            .pool
            .install(|| integrator::render_aovs(&job.scene, &prepared.accel, settings, &out)),
    };
    if settings.aovs.gbuffer.is_some() && out.variance.is_none() {
        say!(
            "Film \"gbuffer\": no Variance channels (they need a per-pixel integrator over a \
             fixed sample count, not --time or a bidirectional one)"
        );
    }
    for note in &out.notes {
        say!("{note}");
    }
    let rays = out.counters.total();
    say!(
        "rendered in {:.3} s: {} rays ({:.2} Mrays/s): camera {}, secondary {}, shadow {}",
        out.seconds,
        rays,
        rays as f64 / out.seconds / 1e6,
        out.counters
            .camera_rays
            .load(std::sync::atomic::Ordering::Relaxed),
        out.counters
            .secondary_rays
            .load(std::sync::atomic::Ordering::Relaxed),
        out.counters
            .shadow_rays
            .load(std::sync::atomic::Ordering::Relaxed),
    );
    let estimate = prepared.estimate;
    if opts.stats {
        print_stats(&out, threads);
        print_raw_rate(
            &job.scene,
            prepared.accel,
            &job.settings,
            &out,
            &prepared.pool,
        );
    }
    let bad = out.image.count_nonfinite();
    if bad > 0 {
        say_err!("photon: warning: {bad} non-finite pixel values");
    }

    let denoised = match opts.denoise {
        true => Some(denoise(&out.image, &data)?),
        false => None,
    };
    if denoised.is_some() {
        layers.push((super::denoise::NOISY, &out.image));
    }
    let image = denoised.as_ref().unwrap_or(&out.image);
    let (strings, typed) = metadata(opts, &job, &out);
    let strings: Vec<(&str, &str)> = strings.iter().map(|(k, v)| (*k, v.as_str())).collect();
    let channels: Vec<(&str, &[f32])> = data.iter().map(|(k, v)| (k.as_str(), &v[..])).collect();
    let extra = imageio::ExrExtra {
        attributes: &strings,
        typed: &typed,
        channels: &channels,
        ..Default::default()
    };
    // Outputs: written to temporary files and renamed together (see `output`).
    outputs.write(image, &layers, pixel, opts.exposure, extra)?;
    for f in &outputs.files {
        say!("wrote {}", f.shown.display());
    }
    say!("{}", crate::memory::report(&estimate));
    Ok(())
}

/// String and typed EXR header attributes.
type Metadata = (
    Vec<(&'static str, String)>,
    Vec<(&'static str, imageio::ExrAttr)>,
);

/// The EXR header's metadata of a finished render: strings (`software`, `integrator`, `seed`,
/// `scene`; `photon.*` names mark partial images) and pbrt-v4's typed attributes (`samplesPerPixel`, `renderTimeSeconds`,
/// `worldToCamera`, `worldToNDC`) plus the sRGB `chromaticities` of photon's linear RGB.
fn metadata(opts: &RenderOptions, job: &Job, out: &integrator::RenderOutput) -> Metadata {
    use imageio::ExrAttr;
    let integrator = clap::ValueEnum::to_possible_value(&opts.integrator)
        .map_or("?".into(), |v| v.get_name().to_string());
    let strings = vec![
        ("software", format!("photon {}", env!("CARGO_PKG_VERSION"))),
        ("integrator", integrator),
        ("seed", job.settings.seed.to_string()),
        ("scene", opts.scene.display().to_string()),
    ];
    let (camera, ndc) = integrator::aov::camera_matrices(&job.scene.camera);
    let rows = |m: crate::math::Mat4| {
        let t = m.transpose().to_cols_array_2d();
        ExrAttr::M44(t)
    };
    let typed = vec![
        (
            "samplesPerPixel",
            ExrAttr::Int(out.spp.min(i32::MAX as u32) as i32),
        ),
        ("renderTimeSeconds", ExrAttr::Float(out.seconds as f32)),
        ("worldToCamera", rows(camera)),
        ("worldToNDC", rows(ndc)),
        (
            "chromaticities",
            ExrAttr::Chromaticities([0.64, 0.33, 0.30, 0.60, 0.15, 0.06, 0.3127, 0.3290]),
        ),
    ];
    (strings, typed)
}

/// `--denoise` before any work: not with a render in passes (its EXR is a partial image,
/// whose mean `merge` sums), and only where the denoiser can run.
fn check_denoise(opts: &RenderOptions) -> Result<(), ToolError> {
    if opts.passes.active(opts.time.is_some()) {
        return Err(ToolError(
            "--denoise: a render in passes writes a partial image; denoise the merged image \
             with `photon denoise`"
                .to_string(),
        ));
    }
    imageio::denoise::available().map_err(|e| ToolError(format!("--denoise: {e}")))
}

/// `--denoise`: the image denoised, with the guides among the render's data channels
/// (`--denoise` asks for `albedo` and `normal`; one line says which were used).
fn denoise(
    image: &imageio::RgbImage,
    data: &[(String, Vec<f32>)],
) -> Result<imageio::RgbImage, ToolError> {
    let done = super::denoise::denoise_image(image, &super::denoise::views(data), true)
        .map_err(|e| ToolError(format!("--denoise: {e}")))?;
    say!(
        "denoised with {} in {:.2} s (Open Image Denoise; an EXR keeps the noisy beauty as layer {})",
        done.guides,
        done.seconds,
        super::denoise::NOISY
    );
    Ok(done.image)
}

/// Prints what is rendered: the scene, its notes, the accelerator, the film and the settings.
fn banner(opts: &RenderOptions, job: &Job, build_s: f64, threads: usize) {
    let (scene, settings) = (&job.scene, &job.settings);
    say!(
        "scene: {} | {} meshes, {} triangles, {} lights, {} materials | loaded in {:.3} s",
        opts.scene.display(),
        scene.meshes.len(),
        scene.triangle_count(),
        scene.lights.len(),
        scene.materials.len(),
        job.load_seconds
    );
    for note in &scene.notes {
        say!("note: {note}");
    }
    say!(
        "accel: {} build {:.3} s{}",
        opts.backend,
        build_s,
        if opts.robust { " (robust)" } else { "" }
    );
    if let Some(why) = &job.spectral_reason {
        say!("color: spectral, four wavelengths per sample ({why}; --no-spectral renders RGB)");
    } else if let Some(why) = integrator::spectral_auto(opts.integrator, scene) {
        say!("note: RGB rendering; {why}: colours may be several percent off pbrt-v4's (spectral) image here: --spectral renders as it does");
    }
    if settings.crop.is_some() {
        let [x0, x1, y0, y1] = settings.pixel_bounds();
        say!("film: crop window: pixels [{x0}, {x1}) x [{y0}, {y1}) of the image below");
    }
    if settings.imaging_ratio != 1.0 {
        say!(
            "film: imaging ratio {} (exposure time x iso / 100)",
            settings.imaging_ratio
        );
    }
    // In passes the samples are the passes' (see render_passes: "passes: A..B of N spp").
    let spp = match opts.passes.active(opts.time.is_some()) {
        true => format!("passes of {} spp", settings.pass_spp.max(1)),
        false => format!("{} spp", settings.spp),
    };
    say!(
        "render: {}x{}, {spp} ({:?}; file sampler \"{}\"), integrator {:?} (file asks for \"{}\"), max depth {}, {} threads",
        settings.width,
        settings.height,
        settings.pattern,
        scene.sampler.name,
        opts.integrator,
        scene.integrator.name,
        settings.max_depth,
        threads
    );
}

/// What a render stopped by `sig` says (one line): the image of the work it finished (`done`:
/// tiles finished of the total; `None`: the passes of a `--time` render) is saved to fallback
/// files by `writers` (see [`Outputs::keep_elsewhere`]), not to its outputs: a stopped render
/// never replaces an output (the unfinished tiles are black).
fn stopped(
    sig: crate::interrupt::Signal,
    done: Option<(u64, u64)>,
    outputs: &Outputs,
    writers: Vec<super::output::Writer>,
) -> String {
    let what = match done {
        Some((0, _)) => {
            return format!(
                "{} received before any tile was finished: nothing written",
                sig.name()
            )
        }
        Some((n, total)) => format!("the {n} of {total} tiles finished (the others black)"),
        None => "the image of the passes finished".to_string(),
    };
    let shown = &outputs.files[0].shown;
    match outputs.keep_elsewhere(writers) {
        Ok(paths) => {
            let paths: Vec<String> = paths.iter().map(|p| p.display().to_string()).collect();
            format!(
                "{} received: {what} saved to {} instead; -o {} not replaced",
                sig.name(),
                paths.join(" and "),
                shown.display()
            )
        }
        Err(e) => format!("{} received: {what} could not be saved: {e}", sig.name()),
    }
}

/// What a render on the command line reports to: the progress bar and the tile count (kept
/// for the message of a stopped render), and the live preview.
struct Watch {
    /// Tiles done and in all.
    tiles: [AtomicU64; 2],
    display: Option<super::display::Display>,
}

impl integrator::Observer for Watch {
    fn tile_done(&self, done: u64, total: u64) {
        self.tiles[0].fetch_max(done, Relaxed);
        self.tiles[1].store(total, Relaxed);
        crate::progress::set("image tiles", done, total);
    }

    fn tile_pixels(&self, x0: u32, y0: u32, x1: u32, y1: u32, px: &[crate::film::Radiance]) {
        if let Some(d) = &self.display {
            d.tile_pixels(x0, y0, x1, y1, px);
        }
    }

    fn image(
        &self,
        image: &imageio::RgbImage,
        layers: &[(&'static str, imageio::RgbImage)],
        pass: u64,
    ) {
        if let Some(d) = &self.display {
            d.image(image, layers, pass);
        }
    }
}

/// The render-loop accounting of `--stats`. Ray-query and lookup times are summed over worker
/// threads, so they are converted to wall-time shares of the render loop with the thread count.
fn print_stats(out: &crate::integrator::RenderOutput, threads: usize) {
    use std::sync::atomic::Ordering::Relaxed;
    let c = &out.counters;
    let loop_s = (out.seconds - out.photon_seconds - out.map_build_seconds).max(1e-9);
    let thread_s = loop_s * threads.max(1) as f64;
    let ray_s = c.ray_ns.load(Relaxed) as f64 * 1e-9;
    let lookup_s = c.lookup_ns.load(Relaxed) as f64 * 1e-9;
    let shading_s = (thread_s - ray_s - lookup_s).max(0.0);
    let pct = |x: f64| 100.0 * x / thread_s;
    say!(
        "time split: photon tracing {:.3} s, map building {:.3} s, render loop {:.3} s x {} threads = ray queries {:.3} s ({:.1}%), photon lookups {:.3} s ({:.1}%), shading and sampling {:.3} s ({:.1}%)",
        out.photon_seconds,
        out.map_build_seconds,
        loop_s,
        threads,
        ray_s,
        pct(ray_s),
        lookup_s,
        pct(lookup_s),
        shading_s,
        pct(shading_s)
    );
    let beams = c.beams.load(Relaxed);
    if beams > 0 {
        let gathered = c.beam_photons.load(Relaxed);
        say!(
            "beam estimates: {beams} (camera segments and those after delta bounces in scattering media), {:.1} volume photons each, {:.2} us each with the other lookups",
            gathered as f64 / beams as f64,
            lookup_s * 1e6 / beams as f64
        );
    }
    let rays = (c.camera_rays.load(Relaxed)
        + c.secondary_rays.load(Relaxed)
        + c.shadow_rays.load(Relaxed)) as f64;
    // The bidirectional integrators query the backend one ray at a time, untimed.
    let querying = if ray_s > 0.0 {
        format!(
            "{:.2} Mrays/s per thread while querying",
            rays / ray_s / 1e6
        )
    } else {
        "query time not measured by this integrator".to_string()
    };
    say!(
        "ray rate inside the render: {querying}, {:.2} Mrays/s of render-loop wall time",
        rays / loop_s / 1e6
    );
}

/// Parses a duration: seconds as a number, or with a suffix `s`, `m` or `ms`; at most
/// [`crate::limits::MAX_SECONDS`].
pub fn parse_duration(s: &str) -> Result<f64, String> {
    let t = s.trim();
    let (num, scale) = if let Some(v) = t.strip_suffix("ms") {
        (v, 1e-3)
    } else if let Some(v) = t.strip_suffix('s') {
        (v, 1.0)
    } else if let Some(v) = t.strip_suffix('m') {
        (v, 60.0)
    } else {
        (t, 1.0)
    };
    let max = crate::limits::MAX_SECONDS;
    match num.trim().parse::<f64>() {
        Ok(v) if v.is_finite() && v > 0.0 && v * scale <= max => Ok(v * scale),
        _ => Err(format!(
            "expected a positive duration of at most {max} s such as 10s, 2.5 or 1m, got {}",
            crate::scene::clip_for_message(s, 40)
        )),
    }
}

/// Replays of each kind of recorded rays; the fastest gives that kind's raw rate.
const RAW_RUNS: usize = 5;

/// The fastest of [`RAW_RUNS`] replays of `rays` of `kind` through `accel` on this thread, in
/// batches of up to 256 consecutive rays (the chunks the recording keeps): seconds per ray.
fn replay_seconds_per_ray(accel: &Accel, kind: RayKind, rays: &[crate::math::Ray]) -> f64 {
    use crate::accel::recording::CHUNK;
    let mut best = f64::INFINITY;
    for _ in 0..RAW_RUNS {
        let t = Instant::now();
        for batch in rays.chunks(CHUNK) {
            if kind == RayKind::Shadow {
                accel.occluded_batch(kind, batch, &mut [false; CHUNK][..batch.len()]);
            } else {
                accel.intersect_batch(kind, batch, &mut [None; CHUNK][..batch.len()]);
            }
        }
        best = best.min(t.elapsed().as_secs_f64());
    }
    best / rays.len().max(1) as f64
}

/// The raw rate of the same backend on the rays a render casts, outside the render loop: a
/// small render with these settings is recorded (as `photon crosscheck` does, 20,000 rays per
/// kind, see [`crate::integrator::recorded`]); each kind the render loop counts (camera, shadow,
/// and gather + bounce as secondary) is replayed on one thread, and the per-kind costs are
/// weighted by the render's own counts of those kinds (gather and bounce split as the recording
/// saw them), so that the raw rate has the render's mix. Printed next to the rate measured
/// inside the render.
fn print_raw_rate(
    scene: &crate::scene::Scene,
    accel: Accel,
    settings: &RenderSettings,
    out: &crate::integrator::RenderOutput,
    pool: &rayon::ThreadPool,
) {
    use crate::accel::recording::Query;
    use std::sync::atomic::Ordering::Relaxed;
    let recorded =
        pool.install(|| crate::integrator::recorded::record(scene, accel, settings, 20_000, 1));
    let (accel, rec) = match recorded {
        Ok(r) => r,
        Err(e) => {
            say!("raw rate: not measured: {e}");
            return;
        }
    };
    let c = &out.counters;
    let seen = |k| {
        rec.rays
            .sets
            .iter()
            .find(|s| s.kind == k)
            .map_or(0, |s| s.seen) as f64
    };
    let gather_share =
        seen(RayKind::Gather) / (seen(RayKind::Gather) + seen(RayKind::Bounce)).max(1.0);
    let secondary = c.secondary_rays.load(Relaxed) as f64;
    let weights = [
        (
            RayKind::Camera,
            Query::Closest,
            c.camera_rays.load(Relaxed) as f64,
        ),
        (
            RayKind::Shadow,
            Query::Occlusion,
            c.shadow_rays.load(Relaxed) as f64,
        ),
        (RayKind::Gather, Query::Closest, secondary * gather_share),
        (
            RayKind::Bounce,
            Query::Closest,
            secondary * (1.0 - gather_share),
        ),
    ];
    let (mut rays, mut seconds, mut replayed) = (0.0, 0.0, 0);
    for (kind, query, w) in weights {
        let set = rec.rays.get(kind, query);
        if set.is_empty() || w <= 0.0 {
            continue;
        }
        rays += w;
        seconds += w * replay_seconds_per_ray(&accel, kind, set);
        replayed += set.len();
    }
    let raw = rays / seconds.max(1e-12) / 1e6;
    let ray_s = c.ray_ns.load(Relaxed) as f64 * 1e-9;
    if ray_s <= 0.0 {
        say!(
            "raw rate on {replayed} recorded camera/shadow/gather/bounce rays, 1 thread, batches of <= 256, weighted by the render's counts: {raw:.2} Mrays/s (this integrator does not time its queries: no share of raw)"
        );
        return;
    }
    let inside = c.total() as f64 / ray_s / 1e6;
    say!(
        "raw rate on {replayed} recorded camera/shadow/gather/bounce rays, 1 thread, batches of <= 256, weighted by the render's counts: {raw:.2} Mrays/s; inside the render {inside:.2} Mrays/s per thread ({:.0}% of raw)",
        100.0 * inside / raw.max(1e-9)
    );
}
