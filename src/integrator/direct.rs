//! The direct + specular integrator, traced as a wavefront per tile so that coherent rays go to
//! the backend in batches (Embree's 8-wide packets): all camera rays of a tile's sample pass,
//! then all their shadow rays, then all continuation rays of the next bounce.
//!
//! At each hit: emitted light (MIS-weighted after a glossy bounce); direct light by shadow rays
//! to a light chosen by its importance at the point (power-heuristic MIS with BSDF sampling
//! on glossy surfaces); then, on specular and glossy surfaces and coats only, a BSDF-sampled
//! continuation. Rays that leave the scene see the infinite lights, weighted like emission
//! ([`wavefront::escaped`]). Diffuse surfaces end the path.
//!
//! Components: light reaching the camera after at most one non-delta scattering event is
//! `direct`; light arriving through further specular/glossy bounces is `specular`.
//!
//! Media: in a scene whose media need tracking ([`crate::scene::Scene::media_need_tracking`])
//! rays track the medium they travel in as the path tracer's do ([`crate::medium`]):
//! `interface` surfaces are crossed, segments in a scattering medium sample their first
//! interaction, and a scattering point is lit by shadow rays through the phase function
//! (transmittance-weighted), power-heuristic-weighted against one phase-sampled ray that
//! looks for emission only (the path's data says so: it ends at whatever it meets), so the
//! integrator gives single scattering plus the specular chains to it; emitting media add
//! their emission along every tracked segment.
//!
//! The steps of a hit (`emission`, `Vertex::new`, `shadow_rays`, `continuation`) are
//! shared with the photon mapper ([`super::photon_mapper`]), which adds its estimates between
//! them.
use super::wavefront::{self, add, Component, PathState, Shade, Shadow, Wave, CAMERA_DIMS};
use super::RenderContext;
use crate::accel::Hit;
use crate::bsdf::{Bsdf, BsdfSample, BxdfFlags, TransportMode};
use crate::film::Radiance;
use crate::interaction::SurfaceInteraction;
use crate::light::Receiver;
use crate::math::Vec3;
use crate::sampling::power_heuristic;
use crate::spectrum::Spectrum;

/// Sampler dimensions one vertex uses with `light_samples` shadow rays.
pub(super) fn dims_per_vertex(light_samples: u32) -> u32 {
    3 * light_samples + 3
}

/// Renders the pixels `[x0, x1) x [y0, y1)`; returns per-pixel means in row-major order.
pub fn render_tile(ctx: &RenderContext, x0: u32, y0: u32, x1: u32, y1: u32) -> Vec<Radiance> {
    let tracks = ctx.scene.media_need_tracking.is_some();
    wavefront::render_tile(ctx, &Direct { tracks }, x0, y0, x1, y1)
}

/// The direct + specular shading step.
pub struct Direct {
    /// Whether rays track the medium they travel in (the scene's media need it).
    pub tracks: bool,
}

/// Light seen directly or after one non-delta event is `direct`, the rest `specular`.
pub(super) fn component(direct: bool) -> Component {
    if direct {
        Component::Direct
    } else {
        Component::Specular
    }
}

/// The component of emitted light a path finds (see [`Shade::emitted_component`]).
pub(super) fn emitted_component<T>(path: &PathState<T>) -> Component {
    component(path.depth == 0 || (path.depth == 1 && !path.prev_delta))
}

impl Shade for Direct {
    type Extra = ();
    /// Whether the path only looks for emission (the phase-sampled ray from a scattering
    /// point in a medium).
    type PathData = bool;

    fn shade(
        &self,
        ctx: &RenderContext,
        mut path: PathState<bool>,
        hit: &Hit,
        wave: &mut Wave<(), bool>,
    ) {
        let si = SurfaceInteraction::new(ctx.scene, hit, &path.ray);
        if self.tracks && si.material(ctx.scene).interface {
            // No surface: the ray goes on into the medium behind the boundary.
            let d = path.ray.d;
            path.medium = si.medium_leaving(d, path.medium);
            path.ray = crate::math::Ray::new(si.spawn(d), d);
            wave.next.push(path);
            return;
        }
        emission(ctx, &path, &si, wave.acc);
        if path.depth >= ctx.settings.max_depth || path.data {
            return;
        }
        let v = Vertex::new(ctx, &mut path, si);
        shadow_rays(ctx, &mut path, &v, wave.shadows, false, |_, _| 1.0);
        if let Some((_, next)) = continuation(path, &v) {
            wave.next.push(next);
        }
    }

    fn emitted_component(&self, path: &PathState<bool>) -> Component {
        emitted_component(path)
    }

