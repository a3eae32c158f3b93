//! Ray queries against the scene's triangles: one method set, two interchangeable backends.
//!
//! - `embree`: Debian's Embree 3 through our `photon-embree-sys` bindings (the default);
//!   single rays plus 8-wide packets for coherent batches.
//! - `bvh`: the pure-Rust obvhs CWBVH, for cross-checking and benchmarking.
//!
//! Both answer with the same [`Hit`], so the renderer cannot tell which one answered. Hot loops
//! dispatch through the closed enum [`Accel`], not a trait object. Every query made through
//! [`Accel`] names the [`RayKind`] it casts, so that a recording wrapper (`recording.rs`,
//! [`Accel::recording`]) can sample the rays of a real render by kind; the backends themselves
//! ignore the kind.
//!
//! ## Alpha cut-outs
//! A shape with `alpha` (`Shape "trianglemesh" ... "float alpha" 0.5` or `"texture alpha"
//! "mask"`, see [`crate::scene::Mesh::alpha`]) is tested inside both backends' traversal, as
//! pbrt-v4's `GeometricPrimitive::Intersect` does: at a candidate hit the alpha texture is
//! evaluated at the hit's uv ([`crate::scene::interpolate_uv`]) giving `a`; `a >= 1` keeps the
//! hit, `a <= 0` rejects it, and otherwise it is kept when `u <= a` for `u` a hash of the
//! ray's origin and direction ([`ray_hash`], pbrt-v4's `HashFloat(r.o, r.d)`). A rejected hit
//! lets traversal go on to the next candidate, so closest-hit and occlusion queries answer as
//! if the cut-out part were not there. Every ray (camera, shadow, gather, photon) goes through
//! these queries, so all of them see the same cut-outs. Embree runs the test in intersection
//! and occlusion filter callbacks set only on geometries with alpha; obvhs in its
//! per-primitive callback. Both call [`AlphaMask::keeps`], so for a constant alpha their
//! decisions are bit-identical (they depend on the ray alone), and for a texture they differ
//! only where the backends' barycentrics (last bits) straddle a texel or cell edge.
//!
//! As in pbrt-v4, the hash depends on the ray only: a ray through two surfaces of the same
//! constant alpha `a` passes both or neither (probability `a` of being stopped by the pair,
//! not `1 - (1-a)^2`); a new ray (another sample, bounce or shadow ray) draws anew.
pub mod bvh;
pub mod cpu;
pub mod embree;
pub mod recording;

use crate::math::{Ray, Vec2, Vec3};
use crate::scene::{interpolate_uv, Mesh, Scene};
use crate::texture::Texture;
use std::fmt;
use std::sync::Arc;

/// A closest hit: distance along the ray (in units of `ray.d`), which mesh and triangle,
/// barycentrics (`p = (1-u-v) p0 + u p1 + v p2`) and the unit geometric normal
/// `normalize(cross(p1 - p0, p2 - p0))` (not flipped; see `Mesh::geometric_normal`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Hit {
    pub t: f32,
    pub mesh: u32,
    pub prim: u32,
    pub u: f32,
    pub v: f32,
    pub ng: Vec3,
}

/// Which backend answers ray queries.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default, clap::ValueEnum)]
pub enum BackendKind {
    #[default]
    Embree,
    Obvhs,
}

impl fmt::Display for BackendKind {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            BackendKind::Embree => "embree",
            BackendKind::Obvhs => "obvhs",
        })
    }
}

/// Build options shared by both backends.
#[derive(Clone, Copy, Debug, Default)]
pub struct AccelOptions {
    /// Embree's `RTC_SCENE_FLAG_ROBUST` (watertight-leaning, slower); obvhs ignores it.
    pub robust: bool,
}

/// An error from building or querying an acceleration structure.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct AccelError(pub String);

impl fmt::Display for AccelError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.0)
    }
}

impl std::error::Error for AccelError {}

