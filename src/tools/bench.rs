//! `photon bench` (and `cargo bench`): Embree against obvhs, and the photon map against a
//! reference kd-tree.
//!
//! Per scene (the shared scenes, `scenes/*.pbrt`, generated bumpy spheres of 100k and 1M
//! triangles, or those named with `--scene` / `--generated`):
//! - **accel**: build time per backend; rays/s on the rays a real render casts, recorded
//!   through a wrapper around Embree (a small photon-mapper render of the scene, see
//!   [`crate::integrator::recorded`]; whole batches of up to 256 rays are kept, as coherent as
//!   the render casts them): camera rays (closest hit), incoherent photon-path rays (closest
//!   hit; the render's "secondary" count is camera-path bounces and gathers instead) and shadow
//!   rays (occlusion), for Embree's single-ray calls (`x1`),
//!   its 8-wide packet calls (`x8`) and obvhs, on 1 and 2 threads;
//! - **photon**: global photons traced per second per backend and thread count; kd-tree build
//!   time and k-nearest queries per second (k = 50, 200; unbounded radius, one thread) at the
//!   diffuse points the recorded camera rays hit, ours against a [`KnnBaseline`] over the
//!   same points and queries; radiance (irradiance) estimates per second with the scene's
//!   lookup settings.
//!
//! Every number is the median of `--runs` timed runs. Output: a table on stdout; `--csv` and
//! `--json` write every row. `--quick` runs a reduced set in about a minute.
//!
//! The baseline kd-tree is `kiddo`, a dev-dependency: `cargo bench` (the `benches/photon.rs`
//! target) passes it in; `photon bench` itself has no baseline and leaves those columns
//! empty, so the shipped binary does not depend on kiddo.
use super::job::{thread_pool, Job};
use super::ToolError;
use crate::accel::bvh::BvhAccel;
use crate::accel::embree::{Device, EmbreeAccel};
use crate::accel::recording::Query;
use crate::accel::{Accel, AccelOptions, BackendKind, RayKind};
use crate::integrator::recorded::{self, DiffusePoint, Recorded};
use crate::integrator::RenderSettings;
use crate::math::{Ray, Vec3};
use crate::photon::estimate::{irradiance_with, EstimateParams};
use crate::photon::trace::{self, TraceSettings};
use crate::photon::{KdTree, KnnResult};
use crate::scene::generate::{short_count, sphere_scene};
use crate::scene::Scene;
use rayon::prelude::*;
use std::fmt::Write as _;
use std::hint::black_box;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// The shared scenes, relative to the repository root.
pub const SHARED_SCENES: [&str; 3] = [
    "../shared/scenes/cornell-box/scene-v4.pbrt",
    "../shared/scenes/veach-mis/scene-v4.pbrt",
    "../shared/scenes/cornell-spheres/scene.pbrt",
];

/// Options of `photon bench`.
#[derive(clap::Args, Clone, Debug, Default)]
pub struct BenchOptions {
    /// Reduced set in about a minute: fewer rays, photons, queries and runs; no 1M mesh.
    #[arg(long)]
    pub quick: bool,
    /// Scene files to run (repeatable). Default: the shared scenes and scenes/*.pbrt.
    #[arg(long = "scene")]
    pub scenes: Vec<PathBuf>,
    /// Generated bumpy spheres, in triangles (comma-separated). Default: 100000,1000000
    /// (--quick: 100000); 0 for none.
    #[arg(long, value_delimiter = ',')]
    pub generated: Option<Vec<usize>>,
    /// Rays of each kind (default 400000; --quick 250000).
    #[arg(long)]
    pub rays: Option<usize>,
    /// Timed runs per number; the median is reported (default 5; --quick 3).
    #[arg(long)]
    pub runs: Option<usize>,
    /// Global photons per tracing run (default 200000; --quick 100000).
    #[arg(long)]
    pub photons: Option<u64>,
    /// k-nearest queries and radiance estimates per run (default 100000; --quick 40000).
    #[arg(long)]
    pub queries: Option<usize>,
    /// Thread counts for the ray and photon-tracing rates (comma-separated).
    #[arg(long, value_delimiter = ',', default_value = "1,2")]
    pub threads: Vec<usize>,
    /// Write every row as CSV here.
    #[arg(long)]
    pub csv: Option<PathBuf>,
    /// Write every row as JSON here.
    #[arg(long)]
    pub json: Option<PathBuf>,
}

