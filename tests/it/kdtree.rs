//! The photon kd-tree against brute force and against `kiddo`.
//!
//! k-nearest and radius queries must return the same photons as an exhaustive scan (up to
//! ties at the k-th distance) on random sets and on degenerate ones: empty, k = 0, k > n,
//! coplanar, heavy duplicates, points on split planes, tiny and huge coordinates. The ignored
//! test `bench_against_kiddo` prints build time and queries/s for both trees, on a uniform cube
//! and on a plane (where photons live).
use kiddo::{ImmutableKdTree, SquaredEuclidean};
use photon::math::Vec3;
use photon::photon::{KdTree, KnnResult, Photon, PhotonMap};
use std::num::NonZeroUsize;
use std::time::Instant;

/// xorshift64* uniform in [0, 1).
fn rng(state: &mut u64) -> f32 {
    *state ^= *state >> 12;
    *state ^= *state << 25;
    *state ^= *state >> 27;
    ((state.wrapping_mul(0x2545_f491_4f6c_dd1d) >> 40) as f32) / (1u64 << 24) as f32
}

fn random_points(n: usize, scale: f32, seed: u64) -> Vec<Vec3> {
    let mut s = seed;
    (0..n)
        .map(|_| Vec3::new(rng(&mut s), rng(&mut s), rng(&mut s)) * scale)
        .collect()
}

/// Squared distance exactly as the tree computes it.
fn dist2(a: Vec3, b: Vec3) -> f32 {
    (a - b).length_squared()
}

/// Checks one k-nearest answer (original indices + squared distances) against brute force:
/// the sorted distance lists are equal, every point strictly closer than the k-th distance is
/// in the answer, and no index repeats. Returns the brute-force final radius.
fn check_knn(points: &[Vec3], q: Vec3, k: usize, max_r2: f32, got: &[(u32, f32)], r2: f32) {
    let mut all: Vec<(f32, u32)> = points
        .iter()
        .enumerate()
        .map(|(i, p)| (dist2(*p, q), i as u32))
        .filter(|(d, _)| *d <= max_r2)
        .collect();
    all.sort_by(|a, b| a.0.total_cmp(&b.0));
    let want = &all[..k.min(all.len())];
    let mut got_d: Vec<f32> = got.iter().map(|g| g.1).collect();
    got_d.sort_by(f32::total_cmp);
    let want_d: Vec<f32> = want.iter().map(|w| w.0).collect();
    assert_eq!(got_d, want_d, "q={q:?} k={k}: distances differ");
    let mut ids: Vec<u32> = got.iter().map(|g| g.0).collect();
    ids.sort_unstable();
    ids.dedup();
    assert_eq!(ids.len(), got.len(), "duplicate index in result");
    for &(i, d) in got {
        assert_eq!(dist2(points[i as usize], q), d, "wrong distance for {i}");
    }
    if let Some(&(kth, _)) = want.last() {
        for &(d, i) in want.iter().filter(|w| w.0 < kth) {
            assert!(ids.binary_search(&i).is_ok(), "missing {i} at d2 {d}");
        }
    }
    let want_r2 = if k > 0 && want.len() == k {
        want[k - 1].0
    } else {
        max_r2
    };
    assert!(
        r2 == want_r2 || (r2 - want_r2).abs() <= 1e-6 * want_r2.abs(),
        "radius {r2} vs {want_r2}"
    );
}

/// Runs k-nearest and radius queries at `queries` for several k and compares to brute force.
fn check_set(points: &[Vec3], queries: &[Vec3], max_r2: f32) {
    let (tree, order) = KdTree::build(points).unwrap();
    assert_eq!(tree.len(), points.len());
    let mut out = KnnResult::new();
    let n = points.len();
    for &q in queries {
        for k in [0, 1, 8, 50, 200, n + 5] {
            tree.knn(q, k, max_r2, &mut out);
            let got: Vec<(u32, f32)> = out
                .neighbors()
                .iter()
                .map(|nb| (order[nb.idx as usize], nb.d2))
                .collect();
            check_knn(points, q, k, max_r2, &got, out.r2());
            let r2 = out.r2();
            out.sort();
            assert!(out.neighbors().windows(2).all(|w| w[0].d2 <= w[1].d2));
            assert_eq!(out.r2(), r2);
        }
        // Radius query: the exact set of indices within r2.
        let r2 = if max_r2.is_finite() { max_r2 } else { 1e30 };
        let mut got = Vec::new();
        tree.radius_query(q, r2, |i, d2| {
            assert_eq!(d2, dist2(points[order[i as usize] as usize], q));
            got.push(order[i as usize]);
        });
        got.sort_unstable();
        let want: Vec<u32> = (0..n as u32)
            .filter(|&i| dist2(points[i as usize], q) <= r2)
            .collect();
        assert_eq!(got, want, "radius query at {q:?}");
    }
}

