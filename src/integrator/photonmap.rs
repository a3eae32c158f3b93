//! Jensen's two-pass photon mapping, pass 2: reflected radiance at a visible diffuse point is
//! split into
//! - **direct** light by shadow rays (as the direct integrator),
//! - **specular/glossy** light by tracing rays through specular and glossy bounces,
//! - **caustics** by a radiance estimate in the caustic map at the point; on a rough glossy
//!   surface without a diffuse lobe (GGX alpha >= `glossyalpha`) from the caustic photons
//!   stored there, each weighted by the BSDF ([`at_glossy`]), while the ray traced on from
//!   it no longer counts emitters found through delta bounces,
//! - **indirect diffuse** by final gathering: stratified cosine-weighted gather rays whose
//!   first diffuse hits read the global map (through a precomputed irradiance cache at a
//!   subset of the photons, Christensen 1999, unless disabled); or, with `finalgather false`,
//!   a direct look at the global map's indirect photons (for inspection);
//!   where the global map is too sparse to read (`sparsemap`: a sky-lit scene whose photons
//!   leave it after one bounce), gather rays go on as paths instead ([`traced`]).
//!
//! ```text
//! Integrator "photonmap"
//!     "integer globalphotons" [ 200000 ]   "integer causticphotons" [ 200000 ]
//!     "integer globallookup" [ 100 ]       "integer causticlookup" [ 60 ]
//!     "float globalradius" [ 0.1 ]         "float causticradius" [ 0.02 ]  # x scene radius
//!     "string kernel" [ "epanechnikov" ]   # box | cone | biweight | epanechnikov
//!     "integer gathersamples" [ 2 ]       "bool finalgather" [ true ]
//!     "bool irradiancecache" [ true ]      "bool projectionmaps" [ true ]
//!     "float sparsemap" [ 0.02 ]           # below: gather rays go on as paths
//!     "integer maxdepth" [ 5 ]             "integer maxphotonbounces" [ 4 ]  # maxdepth - 1
//!     "float glossyalpha" [ 0.1 ]          # rough glossy surfaces receive caustic photons
//! ```
//! Radii are fractions of the scene's bounding-sphere radius. Gathering is stratified over the
//! pixel's samples too, so a few gather rays per pixel sample suffice (hence the default of 2;
//! measured: BENCHMARKS.md, "Design measurements"). Only what the scene needs is built: no caustic map without specular surfaces (or without a diffuse or rough glossy
//! surface to receive its photons), no global map without diffuse ones.
use super::{charge, RenderContext};
use crate::accel::{Accel, Hit, RayKind};
use crate::bsdf::{Bsdf, TransportMode};
use crate::interaction::SurfaceInteraction;
use crate::light::{LightSample, Lights, Pick, Receiver};
use crate::math::{Frame, Ray, Vec2, Vec3};
use crate::photon::cache::{Cached, IrradianceCache, LEVELS};
use crate::photon::estimate::{irradiance_with, radiance_sampled, radiance_with, EstimateParams};
use crate::photon::guide::{cosine_hemisphere_to_square, GatherGuide, GuideSlot};
use crate::photon::trace::{self, PhotonMaps, TraceSettings};
use crate::photon::{Kernel, KnnResult, Photon, PhotonMap};
use crate::sampling::{strata, Pattern, Sampler};
use crate::scene::{ParamSet, Scene, SceneError};
use crate::spectrum::Lambda;
use crate::spectrum::Spectrum;
use std::sync::atomic::AtomicU64;
use std::time::Instant;

/// Pass-2 settings of the photon mapper (pass-1 settings are in `trace`).
#[derive(Clone, Debug)]
pub struct PhotonSettings {
    pub trace: TraceSettings,
    pub global_lookup: usize,
    /// Fraction of the scene radius.
    pub global_radius: f32,
    pub caustic_lookup: usize,
    pub caustic_radius: f32,
    pub kernel: Kernel,
    pub gather_samples: u32,
    pub final_gather: bool,
    /// Gather directions drawn by the nearest photons' incoming light (see
    /// [`crate::photon::guide`]) instead of by the cosine alone. Off by default: on
    /// cornell-spheres at 16 spp it cut relMSE 9% (0.0086 -> 0.0078) for 35% more time; on
    /// veach-bidir at equal time (15 s) it cut it 20% (0.240 -> 0.192, one seed each).
    pub guided_gather: bool,
    /// A gather hit whose estimate's photons fill less than this share of its disc
    /// ([`crate::photon::estimate::fill`]) is passed on: shadow ray and one more cosine
    /// bounce, at most [`THIN_CONTINUATIONS`] times per gather ray. A hard photon estimate
    /// divides a thin tube's strip of photons by its whole disc: forty 1 cm tubes above a
    /// floor came out 0.949 of the path tracer without it, 0.994 with 0.7 (0.979 with 0.5;
    /// tests/it/thin_tubes.rs); Bitterli's classroom 0.964 -> 0.979 of pbrt-v4's mean.
    /// The caustic and glossy estimates at camera points weigh such photons over their own
    /// area instead ([`crate::photon::estimate::Weigh`]).
    pub thin_fill: f32,
    pub irradiance_cache: bool,
    /// A global map that stored fewer than this share of the photons it emitted is not read
    /// ([`PhotonPass::traced_gather`]): the scene is lit mostly straight from lights without a
    /// surface (a sky, the sun) whose photons leave it after their first bounce, so the map is
    /// too sparse for its estimates (teapot: 573 of 200 000 photons stored, the floor beside
    /// the teapot 7% dark). Gather rays then go on as paths. 0: always read the map.
    pub sparse_map: f32,
    /// Progressive photon mapping (Knaus and Zwicker 2011): every pass traces fresh maps and
    /// its estimates use only the photons within a shrinking fraction of the k-nearest radius
    /// (see [`super::passes`]).
    pub progressive: bool,
    /// The radius schedule's alpha in (0, 1): `r_{i+1}^2 = r_i^2 (i + alpha) / (i + 1)`.
    pub alpha: f32,
    /// Factor on the squared k-nearest radii of the current pass's estimates (1 for pass 0
    /// and for Jensen's fixed maps; set by the pass driver).
    pub radius_scale2: f64,
    /// Whether the scene or the command line set `maxphotonbounces`; otherwise it follows the
    /// render's `maxdepth` ([`PhotonSettings::follow_depth`]).
    pub bounces_given: bool,
    /// Photons stored in scattering media ([`crate::photon::volume`]).
    pub volume_photons: u64,
    /// Their spheres' radius in beam estimates, a fraction of the scene radius.
    pub volume_radius: f32,
}

impl Default for PhotonSettings {
    fn default() -> Self {
        PhotonSettings {
            trace: TraceSettings {
                global_photons: 200_000,
                caustic_photons: 200_000,
                max_bounces: 32,
                projection_maps: true,
                projection_resolution: crate::photon::projection::DEFAULT_RESOLUTION,
                seed: 0,
                pattern: Pattern::Stratified,
                receiver_alpha: trace::RECEIVER_ALPHA,
                footprint: None,
                aimed: true,
                store_surfaceless_direct: false,
            },
            global_lookup: 100,
            global_radius: 0.1,
            caustic_lookup: 60,
            caustic_radius: 0.02,
            kernel: Kernel::Epanechnikov,
            gather_samples: 2,
            final_gather: true,
            guided_gather: false,
            thin_fill: 0.7,
            irradiance_cache: true,
            sparse_map: 0.02,
            progressive: false,
            alpha: 2.0 / 3.0,
            radius_scale2: 1.0,
            bounces_given: false,
            volume_photons: 100_000,
            volume_radius: 0.02,
        }
    }
}

