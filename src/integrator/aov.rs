//! Data channels (AOVs) beside the beauty image: what the camera sees first, for compositing,
//! for the denoiser's guides and for pbrt-v4's `Film "gbuffer"`.
//!
//! ```text
//! Film "gbuffer" "string coordinatesystem" "camera"     # or "world"
//! photon render scene.pbrt --aov alpha,albedo,normal,depth,position
//! ```
//!
//! A pass of its own after the render (integrators only write radiance): per pixel, the first
//! [`MAX_SAMPLES`] camera samples of the render (same pixel-filter offsets, same lens samples)
//! are traced to their first surface. Media are not entered and no light is computed, so the
//! pass costs a camera ray per sample plus the chains through mirrors and smooth glass.
//!
//! `--aov` channels (OpenEXR's usual names):
//! - `A` (alpha): the fraction of camera samples that hit a surface (0 where only the
//!   environment is seen).
//! - `albedo.R/G/B` and `normal.X/Y/Z`, the denoiser's guides (Cycles' and Open Image
//!   Denoise's convention): taken at the first surface that is not purely specular, following
//!   mirrors and smooth glass (up to [`MAX_SPECULAR`] bounces) with their Fresnel weights;
//!   albedo is the surface's directional albedo `rho(wo)` (one sample of the BSDF per camera
//!   sample, `f cos / pdf`), clamped to [0, 1]; normal is the world-space shading normal.
//!   Where a path leaves the scene, albedo is the environment's radiance clamped to [0, 1] and
//!   the normal 0.
//! - `Z` (depth): camera-space z of the first hit, averaged over the samples that hit;
//!   +infinity where none did.
//! - `P.X/Y/Z` (position): world-space position of the first hit, averaged over hits.
//!
//! `Film "gbuffer"` channels, as pbrt-v4's `GBufferFilm` writes them (at the camera ray's
//! first hit, in the film's `coordinatesystem`): `Albedo.R/G/B` (`rho(wo)`, averaged over
//! all samples), `P.X/Y/Z`, `dzdx`, `dzdy` (the z change of the hit's tangent plane between
//! neighbouring pixels, absolute), `N.X/Y/Z` (geometric) and `Ns.X/Y/Z` (shading) normals
//! (normalized sums), `u`, `v`; averaged over the samples that hit. Its `Variance.R/G/B` and
//! `RelativeVariance.R/G/B` (pbrt-v4's: variance over mean) are the beauty render's per-pixel
//! sample statistics ([`super::RenderOutput::variance`]; per-pixel integrators over a fixed
//! sample count only: not the bidirectional ones, not `--time`, not renders in passes).
use super::{camera_sample, tile_pixels, RenderContext, TILE};
use crate::accel::RayKind;
use crate::bsdf::TransportMode;
use crate::interaction::SurfaceInteraction;
use crate::light::Pick;
use crate::math::{Mat4, Ray, Vec2, Vec3};
use rayon::prelude::*;

/// Camera samples per pixel the pass traces at most (the render's own count when lower): the
/// data channels converge far faster than radiance.
pub const MAX_SAMPLES: u32 = 16;

/// Mirror and smooth-glass bounces the guides follow at most.
pub const MAX_SPECULAR: u32 = 8;

pub use crate::film::Space;

/// The data channels `--aov` asks for.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum Aov {
    /// `A`: the fraction of camera samples that hit a surface.
    Alpha,
    /// `albedo.R/G/B`: the denoiser's albedo guide (first non-specular surface).
    Albedo,
    /// `normal.X/Y/Z`: the denoiser's normal guide (world-space shading normal there).
    Normal,
    /// `Z`: camera-space depth of the first hit.
    Depth,
    /// `P.X/Y/Z`: world-space position of the first hit.
    Position,
}

/// What the pass computes: `--aov` channels and the film's gbuffer.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Request {
    pub aovs: Vec<Aov>,
    pub gbuffer: Option<Space>,
}

impl Request {
    /// Whether anything is asked for.
    pub fn is_empty(&self) -> bool {
        self.aovs.is_empty() && self.gbuffer.is_none()
    }

    fn wants(&self, a: Aov) -> bool {
        self.aovs.contains(&a)
    }

    /// Bytes per pixel the pass and its channels keep (for the memory model): the per-pixel
    /// sums, the channels written and, for a gbuffer, the variances.
    pub fn bytes_per_pixel(&self) -> u64 {
        if self.is_empty() {
            return 0;
        }
        let floats = [
            (Aov::Alpha, 1),
            (Aov::Albedo, 3),
            (Aov::Normal, 3),
            (Aov::Depth, 1),
        ]
        .iter()
        .filter(|(a, _)| self.wants(*a))
        .map(|(_, n)| n)
        .sum::<u64>()
            + match self.gbuffer {
                Some(_) => 19 + 6 + 6,
                None => 3 * u64::from(self.wants(Aov::Position)),
            };
        std::mem::size_of::<Sums>() as u64 + 4 * floats
    }
}

