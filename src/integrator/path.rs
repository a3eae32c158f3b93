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
//!   against the BSDF density) after a non-delta bounce; a ray that leaves the scene sees the
//!   infinite lights the same way ([`wavefront::escaped`]);
//! - on a non-delta BSDF (diffuse, rough conductor), one light sample chosen by its importance
//!   at the vertex (next-event estimation), power-heuristic-weighted against BSDF sampling (full
//!   weight for delta lights); a uniform sky gets no light samples and is left to the BSDF
//!   sample, with full weight when it escapes, as in pbrt-v4 ([`Receiver::sky_by_bsdf`]: on
//!   spaceship half the variance per sample);
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
//! **Caustics through media** (`--integrator photonmap` on a scene whose media need
//! tracking, which renders with this tracer): at a purely diffuse point the caustic photons
//! traced through the media ([`crate::photon::volume`]) give the light of `L S+ D` paths
//! ([`PhotonPass::caustic_through_media`](super::photonmap::PhotonPass::caustic_through_media)),
//! so a path that leaves such a point and reaches an emitter (or the sky) through delta
//! bounces only, without scattering in a medium on the way, does not count that emission:
//! each such path is counted once, by the photons. The path's data ([`Chain`]) tracks that.
//!
//! Randomness: each vertex reads its numbers from fixed dimensions of the pixel sample's
//! [`crate::sampling::Sampler`] stream (2 for the pixel filter, then [`DIMS_PER_VERTEX`] per vertex: light
//! choice, light point, lobe choice, direction, roulette), so an image depends only on the
//! scene, seed and settings, never on thread scheduling. The path tracer always takes one light
//! sample per vertex (it ignores `RenderSettings::light_samples`).
use super::wavefront::{self, add, Component, PathState, Shade, Shadow, Wave, CAMERA_DIMS};
use super::RenderContext;
use crate::accel::Hit;
use crate::bsdf::{Bsdf, TransportMode};
use crate::film::Radiance;
use crate::interaction::{shadow_ray_from, SurfaceInteraction};
use crate::light::Receiver;
use crate::math::{Ray, Vec3};
use crate::medium::{henyey_greenstein, sample_henyey_greenstein};
use crate::sampling::power_heuristic;
use crate::spectrum::Spectrum;

/// Dimensions each vertex reads: light choice (1), light point (2), BSDF lobe (1), BSDF
/// direction (2), Russian roulette (1).
pub const DIMS_PER_VERTEX: u32 = 7;

/// Bounces made before Russian roulette may end a path: roulette decides from bounce
/// `RR_MIN_BOUNCES + 1` on.
pub const RR_MIN_BOUNCES: u32 = 3;

/// Renders the pixels `[x0, x1) x [y0, y1)` (`x0 < x1 <= width`, `y0 < y1 <= height`);
/// returns the per-pixel means over `ctx.settings.spp` samples in row-major order.
pub fn render_tile(ctx: &RenderContext, x0: u32, y0: u32, x1: u32, y1: u32) -> Vec<Radiance> {
    wavefront::render_tile(ctx, &PathTracer, x0, y0, x1, y1)
}

/// The path tracer's shading step.
pub struct PathTracer;

/// Where a path stands towards the caustic photons through media (see the module docs).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Chain {
    /// No caustic photons cover the light this path finds next.
    #[default]
    Open,
    /// The last non-delta vertex was a purely diffuse point that read caustic photons.
    FromReceiver,
    /// ... and one or more delta bounces followed, with no scattering in a medium: emission
    /// found now is in those photons.
    Covered,
}

type Path = PathState<Chain>;

impl Shade for PathTracer {
    type PathData = Chain;
    type Extra = crate::photon::KnnResult;

    fn shade(
        &self,
        ctx: &RenderContext,
        path: Path,
        hit: &Hit,
        wave: &mut Wave<Self::Extra, Chain>,
    ) {
        shade(ctx, path, hit, wave)
    }

    fn emitted_component(&self, path: &Path) -> Component {
        component(path.depth == 0 || (path.depth == 1 && path.prev_pdf > 0.0))
    }

    fn tracks_media(&self) -> bool {
        true
    }

    fn shade_medium(
        &self,
        ctx: &RenderContext,
        path: Path,
        p: Vec3,
        wave: &mut Wave<Self::Extra, Chain>,
    ) {
        shade_medium(ctx, path, p, wave)
    }

    fn escaped(&self, ctx: &RenderContext, path: &Path) -> Spectrum {
        if path.data == Chain::Covered {
            return Spectrum::ZERO;
        }
        wavefront::escaped(ctx, path)
    }
}

/// Light from an emitter straight away or after one non-delta bounce at the first hit is
/// `direct`, the rest `indirect`.
fn component(direct: bool) -> Component {
    if direct {
        Component::Direct
    } else {
        Component::Indirect
    }
}