/// The sizes a run uses, after `--quick` and the defaults.
#[derive(Clone, Debug, PartialEq)]
pub struct Plan {
    pub scenes: Vec<PathBuf>,
    pub generated: Vec<usize>,
    pub rays: usize,
    pub runs: usize,
    pub photons: u64,
    pub queries: usize,
    pub threads: Vec<usize>,
}

impl BenchOptions {
    /// The sizes to run with. Default scenes that do not exist are left out.
    pub fn plan(&self) -> Plan {
        let q = self.quick;
        let scenes = if self.scenes.is_empty() {
            default_scenes()
        } else {
            self.scenes.clone()
        };
        let generated = self
            .generated
            .clone()
            .unwrap_or_else(|| {
                if q {
                    vec![100_000]
                } else {
                    vec![100_000, 1_000_000]
                }
            })
            .into_iter()
            .filter(|&n| n > 0)
            .collect();
        let threads = if self.threads.is_empty() {
            vec![1, 2]
        } else {
            self.threads.iter().map(|&t| t.max(1)).collect()
        };
        Plan {
            scenes,
            generated,
            rays: self
                .rays
                .unwrap_or(if q { 250_000 } else { 400_000 })
                .max(1),
            runs: self.runs.unwrap_or(if q { 3 } else { 5 }).max(1),
            photons: self
                .photons
                .unwrap_or(if q { 100_000 } else { 200_000 })
                .max(1),
            queries: self
                .queries
                .unwrap_or(if q { 40_000 } else { 100_000 })
                .max(1),
            threads,
        }
    }
}

/// The shared scenes that exist, then `scenes/*.pbrt` sorted by name.
pub fn default_scenes() -> Vec<PathBuf> {
    let mut out: Vec<PathBuf> = SHARED_SCENES
        .iter()
        .map(PathBuf::from)
        .filter(|p| p.is_file())
        .collect();
    if let Ok(dir) = std::fs::read_dir("scenes") {
        let mut own: Vec<PathBuf> = dir
            .filter_map(|e| e.ok().map(|e| e.path()))
            .filter(|p| p.extension().is_some_and(|e| e == "pbrt"))
            .collect();
        own.sort();
        out.extend(own);
    }
    out
}

/// A k-nearest-neighbour structure to compare the photon kd-tree with.
pub trait KnnBaseline: Send {
    /// Its name in the output (e.g. `kiddo`).
    fn name(&self) -> &str;
    /// Builds over `points`, replacing what was built before.
    fn build(&mut self, points: &[Vec3]);
    /// Squared distance of the `k`-th nearest point to `q` (unbounded radius), or +inf with
    /// fewer than `k` points.
    fn kth_d2(&self, q: Vec3, k: usize) -> f32;
}

/// One measured number.
#[derive(Clone, Debug, PartialEq)]
pub struct Row {
    /// Scene name (file stem's folder or generated name).
    pub scene: String,
    pub triangles: usize,
    /// `build`, `camera`, `photon paths`, `shadow`, `photons`, `kd build`, `knn k=50`,
    /// `knn k=200`, `estimate`.
    pub metric: String,
    /// `embree x1`, `embree x8`, `embree`, `obvhs`, `ours` or the baseline's name.
    pub imp: String,
    pub threads: usize,
    /// Median over the runs.
    pub median: f64,
    pub min: f64,
    pub max: f64,
    /// `ms` or `1/s` (rays, photons or queries per second).
    pub unit: &'static str,
    pub runs: usize,
}

