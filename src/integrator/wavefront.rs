//! The tile wavefront every integrator renders through (pbrt-v4's `Render`/`Li` split): this
//! module owns the tile's buffers, the camera rays, the batched and timed ray queries and the
//! shadow-ray resolver; an integrator supplies only its shading step ([`Shade`]).
//!
//! Per sample index, all camera rays of the tile go to the backend as one batch (Embree's
//! 8-wide packets for coherent rays); the integrator shades every hit, emitting shadow rays
//! and continuation paths; the shadow rays are traced as batches of at most
//! [`BATCH`] (and whatever the integrator defers, such as final-gather
//! rays, is flushed the same way); then the continuations form the next wave.
use super::{charge, tile_pixels, RenderContext};
use crate::accel::{Hit, RayKind};
pub use crate::film::Component;
use crate::film::Radiance;
use crate::light::{Pick, Receiver};
use crate::limits::BATCH;
use crate::math::{Ray, Vec3};
use crate::sampling::Sampler;
use crate::spectrum::{Lambda, Spectrum};
use std::sync::atomic::Ordering;
use std::time::Instant;

/// Dimensions the camera sample uses (pixel filter offset).
pub const CAMERA_DIMS: u32 = 2;

/// The sampler dimension a spectral render's wavelengths are drawn from (one per camera
/// sample, far from every other dimension).
pub const LAMBDA_DIM: u32 = (1 << 31) - 1;

/// First sampler dimension of the distance sampling in media: ray segment `k` of a path reads
/// dimensions `MEDIUM_DIMS + 2k` and `+ 2k + 1` (channel, distance), far above any vertex's.
pub const MEDIUM_DIMS: u32 = 1 << 20;

/// One path in flight; `T` is the integrator's own per-path state ([`Shade::PathData`]).
#[derive(Clone, Debug)]
pub struct PathState<T = ()> {
    /// Index of the pixel within the tile.
    pub pixel: usize,
    pub ray: Ray,
    /// Throughput: product of `f |cos| / pdf` (and roulette compensation) so far.
    pub beta: Spectrum,
    /// Number of scattering events so far.
    pub depth: u32,
    /// Solid-angle BSDF density of the last bounce if it was non-delta, else 0 (camera or
    /// delta bounce: emission then counts with full weight).
    pub prev_pdf: f32,
    /// The last scattering point (the camera at first) and its shading normal (zero in a
    /// medium), for the light density at an emitter.
    pub prev: Receiver,
    /// Whether every bounce so far was a delta (specular) one.
    pub prev_delta: bool,
    /// Product of `eta^2` over the delta refractions so far (for roulette).
    pub eta_scale: f32,
    /// The medium the ray travels in (index into `Scene::media`), for integrators that track
    /// media ([`Shade::tracks_media`]).
    pub medium: Option<u32>,
    /// Ray segments traced so far (each reads its own medium dimensions, [`MEDIUM_DIMS`]).
    pub segment: u32,
    /// What `beta` and the path's contributions mean: RGB, or the camera sample's wavelengths
    /// (`--spectral`: the integrator uplifts the scene's colours to them).
    pub lambda: Lambda,
    pub sampler: Sampler,
    /// The integrator's own state.
    pub data: T,
}

impl<T: Default> PathState<T> {
    /// A path leaving the camera along `ray` for pixel `pixel` of the tile.
    pub fn camera(pixel: usize, ray: Ray, sampler: Sampler) -> Self {
        PathState {
            pixel,
            ray,
            beta: Spectrum::ONE,
            depth: 0,
            prev_pdf: 0.0,
            prev: Receiver::in_medium(ray.o),
            prev_delta: true,
            eta_scale: 1.0,
            medium: None,
            segment: 0,
            lambda: Lambda::Rgb,
            sampler,
            data: T::default(),
        }
    }
}

/// A pixel's sums of one sample index while its paths are in flight.
pub type Sums = Radiance<Spectrum>;

/// Adds `value` to a pixel's component; a non-finite value is dropped (one bad sample must not
/// poison a pixel).
pub fn add(acc: &mut [Sums], pixel: usize, c: Component, value: Spectrum) {
    if !value.is_finite() {
        return;
    }
    acc[pixel][c] += value;
}

