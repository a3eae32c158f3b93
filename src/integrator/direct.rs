//! The direct + specular integrator, traced as a wavefront per tile so that coherent rays go to
//! the backend in batches (Embree's 8-wide packets): all camera rays of a tile's sample pass,
//! then all their shadow rays, then all continuation rays of the next bounce.
//!
//! At each hit: emitted light (MIS-weighted after a glossy bounce); direct light by shadow rays
//! to a light chosen in proportion to power (power-heuristic MIS with BSDF sampling on glossy
//! surfaces, with the gather rays on diffuse ones); then, on specular and glossy surfaces only,
//! a BSDF-sampled continuation. Rays that leave the scene see the infinite lights, weighted
//! like emission ([`wavefront::escaped`]).
//! Diffuse surfaces end the path: diffuse interreflection is the photon mapper's job.
//!
//! Components: light reaching the camera after at most one non-delta scattering event is
//! `direct`; light arriving through further specular/glossy bounces is `specular`.
use super::photonmap::{self, Gather};
use super::wavefront::{
    self, add, Component, Covered, PathState, Shade, Shadow, Wave, CAMERA_DIMS,
};
use super::{charge, RenderContext};
use crate::accel::{Hit, RayKind};
use crate::bsdf::TransportMode;
use crate::film::Radiance;
use crate::interaction::SurfaceInteraction;
use crate::math::{Ray, Vec3};
use crate::photon::guide::GuideSlot;
use crate::photon::trace;
use crate::photon::KnnResult;
use crate::sampling::power_heuristic;
use std::sync::atomic::Ordering;
use std::time::Instant;

fn dims_per_vertex(light_samples: u32) -> u32 {
    3 * light_samples + 3
}

/// Renders the pixels `[x0, x1) x [y0, y1)`; returns per-pixel means in row-major order.
pub fn render_tile(ctx: &RenderContext, x0: u32, y0: u32, x1: u32, y1: u32) -> Vec<Radiance> {
    wavefront::render_tile(ctx, &Direct, x0, y0, x1, y1)
}

/// The direct + specular shading step (plus pass 2 of the photon mapper when the context has
/// photon maps).
pub struct Direct;

/// Light seen directly or after one non-delta event is `direct`, the rest `specular`.
fn component(direct: bool) -> Component {
    if direct {
        Component::Direct
    } else {
        Component::Specular
    }
}

/// The final-gather rays of a tile pass, and reusable buffers.
#[derive(Default)]
pub struct Gathers {
    pending: Vec<Gather>,
    rays: Vec<Ray>,
    hits: Vec<Option<Hit>>,
    buf: KnnResult,
    /// Per pixel of the tile: the guide of its last primary diffuse point.
    guides: Vec<Option<GuideSlot>>,
}

impl Shade for Direct {
    type Extra = Gathers;

    fn shade(&self, ctx: &RenderContext, path: PathState, hit: &Hit, wave: &mut Wave<Gathers>) {
        shade(ctx, path, hit, wave)
    }

    fn emitted_component(&self, path: &PathState) -> Component {
        component(path.depth == 0 || (path.depth == 1 && !path.prev_delta))
    }

    fn pending(&self, g: &Gathers) -> usize {
        g.pending.len()
    }

    fn flush(&self, ctx: &RenderContext, g: &mut Gathers, acc: &mut [Radiance]) {
        trace_gathers(ctx, g, acc)
    }
}