/// Median, min and max of `v` (not empty).
fn stats(v: &mut [f64]) -> (f64, f64, f64) {
    v.sort_by(f64::total_cmp);
    let n = v.len();
    let med = if n % 2 == 1 {
        v[n / 2]
    } else {
        0.5 * (v[n / 2 - 1] + v[n / 2])
    };
    (med, v[0], v[n - 1])
}

/// Collects rows for one scene.
struct Recorder<'a> {
    scene: String,
    triangles: usize,
    runs: usize,
    rows: &'a mut Vec<Row>,
}

impl Recorder<'_> {
    /// Runs `f` `runs` times; each call returns the measured value.
    fn measure(
        &mut self,
        metric: &str,
        imp: &str,
        threads: usize,
        unit: &'static str,
        mut f: impl FnMut() -> f64,
    ) -> f64 {
        let mut v: Vec<f64> = (0..self.runs).map(|_| f()).collect();
        let (median, min, max) = stats(&mut v);
        self.rows.push(Row {
            scene: self.scene.clone(),
            triangles: self.triangles,
            metric: metric.into(),
            imp: imp.into(),
            threads,
            median,
            min,
            max,
            unit,
            runs: self.runs,
        });
        median
    }
}

/// Rays per parallel work item in the ray-rate runs.
const CHUNK: usize = 1024;

/// How rays are handed to a backend.
#[derive(Clone, Copy, PartialEq, Eq)]
enum Call {
    Single,
    Packet,
}

/// Rays per second of `accel` on `rays` (of `kind`) on the current pool: closest hits or
/// occlusion.
fn ray_rate(accel: &Accel, kind: RayKind, rays: &[Ray], query: Query, call: Call) -> f64 {
    let t = Instant::now();
    rays.par_chunks(CHUNK).for_each(|c| {
        if query == Query::Closest {
            let mut out = vec![None; c.len()];
            match call {
                Call::Packet => accel.intersect_batch(kind, c, &mut out),
                Call::Single => c
                    .iter()
                    .zip(out.iter_mut())
                    .for_each(|(r, o)| *o = accel.intersect(kind, r)),
            }
            black_box(out);
        } else {
            let mut out = vec![false; c.len()];
            match call {
                Call::Packet => accel.occluded_batch(kind, c, &mut out),
                Call::Single => c
                    .iter()
                    .zip(out.iter_mut())
                    .for_each(|(r, o)| *o = accel.occluded(kind, r)),
            }
            black_box(out);
        }
    });
    rays.len() as f64 / t.elapsed().as_secs_f64().max(1e-9)
}

/// The scene's name in the output: the folder of the shared scenes (their files are all
/// called `scene*.pbrt`), else the file stem.
pub fn scene_name(path: &Path) -> String {
    let stem = path
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default();
    if stem.starts_with("scene") {
        if let Some(dir) = path.parent().and_then(|d| d.file_name()) {
            return dir.to_string_lossy().into_owned();
        }
    }
    stem
}

/// Benchmarks one scene, appending rows.
fn bench_scene(
    name: String,
    job: &Job,
    plan: &Plan,
    baseline: &mut Option<&mut dyn KnnBaseline>,
    rows: &mut Vec<Row>,
) -> Result<(), ToolError> {
    let (scene, settings) = (&job.scene, &job.settings);
    let mut rec = Recorder {
        scene: name,
        triangles: scene.triangle_count(),
        runs: plan.runs,
        rows,
    };
    let pools: Vec<(usize, rayon::ThreadPool)> = plan
        .threads
        .iter()
        .map(|&t| thread_pool(t).map(|p| (t, p)))
        .collect::<Result<_, _>>()?;
    let [embree, obvhs] = bench_builds(&mut rec, scene, &pools)?;
    let (embree, rays) = pools[0]
        .1
        .install(|| recorded::record(scene, embree, settings, plan.rays, 0))
        .map_err(ToolError)?;
    let accels = [embree, obvhs];
    bench_rays(&mut rec, &accels, &rays, &pools);
    bench_photons(
        &mut rec, scene, settings, &accels, &rays, plan, &pools, baseline,
    )
}

