//! Pass 1: shooting photons from the lights and storing them in the global and caustic maps.
//!
//! - **Emission**: photons are divided among lights in proportion to power; each photon's
//!   origin and direction come from a stratified (or N-rooks) 2D pattern over that light's
//!   photons, and every random number is keyed by (seed, map, light, photon index), so the maps
//!   do not depend on thread count.
//! - **Scattering with RGB roulette**: at each hit the BSDF is sampled in importance mode and
//!   gives the per-channel weight `w = f |cos| / pdf` (the reflectance: `rho` for diffuse,
//!   Fresnel `F` for conductors, 1 for glass, whose reflect-or-refract choice is made by the
//!   exact Fresnel term). The photon survives with probability `q = min(1, mean(w))` and its
//!   power becomes `power * w / q`: Jensen's Russian roulette (fewer photons of unchanged
//!   power) and, per channel, RGB roulette (`rho_c / rho_avg`). The power already carries the
//!   cosine; it is never multiplied in again.
//! - **Sharp and wide lobes**: a bounce is *sharp* when its lobe is a delta one or the single
//!   microfacet lobe of a conductor or dielectric narrower than
//!   [`TraceSettings::receiver_alpha`] (`glossyalpha`, 0.1): near-smooth glass focuses light
//!   almost as sharply as smooth glass ([`is_sharp_bounce`]). Wider glossy lobes are
//!   *receivers* ([`is_receiver`]).
//! - **Storage**, at surfaces with a diffuse lobe: the global map keeps every such hit,
//!   flagged `DIRECT` when it came straight from the light, `CAUSTIC` after sharp bounces only,
//!   and `GLOSSY` after bounces off surfaces without a diffuse lobe, at least one of them not
//!   sharp, so that estimates can leave out what shadow rays and the caustic map already give;
//!   the caustic map keeps light -> sharp+ -> diffuse paths (L (S|G)+ D with near-smooth G),
//!   shot with projection maps aimed at the objects that may be sharp.
//! - **Rough glossy receivers**: caustic photons that reach a receiver through sharp bounces
//!   are kept too, flagged `ON_GLOSSY`, in a map of their own
//!   ([`PhotonMaps::caustic_glossy`]): a glass ball on a rough-metal floor gets its caustic
//!   from them even in a scene without a single diffuse surface.
//! - **Glossy caustics** (light that reaches a room only through a metal lamp shade) are
//!   caustics too, but spread wide: the renderer estimates them from the `GLOSSY` photons of
//!   the global map with the global map's radius (see `integrator::photonmap`), not from the
//!   caustic map's sharp, small discs. A bounce counts towards such a chain when the surface
//!   has no diffuse lobe ([`is_caustic_surface`]).
//! - Photons trapped by total internal reflection end at `max_bounces`.
//! - Caustic photons of infinite lights start only where they can reach a specular object
//!   ([`Lights::emit_caustic`]): a disc of the scene's radius would waste almost all of them.
use super::aim::Aim;
use super::projection::ProjectionMap;
use super::{Photon, PhotonMap};
use crate::accel::{Accel, RayKind};
use crate::bsdf::{Bsdf, TransportMode};
use crate::interaction::SurfaceInteraction;
use crate::light::{bounding_sphere, Lights};
use crate::math::{spawn_origin, Ray, Vec3};
use crate::sampling::{hash, Pattern, Sampler};
use crate::scene::Scene;
use rayon::prelude::*;
use std::time::Instant;

/// Photons traced per parallel work item.
const CHUNK: u64 = 4096;

/// Settings of pass 1.
#[derive(Clone, Debug)]
pub struct TraceSettings {
    /// Photons emitted for the global map (0: no global map).
    pub global_photons: u64,
    /// Photons emitted for the caustic map (0: no caustic map).
    pub caustic_photons: u64,
    pub max_bounces: u32,
    pub projection_maps: bool,
    pub projection_resolution: u32,
    pub seed: u64,
    pub pattern: Pattern,
    /// Rough glossy surfaces whose GGX alpha is at least this receive caustic photons
    /// ([`is_receiver`]; infinity: none do).
    pub receiver_alpha: f32,
    /// The render's image for texture footprints (`None`: the file's film and sampler).
    pub footprint: Option<crate::camera::Footprint>,
    /// Distant and infinite lights aim most global photons at what the camera sees
    /// ([`super::aim`]).
    pub aimed: bool,
    /// Keep the global photons stored straight from a light without a surface (point, spot,
    /// distant, infinite). The renderer reads none of them (its camera and gather points take
    /// that light by shadow rays), so it leaves them out; tests of the tracer weigh them.
    pub store_surfaceless_direct: bool,
}