/// Shades one hit: emission, shadow rays, photon-map components, continuation.
fn shade(ctx: &RenderContext, mut path: PathState, hit: &Hit, wave: &mut Wave<Gathers>) {
    let scene = ctx.scene;
    let mut si = SurfaceInteraction::new(scene, hit, &path.ray);

    // Emission seen along the ray (unless the caustic photons of a glossy surface the path
    // left through delta bounces only have counted it).
    if let (Some(li), false) = (si.area_light(), path.covered == Covered::Specular) {
        let le = ctx.lights.le(li, si.ng, si.wo_world);
        if le.max_element() > 0.0 {
            let w = if path.prev_pdf > 0.0 {
                let light_pdf = ctx.lights.pdf_area(li, path.ray.o, si.p, si.ng);
                power_heuristic(path.prev_pdf, light_pdf)
            } else {
                1.0
            };
            let c = Direct.emitted_component(&path);
            add(wave.acc, path.pixel, c, path.beta * le * w);
        }
    }
    if path.depth >= ctx.settings.max_depth {
        return;
    }

    let bsdf = si.bsdf(scene, ctx.settings.footprint());
    let flags = bsdf.flags();
    let coated = bsdf.has_coat();
    let wo = si.wo;
    let ls = ctx.settings.light_samples.max(1);
    path.sampler
        .set_dimension(CAMERA_DIMS + path.depth * dims_per_vertex(ls));

    // Gather rays double as BSDF samples for direct light at diffuse points.
    let gather_n = match &ctx.photons {
        Some(pass) if flags.has_diffuse() => photonmap::gather_count(pass),
        _ => 0,
    };
    let guide = match &ctx.photons {
        Some(pass) if gather_n > 0 => {
            let x = &mut *wave.extra;
            let slot = if path.depth == 0 {
                if x.guides.len() <= path.pixel {
                    x.guides.resize(path.pixel + 1, None);
                }
                Some(&mut x.guides[path.pixel])
            } else {
                None
            };
            photonmap::gather_guide(pass, &ctx.counters.lookup_ns, &si, &mut x.buf, slot)
        }
        _ => None,
    };

    // Sharp bounces after a receiver: light arriving here is in the receiver's caustic
    // photons (L (S|G)+ G paths with near-smooth G), so this vertex casts no shadow rays when
    // its only non-delta lobe is near-smooth.
    let sharp_alpha = ctx.photons.and_then(photonmap::caustic_alpha);
    let covered_here = path.covered != Covered::No
        && sharp_alpha.is_some_and(|a| bsdf.glossy_alpha().is_some_and(|g| g < a));

    // Direct light by shadow rays.
    if flags.has_non_specular() && !ctx.lights.is_empty() && !covered_here {
        for _ in 0..ls {
            let u_sel = path.sampler.next_1d();
            let u = path.sampler.next_2d();
            let Some(s) = ctx.lights.sample(scene, si.p, u_sel, u) else {
                continue;
            };
            let wi = si.frame.to_local(s.wi);
            // A coated surface: its coat (MIS against the coat's continuation ray) and its body
            // (as a diffuse surface) apart.
            let (f, f_coat) = if coated {
                (
                    bsdf.f_body(wo, wi, TransportMode::Radiance) * wi.z.abs(),
                    bsdf.f_coat(wo, wi, TransportMode::Radiance) * wi.z.abs(),
                )
            } else {
                (
                    bsdf.f(wo, wi, TransportMode::Radiance) * wi.z.abs(),
                    Vec3::ZERO,
                )
            };
            if f.max_element() <= 0.0 && f_coat.max_element() <= 0.0 {
                continue;
            }
            // MIS against BSDF sampling: one continuation ray on glossy surfaces, the final
            // gather's cosine-distributed rays on diffuse ones (multi-sample power heuristic).
            let w = if s.delta {
                1.0
            } else if flags.has_glossy() {
                power_heuristic(s.pdf, bsdf.pdf(wo, wi))
            } else if gather_n > 0 {
                let gather_pdf = photonmap::gather_pdf(&si, guide.as_ref(), s.wi);
                power_heuristic(ls as f32 * s.pdf, gather_n as f32 * gather_pdf)
            } else {
                1.0
            };
            let w_coat = if s.delta {
                1.0
            } else {
                power_heuristic(s.pdf, bsdf.pdf_coat(wo, wi))
            };
            let contrib = path.beta * (f * w + f_coat * w_coat) * s.li / (s.pdf * ls as f32);
            wave.shadows.push(Shadow {
                pixel: path.pixel,
                ray: si.shadow_ray(&s),
                contrib,
                component: component(path.depth == 0),
            });
        }
    } else {
        for _ in 0..ls {
            path.sampler.next_1d();
            path.sampler.next_2d();
        }
    }

    // Caustics and indirect diffuse light from the photon maps (pass 2).
    if let (Some(pass), true) = (&ctx.photons, flags.has_diffuse()) {
        let f_d = bsdf.f(
            wo,
            Vec3::new(0.0, 0.0, wo.z.signum()),
            TransportMode::Radiance,
        );
        let primary = path.depth == 0;
        path.sampler
            .set_dimension(CAMERA_DIMS + path.depth * dims_per_vertex(ls) + 3 * ls);
        let got = photonmap::at_diffuse(
            pass,
            &ctx.counters.lookup_ns,
            ls,
            guide.as_ref(),
            &si,
            &bsdf,
            f_d,
            path.beta,
            path.pixel,
            primary,
            &mut path.sampler,
            &mut wave.extra.buf,
            &mut wave.extra.pending,
        );
        if primary {
            add(wave.acc, path.pixel, Component::Caustic, got.caustic);
            add(wave.acc, path.pixel, Component::Indirect, got.indirect);
        } else {
            add(
                wave.acc,
                path.pixel,
                Component::Specular,
                got.caustic + got.indirect,
            );
        }
    }

    // Caustics on a rough glossy surface: the caustic photons stored on such surfaces, each
    // weighted by the BSDF towards wo.
    let mut receiver = false;
    if let (Some(pass), false) = (&ctx.photons, flags.has_diffuse()) {
        let buf = &mut wave.extra.buf;
        if let Some(l) = photonmap::at_glossy(pass, &ctx.counters.lookup_ns, &si, &bsdf, buf) {
            receiver = true;
            let c = if path.depth == 0 {
                Component::Caustic
            } else {
                Component::Specular
            };
            add(wave.acc, path.pixel, c, path.beta * l);
        }
    }

    // Continue through specular and glossy surfaces and coats.
    if !(flags.has_specular() || flags.has_glossy() || coated) {
        return;
    }
    let uc = path.sampler.next_1d();
    let u = path.sampler.next_2d();
    // A coated surface continues along its coat's reflection only: shadow rays and the photon
    // estimates above cover its body.
    let bs = if coated {
        bsdf.sample_coat(wo, uc, u, TransportMode::Radiance)
    } else {
        bsdf.sample(wo, uc, u, TransportMode::Radiance)
    };
    let Some(bs) = bs else {
        return;
    };
    // Where the BSDF has a diffuse lobe too, shadow rays and the photon estimates above
    // already cover every non-delta part: only a delta sample continues.
    if bs.pdf <= 0.0 || (!coated && flags.has_diffuse() && !bs.specular) {
        return;
    }
    let beta = path.beta * bs.f * (bs.wi.z.abs() / bs.pdf);
    if beta.max_element() <= 0.0 || !beta.is_finite() {
        return;
    }
    wave.next.push(PathState {
        ray: si.spawn_ray(si.frame.to_world(bs.wi)),
        beta,
        depth: path.depth + 1,
        prev_pdf: if coated {
            if bs.specular {
                0.0
            } else {
                bs.pdf
            }
        } else {
            bsdf.mis_pdf(wo, &bs)
        },
        prev_p: si.p,
        prev_delta: path.prev_delta && bs.specular,
        covered: path.covered.after(
            receiver,
            sharp_alpha.is_some_and(|a| trace::is_sharp_bounce(&bsdf, bs.lobe_alpha, a)),
        ),
        ..path
    });
}

