//! The memory model of a render, checked against the budget ([`crate::limits::default_budget`]
//! or `--max-memory`) before anything large is allocated, and printed by `photon check`.
//!
//! The model ([`estimate`]) adds up the film (every image the render and the writers keep per
//! pixel), the photon maps (the measured peak per stored photon while tracing and building the
//! kd-trees, times an upper estimate of the photons stored), the per-thread gather, shadow and
//! k-nearest buffers (bounded: they are flushed in batches of [`crate::limits::BATCH`]) and the
//! acceleration structure over the loaded triangles. [`check`] turns an estimate above the
//! budget into one line: `--res: needs ~125 GB (film 125 GB) for 32768x32768 ..., over the
//! limit of 20.2 GB (80% of physical 25.3 GB; --max-memory)`. A render prints its estimate and
//! its peak resident memory (VmHWM) at the end, which `tests/it/hostile.rs` compares; the
//! constants' measurements are in BENCHMARKS.md ("Memory model").
use crate::accel::BackendKind;
use crate::integrator::{IntegratorKind, RenderSettings};
use crate::limits::{human, peak_resident, Budget};
use crate::photon::trace::Landings;
use crate::scene::Scene;

/// Bytes per pixel: the combined image and four component images (12 bytes each) and the
/// tiles' per-pixel `Radiance` (48) before assembly; the writers work by scanline; and 8 of
/// slack for the spread of the peak between runs. Measured (peak RSS, `--integrator direct`,
/// EXR + PNG): 1024x1024 114 MiB, 2048x2048 434 MiB, so 107 bytes per pixel; 2048x2048 again
/// (2026-12-07, 2 threads, five runs): 434-473 MB, the top one 2.2 MB above the 108-byte
/// model's estimate.
pub const FILM_BYTES_PER_PIXEL: u64 = 12 * 5 + 48 + 8;
/// Peak bytes per stored photon while tracing, building the kd-trees and the irradiance cache:
/// the `Landing` (32) in its chunk and in the concatenated copy, the photon records (20), the
/// tree's keys and nodes and the normals in tree order. Measured (peak RSS on cornell-box,
/// 1.48M and 5.94M stored photons: 152 and 579 MiB): 100.5 bytes; the 20-byte record alone
/// would say a fifth of that.
pub const PHOTON_PEAK_BYTES: u64 = 104;
/// Peak bytes per triangle for the loaded mesh plus building the acceleration structure.
/// Measured (peak RSS, 50 and 150 tessellated spheres of 16,128 triangles): Embree 157,
/// obvhs 406.
pub fn triangle_bytes(backend: BackendKind) -> u64 {
    match backend {
        BackendKind::Embree => 160,
        BackendKind::Obvhs => 410,
    }
}
/// Bytes the ray-query backend's alpha masks copy from meshes with `alpha` and uvs (see
/// `accel::AlphaMask`): their indices (12 per triangle) and uvs (8 per vertex). Exact sizes,
/// not measured; 0 without alpha.
pub fn alpha_mask_bytes(scene: &Scene) -> u64 {
    scene
        .meshes
        .iter()
        .filter(|m| m.alpha.is_some())
        .filter_map(|m| Some(m.indices.len() * 12 + m.uvs.as_ref()?.len() * 8))
        .fold(0u64, |a, b| a.saturating_add(b as u64))
}
/// Per worker thread: gather and shadow batches, path states, k-nearest buffers, the stack
/// pages touched. Measured (peak RSS, 1 and 8 threads, 320x180): 0.1 MB per thread on
/// cornell-box, 1.8 MB on kitchen.
pub const THREAD_BYTES: u64 = 2 << 20;
/// The process before any scene: the executable, Embree, OpenEXR and the C and Rust runtimes.
/// Measured (peak RSS of a one-triangle 16x16 render, any integrator): 12.4-13.0 MB.
pub const PROCESS_BYTES: u64 = 13 << 20;
/// Bytes per pixel of a live preview (`--display-server`, [`crate::tools::display`]): its
/// frame of 15 floats per pixel, plus the mean image and layers a render in passes makes for
/// it after each pass (15 floats per pixel, dropped before the next); the pieces it sends are
/// 1 MB at most.
pub const PREVIEW_BYTES_PER_PIXEL: u64 = 2 * 60;
/// The factor on the photons stored per photon emitted that a pilot trace measured
/// ([`crate::photon::trace::pilot`]): its sampling error and the roulette's spread.
pub const PILOT_MARGIN: f64 = 1.25;
/// Bytes per recorded ray, at most (`accel::recording`): the 32-byte ray, and when every chunk
/// holds a single ray (photon paths) its 32-byte heap entry and its allocation's rounding and
/// header (32).
pub const RECORDED_RAY_BYTES: u64 = 96;

