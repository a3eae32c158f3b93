//! The pure-Rust backend: one obvhs compressed wide BVH (CWBVH, 8-wide) over the triangles of
//! all meshes, for cross-checking Embree and for benchmarking.
//!
//! - All meshes' triangles go into one flat array; zero-area triangles (exactly zero
//!   `cross(p1 - p0, p2 - p0)`) are left out, as no ray can hit them. After the build the
//!   triangles are re-laid out in the BVH's `primitive_indices` order, so the slot obvhs hands
//!   to the intersection callback indexes our arrays directly; a table maps each slot back to
//!   `(mesh, prim)`.
//! - Triangles are tested with our own Möller–Trumbore-style test in Embree's conventions:
//!   `t` in `(tmin, tmax]`, barycentrics `p = (1-u-v) p0 + u p1 + v p2`, and a triangle whose
//!   normal is exactly zero never hits.
//! - Alpha cut-outs (see [`super`]): a candidate hit on a mesh with alpha that
//!   [`AlphaMask::keeps`] rejects is answered as a miss inside obvhs's per-primitive callback,
//!   so traversal goes on to the next-closest candidate (and an occlusion query to the next
//!   candidate at all). Scenes without alpha run a copy of the traversal compiled without the
//!   test.
//! - obvhs's node test clamps the entry distance to `1e-4` (in units of the ray direction),
//!   which would cull boxes lying entirely closer than that. We therefore hand obvhs the ray
//!   with its origin moved back by [`ORIGIN_SHIFT`] along the direction (and the interval moved
//!   forward by the same amount), while triangles are still tested against the caller's ray.
//!   Likewise `-0.0` direction components are handed to obvhs as `+0.0` (see `traversal_ray`).
//!
//! ## Build preset
//! [`BvhAccel::build`] uses [`BvhBuildParams::slow_build`]: its spatial splits trace scenes with
//! long triangles (walls, floors) several times faster than the fast presets, and the best
//! preset gains little for twice the build time (measured: BENCHMARKS.md, "Design
//! measurements", and `tests/it/backends.rs` `obvhs_presets`).
use super::{
    face_normals, query_interval, validate_meshes, AccelError, AccelOptions, AlphaMask, Hit,
    RayQuery,
};
use crate::math::{Ray, Vec3};
use crate::scene::Scene;
use glam::Vec3A;
use obvhs::cwbvh::builder::build_cwbvh_from_tris;
use obvhs::cwbvh::CwBvh;
use obvhs::ray::{Ray as ORay, RayHit};
use obvhs::triangle::Triangle;
use obvhs::BvhBuildParams;
use std::sync::Arc;
use std::time::Duration;

/// How far (in units of the ray direction) the origin of the ray handed to obvhs is moved
/// back, ten times obvhs's node-test epsilon of `1e-4`.
pub const ORIGIN_SHIFT: f32 = 1e-3;

/// A triangle as the intersection test wants it: `v0` and the edges `a = v1 - v0`,
/// `b = v2 - v0`.
#[derive(Clone, Copy, Debug)]
struct Tri {
    v0: Vec3A,
    a: Vec3A,
    b: Vec3A,
}

/// Which scene triangle a BVH slot holds, and its unit geometric normal.
#[derive(Clone, Copy, Debug)]
struct Prim {
    mesh: u32,
    prim: u32,
    ng: Vec3,
}

/// A ray-triangle hit: distance and barycentrics of `v1` and `v2`.
#[derive(Clone, Copy, Debug)]
struct TriHit {
    t: f32,
    u: f32,
    v: f32,
}

impl Tri {
    fn new(p0: Vec3, p1: Vec3, p2: Vec3) -> Tri {
        Tri {
            v0: p0.into(),
            a: (p1 - p0).into(),
            b: (p2 - p0).into(),
        }
    }

