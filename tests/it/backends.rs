//! Cross-checks the two ray-query backends (Embree 3 and obvhs CWBVH) against each other, the
//! packet paths against the single-ray paths, and both against hand-computed hits.
//! Also prints build times and ray rates (information only; nothing asserts on speed).
//!
//! Run with `cargo test --release --test it backends:: -- --nocapture --test-threads=1` to see the
//! numbers undisturbed.
use crate::support as common;

use common::Rng;
use photon::accel::bvh::BvhAccel;
use photon::accel::embree::{Device, EmbreeAccel, Geometry, SceneBuilder, SceneConfig};
use photon::accel::{AccelOptions, Hit, RayQuery};
use photon::math::{Ray, Vec3};
use photon::scene::generate::bumpy_sphere;
use photon::scene::{FilmDesc, Mesh, Scene};
use std::path::Path;
use std::time::Instant;

/// A scene holding `meshes`, everything else simple.
fn scene_of(meshes: Vec<Mesh>) -> Scene {
    Scene {
        film: FilmDesc::new(16, 16),
        ..Scene::with_geometry(
            meshes,
            vec![photon::scene::Material::from(
                photon::scene::MaterialKind::Diffuse(photon::material::DiffuseMaterial {
                    reflectance: Vec3::splat(0.5).into(),
                }),
            )],
            Vec::new(),
        )
    }
}

fn mesh_of(positions: Vec<Vec3>, indices: Vec<[u32; 3]>) -> Mesh {
    Mesh {
        positions,
        indices,
        ..Default::default()
    }
}

/// Random rays around `scene`'s bounds: origins in the bounds grown by 20 % per side; half the
/// directions towards a random point of the bounds, half uniform; one ray in five is a segment with a random finite `tmax`, one in ten starts at
/// a random `tmin > 0`.
fn random_rays(scene: &Scene, n: usize, seed: u64) -> Vec<Ray> {
    let (lo, hi) = scene.bounds();
    let (scene_lo, ext) = (lo, hi - lo);
    let (lo, hi) = (lo - 0.2 * ext, hi + 0.2 * ext);
    let diag = ext.length();
    let mut rng = Rng(seed);
    (0..n)
        .map(|k| {
            let o = Vec3::new(
                rng.range(lo.x, hi.x),
                rng.range(lo.y, hi.y),
                rng.range(lo.z, hi.z),
            );
            // Half the rays aim at a random point of the bounds, the others go anywhere.
            // Directions have varied lengths: t is in units of d.
            let dir = if k % 2 == 0 {
                let target = scene_lo + ext * Vec3::new(rng.f(), rng.f(), rng.f());
                (target - o).normalize_or(Vec3::X)
            } else {
                rng.dir()
            };
            let mut ray = Ray::new(o, dir * rng.range(0.5, 2.0));
            if k % 5 == 1 {
                ray.tmax = rng.range(0.0, 0.7 * diag);
            }
            if k % 10 == 3 {
                ray.tmin = rng.range(0.0, 0.3 * diag);
            }
            ray
        })
        .collect()
}

fn rel_close(a: f32, b: f32, rel: f32) -> bool {
    (a - b).abs() <= rel * a.abs().max(b.abs()).max(1e-30)
}

/// How two closest hits for one ray compare.
#[derive(Debug, PartialEq)]
enum Agreement {
    Same,
    /// One hit, one miss.
    HitVsMiss,
    /// Different triangles at the same distance: coplanar overlap or a shared edge/vertex.
    Tie,
    /// Different distances.
    TDiffers,
}

fn classify(a: &Option<Hit>, b: &Option<Hit>) -> Agreement {
    match (a, b) {
        (None, None) => Agreement::Same,
        (Some(_), None) | (None, Some(_)) => Agreement::HitVsMiss,
        (Some(x), Some(y)) => {
            let t_ok = rel_close(x.t, y.t, 1e-4);
            match (t_ok, (x.mesh, x.prim) == (y.mesh, y.prim)) {
                (true, true) => Agreement::Same,
                (true, false) => Agreement::Tie,
                (false, _) => Agreement::TDiffers,
            }
        }
    }
}

