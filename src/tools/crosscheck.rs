//! `photon crosscheck SCENE`: do Embree and obvhs answer the rays of a real render alike?
//!
//! 1. Renders the scene (photon mapper, the file's settings made small: see
//!    [`crate::integrator::recorded`]) through a recording wrapper around Embree and keeps up to
//!    `--rays` of the rays it casts of each kind (camera, shadow, final gather, specular
//!    bounce, photon path), chosen by a seeded hash of the rays; prints how many of each kind
//!    the render cast and how many were kept.
//! 2. Answers each ray with both backends (closest hit and occlusion) and reports, per kind:
//!    hit/miss disagreements, hits on different triangles, occlusion disagreements, and the
//!    |t| difference (absolute and relative; max and 99.9th percentile) where both hit the
//!    same triangle. Every disagreement is classified when it can be explained:
//!    - `self`: a hit at the ray origin (t |d| within 1e-5 of the scene scale): the surface
//!      the ray leaves;
//!    - `tie`: both hit, different triangles at the same t (1e-4 relative): coplanar overlap
//!      or a shared edge, either answer is right;
//!    - `edge` / `vertex`: the (nearer) hit lies within 1e-5 scene units of a triangle edge
//!      or two: the ray grazes an edge where a non-watertight test may leave a crack;
//!    - `end`: the hit lies at the end of the ray's interval (t within 1e-4 of tmin or tmax);
//!    - `unexplained`: none of these.
//! 3. Renders the scene with both backends under the same seed (photon mapper, reduced
//!    resolution) and reports the relMSE between the two images.
//!
//! Exit code 1 when, for any kind, the unexplained disagreements or all disagreements exceed
//! their fraction of the rays, or the 99.9th percentile of the relative |t| difference or the
//! images' relMSE exceed their thresholds (defaults in `--help`).
use super::job::{Job, Overrides};
use super::{parse_resolution, ToolError};
use crate::accel::recording::{Query, RaySet, RecordedRays};
use crate::accel::{Accel, BackendKind, Hit, RayKind, RayQuery};
use crate::imageio::metrics::{self, MaskOptions};
use crate::integrator::{self, recorded, IntegratorKind, RenderSettings};
use crate::math::Ray;
use crate::scene::Scene;
use rayon::prelude::*;
use std::fmt::Write as _;
use std::path::PathBuf;
use std::time::Instant;

/// Default of `--max-unexplained`.
pub const DEFAULT_MAX_UNEXPLAINED: f64 = 1e-4;
/// Default of `--max-disagree`.
pub const DEFAULT_MAX_DISAGREE: f64 = 1e-2;
/// Default of `--max-t-rel`.
pub const DEFAULT_MAX_T_REL: f64 = 1e-4;
/// Default of `--max-relmse`.
pub const DEFAULT_MAX_RELMSE: f64 = 1e-3;

/// Options of `photon crosscheck`.
#[derive(clap::Args, Clone, Debug)]
pub struct CrosscheckOptions {
    /// The pbrt-v4 scene file.
    pub scene: PathBuf,
    /// Rays of each kind (camera, shadow, gather, bounce, photon) to record and compare (at
    /// most 10^8; the memory they need is checked first).
    #[arg(long, default_value_t = 100_000, value_parser = super::usize_in(1, 100_000_000))]
    pub rays: usize,
    /// Seed of the render (sample streams) and of the choice of recorded rays.
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
    /// Resolution of the two comparison renders (default: the Film's, scaled to at most 128
    /// pixels on the longer side).
    #[arg(long, value_parser = parse_resolution)]
    pub image_res: Option<(u32, u32)>,
    /// Samples per pixel of the two comparison renders.
    #[arg(long, default_value_t = 4)]
    pub image_spp: u32,
    /// Skip the two comparison renders.
    #[arg(long)]
    pub no_render: bool,
    /// Worker threads (0 = all cores).
    #[arg(long, default_value_t = 0)]
    pub threads: usize,
    /// Fail when a kind's unexplained disagreements exceed this fraction of its rays.
    #[arg(long, default_value_t = DEFAULT_MAX_UNEXPLAINED)]
    pub max_unexplained: f64,
    /// Fail when a kind's disagreements of any class exceed this fraction of its rays.
    #[arg(long, default_value_t = DEFAULT_MAX_DISAGREE)]
    pub max_disagree: f64,
    /// Fail when the 99.9th percentile of |t_embree - t_obvhs| / t on same-triangle hits
    /// exceeds this.
    #[arg(long, default_value_t = DEFAULT_MAX_T_REL)]
    pub max_t_rel: f64,
    /// Fail when the relMSE between the two renders exceeds this.
    #[arg(long, default_value_t = DEFAULT_MAX_RELMSE)]
    pub max_relmse: f64,
    /// Unexplained disagreements to print per kind.
    #[arg(long, default_value_t = 3)]
    pub show: usize,
    /// Print the report as JSON instead of text.
    #[arg(long)]
    pub json: bool,
}