/// Build time of both backends per thread count (Embree on a device limited to that many
/// threads, obvhs in a rayon pool of that size); returns the last build of each backend.
fn bench_builds(
    rec: &mut Recorder,
    scene: &Scene,
    pools: &[(usize, rayon::ThreadPool)],
) -> Result<[Accel; 2], ToolError> {
    let (mut embree, mut obvhs) = (None, None);
    for (threads, pool) in pools {
        let device = Device::new(&format!("threads={threads}"))?;
        rec.measure("build", "embree", *threads, "ms", || {
            let t = Instant::now();
            embree = EmbreeAccel::build_on(&device, scene, AccelOptions::default()).ok();
            t.elapsed().as_secs_f64() * 1e3
        });
        rec.measure("build", "obvhs", *threads, "ms", || {
            let t = Instant::now();
            obvhs = pool
                .install(|| BvhAccel::build(scene, AccelOptions::default()))
                .ok();
            t.elapsed().as_secs_f64() * 1e3
        });
    }
    let fail = |kind| ToolError(format!("{kind} build failed"));
    Ok([
        Accel::Embree(embree.ok_or_else(|| fail("embree"))?),
        Accel::Obvhs(obvhs.ok_or_else(|| fail("obvhs"))?),
    ])
}

/// Ray rates: camera, photon paths, shadow; Embree x1/x8 and obvhs; per pool.
fn bench_rays(
    rec: &mut Recorder,
    accels: &[Accel],
    rec_rays: &Recorded,
    pools: &[(usize, rayon::ThreadPool)],
) {
    let sets = [
        ("camera", RayKind::Camera, Query::Closest),
        ("photon paths", RayKind::Photon, Query::Closest),
        ("shadow", RayKind::Shadow, Query::Occlusion),
    ];
    for (metric, kind, query) in sets {
        let set = rec_rays.rays.get(kind, query);
        if set.is_empty() {
            continue;
        }
        for (threads, pool) in pools {
            for accel in accels {
                let calls: &[(Call, &str)] = match accel.kind() {
                    BackendKind::Embree => {
                        &[(Call::Single, "embree x1"), (Call::Packet, "embree x8")]
                    }
                    BackendKind::Obvhs => &[(Call::Single, "obvhs")],
                };
                for &(call, imp) in calls {
                    pool.install(|| ray_rate(accel, kind, set, query, call)); // warm-up
                    rec.measure(metric, imp, *threads, "1/s", || {
                        pool.install(|| ray_rate(accel, kind, set, query, call))
                    });
                }
            }
        }
    }
}

/// Photon tracing per backend and pool; kd-tree, k-nearest and estimates on one thread.
#[allow(clippy::too_many_arguments)]
fn bench_photons(
    rec: &mut Recorder,
    scene: &Scene,
    settings: &RenderSettings,
    accels: &[Accel],
    rays: &Recorded,
    plan: &Plan,
    pools: &[(usize, rayon::ThreadPool)],
    baseline: &mut Option<&mut dyn KnnBaseline>,
) -> Result<(), ToolError> {
    let lights = scene.emitters();
    let ts = TraceSettings {
        global_photons: plan.photons,
        caustic_photons: 0,
        projection_maps: false,
        seed: 0,
        ..settings.photon.trace.clone()
    };
    let mut map = None;
    for (threads, pool) in pools {
        for accel in accels {
            rec.measure(
                "photons",
                &accel.kind().to_string(),
                *threads,
                "1/s",
                || {
                    let maps = pool.install(|| trace::trace(scene, accel, &lights, &ts));
                    let rate =
                        maps.stats.global_emitted as f64 / maps.stats.trace_seconds.max(1e-9);
                    map = maps.global;
                    rate
                },
            );
        }
    }
    let Some(map) = map else {
        return Ok(()); // no photon stored: nothing to look up
    };
    let points: Vec<Vec3> = map.photons().iter().map(|p| p.pos()).collect();
    let queries = query_points(&rays.diffuse_points, plan.queries);
    if queries.is_empty() {
        return Ok(());
    }
    let one = thread_pool(1)?;
    one.install(|| bench_kd(rec, &points, &queries, baseline))?;
    let (_, radius) = lights.scene_sphere();
    let mut params = EstimateParams::new(
        settings.photon.global_lookup.max(1),
        (settings.photon.global_radius * radius).powi(2),
    );
    params.kernel = settings.photon.kernel;
    one.install(|| {
        let mut buf = KnnResult::new();
        rec.measure("estimate", "ours", 1, "1/s", || {
            let t = Instant::now();
            let mut sum = Vec3::ZERO;
            for q in &queries {
                sum += irradiance_with(&map, q.p, q.n, &params, &mut buf).0;
            }
            black_box(sum);
            queries.len() as f64 / t.elapsed().as_secs_f64().max(1e-9)
        });
    });
    Ok(())
}

