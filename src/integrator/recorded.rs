//! A small real render whose ray queries are recorded: the rays `photon crosscheck` compares,
//! `photon bench` times and `photon render --stats` measures its raw ray rate on.
//!
//! [`record`] renders the scene with the photon mapper (the integrator that casts every kind of
//! ray: photon paths, camera rays, shadow rays, final-gather rays and specular bounces) through
//! a recording wrapper around the backend ([`crate::accel::recording`]) and hands back the backend
//! with the sampled rays. Nothing rebuilds a ray by hand: whatever the integrators cast is what
//! is recorded. The render uses the scene's settings (as `RenderSettings::from_scene` reads
//! them from the file) made small enough for the sample ([`settings`]):
//!
//! - samples per pixel are lowered (never raised) until the image casts about `2 n` camera
//!   rays for a sample of `n`, and when one sample per pixel is still more than that, the
//!   resolution is scaled down (aspect kept);
//! - the photon counts are scaled down together until at most `2 n` photons are emitted.
//!
//! The diffuse points where photon-map lookups happen ([`DiffusePoint`]) are the diffuse hits
//! of the recorded camera rays.
use super::{IntegratorKind, RenderSettings};
use crate::accel::recording::RecordedRays;
use crate::accel::{Accel, RayKind};
use crate::math::{Ray, Vec3};
use crate::memory::{self, Estimate};
use crate::scene::Scene;
use std::time::Instant;

/// Camera rays and photons the reduced render casts, per ray of the sample wanted.
pub const OVERSAMPLE: u64 = 2;

/// A diffuse point seen by a camera ray: where photon-map lookups happen.
#[derive(Clone, Copy, Debug)]
pub struct DiffusePoint {
    pub p: Vec3,
    /// Unit shading normal turned towards the viewer.
    pub n: Vec3,
}

/// What [`record`] returns besides the backend.
#[derive(Clone, Debug)]
pub struct Recorded {
    pub rays: RecordedRays,
    /// The diffuse hits of the recorded camera rays.
    pub diffuse_points: Vec<DiffusePoint>,
    /// The settings of the recorded render.
    pub settings: RenderSettings,
    /// Wall time of the recorded render.
    pub seconds: f64,
}

/// The settings of a render that casts about `OVERSAMPLE * n` camera rays and emits at most
/// that many photons (see the module docs).
pub fn settings(base: &RenderSettings, n: usize) -> RenderSettings {
    let want = (n as u64).saturating_mul(OVERSAMPLE).max(1);
    let mut s = base.clone();
    let pixels = (base.width as u64 * base.height as u64).max(1);
    s.spp = (want.div_ceil(pixels).min(base.spp.max(1) as u64)) as u32;
    if pixels > want {
        let f = (want as f64 / pixels as f64).sqrt();
        s.width = ((base.width as f64 * f).round() as u32).max(1);
        s.height = ((base.height as f64 * f).round() as u32).max(1);
    }
    let t = &mut s.photon.trace;
    let total = t.global_photons.saturating_add(t.caustic_photons);
    if total > want {
        let f = want as f64 / total as f64;
        t.global_photons = (t.global_photons as f64 * f).floor() as u64;
        t.caustic_photons = (t.caustic_photons as f64 * f).floor() as u64;
    }
    s
}

/// The memory the recorded render `s` needs, recording `n` rays per kind and query.
pub fn estimate(
    scene: &Scene,
    s: &RenderSettings,
    backend: &Accel,
    threads: usize,
    n: usize,
) -> Estimate {
    let kinds = (IntegratorKind::Photonmap, backend.kind());
    let landings = super::pilot(scene, backend, s, IntegratorKind::Photonmap);
    let mut e = memory::estimate(scene, s, kinds, threads, landings);
    e.parts.push(("recorded rays", memory::recording_bytes(n)));
    e.what += &format!(", {n} recorded rays per kind");
    e
}

/// Renders `scene` with the photon mapper at [`settings`]`(base, n)` through a recording of
/// `backend` that keeps up to `n` rays per kind and query, chosen with `seed` (the render's
/// own sample streams use `base.seed`). Runs on the current rayon pool. Fails, before any
/// work, when the estimated memory exceeds the default budget.
pub fn record(
    scene: &Scene,
    backend: Accel,
    base: &RenderSettings,
    n: usize,
    seed: u64,
) -> Result<(Accel, Recorded), String> {
    let s = settings(base, n);
    let e = estimate(scene, &s, &backend, rayon::current_num_threads(), n);
    memory::check(&e, &crate::limits::default_budget())?;
    let t = Instant::now();
    let recording = Accel::recording(backend, n, seed);
    super::render(scene, &recording, &s, IntegratorKind::Photonmap, &|_, _| {});
    let seconds = t.elapsed().as_secs_f64();
    let (backend, rays) = recording.finish_recording();
    let camera = rays.get(RayKind::Camera, crate::accel::recording::Query::Closest);
    let diffuse_points = diffuse_points(scene, &backend, camera);
    Ok((
        backend,
        Recorded {
            rays,
            diffuse_points,
            settings: s,
            seconds,
        },
    ))
}

/// The diffuse surfaces camera rays `rays` hit: points and normals facing the camera.
pub fn diffuse_points(scene: &Scene, accel: &Accel, rays: &[Ray]) -> Vec<DiffusePoint> {
    let mut hits = vec![None; rays.len()];
    accel.intersect_batch(RayKind::Camera, rays, &mut hits);
    rays.iter()
        .zip(&hits)
        .filter_map(|(ray, hit)| {
            let mut si = crate::interaction::SurfaceInteraction::new(scene, hit.as_ref()?, ray);
            si.bsdf(
                scene,
                crate::camera::Footprint::of_file(scene),
                crate::spectrum::Lambda::Rgb,
            )
            .flags()
            .has_diffuse()
            .then(|| DiffusePoint {
                p: si.p,
                n: si.facing_normal(),
            })
        })
        .collect()
}