/// What a ray is cast for (the renderer names it with every query through [`Accel`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum RayKind {
    /// From the camera through a pixel sample.
    Camera,
    /// A segment to a light sample (occlusion).
    Shadow,
    /// A final-gather ray from a diffuse point, and its specular continuations.
    Gather,
    /// The continuation of a camera path after a scattering event (specular and glossy bounces
    /// of the photon mapper and the direct integrator, every bounce of the path tracer).
    Bounce,
    /// A leg of a photon path in pass 1.
    Photon,
}

impl RayKind {
    pub const ALL: [RayKind; 5] = [
        RayKind::Camera,
        RayKind::Shadow,
        RayKind::Gather,
        RayKind::Bounce,
        RayKind::Photon,
    ];

    pub fn name(self) -> &'static str {
        match self {
            RayKind::Camera => "camera",
            RayKind::Shadow => "shadow",
            RayKind::Gather => "gather",
            RayKind::Bounce => "bounce",
            RayKind::Photon => "photon",
        }
    }
}

impl fmt::Display for RayKind {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// The method set every backend implements.
pub trait RayQuery: Send + Sync {
    /// Closest hit with `t` in `[ray.tmin, ray.tmax]`, or `None`.
    fn intersect(&self, ray: &Ray) -> Option<Hit>;
    /// Whether anything blocks the ray within `[ray.tmin, ray.tmax]`.
    fn occluded(&self, ray: &Ray) -> bool;
    /// Closest hits of a batch of (preferably coherent) rays; `out.len() == rays.len()`.
    fn intersect_batch(&self, rays: &[Ray], out: &mut [Option<Hit>]) {
        for (r, o) in rays.iter().zip(out.iter_mut()) {
            *o = self.intersect(r);
        }
    }
    /// Occlusion of a batch of rays; `out.len() == rays.len()`.
    fn occluded_batch(&self, rays: &[Ray], out: &mut [bool]) {
        for (r, o) in rays.iter().zip(out.iter_mut()) {
            *o = self.occluded(r);
        }
    }
}

/// The closed set of backends, or one of them recording its queries; what the renderer holds.
pub enum Accel {
    Embree(embree::EmbreeAccel),
    Obvhs(bvh::BvhAccel),
    Recording(Box<recording::Recording>),
}

impl Accel {
    /// Builds the chosen backend over every mesh of `scene`.
    pub fn build(
        scene: &Scene,
        kind: BackendKind,
        opts: AccelOptions,
    ) -> Result<Accel, AccelError> {
        Ok(match kind {
            BackendKind::Embree => Accel::Embree(embree::EmbreeAccel::build(scene, opts)?),
            BackendKind::Obvhs => Accel::Obvhs(bvh::BvhAccel::build(scene, opts)?),
        })
    }

    /// The backend that answers (through a recording: the wrapped one).
    pub fn kind(&self) -> BackendKind {
        match self {
            Accel::Embree(_) => BackendKind::Embree,
            Accel::Obvhs(_) => BackendKind::Obvhs,
            Accel::Recording(r) => r.backend().kind(),
        }
    }

    /// `backend`, recording up to `capacity` rays per kind and query of the queries it answers,
    /// chosen with `seed` (see [`recording`]).
    pub fn recording(backend: Accel, capacity: usize, seed: u64) -> Accel {
        Accel::Recording(Box::new(recording::Recording::new(backend, capacity, seed)))
    }

    /// Ends a recording: the wrapped backend and what was recorded (nothing when `self` was
    /// not recording).
    pub fn finish_recording(self) -> (Accel, recording::RecordedRays) {
        match self {
            Accel::Recording(r) => r.finish(),
            a => (a, recording::RecordedRays::default()),
        }
    }

    /// The backend itself, for tools that query it directly (nothing is recorded).
    pub fn backend(&self) -> &dyn RayQuery {
        match self {
            Accel::Embree(a) => a,
            Accel::Obvhs(a) => a,
            Accel::Recording(r) => r.backend().backend(),
        }
    }

    /// Closest hit of a ray of `kind` (see [`RayQuery::intersect`]).
    #[inline]
    pub fn intersect(&self, kind: RayKind, ray: &Ray) -> Option<Hit> {
        match self {
            Accel::Embree(a) => a.intersect(ray),
            Accel::Obvhs(a) => a.intersect(ray),
            Accel::Recording(r) => r.intersect(kind, ray),
        }
    }

