//! The scene as the renderer sees it: world-space triangle meshes, materials, lights, camera,
//! film, sampler, pixel filter and integrator settings. Immutable once loaded.
//!
//! `loader` reads it from the pbrt-v4 scene format (see the README for the supported subset).
pub mod generate;
pub mod loader;

use crate::math::{Mat4, Vec2, Vec3};
use std::path::PathBuf;
use std::sync::Arc;

pub use crate::material::{Material, MaterialKind, MAX_MIX_DEPTH};
pub use crate::params::{
    clip_for_message, one_line, Loc, ParamSet, SceneError, MAX_LINE, MAX_MESSAGE, MAX_TOKEN,
};

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

/// The closed set of lights. Radiometric values are linear RGB, already multiplied by `scale`.
#[derive(Clone, Debug, PartialEq)]
pub enum Light {
    /// `AreaLightSource "diffuse"` on mesh `mesh`: radiance `l` leaving the side of the
    /// geometric normal (both sides when `two_sided`).
    Area { mesh: u32, l: Vec3, two_sided: bool },
    /// `LightSource "point"`.
    Point(crate::light::PointLight),
    /// `LightSource "spot"`.
    Spot(crate::light::SpotLight),
    /// `LightSource "distant"`.
    Distant(crate::light::DistantLight),
    /// `LightSource "infinite"`: radiance arriving from every direction at infinity, constant
    /// or from an equal-area image, oriented by the CTM (see [`crate::light::EnvMap`]).
    Infinite { map: Arc<crate::light::EnvMap> },
}

impl Light {
    /// A light with no surface in the scene (point, spot, distant, infinite): what final-gather
    /// hits take direct light from by shadow rays (`integrator::photonmap`).
    pub fn is_surfaceless(&self) -> bool {
        !matches!(self, Light::Area { .. })
    }
}

/// `Camera "perspective"`: `fov` (degrees) spans the shorter image axis of the screen window
/// (pbrt-v4); a thin lens when `lens_radius > 0`.
#[derive(Clone, Debug, PartialEq)]
pub struct CameraDesc {
    /// Camera-to-world transform (the inverse of the CTM at `Camera`). pbrt's camera space:
    /// looks down +z, +y up, and raster x grows towards camera -x... see `camera.rs`.
    pub world_from_camera: Mat4,
    pub fov_deg: f32,
    /// Thin-lens radius in camera-space units (`lensradius`; 0: a pinhole).
    pub lens_radius: f32,
    /// Distance of the plane in focus along camera +z (`focaldistance`).
    pub focal_distance: f32,
    /// pbrt's screen window `[xmin, xmax, ymin, ymax]` when the file sets it (`screenwindow`,
    /// or `frameaspectratio`); `None`: derived from the image's aspect ratio.
    pub screen_window: Option<[f32; 4]>,
    /// `shutterclose - shutteropen`: the exposure time of the film's imaging ratio.
    pub exposure_time: f32,
}

impl CameraDesc {
    /// A pinhole camera with pbrt-v4's defaults for everything but the transform and `fov`.
    pub fn pinhole(world_from_camera: Mat4, fov_deg: f32) -> CameraDesc {
        CameraDesc {
            world_from_camera,
            fov_deg,
            lens_radius: 0.0,
            focal_distance: 1e6,
            screen_window: None,
            exposure_time: 1.0,
        }
    }
}

/// `Film "rgb"` (or `"gbuffer"`, rendered as an RGB film).
#[derive(Clone, Debug, PartialEq)]
pub struct FilmDesc {
    pub xres: u32,
    pub yres: u32,
    pub filename: Option<String>,
    /// The sensor's `iso` (pbrt-v4's imaging ratio is `exposure time * iso / 100`).
    pub iso: f32,
    /// Each camera sample's colour is scaled so that its largest CIE XYZ component (the
    /// default `cie1931` sensor's values, after the imaging ratio) is at most this.
    pub max_component: f32,
    /// `cropwindow` `[x0, x1, y0, y1]` as fractions of the image, ordered and clamped to
    /// [0, 1]; only the pixels pbrt-v4's rounding puts inside are rendered.
    pub crop: Option<[f32; 4]>,
    /// `whitebalance`: the colour temperature (kelvin) adapted to sRGB's white; 0: none.
    pub white_balance: f32,
}

impl FilmDesc {
    /// A film of `xres x yres` with pbrt-v4's defaults for everything else.
    pub fn new(xres: u32, yres: u32) -> FilmDesc {
        FilmDesc {
            xres,
            yres,
            filename: None,
            iso: 100.0,
            max_component: f32::INFINITY,
            crop: None,
            white_balance: 0.0,
        }
    }

    /// pbrt-v4's imaging ratio for a camera exposing for `exposure_time`.
    pub fn imaging_ratio(&self, exposure_time: f32) -> f32 {
        exposure_time * self.iso / 100.0
    }
}

/// `PixelFilter`: radii in pixels.
#[derive(Clone, Debug, PartialEq)]
pub enum FilterDesc {
    Box { radius: Vec2 },
    Triangle { radius: Vec2 },
    Gaussian { radius: Vec2, sigma: f32 },
}

/// `Sampler`: the pbrt name (kept for the statistics) and samples per pixel.
#[derive(Clone, Debug, PartialEq)]
pub struct SamplerDesc {
    pub name: String,
    pub pixel_samples: u32,
}

