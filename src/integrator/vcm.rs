//! Vertex connection and merging (`photon render --integrator vcm`) and its special cases
//! `bdpt` (connections only), `bpm` (merging only) and `lighttracer` (light paths splatted to
//! the camera).
//!
//! ```text
//! photon render scene.pbrt --integrator vcm --spp 64 --merge-radius 2px --alpha 0.75
//! ```
//! Georgiev, Křivánek, Davidovič & Slusallek, "Light transport simulation with vertex
//! connection and merging" (2012), in the formulation of their technical report
//! ("Implementing vertex connection and merging"): each iteration (one per sample per pixel)
//! traces light subpaths, one per pixel or a fraction of that (`--light-paths`, else chosen
//! by a pilot: [`light_fraction`]), keeps their non-delta vertices, and splats each of them
//! to the camera (light tracing); then every pixel traces one camera subpath that, at each
//! non-delta vertex, takes a light sample (next-event estimation), connects to every vertex
//! of light subpath `k mod m` (`k` the pixel's index, `m` the light subpaths) and
//! merges with the light vertices of all subpaths within the merge radius that lie on its
//! surface (photon density estimation, from a hash grid; see `on_surface`). Multiple
//! importance sampling weighs every technique by the balance heuristic through the
//! recursive partial sums `dVCM`, `dVC`, `dVM` of each subpath, so no technique's path is
//! counted twice, with one exception to the balance heuristic:
//! direct light (light, surface, camera) at a surface without glossy or specular lobes is
//! left to light samples and emission hits, light tracing's density counting 0 in its
//! weights ([`DIRECT_LIGHT_TRACING`]). Light samples are the path tracer's: a light picked
//! by its importance at the point, a sphere light sampled by its cone, uniform skies left to
//! BSDF sampling (their density there is 0); light subpaths pick lights by power. The
//! merge radius shrinks with the iteration `i` as
//! `r_i = r_0 / (i + 1)^((1 - alpha) / 2)` (progressive photon mapping), so the estimate
//! converges; `r_0` is `--merge-radius`: by default 2 pixel footprints (a footprint is the
//! median width of a pixel where the camera sees the scene), `Npx` for N of them, or a
//! number F for F times the radius of the scene's bounding sphere (SmallVCM's convention,
//! 0.003 there).
//!
//! `bdpt` turns merging off (the weights then are bidirectional path tracing's), `bpm` turns
//! connections, light samples and light tracing off (merging alone, with emission only along
//! delta chains from the camera: bidirectional photon mapping); `lighttracer`
//! traces light subpaths only, splatting their every vertex (the light's own point included)
//! to the camera with weight 1, so paths the camera sees only through delta bounces are
//! missing from it (as from pbrt-v4's `lighttracer`).
//!
//! Distant and infinite lights draw a light subpath's origin as the photon tracer does
//! ([`crate::photon::aim`]): most (`LIGHT_SHARE`) on the disc that the sphere around what the
//! camera sees casts, the rest on the disc over the whole scene, where the camera sees a small part
//! of a large scene (a room lit through its windows inside a wide ground); every emission
//! density of the weights, the camera side's included, is that mixture's at the origin (the
//! projection of the vertex onto the emission plane). `--aimed-photons=false` turns it off.
//!
//! Conventions: path lengths count segments (a camera ray that hits an emitter is a path of
//! length 1), so `maxdepth` bounces allow `maxdepth + 1` segments. Russian roulette is the
//! path tracer's, on each subpath's throughput relative to its start, from bounce
//! `RR_MIN_BOUNCES + 1` on, and left out of the MIS densities as pbrt-v4's bdpt does
//! ([`roulette`]; the technical report's roulette on the BSDF's albedo at every bounce, folded
//! into the densities, ended 73% of the camera subpaths at material-testball's dark coated
//! ball, whose coat reflects the bright sky: bdpt 17x the path tracer's relMSE per sample).
//! Light subpaths carry importance: their BSDF values take pbrt-v4's
//! correction for shading normals. The coated BSDFs' stochastic `f` and `pdf` are used as they
//! are (their estimates are unbiased; the weights then sum to one only in expectation).
//!
//! Determinism: subpath `k` of iteration `i` draws from its own sample stream, camera
//! subpaths from their pixel's; splats are gathered per chunk of light subpaths and added to
//! the film in chunk order, so an image does not depend on the number of threads.
//!
//! Distant and infinite lights start their subpaths on the disc of the scene's bounding
//! sphere that faces their direction (as photons do); their first segment's length does not
//! count in the partial sums; behind a portal, an infinite light's subpaths that miss it carry
//! nothing (as photons do), while the densities stay the whole map's, which every technique
//! uses alike. With a thin lens, a light vertex connects to a point of the lens drawn for it
//! (the camera subpaths' own lens density, so it leaves the weights as for a pinhole).
//! An orthographic camera samples ray origins on its plane z = 0 instead of directions: a
//! light vertex connects to the point of that plane whose ray (of the lens point's direction)
//! passes through it, with the importance `1 / A` per unit area of the plane
//! ([`crate::camera::Camera::project_through_lens`]), and a camera subpath's first segment
//! does not count in its partial sums (as a distant light's).
use super::path::RR_MIN_BOUNCES;
use super::RenderContext;
use crate::accel::{Hit, RayKind};
use crate::bsdf::{Bsdf, TransportMode};
use crate::film::{Component, Radiance};
use crate::interaction::SurfaceInteraction;
use crate::light::{Pick, Receiver};
use crate::math::{spawn_origin, Frame, Ray, Vec2, Vec3};
use crate::sampling::Sampler;
use rayon::prelude::*;
use std::sync::atomic::Ordering;

/// The bidirectional integrators: which techniques are on.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Technique {
    LightTracer,
    Bdpt,
    /// Merging alone (bidirectional photon mapping): light vertices merged at every
    /// non-delta camera vertex; emission only along delta chains from the camera.
    Bpm,
    Vcm,
}

/// VCM's initial merge radius.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum MergeRadius {
    /// A fraction of the radius of the scene's bounding sphere (`--merge-radius 0.003`).
    Scene(f32),
    /// Pixels: this many times the median footprint of a pixel at the surfaces the camera
    /// sees (`--merge-radius 2px`), measured on a 32x32 grid of camera rays.
    Pixels(f32),
}

impl MergeRadius {
    /// Parses `F` (a fraction of the scene's radius, in (0, 1]) or `Fpx` (pixels, in (0, 1000]).
    pub fn parse(s: &str) -> Result<MergeRadius, String> {
        let t = s.trim();
        let (num, px) = match t.strip_suffix("px") {
            Some(n) => (n, true),
            None => (t, false),
        };
        let v: f32 = num
            .trim()
            .parse()
            .map_err(|_| format!("expected a number or a number of pixels (`2px`), got `{s}`"))?;
        let hi = if px { 1000.0 } else { 1.0 };
        if !(v > 0.0 && v <= hi) {
            return Err(format!("must be in (0, {hi}], got {v}"));
        }
        Ok(if px {
            MergeRadius::Pixels(v)
        } else {
            MergeRadius::Scene(v)
        })
    }
}

/// The settings of the bidirectional integrators.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct VcmSettings {
    /// The initial merge radius.
    pub radius: MergeRadius,
    /// The radius schedule's alpha in (0, 1).
    pub alpha: f32,
    /// Iterations rendered before this render (a time budget renders in several calls):
    /// the radius schedule continues from there.
    pub first: u32,
    /// VCM merges at every non-delta vertex (`--all-merges`), not only where connections
    /// cannot reach (the default, see [`merges_at`]).
    pub all_merges: bool,
    /// Light subpaths per iteration as a fraction of the pixels (`--light-paths`), in
    /// (0, 1]; `None`: chosen by a pilot ([`light_fraction`]).
    pub light_paths: Option<f32>,
}

impl Default for VcmSettings {
    fn default() -> Self {
        VcmSettings {
            radius: MergeRadius::Pixels(DEFAULT_PIXELS),
            alpha: 0.75,
            first: 0,
            all_merges: false,
            light_paths: None,
        }
    }
}

/// The default initial merge radius in pixel footprints. Merges happen only behind specular
/// surfaces, where no connection reaches; there 2 footprints gave water-caustic (128 px, 30 s,
/// two seeds) relMSE 0.0040 / 0.0039 against 0.0058 / 0.0053 at 1, and veach-bidir the same
/// within noise (0.0030 at 1, 1.5 and 2; see BENCHMARKS.md).
pub const DEFAULT_PIXELS: f32 = 2.0;