/// A shadow ray and what it adds to its pixel if unoccluded.
#[derive(Clone, Copy, Debug)]
pub struct Shadow {
    pub pixel: usize,
    pub ray: Ray,
    pub contrib: Spectrum,
    pub component: Component,
    /// The medium the ray starts in (read only by integrators that track media).
    pub medium: Option<u32>,
}

/// Where a shading step puts its results.
pub struct Wave<'a, X, T = ()> {
    /// The tile's per-pixel sums.
    pub acc: &'a mut [Sums],
    pub shadows: &'a mut Vec<Shadow>,
    /// Paths continuing into the next wave.
    pub next: &'a mut Vec<PathState<T>>,
    /// The integrator's own deferred work.
    pub extra: &'a mut X,
}

/// An integrator's shading step.
pub trait Shade: Sync {
    /// Per-tile work the integrator defers and traces in batches (final-gather rays).
    type Extra: Default;
    /// What the integrator carries along each path besides the common [`PathState`].
    type PathData: Copy + Default + std::fmt::Debug;
    /// Shades `path`'s `hit`.
    fn shade(
        &self,
        ctx: &RenderContext,
        path: PathState<Self::PathData>,
        hit: &Hit,
        wave: &mut Wave<Self::Extra, Self::PathData>,
    );
    /// The component that light emitted towards `path` counts towards: an emitter it hits, or
    /// the infinite lights when it leaves the scene (see [`escaped`]).
    fn emitted_component(&self, path: &PathState<Self::PathData>) -> Component;
    /// Whether this integrator tracks the medium each path is in (pbrt-v4's semantics:
    /// segments in a medium sample scattering, [`Shade::shade_medium`] shades the points, and
    /// shadow rays pass `interface` surfaces, taking each medium's transmittance). The others
    /// weigh a segment by the medium on the side of the surface it ends on
    /// ([`crate::accel::transmittance`]), which is exact for absorbing regions closed by the
    /// surfaces that name them.
    fn tracks_media(&self) -> bool {
        false
    }
    /// Shades a scattering point `p` of `path`'s medium (for integrators that track media).
    fn shade_medium(
        &self,
        _ctx: &RenderContext,
        _path: PathState<Self::PathData>,
        _p: Vec3,
        _wave: &mut Wave<Self::Extra, Self::PathData>,
    ) {
    }
    /// What `path` sees of the infinite lights when it leaves the scene (see [`escaped`]).
    fn escaped(&self, ctx: &RenderContext, path: &PathState<Self::PathData>) -> Spectrum {
        escaped(ctx, path)
    }
    /// Entries waiting in `extra` (flushed at [`BATCH`] and at the end of each wave).
    fn pending(&self, _extra: &Self::Extra) -> usize {
        0
    }
    /// Traces and resolves what `extra` holds.
    fn flush(&self, _ctx: &RenderContext, _extra: &mut Self::Extra, _acc: &mut [Sums]) {}
}

/// Closest hits of a batch of rays of `kind`, timed into `ray_ns`.
pub fn intersect_batch(
    ctx: &RenderContext,
    kind: RayKind,
    rays: &[Ray],
    hits: &mut Vec<Option<Hit>>,
) {
    hits.clear();
    hits.resize(rays.len(), None);
    let t = Instant::now();
    ctx.accel.intersect_batch(kind, rays, hits);
    charge(&ctx.counters.ray_ns, t);
}

/// The reusable buffers of one tile.
struct Buffers<T> {
    paths: Vec<PathState<T>>,
    next: Vec<PathState<T>>,
    rays: Vec<Ray>,
    hits: Vec<Option<Hit>>,
    shadows: ShadowQueue,
}

/// Shadow rays waiting to be traced, with the buffers their batch query reuses.
#[derive(Default)]
struct ShadowQueue {
    shadows: Vec<Shadow>,
    rays: Vec<Ray>,
    occluded: Vec<bool>,
}

impl ShadowQueue {
    /// Traces the waiting shadow rays, adds what gets through, and empties the queue.
    fn resolve(&mut self, ctx: &RenderContext, tracks: bool, acc: &mut [Sums]) {
        let (rays, occluded) = (&mut self.rays, &mut self.occluded);
        resolve_shadows(ctx, tracks, &self.shadows, rays, occluded, acc);
        self.shadows.clear();
    }
}