/// `Integrator`: its name and its parameters, left for the integrator to read (and to report
/// as errors those it does not use).
#[derive(Clone, Debug)]
pub struct IntegratorDesc {
    pub name: String,
    pub params: ParamSet,
    pub loc: Option<Loc>,
}

/// A loaded scene.
#[derive(Clone, Debug)]
pub struct Scene {
    pub meshes: Vec<Mesh>,
    pub materials: Vec<Material>,
    pub lights: Vec<Light>,
    pub camera: CameraDesc,
    pub film: FilmDesc,
    pub filter: FilterDesc,
    pub sampler: SamplerDesc,
    pub integrator: IntegratorDesc,
    /// The file the scene was read from (outputs default next to the working directory).
    pub path: PathBuf,
    /// The `Texture`s the file defines (materials and alpha hold what they use).
    pub textures: crate::texture::Textures,
    /// The most bytes the loader held at once for data files (decoded images with their
    /// transient decode buffers, PLY meshes, instanced copies): a floor of the process's peak.
    pub load_peak: u64,
    /// What the loader accepted but ignores, one line each with its location (`Accelerator`,
    /// another renderer's integrator parameters, `Option`s): printed before a render.
    pub notes: Vec<String>,
}

impl Scene {
    /// A scene of the given geometry, materials and lights with simple settings for everything
    /// else (camera at the origin looking down +z, fov 45; 256x256 film; 0.5-pixel box filter;
    /// 1 sample; the photon mapper): for tests and generated benchmark scenes, which override
    /// what they need with struct-update syntax.
    pub fn with_geometry(meshes: Vec<Mesh>, materials: Vec<Material>, lights: Vec<Light>) -> Scene {
        Scene {
            meshes,
            materials,
            lights,
            camera: CameraDesc::pinhole(Mat4::IDENTITY, 45.0),
            film: FilmDesc::new(256, 256),
            filter: FilterDesc::Box {
                radius: Vec2::splat(0.5),
            },
            sampler: SamplerDesc {
                name: "independent".into(),
                pixel_samples: 1,
            },
            integrator: IntegratorDesc {
                name: "photonmap".into(),
                params: ParamSet::default(),
                loc: None,
            },
            path: PathBuf::from("generated.pbrt"),
            notes: Vec::new(),
            textures: Default::default(),
            load_peak: 0,
        }
    }

    /// A 64-bit hash of everything that decides the image: geometry (vertex bits, indices,
    /// normals, uvs, material, light and alpha of each mesh; an image alpha by its settings and
    /// size), materials, lights, camera, pixel filter and the film's iso, clamp and crop window
    /// (the resolution is checked on its own). Partial renders carry it so that parts of different scenes never merge.
    pub fn content_hash(&self) -> u64 {
        use crate::sampling::hash;
        let text = |s: String| {
            s.bytes()
                .fold(0u64, |h, b| crate::sampling::mix64(h ^ b as u64))
        };
        let mut h = hash(&[
            text(format!("{:?}", self.materials)),
            text(format!("{:?}", self.lights)),
            text(format!("{:?}", self.camera)),
            text(format!("{:?}", self.filter)),
            text(format!(
                "{:?}",
                (
                    self.film.iso,
                    self.film.max_component,
                    self.film.crop,
                    self.film.white_balance
                )
            )),
        ]);
        for m in &self.meshes {
            let bits = |v: &[f32]| {
                v.iter()
                    .fold(0u64, |h, x| crate::sampling::mix64(h ^ x.to_bits() as u64))
            };
            let pos: Vec<f32> = m.positions.iter().flat_map(|p| p.to_array()).collect();
            let nrm: Vec<f32> = m
                .normals
                .iter()
                .flatten()
                .flat_map(|p| p.to_array())
                .collect();
            let uv: Vec<f32> = m.uvs.iter().flatten().flat_map(|p| p.to_array()).collect();
            let idx = m
                .indices
                .iter()
                .flatten()
                .fold(0u64, |h, &i| crate::sampling::mix64(h ^ i as u64));
            h = hash(&[
                h,
                bits(&pos),
                bits(&nrm),
                bits(&uv),
                idx,
                m.material as u64,
                m.area_light.map_or(u64::MAX, |l| l as u64),
                m.flip_normals as u64,
            ]);
            // Only with alpha, so that the hash of a scene without alpha is what it was.
            if let Some(a) = &m.alpha {
                h = hash(&[h, text(format!("{a:?}"))]);
            }
        }
        h
    }

    /// Bytes the environment maps of `infinite` lights hold (texels and sampling tables).
    pub fn light_map_bytes(&self) -> u64 {
        self.lights
            .iter()
            .map(|l| match l {
                Light::Infinite { map } => map.bytes(),
                _ => 0,
            })
            .sum()
    }

    pub fn triangle_count(&self) -> usize {
        self.meshes.iter().map(|m| m.indices.len()).sum()
    }

    /// Axis-aligned bounds of all geometry `(min, max)`.
    pub fn bounds(&self) -> (Vec3, Vec3) {
        let mut lo = Vec3::splat(f32::INFINITY);
        let mut hi = Vec3::splat(f32::NEG_INFINITY);
        for p in self.meshes.iter().flat_map(|m| m.positions.iter()) {
            lo = lo.min(*p);
            hi = hi.max(*p);
        }
        (lo, hi)
    }
}