#[test]
fn random_sets_match_brute_force() {
    for (n, nq) in [(10usize, 50usize), (1000, 100), (100_000, 20)] {
        let pts = random_points(n, 1.0, n as u64 + 1);
        let qs = random_points(nq, 1.2, 77);
        check_set(&pts, &qs, f32::INFINITY);
        check_set(&pts, &qs, 0.01);
    }
}

#[test]
fn empty_tree() {
    let (tree, order) = KdTree::build(&[]).unwrap();
    assert!(tree.is_empty() && order.is_empty());
    let mut out = KnnResult::new();
    tree.knn(Vec3::ZERO, 10, 1.0, &mut out);
    assert!(out.is_empty());
    assert_eq!(out.r2(), 1.0);
    tree.radius_query(Vec3::ZERO, 1.0, |_, _| panic!("empty tree found a point"));
    check_set(&[], &[Vec3::ONE], f32::INFINITY);
}

#[test]
fn coplanar_points() {
    let pts: Vec<Vec3> = random_points(5000, 1.0, 3)
        .into_iter()
        .map(|p| Vec3::new(p.x, p.y, 0.0))
        .collect();
    let mut qs = random_points(30, 1.0, 4);
    qs.extend(qs.clone().iter().map(|q| Vec3::new(q.x, q.y, 0.0)));
    check_set(&pts, &qs, f32::INFINITY);
    check_set(&pts, &qs, 0.002);
}

#[test]
fn heavy_duplicates() {
    // 10k points at 3 positions.
    let sites = [
        Vec3::new(0.0, 0.0, 0.0),
        Vec3::new(1.0, 0.0, 0.0),
        Vec3::new(0.5, 0.5, 0.5),
    ];
    let pts: Vec<Vec3> = (0..10_000).map(|i| sites[i % 3]).collect();
    let mut qs = random_points(10, 1.0, 5);
    qs.extend(sites);
    check_set(&pts, &qs, f32::INFINITY);
    check_set(&pts, &qs, 0.3);
}

#[test]
fn integer_grid_points_on_split_planes() {
    let mut pts = Vec::new();
    for x in 0..20 {
        for y in 0..20 {
            for z in 0..10 {
                pts.push(Vec3::new(x as f32, y as f32, z as f32));
            }
        }
    }
    let mut qs: Vec<Vec3> = random_points(20, 20.0, 6)
        .into_iter()
        .map(|p| p.round())
        .collect();
    qs.extend(random_points(20, 20.0, 7));
    qs.push(Vec3::new(9.5, 9.5, 4.5));
    check_set(&pts, &qs, f32::INFINITY);
    check_set(&pts, &qs, 2.0);
}

#[test]
fn tiny_and_huge_scales() {
    for scale in [1e-4f32, 1e4] {
        let pts = random_points(20_000, scale, 8);
        let qs = random_points(20, scale, 9);
        check_set(&pts, &qs, f32::INFINITY);
        check_set(&pts, &qs, 0.001 * scale * scale);
        let (tree, _) = KdTree::build(&pts).unwrap();
        let mut out = KnnResult::new();
        tree.knn(qs[0], 50, f32::INFINITY, &mut out);
        assert!(out.r2().is_finite() && out.neighbors().iter().all(|n| n.d2.is_finite()));
    }
}

#[test]
fn non_finite_points_are_dropped() {
    let mut pts = random_points(100, 1.0, 10);
    pts[3] = Vec3::new(f32::NAN, 0.0, 0.0);
    pts[7] = Vec3::splat(f32::INFINITY);
    let (tree, order) = KdTree::build(&pts).unwrap();
    assert_eq!(tree.len(), 98);
    assert!(!order.contains(&3) && !order.contains(&7));
    let finite: Vec<Vec3> = pts.iter().copied().filter(|p| p.is_finite()).collect();
    let mut out = KnnResult::new();
    tree.knn(Vec3::splat(0.5), 200, f32::INFINITY, &mut out);
    assert_eq!(out.len(), finite.len());
}