/// The default of [`TraceSettings::receiver_alpha`]: lobes at least this wide get caustic
/// photons. Measured on `scenes/glass-on-metal.pbrt` with its floor's alpha varied
/// (`benches/results/glossy-receiver-alpha.txt`): at alpha 0.1 and 0.2 the receivers' estimate
/// beat tracing at every budget from 2 to 32 s (1.25-4.6x lower relMSE); at 0.05 tracing won
/// (1.7x at 32 s), the estimate being blotchy with few photons in so narrow a lobe.
pub const RECEIVER_ALPHA: f32 = 0.1;

/// Which map a photon is shot for.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum MapKind {
    Global,
    Caustic,
}

/// What pass 1 measured.
#[derive(Clone, Debug, Default)]
pub struct TraceStats {
    pub global_emitted: u64,
    pub global_stored: usize,
    pub caustic_emitted: u64,
    pub caustic_stored: usize,
    /// Of `caustic_stored`, the photons on rough glossy surfaces.
    pub caustic_glossy_stored: usize,
    /// Caustic photons whose first hit was sharp (specular or near-smooth) / caustic photons
    /// emitted.
    pub caustic_efficiency: f64,
    /// The same for photons emitted over the whole domain (as without projection maps).
    pub caustic_efficiency_unrestricted: f64,
    /// Photons emitted per light (in proportion to power) for each map.
    pub global_per_light: Vec<u64>,
    pub caustic_per_light: Vec<u64>,
    /// Per light: fraction of the emission domain marked by its projection map.
    pub marked_fraction: Vec<f32>,
    /// Where the distant and infinite lights aimed their global photons.
    pub aim: Option<Aim>,
    pub rays: u64,
    pub trace_seconds: f64,
    pub build_seconds: f64,
}

/// The maps of pass 1 (absent when the scene does not need them or no photon was stored).
pub struct PhotonMaps {
    pub global: Option<PhotonMap>,
    pub caustic: Option<PhotonMap>,
    /// The caustic photons that landed on rough glossy surfaces ([`is_receiver`]), estimated
    /// with the BSDF of the point that reads them.
    pub caustic_glossy: Option<PhotonMap>,
    pub stats: TraceStats,
}

/// A stored photon and the normal of the surface it landed on.
struct Landing {
    photon: Photon,
    normal: Vec3,
}

/// Whether photons pass a surface with these lobes as a caustic bounce: it has specular or
/// glossy lobes and no diffuse one (photons are stored at diffuse lobes, and the caustic path
/// ends there).
pub fn is_caustic_surface(flags: crate::bsdf::BxdfFlags) -> bool {
    (flags.has_specular() || flags.has_glossy()) && !flags.has_diffuse()
}

/// Whether a surface with this BSDF receives caustic photons as a rough glossy surface (it
/// has no diffuse lobe, and a single microfacet lobe at least `min_alpha` wide): light that
/// reaches it through specular bounces (L S+ G) is then a density estimate with the BSDF per
/// photon where the camera sees it, instead of rare paths that must find the light through
/// the glass. Narrow lobes are left to tracing: their estimate would need photons in a small
/// cone of directions. The renderer asks the same question of the same BSDF.
pub fn is_receiver(bsdf: &Bsdf, min_alpha: f32) -> bool {
    !bsdf.flags().has_diffuse() && bsdf.glossy_alpha().is_some_and(|a| a >= min_alpha)
}