/// The factor on light tracing's density in the MIS weights of direct light (paths of two
/// segments: light, surface, camera) at a surface without glossy or specular lobes, where
/// light samples and emission hits are its rivals.
/// The balance heuristic weighs techniques by density alone, and light subpaths aimed at
/// what the camera sees are dense there, so it handed light tracing most of the direct
/// light of a diffuse scene (74% of dragon's image under its distant light), but its
/// splats land on random pixels while each pixel's own light sample is stratified with
/// the pixel's other samples. Scaling a technique's density in every weight of a path
/// keeps the weights summing to one (the image stays unbiased); 0 leaves direct light to
/// light samples and emission hits, which reach every such path that light tracing
/// reaches (a delta surface has no camera connection either). vcm, 128 px, 15 s, seed 0,
/// relMSE against pbrt-v4's converged render for 1 / 0.1 / 0: dragon 1.08e-5 / 3.9e-6 /
/// 2.3e-6, cornell-box 9.7e-4 / 9.0e-4 / 8.4e-4, veach-bidir 0.019 / 0.0092 / 0.0073,
/// glass-of-water 0.016 / 0.014 / 0.014, teapot 3.3e-4 / 2.8e-4 / 3.0e-4; bathroom2,
/// bathroom, veach-ajar and living-room-3 within their run-to-run noise. But veach-mis
/// (glossy plates under sphere lights; 20 s, seeds 0 / 1) 0.00122 / 0.00126 at 1, 0.00167 /
/// 0.00157 at 0: a glossy surface's direct light is where the three techniques each win
/// somewhere, so glossy and specular surfaces keep light tracing (veach-mis 0.00147 / 0.00137
/// then; coffee, veach-bidir, bathroom2, bathroom, veach-ajar unchanged within noise).
/// `lighttracer` keeps its direct light (it has no other technique).
const DIRECT_LIGHT_TRACING: f32 = 0.0;

/// Light subpaths traced together; their splats reach the film in chunk order.
const CHUNK: usize = 256;

/// Salt of the light subpaths' sample streams (camera subpaths use their pixel's stream).
const LIGHT_STREAM: u64 = 0x6c69_6768_7420_7061;

/// Sample dimensions per light-subpath vertex (lobe 1, direction 2) after the emission's 5.
const LIGHT_DIMS_PER_VERTEX: u32 = 3;

/// Sample dimensions per camera-subpath vertex: light choice 1, light point 2, lobe 1,
/// direction 2 (after the camera's).
const CAMERA_DIMS_PER_VERTEX: u32 = 6;

/// What one iteration's MIS weights need (the technical report's eta_VCM and its factors).
#[derive(Clone, Copy, Debug)]
struct Weights {
    use_vc: bool,
    use_vm: bool,
    light_only: bool,
    /// eta_VCM when merging is on, else 0.
    vm_factor: f32,
    /// 1 / eta_VCM when connections are on, else 0.
    vc_factor: f32,
    /// 1 / (pi r^2 N): what a merged light vertex's throughput is scaled by.
    vm_norm: f32,
    radius2: f32,
    /// Light subpaths per iteration.
    n_light: f32,
    /// Segments a full path may have.
    max_len: u32,
    /// Merging only at vertices whose camera-side neighbour is a purely specular surface
    /// (see [`merges_at`]); false: at every non-delta vertex.
    sds: bool,
    /// Where distant and infinite lights aim their light subpaths (the photon tracer's
    /// mixture, [`crate::photon::aim`]); every emission density of such a light is the
    /// mixture's.
    aim: Option<crate::light::Aim>,
}

impl Weights {
    fn new(t: Technique, radius: f32, n_light: usize, max_depth: u32, all: bool) -> Weights {
        let (use_vc, use_vm, light_only) = match t {
            Technique::LightTracer => (false, false, true),
            Technique::Bdpt => (true, false, false),
            Technique::Bpm => (false, true, false),
            Technique::Vcm => (true, true, false),
        };
        let radius2 = radius * radius;
        let eta = std::f32::consts::PI * radius2 * n_light as f32;
        Weights {
            use_vc,
            use_vm,
            light_only,
            vm_factor: if use_vm { eta } else { 0.0 },
            vc_factor: if use_vc { 1.0 / eta } else { 0.0 },
            vm_norm: 1.0 / eta,
            radius2,
            n_light: n_light as f32,
            max_len: max_depth + 1,
            sds: use_vc && use_vm && !all,
            aim: None,
        }
    }

    /// What light tracing's density is scaled by in the weights of a path of two segments
    /// whose surface has `bsdf`: [`DIRECT_LIGHT_TRACING`] where it has no glossy or
    /// specular lobe, else 1 (a function of the path, so every technique weighs it alike);
    /// 1 for `lighttracer`, whose only technique it is.
    fn direct_lt(&self, bsdf: &Bsdf) -> f32 {
        let f = bsdf.flags();
        if self.light_only || f.has_glossy() || f.has_specular() {
            1.0
        } else {
            DIRECT_LIGHT_TRACING
        }
    }
}

/// A subpath as it is extended: the ray to its next vertex and its MIS partial sums.
#[derive(Clone, Copy, Debug)]
struct SubPath {
    ray: Ray,
    beta: Vec3,
    /// Segments so far (1 after the first ray).
    len: u32,
    /// `1 / max(beta)` at the subpath's start, times `eta^2` for each delta refraction of a
    /// camera subpath (the path tracer's `eta_scale`): Russian roulette weighs the throughput
    /// by it ([`roulette`]).
    beta_scale: f32,
    /// Every bounce so far was a delta one.
    specular: bool,
    /// Starts at a perspective camera or a light with a position (not an orthographic camera,
    /// a distant or an infinite light): the first segment's length counts in the partial sums.
    finite: bool,
    dvcm: f32,
    dvc: f32,
    dvm: f32,
    /// Camera subpaths: the last vertex a light sample was taken from, for the density of
    /// that light sample in the weights of an emission hit (see [`nee_pmf_area`]).
    prev: Receiver,
    /// Camera subpaths after one bounce: `dvc` with light tracing's term scaled by
    /// `Weights::direct_lt` (what an emission hit there weighs by).
    direct_dvc: f32,
    /// Camera subpaths: the previous vertex's surface is purely specular (the camera is not),
    /// so merging at the current vertex is allowed under the SDS rule.
    after_specular: bool,
    /// Light subpaths under the SDS rule: the terms of merging at the previous vertex, kept
    /// apart until the next surface says whether that merge exists (it does when that
    /// surface is purely specular).
    pending_vc: f32,
    pending_vm: f32,
}

/// A vertex of a light subpath kept for connections and merging.
#[derive(Clone, Copy, Debug)]
struct LightVertex {
    p: Vec3,
    err: Vec3,
    ng: Vec3,
    frame: Frame,
    /// Towards the previous vertex, in the shading frame and in world space.
    wo: Vec3,
    wo_world: Vec3,
    bsdf: Bsdf,
    beta: Vec3,
    len: u32,
    dvcm: f32,
    dvc: f32,
    dvm: f32,
}

/// The bytes one kept light vertex takes (for the memory estimate).
pub const LIGHT_VERTEX_BYTES: u64 = std::mem::size_of::<LightVertex>() as u64;

/// A surface point with its BSDF, for evaluating it towards world directions.
#[derive(Clone, Copy)]
struct Vertex {
    ng: Vec3,
    frame: Frame,
    wo: Vec3,
    wo_world: Vec3,
    bsdf: Bsdf,
}

/// A BSDF evaluation towards a world direction (`cos` with the shading normal; `pdf` of
/// sampling that direction, `pdf_rev` of sampling `wo` from it).
struct Eval {
    f: Vec3,
    cos: f32,
    pdf: f32,
    pdf_rev: f32,
}

impl Vertex {
    fn of(v: &LightVertex) -> Vertex {
        Vertex {
            ng: v.ng,
            frame: v.frame,
            wo: v.wo,
            wo_world: v.wo_world,
            bsdf: v.bsdf,
        }
    }

    fn eval(&self, wi_world: Vec3, mode: TransportMode) -> Option<Eval> {
        let wi = self.frame.to_local(wi_world);
        let mut f = self.bsdf.f(self.wo, wi, mode).rgb();
        if mode == TransportMode::Importance {
            f *= shading_correction(self.wo_world, wi_world, self.frame.n, self.ng);
        }
        if f.max_element() <= 0.0 || !f.is_finite() {
            return None;
        }
        Some(Eval {
            f,
            cos: wi.z.abs(),
            pdf: self.bsdf.pdf(self.wo, wi),
            pdf_rev: self.bsdf.pdf(wi, self.wo),
        })
    }
}

/// pbrt-v4's correction of importance transport for shading normals (Veach 1997, 5.3):
/// `|wo.ns| |wi.ng| / (|wo.ng| |wi.ns|)`.
fn shading_correction(wo: Vec3, wi: Vec3, ns: Vec3, ng: Vec3) -> f32 {
    let den = wo.dot(ng).abs() * wi.dot(ns).abs();
    if den == 0.0 {
        return 0.0;
    }
    wo.dot(ns).abs() * wi.dot(ng).abs() / den
}