/// `n` query points cycling through the diffuse points the camera saw.
fn query_points(points: &[DiffusePoint], n: usize) -> Vec<DiffusePoint> {
    if points.is_empty() {
        return Vec::new();
    }
    (0..n).map(|i| points[i % points.len()]).collect()
}

/// kd-tree build and k-nearest rates, ours and the baseline's, with a check that both find
/// the same k-th distances.
fn bench_kd(
    rec: &mut Recorder,
    points: &[Vec3],
    queries: &[DiffusePoint],
    baseline: &mut Option<&mut dyn KnnBaseline>,
) -> Result<(), ToolError> {
    let mut tree = None;
    rec.measure("kd build", "ours", 1, "ms", || {
        let t = Instant::now();
        tree = KdTree::build(points).ok().map(|(t, _)| t);
        t.elapsed().as_secs_f64() * 1e3
    });
    let tree = tree.ok_or_else(|| ToolError("kd-tree build failed".into()))?;
    if let Some(b) = baseline.as_deref_mut() {
        let name = b.name().to_string();
        rec.measure("kd build", &name, 1, "ms", || {
            let t = Instant::now();
            b.build(points);
            t.elapsed().as_secs_f64() * 1e3
        });
    }
    for k in [50usize, 200] {
        let metric = format!("knn k={k}");
        let mut out = KnnResult::with_capacity(k);
        let mut ours = Vec::new();
        rec.measure(&metric, "ours", 1, "1/s", || {
            let t = Instant::now();
            ours.clear();
            for q in queries {
                tree.knn(q.p, k, f32::INFINITY, &mut out);
                ours.push(out.r2());
            }
            queries.len() as f64 / t.elapsed().as_secs_f64().max(1e-9)
        });
        let Some(b) = baseline.as_deref() else {
            continue;
        };
        let mut theirs = Vec::new();
        rec.measure(&metric, b.name(), 1, "1/s", || {
            let t = Instant::now();
            theirs.clear();
            theirs.extend(queries.iter().map(|q| b.kth_d2(q.p, k)));
            queries.len() as f64 / t.elapsed().as_secs_f64().max(1e-9)
        });
        check_same_knn(&ours, &theirs, k, b.name())?;
    }
    Ok(())
}

/// Both trees must find the same k-th distance for every query (to 1e-5 relative).
fn check_same_knn(ours: &[f32], theirs: &[f32], k: usize, name: &str) -> Result<(), ToolError> {
    let bad = ours
        .iter()
        .zip(theirs)
        .filter(|(a, b)| !(a == b || (*a - *b).abs() <= 1e-5 * a.abs().max(b.abs())))
        .count();
    if bad > 0 || ours.len() != theirs.len() {
        return Err(ToolError(format!(
            "kd-tree and {name} disagree on the k-th distance (k = {k}) for {bad} of {} queries",
            ours.len()
        )));
    }
    Ok(())
}

/// How a benchmarked scene is obtained: loaded from a file or generated.
type SceneSource = Box<dyn Fn() -> Result<Job<'static>, ToolError>>;

/// Runs the benchmark without a kd-tree baseline (the `photon bench` subcommand).
pub fn run(opts: &BenchOptions) -> Result<(), ToolError> {
    run_with(opts, None).map(|_| ())
}

