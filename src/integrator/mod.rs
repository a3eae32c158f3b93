//! Integrators and the render driver: tiles in parallel, deterministic sample streams,
//! per-component images.
//!
//! ```text
//! Integrator "path" "integer maxdepth" [ 5 ]
//! ```
//! Whatever integrator a file names, it is rendered by the one given on the command line
//! (`--integrator`, default the photon mapper); the statistics say which. Each integrator
//! reads its own parameters from a line that names it: the photon mapper's (the table in
//! [`settings`], `progressive`, `alpha`) only under `Integrator "photonmap"`; `maxdepth` and
//! `passspp` under any name; pbrt-v4's other integrators' own parameters are ignored with a
//! note; any other parameter is an error at its location.
//!
//! Tiles go to the per-pixel integrators (`photon_mapper`, `direct`, `path` through
//! [`wavefront`]); the bidirectional ones (`vcm`, `bdpt`, `lighttracer`: [`vcm`]) splat light
//! paths anywhere on the film, so they render the whole image at once and it is cut into the
//! same tiles afterwards.
pub mod aov;
pub mod direct;
pub mod passes;
pub mod path;
pub mod photon_mapper;
pub mod photonmap;
pub mod recorded;
pub mod settings;
pub mod vcm;
pub mod wavefront;

use crate::accel::Accel;
use crate::camera::Camera;
use crate::film::{self, Component, Filter, Radiance};
use crate::imageio::RgbImage;
use crate::light::Lights;
use crate::math::{Ray, Vec2};
use crate::sampling::Pattern;
use crate::sampling::Sampler;
use crate::scene::{Scene, SceneError};
use rayon::prelude::*;
use std::sync::atomic::{AtomicU64, Ordering};
use std::time::Instant;

/// Edge length of a square render tile, in pixels.
pub const TILE: u32 = 16;

/// The integrators `photon render --integrator` can run.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, clap::ValueEnum)]
pub enum IntegratorKind {
    /// Jensen's two-pass photon mapping: direct, specular/glossy, caustic and indirect
    /// (final gathering) components.
    #[default]
    Photonmap,
    /// Direct light by shadow rays (MIS for glossy surfaces) plus recursive specular and
    /// glossy reflection/refraction; no diffuse interreflection.
    Direct,
    /// Reference path tracer: unbiased, next-event estimation with power-heuristic MIS,
    /// Russian roulette after 3 bounces (`direct` and `indirect` components).
    Path,
    /// Vertex connection and merging: bidirectional connections and photon merging weighed
    /// by multiple importance sampling; light subpaths per sample chosen by a pilot
    /// (`--light-paths`).
    Vcm,
    /// Bidirectional path tracing (VCM without merging).
    Bdpt,
    /// Light tracing: light subpaths splatted to the camera alone.
    Lighttracer,
    /// Bidirectional photon mapping: VCM's merging alone.
    Bpm,
}

impl IntegratorKind {
    /// The bidirectional technique of [`vcm`], for the three integrators it runs.
    pub fn technique(self) -> Option<vcm::Technique> {
        match self {
            IntegratorKind::Vcm => Some(vcm::Technique::Vcm),
            IntegratorKind::Bdpt => Some(vcm::Technique::Bdpt),
            IntegratorKind::Lighttracer => Some(vcm::Technique::LightTracer),
            IntegratorKind::Bpm => Some(vcm::Technique::Bpm),
            _ => None,
        }
    }
}

/// Everything a render needs besides the scene.
#[derive(Clone, Debug)]
pub struct RenderSettings {
    pub width: u32,
    pub height: u32,
    pub spp: u32,
    /// Samples per pixel of the whole render when `spp` is one pass's (set by
    /// [`passes::pass_settings`]): texture footprints shrink with the image's samples.
    pub texture_spp: Option<u32>,
    pub seed: u64,
    pub pattern: Pattern,
    /// Maximum number of bounces (pbrt's `maxdepth`).
    pub max_depth: u32,
    /// Shadow rays per shading point.
    pub light_samples: u32,
    /// The photon mapper's settings (read from the file's `Integrator` parameters).
    pub photon: photonmap::PhotonSettings,
    /// Samples per pixel of each pass when rendering in passes (`"integer passspp"`).
    pub pass_spp: u32,
    /// The film's `cropwindow` or `pixelbounds`, or `--cropwindow`/`--pixelbounds` (see
    /// [`film::pixel_bounds`]).
    pub crop: Option<film::Crop>,
    /// pbrt-v4's imaging ratio (`exposure time * iso / 100`): every pixel is scaled by it.
    pub imaging_ratio: f32,
    /// The film's `maxcomponentvalue` (see [`film::clamp_sample`]), after the imaging ratio.
    pub max_component: f32,
    /// The film's `whitebalance` as a matrix on every pixel (see [`film::white_balance`]).
    pub white_balance: Option<crate::math::Mat3>,
    /// The bidirectional integrators' merge radius and schedule.
    pub vcm: vcm::VcmSettings,
    /// The data channels to write beside the image ([`aov`]: `--aov`, `Film "gbuffer"`). A
    /// gbuffer also keeps each pixel's sample variance ([`RenderOutput::variance`]): the
    /// per-pixel integrators then sum each sample apart before adding it in.
    pub aovs: aov::Request,
    /// Render spectrally (`--spectral`, [`crate::spectrum`]): each camera sample at four
    /// wavelengths, as pbrt-v4 renders; only integrators that [`check_spectral`] accepts.
    pub spectral: bool,
}