    /// Occlusion of a ray of `kind` (see [`RayQuery::occluded`]).
    #[inline]
    pub fn occluded(&self, kind: RayKind, ray: &Ray) -> bool {
        match self {
            Accel::Embree(a) => a.occluded(ray),
            Accel::Obvhs(a) => a.occluded(ray),
            Accel::Recording(r) => r.occluded(kind, ray),
        }
    }

    /// Closest hits of a batch of rays of `kind`; `out.len() == rays.len()`.
    pub fn intersect_batch(&self, kind: RayKind, rays: &[Ray], out: &mut [Option<Hit>]) {
        match self {
            Accel::Embree(a) => a.intersect_batch(rays, out),
            Accel::Obvhs(a) => a.intersect_batch(rays, out),
            Accel::Recording(r) => r.intersect_batch(kind, rays, out),
        }
    }

    /// Occlusion of a batch of rays of `kind`; `out.len() == rays.len()`.
    pub fn occluded_batch(&self, kind: RayKind, rays: &[Ray], out: &mut [bool]) {
        match self {
            Accel::Embree(a) => a.occluded_batch(rays, out),
            Accel::Obvhs(a) => a.occluded_batch(rays, out),
            Accel::Recording(r) => r.occluded_batch(kind, rays, out),
        }
    }
}

/// Checks what both backends rely on before handing geometry to a builder: every index names
/// a vertex of its mesh (Embree reads vertices without bounds checks) and every vertex that a
/// triangle uses is finite. Returns the first problem found as an error.
pub(crate) fn validate_meshes(scene: &Scene) -> Result<(), AccelError> {
    for (m, mesh) in scene.meshes.iter().enumerate() {
        let n = mesh.positions.len();
        for (p, tri) in mesh.indices.iter().enumerate() {
            for &i in tri {
                let Some(pos) = mesh.positions.get(i as usize) else {
                    return Err(AccelError(format!(
                        "mesh {m}, triangle {p}: vertex index {i} out of range ({n} vertices)"
                    )));
                };
                if !pos.is_finite() {
                    return Err(AccelError(format!(
                        "mesh {m}, triangle {p}: vertex {i} is not finite ({pos})"
                    )));
                }
            }
        }
    }
    Ok(())
}

/// The unit geometric normal `normalize(cross(p1 - p0, p2 - p0))` of every triangle of `mesh`
/// (zero for zero-area triangles). Both backends fill [`Hit::ng`] from this one function so
/// that they agree bit for bit. Indices must have been checked by [`validate_meshes`].
/// What survives of light along `ray` up to `hit` (the segment's medium: the side of the
/// hit surface it arrives from, see [`crate::medium`]); 1 without a medium there, or for a
/// ray that leaves the scene (`None`: media are closed regions).
#[inline]
pub fn transmittance(scene: &Scene, hit: Option<&Hit>, ray: &Ray) -> Vec3 {
    let Some(h) = hit else { return Vec3::ONE };
    let mesh = &scene.meshes[h.mesh as usize];
    let Some(mi) = &mesh.interface else {
        return Vec3::ONE;
    };
    match mi.arriving(ray.d, mesh.geometric_normal(h.prim, h.u, h.v)) {
        Some(m) => scene.media[m as usize].transmittance(h.t * ray.d.length()),
        None => Vec3::ONE,
    }
}

pub(crate) fn face_normals(mesh: &crate::scene::Mesh) -> Vec<Vec3> {
    (0..mesh.indices.len() as u32)
        .map(|p| {
            let [p0, p1, p2] = mesh.triangle(p);
            (p1 - p0).cross(p2 - p0).normalize_or_zero()
        })
        .collect()
}

/// The part of a ray both backends agree to query: `Some((tmin, tmax))` with `tmin` clamped to
/// 0 (Embree accepts no negative `tnear`), or `None` when the ray cannot hit anything: empty
/// or NaN interval, non-finite origin, zero or non-finite direction, or coordinates beyond
/// 1.8e18 (which Embree rejects with an assertion).
#[inline]
pub(crate) fn query_interval(ray: &Ray) -> Option<(f32, f32)> {
    let tmin = ray.tmin.max(0.0);
    // Embree asserts (and aborts) on rays with coordinates beyond its FLT_LARGE (1.844e18).
    const LARGE: f32 = 1.8e18;
    let inside = |v: Vec3| v.is_finite() && v.abs().max_element() <= LARGE;
    let ok = tmin <= ray.tmax && inside(ray.o) && inside(ray.d) && ray.d != Vec3::ZERO;
    ok.then_some((tmin, ray.tmax))
}

/// pbrt-v4's `HashFloat(r.o, r.d)`: a uniform number in [0, 1) that depends on the bits of
/// the ray's origin and direction only (here through [`crate::sampling::hash`], not pbrt's
/// MurmurHash: the rays differ from pbrt's anyway, what matters is that both backends draw
/// the same number for the same ray).
#[inline]
pub fn ray_hash(o: Vec3, d: Vec3) -> f32 {
    let pair = |a: f32, b: f32| (a.to_bits() as u64) << 32 | b.to_bits() as u64;
    let h = crate::sampling::hash(&[pair(o.x, o.y), pair(o.z, d.x), pair(d.y, d.z)]);
    crate::sampling::to_unit(h)
}

/// pbrt-v4's stochastic alpha test: whether a hit where the alpha texture is `a` counts, for
/// the ray `(o, d)`. `a >= 1` (or NaN, as in pbrt) keeps it, `a <= 0` rejects it, otherwise
/// it is kept when [`ray_hash`]`(o, d) <= a` (probability `a`).
#[inline]
pub fn alpha_keeps(a: f32, o: Vec3, d: Vec3) -> bool {
    if a.is_nan() || a >= 1.0 {
        return true;
    }
    a > 0.0 && ray_hash(o, d) <= a
}

/// One mesh's alpha cut-out, as both backends test it: the texture and what the hit's uv is
/// computed from (the mesh's uvs and indices, copied so the backends need not borrow the
/// scene; without uvs the uv comes from the barycentrics and nothing is copied).
#[derive(Debug)]
pub struct AlphaMask {
    texture: Arc<Texture>,
    uvs: Option<Vec<Vec2>>,
    indices: Vec<[u32; 3]>,
}

impl AlphaMask {
    /// The mask of `mesh`, or `None` when it has no alpha.
    pub fn of(mesh: &Mesh) -> Option<AlphaMask> {
        let texture = mesh.alpha.clone()?;
        let uvs = mesh.uvs.clone();
        let indices = if uvs.is_some() {
            mesh.indices.clone()
        } else {
            Vec::new()
        };
        Some(AlphaMask {
            texture,
            uvs,
            indices,
        })
    }