/// Runs the benchmark: prints the machine, then one table per scene as it finishes, writes
/// the CSV/JSON files; returns every row.
pub fn run_with(
    opts: &BenchOptions,
    mut baseline: Option<&mut dyn KnnBaseline>,
) -> Result<Vec<Row>, ToolError> {
    // --csv and --json are planned before the work and written as render's outputs are
    // (`super::output`: a FIFO or device is written into, never replaced).
    let files: Vec<(&str, &std::path::Path)> = [("--csv", &opts.csv), ("--json", &opts.json)]
        .into_iter()
        .filter_map(|(flag, p)| p.as_deref().map(|p| (flag, p)))
        .collect();
    let outputs = super::output::Outputs::plan_files(&files).map_err(ToolError)?;
    let plan = opts.plan();
    say!("{}", machine());
    say!(
        "plan: {} rays per kind, {} runs (median), {} photons, {} queries, threads {:?}{}",
        plan.rays,
        plan.runs,
        plan.photons,
        plan.queries,
        plan.threads,
        if opts.quick { " (--quick)" } else { "" }
    );
    let mut rows = Vec::new();
    let mut jobs: Vec<(String, SceneSource)> = Vec::new();
    for p in &plan.scenes {
        let p = p.clone();
        jobs.push((scene_name(&p), Box::new(move || Job::load(&p, None))));
    }
    for &n in &plan.generated {
        jobs.push((
            format!("sphere-{}", short_count(n)),
            Box::new(move || Job::new(sphere_scene(n))),
        ));
    }
    for (name, load) in jobs {
        let job = load()?;
        let start = rows.len();
        let t = Instant::now();
        bench_scene(name, &job, &plan, &mut baseline, &mut rows)?;
        say_part!("{}", table(&rows[start..]));
        say!("({:.1} s)\n", t.elapsed().as_secs_f64());
    }
    let texts: Vec<String> = (outputs.files.iter())
        .map(|f| match f.flag.as_str() {
            "--csv" => to_csv(&rows),
            _ => to_json(&rows),
        })
        .collect();
    let writers: Vec<super::output::Writer> = (texts.iter())
        .map(|t| -> super::output::Writer {
            Box::new(move |tmp: &std::path::Path| std::fs::write(tmp, t).map_err(|e| e.to_string()))
        })
        .collect();
    outputs.commit(writers)?;
    Ok(rows)
}

/// CPU model and logical CPU count (from /proc/cpuinfo where there is one).
pub fn machine() -> String {
    let cpu = std::fs::read_to_string("/proc/cpuinfo")
        .ok()
        .and_then(|s| {
            s.lines()
                .find(|l| l.starts_with("model name"))
                .and_then(|l| l.split_once(':'))
                .map(|(_, v)| v.trim().to_string())
        })
        .unwrap_or_else(|| "unknown CPU".into());
    let n = std::thread::available_parallelism().map_or(0, |n| n.get());
    format!("machine: {cpu}, {n} logical CPUs")
}

fn find<'a>(rows: &'a [Row], metric: &str, imp: &str, threads: usize) -> Option<&'a Row> {
    rows.iter()
        .find(|r| r.metric == metric && r.imp == imp && r.threads == threads)
}

/// Formats a rate in millions or a time in ms, blank when absent.
fn cell(r: Option<&Row>) -> String {
    match r {
        Some(r) if r.unit == "ms" => format!("{:.2}", r.median),
        Some(r) => format!("{:.2}", r.median / 1e6),
        None => "-".into(),
    }
}

/// Speed ratio a / b (time ratio b / a for times), blank when either is absent.
fn ratio(a: Option<&Row>, b: Option<&Row>) -> String {
    match (a, b) {
        (Some(a), Some(b)) if a.unit == "ms" => format!("{:.2}", b.median / a.median),
        (Some(a), Some(b)) => format!("{:.2}", a.median / b.median),
        _ => "-".into(),
    }
}