/// Named float channels, one sample per pixel of the crop window's image, row-major.
pub type Channels = Vec<(String, Vec<f32>)>;

/// Per-pixel sums of one pixel's samples.
#[derive(Clone, Copy, Debug, Default)]
struct Sums {
    samples: f32,
    hits: f32,
    guide_albedo: Vec3,
    guide_normal: Vec3,
    world_p: Vec3,
    albedo: Vec3,
    n: Vec3,
    ns: Vec3,
    uv: Vec2,
    dpdx: Vec3,
    dpdy: Vec3,
}

/// What one camera sample adds (see [`Sums`]).
#[derive(Clone, Copy, Debug, Default)]
struct First {
    /// The world position, geometric and shading normals, uv and rho of the first hit.
    p: Vec3,
    n: Vec3,
    ns: Vec3,
    uv: Vec2,
    rho: Vec3,
    /// `dp/dx`, `dp/dy` on the hit's tangent plane (world space).
    dpdx: Vec3,
    dpdy: Vec3,
}

/// Renders the channels `request` asks for over the render's pixels (the crop window's), in
/// parallel tiles on the current rayon pool; the gbuffer's variance channels are not among
/// them (they come from the beauty render).
pub fn render(ctx: &RenderContext, request: &Request) -> Channels {
    let [bx0, x1, by0, y1] = ctx.settings.pixel_bounds();
    let tiles: Vec<(u32, u32)> = (by0..y1)
        .step_by(TILE as usize)
        .flat_map(|y| (bx0..x1).step_by(TILE as usize).map(move |x| (x, y)))
        .collect();
    let done: Vec<((u32, u32), Vec<Sums>)> = tiles
        .par_iter()
        .map(|&(x0, y0)| {
            let (tx1, ty1) = ((x0 + TILE).min(x1), (y0 + TILE).min(y1));
            ((x0, y0), tile(ctx, x0, y0, tx1, ty1))
        })
        .collect();
    let (w, h) = ((x1 - bx0) as usize, (y1 - by0) as usize);
    let mut sums = vec![Sums::default(); w * h];
    for ((x0, y0), px) in done {
        let tw = ((x0 + TILE).min(x1) - x0) as usize;
        for (i, s) in px.into_iter().enumerate() {
            let (x, y) = ((x0 - bx0) as usize + i % tw, (y0 - by0) as usize + i / tw);
            sums[y * w + x] = s;
        }
    }
    let camera_from_world = ctx.scene.camera.world_from_camera.inverse();
    channels(&sums, request, camera_from_world)
}

/// The sums of the pixels `[x0, x1) x [y0, y1)`, row-major.
fn tile(ctx: &RenderContext, x0: u32, y0: u32, x1: u32, y1: u32) -> Vec<Sums> {
    let n = ctx.settings.spp.clamp(1, MAX_SAMPLES);
    let mut sums = vec![Sums::default(); ((x1 - x0) * (y1 - y0)) as usize];
    let mut rays = Vec::new();
    let mut samplers = Vec::new();
    let mut hits = Vec::new();
    for sample in 0..n {
        rays.clear();
        samplers.clear();
        for (x, y) in tile_pixels(x0, y0, x1, y1) {
            let (ray, sampler) = camera_sample(ctx, x, y, sample);
            rays.push(ray);
            samplers.push((sampler, Vec2::new(x as f32, y as f32)));
        }
        hits.clear();
        hits.resize(rays.len(), None);
        ctx.accel.intersect_batch(RayKind::Camera, &rays, &mut hits);
        for (i, ((ray, hit), (sampler, pixel))) in
            rays.iter().zip(&hits).zip(samplers.iter_mut()).enumerate()
        {
            let s = &mut sums[i];
            s.samples += 1.0;
            let Some(hit) = hit else {
                s.guide_albedo += environment_albedo(ctx, ray);
                continue;
            };
            let mut si = SurfaceInteraction::new(ctx.scene, hit, ray);
            let bsdf = si.bsdf(
                ctx.scene,
                ctx.settings.footprint(),
                crate::spectrum::Lambda::Rgb,
            );
            let first = first_hit(ctx, &si, &bsdf, *pixel, sampler);
            s.hits += 1.0;
            s.albedo += first.rho;
            s.world_p += first.p;
            s.n += first.n;
            s.ns += first.ns;
            s.uv += first.uv;
            s.dpdx += first.dpdx;
            s.dpdy += first.dpdy;
            let (albedo, normal) = match bsdf.flags().is_specular_only() {
                true => guide_through(ctx, &si, &bsdf, sampler),
                false => (first.rho, first.ns),
            };
            s.guide_albedo += albedo.clamp(Vec3::ZERO, Vec3::ONE);
            s.guide_normal += normal;
        }
    }
    sums
}

