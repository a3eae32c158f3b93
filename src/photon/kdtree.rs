//! A static, balanced 3-d tree over points, for k-nearest-neighbour and radius queries.
//!
//! Layout: the points are permuted into "tree order" in one flat array. The node for an index
//! range `lo..hi` is its median `mid = (lo + hi) / 2`; its children are the ranges `lo..mid`
//! and `mid + 1..hi` (an implicit balanced tree, no child pointers). Ranges of at most
//! [`LEAF_SIZE`] points are leaves and are scanned linearly. Each node splits on the axis of
//! largest extent of its range's bounding box; the axis is kept in a byte array beside the
//! positions.
//!
//! Build: `select_nth_unstable_by` at the median of every range (O(n) per level, O(n log n) in
//! all), the two halves in parallel with `rayon::join` above [`PAR_THRESHOLD`] points.
//!
//! Queries walk the tree iteratively with a small fixed stack, nearer child first, using
//! squared distances only. k-nearest results go to a reusable bounded max-heap
//! ([`KnnResult`]) whose radius shrinks once it holds `k` points.
use crate::math::Vec3;
use std::fmt;

/// Ranges of at most this many points are not split further.
pub const LEAF_SIZE: usize = 12;
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

/// Reusable result buffer of a k-nearest query: a max-heap on `d2` of at most `k` entries.
#[derive(Clone, Debug, Default)]
pub struct KnnResult {
    heap: Vec<Neighbor>,
    k: usize,
    max_r2: f32,
}

impl KnnResult {
    /// An empty buffer; it grows to the largest `k` it is used with, then stops allocating.
    pub fn new() -> Self {
        Self::default()
    }

    /// An empty buffer with room for `k` neighbours.
    pub fn with_capacity(k: usize) -> Self {
        KnnResult {
            heap: Vec::with_capacity(k),
            ..Self::default()
        }
    }

    fn reset(&mut self, k: usize, max_r2: f32) {
        self.heap.clear();
        self.heap.reserve(k);
        self.k = k;
        self.max_r2 = max_r2;
    }

    /// Number of neighbours found.
    pub fn len(&self) -> usize {
        self.heap.len()
    }

    pub fn is_empty(&self) -> bool {
        self.heap.is_empty()
    }

    /// True when the query found its full `k` neighbours.
    pub fn is_full(&self) -> bool {
        self.k > 0 && self.heap.len() == self.k
    }

    /// Final squared search radius: the `k`-th smallest distance when `k` neighbours were
    /// found, otherwise the query's `max_r2` (every point within it was found).
    pub fn r2(&self) -> f32 {
        if self.is_full() {
            self.heap[0].d2
        } else {
            self.max_r2
        }
    }

    /// The neighbours in heap order (the farthest first, the rest unordered).
    pub fn neighbors(&self) -> &[Neighbor] {
        &self.heap
    }

    /// Sorts the neighbours by increasing distance (this breaks the heap; use it last).
    pub fn sort(&mut self) {
        self.heap.sort_unstable_by(|a, b| a.d2.total_cmp(&b.d2));
    }

    /// Current acceptance bound: points with `d2 <= bound` may enter.
    #[inline(always)]
    fn bound(&self) -> f32 {
        if self.heap.len() < self.k {
            self.max_r2
        } else {
            self.heap[0].d2
        }
    }

    /// Offers a point with `d2 <= bound()`; keeps the `k` smallest.
    #[inline(always)]
    fn push(&mut self, d2: f32, idx: u32) {
        let n = Neighbor { d2, idx };
        if self.heap.len() < self.k {
            self.heap.push(n);
            self.sift_up();
        } else if d2 < self.heap[0].d2 {
            self.heap[0] = n;
            self.sift_down();
        }
    }

    fn sift_up(&mut self) {
        let h = &mut self.heap;
        let mut i = h.len() - 1;
        let x = h[i];
        while i > 0 {
            let parent = (i - 1) / 2;
            if h[parent].d2 >= x.d2 {
                break;
            }
            h[i] = h[parent];
            i = parent;
        }
        h[i] = x;
    }

    fn sift_down(&mut self) {
        let h = &mut self.heap[..];
        let n = h.len();
        let x = h[0];
        let mut i = 0;
        loop {
            let l = 2 * i + 1;
            if l >= n {
                break;
            }
            let r = l + 1;
            let c = if r < n && h[r].d2 > h[l].d2 { r } else { l };
            if h[c].d2 <= x.d2 {
                break;
            }
            h[i] = h[c];
            i = c;
        }
        h[i] = x;
    }
}