/// The rows of one scene as a Markdown table: ray rates in M/s and build times in ms, with
/// speed ratios (> 1: Embree, or ours, is faster).
pub fn table(rows: &[Row]) -> String {
    let mut s = String::new();
    let Some(first) = rows.first() else {
        return s;
    };
    let _ = writeln!(s, "### {} ({} triangles)\n", first.scene, first.triangles);
    let _ = writeln!(
        s,
        "| measure | threads | Embree x1 | Embree x8 | obvhs | x1/obvhs | x8/obvhs |\n|---|---|---|---|---|---|---|"
    );
    let mut threads: Vec<usize> = rows.iter().map(|r| r.threads).collect();
    threads.sort_unstable();
    threads.dedup();
    for &t in &threads {
        let (e, o) = (
            find(rows, "build", "embree", t),
            find(rows, "build", "obvhs", t),
        );
        if let Some(r) = e {
            let _ = writeln!(
                s,
                "| build (ms) | {} | {} | | {} | {} | |",
                r.threads,
                cell(Some(r)),
                cell(o),
                ratio(Some(r), o)
            );
        }
    }
    for m in ["camera", "photon paths", "shadow"] {
        for &t in &threads {
            let (x1, x8, o) = (
                find(rows, m, "embree x1", t),
                find(rows, m, "embree x8", t),
                find(rows, m, "obvhs", t),
            );
            if x1.is_none() && o.is_none() {
                continue;
            }
            let _ = writeln!(
                s,
                "| {m} (Mrays/s) | {t} | {} | {} | {} | {} | {} |",
                cell(x1),
                cell(x8),
                cell(o),
                ratio(x1, o),
                ratio(x8, o)
            );
        }
    }
    for &t in &threads {
        let (e, o) = (
            find(rows, "photons", "embree", t),
            find(rows, "photons", "obvhs", t),
        );
        if e.is_some() || o.is_some() {
            let _ = writeln!(
                s,
                "| photons traced (M/s) | {t} | {} | | {} | {} | |",
                cell(e),
                cell(o),
                ratio(e, o)
            );
        }
    }
    let base = rows
        .iter()
        .find(|r| r.metric == "kd build" && r.imp != "ours")
        .map(|r| r.imp.clone());
    if rows.iter().any(|r| r.metric == "kd build") {
        let b = base.clone().unwrap_or_else(|| "baseline".into());
        let _ = writeln!(
            s,
            "\n| photon map | ours | {b} | ours/{b} |\n|---|---|---|---|"
        );
        for (m, label) in [
            ("kd build", "kd-tree build (ms)"),
            ("knn k=50", "k=50 queries (M/s)"),
            ("knn k=200", "k=200 queries (M/s)"),
            ("estimate", "radiance estimates (M/s)"),
        ] {
            let ours = find(rows, m, "ours", 1);
            let theirs = base.as_deref().and_then(|b| find(rows, m, b, 1));
            let _ = writeln!(
                s,
                "| {label} | {} | {} | {} |",
                cell(ours),
                cell(theirs),
                ratio(ours, theirs)
            );
        }
    }
    s
}

/// Every row as CSV (header first).
pub fn to_csv(rows: &[Row]) -> String {
    let mut s =
        String::from("scene,triangles,metric,implementation,threads,median,min,max,unit,runs\n");
    for r in rows {
        let _ = writeln!(
            s,
            "{},{},{},{},{},{},{},{},{},{}",
            r.scene,
            r.triangles,
            r.metric,
            r.imp,
            r.threads,
            r.median,
            r.min,
            r.max,
            r.unit,
            r.runs
        );
    }
    s
}

/// Every row as a JSON array of objects, one per line (non-finite numbers as `null`).
pub fn to_json(rows: &[Row]) -> String {
    let items: Vec<String> = rows
        .iter()
        .map(|r| {
            serde_json::json!({
                "scene": r.scene,
                "triangles": r.triangles,
                "metric": r.metric,
                "implementation": r.imp,
                "threads": r.threads,
                "median": r.median,
                "min": r.min,
                "max": r.max,
                "unit": r.unit,
                "runs": r.runs,
            })
            .to_string()
        })
        .collect();
    format!("[\n{}\n]\n", items.join(",\n"))
}
