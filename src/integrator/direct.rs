//! The direct + specular integrator, traced as a wavefront per tile so that coherent rays go to
//! the backend in batches (Embree's 8-wide packets): all camera rays of a tile's sample pass,
//! then all their shadow rays, then all continuation rays of the next bounce.
//!
//! At each hit: emitted light (MIS-weighted after a glossy bounce); direct light by shadow rays
//! to a light chosen in proportion to power (power-heuristic MIS with BSDF sampling on glossy
//! surfaces); then, on specular and glossy surfaces only, a BSDF-sampled continuation.
//! Diffuse surfaces end the path: diffuse interreflection is the photon mapper's job.
//!
//! Components: light reaching the camera after at most one non-delta scattering event is
//! `direct`; light arriving through further specular/glossy bounces is `specular`.
use super::photonmap::{self, Gather};
use super::{charge, power_heuristic, tile_pixels, RenderContext};
use crate::accel::{Hit, RayQuery};
use crate::bsdf::TransportMode;
use crate::film::Radiance;
use crate::interaction::SurfaceInteraction;
use crate::math::{Ray, Vec3};
use crate::photon::KnnResult;
use crate::resources::BATCH;
use crate::sampling::Sampler;
use std::sync::atomic::Ordering;
use std::time::Instant;

/// Dimensions used by the camera sample (pixel filter offset).
const CAMERA_DIMS: u32 = 2;

/// One path in flight.
struct PathState {
    /// Index of the pixel within the tile.
    pixel: usize,
    ray: Ray,
    beta: Vec3,
    /// Number of scattering events so far.
    depth: u32,
    /// BSDF density of the last (non-delta) bounce, for MIS at an emitter; 0 after the camera
    /// or a delta bounce.
    prev_pdf: f32,
    /// Whether all bounces so far were delta (specular).
    prev_delta: bool,
    sampler: Sampler,
}

/// A shadow ray and the radiance it carries if unoccluded.
struct Shadow {
    pixel: usize,
    ray: Ray,
    contrib: Vec3,
    direct: bool,
}

fn dims_per_vertex(light_samples: u32) -> u32 {
    3 * light_samples + 3
}

/// Renders the pixels `[x0, x1) x [y0, y1)`; returns per-pixel means in row-major order.
pub fn render_tile(ctx: &RenderContext, x0: u32, y0: u32, x1: u32, y1: u32) -> Vec<Radiance> {
    let s = &ctx.settings;
    let tw = (x1 - x0) as usize;
    let n = tw * (y1 - y0) as usize;
    let mut acc = vec![Radiance::default(); n];
    let mut paths: Vec<PathState> = Vec::with_capacity(n);
    let mut next: Vec<PathState> = Vec::with_capacity(n);
    let mut rays: Vec<Ray> = Vec::with_capacity(n);
    let mut hits: Vec<Option<Hit>> = Vec::with_capacity(n);
    let mut shadows: Vec<Shadow> = Vec::new();
    let mut shadow_rays: Vec<Ray> = Vec::new();
    let mut occluded: Vec<bool> = Vec::new();
    let mut gathers = Gathers::default();

    for sample in 0..s.spp {
        // Camera rays of the whole tile for this sample index.
        paths.clear();
        for (i, (x, y)) in tile_pixels(x0, y0, x1, y1).enumerate() {
            let (ray, sampler) = super::camera_sample(ctx, x, y, sample);
            paths.push(PathState {
                pixel: i,
                ray,
                beta: Vec3::ONE,
                depth: 0,
                prev_pdf: 0.0,
                prev_delta: true,
                sampler,
            });
        }
        ctx.counters
            .camera_rays
            .fetch_add(paths.len() as u64, Ordering::Relaxed);

        while !paths.is_empty() {
            rays.clear();
            rays.extend(paths.iter().map(|p| p.ray));
            hits.clear();
            hits.resize(rays.len(), None);
            let t = Instant::now();
            ctx.accel.intersect_batch(&rays, &mut hits);
            charge(&ctx.counters.ray_ns, t);
            shadows.clear();
            next.clear();
            for (path, hit) in paths.drain(..).zip(hits.iter()) {
                if let Some(hit) = hit {
                    shade(
                        ctx,
                        path,
                        hit,
                        &mut acc,
                        &mut shadows,
                        &mut next,
                        &mut gathers,
                    );
                }
                // Bounded batches: a point adds at most MAX_LIGHT_SAMPLES shadow rays and
                // MAX_GATHER_SAMPLES gathers beyond BATCH before they are traced.
                if shadows.len() >= BATCH {
                    trace_shadows(ctx, &shadows, &mut shadow_rays, &mut occluded, &mut acc);
                    shadows.clear();
                }
                if gathers.pending.len() >= BATCH {
                    trace_gathers(ctx, &mut gathers, &mut acc);
                }
            }
            trace_shadows(ctx, &shadows, &mut shadow_rays, &mut occluded, &mut acc);
            trace_gathers(ctx, &mut gathers, &mut acc);
            if !next.is_empty() {
                ctx.counters
                    .secondary_rays
                    .fetch_add(next.len() as u64, Ordering::Relaxed);
            }
            std::mem::swap(&mut paths, &mut next);
        }
    }
    let inv = 1.0 / s.spp as f32;
    acc.into_iter().map(|r| r * inv).collect()
}

/// Adds `value` to the pixel's direct or specular component.
fn add(acc: &mut [Radiance], pixel: usize, direct: bool, value: Vec3) {
    if direct {
        acc[pixel].direct += value;
    } else {
        acc[pixel].specular += value;
    }
}

