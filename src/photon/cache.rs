//! Christensen's precomputed irradiance (1999): the irradiance at every
//! [`CACHE_SPACING`]-th global photon, computed once after pass 1, so that a final-gather hit
//! reads one nearby value instead of running a k-nearest estimate of its own.
//!
//! Each cache point keeps the squared radius of the estimate that made it. A lookup at `p`
//! (normal `n`) takes the nearest point whose normal agrees (`dot > 0.9`) and whose own
//! estimate covered `p`: `t^2 + (h / f)^2 <= r_i^2`, with `t` the distance along the point's
//! tangent plane, `h` the height above it and `f` the estimate's disc fraction (the flattened
//! search of [`super::estimate`]). Without that bound the nearest agreeing point could lie
//! anywhere within the global radius: the inside of a lamp can's wall, lit by the bulb, faces
//! the way of the room wall beside it and served it, and the room wall glowed (measured:
//! BENCHMARKS.md, "Design measurements"). Where no point covers `p`, the caller runs the full
//! estimate.
use super::estimate::{disc_d2, fill, irradiance_by_bounce, EstimateParams};
use super::kdtree::{KdTree, KnnResult, TooManyPoints};
use super::map::PhotonMap;
use crate::math::Vec3;
use rayon::prelude::*;

/// Every `CACHE_SPACING`-th global photon gets a precomputed irradiance.
pub const CACHE_SPACING: usize = 4;

/// Smallest cosine between a cache point's normal and the query's.
const MIN_NORMAL_COS: f32 = 0.9;

/// Bounce limits a cache point keeps an irradiance for (see [`IrradianceCache::build`]): one
/// per gather read point's place in its camera path (behind the camera's specular bounces,
/// the gather's own, thin points passed on), later ones estimated in full. Water-caustic at
/// 128 px, 64 spp (most gathers start behind the water surface): 3 levels 5.91 s, 6 levels
/// 4.51 s.
pub const LEVELS: usize = 6;

/// One cache point: what a lookup reads of it, in one 92-byte record (a lookup's filter
/// touches one record per candidate).
#[derive(Clone, Copy, Debug)]
struct CachePoint {
    normal: Vec3,
    /// Squared radius of the estimate.
    r2: f32,
    /// From the photons within each of the build's bounce limits.
    irradiance: [Vec3; LEVELS],
    /// How much of its disc the estimate's photons filled ([`fill`]).
    fill: f32,
}

/// What a cache lookup returns: the irradiance and how much of its disc the photons behind it
/// filled ([`fill`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Cached {
    pub irradiance: Vec3,
    pub fill: f32,
}

/// Precomputed irradiance at a subset of the photon positions.
pub struct IrradianceCache {
    tree: KdTree,
    /// In the tree's order.
    points: Vec<CachePoint>,
    /// The estimates' [`EstimateParams::stretch`].
    stretch: f32,
}

impl IrradianceCache {
    /// The irradiance at every [`CACHE_SPACING`]-th photon of `global` (a map with normals:
    /// none without), estimated with `params`, once for each bounce limit of `limits`
    /// (level `i` sums the photons stored at bounce `limits[i]` or earlier; `u8::MAX`: all).
    pub fn build(
        global: &PhotonMap,
        params: &EstimateParams,
        limits: [u8; LEVELS],
    ) -> Result<IrradianceCache, TooManyPoints> {
        let (photons, normals) = (global.photons(), global.normals());
        let len = if normals.len() == photons.len() {
            photons.len()
        } else {
            0
        };
        crate::progress::begin("irradiance cache", len.div_ceil(CACHE_SPACING) as u64);
        let (positions, points): (Vec<Vec3>, Vec<CachePoint>) = (0..len)
            .into_par_iter()
            .step_by(CACHE_SPACING)
            .map_init(KnnResult::new, |buf, i| {
                crate::progress::add(1);
                let p = photons[i].pos();
                let normal = normals[i];
                let (irradiance, _, r2) =
                    irradiance_by_bounce(global, p, normal, params, buf, limits);
                let point = CachePoint {
                    normal,
                    r2,
                    irradiance,
                    fill: fill(global, p, normal, r2, buf),
                };
                (p, point)
            })
            .unzip();
        if std::env::var_os("PHOTON_FILL_HIST").is_some() {
            let mut h = [0usize; 10];
            for c in &points {
                h[((c.fill * 10.0) as usize).min(9)] += 1;
            }
            eprintln!("fill histogram (0.1 bins): {h:?}");
        }
        let (tree, order) = KdTree::build(&positions)?;
        let points = order.iter().map(|&i| points[i as usize]).collect();
        Ok(IrradianceCache {
            tree,
            points,
            stretch: params.stretch(),
        })
    }