/// Whether a photon that left a surface with BSDF `bsdf` by a sample of lobe alpha
/// `sample_alpha` ([`crate::bsdf::BsdfSample::lobe_alpha`]) took a *sharp* bounce: a delta
/// lobe, or a microfacet lobe narrower than `min_alpha` (near-smooth glass and metal focus
/// light almost as sharply as smooth ones). Caustic paths are chains of sharp bounces
/// (L (S|G)+ D with the G near-smooth); wider glossy lobes end them, at a receiver
/// ([`is_receiver`]). A coat over a diffuse body ([`Bsdf::has_coat`]) is never sharp, however
/// smooth: its reflection is a few percent of the light, mostly off flat or gently curved
/// surfaces (floors, plastic), so it spreads wide and is estimated with the global radius as a
/// glossy caustic ([`is_caustic_bounce`]) instead of from a handful of caustic photons.
pub fn is_sharp_bounce(bsdf: &Bsdf, sample_alpha: f32, min_alpha: f32) -> bool {
    !bsdf.has_coat() && (sample_alpha <= 0.0 || sample_alpha < min_alpha)
}

/// Whether a bounce of lobe alpha `sample_alpha` continues a glossy-caustic chain (light that
/// left specular or glossy lobes only, such as a lamp's metal shade or a coat's reflection):
/// any microfacet or delta lobe, not a diffuse one or a walk through a coat's layer.
pub fn is_caustic_bounce(sample_alpha: f32) -> bool {
    sample_alpha.is_finite()
}

/// Whether caustic photons go on through a surface with this BSDF: it has a delta lobe or a
/// near-smooth microfacet lobe ([`is_sharp_bounce`]).
pub fn is_sharp_surface(bsdf: &Bsdf, min_alpha: f32) -> bool {
    bsdf.flags().has_specular() || bsdf.glossy_alpha().is_some_and(|a| a < min_alpha)
}

/// The bounding spheres of all objects that may be sharp somewhere (a delta or near-smooth
/// lobe, see [`crate::scene::MaterialKind::has_sharp_lobe`]): the targets of the caustic
/// projection maps.
pub fn caustic_targets(scene: &Scene, min_alpha: f32) -> Vec<(Vec3, f32)> {
    scene
        .meshes
        .iter()
        .filter(|m| {
            scene.materials[m.material as usize]
                .kind
                .has_sharp_lobe(min_alpha)
        })
        .map(|m| m.sphere.unwrap_or_else(|| bounding_sphere(&m.positions)))
        .collect()
}

/// Where the distant and infinite lights aim their global photons (see [`super::aim`]):
/// `None` when `s` turns aiming off, no such light shines or the camera sees most of the
/// scene.
fn global_aim(scene: &Scene, accel: &Accel, lights: &Lights, s: &TraceSettings) -> Option<Aim> {
    if !s.aimed || s.global_photons == 0 || !lights.has_distant_or_infinite() {
        return None;
    }
    super::aim::region_of_interest(scene, accel, lights.scene_sphere())
}

/// Splits `total` photons among lights in proportion to `powers` (largest remainders get the
/// leftovers, deterministic).
pub fn allocate(total: u64, powers: &[f32]) -> Vec<u64> {
    let sum: f64 = powers.iter().map(|&p| p.max(0.0) as f64).sum();
    if sum <= 0.0 {
        return vec![0; powers.len()];
    }
    let exact: Vec<f64> = powers
        .iter()
        .map(|&p| total as f64 * p.max(0.0) as f64 / sum)
        .collect();
    let mut counts: Vec<u64> = exact.iter().map(|e| e.floor() as u64).collect();
    let mut order: Vec<usize> = (0..powers.len()).collect();
    order.sort_by(|&a, &b| (exact[b] - exact[b].floor()).total_cmp(&(exact[a] - exact[a].floor())));
    let left = total - counts.iter().sum::<u64>();
    for &i in order.iter().take(left as usize) {
        counts[i] += 1;
    }
    counts
}