/// The failure thresholds (see [`CrosscheckOptions`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Thresholds {
    pub max_unexplained: f64,
    pub max_disagree: f64,
    pub max_t_rel: f64,
    pub max_relmse: f64,
}

impl Default for Thresholds {
    fn default() -> Self {
        Thresholds {
            max_unexplained: DEFAULT_MAX_UNEXPLAINED,
            max_disagree: DEFAULT_MAX_DISAGREE,
            max_t_rel: DEFAULT_MAX_T_REL,
            max_relmse: DEFAULT_MAX_RELMSE,
        }
    }
}

/// Why two answers may differ (see the module docs).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Class {
    SelfHit,
    Tie,
    Edge,
    Vertex,
    IntervalEnd,
    Unexplained,
}

impl Class {
    pub const ALL: [Class; 6] = [
        Class::SelfHit,
        Class::Tie,
        Class::Edge,
        Class::Vertex,
        Class::IntervalEnd,
        Class::Unexplained,
    ];

    pub fn name(self) -> &'static str {
        match self {
            Class::SelfHit => "self",
            Class::Tie => "tie",
            Class::Edge => "edge",
            Class::Vertex => "vertex",
            Class::IntervalEnd => "end",
            Class::Unexplained => "unexplained",
        }
    }
}

/// Maximum and 99.9th percentile of a set of differences.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Spread {
    pub max: f64,
    pub p999: f64,
}

impl Spread {
    /// Of `v` (sorted in place); zeros for an empty set.
    pub fn of(v: &mut [f64]) -> Spread {
        if v.is_empty() {
            return Spread::default();
        }
        v.sort_by(f64::total_cmp);
        let i = ((v.len() as f64 * 0.999).ceil() as usize).clamp(1, v.len()) - 1;
        Spread {
            max: v[v.len() - 1],
            p999: v[i],
        }
    }
}

/// The comparison of one kind of rays.
#[derive(Clone, Debug, Default)]
pub struct KindReport {
    pub kind: Option<RayKind>,
    /// The query the render cast these rays with.
    pub query: Option<Query>,
    /// Rays compared.
    pub rays: usize,
    /// Rays of this kind and query the recorded render cast (`rays` of them were kept).
    pub cast: u64,
    /// Closest hits found by the reference and the candidate.
    pub hits: [usize; 2],
    /// One backend hits, the other misses.
    pub hit_miss: usize,
    /// Both hit, different triangles.
    pub other_triangle: usize,
    /// Occlusion answers differ.
    pub occlusion: usize,
    /// Both hit the same triangle.
    pub same_triangle: usize,
    /// |dt| on same-triangle hits, in units of the ray direction.
    pub t_abs: Spread,
    /// |dt| / t on same-triangle hits.
    pub t_rel: Spread,
    /// Rays with any disagreement (closest hit or occlusion).
    pub disagreeing: usize,
    /// Disagreeing rays per class, in [`Class::ALL`] order.
    pub classes: [usize; 6],
    /// A few unexplained cases, described.
    pub examples: Vec<String>,
}

impl KindReport {
    pub fn unexplained(&self) -> usize {
        self.classes[5]
    }

    pub fn count(&self, c: Class) -> usize {
        let i = Class::ALL.iter().position(|&x| x == c).unwrap_or(5);
        self.classes[i]
    }
}

/// One backend's answers to one ray.
#[derive(Clone, Copy, Debug)]
struct Answer {
    hit: Option<Hit>,
    occluded: bool,
}

fn answer_all(q: &dyn RayQuery, rays: &[Ray]) -> Vec<Answer> {
    rays.par_iter()
        .map(|r| Answer {
            hit: q.intersect(r),
            occluded: q.occluded(r),
        })
        .collect()
}

/// Relative difference `|a - b| / max(|a|, |b|)` (0 when both are 0).
fn rel_diff(a: f32, b: f32) -> f64 {
    let m = a.abs().max(b.abs()) as f64;
    if m == 0.0 {
        0.0
    } else {
        (a as f64 - b as f64).abs() / m
    }
}

