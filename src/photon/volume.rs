//! The volume photon map (Jensen & Christensen 1998) read by beam radiance estimates (Jarosz,
//! Zwicker & Jensen 2008), for scenes with scattering media (issue 18).
//!
//! - **Tracing** ([`trace`]): photons leave the lights (chosen by power, each photon's numbers
//!   keyed by the seed and its index, so the map does not depend on thread count) in the
//!   medium of their light (`MediumInterface` of the area light's shape, or the one current at
//!   `LightSource`), cross `interface` surfaces, scatter off surfaces by their BSDF in
//!   importance mode with Russian and RGB roulette ([`super::trace::scatter`]), and in a
//!   scattering medium sample their next interaction ([`Medium::sample_distance`]). At each
//!   medium interaction the photon is stored with the power it scatters (`sigma_s T / pdf`
//!   folded in) and its direction of travel, then continues in a Henyey-Greenstein direction,
//!   surviving with probability `min(1, max(albedo weight))`. Photons are emitted in batches
//!   until `target` are stored (cut at a photon's end, so every emitted photon's stores are
//!   all in or all out; the powers are divided by the photons emitted up to there).
//! - **Beam estimate** ([`VolumeMap::beam`]): every photon is a sphere of radius `r`; a ray
//!   segment gathers the photons whose sphere it crosses,
//!   `L = sum_i p(wo, -d_i) Phi_i T(t_i) / (pi r^2)`, with `t_i` the ray's closest approach to
//!   photon `i` and `T` the transmittance of the segment's medium up to there: all the light
//!   the medium scatters towards the ray, single and multiple scattering alike, with no
//!   distance sampling. The photons are binned in a dense grid of cells at least `2r` wide
//!   (each photon listed in every cell its sphere's box touches, at most 8); a 3D DDA walks the
//!   cells the segment crosses and counts a photon only in the cell that holds the ray's point
//!   of closest approach to it, so no photon counts twice.
//! - **Caustic photons through media** ([`trace_caustic`]): photons aimed by projection maps
//!   at the specular objects, as the surface caustic map's are, followed while they bounce off
//!   delta lobes only and nothing in a medium scatters them (each segment dimmed by its
//!   medium), and stored where they land on a purely diffuse surface (`L S+ D`): the caustic
//!   map the path tracer reads in such scenes ([`crate::integrator::path`]).
//! - **Point estimate** ([`VolumeMap::point`]): at the scattering points of paths past the
//!   camera segments, the photons within twice the radius give all the light scattered there
//!   (Jensen & Christensen's volume radiance estimate), from photons whose path joined to
//!   the camera's stays within `maxdepth` scattering events; the path ends there.
//! - The radius is `volumeradius`, a fraction of the scene's bounding radius; progressive
//!   passes (`--progressive`) re-trace the map each pass and shrink the radius with the
//!   surface maps' (Knaus-Zwicker's `alpha`).
use crate::accel::{Accel, RayKind};
use crate::interaction::SurfaceInteraction;
use crate::light::Lights;
use crate::math::{spawn_origin, Ray, Vec2, Vec3};
use crate::medium::{henyey_greenstein, sample_henyey_greenstein, Medium, MediumEvent};
use crate::photon::stored::Photon;
use crate::sampling::{hash, mix64, to_unit};
use crate::scene::Scene;
use rayon::prelude::*;

/// One photon stored in a medium.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct VolumePhoton {
    pub p: Vec3,
    /// Unit direction the photon travelled in when it scattered here.
    pub d: Vec3,
    /// The power it scatters here.
    pub power: Vec3,
    /// Its scattering vertices from the light, this one included (surfaces and media).
    pub vertices: u32,
}

/// Bytes a stored volume photon costs at its peak, for the memory model: the photon with the
/// tracer's growth slack (2 x 40), and while the grid is built up to 8 (cell, photon) pairs
/// (8 x 8) beside the 8 references they become (8 x 4).
pub const VOLUME_PHOTON_BYTES: u64 = 2 * 40 + 8 * 8 + 8 * 4;

/// Bytes of the dense cell grid at most ([`MAX_CELLS_PER_AXIS`] cubed, 8 bytes a cell).
pub const MAX_GRID_BYTES: u64 = (MAX_CELLS_PER_AXIS as u64).pow(3) * 8;