/// Russian roulette for a subpath about to take its bounce `bounce` with throughput `beta`
/// (`u` uniform in [0, 1)): the path tracer's rule (`path::roulette`) on the
/// throughput relative to the subpath's start (`beta_scale`): none for the first
/// [`RR_MIN_BOUNCES`] bounces, then survival with probability `min(1, max(beta) beta_scale)`,
/// dividing `beta` by it. `false` when the subpath ends. The MIS weights leave the survival
/// probability out (as pbrt-v4's bdpt does): every technique weighs a path by the same
/// densities, so the weights still sum to one.
fn roulette(beta: &mut Vec3, beta_scale: f32, bounce: u32, u: f32) -> bool {
    if bounce > RR_MIN_BOUNCES {
        let survive = beta.max_element() * beta_scale;
        if survive < 1.0 {
            if u >= survive {
                return false;
            }
            *beta /= survive;
        }
    }
    beta.max_element() > 0.0 && beta.is_finite()
}

/// A light vertex's film contributions: `(raster position, value, component)`.
type Splat = (Vec2, Vec3, Component);

/// What one chunk of light subpaths leaves behind.
#[derive(Default)]
struct ChunkOut {
    vertices: Vec<LightVertex>,
    /// Per subpath, the end of its vertices in `vertices` (relative to the chunk).
    ends: Vec<u32>,
    splats: Vec<Splat>,
    tally: Tally,
}

/// The techniques whose shares of the image `--stats` reports, in [`Tally::sums`]' order.
const TECHNIQUES: [&str; 5] = [
    "emission hit",
    "light samples",
    "connections",
    "merges",
    "light tracing",
];

/// What each technique added (the mean of RGB, summed over samples) and how often merging
/// found a light vertex; summed in a fixed order, so the report is deterministic too.
#[derive(Clone, Copy, Debug, Default)]
struct Tally {
    sums: [f64; 5],
    merged: u64,
    /// Shadow rays cast by each technique (same order as `sums`; emission hits cast none).
    rays: [u64; 5],
    /// Camera rays and the camera subpaths' bounce rays, counted here and added to the
    /// render's shared counters once per iteration (an atomic add per ray, contended by
    /// every thread, was 5% of vcm's time).
    camera_rays: u64,
    secondary_rays: u64,
}

impl Tally {
    fn add(&mut self, technique: usize, v: Vec3) {
        self.sums[technique] += ((v.x + v.y + v.z) / 3.0) as f64;
    }

    fn absorb(&mut self, o: &Tally) {
        for (a, b) in self.sums.iter_mut().zip(o.sums) {
            *a += b;
        }
        self.merged += o.merged;
        for (a, b) in self.rays.iter_mut().zip(o.rays) {
            *a += b;
        }
        self.camera_rays += o.camera_rays;
        self.secondary_rays += o.secondary_rays;
    }

    /// Adds this tally's rays to the render's counters.
    fn count_rays(&self, c: &super::Counters) {
        c.camera_rays.fetch_add(self.camera_rays, Ordering::Relaxed);
        c.secondary_rays
            .fetch_add(self.secondary_rays, Ordering::Relaxed);
        c.shadow_rays
            .fetch_add(self.rays.iter().sum(), Ordering::Relaxed);
    }
}

/// The image of [`render`] and its report.
pub struct Rendered {
    /// The crop window's pixels in row-major order.
    pub pixels: Vec<Radiance>,
    /// Lines for the statistics: the radii, light vertices, each technique's share, times.
    pub notes: Vec<String>,
}

/// Renders the crop window's pixels with `technique`: `ctx.settings.spp` iterations, each a
/// light subpath per pixel and a camera subpath per pixel; returns the pixels' means in
/// row-major order of the crop window. `progress(done, total)` after each iteration.
pub fn render(
    ctx: &RenderContext,
    technique: Technique,
    progress: &dyn super::Observer,
) -> Rendered {
    let s = &ctx.settings;
    let [bx0, bx1, by0, by1] = s.pixel_bounds();
    let (w, h) = ((bx1 - bx0) as usize, (by1 - by0) as usize);
    let n = w * h;
    // Light subpaths per iteration; camera subpath k connects to light subpath k mod m.
    let fraction = light_fraction(ctx.scene, ctx.accel, ctx.lights, &ctx.settings, technique);
    let m = ((n as f64 * fraction as f64).ceil() as usize).clamp(1, n);
    let iterations = s.spp.max(1);
    let mut sum = vec![Radiance::default(); n];
    let r0 = initial_radius(ctx).max(1e-7);
    let aim = light_aim(ctx);
    let mut tally = Tally::default();
    let (mut light_s, mut camera_s, mut stored, mut radii) = (0.0, 0.0, 0u64, (0.0f32, 0.0f32));
    let mut done = 0u32;
    // The film of one iteration, reused by the next.
    let mut film = vec![Radiance::default(); n];
    for it in 0..iterations {
        if crate::interrupt::requested().is_some() {
            break;
        }
        let k = s.vcm.first.saturating_add(it + 1) as f32;
        let radius = r0 / k.powf(0.5 * (1.0 - s.vcm.alpha));
        let wt = Weights {
            aim,
            ..Weights::new(
                technique,
                radius.max(1e-7),
                m,
                s.max_depth,
                s.vcm.all_merges,
            )
        };
        radii = (if it == 0 { radius } else { radii.0 }, radius);
        let t0 = std::time::Instant::now();
        // Light subpaths, chunk by chunk in parallel.
        let chunks = trace_lights(ctx, &wt, m, it);
        film.fill(Radiance::default());
        for c in &chunks {
            for &(p, v, comp) in &c.splats {
                splat(ctx, &mut film, (bx0, by0, w, h), p, v, comp);
                tally.add(4, v);
            }
            tally.absorb(&c.tally);
        }
        let store = Store { chunks };
        stored += store.len() as u64;
        light_s += t0.elapsed().as_secs_f64();
        let t1 = std::time::Instant::now();
        // Built by the first merge that needs it (none may: see `merges_at`).
        let grid = std::sync::OnceLock::new();
        let grid = wt.use_vm.then_some(Merging {
            store: &store,
            grid: &grid,
            radius,
        });
        if !wt.light_only {
            // Each row adds into its own pixels; the rows' tallies are summed in row order.
            let rows: Vec<Tally> = film
                .par_chunks_mut(w)
                .enumerate()
                .map(|(y, row)| {
                    let mut t = Tally::default();
                    for (x, px) in row.iter_mut().enumerate() {
                        let own = store.own((y * w + x) % m);
                        let p = (bx0 + x as u32, by0 + y as u32);
                        *px += trace_camera(ctx, &wt, p, it, own, grid.as_ref(), &mut t);
                    }
                    t
                })
                .collect();
            for t in &rows {
                tally.absorb(t);
            }
        }
        camera_s += t1.elapsed().as_secs_f64();
        for (acc, f) in sum.iter_mut().zip(&film) {
            *acc += *f;
        }
        done += 1;
        progress.tile_done(it as u64 + 1, iterations as u64);
    }
    tally.count_rays(&ctx.counters);
    let scale = 1.0 / iterations as f32;
    let total: f64 = tally.sums.iter().sum::<f64>().max(f64::MIN_POSITIVE);
    let shares: Vec<String> = TECHNIQUES
        .iter()
        .zip(tally.sums)
        .map(|(name, v)| format!("{name} {:.1}%", 100.0 * v / total))
        .collect();
    let paths = (n as u64 * done.max(1) as u64) as f64;
    let mut notes = vec![format!(
        "{technique:?}: {done} iterations of {m} light ({:.3} of the pixels) and {n} camera \
         subpaths; {:.2} light vertices kept per light subpath; light subpaths {light_s:.2} s, \
         camera subpaths {camera_s:.2} s",
        m as f64 / n as f64,
        stored as f64 / (m as f64 * done.max(1) as f64)
    )];
    notes.push(format!(
        "{technique:?}: share of the image: {}",
        shares.join(", ")
    ));
    notes.push(format!(
        "{technique:?}: shadow rays per subpath: light samples {:.2}, connections {:.2}, \
         light tracing {:.2}",
        tally.rays[1] as f64 / paths,
        tally.rays[2] as f64 / paths,
        tally.rays[4] as f64 / paths
    ));
    if let Some(a) = aim {
        notes.push(format!(
            "{technique:?}: distant and infinite lights aim {:.0}% of their light subpaths at the \
             sphere of radius {:.3} around ({:.3}, {:.3}, {:.3}) that the camera sees",
            100.0 * a.share,
            a.radius,
            a.center.x,
            a.center.y,
            a.center.z
        ));
    }
    if technique == Technique::Vcm {
        notes.push(format!(
            "Vcm: merge radius {:.4} -> {:.4} (scene units), {:.2} light vertices merged per \
             camera subpath",
            radii.0,
            radii.1,
            tally.merged as f64 / paths
        ));
    }
    Rendered {
        pixels: sum.iter().map(|r| *r * scale).collect(),
        notes,
    }
}