/// Memory of a recording that keeps up to `per_kind` rays per (kind, query): every pair may
/// hold `per_kind` rays plus the one chunk being inserted.
pub fn recording_bytes(per_kind: usize) -> u64 {
    use crate::accel::{recording, RayKind};
    let pairs = (RayKind::ALL.len() * recording::Query::ALL.len()) as u64;
    let rays = (per_kind as u64).saturating_add(recording::CHUNK as u64);
    pairs
        .saturating_mul(rays)
        .saturating_mul(RECORDED_RAY_BYTES)
}

/// Bytes of one pixel's [`crate::film::Radiance`] (four RGB components).
const RADIANCE_BYTES: u64 = std::mem::size_of::<crate::film::Radiance>() as u64;

/// The parts of an estimate, in bytes.
#[derive(Clone, Debug, Default)]
pub struct Estimate {
    pub parts: Vec<(&'static str, u64)>,
    /// What the estimate is for, for the message (`512x512, 400000 photons`).
    pub what: String,
    /// The loader's own peak ([`Scene::load_peak`]: a decode's transient buffers), which
    /// the process reached before any part was allocated: the total is at least this.
    pub load_peak: u64,
}

impl Estimate {
    /// The parts summed, or the loader's peak when that is larger.
    pub fn total(&self) -> u64 {
        self.parts
            .iter()
            .fold(0u64, |a, (_, b)| a.saturating_add(*b))
            .max(self.load_peak)
    }
}

/// The memory a render of `scene` with `settings` and `kind` on `threads` threads needs.
/// `landings`: the photons stored per photon emitted that a pilot trace measured
/// ([`crate::integrator::pilot`]); `None` leaves the photon maps out (a render checks again
/// with them after its pilot, before pass 1).
pub fn estimate(
    scene: &Scene,
    settings: &RenderSettings,
    (kind, backend): (IntegratorKind, BackendKind),
    threads: usize,
    landings: Option<Landings>,
) -> Estimate {
    let pixels = settings.width as u64 * settings.height as u64;
    let mut e = Estimate {
        parts: vec![
            ("process", PROCESS_BYTES),
            ("film", pixels.saturating_mul(FILM_BYTES_PER_PIXEL)),
        ],
        what: format!("{}x{}", settings.width, settings.height),
        load_peak: scene.load_peak,
    };
    let data = settings.aovs.bytes_per_pixel();
    if data > 0 {
        // Exact sizes (the pass's sums, the channels, the variances), not measured.
        e.parts.push(("data channels", pixels.saturating_mul(data)));
    }
    if let (IntegratorKind::Photonmap, Some(_)) = (kind, &scene.media_need_tracking) {
        // Media that need tracking: the volume map (its photons and at most its grid) and
        // the caustic photons through the media (at most one per photon emitted for them).
        let n = settings.photon.volume_photons;
        let c = settings.photon.trace.caustic_photons;
        let bytes = n
            .saturating_mul(crate::photon::volume::VOLUME_PHOTON_BYTES)
            .saturating_add(crate::photon::volume::MAX_GRID_BYTES)
            .saturating_add(c.saturating_mul(PHOTON_PEAK_BYTES));
        e.parts.push(("photon maps", bytes));
        e.what += &format!(
            ", {n} volume photons x {} B + at most {c} caustic x {PHOTON_PEAK_BYTES} B",
            crate::photon::volume::VOLUME_PHOTON_BYTES
        );
    } else if let (IntegratorKind::Photonmap, Some(per)) = (kind, landings) {
        let t = &settings.photon.trace;
        // Only the maps the scene needs are built (as pass 1 decides: no global map without
        // a diffuse surface, no caustic map without a specular one and a receiver).
        let (global, caustic, _) =
            crate::integrator::photonmap::needed_maps(scene, t.receiver_alpha);
        let global = if global { t.global_photons } else { 0 };
        let caustic = if caustic { t.caustic_photons } else { 0 };
        // The caustic map is built after the global one and kept with it.
        let stored = global as f64 * per.global + caustic as f64 * per.caustic;
        let bytes = stored * PILOT_MARGIN * PHOTON_PEAK_BYTES as f64;
        e.parts
            .push(("photon maps", bytes.min(u64::MAX as f64) as u64));
        let per = PILOT_MARGIN * stored / (global as f64 + caustic as f64).max(1.0);
        e.what +=
            &format!(", {global} + {caustic} photons x{per:.2} stored x {PHOTON_PEAK_BYTES} B");
    }
    if let (Some(_), Some(per)) = (kind.technique(), landings) {
        // One light subpath per pixel of the crop window, each keeping the vertices a pilot
        // trace measured (with the photon maps' margin; plus the hash grid's 8-byte id and
        // 4-byte key and a splat of 32 bytes per vertex), and the iteration's film and sum.
        let (w, h) = settings.image_size();
        let paths = w as u64 * h as u64;
        let vertices = paths as f64 * per.subpath * PILOT_MARGIN;
        let bytes = vertices * (crate::integrator::vcm::LIGHT_VERTEX_BYTES + 12 + 32) as f64;
        e.parts.push((
            "light vertices",
            (bytes.min(u64::MAX as f64) as u64)
                .saturating_add(paths.saturating_mul(4 + 2 * RADIANCE_BYTES)),
        ));
        e.what += &format!(
            ", {paths} pixels x{:.2} light vertices x {} B",
            per.subpath * PILOT_MARGIN,
            crate::integrator::vcm::LIGHT_VERTEX_BYTES
        );
    }
    let tris = scene.triangle_count() as u64;
    let meshes = scene.meshes.len() as u64;
    e.parts.push((
        "geometry",
        tris.saturating_mul(triangle_bytes(backend))
            .saturating_add(meshes.saturating_mul(crate::scene::MESH_OVERHEAD_BYTES)),
    ));
    // Already decoded by the loader (each image checked against MAX_IMAGE_PIXELS first).
    e.parts.push(("textures", scene.textures.decoded_bytes()));
    // Environment maps: texels and sampling tables, shared (Arc) by every render's lights.
    e.parts.push(("environment maps", scene.light_map_bytes()));
    e.parts.push(("alpha masks", alpha_mask_bytes(scene)));
    e.parts.push((
        "threads",
        (threads.max(1) as u64).saturating_mul(THREAD_BYTES),
    ));
    e
}

/// Ok when `e` fits `budget`, else the one-line message.
pub fn check(e: &Estimate, budget: &Budget) -> Result<(), String> {
    let total = e.total();
    if total <= budget.bytes {
        return Ok(());
    }
    // The parts that matter (a tenth of the total or more), to keep the line short.
    let parts: Vec<String> = e
        .parts
        .iter()
        .filter(|(_, b)| *b > 0 && *b >= total / 10)
        .map(|(n, b)| format!("{n} {}", human(*b)))
        .collect();
    let source = match budget.source.as_str() {
        "--max-memory" => budget.source.clone(),
        other => format!("{other}; --max-memory"),
    };
    Err(format!(
        "needs ~{} ({}) for {}, over the limit of {} ({source})",
        human(total),
        parts.join(", "),
        e.what,
        human(budget.bytes),
    ))
}

/// Which sizes the command line gave (the rest came from the scene file), to say where the
/// largest part of an estimate comes from.
#[derive(Clone, Copy, Debug, Default)]
pub struct FromCli {
    pub res: bool,
    pub photons: bool,
}

/// Where the largest part of `e` was set: a flag, the photon-count parameter's
/// `file:line:col`, or the scene file.
fn blame(e: &Estimate, scene: &Scene, cli: FromCli) -> String {
    let largest = e
        .parts
        .iter()
        .max_by_key(|(_, b)| *b)
        .map_or("", |(n, _)| *n);
    let params = &scene.integrator.params;
    let photon_loc = params
        .loc("globalphotons")
        .or_else(|| params.loc("causticphotons"));
    match (largest, photon_loc) {
        ("film", _) if cli.res => "--res".to_string(),
        ("photon maps", _) if cli.photons => "--global-photons/--caustic-photons".to_string(),
        ("photon maps", Some(loc)) => loc.to_string(),
        _ => scene.path.display().to_string(),
    }
}

/// Checks a render against `budget` ([`Budget::resolve`], once before anything large is
/// allocated: what an address-space limit leaves shrinks as the render maps memory) before it
/// starts; `threads` 0 means all cores; `preview` adds a live preview's frame. The message
/// starts with where the largest part was set.
pub fn check_render(
    scene: &Scene,
    settings: &RenderSettings,
    (kind, backend): (IntegratorKind, BackendKind),
    threads: usize,
    landings: Option<Landings>,
    (budget, cli): (&Budget, FromCli),
    preview: bool,
) -> Result<Estimate, String> {
    let threads = match threads {
        0 => std::thread::available_parallelism().map_or(1, |n| n.get()),
        n => n,
    };
    let mut e = estimate(scene, settings, (kind, backend), threads, landings);
    if preview {
        let pixels = settings.width as u64 * settings.height as u64;
        let bytes = pixels.saturating_mul(PREVIEW_BYTES_PER_PIXEL);
        e.parts.push(("live preview", bytes));
    }
    check(&e, budget).map_err(|m| format!("{}: {m}", blame(&e, scene, cli)))?;
    Ok(e)
}

/// The estimate in one short phrase: `~12.3 MB (film 0.0, photon maps 8.1, ...)`, megabytes.
pub fn summary(e: &Estimate) -> String {
    let mb = |b: u64| b as f64 / 1e6;
    let parts: Vec<String> = e
        .parts
        .iter()
        .filter(|(_, b)| *b > 0)
        .map(|(n, b)| format!("{n} {:.1}", mb(*b)))
        .collect();
    format!("~{:.1} MB ({})", mb(e.total()), parts.join(", "))
}

/// The line a render prints at the end: its estimate and its measured peak.
pub fn report(e: &Estimate) -> String {
    let peak = peak_resident().unwrap_or(0);
    format!(
        "memory: estimated {} bytes (~{}), peak resident {} bytes (~{})",
        e.total(),
        human(e.total()),
        peak,
        human(peak)
    )
}
