//! The photon mapper's pass 2 as an integrator (Jensen's split of reflected radiance; the
//! estimates themselves are in [`super::photonmap`]): at each hit the direct integrator's
//! steps (emission, shadow rays, specular continuation: [`super::direct`]) and, between them,
//!
//! - at diffuse points the caustic-map estimate and the final gather (or the global map's
//!   estimate); shadow rays there are weighed by MIS against the gather rays;
//! - at rough glossy surfaces without a diffuse lobe the caustic photons stored there
//!   ([`photonmap::at_glossy`]), after which the path must not count again what those
//!   photons carry ([`Covered`]).
//!
//! Components: `direct` and `specular` as the direct integrator; the caustic and gathered
//! estimates of a primary point are `caustic` and `indirect`, those seen through specular
//! bounces `specular`.
use super::direct::{self, continuation, emission, shadow_rays, Vertex};
use super::photonmap::{self, Gather};
use super::wavefront::{self, add, Component, PathState, Shade, Sums, Wave};
use super::{charge, RenderContext};
use crate::accel::{Hit, RayKind};
use crate::bsdf::TransportMode;
use crate::film::Radiance;
use crate::interaction::SurfaceInteraction;
use crate::math::{Ray, Vec3};
use crate::photon::guide::GuideSlot;
use crate::photon::trace;
use crate::photon::KnnResult;
use crate::spectrum::Spectrum;
use std::sync::atomic::Ordering;
use std::time::Instant;

/// Renders the pixels `[x0, x1) x [y0, y1)` with the photon maps of `ctx.photons`.
pub fn render_tile(ctx: &RenderContext, x0: u32, y0: u32, x1: u32, y1: u32) -> Vec<Radiance> {
    wavefront::render_tile(ctx, &PhotonMapper, x0, y0, x1, y1)
}

/// Pass 2 of the photon mapper.
pub struct PhotonMapper;

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

impl Shade for PhotonMapper {
    type Extra = Gathers;
    type PathData = Covered;

    fn shade(
        &self,
        ctx: &RenderContext,
        path: PathState<Covered>,
        hit: &Hit,
        wave: &mut Wave<Gathers, Covered>,
    ) {
        shade(ctx, path, hit, wave)
    }

    fn emitted_component(&self, path: &PathState<Covered>) -> Component {
        direct::emitted_component(path)
    }

    fn escaped(&self, ctx: &RenderContext, path: &PathState<Covered>) -> Spectrum {
        if path.data == Covered::Specular {
            return Spectrum::ZERO; // an L S+ G path: the glossy surface's caustic photons have it
        }
        wavefront::escaped(ctx, path)
    }

    fn pending(&self, g: &Gathers) -> usize {
        g.pending.len()
    }

    fn flush(&self, ctx: &RenderContext, g: &mut Gathers, acc: &mut [Sums]) {
        trace_gathers(ctx, g, acc)
    }
}

/// Shades one hit: emission, shadow rays, photon-map estimates, continuation.
fn shade(
    ctx: &RenderContext,
    mut path: PathState<Covered>,
    hit: &Hit,
    wave: &mut Wave<Gathers, Covered>,
) {
    let Some(pass) = &ctx.photons else {
        return;
    };
    let si = SurfaceInteraction::new(ctx.scene, hit, &path.ray);
    // Emission seen along the ray, unless the caustic photons of a glossy surface the path
    // left through sharp bounces only have counted it.
    if path.data != Covered::Specular {
        emission(ctx, &path, &si, wave.acc);
    }
    if path.depth >= ctx.settings.max_depth {
        return;
    }
    let v = Vertex::new(ctx, &mut path, si);
    let si = &v.si;

    // Gather rays double as BSDF samples for direct light at diffuse points.
    let gather_n = if v.flags.has_diffuse() {
        photonmap::gather_count(pass)
    } else {
        0
    };
    let guide = if gather_n > 0 {
        let x = &mut *wave.extra;
        let slot = if path.depth == 0 {
            if x.guides.len() <= path.pixel {
                x.guides.resize(path.pixel + 1, None);
            }
            Some(&mut x.guides[path.pixel])
        } else {
            None
        };
        photonmap::gather_guide(pass, &ctx.counters.lookup_ns, si, &mut x.buf, slot)
    } else {
        None
    };

    // Sharp bounces after a receiver: light arriving here is in the receiver's caustic
    // photons (L (S|G)+ G paths with near-smooth G), so this vertex casts no shadow rays when
    // its only non-delta lobe is near-smooth.
    let sharp_alpha = photonmap::caustic_alpha(pass);
    let covered_here = path.data != Covered::No
        && sharp_alpha.is_some_and(|a| v.bsdf.glossy_alpha().is_some_and(|g| g < a));

    // Direct light: at diffuse points MIS against the final gather's rays (multi-sample
    // power heuristic).
    let ls = v.ls;
    let front = photonmap::gather_front_share(&v.bsdf, si.wo);
    shadow_rays(
        ctx,
        &mut path,
        &v,
        wave.shadows,
        covered_here,
        |light_pdf, wi| {
            if gather_n > 0 {
                let gather_pdf = photonmap::gather_pdf(si, guide.as_ref(), front, wi);
                crate::sampling::power_heuristic(
                    ls as f32 * light_pdf,
                    gather_n as f32 * gather_pdf,
                )
            } else {
                1.0
            }
        },
    );

    // Caustics and indirect diffuse light from the photon maps.
    if v.flags.has_diffuse() {
        let wo = si.wo;
        let f_d = v.bsdf.f(
            wo,
            Vec3::new(0.0, 0.0, wo.z.signum()),
            TransportMode::Radiance,
        );
        let primary = path.depth == 0;
        path.sampler.set_dimension(v.after_shadow_rays(&path));
        let got = photonmap::at_diffuse(
            pass,
            &ctx.counters.lookup_ns,
            ls,
            guide.as_ref(),
            si,
            &v.bsdf,
            f_d,
            path.beta,
            path.pixel,
            path.depth,
            path.lambda,
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
    if !v.flags.has_diffuse() {
        let buf = &mut wave.extra.buf;
        if let Some(l) = photonmap::at_glossy(
            pass,
            &ctx.counters.lookup_ns,
            (si, path.depth),
            &v.bsdf,
            path.lambda,
            buf,
        ) {
            receiver = true;
            let c = if path.depth == 0 {
                Component::Caustic
            } else {
                Component::Specular
            };
            add(wave.acc, path.pixel, c, path.beta * l);
        }
    }

    if let Some((bs, mut next)) = continuation(path, &v) {
        let sharp = sharp_alpha.is_some_and(|a| trace::is_sharp_bounce(&v.bsdf, bs.lobe_alpha, a));
        next.data = next.data.after(receiver, sharp);
        wave.next.push(next);
    }
}

/// Traces the pending gather rays as one batch and adds their radiance.
fn trace_gathers(ctx: &RenderContext, g: &mut Gathers, acc: &mut [Sums]) {
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
