//! Recording the rays of a real render, for `photon crosscheck` and `photon bench`.
//!
//! The rays are made by the renderer's own pieces, in the same order and with the same sample
//! streams as the integrator, so they are the rays a render with these settings casts:
//! - **camera**: `Camera::generate_ray` over the image, the pixel filter sampled from each
//!   pixel's stream, tile by tile and sample pass by sample pass (as `integrator::direct`);
//! - **shadow**: at the camera hits, `Lights::sample` and the segment built exactly as
//!   `integrator::direct::shade` builds it (origin spawned past the point's error bound, target
//!   offset off the light, `tmax = 1 - 1e-4`);
//! - **gather**: at diffuse camera hits, the stratified cosine-weighted final-gather
//!   directions of `integrator::photonmap::at_diffuse` (one of the point's gather rays, chosen
//!   by a hash, is kept);
//! - **photon**: every ray of photon paths from `Lights::emit`, continued by importance-mode
//!   BSDF sampling and roulette as `photon::trace` does (global photons, and caustic photons
//!   through projection maps when the scene needs a caustic map).
//!
//! Sampling is deterministic: camera work is taken in whole (tile, sample pass) blocks of up to
//! 256 coherent rays, blocks chosen in a seeded permuted order; photons are chosen by a seeded
//! permutation of the photon indices. The hits that shadow and gather rays start from come
//! from the `reference` backend given to [`record`].
use crate::accel::{Hit, RayQuery};
use crate::bsdf::TransportMode;
use crate::camera::Camera;
use crate::film::Filter;
use crate::integrator::photonmap::needed_maps;
use crate::integrator::{tile_pixels, RenderSettings, TILE};
use crate::interaction::SurfaceInteraction;
use crate::light::Lights;
use crate::math::{spawn_origin, Frame, Ray, Vec2, Vec3};
use crate::photon::projection::ProjectionMap;
use crate::photon::trace::{allocate, caustic_targets, scatter, MapKind, TraceSettings};
use crate::sampling::warp::square_to_cosine_hemisphere;
use crate::sampling::{hash, permute, strata, Sampler};
use crate::scene::Scene;
use std::fmt;

/// The kinds of rays a render casts.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum RayKind {
    Camera,
    Shadow,
    Photon,
    Gather,
}

impl RayKind {
    pub const ALL: [RayKind; 4] = [
        RayKind::Camera,
        RayKind::Shadow,
        RayKind::Photon,
        RayKind::Gather,
    ];

    pub fn name(self) -> &'static str {
        match self {
            RayKind::Camera => "camera",
            RayKind::Shadow => "shadow",
            RayKind::Photon => "photon",
            RayKind::Gather => "gather",
        }
    }
}

impl fmt::Display for RayKind {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// A diffuse point seen by a camera ray: where photon-map queries happen.
#[derive(Clone, Copy, Debug)]
pub struct DiffusePoint {
    pub p: Vec3,
    /// Unit shading normal turned towards the viewer.
    pub n: Vec3,
}

/// The recorded rays, by kind, plus the diffuse points the camera rays saw.
#[derive(Clone, Debug, Default)]
pub struct RecordedRays {
    pub camera: Vec<Ray>,
    pub shadow: Vec<Ray>,
    pub photon: Vec<Ray>,
    pub gather: Vec<Ray>,
    pub diffuse_points: Vec<DiffusePoint>,
}

impl RecordedRays {
    pub fn get(&self, kind: RayKind) -> &[Ray] {
        match kind {
            RayKind::Camera => &self.camera,
            RayKind::Shadow => &self.shadow,
            RayKind::Photon => &self.photon,
            RayKind::Gather => &self.gather,
        }
    }
}

/// Dimensions the camera sample uses (the pixel-filter offset), as in `integrator::direct`.
const CAMERA_DIMS: u32 = 2;
/// Camera blocks to look at, at most, per wanted ray: bounds the work on scenes where most
/// camera rays miss or land on specular surfaces (no shadow or gather rays there).
const BLOCK_BUDGET: usize = 16;

/// Records up to `n` rays of each kind of a render of `scene` with `settings`, choosing them
/// with `select_seed` (the sample streams themselves use `settings.seed`, as a render does).
/// `reference` answers the camera and photon rays whose hits the other rays start from.
pub fn record(
    scene: &Scene,
    reference: &dyn RayQuery,
    settings: &RenderSettings,
    n: usize,
    select_seed: u64,
) -> RecordedRays {
    let mut out = RecordedRays::default();
    let lights = Lights::new(scene);
    record_camera(
        scene,
        reference,
        &lights,
        settings,
        n,
        select_seed,
        &mut out,
    );
    out.photon = record_photons(scene, reference, &lights, settings, n, select_seed);
    out
}

/// What shading a camera hit needs.
struct Shading<'a> {
    scene: &'a Scene,
    lights: &'a Lights,
    settings: &'a RenderSettings,
    /// Whether the render makes gather rays at diffuse points.
    gathers: bool,
    select_seed: u64,
}