/// Shades one hit: emission, a light sample, the caustic photons through media at a purely
/// diffuse point, and a BSDF-sampled continuation.
fn shade(
    ctx: &RenderContext,
    mut path: Path,
    hit: &Hit,
    wave: &mut Wave<crate::photon::KnnResult, Chain>,
) {
    let mut si = SurfaceInteraction::new(ctx.scene, hit, &path.ray);
    if si.material(ctx.scene).interface {
        // No surface: the ray goes on into the medium behind the boundary, no bounce taken.
        let d = path.ray.d;
        path.medium = si.medium_leaving(d, path.medium);
        path.ray = Ray::new(si.spawn(d), d);
        wave.next.push(path);
        return;
    }
    if let (Some(li), false) = (si.area_light(), path.data == Chain::Covered) {
        let le = emitted(ctx, &path, li, si.p, si.ng);
        add(
            wave.acc,
            path.pixel,
            PathTracer.emitted_component(&path),
            le,
        );
    }
    if path.depth >= ctx.settings.max_depth {
        return;
    }
    let bsdf = si.bsdf(ctx.scene, ctx.settings.footprint(), path.lambda);
    let base = CAMERA_DIMS.wrapping_add(path.depth.wrapping_mul(DIMS_PER_VERTEX));
    path.sampler.set_dimension(base);
    if bsdf.flags().has_non_specular() {
        if let Some(s) = light_sample(ctx, &path, &bsdf, &si) {
            wave.shadows.push(s);
        }
    }
    // Caustics through media: photons that took at most the bounces the path has left.
    let caustics = ctx.photons.filter(|p| p.maps.caustic.is_some());
    let receiver = caustics.is_some() && crate::photon::volume::is_caustic_receiver(bsdf.flags());
    if let (Some(pass), true) = (caustics, receiver) {
        let left = ctx.settings.max_depth.saturating_sub(path.depth + 1);
        if left >= 1 {
            let t = std::time::Instant::now();
            let l = pass.caustic_through_media(
                &si,
                &bsdf,
                left.min(u8::MAX as u32) as u8,
                path.lambda,
                wave.extra,
            );
            super::charge(&ctx.counters.lookup_ns, t);
            let c = if path.depth == 0 {
                Component::Caustic
            } else {
                Component::Indirect
            };
            add(wave.acc, path.pixel, c, path.beta * l);
        }
    }
    path.sampler.set_dimension(base + 3);
    if let Some(cont) = continue_path(path, &bsdf, &si, receiver) {
        wave.next.push(cont);
    }
}

/// Radiance emitted by area light `li` at `p` (geometric normal `ng`) towards the path's
/// previous vertex, times the throughput and the MIS weight.
fn emitted(ctx: &RenderContext, path: &Path, li: usize, p: Vec3, ng: Vec3) -> Spectrum {
    let le = path
        .lambda
        .illuminant(ctx.lights.le(li, ng, -path.ray.d.normalize()));
    if le.max_element() <= 0.0 {
        return Spectrum::ZERO;
    }
    let w = if path.prev_pdf > 0.0 {
        let light_pdf = ctx.lights.pdf_area(li, path.prev, p, ng);
        power_heuristic(path.prev_pdf, light_pdf)
    } else {
        1.0
    };
    path.beta * le * w
}

/// Next-event estimation at a non-delta vertex: one light chosen by importance, one point on it,
/// MIS-weighted against BSDF sampling. Reads 3 dimensions of the path's sampler. `None` when
/// the sample carries nothing.
fn light_sample(
    ctx: &RenderContext,
    path: &Path,
    bsdf: &Bsdf,
    v: &SurfaceInteraction,
) -> Option<Shadow> {
    let mut sampler = path.sampler.clone();
    let u_sel = sampler.next_1d();
    let u = sampler.next_2d();
    let s = ctx
        .lights
        .sample(&ctx.scene.meshes, v.receiver().sky_by_bsdf(), u_sel, u)?;
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
    let contrib = path.beta * f * path.lambda.illuminant(s.li) * (w / s.pdf);
    if !contrib.is_finite() || contrib.max_element() <= 0.0 {
        return None;
    }
    Some(Shadow {
        pixel: path.pixel,
        ray: v.shadow_ray(&s),
        contrib,
        component: component(path.depth == 0),
        medium: v.medium_leaving(s.wi, path.medium),
    })
}

