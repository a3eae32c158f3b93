//! A static, balanced 3-d tree over points, for k-nearest-neighbour and radius queries.
//!
//! Layout: the points are permuted into "tree order" and stored as three coordinate arrays.
//! The subtree over an index range `lo..hi` splits at its median `mid = lo + (hi - lo) / 2`
//! into `lo..mid` and `mid..hi`, so ranges are implicit; ranges of at most [`LEAF_SIZE`]
//! points are leaves, scanned as one fixed-size vectorised block. Internal nodes hold only
//! the split plane (value + axis, 8 bytes) in breadth-first order, so the upper tree is
//! compact and cache-resident. Each node splits on the axis of largest extent of its range's
//! bounding box.
//!
//! Build: `select_nth_unstable_by` at the median of every range (O(n) per level, O(n log n) in
//! all), the two halves in parallel with `rayon::join` above [`PAR_THRESHOLD`] points.
//!
//! Queries walk the tree iteratively with a small fixed stack, nearer child first, pruning
//! by the squared distance to each subtree's cell (updated incrementally, Arya & Mount).
//! k-nearest results go to a reusable buffer ([`KnnResult`]): candidates within the current
//! bound are appended, and whenever `2k` have piled up a linear-time selection keeps the `k`
//! nearest and shrinks the bound to the farthest of them, which beat a bounded max-heap. The
//! layout beat Jensen's left-balanced heap layout with one point per node (kept as the ignored
//! test `heap_layout::heap_layout_vs_implicit_layout`), and leaves of 32 beat 8, 16 and 64
//! (measured: BENCHMARKS.md, "Design measurements").
use crate::math::Vec3;
use std::fmt;
use std::sync::atomic::{AtomicU64, Ordering};

/// Ranges of at most this many points are not split further.
pub const LEAF_SIZE: usize = 32;
/// Ranges larger than this are built with `rayon::join`.
pub const PAR_THRESHOLD: usize = 32 * 1024;
/// Depth bound of the traversal stack: ranges halve at every level, so 64 covers any `u32`
/// count.
const STACK: usize = 64;

/// Error from [`KdTree::build`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct TooManyPoints(pub usize);

impl fmt::Display for TooManyPoints {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "kd-tree: {} points exceed the u32 index range", self.0)
    }
}

impl std::error::Error for TooManyPoints {}

/// A found point: tree-order index and squared distance (or the metric's value).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Neighbor {
    pub d2: f32,
    pub idx: u32,
}

/// Reusable result buffer of a k-nearest query: at most `k` entries once the query is done.
#[derive(Clone, Debug, Default)]
pub struct KnnResult {
    buf: Vec<Neighbor>,
    k: usize,
    max_r2: f32,
    /// Acceptance bound: `max_r2` until `k` candidates were seen, then an upper bound of the
    /// `k`-th smallest distance, tightened at every compaction.
    bound: f32,
    /// Final squared radius, set by `finish`.
    r2: f32,
}

impl KnnResult {
    /// An empty buffer; it grows to the largest `k` it is used with, then stops allocating.
    pub fn new() -> Self {
        Self::default()
    }

    /// An empty buffer with room for `k` neighbours.
    pub fn with_capacity(k: usize) -> Self {
        KnnResult {
            buf: Vec::with_capacity(2 * k),
            ..Self::default()
        }
    }

    /// Starts a query for `k` neighbours among `len` points: room is reserved for what can
    /// be found (a huge `k` does not reserve for itself).
    fn reset(&mut self, k: usize, max_r2: f32, len: usize) {
        self.buf.clear();
        self.buf.reserve(2 * k.min(len));
        self.k = k;
        self.max_r2 = max_r2;
        self.bound = max_r2;
        self.r2 = max_r2;
    }

    /// Number of neighbours found.
    pub fn len(&self) -> usize {
        self.buf.len()
    }

    pub fn is_empty(&self) -> bool {
        self.buf.is_empty()
    }

    /// True when the query found its full `k` neighbours.
    pub fn is_full(&self) -> bool {
        self.k > 0 && self.buf.len() == self.k
    }

    /// Final squared search radius: the `k`-th smallest distance when `k` neighbours were
    /// found, otherwise the query's `max_r2` (every point within it was found).
    pub fn r2(&self) -> f32 {
        self.r2
    }

    /// The neighbours: when full, the farthest (the one at distance `r2`) first; otherwise
    /// and after it, in no particular order.
    pub fn neighbors(&self) -> &[Neighbor] {
        &self.buf
    }