/// The grid has at most this many cells along an axis (cells widen past `2r` to keep to it).
pub const MAX_CELLS_PER_AXIS: u32 = 128;

/// The point estimates' radius over the beams' ([`VolumeMap::point`]): twice as wide, eight
/// times the photons, for the scattering points of paths that read the map many times each.
pub const POINT_RADIUS_SCALE: f32 = 2.0;

/// Photons emitted per batch between checks of the stored count.
const BATCH: u64 = 1 << 16;

/// Photons per parallel work item within a batch.
const CHUNK: u64 = 1 << 10;

/// What a traced photon leaves behind.
enum Store {
    Volume(VolumePhoton),
    /// An `L S+ D` photon on a purely diffuse surface.
    Caustic(Photon),
}

/// Whether photons landing on a surface with these lobes are stored as caustic photons
/// through media, and camera paths there read them: purely diffuse surfaces.
pub fn is_caustic_receiver(flags: crate::bsdf::BxdfFlags) -> bool {
    flags.has_diffuse() && !flags.has_specular() && !flags.has_glossy()
}

/// What [`trace`] did.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct VolumeStats {
    pub emitted: u64,
    pub stored: u64,
    /// Caustic photons emitted and stored on diffuse surfaces (see the module docs), and
    /// the seconds they took.
    pub caustic_emitted: u64,
    pub caustic: u64,
    pub caustic_seconds: f64,
    pub rays: u64,
    /// Tracing, and binning ([`VolumeMap::build`], filled in by its caller).
    pub seconds: f64,
    pub build_seconds: f64,
}

/// Traces photons from `lights` until `target` are stored in scattering media (or `64 *
/// target` were emitted). Deterministic for a seed, whatever the thread count.
pub fn trace(
    scene: &Scene,
    accel: &Accel,
    lights: &Lights,
    target: u64,
    max_bounces: u32,
    seed: u64,
) -> (Vec<VolumePhoton>, VolumeStats) {
    let start = std::time::Instant::now();
    let powers = lights.powers();
    let total: f32 = powers.iter().sum();
    let mut stats = VolumeStats::default();
    if target == 0 || total <= 0.0 || !scene.media.iter().any(|m| m.scatters()) {
        return (Vec::new(), stats);
    }
    let cdf: Vec<f32> = powers
        .iter()
        .scan(0.0, |a, p| {
            *a += p / total;
            Some(*a)
        })
        .collect();
    let mut out: Vec<VolumePhoton> = Vec::new();
    let mut emitted = 0u64;
    crate::progress::begin("volume photons", target);
    while (out.len() as u64) < target && emitted < target.saturating_mul(64) {
        crate::progress::set("volume photons", out.len() as u64, target);
        if crate::interrupt::requested().is_some() {
            break;
        }
        let lo = emitted;
        // Each chunk's stores in photon order, and its rays.
        let parts: Vec<(Vec<(u64, Store)>, u64)> = (0..BATCH / CHUNK)
            .into_par_iter()
            .map(|c| {
                let mut v = Vec::new();
                let mut rays = 0;
                for i in lo + c * CHUNK..lo + (c + 1) * CHUNK {
                    let light = (&cdf[..], &powers[..], total);
                    rays += trace_one(
                        scene,
                        accel,
                        lights,
                        light,
                        i,
                        seed,
                        max_bounces,
                        &mut |ph| v.push((i, ph)),
                    );
                }
                (v, rays)
            })
            .collect();
        // Photon i's stores go in whole while fewer than `target` are stored when it starts.
        let mut stop_at = None;
        let mut last = None;
        'parts: for (v, rays) in parts {
            stats.rays += rays;
            for (i, ph) in v {
                if out.len() as u64 >= target && last != Some(i) {
                    stop_at = Some(i);
                    break 'parts;
                }
                last = Some(i);
                if let Store::Volume(ph) = ph {
                    out.push(ph);
                }
            }
        }
        emitted = stop_at.unwrap_or(lo + BATCH);
        if out.is_empty() && emitted >= 4 * BATCH {
            break; // no photon reaches a scattering medium
        }
    }
    // Powers were traced per photon emitted from its light: divide by the photons emitted.
    let inv = 1.0 / emitted.max(1) as f32;
    for ph in &mut out {
        ph.power *= inv;
    }
    stats.emitted = emitted;
    stats.stored = out.len() as u64;
    stats.seconds = start.elapsed().as_secs_f64();
    (out, stats)
}