#[test]
fn photon_map_reorders_payloads_with_the_tree() {
    // Indices below 2048 are exact in the 11-bit power mantissa.
    let pts = random_points(2000, 1.0, 11);
    let photons: Vec<Photon> = pts
        .iter()
        .enumerate()
        .map(|(i, p)| Photon::new(*p, Vec3::splat(i as f32), Vec3::X, (i % 2) as u8))
        .collect();
    let map = PhotonMap::new(&photons).unwrap();
    let mut out = KnnResult::new();
    let q = Vec3::splat(0.5);
    map.knn(q, 20, f32::INFINITY, &mut out);
    for nb in out.neighbors() {
        let ph = map.photon(nb.idx);
        let orig = ph.power().x as usize; // exact: small integers survive the encoding
        assert_eq!(ph.pos(), pts[orig]);
        assert_eq!(ph.flags(), (orig % 2) as u8);
        assert_eq!(nb.d2, dist2(pts[orig], q));
    }
    // Filtered query: only odd flags, equal to brute force over the odd photons.
    map.knn_by(q, 20, f32::INFINITY, &mut out, |ph, _, d2| {
        (ph.flags() == 1).then_some(d2)
    });
    let odd: Vec<Vec3> = pts.iter().copied().skip(1).step_by(2).collect();
    let got: Vec<(u32, f32)> = out
        .neighbors()
        .iter()
        .map(|nb| ((map.photon(nb.idx).power().x as u32 - 1) / 2, nb.d2))
        .collect();
    check_knn(&odd, q, 20, f32::INFINITY, &got, out.r2());
}

#[test]
fn ellipsoid_metric_matches_brute_force() {
    // Flattened search: m = d2 + 15 h^2 (h: offset along n), points on and around a plane.
    let mut pts = random_points(20_000, 1.0, 14);
    for p in pts.iter_mut().step_by(2) {
        p.z = 0.5;
    }
    let n = Vec3::new(0.1, -0.2, 1.0).normalize();
    let metric = |off: Vec3, d2: f32| d2 + 15.0 * off.dot(n) * off.dot(n);
    let (tree, order) = KdTree::build(&pts).unwrap();
    let mut out = KnnResult::new();
    for q in random_points(50, 1.0, 15) {
        let q = Vec3::new(q.x, q.y, 0.5);
        for (k, max_r2) in [(50usize, f32::INFINITY), (200, 0.003)] {
            tree.knn_by(q, k, max_r2, &mut out, |_, off, d2| Some(metric(off, d2)));
            let mut got: Vec<(f32, u32)> = out
                .neighbors()
                .iter()
                .map(|nb| (nb.d2, order[nb.idx as usize]))
                .collect();
            got.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
            let mut want: Vec<(f32, u32)> = pts
                .iter()
                .enumerate()
                .map(|(i, p)| (metric(*p - q, dist2(*p, q)), i as u32))
                .filter(|w| w.0 <= max_r2)
                .collect();
            want.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
            want.truncate(k);
            assert_eq!(got, want, "q={q:?} k={k}");
        }
    }
}

fn kiddo_tree(points: &[Vec3]) -> ImmutableKdTree<f32, 3> {
    let arr: Vec<[f32; 3]> = points.iter().map(|p| p.to_array()).collect();
    ImmutableKdTree::new_from_slice(&arr).unwrap()
}