/// Shoots both maps' photons and builds their kd-trees.
pub fn trace(scene: &Scene, accel: &Accel, lights: &Lights, s: &TraceSettings) -> PhotonMaps {
    let start = Instant::now();
    let mut stats = TraceStats::default();
    let powers = lights.powers();
    let targets = caustic_targets(scene, s.receiver_alpha);
    let aim = global_aim(scene, accel, lights, s);
    stats.aim = aim;
    let global = if s.global_photons > 0 {
        let counts = allocate(s.global_photons, &powers);
        stats.global_emitted = counts.iter().sum();
        stats.global_per_light = counts.clone();
        let full: Vec<ProjectionMap> = (0..powers.len())
            .map(|i| ProjectionMap::full(lights.emission_domain(i)))
            .collect();
        let (l, _, rays) = shoot(
            scene,
            accel,
            lights,
            s,
            MapKind::Global,
            &counts,
            &full,
            &targets,
            aim.as_ref(),
        );
        stats.rays += rays;
        l
    } else {
        Vec::new()
    };
    let caustic = if s.caustic_photons > 0 && !targets.is_empty() {
        let counts = allocate(s.caustic_photons, &powers);
        stats.caustic_emitted = counts.iter().sum();
        stats.caustic_per_light = counts.clone();
        let maps: Vec<ProjectionMap> = (0..powers.len())
            .map(|i| {
                if s.projection_maps {
                    ProjectionMap::build(scene, lights, i, &targets, s.projection_resolution)
                } else {
                    ProjectionMap::full(lights.emission_domain(i))
                }
            })
            .collect();
        stats.marked_fraction = maps.iter().map(|m| m.fraction()).collect();
        let (l, first_specular, rays) = shoot(
            scene,
            accel,
            lights,
            s,
            MapKind::Caustic,
            &counts,
            &maps,
            &targets,
            None,
        );
        stats.rays += rays;
        stats.caustic_efficiency = first_specular as f64 / stats.caustic_emitted.max(1) as f64;
        stats.caustic_efficiency_unrestricted =
            unrestricted_efficiency(scene, accel, lights, s, &powers);
        l
    } else {
        Vec::new()
    };
    stats.trace_seconds = start.elapsed().as_secs_f64();

    let t = Instant::now();
    stats.global_stored = global.len();
    stats.caustic_stored = caustic.len();
    // Photons on glossy surfaces first, in place (a second vector of landings would raise
    // the peak bytes per photon).
    let mut caustic = caustic;
    let mut split = 0;
    for j in 0..caustic.len() {
        if caustic[j].photon.has(Photon::ON_GLOSSY) {
            caustic.swap(split, j);
            split += 1;
        }
    }
    stats.caustic_glossy_stored = split;
    let global_map = build_map(&global, true);
    drop(global);
    let glossy_map = build_map(&caustic[..split], false);
    let caustic_map = build_map(&caustic[split..], true);
    stats.build_seconds = t.elapsed().as_secs_f64();
    PhotonMaps {
        global: global_map,
        caustic: caustic_map,
        caustic_glossy: glossy_map,
        stats,
    }
}

/// Photons stored per photon emitted for each map, as a pilot trace measured them
/// ([`pilot`]); the memory model multiplies the render's photon counts by them.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Landings {
    pub global: f64,
    pub caustic: f64,
    /// Light vertices kept per light subpath (the bidirectional integrators' pilot,
    /// `integrator::vcm::pilot`); 0 for the photon maps' pilot.
    pub subpath: f64,
}

/// Photons a pilot trace shoots for each map it measures.
pub const PILOT_PHOTONS: u64 = 8192;

/// Shoots up to [`PILOT_PHOTONS`] photons for each map `s` asks for (with the render's lights,
/// projection maps, bounces and roulette), keeps none, and returns the photons stored per
/// photon emitted. Deterministic (its own seed); runs on the current rayon pool.
pub fn pilot(scene: &Scene, accel: &Accel, lights: &Lights, s: &TraceSettings) -> Landings {
    let powers = lights.powers();
    let targets = caustic_targets(scene, s.receiver_alpha);
    let mut pilot = s.clone();
    pilot.seed = hash(&[s.seed, 0x0009_1107]);
    let aim = global_aim(scene, accel, lights, s);
    let rate = |kind: MapKind, wanted: u64, maps: &dyn Fn() -> Vec<ProjectionMap>| {
        if wanted == 0 || powers.is_empty() {
            return 0.0;
        }
        let counts = allocate(wanted.min(PILOT_PHOTONS), &powers);
        let aim = (kind == MapKind::Global).then_some(aim.as_ref()).flatten();
        let (l, _, _) = shoot(
            scene,
            accel,
            lights,
            &pilot,
            kind,
            &counts,
            &maps(),
            &targets,
            aim,
        );
        l.len() as f64 / counts.iter().sum::<u64>().max(1) as f64
    };
    let full = || {
        (0..powers.len())
            .map(|i| ProjectionMap::full(lights.emission_domain(i)))
            .collect()
    };
    let aimed = || {
        (0..powers.len())
            .map(|i| match s.projection_maps {
                true => ProjectionMap::build(scene, lights, i, &targets, s.projection_resolution),
                false => ProjectionMap::full(lights.emission_domain(i)),
            })
            .collect()
    };
    Landings {
        global: rate(MapKind::Global, s.global_photons, &full),
        caustic: match targets.is_empty() {
            true => 0.0,
            false => rate(MapKind::Caustic, s.caustic_photons, &aimed),
        },
        subpath: 0.0,
    }
}