/// Times `f` over `n` rays and returns Mrays/s.
fn mrays(n: usize, f: impl FnOnce()) -> f64 {
    let start = Instant::now();
    f();
    n as f64 / start.elapsed().as_secs_f64() / 1e6
}

/// Builds both backends over `scene`, prints their build times (Embree's device creation
/// apart, and its robust mode too), and returns them.
fn build_both(name: &str, scene: &Scene) -> (EmbreeAccel, BvhAccel) {
    photon::accel::cpu::enable_flush_denormals();
    let ms = |t: Instant| t.elapsed().as_secs_f64() * 1e3;
    let t0 = Instant::now();
    let dev = Device::new("").expect("embree device");
    let t_dev = ms(t0);
    let t0 = Instant::now();
    let e = EmbreeAccel::build_on(&dev, scene, AccelOptions::default()).expect("embree build");
    let t_e = ms(t0);
    let t0 = Instant::now();
    drop(EmbreeAccel::build_on(&dev, scene, AccelOptions { robust: true }).expect("robust"));
    let t_robust = ms(t0);
    let t0 = Instant::now();
    let b = BvhAccel::build(scene, AccelOptions::default()).expect("obvhs build");
    let t_b = ms(t0);
    println!(
        "[{name}] {} triangles: embree device {t_dev:.1} ms, scene {t_e:.1} ms (robust \
         {t_robust:.1} ms); obvhs {t_b:.1} ms",
        scene.triangle_count(),
    );
    (e, b)
}

/// Packet answers must equal single-ray answers bit for bit, except that on an exact tie
/// between two triangles (coplanar overlap, shared edge) Embree's packet and single-ray
/// kernels may pick different ones: those are printed and must really be ties (same `t` to
/// 1e-6 relative).
fn check_packets(name: &str, rays: &[Ray], packet: &[Option<Hit>], single: &[Option<Hit>]) {
    let mut ties = 0;
    for (i, (p, s)) in packet.iter().zip(single).enumerate() {
        if p == s {
            continue;
        }
        let tie = match (p, s) {
            (Some(p), Some(s)) => (p.mesh, p.prim) != (s.mesh, s.prim) && rel_close(p.t, s.t, 1e-6),
            _ => false,
        };
        println!(
            "[{name}] ray {i} packet vs single, tie {tie}: {p:?}\n    single {s:?}\n    {:?}",
            rays[i]
        );
        assert!(
            tie,
            "[{name}] ray {i}: packet and single-ray answers differ"
        );
        ties += 1;
    }
    println!(
        "[{name}] packets equal single rays except {ties} tie-breaks between coplanar triangles"
    );
}

