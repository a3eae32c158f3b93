//! A triangle mesh in world space, as the loader builds it and every layer reads it (a leaf
//! beside `math`: the scene, the lights and the ray-query backends share it).
use crate::math::{Vec2, Vec3};
use std::sync::Arc;

/// Bytes each mesh costs beyond its triangles (the `Mesh` and its vectors' headers, the
/// loader's record of where it was written, the backend's per-geometry objects). Measured:
/// see BENCHMARKS.md ("Memory per mesh"); used by [`crate::memory`] and the loader's budget.
pub const MESH_OVERHEAD_BYTES: u64 = 768;

/// A triangle mesh in world space.
#[derive(Clone, Debug, Default)]
pub struct Mesh {
    pub positions: Vec<Vec3>,
    /// Per-vertex shading normals (world space, unit length), if the scene gave them.
    pub normals: Option<Vec<Vec3>>,
    pub uvs: Option<Vec<Vec2>>,
    pub indices: Vec<[u32; 3]>,
    /// Index into `Scene::materials`.
    pub material: u32,
    /// Index into `Scene::lights` of the `Light::Area` this mesh emits as, if any.
    pub area_light: Option<u32>,
    /// `ReverseOrientation` xor a handedness-swapping transform: flips the geometric normal
    /// (pbrt's rule; only matters when the mesh has no shading normals to agree with).
    pub flip_normals: bool,
    /// The analytic sphere (centre, radius) this mesh tessellates, for `Shape "sphere"`.
    pub sphere: Option<(Vec3, f32)>,
    /// The shape's `alpha` (a float texture, or a constant below 1): a hit where it evaluates
    /// to `a < 1` is kept only with probability `a` (see [`crate::accel::alpha_keeps`]).
    /// `None`: opaque.
    pub alpha: Option<Arc<crate::texture::Texture>>,
    /// The media this surface separates (`MediumInterface` with two different media), if
    /// any: see [`crate::medium`].
    pub interface: Option<crate::medium::MediumInterface>,
}

/// The uvs of a triangle's vertices (indices `tri`): from `uvs`, or without them pbrt-v4's
/// default (0, 0), (1, 0), (1, 1) (`Triangle::InteractionFromIntersection`).
#[inline]
pub fn triangle_uvs(uvs: Option<&[Vec2]>, tri: [u32; 3]) -> [Vec2; 3] {
    match uvs {
        Some(uvs) => tri.map(|i| uvs[i as usize]),
        None => [Vec2::ZERO, Vec2::X, Vec2::ONE],
    }
}

/// Texture coordinates at barycentrics `(u, v)` (weights `1-u-v, u, v`) of the triangle with
/// vertex indices `tri`, from [`triangle_uvs`]: `(u + v, v)` without `uvs`. The one place
/// shading and the alpha test compute a hit's uv.
#[inline]
pub fn interpolate_uv(uvs: Option<&[Vec2]>, tri: [u32; 3], u: f32, v: f32) -> Vec2 {
    let [a, b, c] = triangle_uvs(uvs, tri);
    a * (1.0 - u - v) + b * u + c * v
}

impl Mesh {
    /// Bytes a copy of this mesh holds (its arrays plus [`MESH_OVERHEAD_BYTES`]): what an
    /// `ObjectInstance` of it allocates in the loader.
    pub fn bytes(&self) -> u64 {
        let v = self.positions.len() as u64;
        MESH_OVERHEAD_BYTES
            + v * 12
            + self.normals.as_ref().map_or(0, |n| n.len() as u64 * 12)
            + self.uvs.as_ref().map_or(0, |u| u.len() as u64 * 8)
            + self.indices.len() as u64 * 12
    }

    pub fn triangle(&self, prim: u32) -> [Vec3; 3] {
        let [a, b, c] = self.indices[prim as usize];
        [
            self.positions[a as usize],
            self.positions[b as usize],
            self.positions[c as usize],
        ]
    }