/// Builds a map from landed photons, with their surface normals when `normals` (the global
/// and caustic maps', for their irradiance caches); `None` when empty.
fn build_map(landings: &[Landing], normals: bool) -> Option<PhotonMap> {
    if landings.is_empty() {
        return None;
    }
    let photons: Vec<Photon> = landings.iter().map(|l| l.photon).collect();
    if !normals {
        return PhotonMap::new(&photons).ok();
    }
    PhotonMap::with_normals(&photons, |i| landings[i].normal).ok()
}

/// Traces `counts[i]` photons from each light `i` in parallel chunks, concatenated in a fixed
/// order. Returns the landings, how many photons hit a specular surface first, and rays cast.
#[allow(clippy::too_many_arguments)]
fn shoot(
    scene: &Scene,
    accel: &Accel,
    lights: &Lights,
    s: &TraceSettings,
    kind: MapKind,
    counts: &[u64],
    maps: &[ProjectionMap],
    targets: &[(Vec3, f32)],
    aim: Option<&Aim>,
) -> (Vec<Landing>, u64, u64) {
    let work: Vec<(usize, u64, u64)> = counts
        .iter()
        .enumerate()
        .flat_map(|(i, &n)| {
            (0..n.div_ceil(CHUNK)).map(move |c| (i, c * CHUNK, ((c + 1) * CHUNK).min(n)))
        })
        .collect();
    let name = match kind {
        MapKind::Global => "global photons",
        MapKind::Caustic => "caustic photons",
    };
    crate::progress::begin(name, counts.iter().sum());
    let parts: Vec<(Vec<Landing>, u64, u64)> = work
        .par_iter()
        .map(|&(light, lo, hi)| {
            if crate::interrupt::requested().is_some() {
                return (Vec::new(), 0, 0); // stopping: the caller's render is discarded
            }
            crate::progress::add(hi - lo);
            let mut out = Vec::new();
            let (mut first_specular, mut rays) = (0u64, 0u64);
            let map = &maps[light];
            let n = counts[light];
            let strata = crate::sampling::grid(n.max(1) as u32);
            for j in lo..hi {
                let domain = hash(&[kind as u64, light as u64]);
                let mut sampler =
                    Sampler::with_strata(s.pattern, s.seed, domain, j as u32, n as u32, strata);
                let t = trace_one(
                    scene,
                    accel,
                    lights,
                    s,
                    kind,
                    light,
                    n,
                    map,
                    targets,
                    aim,
                    &mut sampler,
                    &mut out,
                );
                first_specular += t.0 as u64;
                rays += t.1;
            }
            (out, first_specular, rays)
        })
        .collect();
    let mut all = Vec::with_capacity(parts.iter().map(|p| p.0.len()).sum());
    let (mut fs, mut rays) = (0, 0);
    for (p, f, r) in parts {
        all.extend(p);
        fs += f;
        rays += r;
    }
    (all, fs, rays)
}