/// Runs `rays` through both backends (single and batch), prints rates, classifies closest-hit
/// and occlusion disagreements, prints every non-`Same` case, and asserts that real
/// disagreements (not ties) stay at or below 0.01 % of rays.
fn cross_check(name: &str, scene: &Scene, rays: &[Ray]) {
    let (e, b) = build_both(name, scene);
    let n = rays.len();
    let mut he = vec![None; n];
    let mut hb = vec![None; n];
    let mut oe = vec![false; n];
    let mut ob = vec![false; n];
    let mut batch = vec![None; n];
    let mut obatch = vec![false; n];
    let r_e = mrays(n, || {
        he.iter_mut()
            .zip(rays)
            .for_each(|(h, r)| *h = e.intersect(r))
    });
    let r_b = mrays(n, || {
        hb.iter_mut()
            .zip(rays)
            .for_each(|(h, r)| *h = b.intersect(r))
    });
    let o_e = mrays(n, || {
        oe.iter_mut()
            .zip(rays)
            .for_each(|(o, r)| *o = e.occluded(r))
    });
    let o_b = mrays(n, || {
        ob.iter_mut()
            .zip(rays)
            .for_each(|(o, r)| *o = b.occluded(r))
    });
    let p_e = mrays(n, || e.intersect_batch(rays, &mut batch));
    let q_e = mrays(n, || e.occluded_batch(rays, &mut obatch));
    println!(
        "[{name}] Mrays/s, 1 thread, random rays: closest embree x1 {r_e:.2}, x8 {p_e:.2}, \
         obvhs {r_b:.2}; occlusion embree x1 {o_e:.2}, x8 {q_e:.2}, obvhs {o_b:.2}"
    );
    check_packets(name, rays, &batch, &he);
    assert_eq!(obatch, oe, "[{name}] embree occlusion packets differ");

    let hits = he.iter().filter(|h| h.is_some()).count();
    let (mut ties, mut fails, mut max_uv) = (0, 0, 0.0f32);
    for (i, (x, y)) in he.iter().zip(&hb).enumerate() {
        match classify(x, y) {
            Agreement::Same => {
                if let (Some(x), Some(y)) = (x, y) {
                    max_uv = max_uv.max((x.u - y.u).abs()).max((x.v - y.v).abs());
                    assert_eq!(x.ng, y.ng, "[{name}] ray {i}: normals differ");
                }
            }
            kind => {
                println!(
                    "[{name}] ray {i} {kind:?}: {:?}\n    embree {x:?}\n    obvhs  {y:?}",
                    rays[i]
                );
                if kind == Agreement::Tie {
                    ties += 1;
                } else {
                    fails += 1;
                }
            }
        }
    }
    let occ_fails = oe.iter().zip(&ob).filter(|(a, b)| a != b).count();
    for (i, _) in oe.iter().zip(&ob).enumerate().filter(|(_, (a, b))| a != b) {
        println!(
            "[{name}] ray {i} occlusion differs: embree {} obvhs {}: {:?}",
            oe[i], ob[i], rays[i]
        );
    }
    // Each backend's occlusion must agree with its own closest hit, too.
    let self_e = oe
        .iter()
        .zip(&he)
        .filter(|(o, h)| **o != h.is_some())
        .count();
    let self_b = ob
        .iter()
        .zip(&hb)
        .filter(|(o, h)| **o != h.is_some())
        .count();
    println!(
        "[{name}] {n} rays, {hits} hits: {fails} closest-hit disagreements, {ties} ties, \
         {occ_fails} occlusion disagreements; occluded != hit: embree {self_e}, obvhs {self_b}; \
         max |du|,|dv| on agreeing hits {max_uv:.2e}"
    );
    let budget = n / 10_000; // 0.01 %
    assert!(
        hits > n / 10,
        "[{name}] too few hits ({hits}) for a meaningful test"
    );
    assert!(fails <= budget, "[{name}] {fails} disagreements > {budget}");
    assert!(
        occ_fails <= budget,
        "[{name}] {occ_fails} occlusion disagreements"
    );
    assert!(
        self_e <= budget && self_b <= budget,
        "[{name}] occlusion vs closest hit"
    );
    assert!(max_uv < 1e-3, "[{name}] barycentrics differ by {max_uv}");
}

#[test]
fn generated_mesh_backends_agree() {
    let scene = scene_of(vec![bumpy_sphere(256, 256)]);
    assert!(scene.triangle_count() >= 100_000);
    let rays = random_rays(&scene, 100_000, 1);
    cross_check("bumpy sphere", &scene, &rays);
}

#[test]
fn cornell_box_backends_agree() {
    let path = Path::new("../shared/scenes/cornell-box/scene-v4.pbrt");
    let scene = photon::scene::loader::load(path).expect("load the Cornell box");
    assert!(scene.meshes.len() > 1, "the Cornell box has several meshes");
    let rays = random_rays(&scene, 100_000, 2);
    cross_check("cornell box", &scene, &rays);
}

