//! One render, set up the same way by every tool and test: load the scene (within a memory
//! budget), apply the command line's overrides to the file's settings, check the memory
//! estimate, build the accelerator, measure the photon maps' size with a pilot trace and check
//! again, render.
//!
//! `render`, `converge`, `crosscheck`, `bench` and the integration tests start from
//! [`Job::load`] (or [`Job::new`] for a scene built in memory); the order of the steps, the
//! override rules and the thread pool live only here.
use super::ToolError;
use crate::accel::{Accel, AccelOptions, BackendKind};
use crate::integrator::settings::PhotonOverrides;
use crate::integrator::{self, IntegratorKind, RenderOutput, RenderSettings};
use crate::limits::Budget;
use crate::memory::{Estimate, FromCli};
use crate::photon::trace::Landings;
use crate::sampling::Pattern;
use crate::scene::{loader, Scene};
use std::borrow::Cow;
use std::path::Path;
use std::time::Instant;

/// What the command line changes in the file's settings (`None`: the file's value).
#[derive(Clone, Debug, Default)]
pub struct Overrides {
    /// Image size `(width, height)`.
    pub res: Option<(u32, u32)>,
    /// Samples per pixel.
    pub spp: Option<u32>,
    /// Maximum bounces (the photon mapper's photon bounces follow it unless given).
    pub max_depth: Option<u32>,
    /// Seed of every sample stream.
    pub seed: u64,
    /// Stratification of each pixel's samples.
    pub pattern: Pattern,
    /// Shadow rays per shading point (`None`: 1).
    pub light_samples: Option<u32>,
    /// The photon mapper's settings given as flags.
    pub photon: PhotonOverrides,
    /// The progressive schedule's alpha (photon mapper and VCM).
    pub alpha: Option<f32>,
    /// VCM's initial merge radius.
    pub merge_radius: Option<crate::integrator::vcm::MergeRadius>,
    /// VCM merges at every non-delta vertex.
    pub all_merges: bool,
    /// VCM's and bdpt's light subpaths per pixel (`None`: chosen by a pilot).
    pub light_paths: Option<f32>,
    /// Progressive photon mapping (also switched on by the file).
    pub progressive: bool,
    /// Samples per pixel of each pass.
    pub pass_spp: Option<u32>,
    /// `--cropwindow` / `--pixelbounds` (instead of the film's).
    pub crop: Option<crate::film::Crop>,
    /// pbrt-v4's `--quick`: a quarter of the resolution on each axis and one sample per pixel,
    /// applied after `res` and `spp`.
    pub quick: bool,
    /// `--aov`: data channels beside the image (added to the film's gbuffer, if any).
    pub aovs: Vec<crate::integrator::aov::Aov>,
    /// `--spectral`: render at sampled wavelengths (`None`: RGB).
    pub spectral: Option<crate::integrator::Spectral>,
}

impl Overrides {
    /// What the memory model must take from the command line rather than the file.
    pub fn from_cli(&self) -> FromCli {
        FromCli {
            res: self.res.is_some(),
            photons: self.photon.global_photons.is_some() || self.photon.caustic_photons.is_some(),
        }
    }
}

/// A scene (loaded, or borrowed from the caller) with its settings and how it is to be
/// rendered.
pub struct Job<'a> {
    pub scene: Cow<'a, Scene>,
    pub settings: RenderSettings,
    pub integrator: IntegratorKind,
    pub backend: BackendKind,
    pub accel: AccelOptions,
    /// Worker threads (0 = all cores).
    pub threads: usize,
    /// Wall time of loading the scene (0 for [`Job::new`]).
    pub load_seconds: f64,
    /// Photons stored per photon emitted, once [`Job::pilot`] measured them.
    pub landings: Option<Landings>,
    /// A live preview will watch the render (`--display-server`): its frame is in the memory
    /// check.
    pub preview: bool,
    /// RGB or spectral, as asked; [`Job::resolve_spectral`] settles `Auto` into the settings.
    pub spectral: crate::integrator::Spectral,
    /// Why the render is spectral, once [`Job::resolve_spectral`] decided it is.
    pub spectral_reason: Option<String>,
}