    /// Solves `o + t d = v0 + u a + v b` by Cramer's rule. Accepts `u, v >= 0`, `u + v <= 1`
    /// and `t` in `(tmin, tmax]`. With `n = a x b`: `den = -d.n`, `t = s.n / den`,
    /// `u = b.q / den`, `v = -a.q / den` where `s = o - v0`, `q = s x d`. A zero `n` (zero
    /// area) gives `den == 0`: no hit.
    #[inline(always)]
    fn intersect(&self, o: Vec3A, d: Vec3A, tmin: f32, tmax: f32) -> Option<TriHit> {
        let n = self.a.cross(self.b);
        let den = -d.dot(n);
        if den == 0.0 {
            return None;
        }
        let inv = 1.0 / den;
        let s = o - self.v0;
        let q = s.cross(d);
        let u = self.b.dot(q) * inv;
        let v = -self.a.dot(q) * inv;
        let t = s.dot(n) * inv;
        let inside = u >= 0.0 && v >= 0.0 && u + v <= 1.0;
        (inside && t > tmin && t <= tmax).then_some(TriHit { t, u, v })
    }
}

/// The obvhs backend.
pub struct BvhAccel {
    /// `None` when the scene has no triangle that can be hit.
    bvh: Option<CwBvh>,
    /// `tris[slot]`: the triangle in BVH slot `slot` (`primitive_indices` order).
    tris: Vec<Tri>,
    /// `prims[slot]`: where that triangle comes from.
    prims: Vec<Prim>,
    /// Alpha masks by mesh index; `None` when no mesh has alpha.
    alpha: Option<Vec<Option<Arc<AlphaMask>>>>,
}

impl BvhAccel {
    /// Builds over every mesh of `scene` with [`BvhBuildParams::slow_build`] (see the module
    /// documentation). `opts` is ignored: obvhs has no robust mode.
    pub fn build(scene: &Scene, opts: AccelOptions) -> Result<Self, AccelError> {
        let _ = opts;
        Self::build_with(scene, BvhBuildParams::slow_build())
    }

    /// Builds over every mesh of `scene` with the obvhs preset or parameters `params`.
    pub fn build_with(scene: &Scene, params: BvhBuildParams) -> Result<Self, AccelError> {
        validate_meshes(scene)?;
        let (flat, ids) = flatten(scene)?;
        if flat.is_empty() {
            return Ok(BvhAccel {
                bvh: None,
                tris: Vec::new(),
                prims: Vec::new(),
                alpha: None,
            });
        }
        let obvhs_tris: Vec<Triangle> = flat
            .iter()
            .map(|t| Triangle {
                v0: t.v0,
                v1: t.v0 + t.a,
                v2: t.v0 + t.b,
            })
            .collect();
        let mut core_time = Duration::ZERO;
        let bvh = build_cwbvh_from_tris(&obvhs_tris, params, &mut core_time);
        let mut tris = Vec::with_capacity(bvh.primitive_indices.len());
        let mut prims = Vec::with_capacity(bvh.primitive_indices.len());
        for &i in &bvh.primitive_indices {
            let i = i as usize;
            let (Some(t), Some(p)) = (flat.get(i), ids.get(i)) else {
                return Err(AccelError(format!(
                    "obvhs: primitive index {i} out of range"
                )));
            };
            tris.push(*t);
            prims.push(*p);
        }
        Ok(BvhAccel {
            bvh: Some(bvh),
            tris,
            prims,
            alpha: AlphaMask::of_scene(scene),
        })
    }

    /// Number of triangles in the BVH (slots; spatial splits may repeat a triangle).
    pub fn slot_count(&self) -> usize {
        self.tris.len()
    }

    /// Whether the hit `h` on the triangle in `slot` counts for the ray `(o, d)`: always,
    /// unless its mesh has an alpha mask that rejects it.
    #[inline(always)]
    fn keeps(&self, slot: usize, h: &TriHit, o: Vec3, d: Vec3) -> bool {
        let Some(masks) = &self.alpha else {
            return true;
        };
        let p = self.prims[slot];
        match masks.get(p.mesh as usize) {
            Some(Some(mask)) => mask.keeps(p.prim, h.u, h.v, o, d),
            _ => true,
        }
    }

    fn to_hit(&self, slot: usize, h: TriHit) -> Hit {
        let p = self.prims[slot];
        Hit {
            t: h.t,
            mesh: p.mesh,
            prim: p.prim,
            u: h.u,
            v: h.v,
            ng: p.ng,
        }
    }
}