impl<T> Default for Buffers<T> {
    fn default() -> Self {
        Buffers {
            paths: Vec::new(),
            next: Vec::new(),
            rays: Vec::new(),
            hits: Vec::new(),
            shadows: ShadowQueue::default(),
        }
    }
}

/// Renders the pixels `[x0, x1) x [y0, y1)` with `shader`; returns the per-pixel means over
/// `ctx.settings.spp` samples in row-major order.
pub fn render_tile<S: Shade>(
    ctx: &RenderContext,
    shader: &S,
    x0: u32,
    y0: u32,
    x1: u32,
    y1: u32,
) -> Vec<Radiance> {
    let spp = ctx.settings.spp.max(1);
    let n = ((x1 - x0) * (y1 - y0)) as usize;
    let mut acc = vec![Radiance::default(); n];
    // Each sample index gathers into its own buffer (a sample's light arrives over several
    // waves): once all its waves are done it is turned into RGB at the sample's wavelengths
    // (a spectral render), clamped (`maxcomponentvalue`) and added to `acc`.
    let clamp = ctx.settings.max_component / ctx.settings.imaging_ratio;
    // Per-pixel sample statistics (the gbuffer's variance channels).
    let mut stats = match ctx.variance {
        Some(_) => vec![Welford::default(); n],
        None => Vec::new(),
    };
    let spectral = ctx.settings.spectral;
    let mut lambdas = Vec::new();
    let mut one = vec![Sums::default(); n];
    let mut b = Buffers::<S::PathData>::default();
    let mut extra = S::Extra::default();
    for sample in 0..spp {
        b.paths.clear();
        lambdas.clear();
        for (i, (x, y)) in tile_pixels(x0, y0, x1, y1).enumerate() {
            let (ray, sampler) = super::camera_sample(ctx, x, y, sample);
            let mut path = PathState::camera(i, ray, sampler);
            path.medium = ctx.scene.camera_medium;
            if spectral {
                let mut s = path.sampler.clone();
                s.set_dimension(LAMBDA_DIM);
                path.lambda = Lambda::sample(s.next_1d());
                lambdas.push(path.lambda);
            }
            b.paths.push(path);
        }
        ctx.counters
            .camera_rays
            .fetch_add(b.paths.len() as u64, Ordering::Relaxed);
        // The first wave is the camera rays, every later one their bounces.
        let mut kind = RayKind::Camera;
        while !b.paths.is_empty() {
            wave(ctx, shader, kind, &mut b, &mut extra, &mut one);
            kind = RayKind::Bounce;
        }
        for (i, (a, r)) in acc.iter_mut().zip(one.iter_mut()).enumerate() {
            let r = std::mem::take(r);
            let l = lambdas.get(i).unwrap_or(&Lambda::Rgb);
            let r = r.map(|v| l.to_rgb(v));
            let r = crate::film::clamp_sample(r, clamp);
            if let Some(w) = stats.get_mut(i) {
                w.add(ctx.settings.film_rgb(r.total()));
            }
            *a += r;
        }
    }
    if let Some(v) = &ctx.variance {
        store_variance(ctx, v, &stats, (x0, y0, x1, y1));
    }
    let inv = 1.0 / spp as f32;
    acc.into_iter().map(|r| r * inv).collect()
}

/// Welford's running mean and sum of squared deviations of one pixel's samples (RGB).
#[derive(Clone, Copy, Debug, Default)]
struct Welford {
    n: f64,
    mean: [f64; 3],
    m2: [f64; 3],
}

impl Welford {
    fn add(&mut self, x: Vec3) {
        self.n += 1.0;
        for c in 0..3 {
            let d = x[c] as f64 - self.mean[c];
            self.mean[c] += d / self.n;
            self.m2[c] += d * (x[c] as f64 - self.mean[c]);
        }
    }

    /// pbrt-v4's `VarianceEstimator`: the sample variance (`n - 1`) and the variance over the
    /// mean (0 for a zero mean), per channel.
    fn variance(&self) -> [f32; 6] {
        let var = |c: usize| match self.n > 1.0 {
            true => self.m2[c] / (self.n - 1.0),
            false => 0.0,
        };
        let rel = |c: usize| match self.mean[c] != 0.0 {
            true => var(c) / self.mean[c],
            false => 0.0,
        };
        [var(0), var(1), var(2), rel(0), rel(1), rel(2)].map(|v| v as f32)
    }
}