/// Rays of every kind, including ones no backend may query (empty interval, NaN, zero
/// direction), in a count that leaves a partial last packet.
fn awkward_rays(scene: &Scene, n: usize) -> Vec<Ray> {
    let mut rays = random_rays(scene, n, 7);
    for (k, r) in rays.iter_mut().enumerate().step_by(13) {
        match k % 4 {
            0 => (r.tmin, r.tmax) = (2.0, 1.0),
            1 => r.d = Vec3::ZERO,
            2 => r.o.x = f32::NAN,
            _ => r.tmax = 0.0,
        }
    }
    rays
}

#[test]
fn packets_equal_single_rays() {
    let scene = scene_of(vec![bumpy_sphere(64, 64)]);
    let (e, b) = build_both("packets", &scene);
    for n in [0, 1, 5, 8, 13, 8 * 125 + 3] {
        let rays = awkward_rays(&scene, n);
        for accel in [&e as &dyn RayQuery, &b] {
            let single: Vec<Option<Hit>> = rays.iter().map(|r| accel.intersect(r)).collect();
            let mut batch = vec![None; n];
            accel.intersect_batch(&rays, &mut batch);
            // No coplanar triangles here: no tie-breaks, answers must be identical.
            assert_eq!(single, batch, "{n} rays");
            assert!(n < 100 || single.iter().filter(|h| h.is_some()).count() > n / 10);
            let single: Vec<bool> = rays.iter().map(|r| accel.occluded(r)).collect();
            let mut batch = vec![true; n];
            accel.occluded_batch(&rays, &mut batch);
            assert_eq!(single, batch, "{n} rays, occlusion");
        }
    }
}

/// Three meshes: a far-away triangle, an empty mesh, and two target triangles (an axis-aligned
/// one at z = 5 and a tilted one far along x).
fn hand_scene() -> Scene {
    let far = mesh_of(
        vec![
            Vec3::new(100.0, 100.0, 100.0),
            Vec3::new(101.0, 100.0, 100.0),
            Vec3::new(100.0, 101.0, 100.0),
        ],
        vec![[0, 1, 2]],
    );
    let target = mesh_of(
        vec![
            Vec3::new(1.0, 0.0, 5.0),
            Vec3::new(3.0, 0.0, 5.0),
            Vec3::new(1.0, 4.0, 5.0),
            Vec3::new(20.0, 0.0, 0.0),
            Vec3::new(21.0, 0.0, 1.0),
            Vec3::new(20.0, 1.0, 1.0),
        ],
        vec![[0, 1, 2], [3, 4, 5]],
    );
    scene_of(vec![far, Mesh::default(), target])
}

#[track_caller]
fn assert_hit(h: Option<Hit>, prim: u32, t: f32, u: f32, v: f32, ng: Vec3, what: &str) {
    let Some(h) = h else {
        panic!("{what}: expected a hit");
    };
    assert_eq!((h.mesh, h.prim), (2, prim), "{what}");
    assert!((h.t - t).abs() < 2e-5 * t, "{what}: t {} vs {t}", h.t);
    assert!(
        (h.u - u).abs() < 1e-5 && (h.v - v).abs() < 1e-5,
        "{what}: {h:?}"
    );
    assert!((h.ng - ng).length() < 1e-6, "{what}: ng {} vs {ng}", h.ng);
}

