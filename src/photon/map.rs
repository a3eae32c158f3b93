//! [`PhotonMap`]: photons stored in kd-tree order beside the [`KdTree`] over their positions.
use super::kdtree::{KdTree, KnnResult, TooManyPoints};
use super::stored::Photon;
use crate::math::Vec3;

/// A built photon map. Indices in query results are tree-order slots into [`Self::photons`].
#[derive(Clone, Debug, Default)]
pub struct PhotonMap {
    tree: KdTree,
    photons: Vec<Photon>,
    /// For each tree-order slot, the index of the photon in the input slice.
    order: Vec<u32>,
    /// Surface normal at each photon (facing the side it arrived from), in tree order; empty
    /// when the map was built without them.
    normals: Vec<Vec3>,
}

impl PhotonMap {
    /// Builds the map. Photons with non-finite positions are dropped.
    pub fn new(photons: &[Photon]) -> Result<Self, TooManyPoints> {
        let points: Vec<Vec3> = photons.iter().map(Photon::pos).collect();
        let (tree, order) = KdTree::build(&points)?;
        let photons = order.iter().map(|&i| photons[i as usize]).collect();
        Ok(PhotonMap {
            tree,
            photons,
            order,
            normals: Vec::new(),
        })
    }

    /// Builds the map with the surface normal at each photon (`normal(i)` for `photons[i]`,
    /// facing the side the photon arrived from), for the irradiance cache's points.
    pub fn with_normals(
        photons: &[Photon],
        normal: impl Fn(usize) -> Vec3,
    ) -> Result<Self, TooManyPoints> {
        let mut map = PhotonMap::new(photons)?;
        map.normals = map.order.iter().map(|&i| normal(i as usize)).collect();
        Ok(map)
    }

    /// The surface normals in tree order (empty without normals).
    pub fn normals(&self) -> &[Vec3] {
        &self.normals
    }

    /// For each tree-order slot, the index of its photon in the slice given to [`Self::new`]
    /// (to carry per-photon data along).
    pub fn order(&self) -> &[u32] {
        &self.order
    }

    /// Number of stored photons.
    pub fn len(&self) -> usize {
        self.photons.len()
    }

    pub fn is_empty(&self) -> bool {
        self.photons.is_empty()
    }

    /// A map (without normals) of the photons for which `keep` holds; `None` when there are
    /// none.
    pub fn subset(&self, keep: impl Fn(&Photon) -> bool) -> Option<PhotonMap> {
        let photons: Vec<Photon> = self.photons.iter().filter(|p| keep(p)).copied().collect();
        if photons.is_empty() {
            return None;
        }
        PhotonMap::new(&photons).ok()
    }

    /// The photons in tree order.
    pub fn photons(&self) -> &[Photon] {
        &self.photons
    }

    /// The photon in tree-order slot `idx` (from a query result).
    pub fn photon(&self, idx: u32) -> &Photon {
        &self.photons[idx as usize]
    }

    /// The underlying tree.
    pub fn tree(&self) -> &KdTree {
        &self.tree
    }

    /// The up-to-`k` photons nearest to `p` within squared radius `max_r2`, into `out`.
    pub fn knn(&self, p: Vec3, k: usize, max_r2: f32, out: &mut KnnResult) {
        self.tree.knn(p, k, max_r2, out);
    }

    /// k-nearest with a per-photon metric: `metric(photon, offset = photon.pos - p, d2)`
    /// returns the ranking distance (raised to at least `d2`) or `None` to skip the photon.
    /// See [`KdTree::knn_by`].
    pub fn knn_by<F>(&self, p: Vec3, k: usize, max_r2: f32, out: &mut KnnResult, mut metric: F)
    where
        F: FnMut(&Photon, Vec3, f32) -> Option<f32>,
    {
        let photons = &self.photons[..];
        self.tree.knn_by(p, k, max_r2, out, |i, off, d2| {
            metric(&photons[i as usize], off, d2)
        });
    }

    /// Calls `f(photon, d2)` for every photon within squared distance `r2` of `p`.
    pub fn radius_query<F>(&self, p: Vec3, r2: f32, mut f: F)
    where
        F: FnMut(&Photon, f32),
    {
        let photons = &self.photons[..];
        self.tree
            .radius_query(p, r2, |i, d2| f(&photons[i as usize], d2));
    }
}