    /// Sorts the neighbours by increasing distance.
    pub fn sort(&mut self) {
        self.buf.sort_unstable_by(|a, b| a.d2.total_cmp(&b.d2));
    }

    /// Current acceptance bound: points with `d2 <= bound` may enter.
    #[inline(always)]
    fn bound(&self) -> f32 {
        self.bound
    }

    /// Offers a point with `d2 <= bound()`. Candidates are appended; when `2k` have piled up
    /// the `k` smallest are kept (a linear-time selection) and the bound tightens to the
    /// largest of them: amortised O(1) per candidate, no per-insert sifting.
    #[inline(always)]
    fn push(&mut self, d2: f32, idx: u32) {
        self.buf.push(Neighbor { d2, idx });
        let n = self.buf.len();
        if n == self.k {
            self.bound = self.buf.iter().fold(0.0f32, |m, nb| m.max(nb.d2));
        } else if n == 2 * self.k {
            self.keep_k();
        }
    }

    /// Keeps the `k` smallest candidates, sets the bound to the largest of them.
    fn keep_k(&mut self) {
        let k = self.k;
        self.buf
            .select_nth_unstable_by(k - 1, |a, b| a.d2.total_cmp(&b.d2));
        self.buf.truncate(k);
        self.bound = self.buf[k - 1].d2;
    }

    /// Ends a query: at most `k` entries, the farthest first when full.
    fn finish(&mut self) {
        if self.k == 0 || self.buf.len() < self.k {
            return;
        }
        if self.buf.len() > self.k {
            self.keep_k();
        }
        let far = (0..self.buf.len())
            .max_by(|&a, &b| self.buf[a].d2.total_cmp(&self.buf[b].d2))
            .unwrap_or(0);
        self.buf.swap(0, far);
        self.r2 = self.buf[0].d2;
    }
}

/// An internal node: split plane `axis = split`; points left of it have coordinate `<= split`,
/// points right of it `>= split`.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
struct Node {
    split: f32,
    axis: u32,
}

/// The tree. Points live only in the leaves, as three coordinate arrays in tree order (padded
/// by [`LEAF_SIZE`] so every leaf can be read as one fixed-size block); the internal nodes
/// are split planes in breadth-first order (children of `i` at `2i + 1`, `2i + 2`), 8 bytes
/// each, so the top of the tree stays in cache. A node's point range is implicit: the node
/// over `lo..hi` splits at `mid = (lo + hi) / 2` into `lo..mid` and `mid..hi`.
#[derive(Clone, Debug, Default)]
pub struct KdTree {
    xs: Vec<f32>,
    ys: Vec<f32>,
    zs: Vec<f32>,
    nodes: Vec<Node>,
    len: usize,
}

/// A subtree still to visit: its node, point range and distance from the query.
#[derive(Clone, Copy, Default)]
struct Pending {
    node: u32,
    lo: u32,
    hi: u32,
    /// Squared distance from the query to the subtree's cell.
    rd: f32,
    /// Per-axis distance from the query to the cell.
    off: [f32; 4],
}

/// A point being sorted during the build: position and its index in the input.
#[derive(Clone, Copy)]
struct Key {
    p: [f32; 3],
    idx: u32,
}

impl KdTree {
    /// Builds the tree over `points`, skipping non-finite ones. Returns the tree and, for each
    /// tree-order slot, the index of its point in `points` (use it to reorder payloads).
    pub fn build(points: &[Vec3]) -> Result<(KdTree, Vec<u32>), TooManyPoints> {
        if points.len() >= u32::MAX as usize {
            return Err(TooManyPoints(points.len()));
        }
        let mut keys: Vec<Key> = points
            .iter()
            .enumerate()
            .filter(|(_, p)| p.is_finite())
            .map(|(i, p)| Key {
                p: p.to_array(),
                idx: i as u32,
            })
            .collect();
        let len = keys.len();
        let nodes: Vec<AtomicU64> = (0..node_slots(len)).map(|_| AtomicU64::new(0)).collect();
        build_range(&mut keys, 0, &nodes);
        let nodes = nodes
            .into_iter()
            .map(|a| {
                let v = a.into_inner();
                Node {
                    split: f32::from_bits(v as u32),
                    axis: (v >> 32) as u32,
                }
            })
            .collect();
        let coord = |a: usize| {
            let mut v: Vec<f32> = keys.iter().map(|k| k.p[a]).collect();
            v.resize(len + LEAF_SIZE, f32::MAX);
            v
        };
        let tree = KdTree {
            xs: coord(0),
            ys: coord(1),
            zs: coord(2),
            nodes,
            len,
        };
        let order = keys.iter().map(|k| k.idx).collect();
        Ok((tree, order))
    }