impl<'a> Job<'a> {
    /// Loads `path` within `max_memory` bytes (default: [`crate::limits::default_budget`]) and
    /// reads its settings; photon mapping on Embree, all cores.
    pub fn load(path: &Path, max_memory: Option<u64>) -> Result<Job<'static>, ToolError> {
        let t0 = Instant::now();
        let max = max_memory.unwrap_or_else(|| crate::limits::default_budget().bytes);
        let scene = loader::load_within(path, max)?;
        let mut job = Job::from(Cow::Owned(scene))?;
        job.load_seconds = t0.elapsed().as_secs_f64();
        Ok(job)
    }

    /// A job for a scene already in memory, with the file's settings.
    pub fn new(scene: Scene) -> Result<Job<'static>, ToolError> {
        Job::from(Cow::Owned(scene))
    }

    /// A job for the caller's scene (tests keep theirs), with the file's settings.
    pub fn borrowing(scene: &'a Scene) -> Result<Job<'a>, ToolError> {
        Job::from(Cow::Borrowed(scene))
    }

    fn from(scene: Cow<'a, Scene>) -> Result<Job<'a>, ToolError> {
        let settings = RenderSettings::from_scene(&scene)?;
        Ok(Job {
            scene,
            settings,
            integrator: IntegratorKind::Photonmap,
            backend: BackendKind::Embree,
            accel: AccelOptions::default(),
            threads: 0,
            load_seconds: 0.0,
            landings: None,
            preview: false,
            spectral: crate::integrator::Spectral::Off,
            spectral_reason: None,
        })
    }

    /// Applies the command line's overrides to the file's settings.
    pub fn with(mut self, o: &Overrides) -> Job<'a> {
        let s = &mut self.settings;
        if let Some((w, h)) = o.res {
            (s.width, s.height) = (w, h);
        }
        if let Some(spp) = o.spp {
            s.spp = spp.max(1);
        }
        if let Some(d) = o.max_depth {
            s.max_depth = d;
        }
        s.seed = o.seed;
        s.pattern = o.pattern;
        s.light_samples = o.light_samples.unwrap_or(1).max(1);
        o.photon.apply(&mut s.photon);
        s.photon.follow_depth(s.max_depth);
        if let Some(a) = o.alpha {
            s.photon.alpha = a; // in range: checked by its parser
            s.vcm.alpha = a;
        }
        if let Some(r) = o.merge_radius {
            s.vcm.radius = r;
        }
        s.vcm.all_merges |= o.all_merges;
        if o.light_paths.is_some() {
            s.vcm.light_paths = o.light_paths;
        }
        s.photon.progressive |= o.progressive;
        if let Some(n) = o.pass_spp {
            s.pass_spp = n.max(1);
        }
        if o.crop.is_some() {
            s.crop = o.crop;
        }
        if o.quick {
            (s.width, s.height) = ((s.width / 4).max(1), (s.height / 4).max(1));
            s.spp = 1;
        }
        self.spectral = o.spectral.unwrap_or_default();
        s.spectral = self.spectral == crate::integrator::Spectral::On;
        for a in &o.aovs {
            if !s.aovs.aovs.contains(a) {
                s.aovs.aovs.push(*a);
            }
        }
        self
    }

    /// Settles `--spectral=auto` for the job's integrator and scene
    /// ([`crate::integrator::spectral_auto`]), keeping why it renders spectrally, if it does.
    pub fn resolve_spectral(&mut self) {
        use crate::integrator::Spectral;
        let why = match self.spectral {
            Spectral::Auto => crate::integrator::spectral_auto(self.integrator, &self.scene),
            Spectral::On => Some("--spectral".into()),
            Spectral::Off => None,
        };
        self.settings.spectral = why.is_some();
        self.spectral_reason = why;
    }

    /// The memory estimate of rendering `settings` (the job's, or a variant of them), an
    /// error when it exceeds `budget` (resolve it once, before the first check). The photon
    /// maps count once [`Job::pilot`] has run.
    pub fn check_memory(
        &self,
        settings: &RenderSettings,
        budget: &Budget,
        cli: FromCli,
    ) -> Result<Estimate, String> {
        let (scene, kinds, threads) = (&self.scene, (self.integrator, self.backend), self.threads);
        let limit = (budget, cli);
        let landings = self.landings;
        crate::memory::check_render(
            scene,
            settings,
            kinds,
            threads,
            landings,
            limit,
            self.preview,
        )
    }

    /// Measures the photons pass 1 stores per photon emitted with a pilot trace on `accel`
    /// (nothing for integrators without pass 1), for [`Job::check_memory`].
    pub fn pilot(&mut self, accel: &Accel, pool: &rayon::ThreadPool) {
        let (scene, settings, kind) = (&self.scene, &self.settings, self.integrator);
        self.landings = pool.install(|| integrator::pilot(scene, accel, settings, kind));
    }

    /// The thread pool of the job's thread count.
    pub fn pool(&self) -> Result<rayon::ThreadPool, ToolError> {
        thread_pool(self.threads)
    }

    /// Builds the job's accelerator on `pool`; returns it with its build time in seconds.
    pub fn build(&self, pool: &rayon::ThreadPool) -> Result<(Accel, f64), ToolError> {
        self.build_on(self.backend, pool)
    }

    /// Builds the accelerator of `backend` (crosscheck builds both).
    pub fn build_on(
        &self,
        backend: BackendKind,
        pool: &rayon::ThreadPool,
    ) -> Result<(Accel, f64), ToolError> {
        let t = Instant::now();
        let accel = pool.install(|| Accel::build(&self.scene, backend, self.accel))?;
        Ok((accel, t.elapsed().as_secs_f64()))
    }

    /// Renders the job's settings with its integrator on `pool`, reporting finished tiles to
    /// `progress(done, total)`.
    pub fn render(
        &self,
        accel: &Accel,
        pool: &rayon::ThreadPool,
        progress: &dyn crate::integrator::Observer,
    ) -> RenderOutput {
        let (scene, settings, kind) = (&self.scene, &self.settings, self.integrator);
        pool.install(|| integrator::render(scene, accel, settings, kind, progress))
    }
}

/// A rayon pool of `threads` workers (0 = all cores) with flush-to-zero set on each.
pub fn thread_pool(threads: usize) -> Result<rayon::ThreadPool, ToolError> {
    rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .start_handler(|_| crate::accel::cpu::enable_flush_denormals())
        .build()
        .map_err(|e| ToolError(format!("cannot start {threads} threads: {e}")))
}