impl PhotonSettings {
    /// Photon paths as long as the render's `maxdepth` allows, unless `maxphotonbounces` was
    /// given: a photon stored at its `b`-th hit (b = 0 straight from the light) and read at a
    /// final-gather hit makes a light path of `b + 2` scattering vertices (its `b + 1` and the
    /// visible point), so photons are traced for `maxdepth - 1` hits (at least 1). Without
    /// this the maps carried light that pbrt-v4, Mitsuba and our path tracer leave out: in a
    /// closed room of albedo 0.7 at maxdepth 8, 3-5% of the image (measured on
    /// scenes/lamp-enclosed.pbrt against our path tracer at maxdepth 8 and 100). Reads later
    /// in a camera path (behind specular bounces, at gather hits) take fewer: [`read_limit`].
    pub fn follow_depth(&mut self, max_depth: u32) {
        if !self.bounces_given {
            self.trace.max_bounces = max_depth.saturating_sub(1).max(1);
        }
    }

    /// Photon counts for a time budget of `budget_s` seconds: `base` photons per map at 4 s,
    /// in proportion to the budget between 1 s and 32 s (pass 1 should stay a modest share of
    /// the time), constant outside.
    pub fn scale_for_budget(&mut self, budget_s: f64, base: u64) {
        let n = (base as f64 * (budget_s / 4.0).clamp(0.25, 8.0)) as u64;
        self.trace.global_photons = n;
        self.trace.caustic_photons = n;
    }

    /// Reads the `photonmap` parameters (each marked used; the table of
    /// [`super::settings`] and the pass schedule's `progressive` and `alpha`); others stay
    /// for the caller.
    pub fn from_params(params: &mut ParamSet) -> Result<PhotonSettings, SceneError> {
        let mut s = PhotonSettings::default();
        super::settings::read_params(&mut s, params)?;
        s.progressive = params.get_bool("progressive", s.progressive)?;
        s.alpha = params.get_float("alpha", s.alpha)?;
        if !super::settings::ALPHA.contains(s.alpha as f64) {
            return Err(SceneError {
                loc: params.loc("alpha").cloned(),
                msg: format!(
                    "\"alpha\" must be in {}, got {}",
                    super::settings::ALPHA.describe(),
                    s.alpha
                ),
            });
        }
        Ok(s)
    }
}

/// Parses a kernel name (`cone` uses Jensen's k = 1.1).
pub fn parse_kernel(name: &str) -> Option<Kernel> {
    Some(match name {
        "box" => Kernel::Box,
        "cone" => Kernel::Cone { k: 1.1 },
        "biweight" | "simpson" => Kernel::Biweight,
        "epanechnikov" => Kernel::Epanechnikov,
        _ => return None,
    })
}

/// Pass 1's products, as pass 2 reads them.
pub struct PhotonPass {
    pub maps: PhotonMaps,
    /// The volume photon map, in scenes whose media scatter (then the surface maps are
    /// empty: the path tracer renders the surfaces, see [`crate::integrator::path`]).
    pub volume: Option<crate::photon::volume::VolumeMap>,
    pub volume_stats: crate::photon::volume::VolumeStats,
    /// Precomputed irradiance at a subset of the global photons.
    pub cache: Option<IrradianceCache>,
    /// Gather rays go on as paths instead of reading the global map, which stored fewer than
    /// [`PhotonSettings::sparse_map`] of its photons ([`traced`]); then no cache, guide or
    /// glossy map is built from it.
    pub traced_gather: bool,
    /// With traced gathers: precomputed caustic-map irradiance for their diffuse points (as
    /// the irradiance cache serves dense maps' gather hits).
    pub caustic_cache: Option<IrradianceCache>,
    /// The global photons that took a diffuse bounce, for guiding the final gather.
    pub guide_map: Option<PhotonMap>,
    /// The global photons flagged `GLOSSY` (glossy caustics), looked up at visible diffuse
    /// points with the global map's parameters when final gathering (without it, the direct
    /// look at the global map includes them).
    pub glossy_map: Option<PhotonMap>,
    pub settings: PhotonSettings,
    global_params: EstimateParams,
    /// The glossy map's lookups ([`typical_radius_params`]).
    glossy_params: EstimateParams,
    caustic_params: EstimateParams,
    /// The lookups of caustic photons on glossy receivers.
    receiver_params: EstimateParams,
    pub cache_seconds: f64,
    /// Components skipped because the scene cannot produce them, for the statistics.
    pub skipped: Vec<&'static str>,
    /// The lights pass 1 emitted from, which pass 2 samples too.
    pub lights: Lights,
}

/// Which maps the scene needs, (global, caustic), and why a map it does not need is skipped:
/// the global map needs a lit diffuse surface, the caustic map a sharp surface (specular, or
/// glossy narrower than `receiver_alpha`) and a
/// surface to store caustic photons on (diffuse, or glossy without a diffuse lobe when
/// `receiver_alpha` is finite).
pub fn needed_maps(scene: &Scene, receiver_alpha: f32) -> (bool, bool, Vec<&'static str>) {
    let kinds = || {
        scene
            .meshes
            .iter()
            .map(|m| &scene.materials[m.material as usize].kind)
    };
    let any_diffuse = kinds().any(|k| k.flags().has_diffuse() && !k.is_black());
    let any_glossy = receiver_alpha.is_finite()
        && kinds().any(|k| k.flags().has_glossy() && !k.flags().has_diffuse());
    let any_specular = kinds().any(|k| k.has_sharp_lobe(receiver_alpha));
    let mut skipped = Vec::new();
    if scene.lights.is_empty() {
        skipped.push("photon maps (no light)");
        return (false, false, skipped);
    }
    if !any_diffuse {
        skipped.push("global map (no lit diffuse surface)");
    }
    if !any_specular {
        skipped.push("caustic map and projection maps (no specular or near-smooth surface)");
    } else if !(any_diffuse || any_glossy) {
        skipped.push("caustic map and projection maps (no diffuse or rough glossy receiver)");
    }
    let caustic = any_specular && (any_diffuse || any_glossy);
    (any_diffuse, caustic, skipped)
}