/// Writes a tile's variances into the image-wide buffer (the crop window's pixels).
fn store_variance(
    ctx: &RenderContext,
    into: &std::sync::Mutex<Vec<[f32; 6]>>,
    stats: &[Welford],
    (x0, y0, x1, y1): (u32, u32, u32, u32),
) {
    let [bx0, bx1, by0, _] = ctx.settings.pixel_bounds();
    let w = (bx1 - bx0) as usize;
    let mut v = into.lock().unwrap_or_else(|e| e.into_inner());
    for ((x, y), s) in tile_pixels(x0, y0, x1, y1).zip(stats) {
        let k = (y - by0) as usize * w + (x - bx0) as usize;
        if let Some(slot) = v.get_mut(k) {
            *slot = s.variance();
        }
    }
}

/// Traces the rays of `b.paths` (all of `kind`) as one batch, shades the hits, resolves their
/// shadow rays and deferred work in bounded batches, and leaves the continuing paths in
/// `b.paths`.
fn wave<S: Shade>(
    ctx: &RenderContext,
    shader: &S,
    kind: RayKind,
    b: &mut Buffers<S::PathData>,
    extra: &mut S::Extra,
    acc: &mut [Sums],
) {
    b.rays.clear();
    b.rays.extend(b.paths.iter().map(|p| p.ray));
    intersect_batch(ctx, kind, &b.rays, &mut b.hits);
    b.shadows.shadows.clear();
    b.next.clear();
    let tracks = shader.tracks_media();
    for (path, hit) in b.paths.drain(..).zip(b.hits.iter()) {
        let mut w = Wave {
            acc,
            shadows: &mut b.shadows.shadows,
            next: &mut b.next,
            extra,
        };
        shade_one(ctx, shader, tracks, path, hit.as_ref(), &mut w);
        // Bounded batches: a point adds a bounded number of shadow rays and deferred entries
        // beyond BATCH before they are traced.
        if b.shadows.shadows.len() >= BATCH {
            b.shadows.resolve(ctx, tracks, acc);
        }
        if shader.pending(extra) >= BATCH {
            shader.flush(ctx, extra, acc);
        }
    }
    b.shadows.resolve(ctx, tracks, acc);
    shader.flush(ctx, extra, acc);
    ctx.counters
        .secondary_rays
        .fetch_add(b.next.len() as u64, Ordering::Relaxed);
    std::mem::swap(&mut b.paths, &mut b.next);
}

/// One path's segment: the medium it crosses (tracking integrators) or the end rule's
/// transmittance, then the hit's shading or what a path leaving the scene sees.
fn shade_one<S: Shade>(
    ctx: &RenderContext,
    shader: &S,
    tracks: bool,
    mut path: PathState<S::PathData>,
    hit: Option<&Hit>,
    w: &mut Wave<S::Extra, S::PathData>,
) {
    if tracks {
        path.segment += 1;
        if let Some(m) = path.medium {
            let medium = &ctx.scene.media[m as usize];
            let len = path.ray.d.length();
            let dist = hit.map_or(f32::INFINITY, |h| h.t * len);
            if medium.emits() {
                // The light the medium emits along the whole segment, in closed form or by
                // ratio tracking; the sampled interaction below estimates the rest.
                let e = medium.emitted_along(
                    path.ray.o,
                    path.ray.d / len,
                    dist,
                    &mut segment_rng(&path.ray, 0x656d),
                );
                add(
                    w.acc,
                    path.pixel,
                    shader.emitted_component(&path),
                    path.beta * Spectrum::from_rgb(e),
                );
            }
            // Camera segments and those after delta bounces only: later ones sample their
            // scattering as the path tracer does (a beam per segment of every path would
            // cost far more than it removes in noise there). Emitting media are sampled as
            // the path tracer does: the volume map holds no photons they emit.
            let volume = ctx.photons.and_then(|p| p.volume.as_ref());
            let beam = medium.scatters() && !medium.emits() && path.prev_delta;
            if let (Some(map), true) = (volume, beam) {
                // The photon mapper: the volume map's beam estimate gives all the light the
                // medium scatters towards the ray; the ray goes on to its hit dimmed.
                let t = Instant::now();
                let d = path.ray.d / len;
                let tr = medium.transmittance_table(path.ray.o, d, dist);
                let (beam, n) = map.beam_with(path.ray.o, d, dist, medium.g, &tr);
                charge(&ctx.counters.lookup_ns, t);
                ctx.counters.beams.fetch_add(1, Ordering::Relaxed);
                ctx.counters
                    .beam_photons
                    .fetch_add(n as u64, Ordering::Relaxed);
                add(
                    w.acc,
                    path.pixel,
                    Component::Indirect,
                    path.beta * Spectrum::from_rgb(beam),
                );
                path.beta *= Spectrum::from_rgb(tr.at(dist));
            } else if let Some(t) = medium_segment(medium, &mut path, dist) {
                let p = path.ray.o + path.ray.d * (t / len);
                shader.shade_medium(ctx, path, p, w);
                return;
            }
            if path.beta.max_element() <= 0.0 {
                return;
            }
        }
    } else if let Some(hit) = hit {
        path.beta *=
            Spectrum::from_rgb(crate::accel::transmittance(ctx.scene, Some(hit), &path.ray));
    }
    if let Some(hit) = hit {
        shader.shade(ctx, path, hit, w);
    } else if ctx.lights.has_infinite() {
        add(
            w.acc,
            path.pixel,
            shader.emitted_component(&path),
            shader.escaped(ctx, &path),
        );
    }
}