/// Tolerances of the classification, from the scene's size.
struct Classifier<'a> {
    scene: &'a Scene,
    /// Radius of the scene's bounding sphere.
    radius: f32,
}

const TIE_REL: f64 = 1e-4;
const SELF_EPS: f32 = 1e-5;
const EDGE_EPS: f32 = 1e-5;
const END_REL: f64 = 1e-4;

impl Classifier<'_> {
    /// Absolute length scale at the ray's origin.
    fn scale(&self, ray: &Ray) -> f32 {
        self.radius.max(ray.o.abs().max_element())
    }

    fn is_self_hit(&self, ray: &Ray, h: &Hit) -> bool {
        h.t * ray.d.length() <= SELF_EPS * self.scale(ray)
    }

    /// Number of edges of its triangle the hit point lies within `EDGE_EPS` scene units of.
    fn edges_near(&self, ray: &Ray, h: &Hit) -> usize {
        let Some(mesh) = self.scene.meshes.get(h.mesh as usize) else {
            return 0;
        };
        if h.prim as usize >= mesh.indices.len() {
            return 0;
        }
        let [p0, p1, p2] = mesh.triangle(h.prim);
        let twice_area = (p1 - p0).cross(p2 - p0).length();
        let eps = EDGE_EPS * self.scale(ray);
        // Distance to the edge opposite vertex i = barycentric_i * (2 area / |edge|).
        let bary = [1.0 - h.u - h.v, h.u, h.v];
        let edges = [p2 - p1, p0 - p2, p1 - p0];
        bary.iter()
            .zip(edges)
            .filter(|(b, e)| {
                let len = e.length();
                len > 0.0 && b.abs() * twice_area / len <= eps
            })
            .count()
    }

    fn at_interval_end(&self, ray: &Ray, h: &Hit) -> bool {
        let near = |x: f32| x.is_finite() && rel_diff(h.t, x) <= END_REL;
        near(ray.tmax) || near(ray.tmin.max(0.0))
    }

    /// Classifies a disagreement whose deciding hit is `h` (the hit one backend found and the
    /// other did not, or the nearer of two).
    fn single(&self, ray: &Ray, h: &Hit) -> Class {
        if self.is_self_hit(ray, h) {
            return Class::SelfHit;
        }
        match self.edges_near(ray, h) {
            0 if self.at_interval_end(ray, h) => Class::IntervalEnd,
            0 => Class::Unexplained,
            1 => Class::Edge,
            _ => Class::Vertex,
        }
    }

    /// Classifies differing closest hits.
    fn closest(&self, ray: &Ray, a: &Option<Hit>, b: &Option<Hit>) -> Class {
        match (a, b) {
            (Some(x), Some(y)) => {
                if self.is_self_hit(ray, x) || self.is_self_hit(ray, y) {
                    Class::SelfHit
                } else if rel_diff(x.t, y.t) <= TIE_REL {
                    Class::Tie
                } else {
                    let (near, far) = if x.t <= y.t { (x, y) } else { (y, x) };
                    match self.single(ray, near) {
                        Class::Unexplained => self.single(ray, far),
                        c => c,
                    }
                }
            }
            (Some(h), None) | (None, Some(h)) => self.single(ray, h),
            (None, None) => Class::Unexplained,
        }
    }

    /// Classifies differing occlusion answers by the closest hit of the backend that says
    /// "occluded".
    fn occlusion(&self, ray: &Ray, a: &Answer, b: &Answer) -> Class {
        let h = if a.occluded { a.hit } else { b.hit };
        match h {
            Some(h) => self.single(ray, &h),
            None => Class::Unexplained,
        }
    }
}