    /// Number of points.
    pub fn len(&self) -> usize {
        self.len
    }

    pub fn is_empty(&self) -> bool {
        self.len == 0
    }

    /// Position of the point in tree-order slot `idx`.
    pub fn position(&self, idx: u32) -> Vec3 {
        let i = idx as usize;
        Vec3::new(self.xs[i], self.ys[i], self.zs[i])
    }

    /// The up-to-`k` nearest points to `q` with squared distance `<= max_r2`, into `out`.
    pub fn knn(&self, q: Vec3, k: usize, max_r2: f32, out: &mut KnnResult) {
        self.knn_by(q, k, max_r2, out, |_, _, d2| Some(d2));
    }

    /// k-nearest with a custom metric. For every point within the current search radius,
    /// `metric(idx, offset = point - q, d2)` returns its distance value for ranking, or `None`
    /// to reject the point. Values below `d2` are raised to `d2`, so pruning stays exact: use
    /// it to flatten the search sphere into an ellipsoid or to filter points out.
    #[inline]
    pub fn knn_by<F>(&self, q: Vec3, k: usize, max_r2: f32, out: &mut KnnResult, mut metric: F)
    where
        F: FnMut(u32, Vec3, f32) -> Option<f32>,
    {
        out.reset(k, max_r2, self.len);
        if k == 0 || self.len == 0 || max_r2.is_nan() || max_r2 < 0.0 {
            return;
        }
        self.walk(q, max_r2, |idx, off, d2| {
            if let Some(m) = metric(idx, off, d2) {
                let m = m.max(d2);
                if m <= out.bound() {
                    out.push(m, idx);
                }
            }
            out.bound()
        });
        out.finish();
    }

    /// Calls `f(idx, d2)` for every point with squared distance `d2 <= r2` from `q`.
    pub fn radius_query<F>(&self, q: Vec3, r2: f32, mut f: F)
    where
        F: FnMut(u32, f32),
    {
        if self.len == 0 || r2.is_nan() || r2 < 0.0 {
            return;
        }
        self.walk(q, r2, |idx, _, d2| {
            f(idx, d2);
            r2
        });
    }

    /// Visits the points with `d2 <= bound` around `q`, starting with `bound = r2`.
    /// `visit(idx, offset, d2)` returns the new bound (it may only shrink); subtrees entirely
    /// beyond it are skipped.
    #[inline(always)]
    fn walk<V>(&self, q: Vec3, r2: f32, mut visit: V)
    where
        V: FnMut(u32, Vec3, f32) -> f32,
    {
        let qa = [q.x, q.y, q.z, 0.0];
        let nodes = &self.nodes[..];
        // Incremental cell distance (Arya & Mount): `off[a]` is the distance from q to the
        // current cell along axis a, `rd` the squared distance to the cell.
        let mut stack = [Pending::default(); STACK];
        let mut sp = 0usize;
        let mut cur = Pending {
            node: 0,
            lo: 0,
            hi: self.len as u32,
            rd: 0.0,
            off: [0.0; 4],
        };
        let mut bound = r2;
        loop {
            while (cur.hi - cur.lo) as usize > LEAF_SIZE {
                let nd = nodes[cur.node as usize];
                let (lo, hi, node) = (cur.lo, cur.hi, cur.node);
                let mid = lo + (hi - lo) / 2;
                let ax = (nd.axis & 3) as usize;
                let d = qa[ax] - nd.split;
                let mut far = cur;
                far.rd = cur.rd - cur.off[ax] * cur.off[ax] + d * d;
                far.off[ax] = d;
                if d < 0.0 {
                    (cur.node, cur.hi) = (2 * node + 1, mid);
                    (far.node, far.lo) = (2 * node + 2, mid);
                } else {
                    (cur.node, cur.lo) = (2 * node + 2, mid);
                    (far.node, far.hi) = (2 * node + 1, mid);
                }
                if far.rd <= bound {
                    stack[sp] = far;
                    sp += 1;
                }
            }
            bound = self.scan_leaf(q, cur.lo as usize, cur.hi as usize, bound, &mut visit);
            loop {
                if sp == 0 {
                    return;
                }
                sp -= 1;
                if stack[sp].rd <= bound {
                    cur = stack[sp];
                    break;
                }
            }
        }
    }