/// Traces the pending gather rays as one batch and adds their radiance.
fn trace_gathers(ctx: &RenderContext, g: &mut Gathers, acc: &mut [Radiance]) {
    let Some(pass) = &ctx.photons else { return };
    if g.pending.is_empty() {
        return;
    }
    g.rays.clear();
    g.rays.extend(g.pending.iter().map(|x| x.ray));
    wavefront::intersect_batch(ctx, RayKind::Gather, &g.rays, &mut g.hits);
    ctx.counters
        .secondary_rays
        .fetch_add(g.rays.len() as u64, Ordering::Relaxed);
    // Resolving a gather is almost all irradiance-cache lookup: timed as a batch (a clock read
    // per lookup cost 3% of the render).
    let t = Instant::now();
    for (gather, hit) in g.pending.iter_mut().zip(g.hits.iter()) {
        let (direct, indirect) = photonmap::gather_radiance(ctx, pass, gather, *hit, &mut g.buf);
        let (direct, indirect) = (gather.weight * direct, gather.weight * indirect);
        if gather.primary {
            add(acc, gather.pixel, Component::Direct, direct);
            add(acc, gather.pixel, Component::Indirect, indirect);
        } else {
            add(acc, gather.pixel, Component::Specular, direct + indirect);
        }
    }
    charge(&ctx.counters.lookup_ns, t);
    g.pending.clear();
}