/// Compares `candidate` with `reference` on the rays of one recorded set.
pub fn compare_kind(
    scene: &Scene,
    reference: &dyn RayQuery,
    candidate: &dyn RayQuery,
    set: &RaySet,
    show: usize,
) -> KindReport {
    let rays = &set.rays;
    let a = answer_all(reference, rays);
    let b = answer_all(candidate, rays);
    let lights = scene.emitters();
    let c = Classifier {
        scene,
        radius: lights.scene_sphere().1,
    };
    let mut r = KindReport {
        kind: Some(set.kind),
        query: Some(set.query),
        rays: rays.len(),
        cast: set.seen,
        ..Default::default()
    };
    let (mut t_abs, mut t_rel) = (Vec::new(), Vec::new());
    for ((ray, x), y) in rays.iter().zip(&a).zip(&b) {
        r.hits[0] += x.hit.is_some() as usize;
        r.hits[1] += y.hit.is_some() as usize;
        let mut class = None;
        match (&x.hit, &y.hit) {
            (Some(p), Some(q)) if (p.mesh, p.prim) == (q.mesh, q.prim) => {
                r.same_triangle += 1;
                t_abs.push((p.t as f64 - q.t as f64).abs());
                t_rel.push(rel_diff(p.t, q.t));
            }
            (None, None) => {}
            (p, q) => {
                if p.is_some() && q.is_some() {
                    r.other_triangle += 1;
                } else {
                    r.hit_miss += 1;
                }
                class = Some(c.closest(ray, p, q));
            }
        }
        if x.occluded != y.occluded {
            r.occlusion += 1;
            class = class.or(Some(c.occlusion(ray, x, y)));
        }
        if let Some(class) = class {
            r.disagreeing += 1;
            let i = Class::ALL.iter().position(|&k| k == class).unwrap_or(5);
            r.classes[i] += 1;
            if class == Class::Unexplained && r.examples.len() < show {
                r.examples.push(format!(
                    "{ray:?}\n      reference {:?} occluded {}\n      candidate {:?} occluded {}",
                    x.hit, x.occluded, y.hit, y.occluded
                ));
            }
        }
    }
    r.t_abs = Spread::of(&mut t_abs);
    r.t_rel = Spread::of(&mut t_rel);
    r
}

/// Compares the backends on every recorded set of `rays`.
pub fn compare_rays(
    scene: &Scene,
    reference: &dyn RayQuery,
    candidate: &dyn RayQuery,
    rays: &RecordedRays,
    show: usize,
) -> Vec<KindReport> {
    rays.sets
        .iter()
        .map(|set| compare_kind(scene, reference, candidate, set, show))
        .collect()
}

/// The thresholds `reports` and the image relMSE (if rendered) exceed, one line each; empty
/// when everything passes.
pub fn failures(reports: &[KindReport], relmse: Option<f64>, th: &Thresholds) -> Vec<String> {
    let mut out = Vec::new();
    for r in reports.iter().filter(|r| r.rays > 0) {
        let kind = r.kind.map_or("?", |k| k.name());
        let n = r.rays as f64;
        if r.unexplained() as f64 > th.max_unexplained * n {
            out.push(format!(
                "{kind}: {} unexplained disagreements > {} x {} rays",
                r.unexplained(),
                th.max_unexplained,
                r.rays
            ));
        }
        if r.disagreeing as f64 > th.max_disagree * n {
            out.push(format!(
                "{kind}: {} disagreeing rays > {} x {} rays",
                r.disagreeing, th.max_disagree, r.rays
            ));
        }
        if r.t_rel.p999 > th.max_t_rel {
            out.push(format!(
                "{kind}: 99.9th percentile of relative |dt| {:.3e} > {:.1e}",
                r.t_rel.p999, th.max_t_rel
            ));
        }
    }
    if let Some(m) = relmse.filter(|&m| m.is_nan() || m > th.max_relmse) {
        out.push(format!(
            "image relMSE {m:.3e} > {:.1e} (or not finite)",
            th.max_relmse
        ));
    }
    out
}

/// The report as a text table.
pub fn table(reports: &[KindReport]) -> String {
    let mut s = String::new();
    let _ =
        writeln!(
        s,
        "{:<7} {:<8} {:>9} {:>7} {:>15} {:>8} {:>9} {:>6} {:>9} {:>9} {:>9} {:>9}  classes of disagreeing rays",
        "kind", "query", "cast", "rays", "hits ref/cand", "hit/miss", "other-tri", "occl", "|dt| max", "|dt| p999",
        "rel max", "rel p999"
    );
    for r in reports {
        let classes: Vec<String> = Class::ALL
            .iter()
            .zip(r.classes)
            .filter(|(_, n)| *n > 0)
            .map(|(c, n)| format!("{} {n}", c.name()))
            .collect();
        let _ = writeln!(
            s,
            "{:<7} {:<8} {:>9} {:>7} {:>15} {:>8} {:>9} {:>6} {:>9.2e} {:>9.2e} {:>9.2e} {:>9.2e}  {}",
            r.kind.map_or("?", |k| k.name()),
            r.query.map_or("?", |q| q.name()),
            r.cast,
            r.rays,
            format!("{}/{}", r.hits[0], r.hits[1]),
            r.hit_miss,
            r.other_triangle,
            r.occlusion,
            r.t_abs.max,
            r.t_abs.p999,
            r.t_rel.max,
            r.t_rel.p999,
            if classes.is_empty() {
                "-".to_string()
            } else {
                classes.join(", ")
            }
        );
    }
    s
}

