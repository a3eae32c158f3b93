//! The tile wavefront every integrator renders through (pbrt-v4's `Render`/`Li` split): this
//! module owns the tile's buffers, the camera rays, the batched and timed ray queries and the
//! shadow-ray resolver; an integrator supplies only its shading step ([`Shade`]).
//!
//! Per sample index, all camera rays of the tile go to the backend as one batch (Embree's
//! 8-wide packets for coherent rays); the integrator shades every hit, emitting shadow rays
//! and continuation paths; the shadow rays are traced as batches of at most
//! [`BATCH`](crate::resources::BATCH) (and whatever the integrator defers, such as final-gather
//! rays, is flushed the same way); then the continuations form the next wave.
use super::{charge, tile_pixels, RenderContext};
use crate::accel::{Hit, RayKind};
use crate::film::Radiance;
use crate::math::{Ray, Vec3};
use crate::resources::BATCH;
use crate::sampling::Sampler;
use std::sync::atomic::Ordering;
use std::time::Instant;

/// Dimensions the camera sample uses (pixel filter offset).
pub const CAMERA_DIMS: u32 = 2;

/// One path in flight.
#[derive(Clone, Debug)]
pub struct PathState {
    /// Index of the pixel within the tile.
    pub pixel: usize,
    pub ray: Ray,
    /// Throughput: product of `f |cos| / pdf` (and roulette compensation) so far.
    pub beta: Vec3,
    /// Number of scattering events so far.
    pub depth: u32,
    /// Solid-angle BSDF density of the last bounce if it was non-delta, else 0 (camera or
    /// delta bounce: emission then counts with full weight).
    pub prev_pdf: f32,
    /// The last scattering point (the camera at first), for the light density at an emitter.
    pub prev_p: Vec3,
    /// Whether every bounce so far was a delta (specular) one.
    pub prev_delta: bool,
    /// Product of `eta^2` over the delta refractions so far (for roulette).
    pub eta_scale: f32,
    /// Whether light this path finds next is already counted by a photon estimate.
    pub covered: Covered,
    pub sampler: Sampler,
}

/// Where a camera path stands towards the caustic photons of rough glossy surfaces: the
/// estimate at such a surface counts every L (S|G)+ G path through it whose bounces before it
/// were sharp (delta or near-smooth, `photon::trace::is_sharp_bounce`), so the path traced on
/// from it must not count light it finds through sharp bounces only: emitters hit after them,
/// and shadow rays from near-smooth vertices.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Covered {
    /// Nothing is covered.
    #[default]
    No,
    /// The last vertex was a receiver (its caustic estimate taken) and the path left it by a
    /// non-delta sample: an emitter hit next is direct light (MIS-weighted), still counted.
    Next,
    /// Sharp bounces only since such a vertex: emitters (and the infinite lights) count zero.
    Specular,
}

impl Covered {
    /// The state after a bounce: `receiver` says whether the vertex took a caustic estimate
    /// from glossy photons, `sharp` whether the bounce was sharp (a delta lobe, or a
    /// near-smooth one; a receiver's own lobe is never near-smooth).
    pub fn after(self, receiver: bool, sharp: bool) -> Covered {
        match (receiver, sharp, self) {
            (true, false, _) => Covered::Next,
            (_, true, Covered::Next | Covered::Specular) => Covered::Specular,
            _ => Covered::No,
        }
    }
}

impl PathState {
    /// A path leaving the camera along `ray` for pixel `pixel` of the tile.
    pub fn camera(pixel: usize, ray: Ray, sampler: Sampler) -> Self {
        PathState {
            pixel,
            ray,
            beta: Vec3::ONE,
            depth: 0,
            prev_pdf: 0.0,
            prev_p: ray.o,
            prev_delta: true,
            eta_scale: 1.0,
            covered: Covered::No,
            sampler,
        }
    }
}

/// The image component a contribution belongs to (see [`Radiance`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Component {
    Direct,
    Specular,
    Caustic,
    Indirect,
}

/// Adds `value` to a pixel's component; a non-finite value is dropped (one bad sample must not
/// poison a pixel).
pub fn add(acc: &mut [Radiance], pixel: usize, c: Component, value: Vec3) {
    if !value.is_finite() {
        return;
    }
    let px = &mut acc[pixel];
    match c {
        Component::Direct => px.direct += value,
        Component::Specular => px.specular += value,
        Component::Caustic => px.caustic += value,
        Component::Indirect => px.indirect += value,
    }
}

/// A shadow ray and what it adds to its pixel if unoccluded.
#[derive(Clone, Copy, Debug)]
pub struct Shadow {
    pub pixel: usize,
    pub ray: Ray,
    pub contrib: Vec3,
    pub component: Component,
}

/// Where a shading step puts its results.
pub struct Wave<'a, X> {
    /// The tile's per-pixel sums.
    pub acc: &'a mut [Radiance],
    pub shadows: &'a mut Vec<Shadow>,
    /// Paths continuing into the next wave.
    pub next: &'a mut Vec<PathState>,
    /// The integrator's own deferred work.
    pub extra: &'a mut X,
}