/// The initial merge radius in scene units (see [`MergeRadius`]).
fn initial_radius(ctx: &RenderContext) -> f32 {
    let (_, scene_radius) = ctx.lights.scene_sphere();
    match ctx.settings.vcm.radius {
        MergeRadius::Scene(f) => f * scene_radius,
        MergeRadius::Pixels(px) => px * pixel_footprint(ctx).unwrap_or(1e-3 * scene_radius),
    }
}

/// The median width of a pixel where the camera's rays through a 32x32 grid of the image
/// first hit a surface (distance times the pixel's angular width); `None` when none hits.
fn pixel_footprint(ctx: &RenderContext) -> Option<f32> {
    const GRID: u32 = 32;
    let (w, h) = (ctx.settings.width as f32, ctx.settings.height as f32);
    let mut widths: Vec<f32> = (0..GRID * GRID)
        .filter_map(|i| {
            let p = Vec2::new(
                ((i % GRID) as f32 + 0.5) / GRID as f32 * w,
                ((i / GRID) as f32 + 0.5) / GRID as f32 * h,
            );
            let ray = ctx.camera.generate_ray(p);
            let hit = ctx.accel.intersect(RayKind::Camera, &ray)?;
            let width = ctx.camera.pixel_width(ray.d, hit.t * ray.d.length());
            (width.is_finite() && width > 0.0).then_some(width)
        })
        .collect();
    if widths.is_empty() {
        return None;
    }
    widths.sort_by(f32::total_cmp);
    Some(widths[widths.len() / 2])
}

/// Light subpaths a pilot trace follows to measure the vertices kept per subpath.
pub const PILOT_SUBPATHS: usize = 8192;

/// Where the distant and infinite lights aim their light subpaths: the photon tracer's
/// sphere around what the camera sees ([`crate::photon::aim::region_of_interest`]; off with
/// `--aimed-photons=false`), `None` without such lights or when the camera sees most of the
/// scene.
fn light_aim(ctx: &RenderContext) -> Option<crate::light::Aim> {
    if !ctx.settings.photon.trace.aimed || !ctx.lights.has_distant_or_infinite() {
        return None;
    }
    crate::photon::aim::region_of_interest(ctx.scene, ctx.accel, ctx.lights.scene_sphere()).map(
        |a| crate::light::Aim {
            share: LIGHT_SHARE,
            ..a
        },
    )
}

/// The share of a distant or infinite light's light subpaths aimed at the camera's region
/// (the photon tracer aims [`crate::photon::aim::SHARE`] of its photons). Classroom, 128 px,
/// vcm against pbrt-v4's reference, relMSE (trimmed of the worst 0.1% of pixels), 10 s,
/// seeds 2-5: share 0.5: 0.097 / 0.082 / 0.079 / 0.078 (0.067-0.070); 0.75: 0.084 / 0.101 /
/// 0.111 / 0.201 (0.052-0.061); 0.95: 0.077 / 0.070 / 0.076 / 0.063 (0.055-0.062); 30 s,
/// seeds 0 / 1: 0.75: 0.030 / 0.955 (one pixel), 0.95: 0.046 / 0.029.
const LIGHT_SHARE: f32 = 0.95;

/// The light vertices `technique` keeps per light subpath, measured on [`PILOT_SUBPATHS`]
/// subpaths of their own seed (what the memory model multiplies the image's pixels by).
/// Runs on the current rayon pool.
pub fn pilot(
    scene: &crate::scene::Scene,
    accel: &crate::accel::Accel,
    settings: &super::RenderSettings,
    technique: Technique,
) -> f64 {
    let lights = scene.emitters();
    let mut s = settings.clone();
    s.seed = crate::sampling::hash(&[settings.seed, 0x0070_696c_6f74]);
    let ctx = RenderContext::new(scene, accel, &lights, s);
    let (_, radius) = lights.scene_sphere();
    let all = settings.vcm.all_merges;
    let wt = Weights {
        aim: light_aim(&ctx),
        ..Weights::new(
            technique,
            radius * 1e-3,
            PILOT_SUBPATHS,
            settings.max_depth,
            all,
        )
    };
    let kept: usize = (0..PILOT_SUBPATHS.div_ceil(CHUNK))
        .into_par_iter()
        .map(|c| {
            let mut out = ChunkOut::default();
            for k in c * CHUNK..((c + 1) * CHUNK).min(PILOT_SUBPATHS) {
                trace_light(&ctx, &wt, k as u64, 0, &mut out);
            }
            out.vertices.len()
        })
        .sum();
    // Per pixel: the render traces a fraction of a light subpath per pixel.
    let fraction = light_fraction(scene, accel, &lights, settings, technique) as f64;
    fraction * kept as f64 / PILOT_SUBPATHS as f64
}

/// Camera subpaths (and as many light subpaths) of the pilot that [`light_fraction`] runs.
const SHARE_PILOT_PIXELS: usize = 4096;

/// Light subpaths per pixel are this many times the share of the image that the light
/// subpaths' techniques carry (light tracing, connections, merges), within
/// [[`MIN_LIGHT_FRACTION`], 1].
const LIGHT_SHARE_GAIN: f64 = 2.0;
const MIN_LIGHT_FRACTION: f64 = 1.0 / 16.0;

/// Light subpaths per iteration as a fraction of the pixels: `--light-paths` if given,
/// 1 for `lighttracer` and `bpm` (their light subpaths are everything), else chosen by a
/// pilot, a VCM iteration of [`SHARE_PILOT_PIXELS`] camera subpaths spread over the image
/// and as many light subpaths (weighted as the full render's), as [`LIGHT_SHARE_GAIN`]
/// times the share of its image that light tracing, connections and merges carry.
/// Every light subpath costs as much as a camera subpath whether its techniques count or
/// not: material-testball (a ball under a uniform sky, which BSDF sampling takes) gets
/// none of its image from them, dragon 2.5% (a diffuse scene under a distant light, whose
/// light samples are exact up to visibility), the Cornell box 19%, veach-bidir most.
/// The pilot's seed is fixed, so every pass of a render and its memory estimate agree.
pub fn light_fraction(
    scene: &crate::scene::Scene,
    accel: &crate::accel::Accel,
    lights: &crate::light::Lights,
    settings: &super::RenderSettings,
    technique: Technique,
) -> f32 {
    if let Some(f) = settings.vcm.light_paths {
        return f;
    }
    if !matches!(technique, Technique::Vcm | Technique::Bdpt) {
        return 1.0;
    }
    let mut s = settings.clone();
    s.seed = crate::sampling::hash(&[0x7368_6172_6520_7069]);
    s.spp = 1;
    let ctx = RenderContext::new(scene, accel, lights, s);
    let [bx0, bx1, by0, by1] = ctx.settings.pixel_bounds();
    let w = (bx1 - bx0) as usize;
    let n = w * (by1 - by0) as usize;
    let p = n.min(SHARE_PILOT_PIXELS);
    if p == 0 {
        return 1.0;
    }
    let r0 = initial_radius(&ctx).max(1e-7);
    let mut wt = Weights {
        aim: light_aim(&ctx),
        ..Weights::new(
            technique,
            r0,
            n,
            ctx.settings.max_depth,
            ctx.settings.vcm.all_merges,
        )
    };
    // Merges find the vertices of p light subpaths, not of n.
    wt.vm_norm = 1.0 / (std::f32::consts::PI * r0 * r0 * p as f32);
    let chunks = trace_lights(&ctx, &wt, p, 0);
    // Splats divide by n light subpaths and camera subpaths cover p pixels: over p light
    // subpaths, both sums are p / n of the full render's.
    let mut tally = Tally::default();
    for c in &chunks {
        for &(_, v, _) in &c.splats {
            tally.add(4, v);
        }
    }
    let store = Store { chunks };
    let grid = std::sync::OnceLock::new();
    let merging = wt.use_vm.then_some(Merging {
        store: &store,
        grid: &grid,
        radius: r0,
    });
    let tallies: Vec<Tally> = (0..p)
        .into_par_iter()
        .map(|j| {
            let k = j * n / p;
            let px = (bx0 + (k % w) as u32, by0 + (k / w) as u32);
            let mut t = Tally::default();
            trace_camera(&ctx, &wt, px, 0, store.own(j), merging.as_ref(), &mut t);
            t
        })
        .collect();
    for t in &tallies {
        tally.absorb(t);
    }
    let total: f64 = tally.sums.iter().sum();
    if !(total > 0.0 && total.is_finite()) {
        return 1.0;
    }
    let share = (tally.sums[2] + tally.sums[3] + tally.sums[4]) / total;
    (LIGHT_SHARE_GAIN * share).clamp(MIN_LIGHT_FRACTION, 1.0) as f32
}