/// The first hit's record; `pixel` is the pixel's corner (for the differentials).
fn first_hit(
    ctx: &RenderContext,
    si: &SurfaceInteraction,
    bsdf: &crate::bsdf::Bsdf,
    pixel: Vec2,
    sampler: &mut crate::sampling::Sampler,
) -> First {
    let uc = sampler.next_1d();
    let u = sampler.next_2d();
    let rho = match bsdf.sample(si.wo, uc, u, TransportMode::Radiance) {
        Some(bs) if bs.pdf > 0.0 => bs.f.rgb() * (bs.wi.z.abs() / bs.pdf),
        _ => Vec3::ZERO,
    };
    let rho = if rho.is_finite() { rho } else { Vec3::ZERO };
    // The tangent plane's points under the rays through the neighbouring pixels' centres.
    let centre = pixel + Vec2::splat(0.5);
    let on_plane = |d: Vec2| {
        let r = ctx.camera.generate_ray(centre + d);
        let denom = si.ng.dot(r.d);
        let t = si.ng.dot(si.p - r.o) / denom;
        let q = r.o + r.d * t;
        if denom.abs() > 1e-8 && q.is_finite() {
            q
        } else {
            si.p
        }
    };
    let base = on_plane(Vec2::ZERO);
    First {
        p: si.p,
        n: si.ng,
        ns: si.ns,
        uv: si.uv,
        rho,
        dpdx: on_plane(Vec2::X) - base,
        dpdy: on_plane(Vec2::Y) - base,
    }
}

/// The guides behind a purely specular first hit: the path follows the BSDF's samples to the
/// first surface that is not purely specular (its `rho` times the Fresnel weights, and its
/// shading normal) or out to the environment.
fn guide_through(
    ctx: &RenderContext,
    si: &SurfaceInteraction,
    bsdf: &crate::bsdf::Bsdf,
    sampler: &mut crate::sampling::Sampler,
) -> (Vec3, Vec3) {
    let mut beta = Vec3::ONE;
    let (mut wo, mut frame, mut p) = (si.wo, si.frame, *si);
    let mut bsdf = *bsdf;
    for _ in 0..MAX_SPECULAR {
        let uc = sampler.next_1d();
        let u = sampler.next_2d();
        let Some(bs) = bsdf.sample(wo, uc, u, TransportMode::Radiance) else {
            return (Vec3::ZERO, Vec3::ZERO);
        };
        if bs.pdf <= 0.0 {
            return (Vec3::ZERO, Vec3::ZERO);
        }
        beta *= bs.f.rgb() * (bs.wi.z.abs() / bs.pdf);
        let ray = p.spawn_ray(frame.to_world(bs.wi));
        let Some(hit) = ctx.accel.intersect(RayKind::Bounce, &ray) else {
            return (beta * environment_albedo(ctx, &ray), Vec3::ZERO);
        };
        let mut next = SurfaceInteraction::new(ctx.scene, &hit, &ray);
        bsdf = next.bsdf(
            ctx.scene,
            ctx.settings.footprint(),
            crate::spectrum::Lambda::Rgb,
        );
        if !bsdf.flags().is_specular_only() {
            let uc = sampler.next_1d();
            let u = sampler.next_2d();
            let rho = match bsdf.sample(next.wo, uc, u, TransportMode::Radiance) {
                Some(bs) if bs.pdf > 0.0 => bs.f.rgb() * (bs.wi.z.abs() / bs.pdf),
                _ => Vec3::ZERO,
            };
            let albedo = beta * rho;
            return match albedo.is_finite() {
                true => (albedo, next.ns),
                false => (Vec3::ZERO, next.ns),
            };
        }
        (wo, frame) = (next.wo, next.frame);
        p = next;
    }
    (Vec3::ZERO, Vec3::ZERO)
}

/// The albedo guide of a ray leaving the scene: the environment's radiance, clamped to [0, 1].
fn environment_albedo(ctx: &RenderContext, ray: &Ray) -> Vec3 {
    let d = ray.d.normalize_or_zero();
    let le = ctx.lights.escaped(ray.o, d, Pick::Power, |_, _| 1.0);
    match le.is_finite() {
        true => le.clamp(Vec3::ZERO, Vec3::ONE),
        false => Vec3::ZERO,
    }
}