/// Runs pass 1 (and the irradiance precomputation) for `scene`.
pub fn prepare(
    scene: &Scene,
    accel: &Accel,
    owned_lights: Lights,
    settings: &PhotonSettings,
) -> PhotonPass {
    let lights = &owned_lights;
    let mut s = settings.clone();
    let (need_global, need_caustic, skipped) = needed_maps(scene, s.trace.receiver_alpha);
    // Media that need tracking: the path tracer renders the surfaces, the volume map the
    // media; no surface map is traced.
    let volume_scene = scene.media_need_tracking.is_some();
    if !need_global || volume_scene {
        s.trace.global_photons = 0;
    }
    if !need_caustic || volume_scene {
        s.trace.caustic_photons = 0;
    }
    let mut maps = trace::trace(scene, accel, lights, &s.trace);
    let (volume, volume_stats) = if volume_scene {
        let (photons, st) = crate::photon::volume::trace(
            scene,
            accel,
            lights,
            s.volume_photons,
            s.trace.max_bounces,
            s.trace.seed,
        );
        // Progressive passes shrink it with the surface maps' radii (`radius_scale2`).
        let r = s.volume_radius * lights.scene_sphere().1 * (s.radius_scale2 as f32).sqrt();
        let t = Instant::now();
        let map = crate::photon::volume::VolumeMap::build(photons, r);
        let build_seconds = t.elapsed().as_secs_f64();
        // The caustic photons through the media, read by the path tracer at diffuse points.
        let t = Instant::now();
        let emitted = if need_caustic {
            settings.trace.caustic_photons
        } else {
            0
        };
        let targets = trace::caustic_targets(scene, s.trace.receiver_alpha);
        let projection = s
            .trace
            .projection_maps
            .then_some(s.trace.projection_resolution);
        let (caustic, rays) = crate::photon::volume::trace_caustic(
            scene,
            accel,
            lights,
            &targets,
            emitted,
            projection,
            s.trace.max_bounces,
            s.trace.seed,
        );
        maps.caustic = PhotonMap::new(&caustic).ok();
        let st = crate::photon::volume::VolumeStats {
            build_seconds,
            caustic_emitted: emitted,
            caustic: caustic.len() as u64,
            caustic_seconds: t.elapsed().as_secs_f64(),
            rays: st.rays + rays,
            ..st
        };
        (map, st)
    } else {
        (None, Default::default())
    };
    let (_, radius) = lights.scene_sphere();
    let r2 = |fraction: f32| ((fraction * radius) as f64).powi(2);
    // Progressive: no minimum photon count (a zero where photons are sparse would be a bias
    // that never averages out; the noise does).
    let min_photons = if s.progressive {
        1
    } else {
        EstimateParams::new(1, 0.0).min_photons
    };
    let params = |k: usize, r2: f64| EstimateParams {
        kernel: s.kernel,
        shrink2: s.radius_scale2 as f32,
        min_photons,
        ..EstimateParams::new(k.max(1), r2 as f32)
    };
    let uncut_global_params = params(s.global_lookup, r2(s.global_radius));
    let global_params = (maps.global.as_ref()).map_or(uncut_global_params, |m| {
        typical_radius_params(m, &uncut_global_params)
    });
    let caustic_params = params(s.caustic_lookup, r2(s.caustic_radius));
    let st = &maps.stats;
    let traced_gather = s.final_gather
        && maps.global.is_some()
        && (st.global_stored as f64) < s.sparse_map as f64 * st.global_emitted as f64;
    let mut skipped = skipped;
    if traced_gather {
        skipped.push("global map reads (too sparse: gather rays go on as paths)");
    }
    let t = Instant::now();
    // Progressive passes estimate at the gather hits themselves: the cache's nearest-point
    // lookup blurs over the cache's spacing, a bias that does not shrink with the radii (on
    // cornell-glass at 64x64, 32 -> 128 passes: 0.0013 -> 0.00083 with it, 0.00115 -> 0.00047
    // without, at the same speed).
    // The cache estimates at photons' own positions and counts each photon itself at the
    // kernel's peak: harmless in a full search (+2% at 100 photons), several percent in a
    // sparse one. So its searches keep the full radius (they run once per cache point) while
    // the lookups at gather hits are cut: veach-ajar 1.025 / 1.011 of our path tracer's mean
    // with cut cache searches, 0.985 / 0.978 without (relMSE 0.30-0.32 -> 0.25).
    let gather_params = EstimateParams {
        min_photons: 1,
        ..uncut_global_params
    };
    let cache = if s.irradiance_cache && s.final_gather && !s.progressive && !traced_gather {
        let global = maps.global.as_ref();
        let limits = std::array::from_fn(|c| bounce_limit(&s.trace, c as u32).unwrap_or(0));
        global.and_then(|g| IrradianceCache::build(g, &gather_params, limits).ok())
    } else {
        None
    };
    let caustic_cache = if traced_gather && s.irradiance_cache && !s.progressive {
        let params = EstimateParams {
            min_photons: 1,
            ..caustic_params
        };
        let limits = [u8::MAX; LEVELS];
        (maps.caustic.as_ref()).and_then(|m| IrradianceCache::build(m, &params, limits).ok())
    } else {
        None
    };
    let guide_map = if s.final_gather && s.guided_gather && !traced_gather {
        crate::photon::guide::indirect_map(maps.global.as_ref())
    } else {
        None
    };
    // Traced gathers find the light of glossy chains themselves.
    let glossy_map = if s.final_gather && !traced_gather {
        maps.global
            .as_ref()
            .and_then(|g| g.subset(|ph| ph.flags() & Photon::GLOSSY != 0))
    } else {
        None
    };
    let glossy_params = glossy_map
        .as_ref()
        .map_or(global_params, |g| typical_radius_params(g, &global_params));
    let receiver_params = (maps.caustic_glossy.as_ref()).map_or(caustic_params, |m| {
        typical_radius_params(m, &caustic_params)
    });
    let caustic_params = (maps.caustic.as_ref()).map_or(caustic_params, |m| {
        typical_radius_params(m, &caustic_params)
    });
    // The estimates read at camera points weigh photons that fill a strip of their disc over
    // the strip's area (`estimate::Weigh`); gather hits pass such points on instead.
    let [caustic_params, receiver_params] =
        [caustic_params, receiver_params].map(|p| EstimateParams {
            min_fill: s.thin_fill,
            ..p
        });
    PhotonPass {
        maps,
        volume,
        volume_stats,
        cache,
        traced_gather,
        caustic_cache,
        guide_map,
        glossy_map,
        settings: s,
        global_params,
        glossy_params,
        caustic_params,
        receiver_params,
        cache_seconds: t.elapsed().as_secs_f64(),
        skipped,
        lights: owned_lights,
    }
}

impl PhotonPass {
    /// In a scene whose media need tracking: the radiance the caustic photons through the
    /// media ([`crate::photon::volume`]) give at a purely diffuse point `si` with BSDF
    /// `bsdf`, from the photons that took at most `max_bounce` bounces; zero without such
    /// photons.
    pub fn caustic_through_media(
        &self,
        si: &SurfaceInteraction,
        bsdf: &Bsdf,
        max_bounce: u8,
        lambda: Lambda,
        buf: &mut KnnResult,
    ) -> Spectrum {
        let Some(map) = &self.maps.caustic else {
            return Spectrum::ZERO;
        };
        let params = EstimateParams {
            max_bounce: max_bounce.min(self.caustic_params.max_bounce),
            ..self.caustic_params
        };
        let (wo, n) = (si.wo, si.facing_normal());
        let f_d = bsdf.f(
            wo,
            Vec3::new(0.0, 0.0, wo.z.signum()),
            TransportMode::Radiance,
        );
        let mut l = f_d * lambda.illuminant(irradiance_with(map, si.p, n, &params, buf).0);
        let f_t = far_side_value(bsdf, wo);
        if f_t != Spectrum::ZERO {
            l += f_t * lambda.illuminant(irradiance_with(map, si.p, -n, &params, buf).0);
        }
        l
    }
}

/// Photons sampled for [`typical_radius_params`].
const RADIUS_PROBES: usize = 64;

/// `params` with the largest radius cut to twice the median k-nearest radius around
/// [`RADIUS_PROBES`] of `map`'s own photons (spread over the tree order, so over space), for
/// the maps read at every camera point (glossy caustics, caustics, caustics on glossy
/// receivers) and the global map read at every gather hit. The global map of a scene lit by
/// a sky holds few photons (only those that bounced: teapot, 4187 of 1.5M emitted), and each
/// gather hit away from them walked the whole map: 657 spp in 30 s, 951 with the cut
/// (relMSE 0.00070 -> 0.00061); classroom 170 -> 330 spp (0.080 -> 0.077), living-room-2
/// 0.030 -> 0.024; dense maps (the Cornell boxes) render the same. A map whose photons gather in a few places never fills a search elsewhere, so
/// each lookup there walked every photon within the largest radius: on classroom at 128 px
/// the glossy lookups took half the render (109 spp in 30 s where 396 ran before the sun's
/// photons were aimed into the room, 217 with the cut); on spaceship the caustic lookups
/// left 30 spp in 8 s (81 with the cut). With the cut, a lookup far from the photons finds
/// fewer of them (its fixed-radius estimate is as unbiased, and noisier), while a dense map
/// fills its searches within the cut anyway.
fn typical_radius_params(map: &PhotonMap, params: &EstimateParams) -> EstimateParams {
    let n = map.len();
    if n == 0 {
        return *params;
    }
    let mut buf = KnnResult::new();
    let mut r2s: Vec<f32> = (0..RADIUS_PROBES.min(n))
        .map(|i| {
            let ph = map.photon((i * n / RADIUS_PROBES.min(n)) as u32);
            map.knn(ph.pos(), params.k, params.max_r2, &mut buf);
            buf.r2()
        })
        .filter(|r2| r2.is_finite())
        .collect();
    if r2s.is_empty() {
        return *params;
    }
    r2s.sort_by(f32::total_cmp);
    // Every photon found counts: a minimum count would zero the lookups the cut left sparse
    // (lamp-enclosed's floor lost 16% of its glossy caustic that way).
    EstimateParams {
        max_r2: (4.0 * r2s[r2s.len() / 2]).min(params.max_r2),
        min_photons: 1,
        ..*params
    }
}

/// Gather rays per diffuse point (0 when not gathering): they also serve as the BSDF-sampling
/// strategy of direct lighting there.
pub fn gather_count(pass: &PhotonPass) -> u32 {
    if pass.settings.final_gather && pass.maps.global.is_some() {
        pass.settings.gather_samples.max(1)
    } else {
        0
    }
}