    /// Number of cache points.
    pub fn len(&self) -> usize {
        self.points.len()
    }

    pub fn is_empty(&self) -> bool {
        self.points.is_empty()
    }

    /// The irradiance (of bounce limit `level`, see [`Self::build`]; at most `LEVELS - 1`) of
    /// the nearest cache point within `max_r2` of `p` whose normal agrees with `n` and whose
    /// own estimate covered `p` (see the module docs); `None` when there is none.
    pub fn lookup(
        &self,
        p: Vec3,
        n: Vec3,
        max_r2: f32,
        level: usize,
        buf: &mut KnnResult,
    ) -> Option<Cached> {
        let (points, stretch) = (&self.points[..], self.stretch);
        self.tree.knn_by(p, 1, max_r2, buf, |i, off, d2| {
            let c = &points[i as usize];
            if c.normal.dot(n) <= MIN_NORMAL_COS {
                return None;
            }
            (disc_d2(stretch, d2, off.dot(c.normal)) <= c.r2).then_some(d2)
        });
        let nb = buf.neighbors().first()?;
        let c = &self.points[nb.idx as usize];
        Some(Cached {
            irradiance: c.irradiance[level.min(LEVELS - 1)],
            fill: c.fill,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::photon::estimate::irradiance_with;
    use crate::photon::Photon;

    /// `n x n` photons of `power` on the square `[0, side]^2` at height `z`, arriving from
    /// above, facing `+z`.
    fn grid(n: usize, side: f32, z: f32, x0: f32, power: f32) -> Vec<Photon> {
        let cell = side / n as f32;
        let mut out = Vec::new();
        for i in 0..n {
            for j in 0..n {
                let p = Vec3::new(x0 + (i as f32 + 0.5) * cell, (j as f32 + 0.5) * cell, z);
                out.push(Photon::new(p, Vec3::splat(power), -Vec3::Z, 0));
            }
        }
        out
    }

    /// Two parallel surfaces facing the same way, 0.1 apart (a wall and the inside of a lamp
    /// can beside it): the wall dim and sparse, the can's inside bright and dense. A point on
    /// the wall under the can must read the wall's irradiance, not the can's: the nearest
    /// normal-agreeing cache point is the can's (0.1 away), whose estimate did not cover it.
    #[test]
    fn a_point_reads_only_a_cache_point_whose_estimate_covered_it() {
        let wall = grid(20, 2.0, 0.0, 0.0, 0.01);
        let can = grid(40, 0.5, 0.1, 0.75, 1.0);
        let photons: Vec<Photon> = wall.iter().chain(&can).copied().collect();
        let global = PhotonMap::with_normals(&photons, |_| Vec3::Z).unwrap();
        let params = EstimateParams::new(20, 1.0);
        let cache = IrradianceCache::build(&global, &params, [u8::MAX; LEVELS]).unwrap();
        let mut buf = KnnResult::new();
        let p = Vec3::new(1.0, 0.25, 0.0);
        let (wall_e, _, _) = irradiance_with(&global, p, Vec3::Z, &params, &mut buf);
        let e = cache
            .lookup(p, Vec3::Z, 1.0, 0, &mut buf)
            .expect("a wall cache point covers p")
            .irradiance;
        // The wall alone: 400 photons of 0.01 over 4 m^2 = 1.0; the can: 1600 of 1.0 over
        // 0.25 m^2 = 6400.
        assert!((wall_e.x - 1.0).abs() < 0.25, "full estimate {wall_e:?}");
        assert!(
            (e.x - 1.0).abs() < 0.25,
            "cached {e:?} (the can reads 6400)"
        );
        // On the can itself, the can's own value.
        let q = Vec3::new(1.0, 0.25, 0.1);
        let e = cache
            .lookup(q, Vec3::Z, 1.0, 0, &mut buf)
            .expect("covered")
            .irradiance;
        assert!(e.x > 3000.0, "on the can {e:?}");
    }
}
