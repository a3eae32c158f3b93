//! Recording the ray queries a render makes (for `photon crosscheck`, `photon bench` and the
//! raw rate of `photon render --stats`).
//!
//! Every query of the renderer names its [`RayKind`], so a [`Recording`] wrapped around a
//! backend ([`Accel::recording`]) sees exactly the rays a render casts: nothing rebuilds them.
//! It forwards each call unchanged (a batch stays one batch, so Embree still gets its 8-wide
//! packets) and keeps a bounded, deterministic sample of the rays per kind and [`Query`]:
//!
//! - each call's rays are cut into chunks of at most [`CHUNK`] consecutive rays (a tile's
//!   camera rays of one sample index are one chunk, as coherent as the render casts them; the
//!   single-ray calls of photon paths are chunks of one);
//! - a chunk's key is a hash of the seed, its kind and query and the bits of its rays;
//! - per (kind, query) the recording keeps the chunks of smallest key while their rays fit into
//!   its capacity; once a chunk has been dropped for lack of room, no chunk of a larger key is
//!   taken (a bottom-k sample). The sample therefore depends only on the set of rays the render
//!   casts, never on the thread count or the order of the calls, and holds at most `capacity`
//!   rays per (kind, query); [`crate::memory::recording_bytes`] bounds its memory.
//!
//! A render that does not record pays nothing: [`Accel`] dispatches through its closed enum as
//! before and the kind is a constant argument at each call site.
use super::{Accel, Hit, RayKind};
use crate::math::Ray;
use crate::sampling::{hash, mix64};
use std::collections::BinaryHeap;
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::{Mutex, PoisonError};

/// Most consecutive rays of one call that are kept or dropped together.
pub const CHUNK: usize = 256;

/// The query a ray was cast with.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Query {
    /// Closest hit.
    Closest,
    /// Any hit (shadow rays).
    Occlusion,
}

impl Query {
    pub const ALL: [Query; 2] = [Query::Closest, Query::Occlusion];

    pub fn name(self) -> &'static str {
        match self {
            Query::Closest => "closest",
            Query::Occlusion => "occluded",
        }
    }
}

/// A chunk of consecutive rays and its sampling key (ordered by key alone).
struct Keyed {
    key: u64,
    rays: Vec<Ray>,
}

impl PartialEq for Keyed {
    fn eq(&self, other: &Self) -> bool {
        self.key == other.key
    }
}
impl Eq for Keyed {}
impl PartialOrd for Keyed {
    fn partial_cmp(&self, other: &Self) -> Option<std::cmp::Ordering> {
        Some(self.cmp(other))
    }
}
impl Ord for Keyed {
    fn cmp(&self, other: &Self) -> std::cmp::Ordering {
        self.key.cmp(&other.key)
    }
}

/// The kept chunks of one (kind, query): a max-heap by key and their ray count.
#[derive(Default)]
struct Kept {
    heap: BinaryHeap<Keyed>,
    rays: usize,
}

/// The sample of one (kind, query).
struct Slot {
    kept: Mutex<Kept>,
    /// Chunks with a key at or above this are refused (it only decreases).
    cutoff: AtomicU64,
    /// Rays queried, kept or not.
    seen: AtomicU64,
}

impl Default for Slot {
    fn default() -> Self {
        Slot {
            kept: Mutex::default(),
            cutoff: AtomicU64::new(u64::MAX),
            seen: AtomicU64::new(0),
        }
    }
}

/// A backend whose queries are sampled as they pass (see the module docs).
pub struct Recording {
    backend: Accel,
    capacity: usize,
    seed: u64,
    /// One per (kind, query), in `RayKind::ALL` x `Query::ALL` order.
    slots: Vec<Slot>,
}

/// The rays recorded of one kind and query.
#[derive(Clone, Debug)]
pub struct RaySet {
    pub kind: RayKind,
    pub query: Query,
    /// The kept rays, chunk by chunk in key order (each chunk in the order it was cast).
    pub rays: Vec<Ray>,
    /// Rays of this kind and query the render cast, kept or not.
    pub seen: u64,
}

/// What a recording kept: one set per (kind, query) the render used.
#[derive(Clone, Debug, Default)]
pub struct RecordedRays {
    pub sets: Vec<RaySet>,
}