#[test]
fn hand_checked_rays() {
    let scene = hand_scene();
    let robust = AccelOptions { robust: true };
    let backends: Vec<(&str, Box<dyn RayQuery>)> = vec![
        (
            "embree",
            Box::new(EmbreeAccel::build(&scene, AccelOptions::default()).unwrap()),
        ),
        (
            "embree robust",
            Box::new(EmbreeAccel::build(&scene, robust).unwrap()),
        ),
        (
            "obvhs",
            Box::new(BvhAccel::build(&scene, AccelOptions::default()).unwrap()),
        ),
    ];
    for (name, a) in &backends {
        // Straight down +z at (1.5, 1): p = p0 + u (2,0,0) + v (0,4,0) gives u = v = 0.25;
        // z goes 0 -> 5 at speed 2: t = 2.5.
        let o = Vec3::new(1.5, 1.0, 0.0);
        let d = Vec3::new(0.0, 0.0, 2.0);
        let z = Vec3::Z;
        assert_hit(a.intersect(&Ray::new(o, d)), 0, 2.5, 0.25, 0.25, z, name);
        assert!(a.occluded(&Ray::new(o, d)), "{name}");
        // From the back side: same triangle, normal not flipped.
        let ob = Vec3::new(1.5, 1.0, 9.0);
        assert_hit(a.intersect(&Ray::new(ob, -d)), 0, 2.0, 0.25, 0.25, z, name);
        // Pointing away.
        assert_eq!(a.intersect(&Ray::new(o, -d)), None, "{name}");
        assert!(!a.occluded(&Ray::new(o, -d)), "{name}");
        // tmax short of the hit, then just past it.
        assert_eq!(a.intersect(&Ray::segment(o, d, 2.49)), None, "{name}");
        assert!(!a.occluded(&Ray::segment(o, d, 2.49)), "{name}");
        assert!(a.occluded(&Ray::segment(o, d, 2.51)), "{name}");
        // tmin past the hit, then just before it.
        let mut r = Ray::new(o, d);
        r.tmin = 2.51;
        assert_eq!(a.intersect(&r), None, "{name}");
        assert!(!a.occluded(&r), "{name}");
        r.tmin = 2.49;
        assert_hit(a.intersect(&r), 0, 2.5, 0.25, 0.25, z, name);
        // A hit very close to the origin (obvhs's node test alone would cull it).
        let oz = 5.0f32 - 2e-5;
        let near = Ray::new(Vec3::new(1.5, 1.0, oz), Vec3::Z);
        assert_hit(a.intersect(&near), 0, 5.0 - oz, 0.25, 0.25, z, name);
        assert!(a.occluded(&near), "{name}");
        // Beside the triangle (u + v > 1).
        let beside = Ray::new(Vec3::new(2.5, 2.5, 0.0), d);
        assert_eq!(a.intersect(&beside), None, "{name}");

        // Tilted triangle p0 = (20,0,0), edges (1,0,1) and (0,1,1): ng = (-1,-1,1)/sqrt(3).
        // Aim at u = 0.2, v = 0.3: p = (20.2, 0.3, 0.5); come from t = 1.7 back along d.
        let p = Vec3::new(20.2, 0.3, 0.5);
        let d = Vec3::new(0.3, -0.2, 1.0);
        let ng = Vec3::new(-1.0, -1.0, 1.0) / 3f32.sqrt();
        assert_hit(
            a.intersect(&Ray::new(p - 1.7 * d, d)),
            1,
            1.7,
            0.2,
            0.3,
            ng,
            name,
        );
    }
}

#[test]
fn zero_area_triangles_never_hit() {
    let p = Vec3::new(0.0, 0.0, 0.0);
    let q = Vec3::new(1.0, 1.0, 0.0);
    let mesh = mesh_of(
        vec![p, q, 2.0 * q, Vec3::new(0.5, 0.5, 0.0)],
        vec![[0, 1, 2], [3, 3, 3], [0, 0, 1]],
    );
    let scene = scene_of(vec![mesh]);
    let e = EmbreeAccel::build(&scene, AccelOptions::default()).unwrap();
    let b = BvhAccel::build(&scene, AccelOptions::default()).unwrap();
    assert_eq!(b.slot_count(), 0);
    for a in [&e as &dyn RayQuery, &b] {
        for o in [
            Vec3::new(0.5, 0.5, -1.0),
            Vec3::new(1.5, 1.5, 1.0),
            Vec3::new(0.0, 0.0, 1.0),
        ] {
            let r = Ray::new(o, Vec3::new(0.0, 0.0, -o.z.signum()));
            assert_eq!(a.intersect(&r), None);
            assert!(!a.occluded(&r));
        }
    }
}