/// The channels of `request` from the per-pixel sums.
fn channels(sums: &[Sums], request: &Request, camera_from_world: Mat4) -> Channels {
    let mut out: Channels = Vec::new();
    let mut push = |name: &str, f: &dyn Fn(&Sums) -> f32| {
        out.push((name.to_string(), sums.iter().map(f).collect()));
    };
    let per_hit = |s: &Sums, v: f32| if s.hits > 0.0 { v / s.hits } else { 0.0 };
    let unit = |v: Vec3| v.normalize_or_zero();
    if request.wants(Aov::Alpha) {
        push("A", &|s| s.hits / s.samples.max(1.0));
    }
    if request.wants(Aov::Albedo) {
        for (c, name) in ["albedo.R", "albedo.G", "albedo.B"].iter().enumerate() {
            push(name, &|s| s.guide_albedo[c] / s.samples.max(1.0));
        }
    }
    if request.wants(Aov::Normal) {
        for (c, name) in ["normal.X", "normal.Y", "normal.Z"].iter().enumerate() {
            push(name, &|s| unit(s.guide_normal)[c]);
        }
    }
    if request.wants(Aov::Depth) {
        push("Z", &|s| match s.hits > 0.0 {
            true => camera_from_world.transform_point3(s.world_p / s.hits).z,
            false => f32::INFINITY,
        });
    }
    let Some(space) = request.gbuffer else {
        if request.wants(Aov::Position) {
            for (c, name) in ["P.X", "P.Y", "P.Z"].iter().enumerate() {
                push(name, &|s| per_hit(s, s.world_p[c]));
            }
        }
        return out;
    };
    // The gbuffer's own `P` (in its space) stands for `--aov position`.
    let m = match space {
        Space::Camera => camera_from_world,
        Space::World => Mat4::IDENTITY,
    };
    let point = |s: &Sums| match s.hits > 0.0 {
        true => m.transform_point3(s.world_p / s.hits),
        false => Vec3::ZERO,
    };
    let vector = |v: Vec3| m.transform_vector3(v);
    for (c, name) in ["Albedo.R", "Albedo.G", "Albedo.B"].iter().enumerate() {
        push(name, &|s| s.albedo[c] / s.samples.max(1.0));
    }
    for (c, name) in ["P.X", "P.Y", "P.Z"].iter().enumerate() {
        push(name, &|s| point(s)[c]);
    }
    // pbrt-v4 sums `outputFromRender(dpdx).z`: the z of the transformed vector.
    push("dzdx", &|s| per_hit(s, vector(s.dpdx).z).abs());
    push("dzdy", &|s| per_hit(s, vector(s.dpdy).z).abs());
    for (c, name) in ["N.X", "N.Y", "N.Z"].iter().enumerate() {
        push(name, &|s| unit(vector(s.n))[c]);
    }
    for (c, name) in ["Ns.X", "Ns.Y", "Ns.Z"].iter().enumerate() {
        push(name, &|s| unit(vector(s.ns))[c]);
    }
    push("u", &|s| per_hit(s, s.uv.x));
    push("v", &|s| per_hit(s, s.uv.y));
    out
}

/// pbrt-v4's metadata matrices of a camera: `cameraFromWorld` and `NDCFromWorld =
/// Translate(0.5, 0.5, 0.5) Scale(0.5, 0.5, 0.5) screenFromCamera cameraFromWorld`
/// (`ProjectiveCamera::InitMetadata`), for column vectors; `screenFromCamera` is
/// `Perspective(fov, 0.01, 1000)`, or `Orthographic(0, 1)` (the identity) for an orthographic
/// camera.
pub fn camera_matrices(desc: &crate::scene::CameraDesc) -> (Mat4, Mat4) {
    let camera_from_world = desc.world_from_camera.inverse();
    let (n, f) = (1e-2f32, 1000.0f32);
    let inv_tan = 1.0 / (desc.fov_deg.to_radians() * 0.5).tan();
    let perspective = Mat4::from_cols_array_2d(&[
        [1.0, 0.0, 0.0, 0.0],
        [0.0, 1.0, 0.0, 0.0],
        [0.0, 0.0, f / (f - n), 1.0],
        [0.0, 0.0, -f * n / (f - n), 0.0],
    ]);
    let screen_from_camera = match desc.projection {
        crate::scene::Projection::Perspective => {
            Mat4::from_scale(Vec3::new(inv_tan, inv_tan, 1.0)) * perspective
        }
        crate::scene::Projection::Orthographic => Mat4::IDENTITY,
    };
    let ndc_from_screen =
        Mat4::from_translation(Vec3::splat(0.5)) * Mat4::from_scale(Vec3::splat(0.5));
    (
        camera_from_world,
        ndc_from_screen * screen_from_camera * camera_from_world,
    )
}