impl RenderSettings {
    /// Settings from the scene file (`Film`, `Sampler`, `Integrator` parameters); unused
    /// integrator parameters are errors.
    pub fn from_scene(scene: &Scene) -> Result<RenderSettings, SceneError> {
        let mut params = scene.integrator.params.clone();
        let max_depth = params.get_int("maxdepth", 5)?;
        crate::limits::check_range(max_depth, 0, crate::limits::MAX_DEPTH as i32).map_err(|m| {
            SceneError {
                loc: params
                    .loc("maxdepth")
                    .or(scene.integrator.loc.as_ref())
                    .cloned(),
                msg: format!("\"maxdepth\" {m}"),
            }
        })?;
        // Each integrator reads its own parameters: the photon mapper's belong to a file whose
        // Integrator is "photonmap" (whichever one --integrator then renders with).
        let name = &scene.integrator.name;
        let mut photon = if name == "photonmap" {
            photonmap::PhotonSettings::from_params(&mut params)?
        } else {
            let keys = settings::SETTINGS.iter().map(|r| r.key);
            for key in keys.chain(["progressive", "alpha"]) {
                if let Some(p) = params.peek(key) {
                    return Err(p.err(format!(
                        "\"{key}\" is a parameter of Integrator \"photonmap\", not of \"{name}\""
                    )));
                }
            }
            photonmap::PhotonSettings::default()
        };
        photon.follow_depth(max_depth as u32);
        let pass_spp = params.get_int("passspp", 4)?;
        if pass_spp < 1 {
            return Err(SceneError {
                loc: params.loc("passspp").cloned(),
                msg: format!("\"passspp\" must be >= 1, got {pass_spp}"),
            });
        }
        params.check_unused()?;
        Ok(RenderSettings {
            width: scene.film.xres,
            height: scene.film.yres,
            spp: scene.sampler.pixel_samples.max(1),
            texture_spp: None,
            seed: 0,
            pattern: Pattern::Stratified,
            max_depth: max_depth as u32,
            light_samples: 1,
            photon,
            pass_spp: pass_spp as u32,
            crop: scene.film.crop,
            imaging_ratio: scene.film.imaging_ratio(scene.camera.exposure_time),
            max_component: scene.film.max_component,
            white_balance: (scene.film.white_balance != 0.0)
                .then(|| film::white_balance(scene.film.white_balance)),
            vcm: vcm::VcmSettings::default(),
            aovs: aov::Request {
                aovs: Vec::new(),
                gbuffer: scene.film.gbuffer,
            },
            spectral: false,
        })
    }

    /// A sample's colour as the film stores it: the imaging ratio and white balance applied.
    pub fn film_rgb(&self, v: crate::math::Vec3) -> crate::math::Vec3 {
        let v = v * self.imaging_ratio;
        self.white_balance.map_or(v, |m| m * v)
    }

    /// The pixels `[x0, x1, y0, y1]` a render computes (the crop window's, at least one).
    /// The image one texture-footprint pixel belongs to: this render's resolution and
    /// samples per pixel (pbrt-v4 scales differentials by `max(1/8, 1/sqrt(spp))`).
    pub fn footprint(&self) -> crate::camera::Footprint {
        crate::camera::Footprint {
            res: (self.width, self.height),
            spp: self.texture_spp.unwrap_or(self.spp),
        }
    }

    pub fn pixel_bounds(&self) -> [u32; 4] {
        let [x0, x1, y0, y1] = film::pixel_bounds(self.crop, self.width, self.height);
        // A crop window that holds a pixel at the file's resolution may hold none at `--res`.
        let (x0, y0) = (x0.min(self.width - 1), y0.min(self.height - 1));
        [x0, x1.max(x0 + 1), y0, y1.max(y0 + 1)]
    }

    /// The size of the image a render writes: the crop window's.
    pub fn image_size(&self) -> (u32, u32) {
        let [x0, x1, y0, y1] = self.pixel_bounds();
        (x1 - x0, y1 - y0)
    }
}

impl RenderOutput {
    /// No image, no counts (to add passes into).
    pub fn empty() -> RenderOutput {
        RenderOutput {
            image: RgbImage::new(0, 0),
            components: Vec::new(),
            seconds: 0.0,
            photon_seconds: 0.0,
            map_build_seconds: 0.0,
            photons_emitted: 0,
            counters: Counters::default(),
            notes: Vec::new(),
            variance: None,
            spp: 0,
        }
    }