/// Adds `v` at continuous raster position `p` to the pixels whose filter covers it, each
/// weighted by the filter's density there.
fn splat(
    ctx: &RenderContext,
    film: &mut [Radiance],
    (bx0, by0, w, h): (u32, u32, usize, usize),
    p: Vec2,
    v: Vec3,
    comp: Component,
) {
    let r = ctx.filter.radius();
    let x0 = (p.x - r.x - 0.5).ceil().max(bx0 as f32) as i64;
    let x1 = (p.x + r.x - 0.5).floor() as i64;
    let y0 = (p.y - r.y - 0.5).ceil().max(by0 as f32) as i64;
    let y1 = (p.y + r.y - 0.5).floor() as i64;
    for y in y0..=y1.min(by0 as i64 + h as i64 - 1) {
        for x in x0..=x1.min(bx0 as i64 + w as i64 - 1) {
            let d = p - Vec2::new(x as f32 + 0.5, y as f32 + 0.5);
            let wgt = ctx.filter.density(d);
            if wgt > 0.0 {
                let k = (y as usize - by0 as usize) * w + (x as usize - bx0 as usize);
                film[k][comp] += v * wgt;
            }
        }
    }
}

/// The component a path with `bounces` scattering events belongs to.
fn component(bounces: u32) -> Component {
    if bounces <= 1 {
        Component::Direct
    } else {
        Component::Indirect
    }
}

/// The next hit of `ray` and the interaction there, with the BSDF.
fn next_vertex<'s>(
    ctx: &'s RenderContext,
    kind: RayKind,
    ray: &Ray,
) -> Option<(Hit, SurfaceInteraction<'s>, Bsdf)> {
    let hit = ctx.accel.intersect(kind, ray)?;
    let mut si = SurfaceInteraction::new(ctx.scene, &hit, ray);
    let bsdf = si.bsdf(
        ctx.scene,
        ctx.settings.footprint(),
        crate::spectrum::Lambda::Rgb,
    );
    Some((hit, si, bsdf))
}

/// Whether the segment between two surface points (each with its error bound and geometric
/// normal) is free.
fn visible(ctx: &RenderContext, a: (Vec3, Vec3, Vec3), b: (Vec3, Vec3, Vec3)) -> bool {
    let side = |n: Vec3, d: Vec3| if n.dot(d) >= 0.0 { n } else { -n };
    let d = b.0 - a.0;
    let o = spawn_origin(a.0, a.1, side(a.2, d));
    let t = if b.2 == Vec3::ZERO {
        b.0
    } else {
        spawn_origin(b.0, b.1, side(b.2, -d))
    };
    !ctx.accel
        .occluded(RayKind::Shadow, &Ray::segment(o, t - o, 1.0 - 1e-4))
}

/// Continues a subpath by sampling the BSDF at `v` (the technical report's
/// `SampleScattering`): updates the throughput and the partial sums; `false` when it ends.
fn scatter(
    path: &mut SubPath,
    v: &Vertex,
    wt: &Weights,
    sampler: &mut Sampler,
    mode: TransportMode,
) -> bool {
    let uc = sampler.next_1d();
    let u = sampler.next_2d();
    let Some(s) = v.bsdf.sample(v.wo, uc, u, mode) else {
        return false;
    };
    // The roulette's number: a hash of the sample, so that it needs no dimension of its own.
    let u_rr = crate::sampling::to_unit(crate::sampling::hash(&[
        uc.to_bits() as u64,
        u.x.to_bits() as u64,
        u.y.to_bits() as u64,
        path.len as u64,
    ]));
    let wi_world = v.frame.to_world(s.wi);
    let cos_out = s.wi.z.abs();
    let mut f = s.f.rgb();
    if mode == TransportMode::Importance {
        f *= shading_correction(v.wo_world, wi_world, v.frame.n, v.ng);
    }
    let mut beta = path.beta * f * (cos_out / s.pdf);
    if s.specular && s.transmission && mode == TransportMode::Radiance {
        // Radiance scales by 1 / eta^2 into glass: the roulette must not end paths for it.
        path.beta_scale *= s.eta * s.eta;
    }
    if !roulette(&mut beta, path.beta_scale, path.len, u_rr) {
        return false;
    }
    let specular_only = v.bsdf.flags().is_specular_only();
    if wt.sds && mode == TransportMode::Importance {
        // The merge at the previous light vertex exists when this surface is purely
        // specular (this surface is then its neighbour towards the camera).
        if specular_only {
            path.dvc += path.pending_vc;
            path.dvm += path.pending_vm;
        }
        (path.pending_vc, path.pending_vm) = (0.0, 0.0);
    }
    // Merging at this vertex: always without the SDS rule; under it, on the camera side
    // when the previous surface is purely specular, on the light side decided later.
    let merge_here = match (wt.sds, mode) {
        (false, _) => 1.0,
        (true, TransportMode::Radiance) if path.after_specular => 1.0,
        (true, _) => 0.0,
    };
    if s.specular {
        path.dvcm = 0.0;
        path.dvc *= cos_out;
        path.dvm *= cos_out;
    } else {
        let pdf = v.bsdf.mis_pdf(v.wo, &s);
        let pdf_rev = v.bsdf.pdf(s.wi, v.wo);
        if pdf <= 0.0 {
            return false;
        }
        let k = cos_out / pdf;
        if mode == TransportMode::Radiance && path.len == 1 {
            // dvc is 0 at the camera's first vertex and dvcm is light tracing's term.
            let lt = wt.direct_lt(&v.bsdf);
            path.direct_dvc = k * (path.dvcm * lt + wt.vm_factor * merge_here);
        }
        path.dvc = k * (path.dvc * pdf_rev + path.dvcm + wt.vm_factor * merge_here);
        path.dvm = k * (path.dvm * pdf_rev + path.dvcm * wt.vc_factor + merge_here);
        if wt.sds && mode == TransportMode::Importance {
            (path.pending_vc, path.pending_vm) = (k * wt.vm_factor, k);
        }
        path.dvcm = 1.0 / pdf;
        path.specular = false;
    }
    path.after_specular = specular_only;
    path.beta = beta;
    path.ray.d = wi_world;
    path.len += 1;
    true
}

/// Finishes the partial sums at a new vertex: the squared distance of the segment reaching
/// it and the cosine there.
fn arrive(path: &mut SubPath, hit_t: f32, cos_in: f32) {
    if path.len > 1 || path.finite {
        path.dvcm *= (hit_t * path.ray.d.length()).powi(2);
    }
    let c = cos_in.max(1e-8);
    path.dvcm /= c;
    path.dvc /= c;
    path.dvm /= c;
    path.direct_dvc /= c;
    path.pending_vc /= c;
    path.pending_vm /= c;
}

/// Traces light subpaths `0..m` of iteration `it`, chunk by chunk in parallel (the render's
/// and the pilot's).
fn trace_lights(ctx: &RenderContext, wt: &Weights, m: usize, it: u32) -> Vec<ChunkOut> {
    (0..m.div_ceil(CHUNK))
        .into_par_iter()
        .map(|c| {
            let mut out = ChunkOut::default();
            for k in c * CHUNK..((c + 1) * CHUNK).min(m) {
                trace_light(ctx, wt, k as u64, it, &mut out);
                out.ends.push(out.vertices.len() as u32);
            }
            // Exact sizes: every chunk is alive until the iteration's end.
            out.vertices.shrink_to_fit();
            out.splats.shrink_to_fit();
            out
        })
        .collect()
}