/// The final-gather rays of a tile pass, and reusable buffers.
#[derive(Default)]
struct Gathers {
    pending: Vec<Gather>,
    rays: Vec<Ray>,
    hits: Vec<Option<Hit>>,
    buf: KnnResult,
}

/// Shades one hit: emission, shadow rays, photon-map components, continuation.
fn shade(
    ctx: &RenderContext,
    mut path: PathState,
    hit: &Hit,
    acc: &mut [Radiance],
    shadows: &mut Vec<Shadow>,
    next: &mut Vec<PathState>,
    gathers: &mut Gathers,
) {
    let scene = ctx.scene;
    let si = SurfaceInteraction::new(scene, hit, &path.ray);

    // Emission seen along the ray.
    if let Some(li) = si.area_light() {
        let le = ctx.lights.le(li, si.ng, si.wo_world);
        if le.max_element() > 0.0 {
            let w = if path.prev_pdf > 0.0 {
                let light_pdf = ctx.lights.pdf_area(li, path.ray.o, si.p, si.ng);
                power_heuristic(path.prev_pdf, light_pdf)
            } else {
                1.0
            };
            let direct = path.depth == 0 || (path.depth == 1 && !path.prev_delta);
            add(acc, path.pixel, direct, path.beta * le * w);
        }
    }
    if path.depth >= ctx.settings.max_depth {
        return;
    }

    let bsdf = si.bsdf(scene);
    let flags = bsdf.flags();
    let wo = si.wo;
    let ls = ctx.settings.light_samples.max(1);
    path.sampler
        .set_dimension(CAMERA_DIMS + path.depth * dims_per_vertex(ls));

    // Gather rays double as BSDF samples for direct light at diffuse points.
    let gather_n = match &ctx.photons {
        Some(pass) if flags.has_diffuse() => photonmap::gather_count(pass),
        _ => 0,
    };

    // Direct light by shadow rays.
    if flags.has_non_specular() && !ctx.lights.is_empty() {
        for _ in 0..ls {
            let u_sel = path.sampler.next_1d();
            let u = path.sampler.next_2d();
            let Some(s) = ctx.lights.sample(scene, si.p, u_sel, u) else {
                continue;
            };
            let wi = si.frame.to_local(s.wi);
            let f = bsdf.f(wo, wi, TransportMode::Radiance) * wi.z.abs();
            if f.max_element() <= 0.0 {
                continue;
            }
            // MIS against BSDF sampling: one continuation ray on glossy surfaces, the final
            // gather's cosine-distributed rays on diffuse ones (multi-sample power heuristic).
            let w = if s.delta {
                1.0
            } else if flags.has_glossy() {
                power_heuristic(s.pdf, bsdf.pdf(wo, wi))
            } else if gather_n > 0 {
                power_heuristic(ls as f32 * s.pdf, gather_n as f32 * bsdf.pdf(wo, wi))
            } else {
                1.0
            };
            let contrib = path.beta * f * s.li * (w / (s.pdf * ls as f32));
            shadows.push(Shadow {
                pixel: path.pixel,
                ray: si.shadow_ray(&s),
                contrib,
                direct: path.depth == 0,
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
            &si,
            f_d,
            path.beta,
            path.pixel,
            primary,
            &mut path.sampler,
            &mut gathers.buf,
            &mut gathers.pending,
        );
        let px = &mut acc[path.pixel];
        if primary {
            px.caustic += got.caustic;
            px.indirect += got.indirect;
        } else {
            px.specular += got.caustic + got.indirect;
        }
    }

    // Continue through specular and glossy surfaces.
    if !(flags.has_specular() || flags.has_glossy()) {
        return;
    }
    let uc = path.sampler.next_1d();
    let u = path.sampler.next_2d();
    let Some(bs) = bsdf.sample(wo, uc, u, TransportMode::Radiance) else {
        return;
    };
    if bs.pdf <= 0.0 {
        return;
    }
    let beta = path.beta * bs.f * (bs.wi.z.abs() / bs.pdf);
    if beta.max_element() <= 0.0 || !beta.is_finite() {
        return;
    }
    next.push(PathState {
        pixel: path.pixel,
        ray: si.spawn_ray(si.frame.to_world(bs.wi)),
        beta,
        depth: path.depth + 1,
        prev_pdf: if bs.specular { 0.0 } else { bs.pdf },
        prev_delta: path.prev_delta && bs.specular,
        sampler: path.sampler,
    });
}

/// Traces a batch of shadow rays and adds the unoccluded contributions.
fn trace_shadows(
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
    ctx.accel.occluded_batch(rays, occluded);
    charge(&ctx.counters.ray_ns, t);
    ctx.counters
        .shadow_rays
        .fetch_add(rays.len() as u64, Ordering::Relaxed);
    for (s, &blocked) in shadows.iter().zip(occluded.iter()) {
        if !blocked {
            add(acc, s.pixel, s.direct, s.contrib);
        }
    }
}

/// Traces the pending gather rays as one batch and adds their radiance.
fn trace_gathers(ctx: &RenderContext, g: &mut Gathers, acc: &mut [Radiance]) {
    let Some(pass) = &ctx.photons else { return };
    if g.pending.is_empty() {
        return;
    }
    g.rays.clear();
    g.rays.extend(g.pending.iter().map(|x| x.ray));
    g.hits.clear();
    g.hits.resize(g.rays.len(), None);
    let t = Instant::now();
    ctx.accel.intersect_batch(&g.rays, &mut g.hits);
    charge(&ctx.counters.ray_ns, t);
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
            acc[gather.pixel].direct += direct;
            acc[gather.pixel].indirect += indirect;
        } else {
            acc[gather.pixel].specular += direct + indirect;
        }
    }
    charge(&ctx.counters.lookup_ns, t);
    g.pending.clear();
}