/// Crosses `dist` units (infinite: the ray leaves the scene) of `medium` along `path`'s ray:
/// an absorbing medium weighs the throughput by its transmittance; a scattering one samples
/// where the ray first interacts ([`crate::medium::Medium::sample_distance`], reading the
/// segment's two [`MEDIUM_DIMS`]) and returns that distance when it falls short of `dist`,
/// the throughput weighed either way.
fn medium_segment<T>(
    medium: &crate::medium::Medium,
    path: &mut PathState<T>,
    dist: f32,
) -> Option<f32> {
    let len = path.ray.d.length();
    let (o, d) = (path.ray.o, path.ray.d / len);
    if medium.is_homogeneous() && !medium.scatters() {
        path.beta *= Spectrum::from_rgb(medium.transmittance(dist));
        return None;
    }
    path.sampler
        .set_dimension(MEDIUM_DIMS.wrapping_add(path.segment.wrapping_mul(2)));
    let (uc, u) = (path.sampler.next_1d(), path.sampler.next_1d());
    if !medium.scatters() {
        let key = crate::sampling::hash(&[uc.to_bits() as u64, u.to_bits() as u64]);
        let mut rng = crate::medium::grid::Rng::new(key);
        path.beta *= Spectrum::from_rgb(medium.transmittance_along(o, d, dist, &mut rng));
        return None;
    }
    match medium.sample_interaction(o, d, dist, uc, u, path.beta.rgb()) {
        crate::medium::MediumEvent::Scatter { t, weight } => {
            path.beta *= Spectrum::from_rgb(weight);
            Some(t)
        }
        crate::medium::MediumEvent::Pass { weight } => {
            path.beta *= Spectrum::from_rgb(weight);
            None
        }
    }
}

/// The fraction of light a shadow ray carries to its end through the media it crosses:
/// segment by segment from `s.medium`, passing through `interface` surfaces (each changes the
/// medium) and stopped (0) by any other surface, or after [`MAX_CROSSINGS`] boundaries.
fn shadow_transmittance(ctx: &RenderContext, s: &Shadow) -> Vec3 {
    let scene = ctx.scene;
    let end = s.ray.at(s.ray.tmax);
    let mut ray = s.ray;
    let mut medium = s.medium;
    let mut tr = Vec3::ONE;
    for _ in 0..MAX_CROSSINGS {
        let hit = ctx.accel.intersect(RayKind::Shadow, &ray);
        let len = ray.d.length();
        let Some(h) = hit else {
            if let Some(m) = medium {
                tr *= along(&scene.media[m as usize], &ray, ray.tmax * len);
            }
            return tr;
        };
        let mesh = &scene.meshes[h.mesh as usize];
        let (true, Some(mi)) = (
            scene.materials[mesh.material as usize].interface,
            mesh.interface,
        ) else {
            return Vec3::ZERO;
        };
        if let Some(m) = medium {
            tr *= along(&scene.media[m as usize], &ray, h.t * len);
        }
        let ng = mesh.geometric_normal(h.prim, h.u, h.v);
        medium = mi.leaving(ray.d, ng);
        let o = crate::math::spawn_origin(
            mesh.point(h.prim, h.u, h.v),
            mesh.point_error(h.prim, h.u, h.v),
            if ng.dot(ray.d) >= 0.0 { ng } else { -ng },
        );
        ray = Ray::segment(o, end - o, 1.0);
        if tr.max_element() <= 0.0 {
            return tr;
        }
    }
    Vec3::ZERO
}

