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
//! - `uv` are the mesh's texture coordinates at the hit, or pbrt-v4's default for a triangle
//!   without them (vertex uvs (0,0), (1,0), (1,1), so uv = (b1 + b2, b2) for barycentrics
//!   (b1, b2));
//! - `wo` points back along the ray, in world space (`wo_world`) and in the frame (`wo`).
//!
//! [`SurfaceInteraction::bsdf`] builds the BSDF per hit from the material with its textures
//! looked up here. When a texture filters (trilinear images, checkerboards) or the material
//! is bump mapped, the lookup gets a footprint: the pixel's extent on the surface from
//! [`crate::camera::approximate_dp_dxy`] (pbrt-v4 uses that approximation for every hit),
//! turned into `du/dx, dv/dx, du/dy, dv/dy` by least squares against the triangle's
//! `dp/du, dp/dv`.
//!
//! Bump mapping (`"texture displacement"`, pbrt-v4's `BumpMap`): with the displacement `d`
//! looked up at the point and at points shifted by `du = (|du/dx| + |du/dy|) / 2` (0.0005 when
//! that is 0) in u and `dv` alike in v, `dp/du' = dp/du + (d(u + du) - d(u)) / du n` (and v
//! alike), and the shading normal becomes `normalize(dp/du' x dp/dv')`, turned to the side of
//! the unbumped one. pbrt-v4's `d(u) dn/du` term is left out (it is zero on meshes without
//! shading normals).
use crate::accel::Hit;
use crate::bsdf::Bsdf;
use crate::camera::Footprint;
use crate::light::LightSample;
use crate::math::{spawn_origin, Frame, Ray, Vec2, Vec3};
use crate::scene::{Material, MaterialKind, Mesh, Scene};
use crate::spectrum::Lambda;
use crate::texture::{Tex, TexCoord};

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
            uv: mesh.uv(prim, u, v),
            wo_world,
            wo: frame.to_local(wo_world),
        }
    }

    /// The BSDF at this point, its textures looked up here and its colours at the wavelengths
    /// `lambda` ([`Lambda::Rgb`]: RGB). A bump-mapped material first moves the shading normal
    /// (and `frame`, `wo` with it).
    pub fn bsdf(&mut self, scene: &Scene, fp: Footprint, lambda: Lambda) -> Bsdf {
        let m = self.material(scene);
        let mut tc = if material_needs_differentials(m) {
            self.tex_coord(scene, fp)
        } else {
            TexCoord::point(self.uv)
        };
        tc.lambda = lambda;
        if let Some(d) = &m.displacement {
            self.bump(d, &tc);
        }
        m.kind.bsdf(&tc)
    }

    /// The material at this point: the mesh's, with every `mix` resolved as pbrt-v4's
    /// `MixMaterial::ChooseMaterial` does: `amount` a <= 0 picks the first, a >= 1 the second,
    /// else the second when a hash of the point and `wo` (and the two materials) is below a.
    pub fn material<'a>(&self, scene: &'a Scene) -> &'a Material {
        let mut m = &scene.materials[self.mesh.material as usize];
        // Mixes name materials defined before them, so chains end, and the loader refuses a
        // chain deeper than MAX_MIX_DEPTH: the loop always reaches a material that is no mix.
        for _ in 0..crate::scene::MAX_MIX_DEPTH {
            let MaterialKind::Mix(crate::material::MixMaterial {
                materials, amount, ..
            }) = &m.kind
            else {
                break;
            };
            let a = amount.eval_float(&TexCoord::point(self.uv));
            let second = if a <= 0.0 {
                false
            } else if a >= 1.0 {
                true
            } else {
                let bits = |v: Vec3| v.to_array().map(|x| x.to_bits() as u64);
                let (p, w) = (bits(self.p), bits(self.wo_world));
                let h = crate::sampling::hash(&[
                    p[0],
                    p[1],
                    p[2],
                    w[0],
                    w[1],
                    w[2],
                    materials[0] as u64,
                    materials[1] as u64,
                ]);
                crate::sampling::to_unit(h) < a
            };
            m = &scene.materials[materials[second as usize] as usize];
        }
        m
    }

    /// The texture lookup at this point with its footprint (one pixel step in x and y of the
    /// image `fp` describes).
    pub fn tex_coord(&self, scene: &Scene, fp: Footprint) -> TexCoord {
        let (dpdx, dpdy) =
            crate::camera::approximate_dp_dxy(&scene.camera, fp.res, fp.spp, self.p, self.ng);
        let (dpdu, dpdv) = self.dpduv();
        TexCoord {
            uv: self.uv,
            duvdx: uv_step(dpdu, dpdv, dpdx),
            duvdy: uv_step(dpdu, dpdv, dpdy),
            lambda: Lambda::Rgb,
        }
    }

    /// The triangle's `dp/du`, `dp/dv` from its vertex uvs (pbrt-v4's `Triangle::Intersect`),
    /// or two tangents of `ng` when the uvs are degenerate.
    pub fn dpduv(&self) -> (Vec3, Vec3) {
        let [p0, p1, p2] = self.mesh.triangle(self.prim);
        let [uv0, uv1, uv2] = self.mesh.triangle_uvs(self.prim);
        let (duv02, duv12) = (uv0 - uv2, uv1 - uv2);
        let (dp02, dp12) = (p0 - p2, p1 - p2);
        let det = duv02.x * duv12.y - duv02.y * duv12.x;
        let dpdu = (dp02 * duv12.y - dp12 * duv02.y) / det;
        let dpdv = (dp12 * duv02.x - dp02 * duv12.x) / det;
        if det.abs() < 1e-9
            || !dpdu.is_finite()
            || !dpdv.is_finite()
            || dpdu.cross(dpdv).length_squared() == 0.0
        {
            let f = Frame::from_normal(self.ng);
            return (f.s, f.t);
        }
        (dpdu, dpdv)
    }

    /// pbrt-v4's bump mapping with displacement texture `d` (see the module docs).
    fn bump(&mut self, d: &Tex, tc: &TexCoord) {
        let (dpdu, dpdv) = self.dpduv();
        let step = |a: f32, b: f32| match 0.5 * (a.abs() + b.abs()) {
            s if s > 0.0 && s.is_finite() => s,
            _ => 0.0005,
        };
        let du = step(tc.duvdx.x, tc.duvdy.x);
        let dv = step(tc.duvdx.y, tc.duvdy.y);
        let at = |uv: Vec2| d.eval_float(&TexCoord { uv, ..*tc });
        let h = at(tc.uv);
        let hu = at(tc.uv + Vec2::new(du, 0.0));
        let hv = at(tc.uv + Vec2::new(0.0, dv));
        let n = self.ns;
        let dpdu = dpdu + n * ((hu - h) / du);
        let dpdv = dpdv + n * ((hv - h) / dv);
        let bumped = dpdu.cross(dpdv).normalize_or_zero();
        if bumped == Vec3::ZERO || !bumped.is_finite() {
            return;
        }
        self.ns = if bumped.dot(n) < 0.0 { -bumped } else { bumped };
        self.frame = Frame::from_normal(self.ns);
        self.wo = self.frame.to_local(self.wo_world);
    }

    /// The area light this surface emits as, if any.
    pub fn area_light(&self) -> Option<usize> {
        self.mesh.area_light.map(|l| l as usize)
    }

    /// This point and its shading normal (after any bump or normal map), as a receiver of
    /// light for light selection ([`crate::light::Lights::pick_at`]).
    pub fn receiver(&self) -> crate::light::Receiver {
        crate::light::Receiver::new(self.p, self.frame.n)
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

    /// The medium a ray leaving this point along world direction `d` travels in: the side of
    /// the mesh's medium boundary it goes to, or `current` where the surface is no boundary
    /// (pbrt-v4's `GetMedium`).
    pub fn medium_leaving(&self, d: Vec3, current: Option<u32>) -> Option<u32> {
        match &self.mesh.interface {
            Some(mi) => mi.leaving(d, self.ng),
            None => current,
        }
    }

    /// The shadow ray to a light sample: from past this point's error bound to just short of
    /// the light point (itself moved past its own bound towards this side).
    pub fn shadow_ray(&self, s: &LightSample) -> Ray {
        shadow_ray_from(self.spawn(s.wi), s)
    }
}