/// A gather ray in flight and what its radiance is worth to its pixel.
pub struct Gather {
    pub pixel: usize,
    pub ray: Ray,
    pub weight: Spectrum,
    /// Solid-angle density of the ray's direction (for MIS with shadow rays).
    pub pdf: f32,
    /// Shadow rays taken at the gather's origin (for MIS), and that origin as their receiver.
    pub light_samples: u32,
    pub from: Receiver,
    /// Counts towards the `indirect` component (else `specular`: seen through a bounce).
    pub primary: bool,
    /// Bounces behind the ray's origin (0 at the camera's first hit).
    pub depth: u32,
    pub sampler: Sampler,
    /// The camera sample's wavelengths: `weight` and the radiance the ray brings back are
    /// at them (the surfaces it reaches are evaluated there, the photon maps' and lights' RGB
    /// uplifted).
    pub lambda: Lambda,
}

/// What a visible diffuse point gets from the photon maps now (caustic, and indirect when not
/// gathering), plus the gather rays it asks for.
pub struct DiffusePhotons {
    pub caustic: Spectrum,
    pub indirect: Spectrum,
}

/// Photons whose direction the body of a coated surface is evaluated at, per estimate.
const BODY_SAMPLES: usize = 4;

/// Dimensions of the sampler used per gather ray.
pub const GATHER_DIMS: u32 = 2;

/// The gather guide at the diffuse point `si` (see [`crate::photon::guide`]), when guiding is
/// on and the nearest photons say enough; `slot` (the pixel's, for primary points) may hold
/// one to reuse. Shadow rays need it first: their MIS weights use the density [`gather_pdf`]
/// with which the gather would have picked their direction.
pub fn gather_guide(
    pass: &PhotonPass,
    counters: &AtomicU64,
    si: &SurfaceInteraction,
    buf: &mut KnnResult,
    slot: Option<&mut Option<GuideSlot>>,
) -> Option<GatherGuide> {
    let map = pass.guide_map.as_ref()?;
    let t = Instant::now();
    let frame = gather_frame(si);
    let max_r2 = pass.global_params.max_r2;
    let guide = match slot {
        Some(slot) => GuideSlot::get(slot, map, si.p, &frame, max_r2, buf),
        None => GatherGuide::build(map, si.p, &frame, max_r2, buf),
    };
    charge(counters, t);
    guide
}

/// The frame the final gather at `si` samples directions in (around the shading normal on
/// `wo`'s side); the guide, the gather and [`gather_pdf`] must use the same one.
fn gather_frame(si: &SurfaceInteraction) -> Frame {
    Frame::from_normal(si.facing_normal())
}

/// The value of a diffuse point's BSDF (local `wo`) from the far side of its surface towards
/// `wo`: a diffuse transmitter's `T / pi`, zero for a reflector and for a coated surface.
/// Photon estimates weigh the irradiance arriving on the far side by it.
pub fn far_side_value(bsdf: &Bsdf, wo: Vec3) -> Spectrum {
    if bsdf.has_coat() || !bsdf.flags().has_transmission() {
        return Spectrum::ZERO;
    }
    bsdf.f(
        wo,
        Vec3::new(0.0, 0.0, -wo.z.signum()),
        TransportMode::Radiance,
    )
}

/// The share of a diffuse point's gather rays sent into `wo`'s hemisphere: 1, except for a
/// diffuse transmitter, which sends the rest to its far side in proportion to its largest
/// transmitted against its largest reflected value (as its own sampling does).
pub fn gather_front_share(bsdf: &Bsdf, wo: Vec3) -> f32 {
    let t = far_side_value(bsdf, wo).max_element();
    if t.is_nan() || t <= 0.0 {
        return 1.0;
    }
    let r = bsdf
        .f(
            wo,
            Vec3::new(0.0, 0.0, wo.z.signum()),
            TransportMode::Radiance,
        )
        .max_element()
        .max(0.0);
    let share = r / (r + t);
    if share.is_finite() {
        share
    } else {
        1.0
    }
}

/// The solid-angle density with which the final gather at `si` picks world direction `wi`.
/// `front`: the share of gather rays on `wo`'s side ([`gather_front_share`]).
pub fn gather_pdf(
    si: &SurfaceInteraction,
    guide: Option<&GatherGuide>,
    front: f32,
    wi: Vec3,
) -> f32 {
    let frame = gather_frame(si);
    let local = frame.to_local(wi);
    if local.z <= 0.0 {
        return (1.0 - front) * (-local.z).max(0.0) / std::f32::consts::PI;
    }
    let q = guide.map_or(1.0, |g| g.pdf(cosine_hemisphere_to_square(local)));
    front * q * local.z / std::f32::consts::PI
}

/// Photon-map radiance at the diffuse point `si` (BSDF `bsdf`), and its gather rays pushed to
/// `gathers` with throughput `beta`, drawn by `guide` when there is one. For a Lambertian (or
/// diffuse-transmission) surface the photon estimates are `f_d E` with `f_d` its value towards
/// the normal; a coated surface's body weighs photons by its own BSDF
/// ([`Bsdf::f_body`], through [`radiance_sampled`]), its coat being traced by the caller. A
/// gather ray's weight is `f cos / pdf` with the body's own value where it is not Lambertian.
#[allow(clippy::too_many_arguments)]
pub fn at_diffuse(
    pass: &PhotonPass,
    counters: &AtomicU64,
    light_samples: u32,
    guide: Option<&GatherGuide>,
    si: &SurfaceInteraction,
    bsdf: &Bsdf,
    f_d: Spectrum,
    beta: Spectrum,
    pixel: usize,
    depth: u32,
    lambda: Lambda,
    sampler: &mut Sampler,
    buf: &mut KnnResult,
    gathers: &mut Vec<Gather>,
) -> DiffusePhotons {
    let (p, n) = (si.p, si.facing_normal());
    let mut out = DiffusePhotons {
        caustic: Spectrum::ZERO,
        indirect: Spectrum::ZERO,
    };
    let Some(last) = read_limit(&pass.settings.trace, depth + 1) else {
        return out;
    };
    // A coated surface's body is no Lambertian: its photon estimates weigh photons by its own
    // (stochastic) BSDF, evaluated at a few photons drawn by power (`radiance_sampled`).
    let coated = bsdf.has_coat();
    let u_photon = if coated { sampler.next_1d() } else { 0.0 };
    // A diffuse transmitter also passes on what lands on its far side.
    let f_t = far_side_value(bsdf, si.wo);
    let estimate = |map: &PhotonMap, params: &EstimateParams, buf: &mut KnnResult| {
        let t = Instant::now();
        let l = if coated {
            let f = |wi: Vec3, power: Vec3| {
                let f = bsdf.f_body(si.wo, si.frame.to_local(wi), TransportMode::Radiance);
                f * lambda.illuminant(power)
            };
            radiance_sampled(map, p, n, params, buf, (BODY_SAMPLES, u_photon), f).0
        } else {
            let e = irradiance_with(map, p, n, params, buf).0;
            let mut l = f_d * lambda.illuminant(e);
            if f_t != Spectrum::ZERO {
                let e = irradiance_with(map, p, -n, params, buf).0;
                l += f_t * lambda.illuminant(e);
            }
            l
        };
        charge(counters, t);
        beta * l
    };
    if let Some(caustic) = &pass.maps.caustic {
        out.caustic = estimate(caustic, &pass.caustic_params.up_to(last), buf);
    }
    if let Some(glossy) = &pass.glossy_map {
        // Glossy caustics: spread wide, so estimated with the global map's radius.
        out.caustic += estimate(glossy, &pass.glossy_params.up_to(last), buf);
    }
    let Some(global) = &pass.maps.global else {
        return out;
    };
    if !pass.settings.final_gather {
        // The direct look at the global map: only photons that took a diffuse bounce (shadow
        // rays and the caustic map have the rest).
        let params = EstimateParams {
            exclude_flags: Photon::DIRECT | Photon::CAUSTIC,
            ..pass.global_params.up_to(last)
        };
        out.indirect = estimate(global, &params, buf);
        return out;
    }
    // Final gathering: stratified directions, cosine-weighted and (when guided) moved towards
    // where the nearest photons came from; f cos / pdf = f_d pi / q. A diffuse transmitter
    // sends the share `1 - front` of its strata (in u.x) to its far side, cosine-weighted.
    let g = pass.settings.gather_samples.max(1);
    let (nx, ny) = strata(g);
    let frame = gather_frame(si);
    let weight = beta * f_d * (std::f32::consts::PI / g as f32);
    let lambertian = bsdf.is_lambertian();
    let front = gather_front_share(bsdf, si.wo);
    for k in 0..g {
        let j = sampler.next_2d();
        let mut u = Vec2::new(
            ((k % nx) as f32 + j.x) / nx as f32,
            ((k / nx) as f32 + j.y) / ny as f32,
        );
        let (local, q, pdf) = if u.x < front {
            u.x = (u.x / front).min(crate::sampling::ONE_MINUS_EPSILON);
            let (u, q) = guide.map_or((u, 1.0), |gd| gd.sample(u));
            let local = crate::sampling::warp::square_to_cosine_hemisphere(u);
            (local, q, front * q * local.z / std::f32::consts::PI)
        } else {
            u.x = ((u.x - front) / (1.0 - front)).min(crate::sampling::ONE_MINUS_EPSILON);
            let l = crate::sampling::warp::square_to_cosine_hemisphere(u);
            let pdf = (1.0 - front) * l.z / std::f32::consts::PI;
            (Vec3::new(l.x, l.y, -l.z), 1.0, pdf)
        };
        let d = frame.to_world(local);
        let o = si.spawn(if local.z < 0.0 { -n } else { n });
        let w = if lambertian {
            weight / q
        } else {
            let wi = si.frame.to_local(d);
            let f = bsdf.f_body(si.wo, wi, TransportMode::Radiance);
            beta * f * (wi.z.abs() / (pdf * g as f32))
        };
        // Keyed by the pixel's own stream (not the tile-local `pixel`, which a crop window
        // or another tiling changes).
        let gs = Sampler::new(Pattern::Independent, sampler_key(sampler), 0, k, g);
        gathers.push(Gather {
            pixel,
            ray: Ray::new(o, d),
            weight: w,
            pdf,
            light_samples,
            from: si.receiver(),
            primary: depth == 0,
            depth,
            sampler: gs,
            lambda,
        });
    }
    out
}