/// Traces light subpath `k` of iteration `it`: keeps its non-delta vertices in `out` and
/// splats their connections to the camera.
fn trace_light(ctx: &RenderContext, wt: &Weights, k: u64, it: u32, out: &mut ChunkOut) {
    let s = &ctx.settings;
    let mut sampler = Sampler::new(s.pattern, s.seed ^ LIGHT_STREAM, k, it, s.spp);
    let (u_sel, u_pos, u_dir) = (sampler.next_1d(), sampler.next_2d(), sampler.next_2d());
    let lights = ctx.lights;
    let Some((i, pmf)) = lights.pick(u_sel) else {
        return;
    };
    let Some(e) = lights.emit_aimed(&ctx.scene.meshes, i, u_pos, u_dir, wt.aim.as_ref()) else {
        return;
    };
    let (pdf_pos, pdf_dir) = lights.emit_pdfs(i, e.p, e.n, e.dir, wt.aim.as_ref());
    if pdf_pos <= 0.0 || pdf_dir <= 0.0 {
        return;
    }
    let emission_pdf = pmf * pdf_pos * pdf_dir;
    let finite = lights.is_finite(i);
    let point = lights.is_delta_position(i);
    let delta = point || lights.is_delta_direction(i);
    // The density of the light's first vertex as a light sample from the subpath's first
    // surface picks it ([`nee_pmf_area`]): known once that surface is, below.
    let cos_light = if !finite || point {
        1.0
    } else {
        e.n.dot(e.dir).abs()
    };
    if wt.light_only && finite && !point {
        splat_emitter(ctx, wt, i, pmf * pdf_pos, &e, lens_u(s.seed, k, it, 0), out);
    }
    let dvc = if delta { 0.0 } else { cos_light / emission_pdf };
    let o = if e.n == Vec3::ZERO {
        e.p
    } else {
        spawn_origin(e.p, e.err, if e.n.dot(e.dir) >= 0.0 { e.n } else { -e.n })
    };
    let mut path = SubPath {
        ray: Ray::new(o, e.dir),
        beta: e.flux / pmf,
        len: 1,
        beta_scale: 1.0 / (e.flux / pmf).max_element(),
        specular: true,
        finite,
        dvcm: 0.0,
        dvc,
        dvm: dvc * wt.vc_factor,
        prev: Receiver::in_medium(e.p),
        direct_dvc: 0.0,
        after_specular: false,
        pending_vc: 0.0,
        pending_vm: 0.0,
    };
    while let Some((hit, si, bsdf)) = next_vertex(ctx, RayKind::Photon, &path.ray) {
        if path.len == 1 {
            let r = si.receiver().sky_by_bsdf();
            path.dvcm = nee_pmf_area(ctx, i, r, (e.p, e.n), pdf_dir) / emission_pdf;
        }
        arrive(&mut path, hit.t, si.wo.z.abs());
        path.beta *= crate::accel::transmittance(ctx.scene, Some(&hit), &path.ray);
        let v = Vertex {
            ng: si.ng,
            frame: si.frame,
            wo: si.wo,
            wo_world: si.wo_world,
            bsdf,
        };
        // Connected to the camera or another vertex, or merged, this vertex makes a path of
        // at least one more segment.
        if bsdf.flags().has_non_specular() && path.len < wt.max_len {
            let lv = LightVertex {
                p: si.p,
                err: si.err,
                ng: si.ng,
                frame: si.frame,
                wo: si.wo,
                wo_world: si.wo_world,
                bsdf,
                beta: path.beta,
                len: path.len,
                dvcm: path.dvcm,
                dvc: path.dvc,
                dvm: path.dvm,
            };
            if wt.use_vc || wt.use_vm {
                out.vertices.push(lv);
            }
            if wt.use_vc || wt.light_only {
                connect_to_camera(ctx, wt, &lv, lens_u(s.seed, k, it, path.len), out);
            }
        }
        if path.len + 2 > wt.max_len {
            break;
        }
        sampler.set_dimension(5 + (path.len - 1) * LIGHT_DIMS_PER_VERTEX);
        if !scatter(&mut path, &v, wt, &mut sampler, TransportMode::Importance) {
            break;
        }
        path.ray = si.spawn_ray(path.ray.d);
    }
}

/// The lens sample of the camera connection of light subpath `k`'s vertex after `len`
/// segments in iteration `it` (a hash: the subpath's own dimensions stay as they are).
fn lens_u(seed: u64, k: u64, it: u32, len: u32) -> Vec2 {
    use crate::sampling::{hash, to_unit};
    let h = |d: u64| to_unit(hash(&[seed, LIGHT_STREAM, k, it as u64, len as u64, d]));
    Vec2::new(h(0), h(1))
}

/// The light's own point seen by the camera (light tracing only): `pdf_a` is the density of
/// the point (light choice included).
fn splat_emitter(
    ctx: &RenderContext,
    wt: &Weights,
    i: usize,
    pdf_a: f32,
    e: &crate::light::Emission,
    u_lens: Vec2,
    out: &mut ChunkOut,
) {
    let Some((raster, to_area, cam)) =
        ctx.camera
            .project_through_lens(e.p, u_lens, ctx.filter.radius())
    else {
        return;
    };
    let dir = (cam - e.p).normalize();
    let le = ctx.lights.le(i, e.n, dir);
    if le.max_element() <= 0.0 {
        return;
    }
    let to_surface = to_area * e.n.dot(dir).abs();
    let v = le * (to_surface / (pdf_a * wt.n_light));
    if !v.is_finite() {
        return;
    }
    out.tally.rays[4] += 1;
    if visible(ctx, (e.p, e.err, e.n), (cam, Vec3::ZERO, Vec3::ZERO)) {
        out.splats.push((raster, v, Component::Direct));
    }
}

/// Connects light vertex `lv` to the camera (the report's `ConnectToCamera`).
fn connect_to_camera(
    ctx: &RenderContext,
    wt: &Weights,
    lv: &LightVertex,
    u_lens: Vec2,
    out: &mut ChunkOut,
) {
    // Light tracing's density scale in the weights (direct light: `DIRECT_LIGHT_TRACING`).
    let lt = if lv.len == 1 {
        wt.direct_lt(&lv.bsdf)
    } else {
        1.0
    };
    if lt <= 0.0 {
        return;
    }
    let Some((raster, to_area, cam)) =
        ctx.camera
            .project_through_lens(lv.p, u_lens, ctx.filter.radius())
    else {
        return;
    };
    let dir = (cam - lv.p).normalize();
    let Some(ev) = Vertex::of(lv).eval(dir, TransportMode::Importance) else {
        return;
    };
    let to_surface = to_area * ev.cos;
    let w = if wt.light_only {
        1.0
    } else {
        let vm = if wt.sds { 0.0 } else { wt.vm_factor };
        let w_light = (to_surface / wt.n_light) * (vm + lv.dvcm + lv.dvc * ev.pdf_rev);
        lt / (lt + w_light)
    };
    let v = lv.beta * ev.f * (w * to_surface / wt.n_light);
    if !v.is_finite() || v.max_element() <= 0.0 {
        return;
    }
    out.tally.rays[4] += 1;
    if visible(ctx, (lv.p, lv.err, lv.ng), (cam, Vec3::ZERO, Vec3::ZERO)) {
        out.splats.push((raster, v, component(lv.len)));
    }
}

/// Traces the camera subpath of pixel `(x, y)` in iteration `it`: emission it hits, light
/// samples, connections to `own` (its light subpath's vertices) and merges.
fn trace_camera(
    ctx: &RenderContext,
    wt: &Weights,
    (x, y): (u32, u32),
    it: u32,
    own: &[LightVertex],
    merging: Option<&Merging>,
    tally: &mut Tally,
) -> Radiance {
    let mut out = Radiance::default();
    let (ray, mut sampler) = super::camera_sample(ctx, x, y, it);
    tally.camera_rays += 1;
    let cos = ctx.camera.cos_to_axis(ray.d.normalize());
    if cos <= 0.0 {
        return out;
    }
    // Per unit solid angle (perspective) or per unit area across the ray (orthographic: the
    // first segment's length does not count, as after a distant light).
    let (density, finite) = ctx.camera.ray_density(ray.d.normalize());
    let mut path = SubPath {
        ray,
        beta: Vec3::ONE,
        len: 1,
        beta_scale: 1.0,
        specular: true,
        finite,
        dvcm: wt.n_light / density,
        dvc: 0.0,
        dvm: 0.0,
        prev: Receiver::in_medium(ray.o),
        direct_dvc: 0.0,
        after_specular: false,
        pending_vc: 0.0,
        pending_vm: 0.0,
    };
    let base = super::wavefront::CAMERA_DIMS;
    loop {
        let kind = if path.len == 1 {
            RayKind::Camera
        } else {
            RayKind::Bounce
        };
        let Some((hit, si, bsdf)) = next_vertex(ctx, kind, &path.ray) else {
            let c = path.beta * escaped(ctx, wt, &path);
            out[component(path.len - 1)] += c;
            tally.add(0, c);
            break;
        };
        arrive(&mut path, hit.t, si.wo.z.abs());
        path.beta *= crate::accel::transmittance(ctx.scene, Some(&hit), &path.ray);
        if let Some(li) = si.area_light() {
            let c = path.beta * emitted(ctx, wt, &path, li, &si);
            out[component(path.len - 1)] += c;
            tally.add(0, c);
        }
        if path.len >= wt.max_len {
            break;
        }
        let v = Vertex {
            ng: si.ng,
            frame: si.frame,
            wo: si.wo,
            wo_world: si.wo_world,
            bsdf,
        };
        sampler.set_dimension(base + (path.len - 1) * CAMERA_DIMS_PER_VERTEX);
        if bsdf.flags().has_non_specular() {
            if wt.use_vc {
                let c = path.beta * light_sample(ctx, wt, &path, &v, &si, &mut sampler, tally);
                out[component(path.len)] += c;
                tally.add(1, c);
                for lv in own {
                    if lv.len + path.len + 1 > wt.max_len {
                        break;
                    }
                    let c = path.beta * lv.beta * connect(ctx, wt, &path, &v, &si, lv, tally);
                    out[Component::Indirect] += c;
                    tally.add(2, c);
                }
            }
            if let (Some(m), true) = (merging, merges_at(wt, &path)) {
                let (c, found) = merge(wt, &path, &v, si.p, m);
                let c = path.beta * c * wt.vm_norm;
                out[component(path.len)] += c;
                tally.add(3, c);
                tally.merged += found;
            }
        }
        sampler.set_dimension(base + (path.len - 1) * CAMERA_DIMS_PER_VERTEX + 3);
        if !scatter(&mut path, &v, wt, &mut sampler, TransportMode::Radiance) {
            break;
        }
        path.prev = si.receiver().sky_by_bsdf();
        path.ray = si.spawn_ray(path.ray.d);
        tally.secondary_rays += 1;
    }
    out
}