impl RecordedRays {
    /// The recorded rays of `kind` cast with `query` (empty when there were none).
    pub fn get(&self, kind: RayKind, query: Query) -> &[Ray] {
        self.sets
            .iter()
            .find(|s| s.kind == kind && s.query == query)
            .map_or(&[], |s| &s.rays)
    }
}

/// The sampling key of a chunk.
fn chunk_key(seed: u64, kind: RayKind, query: Query, rays: &[Ray]) -> u64 {
    let bits = |a: f32, b: f32| (a.to_bits() as u64) << 32 | b.to_bits() as u64;
    let start = hash(&[seed, kind as u64, query as u64, rays.len() as u64]);
    rays.iter().fold(start, |h, r| {
        [
            bits(r.o.x, r.o.y),
            bits(r.o.z, r.d.x),
            bits(r.d.y, r.d.z),
            bits(r.tmin, r.tmax),
        ]
        .iter()
        .fold(h, |h, &w| mix64(h ^ w))
    })
}

impl Recording {
    /// Records up to `capacity` rays per (kind, query) of the queries `backend` answers,
    /// choosing them with `seed`.
    pub fn new(backend: Accel, capacity: usize, seed: u64) -> Recording {
        let n = RayKind::ALL.len() * Query::ALL.len();
        Recording {
            backend,
            capacity,
            seed,
            slots: (0..n).map(|_| Slot::default()).collect(),
        }
    }

    fn slot(&self, kind: RayKind, query: Query) -> &Slot {
        &self.slots[kind as usize * Query::ALL.len() + query as usize]
    }

    /// Offers the rays of one call to the sample.
    pub fn record(&self, kind: RayKind, query: Query, rays: &[Ray]) {
        let slot = self.slot(kind, query);
        slot.seen.fetch_add(rays.len() as u64, Ordering::Relaxed);
        if self.capacity == 0 {
            return;
        }
        for chunk in rays.chunks(CHUNK.min(self.capacity)) {
            self.offer(slot, chunk_key(self.seed, kind, query, chunk), chunk);
        }
    }

    /// Keeps `rays` under `key` if it is below the cutoff, then drops the chunks of largest
    /// key (all chunks of that key at once, so ties cannot depend on order) until the kept rays
    /// fit the capacity, lowering the cutoff to the dropped key.
    fn offer(&self, slot: &Slot, key: u64, rays: &[Ray]) {
        if key >= slot.cutoff.load(Ordering::Relaxed) {
            return;
        }
        let mut kept = slot.kept.lock().unwrap_or_else(PoisonError::into_inner);
        if key >= slot.cutoff.load(Ordering::Relaxed) {
            return;
        }
        kept.rays += rays.len();
        kept.heap.push(Keyed {
            key,
            rays: rays.to_vec(),
        });
        while kept.rays > self.capacity {
            let Some(top) = kept.heap.peek().map(|k| k.key) else {
                break;
            };
            while kept.heap.peek().is_some_and(|k| k.key == top) {
                if let Some(k) = kept.heap.pop() {
                    kept.rays -= k.rays.len();
                }
            }
            slot.cutoff.store(top, Ordering::Relaxed);
        }
    }

    /// The backend and the recorded rays of every (kind, query) that was queried.
    pub fn finish(self) -> (Accel, RecordedRays) {
        let mut sets = Vec::new();
        for kind in RayKind::ALL {
            for query in Query::ALL {
                let slot = self.slot(kind, query);
                let seen = slot.seen.load(Ordering::Relaxed);
                if seen == 0 {
                    continue;
                }
                let kept =
                    std::mem::take(&mut *slot.kept.lock().unwrap_or_else(PoisonError::into_inner));
                let rays = kept
                    .heap
                    .into_sorted_vec()
                    .into_iter()
                    .flat_map(|k| k.rays)
                    .collect();
                sets.push(RaySet {
                    kind,
                    query,
                    rays,
                    seen,
                });
            }
        }
        (self.backend, RecordedRays { sets })
    }

    #[inline]
    pub fn intersect(&self, kind: RayKind, ray: &Ray) -> Option<Hit> {
        self.record(kind, Query::Closest, std::slice::from_ref(ray));
        self.backend.intersect(kind, ray)
    }