fn sampler_key(s: &mut Sampler) -> u64 {
    (s.next_1d().to_bits() as u64) << 32 | s.next_1d().to_bits() as u64
}

/// Most specular bounces a gather ray follows to reach a diffuse surface.
const GATHER_SPECULAR_BOUNCES: u32 = 4;

/// Radiance arriving along a gather ray that hit `hit`, split as (direct, indirect): an
/// emitter hit straight away, or the infinite lights when the ray leaves the scene, is the
/// BSDF-sampling half of direct lighting (MIS-weighted against the shadow rays); otherwise the reflected radiance of the first diffuse surface the
/// ray reaches (through at most a few specular/glossy bounces), from the irradiance cache or
/// the global map. Emitters reached through specular or glossy bounces count zero: the caustic
/// map has that light (L (S|G)+ paths, see `photon::trace`).
pub fn gather_radiance(
    ctx: &RenderContext,
    pass: &PhotonPass,
    g: &mut Gather,
    hit: Option<Hit>,
    buf: &mut KnnResult,
) -> (Spectrum, Spectrum) {
    let Some(global) = &pass.maps.global else {
        return (Spectrum::ZERO, Spectrum::ZERO);
    };
    let n_g = pass.settings.gather_samples.max(1) as f32;
    // The gather's weight holds 1/n_g; the heuristic's sample counts do the rest.
    let mis = |light_pdf: f32| {
        crate::sampling::power_heuristic(n_g * g.pdf, g.light_samples as f32 * light_pdf)
    };
    // The gather ray's own segment (a medium it crosses) weighs both.
    let tr = Spectrum::from_rgb(crate::accel::transmittance(ctx.scene, hit.as_ref(), &g.ray));
    let direct = emitted(ctx, &g.ray, g.from, hit.as_ref(), g.lambda, mis);
    (tr * direct, tr * reflected(ctx, pass, global, g, hit, buf))
}

/// The GGX alpha below which glossy lobes count as sharp (caustic chains go on through them,
/// wider ones receive caustic photons), when this pass shot caustic photons; `None` otherwise
/// (then nothing is covered by photons on the camera side).
pub fn caustic_alpha(pass: &PhotonPass) -> Option<f32> {
    (pass.settings.trace.caustic_photons > 0).then_some(pass.settings.trace.receiver_alpha)
}

/// The caustic radiance towards `si.wo` at a rough glossy point (L S+ G paths) from the
/// caustic photons on glossy surfaces, each weighted by `bsdf` (see
/// [`crate::photon::estimate::radiance_with`]); `None` when the point is no receiver
/// ([`trace::is_receiver`]) or no caustic photons were shot. A `Some` means the camera path
/// must not count light it finds from here through sharp bounces only
/// ([`super::photon_mapper::Covered`]).
pub fn at_glossy(
    pass: &PhotonPass,
    counters: &AtomicU64,
    (si, depth): (&SurfaceInteraction, u32),
    bsdf: &Bsdf,
    lambda: Lambda,
    buf: &mut KnnResult,
) -> Option<Spectrum> {
    if !trace::is_receiver(bsdf, caustic_alpha(pass)?) {
        return None;
    }
    let Some(last) = read_limit(&pass.settings.trace, depth + 1) else {
        return Some(Spectrum::ZERO);
    };
    let params = pass.receiver_params.up_to(last);
    let Some(map) = &pass.maps.caustic_glossy else {
        return Some(Spectrum::ZERO); // photons were shot and none arrived on a glossy surface
    };
    let t = Instant::now();
    let wo = si.wo;
    let (l, _, _) = radiance_with(map, si.p, si.ng, &params, buf, |ph| {
        let wi = si.frame.to_local(-ph.dir());
        bsdf.f(wo, wi, TransportMode::Radiance) * lambda.illuminant(ph.power())
    });
    charge(counters, t);
    Some(l)
}