/// Radiance of area light `li` that a camera subpath hits, MIS-weighted (the report's
/// `GetLightRadiance`).
fn emitted(
    ctx: &RenderContext,
    wt: &Weights,
    path: &SubPath,
    li: usize,
    si: &SurfaceInteraction,
) -> Vec3 {
    let le = ctx.lights.le(li, si.ng, si.wo_world);
    if le.max_element() <= 0.0 || path.len == 1 {
        return le;
    }
    if !wt.use_vc {
        // Merging alone: paths of delta bounces only get here, the rest is merged.
        return if path.specular { le } else { Vec3::ZERO };
    }
    let (pdf_pos, pdf_dir) = ctx.lights.emit_pdfs(li, si.p, si.ng, si.wo_world, None);
    let direct_pdf = nee_pmf_area(ctx, li, path.prev, (si.p, si.ng), pdf_dir);
    let emission_pdf = ctx.lights.selection_pmf(li) * pdf_pos * pdf_dir;
    let w_camera = direct_pdf * path.dvcm + emission_pdf * camera_dvc(path);
    le / (1.0 + w_camera)
}

/// Radiance of the infinite lights along a camera subpath's ray that leaves the scene,
/// MIS-weighted (a uniform sky takes no light samples: its density there is 0).
fn escaped(ctx: &RenderContext, wt: &Weights, path: &SubPath) -> Vec3 {
    if !ctx.lights.has_infinite() {
        return Vec3::ZERO;
    }
    let d = path.ray.d.normalize();
    let disc_pdf = ctx.lights.disc_pdf(-d, path.ray.o, wt.aim.as_ref());
    ctx.lights
        .escaped(path.ray.o, d, Pick::Power, |i, power_pdf| {
            if path.len == 1 {
                1.0
            } else if !wt.use_vc {
                if path.specular {
                    1.0
                } else {
                    0.0
                }
            } else {
                // power_pdf: the light's choice by power (the light subpaths') times the
                // direction's density.
                let sel = ctx.lights.selection_pmf(i);
                let direct_pdf = match sel > 0.0 {
                    true => power_pdf * ctx.lights.pmf_at(path.prev, i) / sel,
                    false => 0.0,
                };
                let emission_pdf = power_pdf * disc_pdf;
                1.0 / (1.0 + direct_pdf * path.dvcm + emission_pdf * camera_dvc(path))
            }
        })
}

/// Next-event estimation at camera vertex `v` (the report's `DirectIllumination`); reads 3
/// dimensions.
fn light_sample(
    ctx: &RenderContext,
    wt: &Weights,
    path: &SubPath,
    v: &Vertex,
    si: &SurfaceInteraction,
    sampler: &mut Sampler,
    tally: &mut Tally,
) -> Vec3 {
    let (u_sel, u) = (sampler.next_1d(), sampler.next_2d());
    let lights = ctx.lights;
    // By importance at this point, as the path tracer picks, uniform skies left to BSDF
    // sampling; a sphere light by its cone.
    let Some((i, pmf)) = lights.pick_at(si.receiver().sky_by_bsdf(), u_sel) else {
        return Vec3::ZERO;
    };
    let Some(s) = lights.sample_chosen(&ctx.scene.meshes, (i, pmf), si.p, u) else {
        return Vec3::ZERO;
    };
    let Some(ev) = v.eval(s.wi, TransportMode::Radiance) else {
        return Vec3::ZERO;
    };
    let d2 = (s.p - si.p).length_squared();
    // The light's own densities without its choice: per solid angle at this point for area
    // and infinite lights, d^2 for point lights (the report's convention), 1 for distant.
    let (direct_pdf_w, cos_at_light) = if lights.is_delta_position(i) {
        (d2, 1.0)
    } else if lights.is_delta_direction(i) {
        (1.0, 1.0)
    } else if !lights.is_finite(i) {
        (s.pdf / pmf, 1.0)
    } else {
        (s.pdf / pmf, s.n.dot(s.wi).abs())
    };
    let w_light = if s.delta { 0.0 } else { ev.pdf / s.pdf };
    // A light without a surface: the light subpath's origin is this vertex's projection.
    let (pdf_pos, pdf_dir) = lights.emit_pdfs(i, si.p, s.n, -s.wi, wt.aim.as_ref());
    // At the camera's first vertex dvcm is light tracing's term (dvc is 0).
    let dvcm = if path.len == 1 {
        path.dvcm * wt.direct_lt(&v.bsdf)
    } else {
        path.dvcm
    };
    // Light subpaths choose the light by power among all lights, light samples without the
    // uniform skies.
    let choice = lights.selection_pmf(i) / pmf;
    let w_camera = (choice * pdf_pos * pdf_dir * ev.cos / (direct_pdf_w * cos_at_light))
        * (camera_vm(wt, path) + dvcm + path.dvc * ev.pdf_rev);
    let w = 1.0 / (w_light + 1.0 + w_camera);
    let c = s.li * ev.f * (w * ev.cos / s.pdf);
    if !c.is_finite() || c.max_element() <= 0.0 {
        return Vec3::ZERO;
    }
    tally.rays[1] += 1;
    if ctx.accel.occluded(RayKind::Shadow, &si.shadow_ray(&s)) {
        return Vec3::ZERO;
    }
    c
}

/// The density (choice included) with which a light sample from receiver `r` picks the
/// point `y` (normal `n`; zero off a surface) of light `i`: per unit area on an area light
/// (its cone's density for a sphere), `dir_pdf` times the choice for an infinite light
/// (`dir_pdf`: the direction's solid-angle density), the choice alone for a delta light.
/// Light samples pick by importance at the receiver ([`crate::light::Lights::pick_at`]) and
/// never pick a uniform sky.
fn nee_pmf_area(
    ctx: &RenderContext,
    i: usize,
    r: Receiver,
    (y, n): (Vec3, Vec3),
    dir_pdf: f32,
) -> f32 {
    let lights = ctx.lights;
    if lights.is_delta_position(i) || lights.is_delta_direction(i) {
        return lights.pmf_at(r, i);
    }
    if !lights.is_finite(i) {
        return lights.pmf_at(r, i) * dir_pdf;
    }
    let d = r.p - y;
    let d2 = d.length_squared();
    if d2 <= 0.0 {
        return 0.0;
    }
    lights.pdf_area(i, r, y, n) * n.dot(d).abs() / (d2 * d2.sqrt())
}

/// The camera subpath's `dvc` as an emission hit weighs by it: after one bounce, with light
/// tracing's term scaled for direct light.
fn camera_dvc(path: &SubPath) -> f32 {
    if path.len == 2 {
        path.direct_dvc
    } else {
        path.dvc
    }
}

/// `eta_VCM` when merging at the camera subpath's current vertex exists, else 0 (see
/// [`merges_at`]).
fn camera_vm(wt: &Weights, path: &SubPath) -> f32 {
    if merges_at(wt, path) {
        wt.vm_factor
    } else {
        0.0
    }
}

/// Whether the camera subpath's current vertex merges.
///
/// VCM merges only where connections cannot reach (unless `--all-merges`): at a vertex whose
/// neighbour towards the camera is a purely specular surface (a caustic seen through glass
/// or in a mirror, paths `L ... D S+ E`-wards of the merge, the specular-diffuse-specular
/// paths no connection samples). Elsewhere bdpt's techniques carry the path alone, so
/// merges add no noise of their own there. The MIS weights count exactly the merges that
/// exist: a camera subpath knows its previous surface when it scatters; a light subpath
/// keeps the merge terms of its last vertex pending until its next surface is known.
/// veach-bidir at 128 px, 30 s, against Tungsten's reference: relMSE 0.0193 with merges at
/// every vertex, 0.0127 / 0.0132 (seeds 0, 1) with this rule; water-caustic unchanged.
fn merges_at(wt: &Weights, path: &SubPath) -> bool {
    !wt.sds || path.after_specular
}