    #[inline]
    pub fn occluded(&self, kind: RayKind, ray: &Ray) -> bool {
        self.record(kind, Query::Occlusion, std::slice::from_ref(ray));
        self.backend.occluded(kind, ray)
    }

    pub fn intersect_batch(&self, kind: RayKind, rays: &[Ray], out: &mut [Option<Hit>]) {
        self.record(kind, Query::Closest, rays);
        self.backend.intersect_batch(kind, rays, out)
    }

    pub fn occluded_batch(&self, kind: RayKind, rays: &[Ray], out: &mut [bool]) {
        self.record(kind, Query::Occlusion, rays);
        self.backend.occluded_batch(kind, rays, out)
    }

    /// The wrapped backend.
    pub fn backend(&self) -> &Accel {
        &self.backend
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::Vec3;

    fn ray(i: u32) -> Ray {
        Ray::new(Vec3::new(i as f32, 0.0, 0.0), Vec3::Z)
    }

    /// A recording over a backend no query reaches (only `record` is called).
    fn recording(capacity: usize) -> Recording {
        let scene = crate::scene::generate::sphere_scene(10);
        let backend = Accel::build(&scene, super::super::BackendKind::Obvhs, Default::default())
            .expect("obvhs builds");
        Recording::new(backend, capacity, 7)
    }

    /// The kept set is the bottom-k by key of all chunks offered, whatever the order: checked
    /// against sorting every chunk's key (an independent computation of the same sample).
    #[test]
    fn sample_is_the_smallest_keys_in_any_order() {
        let chunks: Vec<Vec<Ray>> = (0..300)
            .map(|i| (0..1 + i % 7).map(|j| ray(i * 10 + j)).collect())
            .collect();
        let cap = 200;
        let mut keyed: Vec<(u64, &Vec<Ray>)> = chunks
            .iter()
            .map(|c| (chunk_key(7, RayKind::Photon, Query::Closest, c), c))
            .collect();
        keyed.sort_by_key(|k| k.0);
        let mut want = Vec::new();
        for (_, c) in &keyed {
            if want.len() + c.len() > cap {
                break;
            }
            want.extend(c.iter().copied());
        }
        for order in [false, true] {
            let r = recording(cap);
            let mut idx: Vec<usize> = (0..chunks.len()).collect();
            if order {
                idx.reverse();
            }
            for i in idx {
                r.record(RayKind::Photon, Query::Closest, &chunks[i]);
            }
            let (_, got) = r.finish();
            assert_eq!(got.sets.len(), 1);
            assert_eq!(
                got.sets[0].seen,
                chunks.iter().map(|c| c.len() as u64).sum::<u64>()
            );
            assert_eq!(got.get(RayKind::Photon, Query::Closest), &want[..]);
            assert!(want.len() <= cap && want.len() > cap - 7);
        }
    }

    /// Batches are cut into chunks of at most CHUNK rays; kinds and queries are kept apart.
    #[test]
    fn batches_are_chunked_and_kinds_separate() {
        let r = recording(10_000);
        let batch: Vec<Ray> = (0..1000).map(ray).collect();
        r.record(RayKind::Camera, Query::Closest, &batch);
        r.record(RayKind::Shadow, Query::Occlusion, &batch[..5]);
        let (_, got) = r.finish();
        let cam = got.get(RayKind::Camera, Query::Closest);
        assert_eq!(cam.len(), 1000);
        // Runs of consecutive rays that break only where a chunk of the call starts.
        let mut sorted: Vec<u32> = cam.iter().map(|r| r.o.x as u32).collect();
        let breaks: Vec<u32> = sorted
            .windows(2)
            .filter(|w| w[1] != w[0] + 1)
            .map(|w| w[1])
            .collect();
        assert!(breaks.len() <= 3);
        assert!(
            breaks.iter().all(|b| (*b as usize).is_multiple_of(CHUNK)),
            "{breaks:?}"
        );
        sorted.sort_unstable();
        assert_eq!(sorted, (0..1000).collect::<Vec<_>>());
        assert_eq!(got.get(RayKind::Shadow, Query::Occlusion).len(), 5);
        assert!(got.get(RayKind::Shadow, Query::Closest).is_empty());
        assert_eq!(got.sets.len(), 2);
    }
}