/// An integrator's shading step.
pub trait Shade: Sync {
    /// Per-tile work the integrator defers and traces in batches (final-gather rays).
    type Extra: Default;
    /// Shades `path`'s `hit`.
    fn shade(&self, ctx: &RenderContext, path: PathState, hit: &Hit, wave: &mut Wave<Self::Extra>);
    /// The component that light emitted towards `path` counts towards: an emitter it hits, or
    /// the infinite lights when it leaves the scene (see [`escaped`]).
    fn emitted_component(&self, path: &PathState) -> Component;
    /// Entries waiting in `extra` (flushed at [`BATCH`] and at the end of each wave).
    fn pending(&self, _extra: &Self::Extra) -> usize {
        0
    }
    /// Traces and resolves what `extra` holds.
    fn flush(&self, _ctx: &RenderContext, _extra: &mut Self::Extra, _acc: &mut [Radiance]) {}
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
    // With `maxcomponentvalue`, each sample index gathers into its own buffer and is clamped
    // when all its waves are done (a sample's light arrives over several waves); without it,
    // straight into `acc` (the sums, and so the image, stay what they always were).
    let clamp = ctx.settings.max_component / ctx.settings.imaging_ratio;
    let mut one = if clamp.is_finite() {
        vec![Radiance::default(); n]
    } else {
        Vec::new()
    };
    let mut b = Buffers::default();
    let mut extra = S::Extra::default();
    for sample in 0..spp {
        b.paths.clear();
        for (i, (x, y)) in tile_pixels(x0, y0, x1, y1).enumerate() {
            let (ray, sampler) = super::camera_sample(ctx, x, y, sample);
            b.paths.push(PathState::camera(i, ray, sampler));
        }
        ctx.counters
            .camera_rays
            .fetch_add(b.paths.len() as u64, Ordering::Relaxed);
        // The first wave is the camera rays, every later one their bounces.
        let mut kind = RayKind::Camera;
        let sums = if one.is_empty() { &mut acc } else { &mut one };
        while !b.paths.is_empty() {
            wave(ctx, shader, kind, &mut b, &mut extra, sums);
            kind = RayKind::Bounce;
        }
        for (a, r) in acc.iter_mut().zip(one.iter_mut()) {
            *a += crate::film::clamp_sample(std::mem::take(r), clamp);
        }
    }
    let inv = 1.0 / spp as f32;
    acc.into_iter().map(|r| r * inv).collect()
}

/// Traces the rays of `b.paths` (all of `kind`) as one batch, shades the hits, resolves their
/// shadow rays and deferred work in bounded batches, and leaves the continuing paths in
/// `b.paths`.
fn wave<S: Shade>(
    ctx: &RenderContext,
    shader: &S,
    kind: RayKind,
    b: &mut Buffers,
    extra: &mut S::Extra,
    acc: &mut [Radiance],
) {
    b.rays.clear();
    b.rays.extend(b.paths.iter().map(|p| p.ray));
    intersect_batch(ctx, kind, &b.rays, &mut b.hits);
    b.shadows.clear();
    b.next.clear();
    for (path, hit) in b.paths.drain(..).zip(b.hits.iter()) {
        if let Some(hit) = hit {
            let mut w = Wave {
                acc,
                shadows: &mut b.shadows,
                next: &mut b.next,
                extra,
            };
            shader.shade(ctx, path, hit, &mut w);
        } else if ctx.lights.has_infinite() {
            add(
                acc,
                path.pixel,
                shader.emitted_component(&path),
                escaped(ctx, &path),
            );
        }
        // Bounded batches: a point adds a bounded number of shadow rays and deferred entries
        // beyond BATCH before they are traced.
        if b.shadows.len() >= BATCH {
            resolve_shadows(ctx, &b.shadows, &mut b.shadow_rays, &mut b.occluded, acc);
            b.shadows.clear();
        }
        if shader.pending(extra) >= BATCH {
            shader.flush(ctx, extra, acc);
        }
    }
    resolve_shadows(ctx, &b.shadows, &mut b.shadow_rays, &mut b.occluded, acc);
    shader.flush(ctx, extra, acc);
    ctx.counters
        .secondary_rays
        .fetch_add(b.next.len() as u64, Ordering::Relaxed);
    std::mem::swap(&mut b.paths, &mut b.next);
}

/// What a path that leaves the scene sees of the infinite lights, times its throughput: with
/// full weight after the camera or a delta bounce, else power-heuristic-weighted against light
/// sampling (the BSDF density of the last bounce against the lights' density of the direction);
/// zero when photons already count it ([`Covered::Specular`]).
pub fn escaped(ctx: &RenderContext, path: &PathState) -> Vec3 {
    if path.covered == Covered::Specular {
        return Vec3::ZERO; // an L S+ G path: the glossy surface's caustic photons have it
    }
    let d = path.ray.d.normalize_or_zero();
    let le = ctx.lights.escaped(path.ray.o, d, |light_pdf| {
        if path.prev_pdf > 0.0 {
            crate::sampling::power_heuristic(path.prev_pdf, light_pdf)
        } else {
            1.0
        }
    });
    path.beta * le
}

/// Traces a batch of shadow rays and adds the unoccluded contributions.
fn resolve_shadows(
    ctx: &RenderContext,
    shadows: &[Shadow],
    rays: &mut Vec<Ray>,
    occluded: &mut Vec<bool>,
    acc: &mut [Radiance],
) {
    if shadows.is_empty() {
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

#[cfg(test)]
mod tests {
    use super::Covered::{self, *};

    #[test]
    fn covered_drops_only_delta_chains_after_a_receiver() {
        // receiver -> glossy sample: the next emitter is direct light (kept).
        assert_eq!(No.after(true, false), Next);
        // ... then delta bounces: L S+ G paths, which the receiver's photons have.
        assert_eq!(Next.after(false, true), Specular);
        assert_eq!(Specular.after(false, true), Specular);
        // Any non-delta bounce that is no receiver ends the cover.
        assert_eq!(Specular.after(false, false), No);
        assert_eq!(Next.after(false, false), No);
        // Delta bounces without a receiver before them cover nothing.
        assert_eq!(No.after(false, true), No);
        // A receiver that continues by a delta lobe covers nothing of that lobe.
        assert_eq!(No.after(true, true), No);
        assert_eq!(Covered::default(), No);
    }
}