#[test]
fn same_results_as_kiddo() {
    let pts = random_points(50_000, 1.0, 12);
    let qs = random_points(300, 1.0, 13);
    let (tree, order) = KdTree::build(&pts).unwrap();
    let kd = kiddo_tree(&pts);
    let mut out = KnnResult::new();
    for &q in &qs {
        for k in [1usize, 50, 200] {
            let max_r2 = 0.01;
            tree.knn(q, k, max_r2, &mut out);
            let mut ours: Vec<(u32, f32)> = out
                .neighbors()
                .iter()
                .map(|n| (order[n.idx as usize], n.d2))
                .collect();
            let mut theirs: Vec<(u32, f32)> = kd
                .query(&q.to_array())
                .nearest_n::<SquaredEuclidean<f32>>(NonZeroUsize::new(k).unwrap())
                .within(max_r2)
                .execute()
                .into_iter()
                .map(|r| (r.item, r.distance))
                .collect();
            ours.sort_by(|a, b| a.1.total_cmp(&b.1).then(a.0.cmp(&b.0)));
            theirs.sort_by(|a, b| a.1.total_cmp(&b.1).then(a.0.cmp(&b.0)));
            assert_eq!(ours.len(), theirs.len(), "q={q:?} k={k}");
            for (a, b) in ours.iter().zip(&theirs) {
                assert_eq!(a.0, b.0, "q={q:?} k={k}");
                assert!((a.1 - b.1).abs() <= 1e-6 * b.1.max(1e-12));
            }
        }
    }
}

#[test]
#[ignore]
fn bench_against_kiddo() {
    let n = 1_000_000;
    let nq = 100_000;
    let pts = random_points(n, 1.0, 21);
    let qs = random_points(nq, 1.0, 22);
    bench_set("uniform cube", &pts, &qs);
    // Photons live on surfaces: the same on the plane z = 0.
    let flat = |v: Vec<Vec3>| -> Vec<Vec3> { v.iter().map(|p| Vec3::new(p.x, p.y, 0.0)).collect() };
    bench_set("plane z = 0", &flat(pts), &flat(qs));
}

/// Build times and best-of-3 k-nearest throughput of our tree and kiddo on one point set.
fn bench_set(name: &str, pts: &[Vec3], qs: &[Vec3]) {
    let nq = qs.len();
    let t = Instant::now();
    let (tree, _) = KdTree::build(pts).unwrap();
    let ours_build = t.elapsed().as_secs_f64();
    let t = Instant::now();
    let kd = kiddo_tree(pts);
    let kiddo_build = t.elapsed().as_secs_f64();
    println!(
        "[{name}] build {} points: ours {ours_build:.3} s, kiddo {kiddo_build:.3} s",
        pts.len()
    );
    let photons: Vec<Photon> = pts
        .iter()
        .map(|p| Photon::new(*p, Vec3::ONE, -Vec3::Z, 0))
        .collect();
    let t = Instant::now();
    let map = PhotonMap::new(&photons).unwrap();
    println!(
        "[{name}] PhotonMap::new: {:.3} s ({} photons)",
        t.elapsed().as_secs_f64(),
        map.len()
    );

    // Best of 3 interleaved rounds, to damp noise from other work on the machine.
    for k in [50usize, 200] {
        let kk = NonZeroUsize::new(k).unwrap();
        let mut out = KnnResult::with_capacity(k);
        let (mut ours, mut sorted, mut unsorted) = (0f64, 0f64, 0f64);
        for _round in 0..3 {
            // Unbounded radius, like kiddo's plain nearest_n.
            let t = Instant::now();
            let mut check = 0f64;
            for &q in qs {
                tree.knn(q, k, f32::INFINITY, &mut out);
                check += out.r2() as f64;
            }
            ours = ours.max(nq as f64 / t.elapsed().as_secs_f64());
            let t = Instant::now();
            let mut check_k = 0f64;
            for q in qs {
                let res = kd
                    .query(&q.to_array())
                    .nearest_n::<SquaredEuclidean<f32>>(kk)
                    .execute();
                check_k += res.last().map_or(0.0, |r| r.distance as f64);
            }
            sorted = sorted.max(nq as f64 / t.elapsed().as_secs_f64());
            assert!(
                (check - check_k).abs() <= 1e-4 * check_k,
                "{check} vs {check_k}"
            );
            let t = Instant::now();
            let mut count = 0usize;
            for q in qs {
                let res = kd
                    .query(&q.to_array())
                    .nearest_n::<SquaredEuclidean<f32>>(kk)
                    .within(f32::INFINITY)
                    .unsorted()
                    .execute();
                count += res.len();
            }
            unsorted = unsorted.max(nq as f64 / t.elapsed().as_secs_f64());
            assert_eq!(count, k * nq);
        }
        println!(
            "[{name}] k={k}: ours {ours:.0} q/s, kiddo sorted {sorted:.0} q/s, kiddo unsorted {unsorted:.0} q/s, ours/best kiddo {:.2}",
            ours / sorted.max(unsorted)
        );
    }
}