/// The tree: positions in tree order plus one split-axis byte per node.
#[derive(Clone, Debug, Default)]
pub struct KdTree {
    pos: Vec<[f32; 3]>,
    axis: Vec<u8>,
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
        let mut axis = vec![0u8; keys.len()];
        build_range(&mut keys, &mut axis);
        let pos = keys.iter().map(|k| k.p).collect();
        let order = keys.iter().map(|k| k.idx).collect();
        Ok((KdTree { pos, axis }, order))
    }

    /// Number of points.
    pub fn len(&self) -> usize {
        self.pos.len()
    }

    pub fn is_empty(&self) -> bool {
        self.pos.is_empty()
    }

    /// Position of the point in tree-order slot `idx`.
    pub fn position(&self, idx: u32) -> Vec3 {
        Vec3::from_array(self.pos[idx as usize])
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
        out.reset(k, max_r2);
        if k == 0 || self.pos.is_empty() || !(max_r2 >= 0.0) {
            return;
        }
        self.walk(q, |idx, off, d2| {
            if d2 <= out.bound() {
                if let Some(m) = metric(idx, off, d2) {
                    let m = m.max(d2);
                    if m <= out.bound() {
                        out.push(m, idx);
                    }
                }
            }
            out.bound()
        });
    }

    /// Calls `f(idx, d2)` for every point with squared distance `d2 <= r2` from `q`.
    pub fn radius_query<F>(&self, q: Vec3, r2: f32, mut f: F)
    where
        F: FnMut(u32, f32),
    {
        if self.pos.is_empty() || !(r2 >= 0.0) {
            return;
        }
        self.walk(q, |idx, _, d2| {
            if d2 <= r2 {
                f(idx, d2);
            }
            r2
        });
    }

    /// Visits points near `q`. `visit(idx, offset, d2)` sees each candidate and returns the
    /// current squared search bound; subtrees entirely beyond it are skipped.
    #[inline(always)]
    fn walk<V>(&self, q: Vec3, mut visit: V)
    where
        V: FnMut(u32, Vec3, f32) -> f32,
    {
        let qa = q.to_array();
        let pos = &self.pos[..];
        let axis = &self.axis[..];
        let mut stack = [(0u32, 0u32, 0f32); STACK];
        let mut sp = 0usize;
        let (mut lo, mut hi) = (0usize, pos.len());
        let mut bound = f32::INFINITY;
        loop {
            while hi - lo > LEAF_SIZE {
                let mid = (lo + hi) / 2;
                let p = pos[mid];
                let ax = axis[mid] as usize;
                let d = qa[ax] - p[ax];
                let off = Vec3::from_array(p) - q;
                bound = visit(mid as u32, off, off.length_squared());
                let d2p = d * d;
                if d < 0.0 {
                    if d2p <= bound {
                        stack[sp] = ((mid + 1) as u32, hi as u32, d2p);
                        sp += 1;
                    }
                    hi = mid;
                } else {
                    if d2p <= bound {
                        stack[sp] = (lo as u32, mid as u32, d2p);
                        sp += 1;
                    }
                    lo = mid + 1;
                }
            }
            for (i, p) in pos[lo..hi].iter().enumerate() {
                let off = Vec3::from_array(*p) - q;
                let d2 = off.length_squared();
                if d2 <= bound {
                    bound = visit((lo + i) as u32, off, d2);
                }
            }
            loop {
                if sp == 0 {
                    return;
                }
                sp -= 1;
                let (l, h, d2p) = stack[sp];
                if d2p <= bound {
                    lo = l as usize;
                    hi = h as usize;
                    break;
                }
            }
        }
    }
}

/// Splits `keys` at its median on the axis of largest extent, records the axis, recurses.
fn build_range(keys: &mut [Key], axis: &mut [u8]) {
    let n = keys.len();
    if n <= LEAF_SIZE {
        return;
    }
    let ax = widest_axis(keys);
    let mid = n / 2;
    keys.select_nth_unstable_by(mid, |a, b| a.p[ax].total_cmp(&b.p[ax]));
    axis[mid] = ax as u8;
    let (kl, kr) = keys.split_at_mut(mid);
    let (al, ar) = axis.split_at_mut(mid);
    let (kr, ar) = (&mut kr[1..], &mut ar[1..]);
    if n > PAR_THRESHOLD {
        rayon::join(|| build_range(kl, al), || build_range(kr, ar));
    } else {
        build_range(kl, al);
        build_range(kr, ar);
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