#[test]
fn embree_errors_surface_as_err() {
    // An invalid device configuration.
    let err = Device::new("threads=not-a-number")
        .err()
        .expect("bad config must fail");
    println!("bad config: {err}");
    assert!(err.0.contains("embree"), "{err}");
    // A geometry id used twice: Embree reports RTC_ERROR_INVALID_ARGUMENT.
    let dev = Device::new("").unwrap();
    let pos = [Vec3::ZERO, Vec3::X, Vec3::Y];
    let quality = photon_embree_sys::RTC_BUILD_QUALITY_HIGH;
    let mut builder = SceneBuilder::new(&dev, SceneConfig::default()).unwrap();
    builder
        .attach(
            Geometry::triangles(&dev, &pos, &[[0, 1, 2]], quality, None).unwrap(),
            0,
        )
        .unwrap();
    let g = Geometry::triangles(&dev, &pos, &[[0, 1, 2]], quality, None).unwrap();
    let err = builder.attach(g, 0).expect_err("second geometry on id 0");
    println!("duplicate id: {err}");
    assert!(err.0.contains("RTC_ERROR_INVALID"), "{err}");
    // Out-of-range indices are refused before Embree sees them, by both backends.
    let bad = scene_of(vec![mesh_of(pos.to_vec(), vec![[0, 1, 3]])]);
    assert!(EmbreeAccel::build(&bad, AccelOptions::default()).is_err());
    assert!(BvhAccel::build(&bad, AccelOptions::default()).is_err());
    assert!(Geometry::triangles(&dev, &pos, &[[0, 1, 3]], quality, None).is_err());
}

#[test]
fn flush_denormals_sets_ftz_daz() {
    std::thread::spawn(|| {
        let tiny = std::hint::black_box(1e-39f32);
        assert!(tiny * std::hint::black_box(1.0f32) != 0.0);
        photon::accel::cpu::enable_flush_denormals();
        if cfg!(target_arch = "x86_64") {
            assert_eq!(tiny * std::hint::black_box(1.0f32), 0.0);
        }
    })
    .join()
    .unwrap();
}

/// Information only: build time and traversal speed of four obvhs presets on a 131k-triangle
/// mesh plus 300 long slivers (the choice is documented in `accel/bvh.rs`).
#[test]
fn obvhs_presets() {
    use obvhs::BvhBuildParams as P;
    // The bumpy sphere's triangles are all alike; add long slivers crossing the whole scene,
    // the case spatial splits (slow presets) are for.
    let mut rng = Rng(11);
    let mut slivers = Vec::new();
    for _ in 0..300 {
        let a = 1.4 * rng.dir();
        let w = 0.01 * rng.dir();
        slivers.extend([a, -a, -a + w]);
    }
    let idx = (0..300).map(|i| [3 * i, 3 * i + 1, 3 * i + 2]).collect();
    let scene = scene_of(vec![bumpy_sphere(256, 256), mesh_of(slivers, idx)]);
    let rays = random_rays(&scene, 100_000, 3);
    let presets = [
        ("fast_build", P::fast_build()),
        ("medium_build", P::medium_build()),
        ("slow_build", P::slow_build()),
        ("very_slow_build", P::very_slow_build()),
    ];
    let mut reference: Option<Vec<bool>> = None;
    for (name, params) in presets {
        let t0 = Instant::now();
        let b = BvhAccel::build_with(&scene, params).unwrap();
        let build = t0.elapsed().as_secs_f64();
        // Best of three runs each: the machine is shared and noisy.
        let mut occ = Vec::new();
        let (mut rc, mut ro) = (0.0f64, 0.0f64);
        for _ in 0..3 {
            rc = rc.max(mrays(rays.len(), || {
                std::hint::black_box(rays.iter().filter_map(|r| b.intersect(r)).count());
            }));
            ro = ro.max(mrays(rays.len(), || {
                occ = rays.iter().map(|r| b.occluded(r)).collect()
            }));
        }
        println!(
            "obvhs {name}: build {:.0} ms, closest {rc:.2} Mrays/s, occlusion {ro:.2} Mrays/s",
            build * 1e3
        );
        // All presets must answer the same occlusion queries (up to a handful of edge cases).
        match &reference {
            None => reference = Some(occ),
            Some(r) => assert!(r.iter().zip(&occ).filter(|(a, b)| a != b).count() <= 10),
        }
    }
}

