//! The scene as the renderer sees it: world-space triangle meshes, materials, lights, camera,
//! film, sampler, pixel filter and integrator settings. Immutable once loaded.
//!
//! `loader` reads it from the pbrt-v4 scene format (see the README for the supported subset).
pub mod generate;
pub mod loader;
pub mod upgrade;

use crate::math::{Mat4, Vec2, Vec3};
use std::path::PathBuf;

pub use crate::material::{Material, MaterialKind, MAX_MIX_DEPTH};
pub use crate::params::{
    clip_for_message, one_line, Loc, ParamSet, SceneError, MAX_LINE, MAX_MESSAGE, MAX_TOKEN,
};

pub use crate::light::Light;
pub use crate::mesh::{interpolate_uv, Mesh, MESH_OVERHEAD_BYTES};

/// `Camera "perspective"` or `"orthographic"`: for a perspective camera `fov` (degrees) spans
/// the shorter image axis of the screen window (pbrt-v4); an orthographic one maps the screen
/// window itself, in camera-space units, onto the image; a thin lens when `lens_radius > 0`.
#[derive(Clone, Debug, PartialEq)]
pub struct CameraDesc {
    /// Perspective or orthographic.
    pub projection: Projection,
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
            projection: Projection::Perspective,
            world_from_camera,
            fov_deg,
            lens_radius: 0.0,
            focal_distance: 1e6,
            screen_window: None,
            exposure_time: 1.0,
        }
    }
}

/// The camera's projection (pbrt-v4's `Camera "perspective"` and `"orthographic"`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Projection {
    /// Rays leave the camera-space origin (or a lens point) through the screen window at z = 1
    /// scaled by `tan(fov / 2)`.
    Perspective,
    /// Rays start at the screen-window point on the plane z = 0 of camera space and run along
    /// +z (through a lens: towards that point moved to z = `focaldistance`).
    Orthographic,
}

/// `Film "rgb"` or `"gbuffer"` (an RGB film plus the data channels of `crate::integrator::aov`).
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
    /// `cropwindow` or `pixelbounds`: only the pixels inside are rendered (see
    /// [`crate::film::Crop`]).
    pub crop: Option<crate::film::Crop>,
    /// `whitebalance`: the colour temperature (kelvin) adapted to sRGB's white; 0: none.
    pub white_balance: f32,
    /// `Film "gbuffer"`: the space of its position and normal channels (its
    /// `coordinatesystem`); `None` for an `"rgb"` film.
    pub gbuffer: Option<crate::film::Space>,
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
            gbuffer: None,
        }
    }

    /// pbrt-v4's imaging ratio for a camera exposing for `exposure_time`.
    pub fn imaging_ratio(&self, exposure_time: f32) -> f32 {
        exposure_time * self.iso / 100.0
    }
}

/// `PixelFilter` (see [`crate::film`]).
pub use crate::film::FilterDesc;

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
    /// `MakeNamedMedium` media, indexed by [`crate::medium::MediumInterface`]s.
    pub media: Vec<crate::medium::Medium>,
    /// Per light of `lights`, the media around it (pbrt-v4: an area light's shape's
    /// `MediumInterface`, a `LightSource`'s outside medium on both sides); may be shorter
    /// than `lights` (vacuum).
    pub light_media: Vec<crate::medium::MediumInterface>,
    /// The medium the camera sits in (`MediumInterface` before `Camera`: its outside one).
    pub camera_medium: Option<u32>,
    /// Why this scene's media need a path that tracks the medium it is in (pbrt-v4's
    /// semantics: scattering, the camera or a light inside a medium, `interface` surfaces,
    /// surfaces immersed in a medium): `file:line:col: what`. `None` when every medium is an
    /// absorbing region closed by the surfaces that name it, which every integrator handles
    /// (see [`crate::medium`]).
    pub media_need_tracking: Option<String>,
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
    /// The scene's lights ready to sample (area lights with their triangle distributions).
    pub fn emitters(&self) -> crate::light::Lights {
        crate::light::Lights::new(&self.lights, &self.meshes, self.bounds())
    }

    /// A scene of the given geometry, materials and lights with simple settings for everything
    /// else (camera at the origin looking down +z, fov 45; 256x256 film; 0.5-pixel box filter;
    /// 1 sample; the photon mapper): for tests and generated benchmark scenes, which override
    /// what they need with struct-update syntax.
    pub fn with_geometry(meshes: Vec<Mesh>, materials: Vec<Material>, lights: Vec<Light>) -> Scene {
        Scene {
            meshes,
            materials,
            lights,
            media: Vec::new(),
            light_media: Vec::new(),
            camera_medium: None,
            media_need_tracking: None,
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
        if !self.media.is_empty() {
            h = hash(&[h, text(format!("{:?}", self.media))]);
        }
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
            if let Some(mi) = &m.interface {
                h = hash(&[h, text(format!("{mi:?}"))]);
            }
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