/// Connects camera vertex `v` to light vertex `lv` (the report's `ConnectVertices`); the
/// caller multiplies by both throughputs.
fn connect(
    ctx: &RenderContext,
    wt: &Weights,
    path: &SubPath,
    v: &Vertex,
    si: &SurfaceInteraction,
    lv: &LightVertex,
    tally: &mut Tally,
) -> Vec3 {
    let to = lv.p - si.p;
    let d2 = to.length_squared();
    if d2 <= 0.0 {
        return Vec3::ZERO;
    }
    let dir = to / d2.sqrt();
    let Some(cam) = v.eval(dir, TransportMode::Radiance) else {
        return Vec3::ZERO;
    };
    let Some(light) = Vertex::of(lv).eval(-dir, TransportMode::Importance) else {
        return Vec3::ZERO;
    };
    let g = cam.cos * light.cos / d2;
    let cam_pdf_a = cam.pdf * light.cos / d2;
    let light_pdf_a = light.pdf * cam.cos / d2;
    // Merging at the light vertex would need this (non-delta) camera vertex to be specular.
    let light_vm = if wt.sds { 0.0 } else { wt.vm_factor };
    let w_light = cam_pdf_a * (light_vm + lv.dvcm + lv.dvc * light.pdf_rev);
    let w_camera = light_pdf_a * (camera_vm(wt, path) + path.dvcm + path.dvc * cam.pdf_rev);
    let c = cam.f * light.f * (g / (w_light + 1.0 + w_camera));
    if !c.is_finite() || c.max_element() <= 0.0 {
        return Vec3::ZERO;
    }
    tally.rays[2] += 1;
    if !visible(ctx, (si.p, si.err, si.ng), (lv.p, lv.err, lv.ng)) {
        return Vec3::ZERO;
    }
    c
}

/// The merges of camera vertex `v` at `p` with the light vertices within the radius (the
/// report's range query), before the `1 / (pi r^2 N)` normalisation, and how many light
/// vertices were within the radius.
fn merge(wt: &Weights, path: &SubPath, v: &Vertex, p: Vec3, m: &Merging) -> (Vec3, u64) {
    let (mut sum, mut found) = (Vec3::ZERO, 0);
    let g = m.grid.get_or_init(|| Grid::new(m.store, m.radius));
    g.query(p, |id| {
        let lv = m.store.get(id);
        let d = lv.p - p;
        if d.length_squared() > wt.radius2
            || lv.len + path.len > wt.max_len
            || !on_surface(d, v.ng, lv.ng, m.radius)
        {
            return;
        }
        found += 1;
        let Some(ev) = v.eval(lv.wo_world, TransportMode::Radiance) else {
            return;
        };
        let w_light = lv.dvcm * wt.vc_factor + lv.dvm * ev.pdf;
        // Direct light (both subpaths one segment long): the camera's dvcm is light
        // tracing's term.
        let lt = if path.len == 1 && lv.len == 1 {
            wt.direct_lt(&v.bsdf)
        } else {
            1.0
        };
        let w_camera = path.dvcm * lt * wt.vc_factor + path.dvm * ev.pdf_rev;
        sum += ev.f * lv.beta / (w_light + 1.0 + w_camera);
    });
    (sum, found)
}

/// How far from a camera vertex's tangent plane, as a fraction of the merge radius, a light
/// vertex on a surface of the same orientation is still merged there (see [`on_surface`]).
const MERGE_THICKNESS: f32 = 0.05;

/// Whether a light vertex at offset `d` from a camera vertex (geometric normals `n` there and
/// `n_light` at the light vertex) lies on the camera vertex's surface for merging: within
/// `MERGE_THICKNESS * radius` of its tangent plane, plus what the surface's curvature between
/// the two normals explains (`|d| sin` of their angle: on a sphere of any size the height of
/// a point at chord `d` above the tangent plane is at most that). Without it the merge disc
/// took light vertices from a parallel surface just behind or in front (Bitterli's bathroom2:
/// a wall 0.08 merge radii behind a shadowed panel, seen in a mirror, whose vcm pixels came
/// out 1.9-2.6x the path tracer's), which the MIS weights cannot undo: no other technique
/// makes that path.
fn on_surface(d: Vec3, n: Vec3, n_light: Vec3, radius: f32) -> bool {
    d.dot(n).abs() <= MERGE_THICKNESS * radius + d.length() * n.cross(n_light).length()
}

/// One iteration's light vertices, left in the chunks that traced them (copying 240-byte
/// vertices into one array cost 5% of vcm's time on one thread).
struct Store {
    chunks: Vec<ChunkOut>,
}

impl Store {
    /// The vertices of light subpath `k`.
    fn own(&self, k: usize) -> &[LightVertex] {
        let c = &self.chunks[k / CHUNK];
        let j = k % CHUNK;
        let start = if j == 0 { 0 } else { c.ends[j - 1] as usize };
        &c.vertices[start..c.ends[j] as usize]
    }

    /// The vertex with id `chunk << 32 | index`.
    fn get(&self, id: u64) -> &LightVertex {
        &self.chunks[(id >> 32) as usize].vertices[id as u32 as usize]
    }

    fn len(&self) -> usize {
        self.chunks.iter().map(|c| c.vertices.len()).sum()
    }
}

/// What merging at a camera vertex reads: the light vertices and their grid, built on
/// first use.
struct Merging<'a> {
    store: &'a Store,
    grid: &'a std::sync::OnceLock<Grid>,
    radius: f32,
}

/// A uniform grid of cell size `2r` hashed into as many buckets as there are vertices
/// (the report's hash grid), built by a counting sort so that queries visit vertices in a
/// fixed order.
struct Grid {
    lo: Vec3,
    inv_cell: f32,
    /// Bucket `b` holds `order[starts[b]..starts[b + 1]]` (vertex ids, see [`Store::get`]).
    starts: Vec<u32>,
    order: Vec<u64>,
}

impl Grid {
    fn new(store: &Store, radius: f32) -> Grid {
        let lo = store
            .chunks
            .iter()
            .flat_map(|c| &c.vertices)
            .fold(Vec3::splat(f32::INFINITY), |a, v| a.min(v.p));
        let inv_cell = 1.0 / (2.0 * radius);
        let len = store.len();
        let mut g = Grid {
            lo,
            inv_cell,
            starts: vec![0; len.max(1) + 1],
            order: vec![0; len],
        };
        let keys: Vec<Vec<u32>> = store
            .chunks
            .par_iter()
            .map(|c| {
                c.vertices
                    .iter()
                    .map(|v| g.bucket(g.cell(v.p)) as u32)
                    .collect()
            })
            .collect();
        for &b in keys.iter().flatten() {
            g.starts[b as usize + 1] += 1;
        }
        for b in 0..len.max(1) {
            g.starts[b + 1] += g.starts[b];
        }
        let mut next = g.starts.clone();
        for (c, ks) in keys.iter().enumerate() {
            for (k, &b) in ks.iter().enumerate() {
                g.order[next[b as usize] as usize] = (c as u64) << 32 | k as u64;
                next[b as usize] += 1;
            }
        }
        g
    }

    fn cell(&self, p: Vec3) -> [i64; 3] {
        let c = ((p - self.lo) * self.inv_cell).floor();
        [c.x as i64, c.y as i64, c.z as i64]
    }

    fn bucket(&self, c: [i64; 3]) -> usize {
        let h = (c[0].wrapping_mul(73_856_093))
            ^ (c[1].wrapping_mul(19_349_663))
            ^ (c[2].wrapping_mul(83_492_791));
        (h as u64 % (self.starts.len() as u64 - 1)) as usize
    }

    /// Calls `f` with every vertex of the (up to 8) cells that a sphere of radius `r` about
    /// `p` touches, and possibly others sharing their buckets.
    fn query(&self, p: Vec3, mut f: impl FnMut(u64)) {
        if self.order.is_empty() {
            return;
        }
        // With cells of 2r, the sphere touches the cell of p and its neighbours towards the
        // side of the cell's centre p is nearest to.
        let q = (p - self.lo) * self.inv_cell;
        let c = q.floor();
        let frac = q - c;
        let step = |fr: f32| if fr < 0.5 { -1 } else { 1 };
        let base = [c.x as i64, c.y as i64, c.z as i64];
        let steps = [step(frac.x), step(frac.y), step(frac.z)];
        let mut seen = [usize::MAX; 8];
        for (n, corner) in (0..8u32).enumerate() {
            let cell = [
                base[0] + if corner & 1 != 0 { steps[0] } else { 0 },
                base[1] + if corner & 2 != 0 { steps[1] } else { 0 },
                base[2] + if corner & 4 != 0 { steps[2] } else { 0 },
            ];
            let b = self.bucket(cell);
            if seen[..n].contains(&b) {
                continue;
            }
            seen[n] = b;
            let (s, e) = (self.starts[b] as usize, self.starts[b + 1] as usize);
            for &k in &self.order[s..e] {
                f(k);
            }
        }
    }
}