/// The report as one line of JSON (non-finite numbers as `null`).
pub fn to_json(reports: &[KindReport], relmse: Option<f64>, failures: &[String]) -> String {
    let kinds: Vec<serde_json::Value> = reports
        .iter()
        .map(|r| {
            let classes: serde_json::Map<String, serde_json::Value> = Class::ALL
                .iter()
                .zip(r.classes)
                .map(|(c, n)| (c.name().to_string(), n.into()))
                .collect();
            serde_json::json!({
                "kind": r.kind.map_or("?", |k| k.name()),
                "query": r.query.map_or("?", |q| q.name()),
                "cast": r.cast,
                "rays": r.rays,
                "hits": [r.hits[0], r.hits[1]],
                "hit_miss": r.hit_miss,
                "other_triangle": r.other_triangle,
                "occlusion": r.occlusion,
                "same_triangle": r.same_triangle,
                "t_abs_max": r.t_abs.max,
                "t_abs_p999": r.t_abs.p999,
                "t_rel_max": r.t_rel.max,
                "t_rel_p999": r.t_rel.p999,
                "disagreeing": r.disagreeing,
                "classes": classes,
            })
        })
        .collect();
    serde_json::json!({
        "kinds": kinds,
        "image_relmse": relmse,
        "pass": failures.is_empty(),
        "failures": failures,
    })
    .to_string()
}

/// The comparison renders' resolution: `--image-res`, else the Film's scaled to at most 128
/// pixels on the longer side.
fn image_resolution(opts: &CrosscheckOptions, scene: &Scene) -> (u32, u32) {
    if let Some(r) = opts.image_res {
        return r;
    }
    let (w, h) = (scene.film.xres.max(1), scene.film.yres.max(1));
    let f = (128.0 / w.max(h) as f64).min(1.0);
    (
        ((w as f64 * f).round() as u32).max(1),
        ((h as f64 * f).round() as u32).max(1),
    )
}

/// Renders with both backends under the same seed; returns (relMSE, seconds per backend).
fn compare_images(
    scene: &Scene,
    accels: [&Accel; 2],
    settings: &RenderSettings,
    pool: &rayon::ThreadPool,
) -> Result<(f64, [f64; 2]), ToolError> {
    let mut images = Vec::new();
    let mut secs = [0.0; 2];
    for (i, accel) in accels.iter().enumerate() {
        let out = pool.install(|| {
            integrator::render(
                scene,
                accel,
                settings,
                IntegratorKind::Photonmap,
                &|_, _| {},
            )
        });
        secs[i] = out.seconds;
        images.push(out.image);
    }
    let m = metrics::compare(&images[1], &images[0], MaskOptions::default()).map_err(ToolError)?;
    Ok((m.overall.relmse, secs))
}

/// What was recorded: the render's size and, per kind, rays kept of rays cast.
pub fn describe_recording(r: &recorded::Recorded) -> String {
    let s = &r.settings;
    let kinds: Vec<String> = r
        .rays
        .sets
        .iter()
        .map(|k| format!("{} {} of {}", k.kind, k.rays.len(), k.seen))
        .collect();
    format!(
        "recorded render: photon mapper {}x{}, {} spp, {} + {} photons; rays kept of cast: {}",
        s.width,
        s.height,
        s.spp,
        s.photon.trace.global_photons,
        s.photon.trace.caustic_photons,
        kinds.join(", ")
    )
}