    /// Adds `other`'s counters, pass-1 times and photon counts to these.
    pub fn add_counts(&mut self, other: &RenderOutput) {
        self.counters.add(&other.counters);
        self.photon_seconds += other.photon_seconds;
        self.map_build_seconds += other.map_build_seconds;
        self.photons_emitted += other.photons_emitted;
        if self.notes.is_empty() {
            self.notes = other.notes.clone();
        }
    }
}

/// Ray and time counters of one render.
#[derive(Debug, Default)]
pub struct Counters {
    pub camera_rays: AtomicU64,
    pub secondary_rays: AtomicU64,
    pub shadow_rays: AtomicU64,
    /// Thread-nanoseconds spent inside batched ray queries of the render loop.
    pub ray_ns: AtomicU64,
    /// Thread-nanoseconds spent in photon-map lookups (caustic estimates, gather lookups,
    /// beam estimates).
    pub lookup_ns: AtomicU64,
    /// Beam estimates of the volume photon map, and the photons they gathered.
    pub beams: AtomicU64,
    pub beam_photons: AtomicU64,
}

/// Adds the time since `start` to `counter` (thread-nanoseconds).
#[inline]
pub fn charge(counter: &AtomicU64, start: Instant) {
    counter.fetch_add(start.elapsed().as_nanos() as u64, Ordering::Relaxed);
}

impl Counters {
    /// Adds `other`'s counts to these.
    pub fn add(&self, other: &Counters) {
        for (x, y) in [
            (&self.camera_rays, &other.camera_rays),
            (&self.secondary_rays, &other.secondary_rays),
            (&self.shadow_rays, &other.shadow_rays),
            (&self.ray_ns, &other.ray_ns),
            (&self.lookup_ns, &other.lookup_ns),
            (&self.beams, &other.beams),
            (&self.beam_photons, &other.beam_photons),
        ] {
            x.fetch_add(y.load(Ordering::Relaxed), Ordering::Relaxed);
        }
    }

    pub fn total(&self) -> u64 {
        self.camera_rays.load(Ordering::Relaxed)
            + self.secondary_rays.load(Ordering::Relaxed)
            + self.shadow_rays.load(Ordering::Relaxed)
    }
}

/// The rendered images and what it took.
pub struct RenderOutput {
    pub image: RgbImage,
    /// `(name, image)` per component; they sum to `image`.
    pub components: Vec<(&'static str, RgbImage)>,
    pub seconds: f64,
    /// Seconds of pass 1: photon tracing, and building the maps and the irradiance cache.
    pub photon_seconds: f64,
    pub map_build_seconds: f64,
    /// Photons pass 1 emitted (both maps).
    pub photons_emitted: u64,
    pub counters: Counters,
    /// Statistics lines of the integrator (photon counts, timings, skipped components).
    pub notes: Vec<String>,
    /// Per pixel of `image`, the sample variance of R, G, B and the variance over the mean
    /// (pbrt-v4's `Variance` and `RelativeVariance`), when a gbuffer ([`RenderSettings::aovs`])
    /// asked for it and the integrator renders per pixel over one sample count.
    pub variance: Option<Vec<[f32; 6]>>,
    /// Samples per pixel of the image.
    pub spp: u32,
}

/// The shared, read-only state every tile renders from.
pub struct RenderContext<'a> {
    pub scene: &'a Scene,
    pub accel: &'a Accel,
    pub lights: &'a Lights,
    pub camera: Camera,
    pub filter: Filter,
    pub settings: RenderSettings,
    pub counters: Counters,
    /// Pass 1's maps when rendering with the photon mapper.
    pub photons: Option<&'a photonmap::PhotonPass>,
    /// Per-pixel sample variances, filled tile by tile for a gbuffer ([`RenderSettings::aovs`]).
    pub variance: Option<std::sync::Mutex<Vec<[f32; 6]>>>,
}

impl<'a> RenderContext<'a> {
    /// A context for `settings` without photon maps or a variance buffer (pilots, AOVs).
    pub fn new(
        scene: &'a Scene,
        accel: &'a Accel,
        lights: &'a Lights,
        settings: RenderSettings,
    ) -> Self {
        RenderContext {
            scene,
            accel,
            lights,
            camera: Camera::new(&scene.camera, settings.width, settings.height),
            filter: Filter::new(&scene.filter),
            settings,
            counters: Counters::default(),
            photons: None,
            variance: None,
        }
    }
}