    /// Visits the points of leaf `lo..hi` within `bound`; returns the updated bound.
    #[inline(always)]
    fn scan_leaf<V>(&self, q: Vec3, lo: usize, hi: usize, mut bound: f32, visit: &mut V) -> f32
    where
        V: FnMut(u32, Vec3, f32) -> f32,
    {
        // A fixed-size block (the arrays are padded) so the distances vectorise.
        let block = |v: &[f32]| -> [f32; LEAF_SIZE] {
            let mut b = [0.0; LEAF_SIZE];
            b.copy_from_slice(&v[lo..lo + LEAF_SIZE]);
            b
        };
        let (xs, ys, zs) = (block(&self.xs), block(&self.ys), block(&self.zs));
        let mut d2 = [0f32; LEAF_SIZE];
        for i in 0..LEAF_SIZE {
            let (dx, dy, dz) = (xs[i] - q.x, ys[i] - q.y, zs[i] - q.z);
            // Same operation order as glam's `length_squared`.
            d2[i] = dx * dx + dy * dy + dz * dz;
        }
        for i in 0..(hi - lo).min(LEAF_SIZE) {
            if d2[i] <= bound {
                let off = Vec3::new(xs[i] - q.x, ys[i] - q.y, zs[i] - q.z);
                bound = visit((lo + i) as u32, off, d2[i]);
            }
        }
        bound
    }
}

/// Breadth-first node slots for `n` points: a complete tree down to the deepest split.
fn node_slots(n: usize) -> usize {
    let mut size = n;
    let mut depth = 0;
    while size > LEAF_SIZE {
        size -= size / 2; // the larger half
        depth += 1;
    }
    (1usize << depth) - 1
}

/// Splits `keys` (the range of node `node`) at its median on the axis of largest extent,
/// records the split plane, recurses.
fn build_range(keys: &mut [Key], node: usize, nodes: &[AtomicU64]) {
    let n = keys.len();
    if n <= LEAF_SIZE {
        return;
    }
    let ax = widest_axis(keys);
    let mid = n / 2;
    keys.select_nth_unstable_by(mid, |a, b| a.p[ax].total_cmp(&b.p[ax]));
    let split = keys[mid].p[ax];
    nodes[node].store(
        split.to_bits() as u64 | (ax as u64) << 32,
        Ordering::Relaxed,
    );
    let (kl, kr) = keys.split_at_mut(mid);
    let (l, r) = (2 * node + 1, 2 * node + 2);
    if n > PAR_THRESHOLD {
        rayon::join(|| build_range(kl, l, nodes), || build_range(kr, r, nodes));
    } else {
        build_range(kl, l, nodes);
        build_range(kr, r, nodes);
    }
}

/// Axis (0, 1, 2) along which the bounding box of `keys` is largest.
fn widest_axis(keys: &[Key]) -> usize {
    let mut lo = [f32::INFINITY; 3];
    let mut hi = [f32::NEG_INFINITY; 3];
    for k in keys {
        for a in 0..3 {
            lo[a] = lo[a].min(k.p[a]);
            hi[a] = hi[a].max(k.p[a]);
        }
    }
    let ext = [hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2]];
    if ext[0] >= ext[1] && ext[0] >= ext[2] {
        0
    } else if ext[1] >= ext[2] {
        1
    } else {
        2
    }
}

/// Layout experiment kept as a benchmark: Jensen's left-balanced heap layout (node `i` has
/// children `2i + 1`, `2i + 2`, one point per node) against the implicit median layout with
/// leaf buckets used above. Run with
/// `cargo test --release --lib photon::kdtree::heap_layout -- --ignored --nocapture`.
#[cfg(test)]
mod heap_layout {
    use super::*;
    use glam::{Vec3A, Vec4};
    use std::time::Instant;

    /// Nodes in the left subtree of a complete (left-balanced) tree of `n` nodes.
    fn left_size(n: usize) -> usize {
        if n <= 1 {
            return 0;
        }
        let h = usize::BITS - 1 - n.leading_zeros(); // floor(log2 n)
        let half = 1usize << (h - 1);
        let last = n - ((1usize << h) - 1);
        half - 1 + last.min(half)
    }