/// The reflected part of [`gather_radiance`]: what the first diffuse surface along the gather
/// ray reflects towards its origin.
fn reflected(
    ctx: &RenderContext,
    pass: &PhotonPass,
    global: &PhotonMap,
    g: &mut Gather,
    hit: Option<Hit>,
    buf: &mut KnnResult,
) -> Spectrum {
    if pass.traced_gather {
        return traced(ctx, pass, g, hit, buf);
    }
    let scene = ctx.scene;
    let mut hit = hit;
    let mut ray = g.ray;
    let mut throughput = Spectrum::ONE;
    // Light taken at thin points passed on (see below), and how many; the specular and coat
    // bounces followed. With the camera path's depth they make the read point later
    // ([`bounce_limit`]).
    let (mut out, mut continued, mut followed) = (Spectrum::ZERO, 0, 0);
    // The density of the direction just drawn at a thin point: an emitter it reaches
    // counts, weighed against that point's shadow ray by the power heuristic.
    let mut from_thin: Option<(f32, Receiver)> = None;
    for _ in 0..=GATHER_SPECULAR_BOUNCES + THIN_CONTINUATIONS {
        if let Some((pdf, from)) = from_thin.take() {
            let mis = |light_pdf: f32| crate::sampling::power_heuristic(pdf, light_pdf);
            out += throughput * emitted(ctx, &ray, from, hit.as_ref(), g.lambda, mis);
        }
        let Some(h) = hit else { return out };
        let extra = g.depth + continued + followed;
        let mut si = SurfaceInteraction::new(scene, &h, &ray);
        let bsdf = si.bsdf(scene, ctx.settings.footprint(), g.lambda);
        let wo = si.wo;
        if bsdf.has_coat() {
            // A coated surface: its coat's reflection (followed, like a specular bounce) or its
            // body (the cached irradiance weighed by the body's value towards a cosine-sampled
            // direction: its albedo for light from all around), chosen by the coat's Fresnel
            // reflectance towards wo (at least 0.1 each).
            let p_coat = coat_choice(&bsdf, wo);
            if g.sampler.next_1d() >= p_coat {
                let wi = crate::sampling::warp::square_to_cosine_hemisphere(g.sampler.next_2d());
                let wi = if wo.z < 0.0 { -wi } else { wi };
                let f_b = bsdf.f_body(wo, wi, TransportMode::Radiance);
                let n = si.facing_normal();
                let e = cached_irradiance(pass, global, si.p, n, extra, buf);
                let direct = direct_at_gather(ctx, &si, &mut g.sampler, g.lambda, |wi| {
                    bsdf.f_body(wo, wi, TransportMode::Radiance)
                });
                let e = g.lambda.illuminant(e.irradiance);
                return out + throughput * (f_b * e + direct) / (1.0 - p_coat);
            }
            let Some(bs) = bsdf.sample_coat(
                wo,
                g.sampler.next_1d(),
                g.sampler.next_2d(),
                TransportMode::Radiance,
            ) else {
                return out;
            };
            throughput *= bs.f * (bs.wi.z.abs() / (bs.pdf * p_coat));
            ray = si.spawn_ray(si.frame.to_world(bs.wi));
            let (h, tr) = gather_segment(ctx, &ray);
            (hit, throughput) = (h, throughput * tr);
            followed += 1;
            continue;
        }
        if bsdf.flags().has_diffuse() {
            let f_d = bsdf.f(
                wo,
                Vec3::new(0.0, 0.0, wo.z.signum()),
                TransportMode::Radiance,
            );
            let n = si.facing_normal();
            let cached = cached_irradiance(pass, global, si.p, n, extra, buf);
            // A diffuse transmitter (a curtain) passes on what lands on its far side.
            let f_t = far_side_value(&bsdf, wo);
            if cached.fill < pass.settings.thin_fill
                && continued < THIN_CONTINUATIONS
                && bounce_limit(&pass.settings.trace, extra + 1).is_some()
                && f_t == Spectrum::ZERO
            {
                // Thin geometry: the estimate's photons fill a strip of its disc (a tube, an
                // edge) and divide by the whole disc. Take this point's light by a shadow ray
                // to any light and go on one cosine-sampled bounce; emitters that ray reaches
                // count zero (the shadow ray has them).
                continued += 1;
                let f = |wi: Vec3| bsdf.f(wo, wi, TransportMode::Radiance);
                out += throughput * direct_mis(ctx, &si, &mut g.sampler, g.lambda, f);
                // The light that reaches it through specular bounces (sun through a window
                // onto a chair's tube), which its estimate held and no shadow ray finds: the
                // caustic map's. (Tracing on to the lights through the glass made fireflies:
                // cornell-spheres at 16 spp, relMSE 0.0081 -> 0.0091.)
                if let (Some(caustic), Some(last)) = (
                    &pass.maps.caustic,
                    bounce_limit(&pass.settings.trace, extra),
                ) {
                    let params = pass.caustic_params.up_to(last);
                    let e = irradiance_with(caustic, si.p, n, &params, buf).0;
                    out += throughput * f_d * g.lambda.illuminant(e);
                }
                let local = crate::sampling::warp::square_to_cosine_hemisphere(g.sampler.next_2d());
                let wi = if wo.z < 0.0 { -local } else { local };
                let pdf = local.z / std::f32::consts::PI;
                if pdf <= 0.0 {
                    return out;
                }
                throughput *= f(wi) * (wi.z.abs() / pdf);
                from_thin = Some((pdf, si.receiver()));
                ray = si.spawn_ray(si.frame.to_world(wi));
                let (h, tr) = gather_segment(ctx, &ray);
                (hit, throughput) = (h, throughput * tr);
                continue;
            }
            let mut e = f_d * g.lambda.illuminant(cached.irradiance);
            if f_t != Spectrum::ZERO {
                let far = cached_irradiance(pass, global, si.p, -n, extra, buf).irradiance;
                e += f_t * g.lambda.illuminant(far);
            }
            let direct = direct_at_gather(ctx, &si, &mut g.sampler, g.lambda, |wi| {
                bsdf.f(wo, wi, TransportMode::Radiance)
            });
            return out + throughput * (e + direct);
        }
        // Specular or glossy: follow one sampled direction.
        let Some(bs) = bsdf.sample(
            wo,
            g.sampler.next_1d(),
            g.sampler.next_2d(),
            TransportMode::Radiance,
        ) else {
            return out;
        };
        throughput *= bs.f * (bs.wi.z.abs() / bs.pdf);
        ray = si.spawn_ray(si.frame.to_world(bs.wi));
        let (h, tr) = gather_segment(ctx, &ray);
        (hit, throughput) = (h, throughput * tr);
        followed += 1;
    }
    out
}

/// How a traced gather path counts an emitter it reaches (see [`traced`]).
#[derive(Clone, Copy)]
enum EmitterWeight {
    /// Right after a vertex that took a shadow ray: the power heuristic of the sampled
    /// direction's density against the light's for that vertex's shadow ray.
    Mis(f32, Receiver),
    /// After a bounce that no shadow ray stands for (a glossy or coat reflection).
    Full,
    /// Counted elsewhere: the gather's own origin weighs it against its shadow rays
    /// ([`emitted`] in [`gather_radiance`]), or the caustic map holds it (sharp bounces only
    /// since the last point that read it).
    Zero,
}