/// Whether `kind` renders `scene` right: the path tracer and the direct integrator track the
/// medium each ray is in (the photon mapper renders such scenes with the path tracer, adding
/// its volume map's beam estimates), so scenes whose media need that
/// ([`Scene::media_need_tracking`]) are refused by the bidirectional ones with the file
/// location of the first reason.
pub fn check_scene(kind: IntegratorKind, scene: &Scene) -> Result<(), String> {
    match (&scene.media_need_tracking, kind) {
        (None, _)
        | (Some(_), IntegratorKind::Path | IntegratorKind::Photonmap | IntegratorKind::Direct) => {
            Ok(())
        }
        (Some(why), _) => Err(format!(
            "{why}: only --integrator path, direct and photonmap render such media yet (--integrator \
             {} handles absorbing media closed by the surfaces that name them)",
            clap::ValueEnum::to_possible_value(&kind)
                .map_or("?".into(), |v| v.get_name().to_string())
        )),
    }
}

/// How a render picks RGB or spectral rendering (`--spectral[=on|off|auto]`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, clap::ValueEnum)]
pub enum Spectral {
    /// Spectral when saturated colours scatter enough light twice and the integrator can
    /// (see `spectral_auto`).
    Auto,
    /// Spectral (an error for integrators that render RGB only, and with media).
    #[value(alias = "true")]
    On,
    /// RGB.
    #[default]
    #[value(alias = "false")]
    Off,
}

/// Why `Auto` renders `scene` spectrally with `kind`, or `None` for RGB: spectrally when
/// enough of the scene's light may be scattered twice by a saturated colour
/// ([`coloured_share`] above [`SPECTRAL_AUTO_SHARE`]: two such factors along a path multiply
/// differently in RGB, by several percent), the integrator renders spectrally and the scene
/// has no media. Otherwise RGB gives (nearly) the same image without the colour noise of
/// sampled wavelengths (at 30 s, spectral path tracing's relMSE against pbrt-v4 is 2-3.6x
/// RGB's on teapot, car, car2, spaceship, house, lamp and veach-mis).
pub fn spectral_auto(kind: IntegratorKind, scene: &Scene) -> Option<String> {
    if !matches!(
        kind,
        IntegratorKind::Path | IntegratorKind::Photonmap | IntegratorKind::Direct
    ) || !scene.media.is_empty()
    {
        return None;
    }
    let share = coloured_share(scene);
    (share > SPECTRAL_AUTO_SHARE).then(|| {
        format!("{share:.4} of the surface's light is coloured twice, above {SPECTRAL_AUTO_SHARE}")
    })
}

/// [`coloured_share`] above which `--spectral=auto` renders spectrally. Of ten Bitterli
/// scenes, cornell-box (0.0112) and coffee (0.0085), whose RGB renders are 2.5-11% off
/// pbrt-v4's in places, are above; so is material-testball (0.0121: a convex ball does not
/// light itself, and its RGB render agrees with pbrt-v4's while the spectral one is 2.6x
/// noisier), the rule's known false positive; teapot (0.0003), house (0.0004) and the others
/// are below. The measure knows areas, not visibility.
pub const SPECTRAL_AUTO_SHARE: f32 = 0.004;

/// How much RGB rendering of `scene` may differ from spectral: over the surfaces that emit
/// nothing, the area-weighted mean of `max(a)^2` times [`crate::spectrum::two_bounce_discrepancy`]
/// of their coloured reflectance `a` (mean over its texture) under the most powerful area
/// light's colour (white without one: sky, sun and point lights count as white).
pub fn coloured_share(scene: &Scene) -> f32 {
    let light = (scene.lights.iter())
        .filter_map(|l| match l {
            crate::light::Light::Area { l, .. } => Some(*l),
            _ => None,
        })
        .max_by(|a, b| a.element_sum().total_cmp(&b.element_sum()))
        .unwrap_or(crate::math::Vec3::ONE);
    let mut memo: Vec<Option<f32>> = vec![None; scene.materials.len()];
    let (mut total, mut coloured) = (0.0f64, 0.0f64);
    for mesh in scene.meshes.iter().filter(|m| m.area_light.is_none()) {
        let area: f64 = (0..mesh.indices.len() as u32)
            .map(|p| mesh.area_f64(p))
            .sum();
        if !area.is_finite() {
            continue;
        }
        total += area;
        let m = mesh.material as usize;
        let w = *memo[m].get_or_insert_with(|| {
            scene.materials[m].kind.coloured_albedo().map_or(0.0, |a| {
                let a = a.clamp(crate::math::Vec3::ZERO, crate::math::Vec3::ONE);
                a.max_element().powi(2) * crate::spectrum::two_bounce_discrepancy(a, light)
            })
        });
        coloured += area * w as f64;
    }
    if total > 0.0 {
        (coloured / total) as f32
    } else {
        0.0
    }
}

