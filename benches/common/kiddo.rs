//! `kiddo` as the k-nearest baseline of `photon bench` (shared by `benches/photon.rs` and
//! `tests/it/bench.rs`; kiddo is a dev-dependency, so the library cannot name it).
use kiddo::{ImmutableKdTree, SquaredEuclidean};
use photon::math::Vec3;
use photon::tools::bench::KnnBaseline;
use std::num::NonZeroUsize;

/// kiddo's `ImmutableKdTree` over the benchmark's points.
#[derive(Default)]
pub struct Kiddo {
    tree: Option<ImmutableKdTree<f32, 3>>,
}

impl KnnBaseline for Kiddo {
    fn name(&self) -> &str {
        "kiddo"
    }

    fn build(&mut self, points: &[Vec3]) {
        let arr: Vec<[f32; 3]> = points.iter().map(|p| p.to_array()).collect();
        self.tree = ImmutableKdTree::new_from_slice(&arr).ok();
    }

    fn kth_d2(&self, q: Vec3, k: usize) -> f32 {
        let (Some(tree), Some(k)) = (&self.tree, NonZeroUsize::new(k)) else {
            return f32::INFINITY;
        };
        let found = tree
            .query(&q.to_array())
            .nearest_n::<SquaredEuclidean<f32>>(k)
            .execute();
        match found.last() {
            Some(r) if found.len() == k.get() => r.distance,
            _ => f32::INFINITY,
        }
    }
}
