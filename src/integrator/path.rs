//! The reference path tracer (`photon render --integrator path`): unbiased unidirectional path
//! tracing with next-event estimation and multiple importance sampling, for validating the
//! photon mapper against the same materials and lights.
//!
//! ```text
//! Integrator "path" "integer maxdepth" [ 5 ]
//! ```
//!
//! Like [`super::direct`], it is traced as a wavefront per tile and sample index: all camera
//! rays of a tile go to the backend as one batch, then all shadow rays of that bounce, then all
//! continuation rays of the next bounce.
//!
//! At every vertex:
//! - emission seen along the ray counts with full weight after the camera or a delta bounce,
//!   and MIS-weighted (power heuristic, [`Lights::pdf_area`](crate::light::Lights::pdf_area)
//!   against the BSDF density) after a non-delta bounce;
//! - on a non-delta BSDF (diffuse, rough conductor), one light sample chosen in proportion to
//!   power (next-event estimation), power-heuristic-weighted against BSDF sampling (full weight
//!   for delta lights);
//! - a BSDF-sampled continuation; after [`RR_MIN_BOUNCES`] bounces, Russian roulette on the
//!   throughput times the refraction scale `eta_scale` (pbrt-v4: survive with probability
//!   `min(1, max_component(beta * eta_scale))`, dividing `beta` by it, so it stays unbiased).
//!   `eta_scale` multiplies in `eta^2` at each delta refraction so that the `1 / eta^2`
//!   radiance scaling inside glass does not make roulette kill paths there.
//!
//! Depth follows pbrt-v4: `maxdepth` is the maximum number of bounces (scattering events); the
//! emission at the vertex reached after `maxdepth` bounces still counts, and light samples are
//! taken only at vertices with fewer than `maxdepth` bounces behind them, so `maxdepth 0` shows
//! only emitters and `maxdepth 1` is direct lighting.
//!
//! Components (see [`Radiance`]): light reaching the camera directly from an emitter, or after
//! exactly one non-delta scattering event at the first hit (its light sample, or its
//! BSDF-sampled ray hitting an emitter), is `direct`; everything else (any path through a delta
//! bounce or with two or more bounces) is `indirect`. The other components stay zero.
//!
//! Randomness: each vertex reads its numbers from fixed dimensions of the pixel sample's
//! [`Sampler`] stream (2 for the pixel filter, then [`DIMS_PER_VERTEX`] per vertex: light
//! choice, light point, lobe choice, direction, roulette), so an image depends only on the
//! scene, seed and settings, never on thread scheduling. The path tracer always takes one light
//! sample per vertex (it ignores `RenderSettings::light_samples`).
use super::{power_heuristic, tile_pixels, RenderContext};
use crate::accel::{Hit, RayQuery};
use crate::bsdf::{Bsdf, TransportMode};
use crate::film::Radiance;
use crate::interaction::SurfaceInteraction;
use crate::math::{max_component, Ray, Vec3};
use crate::sampling::Sampler;
use std::sync::atomic::Ordering;

/// Dimensions used by the camera sample (pixel filter offset).
const CAMERA_DIMS: u32 = 2;

/// Dimensions each vertex reads: light choice (1), light point (2), BSDF lobe (1), BSDF
/// direction (2), Russian roulette (1).
pub const DIMS_PER_VERTEX: u32 = 7;

/// Bounces made before Russian roulette may end a path: roulette decides from bounce
/// `RR_MIN_BOUNCES + 1` on.
pub const RR_MIN_BOUNCES: u32 = 3;

/// One path in flight.
struct PathState {
    /// Index of the pixel within the tile.
    pixel: usize,
    ray: Ray,
    /// Throughput: product of `f |cos| / pdf` (and roulette compensation) so far.
    beta: Vec3,
    /// Number of bounces (scattering events) so far.
    depth: u32,
    /// Solid-angle BSDF density of the last bounce if it was non-delta, else 0 (camera or
    /// delta bounce: emission then counts with full weight).
    prev_pdf: f32,
    /// The last scattering point (not offset), for the light density of an emitter hit.
    prev_p: Vec3,
    /// Product of `eta^2` over the delta refractions so far (for roulette).
    eta_scale: f32,
    sampler: Sampler,
}

/// A shadow ray and the radiance it carries if unoccluded.
struct Shadow {
    pixel: usize,
    ray: Ray,
    contrib: Vec3,
    direct: bool,
}