    /// pbrt's geometric normal of triangle `prim`: `cross(p1 - p0, p2 - p0)` normalised, turned
    /// to agree with the interpolated shading normal when there is one, else flipped by
    /// `flip_normals`. Area lights emit on this side.
    pub fn geometric_normal(&self, prim: u32, u: f32, v: f32) -> Vec3 {
        let [p0, p1, p2] = self.triangle(prim);
        let n = (p1 - p0).cross(p2 - p0).normalize_or_zero();
        match self.shading_normal(prim, u, v) {
            Some(ns) if n.dot(ns) < 0.0 => -n,
            Some(_) => n,
            None if self.flip_normals => -n,
            None => n,
        }
    }

    /// The surface point at barycentrics `(u, v)` of triangle `prim`, interpolated from the
    /// vertices. Use this rather than `ray.o + t ray.d` for hit points: its error is relative to
    /// the vertices' own magnitude, which is what the robust ray-origin offset
    /// ([`crate::math::spawn_origin`]) assumes; `o + t d` is off by up to ~1e-7 of the ray's
    /// coordinates, which defeats the offset in large scenes.
    pub fn point(&self, prim: u32, u: f32, v: f32) -> Vec3 {
        let [p0, p1, p2] = self.triangle(prim);
        p0 * (1.0 - u - v) + p1 * u + p2 * v
    }

    /// A conservative bound on the rounding error of each component of
    /// [`Self::point`]`(prim, u, v)` (pbrt-v4: `gamma(7) (|b0 p0| + |b1 p1| + |b2 p2|)`).
    pub fn point_error(&self, prim: u32, u: f32, v: f32) -> Vec3 {
        let [p0, p1, p2] = self.triangle(prim);
        let sum = (p0 * (1.0 - u - v)).abs() + (p1 * u).abs() + (p2 * v).abs();
        sum * crate::math::gamma(7)
    }

    /// The origin of a ray leaving the surface at barycentrics `(u, v)` of triangle `prim`
    /// towards the side of `n` (flip the normal for transmission): the interpolated point,
    /// moved past its error bound (see [`crate::math::spawn_origin`]).
    pub fn spawn(&self, prim: u32, u: f32, v: f32, n: Vec3) -> Vec3 {
        crate::math::spawn_origin(self.point(prim, u, v), self.point_error(prim, u, v), n)
    }

    /// The texture coordinates at barycentrics `(u, v)` of triangle `prim` (see
    /// [`interpolate_uv`]).
    pub fn uv(&self, prim: u32, u: f32, v: f32) -> Vec2 {
        interpolate_uv(self.uvs.as_deref(), self.indices[prim as usize], u, v)
    }

    /// The uvs of triangle `prim`'s vertices (see [`triangle_uvs`]).
    pub fn triangle_uvs(&self, prim: u32) -> [Vec2; 3] {
        triangle_uvs(self.uvs.as_deref(), self.indices[prim as usize])
    }

    /// The interpolated shading normal at barycentrics `(u, v)` (weights `1-u-v, u, v`).
    pub fn shading_normal(&self, prim: u32, u: f32, v: f32) -> Option<Vec3> {
        let normals = self.normals.as_ref()?;
        let [a, b, c] = self.indices[prim as usize];
        let n =
            normals[a as usize] * (1.0 - u - v) + normals[b as usize] * u + normals[c as usize] * v;
        Some(n.normalize_or_zero())
    }

    /// The area of triangle `prim` computed in f64 (exact for any finite f32 vertices).
    pub fn area_f64(&self, prim: u32) -> f64 {
        let [p0, p1, p2] = self.triangle(prim).map(|p| p.as_dvec3());
        0.5 * (p1 - p0).cross(p2 - p0).length()
    }

    pub fn area(&self, prim: u32) -> f32 {
        let [p0, p1, p2] = self.triangle(prim);
        0.5 * (p1 - p0).cross(p2 - p0).length()
    }
}