    fn tracks_media(&self) -> bool {
        self.tracks
    }

    fn shade_medium(
        &self,
        ctx: &RenderContext,
        path: PathState<bool>,
        p: Vec3,
        wave: &mut Wave<(), bool>,
    ) {
        medium_vertex(ctx, path, p, wave);
    }
}

/// Direct light at scattering point `p` of the path's medium: `light_samples` shadow rays
/// to lights chosen by importance, each weighted by the Henyey-Greenstein phase function and
/// carried through the media on the way, power-heuristic-weighted against a phase-sampled
/// ray that only looks for emission (pushed to `wave.next`). Reads the vertex's dimensions
/// as a surface vertex does. A path that only looks for emission ends here.
fn medium_vertex(
    ctx: &RenderContext,
    mut path: PathState<bool>,
    p: Vec3,
    wave: &mut Wave<(), bool>,
) {
    let Some(m) = path.medium else {
        return;
    };
    if path.depth >= ctx.settings.max_depth || path.data {
        return;
    }
    let g = ctx.scene.media[m as usize].g;
    let wo = -path.ray.d.normalize();
    let ls = ctx.settings.light_samples.max(1);
    path.sampler
        .set_dimension(CAMERA_DIMS + path.depth * dims_per_vertex(ls));
    for _ in 0..ls {
        let u_sel = path.sampler.next_1d();
        let u = path.sampler.next_2d();
        let Some(s) = ctx
            .lights
            .sample(&ctx.scene.meshes, Receiver::in_medium(p), u_sel, u)
        else {
            continue;
        };
        let f = crate::medium::henyey_greenstein(wo.dot(s.wi), g);
        let w = if s.delta {
            1.0
        } else {
            power_heuristic(s.pdf, f)
        };
        let contrib = path.beta * path.lambda.illuminant(s.li) * (f * w / (s.pdf * ls as f32));
        if contrib.is_finite() && contrib.max_element() > 0.0 {
            wave.shadows.push(Shadow {
                pixel: path.pixel,
                ray: crate::interaction::shadow_ray_from(p, &s),
                contrib,
                component: component(path.depth == 0),
                medium: path.medium,
            });
        }
    }
    // The phase-sampled ray (the phase function's weight f / pdf is 1).
    let (wi, pdf) = crate::medium::sample_henyey_greenstein(wo, g, path.sampler.next_2d());
    path.ray = crate::math::Ray::new(p, wi);
    path.depth += 1;
    path.prev_pdf = pdf;
    path.prev = Receiver::in_medium(p);
    path.prev_delta = false;
    path.data = true;
    wave.next.push(path);
}

/// Adds the light an emitter at `si` sends along the path's ray: with full weight after the
/// camera or a delta bounce, else power-heuristic-weighted against light sampling.
pub(super) fn emission<T>(
    ctx: &RenderContext,
    path: &PathState<T>,
    si: &SurfaceInteraction,
    acc: &mut [wavefront::Sums],
) {
    let Some(li) = si.area_light() else {
        return;
    };
    let le = path
        .lambda
        .illuminant(ctx.lights.le(li, si.ng, si.wo_world));
    if le.max_element() > 0.0 {
        let w = if path.prev_pdf > 0.0 {
            let light_pdf = ctx.lights.pdf_area(li, path.prev, si.p, si.ng);
            power_heuristic(path.prev_pdf, light_pdf)
        } else {
            1.0
        };
        add(acc, path.pixel, emitted_component(path), path.beta * le * w);
    }
}

/// A scattering vertex: the hit, its BSDF and what the steps read of it.
pub(super) struct Vertex<'a> {
    pub si: SurfaceInteraction<'a>,
    pub bsdf: Bsdf,
    pub flags: BxdfFlags,
    /// A coat over a body ([`Bsdf::has_coat`]): the coat is traced, the body lit apart.
    pub coated: bool,
    /// Shadow rays per vertex.
    pub ls: u32,
}

impl<'a> Vertex<'a> {
    /// The BSDF at `si`; puts the path's sampler at this vertex's first dimension.
    pub fn new<T>(
        ctx: &RenderContext,
        path: &mut PathState<T>,
        mut si: SurfaceInteraction<'a>,
    ) -> Self {
        let bsdf = si.bsdf(ctx.scene, ctx.settings.footprint(), path.lambda);
        let ls = ctx.settings.light_samples.max(1);
        path.sampler
            .set_dimension(CAMERA_DIMS + path.depth * dims_per_vertex(ls));
        Vertex {
            flags: bsdf.flags(),
            coated: bsdf.has_coat(),
            si,
            bsdf,
            ls,
        }
    }