/// What the gather ray `g` (first hit `hit`) brings back when the global map is too sparse to
/// read ([`PhotonPass::traced_gather`]): the reflected light is path-traced. At each point
/// with a diffuse lobe (a coated surface's body, chosen as in [`reflected`]) a shadow ray to
/// any light (power heuristic against the cosine-sampled continuation), the caustic map's
/// irradiance (from its cache, [`PhotonPass::caustic_cache`]), and a cosine-sampled bounce on; specular and glossy surfaces are followed by
/// their BSDF. An emitter reached after sharp bounces only from such a point is the caustic
/// map's; one reached after a glossy bounce counts in full (the glossy map is not built in
/// this mode). Paths keep to the render's `maxdepth`; Russian roulette on the throughput
/// after [`super::path::RR_MIN_BOUNCES`] bounces.
fn traced(
    ctx: &RenderContext,
    pass: &PhotonPass,
    g: &mut Gather,
    hit: Option<Hit>,
    buf: &mut KnnResult,
) -> Spectrum {
    let scene = ctx.scene;
    let sharp_alpha = caustic_alpha(pass);
    let caustic = pass.maps.caustic.as_ref();
    let (mut hit, mut ray) = (hit, g.ray);
    let (mut throughput, mut out) = (Spectrum::ONE, Spectrum::ZERO);
    let mut weight = EmitterWeight::Zero;
    // Sharp bounces only since the last point that read the caustic map (the gather's origin
    // read it).
    let mut sharp_chain = true;
    let mut depth = g.depth + 1;
    loop {
        let w = match weight {
            EmitterWeight::Zero => None,
            EmitterWeight::Full => Some(None),
            EmitterWeight::Mis(pdf, from) => Some(Some((pdf, from))),
        };
        if let Some(pdf) = w {
            let from = pdf.map_or(g.from, |(_, from)| from);
            let mis = |light_pdf: f32| {
                pdf.map_or(1.0, |(p, _)| crate::sampling::power_heuristic(p, light_pdf))
            };
            out += throughput * emitted(ctx, &ray, from, hit.as_ref(), g.lambda, mis);
        }
        let Some(h) = hit else { return out };
        if depth >= ctx.settings.max_depth {
            return out;
        }
        let mut si = SurfaceInteraction::new(scene, &h, &ray);
        let bsdf = si.bsdf(scene, ctx.settings.footprint(), g.lambda);
        let wo = si.wo;
        let coated = bsdf.has_coat();
        let p_coat = coat_choice(&bsdf, wo);
        let body = coated && g.sampler.next_1d() >= p_coat;
        let wi;
        if body
            || (!coated
                && bsdf.flags().has_diffuse()
                && far_side_value(&bsdf, wo) == Spectrum::ZERO)
        {
            // A diffuse point: shadow ray, caustic estimate, cosine-sampled bounce.
            let choice = if coated { 1.0 - p_coat } else { 1.0 };
            let f = |wi: Vec3| {
                if coated {
                    bsdf.f_body(wo, wi, TransportMode::Radiance)
                } else {
                    bsdf.f(wo, wi, TransportMode::Radiance)
                }
            };
            out += throughput * direct_mis(ctx, &si, &mut g.sampler, g.lambda, f) / choice;
            // The caustic photons this point may read: all of them up to the second vertex
            // (the cache's), then fewer ([`read_limit`]).
            let last = read_limit(&pass.settings.trace, depth + 1);
            if let (Some(map), Some(last)) = (caustic, last) {
                let n = si.facing_normal();
                let params = pass.caustic_params.up_to(last);
                let cache = (pass.caustic_cache.as_ref()).filter(|_| depth < 2 || last == u8::MAX);
                let cached = cache.and_then(|c| c.lookup(si.p, n, params.max_r2, 0, buf));
                let l = if let Some(c) = cached {
                    // The body at a cosine-drawn direction for light from all around, as the
                    // dense maps' gather hits read it.
                    let local =
                        crate::sampling::warp::square_to_cosine_hemisphere(g.sampler.next_2d());
                    let wi = if wo.z < 0.0 { -local } else { local };
                    f(wi) * g.lambda.illuminant(c.irradiance)
                } else if cache.is_some() {
                    // No cache point's estimate covers this point: at most a few caustic
                    // photons lie near it. Zero, not a full search (which there walks every
                    // photon of the other side of a thin panel: car 2.6 s -> 1.7 s at 16 spp;
                    // the image's mean moved 0.03%, its 4x4 blocks at most 0.1%).
                    Spectrum::ZERO
                } else if coated {
                    let u = g.sampler.next_1d();
                    let fw =
                        |w: Vec3, power: Vec3| f(si.frame.to_local(w)) * g.lambda.illuminant(power);
                    radiance_sampled(map, si.p, n, &params, buf, (BODY_SAMPLES, u), fw).0
                } else {
                    let f_d = f(Vec3::new(0.0, 0.0, wo.z.signum()));
                    let e = irradiance_with(map, si.p, n, &params, buf).0;
                    f_d * g.lambda.illuminant(e)
                };
                out += throughput * l / choice;
            }
            let local = crate::sampling::warp::square_to_cosine_hemisphere(g.sampler.next_2d());
            let pdf = local.z / std::f32::consts::PI;
            if pdf <= 0.0 {
                return out;
            }
            wi = if wo.z < 0.0 { -local } else { local };
            throughput *= f(wi) * (wi.z.abs() / (pdf * choice));
            weight = EmitterWeight::Mis(pdf, si.receiver());
            sharp_chain = true;
        } else {
            // Specular, glossy, a coat's reflection or a diffuse transmitter: one sampled
            // direction.
            let (uc, u) = (g.sampler.next_1d(), g.sampler.next_2d());
            let bs = if coated {
                bsdf.sample_coat(wo, uc, u, TransportMode::Radiance)
            } else {
                bsdf.sample(wo, uc, u, TransportMode::Radiance)
            };
            let Some(bs) = bs else { return out };
            let choice = if coated { p_coat } else { 1.0 };
            throughput *= bs.f * (bs.wi.z.abs() / (bs.pdf * choice));
            wi = bs.wi;
            let sharp =
                sharp_alpha.is_some_and(|a| trace::is_sharp_bounce(&bsdf, bs.lobe_alpha, a));
            sharp_chain &= sharp;
            weight = if sharp_chain && caustic.is_some() {
                EmitterWeight::Zero
            } else {
                EmitterWeight::Full
            };
        }
        depth += 1;
        if depth > super::path::RR_MIN_BOUNCES {
            let survive = throughput.max_element().min(1.0);
            if g.sampler.next_1d() >= survive {
                return out;
            }
            throughput /= survive;
        }
        if !throughput.is_finite() || throughput.max_element() <= 0.0 {
            return out;
        }
        ray = si.spawn_ray(si.frame.to_world(wi));
        let (h, tr) = gather_segment(ctx, &ray);
        (hit, throughput) = (h, throughput * tr);
    }
}

/// The next hit of a gather path along `ray` (counted as a secondary ray) and the
/// transmittance of the media the segment crosses.
fn gather_segment(ctx: &RenderContext, ray: &Ray) -> (Option<Hit>, Spectrum) {
    let hit = ctx.accel.intersect(RayKind::Gather, ray);
    ctx.counters
        .secondary_rays
        .fetch_add(1, std::sync::atomic::Ordering::Relaxed);
    let tr = crate::accel::transmittance(ctx.scene, hit.as_ref(), ray);
    (hit, Spectrum::from_rgb(tr))
}

/// Most thin points a gather ray passes on.
const THIN_CONTINUATIONS: u32 = 2;
const _: () = assert!(
    (THIN_CONTINUATIONS as usize) < LEVELS,
    "the cache keeps a level per continuation"
);

/// Direct light at a thin point `si` from one light of any kind picked by importance: one shadow
/// ray, weighted by `f(wi)` (local `wi`) `|cos| / pdf` and, for lights a cosine-drawn
/// direction can reach, by the power heuristic against that direction (its half is
/// [`emitted`]). Without the heuristic a thin point beside a lamp's bulb made fireflies
/// (dining-room: two pixels 0.67 and 0.94 where pbrt-v4 has 0.05 and 0.16).
fn direct_mis(
    ctx: &RenderContext,
    si: &SurfaceInteraction,
    sampler: &mut Sampler,
    lambda: Lambda,
    f: impl Fn(Vec3) -> Spectrum,
) -> Spectrum {
    let u_sel = sampler.next_1d();
    let u = sampler.next_2d();
    let s = ctx
        .lights
        .sample(&ctx.scene.meshes, si.receiver(), u_sel, u);
    shadow_ray_value(ctx, si, s, lambda, f, true)
}

/// The light a ray finds straight away: the emitter it hit, or the infinite lights when it
/// left the scene (`hit` `None`), each times `weight(pdf)` where `pdf` is the density with
/// which a shadow ray from `from` would have picked that point ([`Lights::pdf_area`],
/// [`Lights::escaped`]): the BSDF-sampling half of MIS at gather origins and at thin points
/// ([`direct_mis`]).
fn emitted(
    ctx: &RenderContext,
    ray: &Ray,
    from: Receiver,
    hit: Option<&Hit>,
    lambda: Lambda,
    weight: impl Fn(f32) -> f32,
) -> Spectrum {
    let Some(h) = hit else {
        return lambda.illuminant(
            ctx.lights
                .escaped(ray.o, ray.d, Pick::At(from), |_, pdf| weight(pdf)),
        );
    };
    let mesh = &ctx.scene.meshes[h.mesh as usize];
    let Some(li) = mesh.area_light else {
        return Spectrum::ZERO;
    };
    let p = mesh.point(h.prim, h.u, h.v);
    let ng = mesh.geometric_normal(h.prim, h.u, h.v);
    let le = lambda.illuminant(ctx.lights.le(li as usize, ng, -ray.d));
    le * weight(ctx.lights.pdf_area(li as usize, from, p, ng))
}

/// Direct light of the lights without a surface (point, spot, distant, infinite) at a gather
/// ray's diffuse hit `si`: one shadow ray to one of them picked by power, weighted by `f(wi)`
/// (the BSDF's diffuse part, local `wi`) `|cos| / pdf`; the global map holds no photon stored
/// straight from them (`photon::trace`). Such lights reach a room through its
/// windows: a few of their photons enter, in sharp patches that blur and leak at any photon
/// count a render can afford, while a shadow ray is exact (noise-free for the sun). Area
/// lights keep their direct photons, which are dense around them and cost no ray.
fn direct_at_gather(
    ctx: &RenderContext,
    si: &SurfaceInteraction,
    sampler: &mut Sampler,
    lambda: Lambda,
    f: impl Fn(Vec3) -> Spectrum,
) -> Spectrum {
    if !ctx.lights.has_surfaceless() {
        return Spectrum::ZERO;
    }
    let u_sel = sampler.next_1d();
    let u = sampler.next_2d();
    let s = (ctx.lights).sample_surfaceless(&ctx.scene.meshes, si.p, u_sel, u);
    shadow_ray_value(ctx, si, s, lambda, f, false)
}