/// The caustic photons through the media: `emitted` photons split among the lights by power,
/// each aimed by the light's projection map at the specular objects `targets` (as the
/// surface caustic map's photons are, [`super::trace`]; `projection`: the maps' resolution,
/// `None` for no maps), followed through the media while every bounce is a delta one and
/// nothing scatters them, and stored where they land on a purely diffuse surface (at most
/// one each). Deterministic for a seed, whatever the thread count. Returns the photons and
/// the rays cast.
#[allow(clippy::too_many_arguments)]
pub fn trace_caustic(
    scene: &Scene,
    accel: &Accel,
    lights: &Lights,
    targets: &[(Vec3, f32)],
    emitted: u64,
    projection: Option<u32>,
    max_bounces: u32,
    seed: u64,
) -> (Vec<Photon>, u64) {
    let powers = lights.powers();
    if emitted == 0 || targets.is_empty() {
        return (Vec::new(), 0);
    }
    let counts = super::trace::allocate(emitted, &powers);
    let maps: Vec<super::projection::ProjectionMap> = (0..powers.len())
        .map(|i| match projection {
            Some(res) => super::projection::ProjectionMap::build(scene, lights, i, targets, res),
            None => super::projection::ProjectionMap::full(lights.emission_domain(i)),
        })
        .collect();
    let mut first = 0u64;
    let mut out = Vec::new();
    let mut rays = 0u64;
    for (light, (&count, map)) in counts.iter().zip(&maps).enumerate() {
        let chunks = count.div_ceil(CHUNK);
        let parts: Vec<(Vec<Photon>, u64)> = (0..chunks)
            .into_par_iter()
            .map(|c| {
                let mut v = Vec::new();
                let mut rays = 0;
                for j in c * CHUNK..((c + 1) * CHUNK).min(count) {
                    let i = first + j;
                    let mut numbers = Numbers::new(hash(&[seed, 0x0063_6175_7374_6963, i]));
                    let (u_pos, u_dir) = (numbers.next2(), numbers.next2());
                    let emitted = super::trace::emit_caustic(
                        scene, lights, light, map, targets, u_pos, u_dir,
                    );
                    let Some(e) = emitted else {
                        continue;
                    };
                    let power = e.flux * (map.fraction() / count as f32);
                    let walk = Walk {
                        scene,
                        accel,
                        max_bounces,
                        seed,
                        index: i,
                        caustic: true,
                    };
                    rays += walk.follow(light, &e, power, &mut numbers, &mut |st| {
                        if let Store::Caustic(ph) = st {
                            v.push(ph);
                        }
                    });
                }
                (v, rays)
            })
            .collect();
        for (v, r) in parts {
            out.extend(v);
            rays += r;
        }
        first += count;
    }
    (out, rays)
}

/// Traces photon `i` of the volume pass: calls `store` at each medium interaction;
/// returns the rays it cast.
#[allow(clippy::too_many_arguments)]
fn trace_one(
    scene: &Scene,
    accel: &Accel,
    lights: &Lights,
    (cdf, powers, total): (&[f32], &[f32], f32),
    i: u64,
    seed: u64,
    max_bounces: u32,
    store: &mut dyn FnMut(Store),
) -> u64 {
    let key = hash(&[seed, 0x766f_6c75_6d65, i]);
    let mut numbers = Numbers::new(key);
    let u_light = numbers.next();
    let light = cdf
        .iter()
        .position(|&c| u_light < c)
        .unwrap_or(cdf.len() - 1);
    let p_light = powers[light] / total;
    if p_light <= 0.0 {
        return 0;
    }
    let (u_pos, u_dir) = (numbers.next2(), numbers.next2());
    let Some(e) = lights.emit_aimed(&scene.meshes, light, u_pos, u_dir, None) else {
        return 0;
    };
    let power = e.flux / p_light;
    let walk = Walk {
        scene,
        accel,
        max_bounces,
        seed,
        index: i,
        caustic: false,
    };
    walk.follow(light, &e, power, &mut numbers, store)
}

/// A photon's stream of numbers beyond the sampler's: keyed by the seed and its index.
struct Numbers {
    key: u64,
    dim: u64,
}

impl Numbers {
    fn new(key: u64) -> Numbers {
        Numbers { key, dim: 0 }
    }