/// The committed scenes are shared across threads: rayon's answers equal sequential ones,
/// through the `Accel` enum the renderer uses, and a recording wrapper answers exactly as the
/// backend it wraps.
#[test]
fn parallel_queries_match_sequential() {
    use photon::accel::recording::Query;
    use photon::accel::{Accel, BackendKind, RayKind};
    use rayon::prelude::*;
    let scene = scene_of(vec![bumpy_sphere(64, 64)]);
    let rays = random_rays(&scene, 20_000, 5);
    let cam = RayKind::Camera;
    for kind in [BackendKind::Embree, BackendKind::Obvhs] {
        let accel = Accel::build(&scene, kind, AccelOptions::default()).unwrap();
        assert_eq!(accel.kind(), kind);
        let seq: Vec<Option<Hit>> = rays.iter().map(|r| accel.intersect(cam, r)).collect();
        let par: Vec<Option<Hit>> = rays.par_iter().map(|r| accel.intersect(cam, r)).collect();
        assert_eq!(seq, par, "{kind}");
        assert!(seq.iter().filter(|h| h.is_some()).count() > rays.len() / 10);
        let batches = |accel: &Accel| -> Vec<Option<Hit>> {
            rays.par_chunks(64)
                .flat_map_iter(|c| {
                    let mut out = vec![None; c.len()];
                    accel.intersect_batch(cam, c, &mut out);
                    out
                })
                .collect()
        };
        assert_eq!(seq, batches(&accel), "{kind} batches");
        let occ: Vec<bool> = rays.iter().map(|r| accel.occluded(cam, r)).collect();
        let rec = Accel::recording(accel, 1000, 3);
        assert_eq!(rec.kind(), kind);
        assert_eq!(seq, batches(&rec), "{kind} recording");
        let rec_occ: Vec<bool> = rays
            .iter()
            .map(|r| rec.occluded(RayKind::Shadow, r))
            .collect();
        assert_eq!(occ, rec_occ, "{kind} recording");
        let (_, got) = rec.finish_recording();
        // Whole chunks of the 64-ray batches: at most 1000, at most one chunk fewer.
        let kept = got.get(cam, Query::Closest).len();
        assert!(kept <= 1000 && kept > 1000 - 64, "{kept}");
        assert_eq!(got.get(RayKind::Shadow, Query::Occlusion).len(), 1000);
        assert_eq!(
            got.sets.iter().map(|s| s.seen).sum::<u64>(),
            2 * rays.len() as u64
        );
    }
}

/// Information only (run with `--ignored`): build times and single-thread rates on a
/// 1M-triangle bumpy sphere.
#[test]
#[ignore]
fn build_times_1m() {
    let scene = scene_of(vec![bumpy_sphere(708, 708)]);
    let rays = random_rays(&scene, 200_000, 9);
    let (e, b) = build_both("1M sphere", &scene);
    let n = rays.len();
    let r_e = mrays(n, || {
        std::hint::black_box(rays.iter().filter_map(|r| e.intersect(r)).count());
    });
    let r_b = mrays(n, || {
        std::hint::black_box(rays.iter().filter_map(|r| b.intersect(r)).count());
    });
    println!("[1M sphere] closest hit Mrays/s, 1 thread: embree {r_e:.2}, obvhs {r_b:.2}");
}