/// What the light sample `s` brings to `si` through one shadow ray: `f(wi)` (local `wi`)
/// `|cos| / pdf` times its radiance, zero when occluded; with `cosine_mis`, times the power
/// heuristic against a cosine-drawn direction for lights such a direction can reach.
fn shadow_ray_value(
    ctx: &RenderContext,
    si: &SurfaceInteraction,
    s: Option<LightSample>,
    lambda: Lambda,
    f: impl Fn(Vec3) -> Spectrum,
    cosine_mis: bool,
) -> Spectrum {
    let Some(s) = s else {
        return Spectrum::ZERO;
    };
    let wi = si.frame.to_local(s.wi);
    let mut value = f(wi) * (wi.z.abs() / s.pdf);
    if value.max_element() <= 0.0 || !value.is_finite() {
        return Spectrum::ZERO;
    }
    if cosine_mis && !s.delta {
        let cos_pdf = wi.z.abs() / std::f32::consts::PI;
        value *= crate::sampling::power_heuristic(s.pdf, cos_pdf);
    }
    ctx.counters
        .shadow_rays
        .fetch_add(1, std::sync::atomic::Ordering::Relaxed);
    if ctx.accel.occluded(RayKind::Shadow, &si.shadow_ray(&s)) {
        return Spectrum::ZERO;
    }
    value * lambda.illuminant(s.li)
}

/// The probability with which a gather ray that reaches a coated surface follows its coat:
/// the coat's Fresnel reflectance towards `wo`, within [0.1, 0.9].
fn coat_choice(bsdf: &Bsdf, wo: Vec3) -> f32 {
    let Some(eta) = bsdf.coat_eta() else {
        return 0.0;
    };
    crate::bsdf::fresnel::fr_dielectric(wo.z.abs(), eta).clamp(0.1, 0.9)
}

/// The last bounce ([`Photon::bounce`]) of the photons a read at the `vertex`-th scattering
/// vertex of a camera path (1: the camera's first hit) may use: a photon stored at bounce `b`
/// (0 straight from the light) read there makes a light path of `vertex + b` scattering
/// vertices, at most the render's `maxdepth` (`max_bounces + 1`, see
/// [`PhotonSettings::follow_depth`]). `Some(u8::MAX)` when no photon is too late, `None`
/// when every one is. Without it a camera path that reached its diffuse point through
/// specular bounces read light one bounce too long per bounce: water-caustic (seen through
/// its water, light trapped below it by total internal reflection) 2-6% too bright against
/// pbrt-v4 and our vcm at maxdepth 9.
fn read_limit(trace: &TraceSettings, vertex: u32) -> Option<u8> {
    let last = (trace.max_bounces + 1).checked_sub(vertex)?;
    Some(if last >= Photon::MAX_BOUNCE as u32 {
        u8::MAX
    } else {
        last as u8
    })
}

/// [`read_limit`] at a gather hit `extra` scattering vertices later than the shortest one
/// (the gather from the camera's first hit): the camera path's depth, the specular bounces
/// and thin points the gather passed.
fn bounce_limit(trace: &TraceSettings, extra: u32) -> Option<u8> {
    read_limit(trace, extra + 2)
}

/// Irradiance at `p` (normal `n`) read by a gather path whose read point lies `extra`
/// scattering vertices later than the shortest gather's, from the photons it may read
/// ([`bounce_limit`]): the cached value that covers `p` (see [`IrradianceCache::lookup`]),
/// else a full global-map estimate.
fn cached_irradiance(
    pass: &PhotonPass,
    global: &PhotonMap,
    p: Vec3,
    n: Vec3,
    extra: u32,
    buf: &mut KnnResult,
) -> Cached {
    let Some(max_bounce) = bounce_limit(&pass.settings.trace, extra) else {
        return Cached {
            irradiance: Vec3::ZERO,
            fill: 1.0,
        };
    };
    let cached = pass.cache.as_ref().filter(|_| (extra as usize) < LEVELS);
    let max_r2 = pass.global_params.max_r2;
    if let Some(c) = cached.and_then(|c| c.lookup(p, n, max_r2, extra as usize, buf)) {
        return c;
    }
    let params = EstimateParams {
        min_photons: 1,
        max_bounce,
        ..pass.global_params
    };
    let (irradiance, _, r2) = irradiance_with(global, p, n, &params, buf);
    Cached {
        irradiance,
        fill: crate::photon::estimate::fill(global, p, n, r2, buf),
    }
}

/// The pass-1 statistics as printed lines.
pub fn describe(pass: &PhotonPass) -> Vec<String> {
    let vs = &pass.volume_stats;
    if vs.emitted > 0 {
        return vec![format!(
            "volume photons: {} emitted -> {} stored in scattering media in {:.3} s, binned in {:.3} s, {:.1} MB, sphere radius {:.4}; caustic photons through the media: {} emitted (aimed) -> {} stored on diffuse surfaces in {:.3} s; {:.2} rays/photon; the surfaces are path-traced with the caustic photons, the media read by beams (camera segments) and point estimates (later scattering points)",
            vs.emitted,
            vs.stored,
            vs.seconds,
            vs.build_seconds,
            pass.volume.as_ref().map_or(0, |v| v.bytes()) as f64 / 1e6,
            pass.volume.as_ref().map_or(0.0, |v| v.radius()),
            vs.caustic_emitted,
            vs.caustic,
            vs.caustic_seconds,
            vs.rays as f64 / (vs.emitted + vs.caustic_emitted).max(1) as f64,
        )];
    }
    let st = &pass.maps.stats;
    let bytes = std::mem::size_of::<Photon>();
    let mut lines = vec![format!(
        "photons: global {} emitted -> {} stored; caustic {} emitted -> {} stored ({} on glossy surfaces); {} bytes/photon; traced in {:.3} s ({:.2} Mphotons/s, {:.2} rays/photon), kd-trees built in {:.3} s",
        st.global_emitted,
        st.global_stored,
        st.caustic_emitted,
        st.caustic_stored,
        st.caustic_glossy_stored,
        bytes,
        st.trace_seconds,
        (st.global_emitted + st.caustic_emitted) as f64 / st.trace_seconds.max(1e-9) / 1e6,
        st.rays as f64 / (st.global_emitted + st.caustic_emitted).max(1) as f64,
        st.build_seconds
    )];
    if st.caustic_emitted > 0 {
        lines.push(format!(
            "caustic efficiency: {:.1}% of caustic photons reach a specular or near-smooth surface ({:.1}% without projection maps); marked fraction per light {:?}",
            100.0 * st.caustic_efficiency,
            100.0 * st.caustic_efficiency_unrestricted,
            st.marked_fraction.iter().map(|f| (f * 1000.0).round() / 1000.0).collect::<Vec<_>>()
        ));
    }
    if let Some(a) = &st.aim {
        lines.push(format!(
            "aimed global photons: {:.0}% of the distant and infinite lights' at the sphere of radius {:.3} around ({:.3}, {:.3}, {:.3}) that the camera sees",
            100.0 * a.share,
            a.radius,
            a.center.x,
            a.center.y,
            a.center.z
        ));
    }
    if st.global_per_light.len() > 1 || st.caustic_per_light.len() > 1 {
        lines.push(format!(
            "photon budget by light power: global {:?}, caustic {:?}",
            st.global_per_light, st.caustic_per_light
        ));
    }
    if let Some(c) = &pass.cache {
        lines.push(format!(
            "irradiance cache: {} points in {:.3} s",
            c.len(),
            pass.cache_seconds
        ));
    }
    for s in &pass.skipped {
        lines.push(format!("skipped: {s}"));
    }
    lines
}