    fn next(&mut self) -> f32 {
        self.dim += 1;
        to_unit(mix64(
            self.key ^ self.dim.wrapping_mul(0x9E37_79B9_7F4A_7C15),
        ))
    }

    fn next2(&mut self) -> Vec2 {
        let a = self.next();
        Vec2::new(a, self.next())
    }
}

/// How photons are followed through the scene and its media.
struct Walk<'a> {
    scene: &'a Scene,
    accel: &'a Accel,
    max_bounces: u32,
    seed: u64,
    /// The photon's index (keys its samplers).
    index: u64,
    /// Whether it follows a caustic chain only and stores caustic photons (else it stores
    /// volume photons).
    caustic: bool,
}

impl Walk<'_> {
    /// Follows the photon `e` of light `light` carrying `power`: stores it at each medium
    /// interaction or (a caustic walk) at its caustic landing; returns the rays cast.
    fn follow(
        &self,
        light: usize,
        e: &crate::light::Emission,
        mut power: Vec3,
        numbers: &mut Numbers,
        store: &mut dyn FnMut(Store),
    ) -> u64 {
        let (scene, accel, i, seed) = (self.scene, self.accel, self.index, self.seed);
        let key = numbers.key;
        let mi = scene.light_media.get(light).copied().unwrap_or_default();
        let mut medium = if e.n == Vec3::ZERO {
            mi.outside
        } else {
            mi.leaving(e.dir, e.n)
        };
        let o = if e.n == Vec3::ZERO {
            e.p
        } else {
            spawn_origin(e.p, e.err, if e.n.dot(e.dir) >= 0.0 { e.n } else { -e.n })
        };
        let mut ray = Ray::new(o, e.dir);
        let mut rays = 0;
        // Scattering vertices so far: a photon stored at its k-th is read by a camera ray as
        // the light of a path of k vertices, so photons are stored up to the render's
        // maxdepth (`max_bounces + 1`, as the surface maps' bounces are counted).
        let mut vertices = 0u32;
        let max_vertices = self.max_bounces.saturating_add(1);
        // Every bounce so far a delta one, at least one, and no scattering in a medium.
        let (mut all_delta, mut any_delta) = (true, false);
        // Crossings of `interface` surfaces are no bounce; they are bounded all the same.
        for _ in 0..max_vertices.saturating_mul(4).max(8) {
            rays += 1;
            let hit = accel.intersect(RayKind::Photon, &ray);
            let len = ray.d.length();
            let dist = hit.as_ref().map_or(f32::INFINITY, |h| h.t * len);
            if let Some(m) = medium {
                let med: &Medium = &scene.media[m as usize];
                let d = ray.d / len;
                if med.scatters() {
                    let (u1, u2) = (numbers.next(), numbers.next());
                    match med.sample_interaction(ray.o, d, dist, u1, u2, power) {
                        MediumEvent::Scatter { t, weight } => {
                            if self.caustic {
                                return rays; // no longer a caustic photon
                            }
                            let p = ray.o + d * t;
                            let arriving = power;
                            power *= weight;
                            vertices += 1;
                            store(Store::Volume(VolumePhoton {
                                p,
                                d,
                                power,
                                vertices,
                            }));
                            all_delta = false;
                            if vertices >= max_vertices {
                                return rays;
                            }
                            // Roulette on the albedo weight (power relative to what arrived).
                            let q = (power / arriving.max(Vec3::splat(1e-30)))
                                .max_element()
                                .min(1.0);
                            if q.is_nan() || q <= 0.0 || numbers.next() >= q {
                                return rays;
                            }
                            power /= q;
                            let (wi, _) = sample_henyey_greenstein(-d, med.g, numbers.next2());
                            ray = Ray::new(p, wi);
                            continue;
                        }
                        MediumEvent::Pass { weight } => power *= weight,
                    }
                } else {
                    let mut rng = crate::medium::grid::Rng::new(hash(&[key, 0x7472, rays]));
                    power *= med.transmittance_along(ray.o, d, dist, &mut rng);
                }
            }
            let Some(hit) = hit else {
                return rays;
            };
            let mut si = SurfaceInteraction::new(scene, &hit, &ray);
            let material = si.material(scene);
            if material.interface {
                let d = ray.d;
                medium = si.medium_leaving(d, medium);
                ray = Ray::new(si.spawn(d), d);
                continue;
            }
            vertices += 1;
            let footprint = crate::camera::Footprint::of_file(scene);
            let bsdf = si.bsdf(scene, footprint, crate::spectrum::Lambda::Rgb);
            if self.caustic && all_delta && any_delta && is_caustic_receiver(bsdf.flags()) {
                let d = ray.d / ray.d.length();
                store(Store::Caustic(
                    Photon::new(si.p, power, d, Photon::CAUSTIC).with_bounce(vertices - 1),
                ));
            }
            if vertices >= max_vertices {
                return rays;
            }
            let mut sampler = crate::sampling::Sampler::new(
                crate::sampling::Pattern::Independent,
                seed,
                hash(&[0x766f_6c75_6d65 ^ !self.caustic as u64, i, vertices as u64]),
                0,
                1,
            );
            let Some(sc) = super::trace::scatter(&si, &bsdf, &mut sampler) else {
                return rays;
            };
            power *= sc.power_scale;
            all_delta &= sc.specular;
            any_delta |= sc.specular;
            if self.caustic && !sc.specular {
                return rays;
            }
            medium = si.medium_leaving(sc.ray.d, medium);
            ray = sc.ray;
        }
        rays
    }
}