    /// The masks of every mesh of `scene` (by mesh index), or `None` when no mesh has alpha.
    pub fn of_scene(scene: &Scene) -> Option<Vec<Option<Arc<AlphaMask>>>> {
        scene.meshes.iter().any(|m| m.alpha.is_some()).then(|| {
            scene
                .meshes
                .iter()
                .map(|m| AlphaMask::of(m).map(Arc::new))
                .collect()
        })
    }

    /// The alpha texture's value at barycentrics `(u, v)` of triangle `prim` (its first
    /// channel: float textures have three equal ones). A triangle the mask does not know
    /// (cannot happen for ids the backends report) reads as opaque.
    pub fn alpha(&self, prim: u32, u: f32, v: f32) -> f32 {
        let tri = match &self.uvs {
            Some(_) => match self.indices.get(prim as usize) {
                Some(&t) => t,
                None => return 1.0,
            },
            None => [0; 3],
        };
        let uv = interpolate_uv(self.uvs.as_deref(), tri, u, v);
        self.texture.eval(uv).x
    }

    /// Whether the candidate hit at barycentrics `(u, v)` of triangle `prim` of the ray
    /// `(o, d)` counts ([`alpha_keeps`]).
    #[inline]
    pub fn keeps(&self, prim: u32, u: f32, v: f32, o: Vec3, d: Vec3) -> bool {
        alpha_keeps(self.alpha(prim, u, v), o, d)
    }
}