/// Camera rays in seeded blocks; shadow and gather rays at their hits.
fn record_camera(
    scene: &Scene,
    reference: &dyn RayQuery,
    lights: &Lights,
    s: &RenderSettings,
    n: usize,
    select_seed: u64,
    out: &mut RecordedRays,
) {
    let (w, h) = (s.width.max(1), s.height.max(1));
    let camera = Camera::new(&scene.camera, w, h);
    let filter = Filter::new(&scene.filter);
    let (tx, ty) = (w.div_ceil(TILE), h.div_ceil(TILE));
    let spp = s.spp.max(1);
    let blocks = tx as u64 * ty as u64 * spp as u64;
    let Ok(blocks) = u32::try_from(blocks) else {
        return;
    };
    let shading = Shading {
        scene,
        lights,
        settings: s,
        gathers: needed_maps(scene).0 && s.photon.final_gather,
        select_seed,
    };
    let max_blocks = (n * BLOCK_BUDGET).div_ceil((TILE * TILE) as usize);
    let mut rays = Vec::new();
    let mut samplers = Vec::new();
    let mut hits = Vec::new();
    for b in 0..blocks.min(max_blocks as u32) {
        let full = out.camera.len() >= n
            && out.shadow.len() >= n
            && (out.gather.len() >= n || !shading.gathers);
        if full || n == 0 {
            break;
        }
        let block = permute(b, blocks, hash(&[select_seed, 0xb10c]));
        let (tile, sample) = (block / spp, block % spp);
        let (x0, y0) = ((tile % tx) * TILE, (tile / tx) * TILE);
        rays.clear();
        samplers.clear();
        for (x, y) in tile_pixels(x0, y0, (x0 + TILE).min(w), (y0 + TILE).min(h)) {
            let pixel = y as u64 * w as u64 + x as u64;
            let mut sampler = Sampler::new(s.pattern, s.seed, pixel, sample, spp);
            let offset = filter.sample(sampler.next_2d());
            rays.push(camera.generate_ray(Vec2::new(x as f32 + 0.5, y as f32 + 0.5) + offset));
            samplers.push((pixel, sampler));
        }
        hits.clear();
        hits.resize(rays.len(), None);
        reference.intersect_batch(&rays, &mut hits);
        let room = n.saturating_sub(out.camera.len());
        out.camera.extend(rays.iter().take(room));
        for ((ray, hit), (pixel, sampler)) in rays.iter().zip(&hits).zip(samplers.drain(..)) {
            if let Some(hit) = hit {
                shade(&shading, ray, hit, pixel, sample, sampler, out);
            }
        }
    }
    out.shadow.truncate(n);
    out.gather.truncate(n);
    out.diffuse_points.truncate(n);
}