    fn build(keys: &mut [Key], node: usize, out: &mut [Vec4]) {
        if keys.is_empty() {
            return;
        }
        let ax = widest_axis(keys);
        let m = left_size(keys.len());
        keys.select_nth_unstable_by(m, |a, b| a.p[ax].total_cmp(&b.p[ax]));
        let p = keys[m].p;
        out[node] = Vec4::new(p[0], p[1], p[2], ax as f32);
        let (l, r) = keys.split_at_mut(m);
        build(l, 2 * node + 1, out);
        build(&mut r[1..], 2 * node + 2, out);
    }

    fn knn(nodes: &[Vec4], q: Vec3, k: usize, out: &mut KnnResult) {
        out.reset(k, f32::INFINITY, nodes.len());
        let q4 = Vec3A::from(q);
        let mut stack = [(0usize, 0f32); STACK];
        let mut sp = 1;
        while sp > 0 {
            sp -= 1;
            let (mut i, d2p) = stack[sp];
            if d2p > out.bound() {
                continue;
            }
            while i < nodes.len() {
                let p = nodes[i];
                let off = Vec3A::from_vec4(p) - q4;
                let d2 = off.length_squared();
                if d2 <= out.bound() {
                    out.push(d2, i as u32);
                }
                let d = -[off.x, off.y, off.z][p.w as usize];
                let (near, far) = if d < 0.0 {
                    (2 * i + 1, 2 * i + 2)
                } else {
                    (2 * i + 2, 2 * i + 1)
                };
                if far < nodes.len() && d * d <= out.bound() {
                    stack[sp] = (far, d * d);
                    sp += 1;
                }
                i = near;
            }
        }
        out.finish();
    }

    fn points(n: usize) -> Vec<Vec3> {
        let mut s = 0x9e37_79b9_7f4a_7c15u64;
        let mut r = || {
            s ^= s << 13;
            s ^= s >> 7;
            s ^= s << 17;
            (s >> 40) as f32 / (1u64 << 24) as f32
        };
        (0..n).map(|_| Vec3::new(r(), r(), r())).collect()
    }

    #[test]
    fn heap_layout_matches_brute_force() {
        let pts = points(3000);
        let mut keys: Vec<Key> = pts
            .iter()
            .map(|p| Key {
                p: p.to_array(),
                idx: 0,
            })
            .collect();
        let mut nodes = vec![Vec4::ZERO; keys.len()];
        build(&mut keys, 0, &mut nodes);
        let mut out = KnnResult::new();
        for q in points(50) {
            knn(&nodes, q, 20, &mut out);
            let mut got: Vec<f32> = out.neighbors().iter().map(|n| n.d2).collect();
            got.sort_by(f32::total_cmp);
            let mut want: Vec<f32> = pts.iter().map(|p| (*p - q).length_squared()).collect();
            want.sort_by(f32::total_cmp);
            assert_eq!(got, want[..20]);
        }
    }

    #[test]
    #[ignore]
    fn heap_layout_vs_implicit_layout() {
        let pts = points(1_000_000);
        let qs: Vec<Vec3> = points(100_000)
            .iter()
            .map(|p| Vec3::new(p.z, p.x, p.y))
            .collect();
        let mut keys: Vec<Key> = pts
            .iter()
            .map(|p| Key {
                p: p.to_array(),
                idx: 0,
            })
            .collect();
        let mut nodes = vec![Vec4::ZERO; keys.len()];
        build(&mut keys, 0, &mut nodes);
        let (tree, _) = KdTree::build(&pts).unwrap();
        for k in [50usize, 200] {
            let mut out = KnnResult::new();
            let t = Instant::now();
            let mut a = 0.0f64;
            for &q in &qs {
                knn(&nodes, q, k, &mut out);
                a += out.r2() as f64;
            }
            let heap_qps = qs.len() as f64 / t.elapsed().as_secs_f64();
            let t = Instant::now();
            let mut b = 0.0f64;
            for &q in &qs {
                tree.knn(q, k, f32::INFINITY, &mut out);
                b += out.r2() as f64;
            }
            let implicit_qps = qs.len() as f64 / t.elapsed().as_secs_f64();
            assert!((a - b).abs() <= 1e-6 * b);
            println!("k={k}: heap layout {heap_qps:.0} q/s, implicit+leaves {implicit_qps:.0} q/s");
        }
    }
}