/// Traces one photon; returns (first hit was specular, rays cast).
#[allow(clippy::too_many_arguments)]
fn trace_one(
    scene: &Scene,
    accel: &Accel,
    lights: &Lights,
    s: &TraceSettings,
    kind: MapKind,
    light: usize,
    count: u64,
    map: &ProjectionMap,
    targets: &[(Vec3, f32)],
    aim: Option<&Aim>,
    sampler: &mut Sampler,
    out: &mut Vec<Landing>,
) -> (bool, u64) {
    // Emission: the projection map restricts one of the two 2D samples.
    let (u_pos, u_dir) = (sampler.next_2d(), sampler.next_2d());
    let e = match kind {
        MapKind::Global => {
            let Some((u_pos, u_dir)) = map.restrict(u_pos, u_dir) else {
                return (false, 0);
            };
            lights.emit_aimed(&scene.meshes, light, u_pos, u_dir, aim)
        }
        MapKind::Caustic => emit_caustic(scene, lights, light, map, targets, u_pos, u_dir),
    };
    let Some(e) = e else {
        return (false, 0);
    };
    let mut power = e.flux * (map.fraction() / count as f32);
    let o = if e.n == Vec3::ZERO {
        e.p
    } else {
        spawn_origin(e.p, e.err, e.n)
    };
    let mut ray = Ray::new(o, e.dir);
    let mut rays = 0;
    // Every bounce so far was off a surface without a diffuse lobe; every bounce was sharp
    // (a delta or near-smooth lobe, `is_sharp_bounce`).
    let mut caustic_chain = true;
    let mut sharp_chain = true;
    let mut first_specular = false;
    let footprint = s
        .footprint
        .unwrap_or_else(|| crate::camera::Footprint::of_file(scene));
    for bounce in 0..s.max_bounces {
        rays += 1;
        let Some(hit) = accel.intersect(RayKind::Photon, &ray) else {
            break;
        };
        power *= crate::accel::transmittance(scene, Some(&hit), &ray);
        let mut si = SurfaceInteraction::new(scene, &hit, &ray);
        let bsdf = si.bsdf(scene, footprint, crate::spectrum::Lambda::Rgb);
        let flags = bsdf.flags();
        let caustic_surface = is_caustic_surface(flags);
        if bounce == 0 {
            first_specular = is_sharp_surface(&bsdf, s.receiver_alpha);
        }
        let dir = -si.wo_world;
        let facing = if si.ng.dot(dir) < 0.0 { si.ng } else { -si.ng };
        if kind == MapKind::Caustic
            && sharp_chain
            && bounce > 0
            && power.max_element() > 0.0
            && is_receiver(&bsdf, s.receiver_alpha)
        {
            out.push(Landing {
                photon: Photon::new(si.p, power, dir, Photon::CAUSTIC | Photon::ON_GLOSSY)
                    .with_bounce(bounce),
                normal: facing,
            });
        }
        if flags.has_diffuse() {
            // Nothing reads the photons stored straight from a light without a surface (point,
            // spot, distant, infinite): camera and gather points take that light by shadow rays
            // (`integrator::photonmap::direct_at_gather`). Left out, they no longer crowd the
            // searches that skip them (a sunlit floor holds most photons of a room).
            let store = match kind {
                MapKind::Global => {
                    bounce > 0
                        || s.store_surfaceless_direct
                        || !scene.lights[light].is_surfaceless()
                }
                MapKind::Caustic => sharp_chain && bounce > 0,
            };
            if store && power.max_element() > 0.0 {
                let flags = match (bounce, sharp_chain, caustic_chain) {
                    (0, _, _) => Photon::DIRECT,
                    (_, true, _) => Photon::CAUSTIC,
                    (_, false, true) => Photon::GLOSSY,
                    _ => 0,
                };
                out.push(Landing {
                    photon: Photon::new(si.p, power, dir, flags).with_bounce(bounce),
                    normal: facing,
                });
            }
        }
        let sharp_surface = is_sharp_surface(&bsdf, s.receiver_alpha);
        if kind == MapKind::Caustic && !sharp_surface {
            break; // a caustic path ends at its first surface that is not sharp
        }
        let Some(sc) = scatter(&si, &bsdf, sampler) else {
            break;
        };
        let sharp = is_sharp_bounce(&bsdf, sc.lobe_alpha, s.receiver_alpha);
        if kind == MapKind::Caustic && !sharp {
            break; // the sampled lobe was a wide glossy or a diffuse one
        }
        power *= sc.power_scale;
        caustic_chain &= caustic_surface || (bsdf.has_coat() && is_caustic_bounce(sc.lobe_alpha));
        sharp_chain &= sharp;
        ray = sc.ray;
    }
    (first_specular, rays)
}