/// The per-bounce ray buffers of one tile, reused across bounces and samples.
#[derive(Default)]
struct Buffers {
    paths: Vec<PathState>,
    next: Vec<PathState>,
    rays: Vec<Ray>,
    hits: Vec<Option<Hit>>,
    shadows: Vec<Shadow>,
    shadow_rays: Vec<Ray>,
    occluded: Vec<bool>,
}

/// Renders the pixels `[x0, x1) x [y0, y1)` (`x0 < x1 <= width`, `y0 < y1 <= height`);
/// returns the per-pixel means over `ctx.settings.spp` samples in row-major order.
pub fn render_tile(ctx: &RenderContext, x0: u32, y0: u32, x1: u32, y1: u32) -> Vec<Radiance> {
    let s = &ctx.settings;
    let n = ((x1 - x0) * (y1 - y0)) as usize;
    let mut acc = vec![Radiance::default(); n];
    let mut b = Buffers::default();
    for sample in 0..s.spp {
        camera_rays(ctx, x0, y0, x1, y1, sample, &mut b.paths);
        while !b.paths.is_empty() {
            trace_bounce(ctx, &mut b, &mut acc);
        }
    }
    let inv = 1.0 / s.spp.max(1) as f32;
    acc.into_iter().map(|r| r * inv).collect()
}

/// Fills `paths` with the camera rays of sample index `sample` for every pixel of the tile.
fn camera_rays(
    ctx: &RenderContext,
    x0: u32,
    y0: u32,
    x1: u32,
    y1: u32,
    sample: u32,
    paths: &mut Vec<PathState>,
) {
    paths.clear();
    for (i, (x, y)) in tile_pixels(x0, y0, x1, y1).enumerate() {
        let (ray, sampler) = super::camera_sample(ctx, x, y, sample);
        paths.push(PathState {
            pixel: i,
            ray,
            beta: Vec3::ONE,
            depth: 0,
            prev_pdf: 0.0,
            prev_p: ray.o,
            eta_scale: 1.0,
            sampler,
        });
    }
    ctx.counters
        .camera_rays
        .fetch_add(paths.len() as u64, Ordering::Relaxed);
}

/// Traces the rays of `b.paths` as one batch, shades the hits, traces their shadow rays as one
/// batch and leaves the continuing paths in `b.paths`.
fn trace_bounce(ctx: &RenderContext, b: &mut Buffers, acc: &mut [Radiance]) {
    b.rays.clear();
    b.rays.extend(b.paths.iter().map(|p| p.ray));
    b.hits.clear();
    b.hits.resize(b.rays.len(), None);
    ctx.accel.intersect_batch(&b.rays, &mut b.hits);
    b.shadows.clear();
    b.next.clear();
    for (path, hit) in b.paths.drain(..).zip(b.hits.iter()) {
        // No infinite lights exist in the light set: an escaping path carries nothing.
        if let Some(hit) = hit {
            shade(ctx, path, hit, acc, &mut b.shadows, &mut b.next);
        }
    }
    trace_shadows(ctx, b, acc);
    if !b.next.is_empty() {
        ctx.counters
            .secondary_rays
            .fetch_add(b.next.len() as u64, Ordering::Relaxed);
    }
    std::mem::swap(&mut b.paths, &mut b.next);
}

/// Adds `value` to the pixel's direct or indirect component.
fn add(acc: &mut [Radiance], pixel: usize, direct: bool, value: Vec3) {
    if !value.is_finite() {
        return;
    }
    if direct {
        acc[pixel].direct += value;
    } else {
        acc[pixel].indirect += value;
    }
}

/// Shades one hit: emission, a light sample, and a BSDF-sampled continuation.
///
/// - `path`: the path whose ray produced `hit`;
/// - `acc`: the tile's per-pixel sums;
/// - `shadows`, `next`: where the light sample's shadow ray and the continuing path go.
fn shade(
    ctx: &RenderContext,
    mut path: PathState,
    hit: &Hit,
    acc: &mut [Radiance],
    shadows: &mut Vec<Shadow>,
    next: &mut Vec<PathState>,
) {
    let si = SurfaceInteraction::new(ctx.scene, hit, &path.ray);
    if let Some(li) = si.area_light() {
        let le = emitted(ctx, &path, li, si.p, si.ng);
        let direct = path.depth == 0 || (path.depth == 1 && path.prev_pdf > 0.0);
        add(acc, path.pixel, direct, le);
    }
    if path.depth >= ctx.settings.max_depth {
        return;
    }
    let bsdf = si.bsdf(ctx.scene);
    let base = CAMERA_DIMS.wrapping_add(path.depth.wrapping_mul(DIMS_PER_VERTEX));
    path.sampler.set_dimension(base);
    if bsdf.flags().has_non_specular() {
        if let Some(s) = light_sample(ctx, &path, &bsdf, &si) {
            shadows.push(s);
        }
    }
    path.sampler.set_dimension(base + 3);
    if let Some(cont) = continue_path(path, &bsdf, &si) {
        next.push(cont);
    }
}