/// Whether `kind` renders spectrally: with `settings.spectral`, the path tracer, the direct
/// integrator and the photon mapper's camera side do (in scenes without media: their
/// coefficients are still RGB); the others are refused.
pub fn check_spectral(
    kind: IntegratorKind,
    settings: &RenderSettings,
    scene: &Scene,
) -> Result<(), String> {
    if !settings.spectral {
        return Ok(());
    }
    if !matches!(
        kind,
        IntegratorKind::Path | IntegratorKind::Photonmap | IntegratorKind::Direct
    ) {
        return Err(format!(
            "--spectral: only --integrator path, photonmap and direct render spectrally yet, not {}",
            clap::ValueEnum::to_possible_value(&kind)
                .map_or("?".into(), |v| v.get_name().to_string())
        ));
    }
    if !scene.media.is_empty() {
        return Err("--spectral: scenes with media render in RGB only yet".into());
    }
    Ok(())
}

/// Pass 1 for `kind` (photon maps for the photon mapper, nothing otherwise).
pub fn prepare(
    scene: &Scene,
    accel: &Accel,
    settings: &RenderSettings,
    kind: IntegratorKind,
) -> Option<photonmap::PhotonPass> {
    (kind == IntegratorKind::Photonmap).then(|| {
        let mut ps = settings.photon.clone();
        ps.trace.seed = settings.seed;
        ps.trace.pattern = settings.pattern;
        ps.trace.footprint = Some(settings.footprint());
        photonmap::prepare(scene, accel, scene.emitters(), &ps)
    })
}

/// The photons pass 1 of `settings` would store per photon emitted, or the light vertices the
/// bidirectional integrators keep per light subpath, measured by a pilot trace (`None` for
/// the other integrators). Runs on the current rayon pool.
pub fn pilot(
    scene: &Scene,
    accel: &Accel,
    settings: &RenderSettings,
    kind: IntegratorKind,
) -> Option<crate::photon::trace::Landings> {
    if let Some(t) = kind.technique() {
        return Some(crate::photon::trace::Landings {
            subpath: vcm::pilot(scene, accel, settings, t),
            ..Default::default()
        });
    }
    (kind == IntegratorKind::Photonmap).then(|| {
        let mut t = settings.photon.trace.clone();
        (t.seed, t.pattern) = (settings.seed, settings.pattern);
        t.footprint = Some(settings.footprint());
        let (global, caustic, _) = photonmap::needed_maps(scene, t.receiver_alpha);
        t.global_photons *= u64::from(global);
        t.caustic_photons *= u64::from(caustic);
        crate::photon::trace::pilot(scene, accel, &scene.emitters(), &t)
    })
}