/// The shadow and gather rays `integrator::direct::shade` makes at a camera hit.
fn shade(
    c: &Shading,
    ray: &Ray,
    hit: &Hit,
    pixel: u64,
    sample: u32,
    mut sampler: Sampler,
    out: &mut RecordedRays,
) {
    let s = c.settings;
    if s.max_depth == 0 {
        return;
    }
    let mut si = SurfaceInteraction::new(c.scene, hit, ray);
    let bsdf = si.bsdf(c.scene);
    let ls = s.light_samples.max(1);
    sampler.set_dimension(CAMERA_DIMS);
    if bsdf.flags().has_non_specular() && !c.lights.is_empty() {
        for _ in 0..ls {
            let u_sel = sampler.next_1d();
            let u = sampler.next_2d();
            let Some(ls) = c.lights.sample(c.scene, si.p, u_sel, u) else {
                continue;
            };
            let wi = si.frame.to_local(ls.wi);
            let f = bsdf.f(si.wo, wi, TransportMode::Radiance) * wi.z.abs();
            if f.max_element() <= 0.0 {
                continue;
            }
            out.shadow.push(si.shadow_ray(&ls));
        }
    }
    if !bsdf.flags().has_diffuse() {
        return;
    }
    let n = si.facing_normal();
    out.diffuse_points.push(DiffusePoint { p: si.p, n });
    if c.gathers {
        sampler.set_dimension(CAMERA_DIMS + 3 * ls);
        out.gather
            .push(gather_ray(c, &si, pixel, sample, &mut sampler));
    }
}

/// One of the final-gather rays of `integrator::photonmap::at_diffuse` at `p` (normal `n`),
/// the k-th of the point's stratified set for a k chosen by hashing the pixel and sample.
fn gather_ray(
    c: &Shading,
    si: &SurfaceInteraction,
    pixel: u64,
    sample: u32,
    sampler: &mut Sampler,
) -> Ray {
    let n = si.facing_normal();
    let g = c.settings.photon.gather_samples.max(1);
    let keep = (hash(&[c.select_seed, pixel, sample as u64, 0x6a7]) % g as u64) as u32;
    let (nx, ny) = strata(g);
    let frame = Frame::from_normal(n);
    let o = si.spawn(n);
    let mut d = n;
    for k in 0..=keep {
        let j = sampler.next_2d();
        let u = Vec2::new(
            ((k % nx) as f32 + j.x) / nx as f32,
            ((k / nx) as f32 + j.y) / ny as f32,
        );
        d = frame.to_world(square_to_cosine_hemisphere(u));
        // at_diffuse keys each gather ray's own stream with two more 1D numbers.
        sampler.next_1d();
        sampler.next_1d();
    }
    Ray::new(o, d)
}

/// Rays of photon paths: global photons, and caustic photons when the scene needs them.
fn record_photons(
    scene: &Scene,
    reference: &dyn RayQuery,
    lights: &Lights,
    s: &RenderSettings,
    n: usize,
    select_seed: u64,
) -> Vec<Ray> {
    let mut trace = s.photon.trace.clone();
    trace.seed = s.seed;
    trace.pattern = s.pattern;
    let (need_global, need_caustic) = needed_maps(scene);
    let mut maps = Vec::new();
    if need_global && trace.global_photons > 0 {
        maps.push(MapKind::Global);
    }
    if need_caustic && trace.caustic_photons > 0 {
        maps.push(MapKind::Caustic);
    }
    let mut out = Vec::with_capacity(n);
    for (i, &kind) in maps.iter().enumerate() {
        let want = n * (i + 1) / maps.len();
        photon_paths(
            scene,
            reference,
            lights,
            &trace,
            kind,
            want,
            select_seed,
            &mut out,
        );
    }
    out.truncate(n);
    out
}

