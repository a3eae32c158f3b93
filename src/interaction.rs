//! The surface interaction: everything shading needs about a ray hit, built once per hit.
//!
//! Every integrator, the photon tracer and the ray recorder shade through this one type, so a
//! hit point, its rounding-error bound, the geometric and shading normals, the shading frame,
//! the texture coordinates and the outgoing direction are computed in one place:
//!
//! - `p` is interpolated from the barycentrics (not `o + t d`) with its error bound `err`, and
//!   rays leave it through [`SurfaceInteraction::spawn`] (pbrt-v4's offset past the bound);
//! - `ng` follows pbrt's orientation (`Mesh::geometric_normal`), `ns` is the interpolated
//!   shading normal (or `ng`), and `frame` has `z = ns`;
//! - `uv` are the mesh's texture coordinates at the hit, or the barycentrics `(u, v)` when the
//!   mesh has none (pbrt-v4's default parameterisation of a triangle);
//! - `wo` points back along the ray, in world space (`wo_world`) and in the frame (`wo`).
use crate::accel::Hit;
use crate::bsdf::Bsdf;
use crate::light::LightSample;
use crate::math::{spawn_origin, Frame, Ray, Vec2, Vec3};
use crate::scene::{Mesh, Scene};

/// A ray hit, ready to shade.
#[derive(Clone, Copy, Debug)]
pub struct SurfaceInteraction<'s> {
    pub mesh: &'s Mesh,
    /// Index of the mesh in `Scene::meshes`.
    pub mesh_index: u32,
    pub prim: u32,
    /// Barycentrics of the hit (weights `1-u-v, u, v`).
    pub bary: Vec2,
    pub p: Vec3,
    /// Rounding-error bound of `p`.
    pub err: Vec3,
    /// Geometric normal.
    pub ng: Vec3,
    /// Shading normal (unit).
    pub ns: Vec3,
    /// Shading frame, `z = ns`.
    pub frame: Frame,
    pub uv: Vec2,
    /// Unit direction back along the incoming ray (world space).
    pub wo_world: Vec3,
    /// `wo_world` in the shading frame.
    pub wo: Vec3,
}

impl<'s> SurfaceInteraction<'s> {
    /// The interaction of `ray` hitting `hit` in `scene`.
    pub fn new(scene: &'s Scene, hit: &Hit, ray: &Ray) -> Self {
        let mesh = &scene.meshes[hit.mesh as usize];
        let (prim, u, v) = (hit.prim, hit.u, hit.v);
        let ng = mesh.geometric_normal(prim, u, v);
        let ns = mesh.shading_normal(prim, u, v).unwrap_or(ng);
        let frame = Frame::from_normal(ns);
        let wo_world = -ray.d.normalize();
        SurfaceInteraction {
            mesh,
            mesh_index: hit.mesh,
            prim,
            bary: Vec2::new(u, v),
            p: mesh.point(prim, u, v),
            err: mesh.point_error(prim, u, v),
            ng,
            ns,
            frame,
            uv: mesh_uv(mesh, prim, u, v),
            wo_world,
            wo: frame.to_local(wo_world),
        }
    }

    /// The BSDF at this point.
    pub fn bsdf(&self, scene: &Scene) -> Bsdf {
        Bsdf::from_material(&scene.materials[self.mesh.material as usize])
    }

    /// The area light this surface emits as, if any.
    pub fn area_light(&self) -> Option<usize> {
        self.mesh.area_light.map(|l| l as usize)
    }

    /// The shading normal turned to the side `wo` is on.
    pub fn facing_normal(&self) -> Vec3 {
        if self.wo.z >= 0.0 {
            self.ns
        } else {
            -self.ns
        }
    }

    /// A ray origin past the error bound on the side of world direction `w`.
    pub fn spawn(&self, w: Vec3) -> Vec3 {
        spawn_origin(
            self.p,
            self.err,
            if self.ng.dot(w) >= 0.0 {
                self.ng
            } else {
                -self.ng
            },
        )
    }

    /// A ray leaving in world direction `w`.
    pub fn spawn_ray(&self, w: Vec3) -> Ray {
        Ray::new(self.spawn(w), w)
    }

    /// The shadow ray to a light sample: from past this point's error bound to just short of
    /// the light point (itself moved past its own bound towards this side).
    pub fn shadow_ray(&self, s: &LightSample) -> Ray {
        let o = self.spawn(s.wi);
        let target = if s.n == Vec3::ZERO {
            s.p
        } else {
            spawn_origin(s.p, s.err, if s.n.dot(o - s.p) >= 0.0 { s.n } else { -s.n })
        };
        Ray::segment(o, target - o, 1.0 - 1e-4)
    }
}

/// The mesh's texture coordinates at barycentrics `(u, v)`, or `(u, v)` without them.
fn mesh_uv(mesh: &Mesh, prim: u32, u: f32, v: f32) -> Vec2 {
    match &mesh.uvs {
        Some(uvs) => {
            let [a, b, c] = mesh.indices[prim as usize];
            uvs[a as usize] * (1.0 - u - v) + uvs[b as usize] * u + uvs[c as usize] * v
        }
        None => Vec2::new(u, v),
    }
}
