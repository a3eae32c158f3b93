//! Diffuse area light on a triangle mesh: `AreaLightSource "diffuse"`.
//!
//! Points are sampled uniformly by area (a triangle in proportion to its area, then a uniform
//! point on it), so the solid-angle density seen from `p` is `d^2 / (|cos theta_l| A)`.
use super::{scalar_power, LightSample};
use crate::math::{Vec2, Vec3};
use crate::sampling::warp::{square_to_triangle, Distribution1D};
use crate::scene::Mesh;
use std::f32::consts::PI;

#[derive(Clone, Debug)]
pub struct AreaLight {
    pub mesh: u32,
    pub l: Vec3,
    pub two_sided: bool,
    triangles: Distribution1D,
    area: f32,
}

impl AreaLight {
    pub fn new(mesh: &Mesh, index: u32, l: Vec3, two_sided: bool) -> AreaLight {
        let areas: Vec<f32> = (0..mesh.indices.len() as u32)
            .map(|t| mesh.area(t))
            .collect();
        let triangles = Distribution1D::new(&areas);
        AreaLight {
            mesh: index,
            l,
            two_sided,
            area: triangles.total(),
            triangles,
        }
    }

    pub fn area(&self) -> f32 {
        self.area
    }

    pub fn power(&self) -> f32 {
        let sides = if self.two_sided { 2.0 } else { 1.0 };
        PI * sides * self.area * scalar_power(self.l)
    }

    /// Radiance leaving along `w` from a point with geometric normal `n`.
    pub fn le(&self, n: Vec3, w: Vec3) -> Vec3 {
        if self.two_sided || n.dot(w) > 0.0 {
            self.l
        } else {
            Vec3::ZERO
        }
    }

    /// Uniform point on the mesh, and the unit normal there.
    pub fn sample_point(&self, mesh: &Mesh, u_tri: f32, u: Vec2) -> Option<(Vec3, Vec3)> {
        let (t, _, _) = self.triangles.sample(u_tri)?;
        let b = square_to_triangle(u);
        let [p0, p1, p2] = mesh.triangle(t as u32);
        let p = p0 * (1.0 - b.x - b.y) + p1 * b.x + p2 * b.y;
        Some((p, mesh.geometric_normal(t as u32, b.x, b.y)))
    }

    pub fn sample(&self, meshes: &[Mesh], p_ref: Vec3, u: Vec2) -> Option<LightSample> {
        // Reuse u.x for the triangle choice and re-stretch it: keeps the 2D stratification.
        let (t, _, rem) = self.triangles.sample(u.x)?;
        let mesh = &meshes[self.mesh as usize];
        let b = square_to_triangle(Vec2::new(rem, u.y));
        let [p0, p1, p2] = mesh.triangle(t as u32);
        let p = p0 * (1.0 - b.x - b.y) + p1 * b.x + p2 * b.y;
        let n = mesh.geometric_normal(t as u32, b.x, b.y);
        let to = p - p_ref;
        let d2 = to.length_squared();
        if d2 <= 0.0 {
            return None;
        }
        let wi = to / d2.sqrt();
        let pdf = self.pdf(p_ref, p, n);
        let li = self.le(n, -wi);
        (pdf > 0.0 && pdf.is_finite()).then_some(LightSample {
            li,
            wi,
            p,
            n,
            pdf,
            delta: false,
        })
    }

    /// Solid-angle density of `sample` producing `p` (normal `n`) as seen from `p_ref`.
    pub fn pdf(&self, p_ref: Vec3, p: Vec3, n: Vec3) -> f32 {
        let to = p - p_ref;
        let d2 = to.length_squared();
        let cos = n.dot(to).abs() / d2.sqrt();
        if cos <= 0.0 || self.area <= 0.0 {
            return 0.0;
        }
        d2 / (cos * self.area)
    }
}