/// The shadow ray from `o` (already clear of its surface, or a point in a medium) to a light
/// sample, ending just short of the light point (moved past its own bound towards `o`).
pub fn shadow_ray_from(o: Vec3, s: &LightSample) -> Ray {
    let target = if s.n == Vec3::ZERO {
        s.p
    } else {
        spawn_origin(s.p, s.err, if s.n.dot(o - s.p) >= 0.0 { s.n } else { -s.n })
    };
    Ray::segment(o, target - o, 1.0 - 1e-4)
}

/// Whether any texture of `m` reads its footprint, or `m` is bump mapped.
fn material_needs_differentials(m: &Material) -> bool {
    let mut any = m.displacement.is_some();
    m.kind
        .for_each_texture(&mut |t| any |= t.needs_differentials());
    any
}

/// The `(du, dv)` that best explains the surface step `dp` (least squares against `dpdu`,
/// `dpdv`; pbrt-v4's `ComputeDifferentials`), clamped to +-1e8; 0 when degenerate.
fn uv_step(dpdu: Vec3, dpdv: Vec3, dp: Vec3) -> Vec2 {
    let (a00, a01, a11) = (dpdu.dot(dpdu), dpdu.dot(dpdv), dpdv.dot(dpdv));
    let inv_det = 1.0 / (a00 * a11 - a01 * a01);
    let (b0, b1) = (dpdu.dot(dp), dpdv.dot(dp));
    let uv = Vec2::new(a11 * b0 - a01 * b1, a00 * b1 - a01 * b0) * inv_det;
    if uv.is_finite() {
        uv.clamp(Vec2::splat(-1e8), Vec2::splat(1e8))
    } else {
        Vec2::ZERO
    }
}