/// What a render reports as it goes, for progress displays and live previews. Every method
/// has a default that ignores the report; a closure `Fn(done, total)` is an observer of
/// finished tiles only.
pub trait Observer: Sync {
    /// `done` of `total` tiles finished (called from worker threads, in any order).
    fn tile_done(&self, _done: u64, _total: u64) {}
    /// The final pixels of the tile `[x0, x1) x [y0, y1)` (image coordinates of the crop
    /// window's image, row-major, imaging ratio and white balance applied), as it finishes.
    fn tile_pixels(&self, _x0: u32, _y0: u32, _x1: u32, _y1: u32, _px: &[Radiance]) {}
    /// The whole image so far and its component layers, after a pass is added into it
    /// (renders in passes; `pass` counts from 0).
    fn image(&self, _image: &RgbImage, _layers: &[(&'static str, RgbImage)], _pass: u64) {}
}

impl<F: Fn(u64, u64) + Sync> Observer for F {
    fn tile_done(&self, done: u64, total: u64) {
        self(done, total)
    }
}

/// The observer of nothing.
pub const UNOBSERVED: &dyn Observer = &|_: u64, _: u64| {};

/// Renders `scene` with `kind`, reporting finished tiles to `progress`. Runs on the current
/// rayon pool.
pub fn render(
    scene: &Scene,
    accel: &Accel,
    settings: &RenderSettings,
    kind: IntegratorKind,
    progress: &dyn Observer,
) -> RenderOutput {
    let start = Instant::now();
    let photons = prepare(scene, accel, settings, kind);
    let mut out = render_prepared(scene, accel, settings, kind, photons.as_ref(), progress);
    out.seconds = start.elapsed().as_secs_f64();
    out
}

/// Pass 2 (the whole render for integrators without a pass 1) over an already prepared pass 1;
/// `seconds` counts pass 1's time too.
pub fn render_prepared(
    scene: &Scene,
    accel: &Accel,
    settings: &RenderSettings,
    kind: IntegratorKind,
    photons: Option<&photonmap::PhotonPass>,
    progress: &dyn Observer,
) -> RenderOutput {
    let start = Instant::now();
    // Pass 1's lights when there was one (built once per render).
    let own;
    let lights = match photons {
        Some(p) => &p.lights,
        None => {
            own = scene.emitters();
            &own
        }
    };
    let mut notes = photons.map(photonmap::describe).unwrap_or_default();
    let (photon_seconds, map_build_seconds) = photons.map_or((0.0, 0.0), |p| {
        let (st, vs) = (&p.maps.stats, &p.volume_stats);
        (
            st.trace_seconds + vs.seconds,
            st.build_seconds + p.cache_seconds + vs.build_seconds,
        )
    });
    if settings.spectral {
        // Fitted here, once, with the whole pool (not inside the first tile that needs it).
        crate::spectrum::fit_table();
    }
    let ctx = RenderContext {
        photons,
        variance: (settings.aovs.gbuffer.is_some() && kind.technique().is_none()).then(|| {
            let (w, h) = settings.image_size();
            std::sync::Mutex::new(vec![[0.0; 6]; w as usize * h as usize])
        }),
        ..RenderContext::new(scene, accel, lights, settings.clone())
    };
    let [bx0, w, by0, h] = settings.pixel_bounds();
    let tiles: Vec<(u32, u32)> = (by0..h)
        .step_by(TILE as usize)
        .flat_map(|y| (bx0..w).step_by(TILE as usize).map(move |x| (x, y)))
        .collect();
    let total = tiles.len() as u64;
    let done = AtomicU64::new(0);
    let rendered: Vec<((u32, u32), Vec<Radiance>)> = if let Some(t) = kind.technique() {
        // One image from the bidirectional integrator, cut into tiles for the assembly below.
        let out = vcm::render(&ctx, t, progress);
        notes.extend(out.notes);
        let mut px = out.pixels;
        if settings.imaging_ratio != 1.0 {
            px.iter_mut().for_each(|r| *r = *r * settings.imaging_ratio);
        }
        if let Some(m) = settings.white_balance {
            px.iter_mut().for_each(|r| *r = r.map(|v| m * v));
        }
        let wu = (w - bx0) as usize;
        tiles
            .iter()
            .map(|&(x0, y0)| {
                let (x1, y1) = ((x0 + TILE).min(w), (y0 + TILE).min(h));
                let tile: Vec<Radiance> = tile_pixels(x0, y0, x1, y1)
                    .map(|(x, y)| px[(y - by0) as usize * wu + (x - bx0) as usize])
                    .collect();
                progress.tile_pixels(x0 - bx0, y0 - by0, x1 - bx0, y1 - by0, &tile);
                ((x0, y0), tile)
            })
            .collect()
    } else {
        tiles
            .par_iter()
            .map(|&(x0, y0)| {
                let x1 = (x0 + TILE).min(w);
                let y1 = (y0 + TILE).min(h);
                if crate::interrupt::requested().is_some() {
                    // Stopping: the caller discards this render.
                    let n = ((x1 - x0) * (y1 - y0)) as usize;
                    return ((x0, y0), vec![Radiance::default(); n]);
                }
                let mut px = match kind {
                    IntegratorKind::Photonmap if scene.media_need_tracking.is_some() => {
                        path::render_tile(&ctx, x0, y0, x1, y1)
                    }
                    IntegratorKind::Photonmap if ctx.photons.is_some() => {
                        photon_mapper::render_tile(&ctx, x0, y0, x1, y1)
                    }
                    IntegratorKind::Direct | IntegratorKind::Photonmap => {
                        direct::render_tile(&ctx, x0, y0, x1, y1)
                    }
                    IntegratorKind::Path => path::render_tile(&ctx, x0, y0, x1, y1),
                    IntegratorKind::Vcm
                    | IntegratorKind::Bdpt
                    | IntegratorKind::Lighttracer
                    | IntegratorKind::Bpm => {
                        unreachable!("rendered by vcm::render above")
                    }
                };
                // The film's imaging ratio and white balance.
                if settings.imaging_ratio != 1.0 {
                    px.iter_mut().for_each(|r| *r = *r * settings.imaging_ratio);
                }
                if let Some(m) = settings.white_balance {
                    px.iter_mut().for_each(|r| *r = r.map(|v| m * v));
                }
                progress.tile_pixels(x0 - bx0, y0 - by0, x1 - bx0, y1 - by0, &px);
                progress.tile_done(done.fetch_add(1, Ordering::Relaxed) + 1, total);
                ((x0, y0), px)
            })
            .collect()
    };

    // Assemble the tiles into the combined image and one image per component (the pixels of
    // the crop window).
    let (wu, hu) = ((w - bx0) as usize, (h - by0) as usize);
    let mut parts: [RgbImage; 4] = std::array::from_fn(|_| RgbImage::new(wu, hu));
    let mut image = RgbImage::new(wu, hu);
    for ((x0, y0), px) in rendered {
        let tw = ((x0 + TILE).min(w) - x0) as usize;
        for (i, r) in px.iter().enumerate() {
            let (x, y) = ((x0 - bx0) as usize + i % tw, (y0 - by0) as usize + i / tw);
            let k = y * wu + x;
            for (part, v) in parts.iter_mut().zip(r.0) {
                part.pixels[k] = v.to_array();
            }
            image.pixels[k] = r.total().to_array();
        }
    }
    RenderOutput {
        image,
        components: Component::NAMES.into_iter().zip(parts).collect(),
        seconds: start.elapsed().as_secs_f64() + photon_seconds + map_build_seconds,
        photon_seconds,
        map_build_seconds,
        photons_emitted: photons.map_or(0, |p| {
            p.maps.stats.global_emitted + p.maps.stats.caustic_emitted
        }),
        counters: ctx.counters,
        notes,
        variance: ctx
            .variance
            .map(|v| v.into_inner().unwrap_or_else(|e| e.into_inner())),
        spp: settings.spp,
    }
}

/// The data channels `settings.aovs` asks for ([`aov`]), in a pass of their own over the
/// render's pixels, plus a gbuffer's variance channels from `out` (the beauty render). Runs
/// on the current rayon pool.
pub fn render_aovs(
    scene: &Scene,
    accel: &Accel,
    settings: &RenderSettings,
    out: &RenderOutput,
) -> aov::Channels {
    let lights = scene.emitters();
    let ctx = RenderContext::new(scene, accel, &lights, settings.clone());
    let mut channels = aov::render(&ctx, &settings.aovs);
    if let (Some(_), Some(v)) = (settings.aovs.gbuffer, &out.variance) {
        let names = [
            "Variance.R",
            "Variance.G",
            "Variance.B",
            "RelativeVariance.R",
            "RelativeVariance.G",
            "RelativeVariance.B",
        ];
        for (c, name) in names.iter().enumerate() {
            channels.push((name.to_string(), v.iter().map(|p| p[c]).collect()));
        }
    }
    channels
}

/// The sample dimensions of a thin lens's 2D sample: far above every dimension the
/// integrators use (they start at [`wavefront::CAMERA_DIMS`] and add a few per bounce), so a
/// lens changes no other sample and a scene without one draws exactly what it drew before.
pub const LENS_DIM: u32 = 1 << 31;

/// The camera ray through pixel `(x, y)` for sample index `sample`, and the pixel's sample
/// stream positioned after the two dimensions the pixel filter used.
pub fn camera_sample(ctx: &RenderContext, x: u32, y: u32, sample: u32) -> (Ray, Sampler) {
    let s = &ctx.settings;
    let pixel_id = y as u64 * s.width as u64 + x as u64;
    let mut sampler = Sampler::new(s.pattern, s.seed, pixel_id, sample, s.spp);
    let offset = ctx.filter.sample(sampler.next_2d());
    let p = Vec2::new(x as f32 + 0.5, y as f32 + 0.5) + offset;
    let ray = if ctx.camera.has_lens() {
        let mut lens = sampler.clone();
        lens.set_dimension(LENS_DIM);
        ctx.camera.generate_ray_lens(p, lens.next_2d())
    } else {
        ctx.camera.generate_ray(p)
    };
    (ray, sampler)
}

/// Pixels of a tile in row-major order: `(x, y)` for `x0..x1`, `y0..y1`.
pub fn tile_pixels(x0: u32, y0: u32, x1: u32, y1: u32) -> impl Iterator<Item = (u32, u32)> {
    (y0..y1).flat_map(move |y| (x0..x1).map(move |x| (x, y)))
}

/// Renders passes of increasing sample counts over one pass 1 until `budget_s` seconds (pass 1
/// included) are spent, averaging them by sample count. Pass `k` uses seed `seed + k`, so the
/// result is deterministic for a given sequence of pass sizes (which depends on timing).
/// Returns the image and the total samples per pixel. `observer` sees the image after each
/// pass.
pub fn render_for_time(
    scene: &Scene,
    accel: &Accel,
    settings: &RenderSettings,
    kind: IntegratorKind,
    budget_s: f64,
    observer: &dyn Observer,
) -> (RenderOutput, u32) {
    if kind == IntegratorKind::Photonmap && settings.photon.progressive {
        return passes::render_for_time(scene, accel, settings, kind, budget_s, observer);
    }
    let start = Instant::now();
    let (fitted, fit_note) = fit_photons_to_budget(scene, accel, settings, kind, budget_s);
    let settings = &fitted;
    let photons = prepare(scene, accel, settings, kind);
    let mut s = settings.clone();
    s.spp = 1;
    let mut total: Option<RenderOutput> = None;
    let mut spp_done = 0u32;
    let mut pass = 0u64;
    let mut per_spp;
    loop {
        let t = Instant::now();
        s.seed = settings.seed.wrapping_add(pass);
        s.vcm.first = spp_done;
        let out = render_prepared(scene, accel, &s, kind, photons.as_ref(), UNOBSERVED);
        let stopping = crate::interrupt::requested().is_some();
        if stopping && total.is_some() {
            break; // cut short by a signal: not added
        }
        // The latest pass's rate: the smallest one seen undercounts when the machine gets
        // busier (a 30 s budget took 60 s on a loaded machine).
        per_spp = t.elapsed().as_secs_f64() / s.spp as f64;
        total = Some(match total {
            None => out,
            Some(acc) => merge(acc, spp_done, out, s.spp),
        });
        if let Some(t) = &total {
            observer.image(&t.image, &t.components, pass);
        }
        spp_done += s.spp;
        pass += 1;
        let left = budget_s - start.elapsed().as_secs_f64();
        if left < per_spp || stopping {
            break;
        }
        // Fill most of the remaining time, growing at most 4x per pass.
        s.spp = ((left * 0.9 / per_spp) as u32).clamp(1, 4 * spp_done);
    }
    let mut out = total.expect("at least one pass");
    out.seconds = start.elapsed().as_secs_f64();
    out.notes.extend(fit_note);
    (out, spp_done)
}

/// Photon work (pass 1: tracing, kd-trees, irradiance cache) of a fixed-map render for a time
/// budget is kept to at most this share of the budget.
pub const BUDGET_PHOTON_SHARE: f64 = 0.5;

/// A pilot pass 1 traces this fraction of the photons (at least [`PILOT_MIN_PHOTONS`]) to
/// measure their cost before a render for a time budget.
pub const PILOT_FRACTION: u64 = 16;
pub const PILOT_MIN_PHOTONS: u64 = 5_000;

/// The photon mapper's settings for a render of `budget_s` seconds: the photon counts of
/// `settings`, scaled down (global, caustic and volume alike) when a pilot pass 1 of
/// 1/[`PILOT_FRACTION`] of them predicts (linearly) that pass 1 would take more than
/// [`BUDGET_PHOTON_SHARE`] of the time left after the pilot; a note says so. Other
/// integrators and small counts are returned unchanged. Without this a budget scaled photon
/// count could take longer than the budget by itself (`converge`'s `photonmap-photons4x` ran
/// ~2x over).
fn fit_photons_to_budget(
    scene: &Scene,
    accel: &Accel,
    settings: &RenderSettings,
    kind: IntegratorKind,
    budget_s: f64,
) -> (RenderSettings, Option<String>) {
    let start = Instant::now();
    let t = &settings.photon.trace;
    let counts = [
        t.global_photons,
        t.caustic_photons,
        settings.photon.volume_photons,
    ];
    let total: u64 = counts.iter().sum();
    if kind != IntegratorKind::Photonmap || total < PILOT_FRACTION * PILOT_MIN_PHOTONS {
        return (settings.clone(), None);
    }
    let scaled = |f: f64| {
        let mut s = settings.clone();
        let c = counts.map(|n| (n as f64 * f).round() as u64);
        s.photon.trace.global_photons = c[0];
        s.photon.trace.caustic_photons = c[1];
        s.photon.volume_photons = c[2];
        s
    };
    let f = 1.0 / PILOT_FRACTION as f64;
    drop(prepare(scene, accel, &scaled(f), kind));
    let pilot = start.elapsed().as_secs_f64();
    let predicted = pilot / f;
    let allowed = BUDGET_PHOTON_SHARE * (budget_s - pilot).max(0.0);
    if predicted <= allowed {
        return (settings.clone(), None);
    }
    let keep = (allowed / predicted).max(f);
    let s = scaled(keep);
    let note = format!(
        "time budget: photons scaled to {:.1}% ({} + {} emitted) so that pass 1 (predicted {:.2} s at the full count by a {:.3} s pilot) takes at most {:.0}% of the {budget_s} s",
        100.0 * keep,
        s.photon.trace.global_photons,
        s.photon.trace.caustic_photons,
        predicted,
        pilot,
        100.0 * BUDGET_PHOTON_SHARE
    );
    (s, Some(note))
}

/// Averages two renders by their sample counts.
fn merge(a: RenderOutput, na: u32, b: RenderOutput, nb: u32) -> RenderOutput {
    let (wa, wb) = (na as f32 / (na + nb) as f32, nb as f32 / (na + nb) as f32);
    let mix = |x: &RgbImage, y: &RgbImage| RgbImage {
        width: x.width,
        height: x.height,
        pixels: x
            .pixels
            .iter()
            .zip(&y.pixels)
            .map(|(p, q)| std::array::from_fn(|c| p[c] * wa + q[c] * wb))
            .collect(),
    };
    a.counters.add(&b.counters);
    RenderOutput {
        image: mix(&a.image, &b.image),
        components: a
            .components
            .iter()
            .zip(&b.components)
            .map(|((n, x), (_, y))| (*n, mix(x, y)))
            .collect(),
        seconds: a.seconds + b.seconds,
        photon_seconds: a.photon_seconds,
        map_build_seconds: a.map_build_seconds,
        photons_emitted: a.photons_emitted,
        counters: a.counters,
        notes: a.notes,
        // Variances of renders of different sample counts do not combine into the mean's.
        variance: None,
        spp: na + nb,
    }
}