/// A photon's next leg after a surface hit.
pub struct Scattered {
    pub ray: Ray,
    /// Per-channel factor of the photon's power: `w / q` (RGB roulette).
    pub power_scale: Vec3,
    /// Whether the sampled lobe was a delta (specular) one.
    pub specular: bool,
    /// The sampled lobe's GGX alpha ([`crate::bsdf::BsdfSample::lobe_alpha`]).
    pub lobe_alpha: f32,
}

/// Scatters a photon arriving at `si`: samples the BSDF in importance mode, then Russian +
/// RGB roulette on its weight `w = f |cos| / pdf` (survive with `q = min(1, mean(w))`). Uses
/// 4 sample dimensions. `None`: absorbed.
pub fn scatter(si: &SurfaceInteraction, bsdf: &Bsdf, sampler: &mut Sampler) -> Option<Scattered> {
    let wo = si.wo;
    let uc = sampler.next_1d();
    let u2 = sampler.next_2d();
    let u_rr = sampler.next_1d();
    let bs = bsdf.sample(wo, uc, u2, TransportMode::Importance)?;
    let w = bs.f.rgb() * (bs.wi.z.abs() / bs.pdf);
    let q = ((w.x + w.y + w.z) / 3.0).min(1.0);
    if q.is_nan() || q <= 0.0 || u_rr >= q {
        return None;
    }
    Some(Scattered {
        ray: si.spawn_ray(si.frame.to_world(bs.wi)),
        power_scale: w / q,
        specular: bs.specular,
        lobe_alpha: bs.lobe_alpha,
    })
}

/// A caustic photon of light `light`: the emission samples restricted by its projection map
/// `map`, emitted towards `targets` (the specular objects), and `None` when the map marks
/// nothing or the photon cannot reach a target (rejected). Its power is `flux *
/// map.fraction() / photons emitted`.
pub(crate) fn emit_caustic(
    scene: &Scene,
    lights: &Lights,
    light: usize,
    map: &ProjectionMap,
    targets: &[(Vec3, f32)],
    u_pos: crate::math::Vec2,
    u_dir: crate::math::Vec2,
) -> Option<crate::light::Emission> {
    let (u_pos, u_dir) = map.restrict(u_pos, u_dir)?;
    let e = lights.emit_caustic(&scene.meshes, light, u_pos, u_dir, targets)?;
    targets
        .iter()
        .any(|&(c, r)| ray_meets_sphere(e.p, e.dir, c, r))
        .then_some(e)
}

/// Whether the ray from `o` along unit `d` meets the sphere `(c, r)`.
fn ray_meets_sphere(o: Vec3, d: Vec3, c: Vec3, r: f32) -> bool {
    let v = c - o;
    if v.length_squared() <= r * r {
        return true;
    }
    let along = v.dot(d);
    along > 0.0 && (v - d * along).length_squared() <= r * r
}

/// Fraction of photons emitted over the whole domain whose first hit is specular (what the
/// caustic pass would achieve without projection maps), from up to 20k photons.
fn unrestricted_efficiency(
    scene: &Scene,
    accel: &Accel,
    lights: &Lights,
    s: &TraceSettings,
    powers: &[f32],
) -> f64 {
    let counts = allocate(s.caustic_photons.min(20_000), powers);
    let (mut hits, mut total) = (0u64, 0u64);
    for (i, &n) in counts.iter().enumerate() {
        for j in 0..n {
            total += 1;
            let mut sampler =
                Sampler::new(s.pattern, s.seed ^ 0x5eed, i as u64, j as u32, n as u32);
            let (u_pos, u_dir) = (sampler.next_2d(), sampler.next_2d());
            let Some(e) = lights.emit(&scene.meshes, i, u_pos, u_dir) else {
                continue;
            };
            let o = if e.n == Vec3::ZERO {
                e.p
            } else {
                spawn_origin(e.p, e.err, e.n)
            };
            if let Some(h) = accel.intersect(RayKind::Photon, &Ray::new(o, e.dir)) {
                let material = &scene.materials[scene.meshes[h.mesh as usize].material as usize];
                hits += material.kind.has_sharp_lobe(s.receiver_alpha) as u64;
            }
        }
    }
    hits as f64 / total.max(1) as f64
}