/// Appends the rays of photon paths of map `kind` to `out` until it holds `want` rays (or
/// every photon was traced).
#[allow(clippy::too_many_arguments)]
fn photon_paths(
    scene: &Scene,
    reference: &dyn RayQuery,
    lights: &Lights,
    t: &TraceSettings,
    kind: MapKind,
    want: usize,
    select_seed: u64,
    out: &mut Vec<Ray>,
) {
    let powers = lights.powers(scene);
    let total = match kind {
        MapKind::Global => t.global_photons,
        MapKind::Caustic => t.caustic_photons,
    };
    let counts = allocate(total, &powers);
    let targets = caustic_targets(scene);
    let maps: Vec<ProjectionMap> = (0..powers.len())
        .map(|i| match kind {
            MapKind::Caustic if t.projection_maps && counts[i] > 0 => {
                ProjectionMap::build(scene, lights, i, &targets, t.projection_resolution)
            }
            _ => ProjectionMap::full(lights.emission_domain(scene, i)),
        })
        .collect();
    let Ok(total) = u32::try_from(counts.iter().sum::<u64>()) else {
        return;
    };
    let seed = hash(&[select_seed, kind as u64, 0x9407]);
    for j in 0..total {
        if out.len() >= want {
            break;
        }
        // Photon `g` of the whole map is photon `idx` of light `light`.
        let mut g = permute(j, total, seed) as u64;
        let mut light = 0;
        while g >= counts[light] {
            g -= counts[light];
            light += 1;
        }
        let domain = hash(&[kind as u64, light as u64]);
        let mut sampler = Sampler::new(t.pattern, t.seed, domain, g as u32, counts[light] as u32);
        let path = PhotonPath {
            scene,
            lights,
            kind,
            light,
            map: &maps[light],
            targets: &targets,
            max_bounces: t.max_bounces,
        };
        path.trace(reference, &mut sampler, out);
    }
}

/// One photon's path, as `photon::trace` traces it.
struct PhotonPath<'a> {
    scene: &'a Scene,
    lights: &'a Lights,
    kind: MapKind,
    light: usize,
    map: &'a ProjectionMap,
    targets: &'a [(Vec3, f32)],
    max_bounces: u32,
}

impl PhotonPath<'_> {
    /// Appends every ray the photon casts to `out`.
    fn trace(&self, accel: &dyn RayQuery, sampler: &mut Sampler, out: &mut Vec<Ray>) {
        let (mut u_pos, mut u_dir) = (sampler.next_2d(), sampler.next_2d());
        let restricted = match self.map.domain {
            crate::light::EmissionDomain::Direction => &mut u_dir,
            crate::light::EmissionDomain::Position => &mut u_pos,
        };
        let Some(u) = self.map.sample(*restricted) else {
            return;
        };
        *restricted = u;
        let Some(e) = self.lights.emit(self.scene, self.light, u_pos, u_dir) else {
            return;
        };
        let reaches = |&(c, r): &(Vec3, f32)| ray_meets_sphere(e.p, e.dir, c, r);
        if self.kind == MapKind::Caustic && !self.targets.iter().any(reaches) {
            return;
        }
        let o = if e.n == Vec3::ZERO {
            e.p
        } else {
            spawn_origin(e.p, e.err, e.n)
        };
        let mut ray = Ray::new(o, e.dir);
        for _ in 0..self.max_bounces {
            out.push(ray);
            let Some(hit) = accel.intersect(&ray) else {
                break;
            };
            let mut si = SurfaceInteraction::new(self.scene, &hit, &ray);
            let bsdf = si.bsdf(self.scene);
            if self.kind == MapKind::Caustic && !bsdf.flags().has_specular() {
                break;
            }
            let Some(sc) = scatter(&si, &bsdf, sampler) else {
                break;
            };
            ray = sc.ray;
        }
    }
}

/// Whether the ray from `o` along unit `d` meets the sphere `(c, r)` (the caustic pass's
/// rejection test).
fn ray_meets_sphere(o: Vec3, d: Vec3, c: Vec3, r: f32) -> bool {
    let v = c - o;
    if v.length_squared() <= r * r {
        return true;
    }
    let along = v.dot(d);
    along > 0.0 && (v - d * along).length_squared() <= r * r
}