/// All hittable triangles of `scene` in one array, with their `(mesh, prim)` and normal.
fn flatten(scene: &Scene) -> Result<(Vec<Tri>, Vec<Prim>), AccelError> {
    let mut tris = Vec::with_capacity(scene.triangle_count());
    let mut prims = Vec::with_capacity(scene.triangle_count());
    for (m, mesh) in scene.meshes.iter().enumerate() {
        let normals = face_normals(mesh);
        for (p, ng) in normals.into_iter().enumerate() {
            let [p0, p1, p2] = mesh.triangle(p as u32);
            let tri = Tri::new(p0, p1, p2);
            if tri.a.cross(tri.b) == Vec3A::ZERO {
                continue;
            }
            let (Ok(mesh), Ok(prim)) = (u32::try_from(m), u32::try_from(p)) else {
                return Err(AccelError(
                    "obvhs: more than 2^32 meshes or triangles".into(),
                ));
            };
            tris.push(tri);
            prims.push(Prim { mesh, prim, ng });
        }
    }
    if tris.len() >= u32::MAX as usize {
        return Err(AccelError("obvhs: more than 2^32 - 1 triangles".into()));
    }
    Ok((tris, prims))
}

/// The ray handed to obvhs: origin moved back by [`ORIGIN_SHIFT`], interval `[0, tmax + shift]`,
/// and `-0.0` direction components turned into `+0.0`: obvhs picks a node's slab order from
/// `d < 0` (false for `-0.0`) but inverts `-0.0` to a large *negative* value, which makes every
/// box miss (a ray along `-z` exactly, say).
#[inline]
fn traversal_ray(o: Vec3A, d: Vec3A, tmax: f32) -> ORay {
    let d = d + Vec3A::ZERO;
    ORay::new(o - d * ORIGIN_SHIFT, d, 0.0, tmax + ORIGIN_SHIFT)
}

impl BvhAccel {
    /// The closest hit that `keep(slot, hit)` accepts; rejected candidates leave the interval
    /// as it was, so traversal goes on to the next one.
    #[inline(always)]
    fn closest(&self, ray: &Ray, keep: impl Fn(usize, &TriHit) -> bool) -> Option<Hit> {
        let bvh = self.bvh.as_ref()?;
        let (tmin, tmax) = query_interval(ray)?;
        let (o, d) = (Vec3A::from(ray.o), Vec3A::from(ray.d));
        let mut best: Option<(usize, TriHit)> = None;
        let mut cur_tmax = tmax;
        let mut unused = RayHit::none();
        bvh.ray_traverse(
            traversal_ray(o, d, tmax),
            &mut unused,
            |_, slot| match self.tris[slot].intersect(o, d, tmin, cur_tmax) {
                Some(h) if keep(slot, &h) => {
                    cur_tmax = h.t;
                    best = Some((slot, h));
                    h.t + ORIGIN_SHIFT
                }
                _ => f32::INFINITY,
            },
        );
        best.map(|(slot, h)| self.to_hit(slot, h))
    }

    /// Whether any hit that `keep(slot, hit)` accepts lies in the ray's interval.
    #[inline(always)]
    fn any(&self, ray: &Ray, keep: impl Fn(usize, &TriHit) -> bool) -> bool {
        let (Some(bvh), Some((tmin, tmax))) = (self.bvh.as_ref(), query_interval(ray)) else {
            return false;
        };
        let (o, d) = (Vec3A::from(ray.o), Vec3A::from(ray.d));
        // Any hit stops the traversal: report it as distance 0, inside every interval.
        !bvh.ray_traverse_miss(traversal_ray(o, d, tmax), |_, slot| {
            match self.tris[slot].intersect(o, d, tmin, tmax) {
                Some(h) if keep(slot, &h) => 0.0,
                _ => f32::INFINITY,
            }
        })
    }
}

/// Without alpha the traversal is compiled with an always-true test (the code of a scene
/// without alpha is the code before alpha existed); with alpha, `BvhAccel::keeps`.
impl RayQuery for BvhAccel {
    fn intersect(&self, ray: &Ray) -> Option<Hit> {
        match self.alpha {
            None => self.closest(ray, |_, _| true),
            Some(_) => self.closest(ray, |slot, h| self.keeps(slot, h, ray.o, ray.d)),
        }
    }

    fn occluded(&self, ray: &Ray) -> bool {
        match self.alpha {
            None => self.any(ray, |_, _| true),
            Some(_) => self.any(ray, |slot, h| self.keeps(slot, h, ray.o, ray.d)),
        }
    }
}