/// Radiance emitted by area light `li` at `p` (geometric normal `ng`) towards the path's
/// previous vertex, times the throughput and the MIS weight.
fn emitted(ctx: &RenderContext, path: &PathState, li: usize, p: Vec3, ng: Vec3) -> Vec3 {
    let le = ctx.lights.le(li, ng, -path.ray.d.normalize());
    if le.max_element() <= 0.0 {
        return Vec3::ZERO;
    }
    let w = if path.prev_pdf > 0.0 {
        let light_pdf = ctx.lights.pdf_area(li, path.prev_p, p, ng);
        power_heuristic(path.prev_pdf, light_pdf)
    } else {
        1.0
    };
    path.beta * le * w
}

/// Next-event estimation at a non-delta vertex: one light chosen by power, one point on it,
/// MIS-weighted against BSDF sampling. Reads 3 dimensions of the path's sampler. `None` when
/// the sample carries nothing.
fn light_sample(
    ctx: &RenderContext,
    path: &PathState,
    bsdf: &Bsdf,
    v: &SurfaceInteraction,
) -> Option<Shadow> {
    let mut sampler = path.sampler.clone();
    let u_sel = sampler.next_1d();
    let u = sampler.next_2d();
    let s = ctx.lights.sample(ctx.scene, v.p, u_sel, u)?;
    let wi = v.frame.to_local(s.wi);
    let f = bsdf.f(v.wo, wi, TransportMode::Radiance) * wi.z.abs();
    if f.max_element() <= 0.0 {
        return None;
    }
    let w = if s.delta {
        1.0
    } else {
        power_heuristic(s.pdf, bsdf.pdf(v.wo, wi))
    };
    let contrib = path.beta * f * s.li * (w / s.pdf);
    if !contrib.is_finite() || contrib.max_element() <= 0.0 {
        return None;
    }
    Some(Shadow {
        pixel: path.pixel,
        ray: v.shadow_ray(&s),
        contrib,
        direct: path.depth == 0,
    })
}

/// Samples the BSDF for the next bounce and applies Russian roulette; `None` when the path
/// ends. Reads 4 dimensions of the path's sampler (lobe, direction, roulette).
fn continue_path(mut path: PathState, bsdf: &Bsdf, v: &SurfaceInteraction) -> Option<PathState> {
    let uc = path.sampler.next_1d();
    let u = path.sampler.next_2d();
    let u_rr = path.sampler.next_1d();
    let bs = bsdf.sample(v.wo, uc, u, TransportMode::Radiance)?;
    let mut beta = path.beta * bs.f * (bs.wi.z.abs() / bs.pdf);
    let mut eta_scale = path.eta_scale;
    if bs.specular && bs.transmission {
        eta_scale *= bs.eta * bs.eta;
    }
    let depth = path.depth + 1;
    if depth > RR_MIN_BOUNCES {
        let survive = max_component(beta * eta_scale);
        if survive < 1.0 {
            if u_rr >= survive {
                return None;
            }
            beta /= survive;
        }
    }
    if beta.max_element() <= 0.0 || !beta.is_finite() {
        return None;
    }
    path.ray = v.spawn_ray(v.frame.to_world(bs.wi));
    path.beta = beta;
    path.depth = depth;
    path.prev_pdf = if bs.specular { 0.0 } else { bs.pdf };
    path.prev_p = v.p;
    path.eta_scale = eta_scale;
    Some(path)
}

/// Traces `b.shadows` as one batch and adds the unoccluded contributions.
fn trace_shadows(ctx: &RenderContext, b: &mut Buffers, acc: &mut [Radiance]) {
    if b.shadows.is_empty() {
        return;
    }
    b.shadow_rays.clear();
    b.shadow_rays.extend(b.shadows.iter().map(|s| s.ray));
    b.occluded.clear();
    b.occluded.resize(b.shadow_rays.len(), false);
    ctx.accel.occluded_batch(&b.shadow_rays, &mut b.occluded);
    ctx.counters
        .shadow_rays
        .fetch_add(b.shadow_rays.len() as u64, Ordering::Relaxed);
    for (s, &blocked) in b.shadows.iter().zip(b.occluded.iter()) {
        if !blocked {
            add(acc, s.pixel, s.direct, s.contrib);
        }
    }
}