/// Runs the cross-check; `Ok(false)` when a threshold is exceeded.
pub fn run(opts: &CrosscheckOptions) -> Result<bool, ToolError> {
    let overrides = Overrides {
        seed: opts.seed,
        ..Default::default()
    };
    let mut job = Job::load(&opts.scene, None)?.with(&overrides);
    job.threads = opts.threads;
    let pool = job.pool()?;
    let (embree, embree_s) = job.build_on(BackendKind::Embree, &pool)?;
    let (obvhs, obvhs_s) = job.build_on(BackendKind::Obvhs, &pool)?;
    let build_s = embree_s + obvhs_s;
    let (scene, settings) = (&job.scene, &job.settings);
    let (embree, recorded) = pool
        .install(|| recorded::record(scene, embree, settings, opts.rays, opts.seed))
        .map_err(ToolError)?;
    let t = Instant::now();
    let reports = pool.install(|| {
        compare_rays(
            scene,
            embree.backend(),
            obvhs.backend(),
            &recorded.rays,
            opts.show,
        )
    });
    let compare_s = t.elapsed().as_secs_f64();
    let image = if opts.no_render {
        None
    } else {
        let mut s = settings.clone();
        (s.width, s.height) = image_resolution(opts, scene);
        s.spp = opts.image_spp.max(1);
        s.seed = opts.seed;
        Some((
            s.width,
            s.height,
            compare_images(scene, [&embree, &obvhs], &s, &pool)?,
        ))
    };
    let relmse = image.as_ref().map(|(_, _, (m, _))| *m);
    let th = Thresholds {
        max_unexplained: opts.max_unexplained,
        max_disagree: opts.max_disagree,
        max_t_rel: opts.max_t_rel,
        max_relmse: opts.max_relmse,
    };
    let fails = failures(&reports, relmse, &th);
    if opts.json {
        say!("{}", to_json(&reports, relmse, &fails));
        return Ok(fails.is_empty());
    }
    say!(
        "crosscheck {}: {} triangles; reference embree, candidate obvhs; seed {}; \
         builds {:.2} s, recording {:.2} s, comparing {:.2} s",
        opts.scene.display(),
        scene.triangle_count(),
        opts.seed,
        build_s,
        recorded.seconds,
        compare_s
    );
    say!("{}", describe_recording(&recorded));
    say_part!("{}", table(&reports));
    for r in &reports {
        for e in &r.examples {
            say!("  unexplained {}: {e}", r.kind.map_or("?", |k| k.name()));
        }
    }
    if let Some((w, h, (m, secs))) = image {
        say!(
            "image: {w}x{h}, {} spp, photon mapper, seed {}: relMSE(obvhs vs embree) {m:.3e} \
             (renders {:.2} s / {:.2} s)",
            opts.image_spp.max(1),
            opts.seed,
            secs[0],
            secs[1]
        );
    }
    say!(
        "thresholds: unexplained <= {} and disagreeing <= {} of each kind's rays, rel |dt| \
         p99.9 <= {}, image relMSE <= {}",
        th.max_unexplained,
        th.max_disagree,
        th.max_t_rel,
        th.max_relmse
    );
    if fails.is_empty() {
        say!("PASS");
    } else {
        for f in &fails {
            say!("FAIL: {f}");
        }
    }
    Ok(fails.is_empty())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::Vec3;

    #[test]
    fn spread_percentile() {
        let mut v: Vec<f64> = (1..=2000).map(|i| i as f64).collect();
        let s = Spread::of(&mut v);
        assert_eq!(s.max, 2000.0);
        assert_eq!(s.p999, 1998.0);
        assert_eq!(Spread::of(&mut []), Spread::default());
    }

    #[test]
    fn edge_distance_classification() {
        let mesh = crate::scene::Mesh {
            positions: vec![
                Vec3::ZERO,
                Vec3::new(2.0, 0.0, 0.0),
                Vec3::new(0.0, 2.0, 0.0),
            ],
            indices: vec![[0, 1, 2]],
            ..Default::default()
        };
        let scene = crate::scene::generate::sphere_scene(10);
        let mut scene = scene;
        scene.meshes = vec![mesh];
        let c = Classifier {
            scene: &scene,
            radius: 1.0,
        };
        let ray = Ray::new(Vec3::new(0.5, 0.5, 1.0), -Vec3::Z);
        let hit = |u: f32, v: f32| Hit {
            t: 1.0,
            mesh: 0,
            prim: 0,
            u,
            v,
            ng: Vec3::Z,
        };
        // Height of the edge opposite vertex 1 (along y) is 2: u = 4e-6 is 8e-6 away.
        assert_eq!(c.edges_near(&ray, &hit(4e-6, 0.3)), 1);
        assert_eq!(c.edges_near(&ray, &hit(6e-6, 0.3)), 0);
        assert_eq!(c.edges_near(&ray, &hit(1e-6, 1e-6)), 2);
        assert_eq!(c.single(&ray, &hit(0.3, 0.3)), Class::Unexplained);
        let mut seg = ray;
        seg.tmax = 1.0;
        assert_eq!(c.single(&seg, &hit(0.3, 0.3)), Class::IntervalEnd);
    }
}