    /// The sampler dimension after this vertex's shadow rays.
    pub fn after_shadow_rays<T>(&self, path: &PathState<T>) -> u32 {
        CAMERA_DIMS + path.depth * dims_per_vertex(self.ls) + 3 * self.ls
    }
}

/// Direct light at `v` by `v.ls` shadow rays to lights chosen by importance (each
/// draws three sampler dimensions, also when `skip` says the vertex casts none). On a coated
/// surface the coat (MIS against the coat's continuation) and the body are lit apart; glossy
/// lobes are weighed by the power heuristic against BSDF sampling, diffuse ones by
/// `diffuse_weight(light pdf, world direction)`.
pub(super) fn shadow_rays<T>(
    ctx: &RenderContext,
    path: &mut PathState<T>,
    v: &Vertex,
    shadows: &mut Vec<Shadow>,
    skip: bool,
    diffuse_weight: impl Fn(f32, Vec3) -> f32,
) {
    let (si, bsdf, ls) = (&v.si, &v.bsdf, v.ls);
    let wo = si.wo;
    if !v.flags.has_non_specular() || ctx.lights.is_empty() || skip {
        for _ in 0..ls {
            path.sampler.next_1d();
            path.sampler.next_2d();
        }
        return;
    }
    for _ in 0..ls {
        let u_sel = path.sampler.next_1d();
        let u = path.sampler.next_2d();
        let Some(s) = ctx
            .lights
            .sample(&ctx.scene.meshes, si.receiver(), u_sel, u)
        else {
            continue;
        };
        let wi = si.frame.to_local(s.wi);
        let rad = TransportMode::Radiance;
        let (f, f_coat) = if v.coated {
            (
                bsdf.f_body(wo, wi, rad) * wi.z.abs(),
                bsdf.f_coat(wo, wi, rad) * wi.z.abs(),
            )
        } else {
            (bsdf.f(wo, wi, rad) * wi.z.abs(), Spectrum::ZERO)
        };
        if f.max_element() <= 0.0 && f_coat.max_element() <= 0.0 {
            continue;
        }
        let w = if s.delta {
            1.0
        } else if v.flags.has_glossy() {
            power_heuristic(s.pdf, bsdf.pdf(wo, wi))
        } else {
            diffuse_weight(s.pdf, s.wi)
        };
        let w_coat = if s.delta {
            1.0
        } else {
            power_heuristic(s.pdf, bsdf.pdf_coat(wo, wi))
        };
        let li = path.lambda.illuminant(s.li);
        let contrib = path.beta * (f * w + f_coat * w_coat) * li / (s.pdf * ls as f32);
        shadows.push(Shadow {
            pixel: path.pixel,
            ray: si.shadow_ray(&s),
            contrib,
            component: component(path.depth == 0),
            medium: si.medium_leaving(s.wi, path.medium),
        });
    }
}

/// The continuation through a specular or glossy surface or a coat (a coat continues along
/// its reflection only; where the BSDF has a diffuse lobe, only a delta sample continues,
/// since shadow rays and estimates cover the rest): the sample and the next path, carrying
/// this path's data unchanged. Draws three sampler dimensions when it samples.
pub(super) fn continuation<T>(
    mut path: PathState<T>,
    v: &Vertex,
) -> Option<(BsdfSample, PathState<T>)> {
    let (flags, coated, bsdf) = (v.flags, v.coated, &v.bsdf);
    if !(flags.has_specular() || flags.has_glossy() || coated) {
        return None;
    }
    let wo = v.si.wo;
    let uc = path.sampler.next_1d();
    let u = path.sampler.next_2d();
    let bs = if coated {
        bsdf.sample_coat(wo, uc, u, TransportMode::Radiance)
    } else {
        bsdf.sample(wo, uc, u, TransportMode::Radiance)
    }?;
    if bs.pdf <= 0.0 || (!coated && flags.has_diffuse() && !bs.specular) {
        return None;
    }
    let beta = path.beta * bs.f * (bs.wi.z.abs() / bs.pdf);
    if beta.max_element() <= 0.0 || !beta.is_finite() {
        return None;
    }
    let prev_pdf = match (coated, bs.specular) {
        (true, true) => 0.0,
        (true, false) => bs.pdf,
        (false, _) => bsdf.mis_pdf(wo, &bs),
    };
    let wi = v.si.frame.to_world(bs.wi);
    let next = PathState {
        ray: v.si.spawn_ray(wi),
        medium: v.si.medium_leaving(wi, path.medium),
        beta,
        depth: path.depth + 1,
        prev_pdf,
        prev: v.si.receiver(),
        prev_delta: path.prev_delta && bs.specular,
        ..path
    };
    Some((bs, next))
}