/// Stored volume photons binned for beam estimates.
pub struct VolumeMap {
    photons: Vec<VolumePhoton>,
    radius: f32,
    lo: Vec3,
    cell: f32,
    dims: [i32; 3],
    /// Per cell, `(start, count)` into `refs`.
    cells: Vec<(u32, u32)>,
    refs: Vec<u32>,
}

impl VolumeMap {
    /// Bins `photons` as spheres of `radius`; `None` when there are none.
    pub fn build(photons: Vec<VolumePhoton>, radius: f32) -> Option<VolumeMap> {
        if photons.is_empty() || radius.is_nan() || radius <= 0.0 {
            return None;
        }
        let (mut lo, mut hi) = (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY));
        for ph in &photons {
            lo = lo.min(ph.p);
            hi = hi.max(ph.p);
        }
        lo -= Vec3::splat(radius);
        hi += Vec3::splat(radius);
        let extent = (hi - lo).max_element();
        let cell = (2.0 * radius).max(extent / MAX_CELLS_PER_AXIS as f32 * 1.0001);
        let dims = ((hi - lo) / cell).ceil().max(Vec3::ONE);
        let dims = [dims.x as i32, dims.y as i32, dims.z as i32];
        let index = |c: [i32; 3]| ((c[2] * dims[1] + c[1]) * dims[0] + c[0]) as usize;
        let clampc = |v: Vec3| -> [i32; 3] {
            let c = ((v - lo) / cell).floor();
            [
                (c.x as i32).clamp(0, dims[0] - 1),
                (c.y as i32).clamp(0, dims[1] - 1),
                (c.z as i32).clamp(0, dims[2] - 1),
            ]
        };
        // Photons in the order of the cell holding them: a cell's list then reads few,
        // mostly consecutive cache lines.
        let mut photons = photons;
        photons.sort_by_cached_key(|ph| index(clampc(ph.p)) as u32);
        let mut pairs: Vec<(u32, u32)> = Vec::new();
        for (i, ph) in photons.iter().enumerate() {
            let (a, b) = (
                clampc(ph.p - Vec3::splat(radius)),
                clampc(ph.p + Vec3::splat(radius)),
            );
            for z in a[2]..=b[2] {
                for y in a[1]..=b[1] {
                    for x in a[0]..=b[0] {
                        pairs.push((index([x, y, z]) as u32, i as u32));
                    }
                }
            }
        }
        pairs.sort_unstable();
        let n = (dims[0] * dims[1] * dims[2]) as usize;
        let mut cells = vec![(0u32, 0u32); n];
        let mut k = 0;
        while k < pairs.len() {
            let c = pairs[k].0;
            let start = k;
            while k < pairs.len() && pairs[k].0 == c {
                k += 1;
            }
            cells[c as usize] = (start as u32, (k - start) as u32);
        }
        let refs = pairs.into_iter().map(|(_, i)| i).collect();
        Some(VolumeMap {
            photons,
            radius,
            lo,
            cell,
            dims,
            cells,
            refs,
        })
    }

    pub fn len(&self) -> usize {
        self.photons.len()
    }

    pub fn is_empty(&self) -> bool {
        self.photons.is_empty()
    }

    pub fn radius(&self) -> f32 {
        self.radius
    }

    /// Bytes held.
    pub fn bytes(&self) -> u64 {
        (self.photons.len() * std::mem::size_of::<VolumePhoton>()
            + self.cells.len() * 8
            + self.refs.len() * 4) as u64
    }

    /// The point estimate of the light scattered at `p` towards `-d` (`d` unit, the
    /// direction of travel of the ray that reached `p`): `sum_i p(d, d_i) Phi_i / (4/3 pi
    /// R^3)` over the photons within `R = POINT_RADIUS_SCALE x` the beam radius (Jensen &
    /// Christensen's volume radiance estimate, `sigma_s` folded into the photons' powers)
    /// that took at most `max_vertices` scattering vertices from the light, and how many
    /// photons it used. Each photon counts once: in the cell holding it.
    pub fn point(&self, p: Vec3, d: Vec3, g: f32, max_vertices: u32) -> (Vec3, u32) {
        let r = self.radius * POINT_RADIUS_SCALE;
        let r2 = r * r;
        let cell_of = |v: Vec3| -> [i32; 3] {
            let c = ((v - self.lo) / self.cell).floor();
            [
                (c.x as i32).clamp(0, self.dims[0] - 1),
                (c.y as i32).clamp(0, self.dims[1] - 1),
                (c.z as i32).clamp(0, self.dims[2] - 1),
            ]
        };
        if !p.is_finite() {
            return (Vec3::ZERO, 0);
        }
        let (a, b) = (cell_of(p - Vec3::splat(r)), cell_of(p + Vec3::splat(r)));
        let mut sum = Vec3::ZERO;
        let mut used = 0u32;
        for z in a[2]..=b[2] {
            for y in a[1]..=b[1] {
                for x in a[0]..=b[0] {
                    let (start, count) =
                        self.cells[((z * self.dims[1] + y) * self.dims[0] + x) as usize];
                    for &i in &self.refs[start as usize..(start + count) as usize] {
                        let ph = &self.photons[i as usize];
                        if ph.vertices > max_vertices
                            || (ph.p - p).length_squared() > r2
                            || cell_of(ph.p) != [x, y, z]
                        {
                            continue;
                        }
                        sum += ph.power * henyey_greenstein(d.dot(ph.d), g);
                        used += 1;
                    }
                }
            }
        }
        let volume = 4.0 / 3.0 * std::f32::consts::PI * r2 * r;
        (sum / volume, used)
    }

    /// The beam radiance estimate along the segment `o + t d`, `t` in `[0, t_max]` (`d` unit,
    /// `t_max` may be infinite) through `medium`: the radiance its photons scatter towards
    /// `-d`, each weighed by the medium's transmittance from `o` to its closest approach;
    /// and how many photons it gathered.
    pub fn beam(&self, o: Vec3, d: Vec3, t_max: f32, medium: &Medium) -> (Vec3, u32) {
        let tr = medium.transmittance_table(o, d, t_max);
        self.beam_with(o, d, t_max, medium.g, &tr)
    }

    /// [`Self::beam`] with the segment's transmittance already tabled.
    pub fn beam_with(
        &self,
        o: Vec3,
        d: Vec3,
        t_max: f32,
        g: f32,
        tr: &crate::medium::TransmittanceTable,
    ) -> (Vec3, u32) {
        let hi = self.lo
            + Vec3::new(
                self.dims[0] as f32,
                self.dims[1] as f32,
                self.dims[2] as f32,
            ) * self.cell;
        // Clip the segment to the grid (slabs).
        let inv = d.recip();
        let (t0, t1) = ((self.lo - o) * inv, (hi - o) * inv);
        let tmin = t0.min(t1).max_element().max(0.0);
        let tmax = t0.max(t1).min_element().min(t_max);
        if tmin.is_nan() || tmax.is_nan() || tmin > tmax {
            return (Vec3::ZERO, 0);
        }
        let r2 = self.radius * self.radius;
        let norm = 1.0 / (std::f32::consts::PI * r2);
        let mut sum = Vec3::ZERO;
        let mut gathered = 0u32;
        // 3D DDA (Amanatides & Woo) from the entry point.
        let p = o + d * tmin;
        let rel = (p - self.lo) / self.cell;
        let mut c = [0i32; 3];
        let mut step = [0i32; 3];
        let mut next_t = [f32::INFINITY; 3];
        let mut delta = [f32::INFINITY; 3];
        for a in 0..3 {
            c[a] = (rel[a].floor() as i32).clamp(0, self.dims[a] - 1);
            if d[a] > 0.0 {
                step[a] = 1;
                let edge = self.lo[a] + (c[a] + 1) as f32 * self.cell;
                next_t[a] = (edge - o[a]) / d[a];
                delta[a] = self.cell / d[a];
            } else if d[a] < 0.0 {
                step[a] = -1;
                let edge = self.lo[a] + c[a] as f32 * self.cell;
                next_t[a] = (edge - o[a]) / d[a];
                delta[a] = -self.cell / d[a];
            }
        }
        let mut ta = tmin;
        loop {
            let axis = if next_t[0] < next_t[1] {
                if next_t[0] < next_t[2] {
                    0
                } else {
                    2
                }
            } else if next_t[1] < next_t[2] {
                1
            } else {
                2
            };
            let tb = next_t[axis].min(tmax);
            let last = next_t[axis] >= tmax;
            let (start, count) =
                self.cells[((c[2] * self.dims[1] + c[1]) * self.dims[0] + c[0]) as usize];
            for &i in &self.refs[start as usize..(start + count) as usize] {
                let ph = &self.photons[i as usize];
                let v = ph.p - o;
                let t = v.dot(d);
                // Counted in the cell holding the closest approach only (the last cell
                // takes the segment's end, the first its start).
                if t < ta || (t >= tb && !last) || t > tmax {
                    continue;
                }
                if (v - d * t).length_squared() > r2 {
                    continue;
                }
                sum += ph.power * tr.at(t) * henyey_greenstein(d.dot(ph.d), g);
                gathered += 1;
            }
            if last {
                break;
            }
            c[axis] += step[axis];
            if c[axis] < 0 || c[axis] >= self.dims[axis] {
                break;
            }
            ta = tb;
            next_t[axis] += delta[axis];
        }
        (sum * norm, gathered)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The beam estimate against a brute-force sum over all photons, on random segments
    /// through a cloud of photons (every photon counted once, none missed).
    #[test]
    fn beam_equals_brute_force_over_all_photons() {
        let photons: Vec<VolumePhoton> = (0..5000u64)
            .map(|i| {
                let h = |k: u64| to_unit(hash(&[i, k]));
                VolumePhoton {
                    p: Vec3::new(h(0), h(1), h(2)) * Vec3::new(2.0, 1.0, 0.5),
                    d: Vec3::new(h(3) - 0.5, h(4) - 0.5, h(5) - 0.5).normalize(),
                    power: Vec3::new(h(6), h(7), h(8)),
                    vertices: 1,
                }
            })
            .collect();
        let medium = Medium::homogeneous("m", Vec3::new(0.1, 0.2, 0.0), Vec3::splat(0.5), 0.4);
        for radius in [0.01f32, 0.05, 0.3] {
            let map = VolumeMap::build(photons.clone(), radius).unwrap();
            for j in 0..200u64 {
                let h = |k: u64| to_unit(hash(&[99, j, k]));
                let o = Vec3::new(h(0) * 3.0 - 0.5, h(1) * 2.0 - 0.5, h(2) * 1.5 - 0.5);
                let d = Vec3::new(h(3) - 0.5, h(4) - 0.5, h(5) - 0.5).normalize();
                let t_max = if j % 3 == 0 {
                    f32::INFINITY
                } else {
                    h(6) * 2.0
                };
                let got = map.beam(o, d, t_max, &medium).0;
                let mut want = Vec3::ZERO;
                for ph in &photons {
                    let v = ph.p - o;
                    let t = v.dot(d);
                    if t < 0.0 || t > t_max || (v - d * t).length_squared() > radius * radius {
                        continue;
                    }
                    want += ph.power
                        * medium.transmittance(t)
                        * henyey_greenstein(d.dot(ph.d), medium.g)
                        / (std::f32::consts::PI * radius * radius);
                }
                let err = (got - want).abs().max_element();
                assert!(
                    err <= 1e-4 * want.max_element().max(1.0),
                    "r {radius} ray {j}: {got} vs {want}"
                );
            }
        }
    }
}