/// A shadow segment's transmittance through `medium` over `dist` (ratio tracking in a grid,
/// its numbers keyed by the segment itself, so the image stays independent of scheduling).
fn along(medium: &crate::medium::Medium, ray: &Ray, dist: f32) -> Vec3 {
    medium.transmittance_along(ray.o, ray.d.normalize(), dist, &mut segment_rng(ray, 0))
}

/// A random stream keyed by a ray segment itself (and `salt`), so that what a tracker draws
/// along it does not depend on scheduling.
fn segment_rng(ray: &Ray, salt: u64) -> crate::medium::grid::Rng {
    let bits = |v: Vec3| v.to_array().map(|x| x.to_bits() as u64);
    let (o, dd) = (bits(ray.o), bits(ray.d.normalize()));
    let key = match salt {
        0 => crate::sampling::hash(&[o[0], o[1], o[2], dd[0], dd[1], dd[2]]),
        _ => crate::sampling::hash(&[o[0], o[1], o[2], dd[0], dd[1], dd[2], salt]),
    };
    crate::medium::grid::Rng::new(key)
}

/// Medium boundaries a shadow ray may pass before it is taken as blocked.
pub const MAX_CROSSINGS: u32 = 64;

/// What a path that leaves the scene sees of the infinite lights, times its throughput: with
/// full weight after the camera or a delta bounce, else power-heuristic-weighted against light
/// sampling (the BSDF density of the last bounce against the lights' density of the direction).
pub fn escaped<T>(ctx: &RenderContext, path: &PathState<T>) -> Spectrum {
    let d = path.ray.d.normalize_or_zero();
    let le = ctx
        .lights
        .escaped(path.ray.o, d, Pick::At(path.prev), |_, light_pdf| {
            if path.prev_pdf > 0.0 {
                crate::sampling::power_heuristic(path.prev_pdf, light_pdf)
            } else {
                1.0
            }
        });
    path.beta * path.lambda.illuminant(le)
}

/// Traces a batch of shadow rays and adds the unoccluded contributions (for an integrator that
/// `tracks` media in a scene with media: each ray's [`shadow_transmittance`]).
fn resolve_shadows(
    ctx: &RenderContext,
    tracks: bool,
    shadows: &[Shadow],
    rays: &mut Vec<Ray>,
    occluded: &mut Vec<bool>,
    acc: &mut [Sums],
) {
    if shadows.is_empty() {
        return;
    }
    if tracks && !ctx.scene.media.is_empty() {
        let t = Instant::now();
        for s in shadows {
            let tr = shadow_transmittance(ctx, s);
            add(
                acc,
                s.pixel,
                s.component,
                s.contrib * Spectrum::from_rgb(tr),
            );
        }
        charge(&ctx.counters.ray_ns, t);
        ctx.counters
            .shadow_rays
            .fetch_add(shadows.len() as u64, Ordering::Relaxed);
        return;
    }
    rays.clear();
    rays.extend(shadows.iter().map(|s| s.ray));
    occluded.clear();
    occluded.resize(rays.len(), false);
    let t = Instant::now();
    ctx.accel.occluded_batch(RayKind::Shadow, rays, occluded);
    charge(&ctx.counters.ray_ns, t);
    ctx.counters
        .shadow_rays
        .fetch_add(rays.len() as u64, Ordering::Relaxed);
    for (s, &blocked) in shadows.iter().zip(occluded.iter()) {
        if !blocked {
            add(acc, s.pixel, s.component, s.contrib);
        }
    }
}
