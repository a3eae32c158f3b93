//! `photon check SCENE...`: loads each scene without rendering and prints one line per scene
//! (triangles, lights, materials, `Texture` directives, a memory estimate), then every problem
//! the loader found, each with its `file:line:column`, and the loader's notes (what it accepted
//! but ignores). Exit code 2 if any scene has a problem.
//!
//! ```text
//! $ photon check scenes/cornell-glass.pbrt bathroom/scene-v4.pbrt
//! scenes/cornell-glass.pbrt: ok | 16140 triangles, 1 lights, 5 materials, 0 textures | ~19.2 MB (geometry 0.5, film 3.9, photon maps 14.8, textures 0.0)
//! bathroom/scene-v4.pbrt: 2 problems | 517308 triangles, ...
//!   bathroom/scene-v4.pbrt:20:26: imagemap "bathroom/textures/wood.tga": No such file or directory (os error 2)
//!   bathroom/scene-v4.pbrt:52:5: unsupported material type "coateddiffuse"
//! ```
//!
//! The loader runs in its collect mode ([`crate::scene::loader::load_collecting`]): a directive
//! with an error is recorded and skipped, so one run lists every problem of a scene, while a
//! render stops at the first. The `Integrator` parameters are checked as a render checks them.

use super::ToolError;
use crate::integrator::RenderSettings;
use crate::scene::loader::load_collecting;
use crate::scene::{Scene, SceneError};
use clap::Args;
use std::fmt;
use std::path::{Path, PathBuf};

/// `photon check` options.
#[derive(Args, Debug, Clone)]
pub struct CheckOptions {
    /// The scene files to check.
    #[arg(required = true)]
    pub scenes: Vec<PathBuf>,
}

/// Bytes per vertex of a mesh: position and normal (12 B each), uv (8 B).
const VERTEX_BYTES: u64 = 12 + 12 + 8;
/// Bytes per triangle: three u32 indices.
const TRIANGLE_BYTES: u64 = 12;
/// Bytes per film pixel: the sum and the four component images, RGB f32 each.
const PIXEL_BYTES: u64 = 5 * 12;
/// Bytes per stored photon: the 20-byte record plus the kd-tree's share: its coordinates in
/// tree order (12 B), the tree-order index (4 B) and 8-byte split nodes, one per 16 photons
/// (leaves of 32), rounded up.
const PHOTON_BYTES: u64 = 20 + 12 + 4 + 1;

/// A rough memory estimate of a render, in bytes: what stays resident. It leaves out the
/// ray-tracing BVH (which depends on the backend), the irradiance cache, per-thread buffers and
/// the photon buffers of the map build, and counts one stored photon per emitted photon (the
/// global map stores one per diffuse bounce: 1.5 per emitted photon in the Cornell box, more
/// in bright closed scenes). Take it as a lower bound: Bitterli's Cornell box (64x64, 200k
/// global photons, estimate 7.6 MB) peaked 31 MB above the process's baseline.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct MemoryEstimate {
    /// Mesh vertices (as if every mesh had normals and uvs) and indices.
    pub geometry: u64,
    /// The film's images at the file's resolution.
    pub film: u64,
    /// The global and caustic maps at the photon counts the file asks for (or the defaults);
    /// no caustic map in a scene without specular surfaces.
    pub photons: u64,
    /// The decoded texture images and MIP pyramids, each counted once however many textures
    /// share it, and the environment maps with their sampling tables.
    pub textures: u64,
}

impl MemoryEstimate {
    /// The estimate for `scene`, with `photons` emitted in all (both maps).
    pub fn of(scene: &Scene, photons: u64) -> MemoryEstimate {
        let geometry = scene
            .meshes
            .iter()
            .map(|m| {
                m.positions.len() as u64 * VERTEX_BYTES + m.indices.len() as u64 * TRIANGLE_BYTES
            })
            .sum();
        MemoryEstimate {
            geometry,
            film: scene.film.xres as u64 * scene.film.yres as u64 * PIXEL_BYTES,
            photons: photons * PHOTON_BYTES,
            textures: scene.textures.decoded_bytes() + scene.light_map_bytes(),
        }
    }

    pub fn total(&self) -> u64 {
        self.geometry + self.film + self.photons + self.textures
    }
}

impl fmt::Display for MemoryEstimate {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let mb = |b: u64| b as f64 / 1e6;
        write!(
            f,
            "~{:.1} MB (geometry {:.1}, film {:.1}, photon maps {:.1}, textures {:.1})",
            mb(self.total()),
            mb(self.geometry),
            mb(self.film),
            mb(self.photons),
            mb(self.textures)
        )
    }
}

/// What `check` found in one scene.
#[derive(Debug)]
pub struct SceneReport {
    pub path: PathBuf,
    pub triangles: usize,
    pub lights: usize,
    pub materials: usize,
    /// `Texture` directives read (parsed, but a material that uses one is still a problem).
    pub textures: usize,
    pub memory: MemoryEstimate,
    /// Every error, in file order.
    pub problems: Vec<SceneError>,
    /// What the loader accepted but ignores.
    pub notes: Vec<String>,
}

impl fmt::Display for SceneReport {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let status = match self.problems.len() {
            0 => "ok".to_string(),
            1 => "1 problem".to_string(),
            n => format!("{n} problems"),
        };
        write!(
            f,
            "{}: {status} | {} triangles, {} lights, {} materials, {} textures | {}",
            self.path.display(),
            self.triangles,
            self.lights,
            self.materials,
            self.textures,
            self.memory
        )?;
        let line = |s: String| crate::scene::one_line(&s, crate::scene::MAX_LINE - 2);
        for p in &self.problems {
            write!(f, "\n  {}", line(p.to_string()))?;
        }
        for n in &self.notes {
            write!(f, "\n  {}", line(format!("note: {n}")))?;
        }
        Ok(())
    }
}

/// Loads `path` in collect mode and reports on it.
pub fn check_scene(path: &Path) -> SceneReport {
    let got = load_collecting(path);
    let mut problems = got.errors;
    let scene = got.scene;
    let settings = RenderSettings::from_scene(&scene).or_else(|e| {
        problems.push(e);
        RenderSettings::from_scene(&Scene::with_geometry(Vec::new(), Vec::new(), Vec::new()))
    });
    // As a render does, no caustic map without a specular (non-diffuse) surface.
    let specular = scene.meshes.iter().any(|m| {
        scene
            .materials
            .get(m.material as usize)
            .is_some_and(|m| m.kind.flags().has_specular())
    });
    let photons = settings.map_or(0, |s| {
        s.photon.trace.global_photons + u64::from(specular) * s.photon.trace.caustic_photons
    });
    SceneReport {
        path: path.to_path_buf(),
        triangles: scene.triangle_count(),
        lights: scene.lights.len(),
        materials: scene.materials.len(),
        textures: got.textures,
        memory: MemoryEstimate::of(&scene, photons),
        problems,
        notes: scene.notes,
    }
}

/// Checks every scene, printing each report; an error (exit code 2) if any has a problem.
pub fn run(opts: &CheckOptions) -> Result<(), ToolError> {
    let mut bad = 0;
    for path in &opts.scenes {
        let report = check_scene(path);
        println!("{report}");
        bad += usize::from(!report.problems.is_empty());
    }
    if bad > 0 {
        return Err(ToolError(format!(
            "{bad} of {} scenes have problems",
            opts.scenes.len()
        )));
    }
    Ok(())
}