/// Samples the BSDF for the next bounce and applies Russian roulette; `None` when the path
/// ends. Reads 4 dimensions of the path's sampler (lobe, direction, roulette). `receiver`:
/// the vertex read caustic photons (sets the path's [`Chain`]).
fn continue_path(
    mut path: Path,
    bsdf: &Bsdf,
    v: &SurfaceInteraction,
    receiver: bool,
) -> Option<Path> {
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
    if !roulette(&mut beta, eta_scale, depth, u_rr) {
        return None;
    }
    let wi = v.frame.to_world(bs.wi);
    path.medium = v.medium_leaving(wi, path.medium);
    path.ray = v.spawn_ray(wi);
    path.beta = beta;
    path.depth = depth;
    path.prev_pdf = bsdf.mis_pdf(v.wo, &bs);
    path.prev = v.receiver().sky_by_bsdf();
    path.prev_delta &= bs.specular;
    path.eta_scale = eta_scale;
    // Delta bounces after a receiver lead to light its caustic photons hold (the photons'
    // own test: `Scattered::specular`).
    path.data = match (receiver, bs.specular, path.data) {
        (true, _, _) => Chain::FromReceiver,
        (false, true, Chain::FromReceiver | Chain::Covered) => Chain::Covered,
        _ => Chain::Open,
    };
    Some(path)
}

/// Russian roulette for a path reaching bounce `depth` (from bounce `RR_MIN_BOUNCES + 1` on:
/// survive with `min(1, max_component(beta * eta_scale))`, dividing `beta` by it); false when
/// the path ends (killed, or a throughput that is zero or not finite).
fn roulette(beta: &mut Spectrum, eta_scale: f32, depth: u32, u_rr: f32) -> bool {
    if depth > RR_MIN_BOUNCES {
        let survive = (*beta * eta_scale).max_element();
        if survive < 1.0 {
            if u_rr >= survive {
                return false;
            }
            *beta /= survive;
        }
    }
    beta.max_element() > 0.0 && beta.is_finite()
}

/// Shades a scattering point `p` in the path's medium (the throughput already holds
/// `sigma_s T / pdf`): a light sample through the phase function, MIS-weighted against phase
/// sampling, and a phase-sampled continuation; a medium vertex is a bounce like a surface one
/// and reads the same dimensions.
fn shade_medium(
    ctx: &RenderContext,
    mut path: Path,
    p: Vec3,
    wave: &mut Wave<crate::photon::KnnResult, Chain>,
) {
    if path.depth >= ctx.settings.max_depth {
        return;
    }
    let g = match path.medium {
        Some(m) => ctx.scene.media[m as usize].g,
        None => return,
    };
    let wo = -path.ray.d.normalize();
    let medium = &ctx.scene.media[path.medium.unwrap_or(0) as usize];
    let volume = ctx.photons.and_then(|p| p.volume.as_ref());
    if let (Some(map), false) = (volume, medium.emits()) {
        // The photon mapper: all the light scattered here, direct and multiple, from the
        // volume map's photons around p (a point estimate), and the path ends.
        let t = std::time::Instant::now();
        // Photons whose path joined to this one stays within maxdepth scattering events.
        let left = ctx.settings.max_depth - path.depth;
        let (l, _) = map.point(p, -wo, g, left);
        super::charge(&ctx.counters.lookup_ns, t);
        // The photons carry sigma_s; the throughput holds it already.
        let s = medium.at(p).sigma_s;
        let l = Vec3::select(s.cmpgt(Vec3::ZERO), l / s, Vec3::ZERO);
        add(
            wave.acc,
            path.pixel,
            component(false),
            path.beta * path.lambda.illuminant(l),
        );
        return;
    }
    let base = CAMERA_DIMS.wrapping_add(path.depth.wrapping_mul(DIMS_PER_VERTEX));
    path.sampler.set_dimension(base);
    let mut sampler = path.sampler.clone();
    let u_sel = sampler.next_1d();
    let u = sampler.next_2d();
    if let Some(s) = ctx.lights.sample(
        &ctx.scene.meshes,
        Receiver::in_medium(p).sky_by_bsdf(),
        u_sel,
        u,
    ) {
        let f = henyey_greenstein(wo.dot(s.wi), g);
        let w = if s.delta {
            1.0
        } else {
            power_heuristic(s.pdf, f)
        };
        let contrib = path.beta * path.lambda.illuminant(s.li) * (f * w / s.pdf);
        if contrib.is_finite() && contrib.max_element() > 0.0 {
            wave.shadows.push(Shadow {
                pixel: path.pixel,
                ray: shadow_ray_from(p, &s),
                contrib,
                component: component(path.depth == 0),
                medium: path.medium,
            });
        }
    }
    path.sampler.set_dimension(base + 4);
    let u = path.sampler.next_2d();
    let u_rr = path.sampler.next_1d();
    let (wi, pdf) = sample_henyey_greenstein(wo, g, u);
    let depth = path.depth + 1;
    if !roulette(&mut path.beta, path.eta_scale, depth, u_rr) {
        return;
    }
    path.ray = Ray::new(p, wi);
    path.depth = depth;
    path.prev_pdf = pdf;
    path.prev = Receiver::in_medium(p).sky_by_bsdf();
    path.prev_delta = false;
    path.data = Chain::Open;
    wave.next.push(path);
}
