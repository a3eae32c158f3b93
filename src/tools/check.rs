//! `photon check SCENE|FOLDER...`: loads each scene (a folder: every scene file under it)
//! without rendering and prints one line per scene
//! (triangles, lights, materials, `Texture` directives, a memory estimate), then every problem
//! the loader found, each with its `file:line:column`, and the loader's notes (what it accepted
//! but ignores). Exit code 2 if any scene has a problem.
//!
//! ```text
//! $ photon check scenes/cornell-glass.pbrt bathroom/scene-v4.pbrt
//! scenes/cornell-glass.pbrt: ok | 16140 triangles, 1 lights, 5 materials, 0 textures | ~71.3 MB (process 13.6, film 7.1, photon maps 43.8, geometry 2.6, threads 4.2)
//! bathroom/scene-v4.pbrt: 2 problems | 517308 triangles, ...
//!   bathroom/scene-v4.pbrt:20:26: imagemap "bathroom/textures/wood.tga": No such file or directory (os error 2)
//!   bathroom/scene-v4.pbrt:52:5: unsupported material type "coateddiffuse"
//! ```
//!
//! The loader runs in its collect mode ([`crate::scene::loader::load_collecting`]): a directive
//! with an error is recorded and skipped, so one run lists every problem of a scene, while a
//! render stops at the first. The `Integrator` parameters are checked as a render checks them,
//! and the memory estimate is the one `render` checks its budget with
//! ([`crate::memory::estimate`], for a default render: photon mapper, Embree, every core),
//! the photon maps sized by the same pilot trace (so `check` builds the Embree BVH).

use super::ToolError;
use crate::accel::{Accel, AccelOptions, BackendKind};
use crate::integrator::{pilot, IntegratorKind, RenderSettings};
use crate::memory::{estimate, summary, Estimate};
use crate::scene::loader::load_collecting;
use crate::scene::{Scene, SceneError};
use clap::Args;
use std::fmt;
use std::path::{Path, PathBuf};

/// `photon check` options.
#[derive(Args, Debug, Clone)]
pub struct CheckOptions {
    /// The scene files to check; a folder stands for every scene file under it (`.pbrt` files
    /// with a `WorldBegin` in their first MiB, so that included geometry and material files
    /// are skipped), in name order.
    #[arg(required = true)]
    pub scenes: Vec<PathBuf>,
}

/// Appends the scene files under folder `dir` (recursively, in name order): `.pbrt` files
/// whose first MiB holds `WorldBegin` (the rest are files that scenes include).
fn scenes_under(dir: &Path, out: &mut Vec<PathBuf>) -> Result<(), ToolError> {
    use std::io::Read;
    let read = |e: std::io::Error| ToolError(format!("{}: {e}", dir.display()));
    let mut entries: Vec<PathBuf> = std::fs::read_dir(dir)
        .map_err(read)?
        .map(|e| e.map(|e| e.path()))
        .collect::<Result<_, _>>()
        .map_err(read)?;
    entries.sort();
    for path in entries {
        if path.is_dir() {
            scenes_under(&path, out)?;
        } else if path.extension().is_some_and(|e| e == "pbrt") {
            let mut head = Vec::new();
            let opened =
                std::fs::File::open(&path).and_then(|f| f.take(1 << 20).read_to_end(&mut head));
            // An unreadable file is listed: its check says why.
            if opened.is_err() || head.windows(10).any(|w| w == b"WorldBegin") {
                out.push(path);
            }
        }
    }
    Ok(())
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
    /// The memory a default render of the scene needs (photon mapper, Embree, every core):
    /// the model `render` checks against its budget ([`crate::memory::estimate`]).
    pub memory: Estimate,
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
            summary(&self.memory)
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
    let settings = settings.unwrap_or_else(|_| {
        let empty = Scene::with_geometry(Vec::new(), Vec::new(), Vec::new());
        RenderSettings::from_scene(&empty).expect("the defaults are valid")
    });
    let threads = std::thread::available_parallelism().map_or(1, |n| n.get());
    // The photon maps as a render measures them: a pilot trace on the scene's accelerator.
    let kinds = (IntegratorKind::Photonmap, BackendKind::Embree);
    let accel = Accel::build(&scene, BackendKind::Embree, AccelOptions::default());
    let landings = accel
        .ok()
        .and_then(|a| pilot(&scene, &a, &settings, IntegratorKind::Photonmap));
    let memory = estimate(&scene, &settings, kinds, threads, landings);
    let mut notes = scene.notes.clone();
    let share = crate::integrator::coloured_share(&scene);
    if let Some(why) = crate::integrator::spectral_auto(IntegratorKind::Photonmap, &scene) {
        notes.push(format!(
            "colour: {why}: RGB may be several percent off pbrt-v4 here (--spectral=auto renders spectrally)"
        ));
    } else if share > 0.0 {
        notes.push(format!(
            "colour: {share:.4} of the surface's light is coloured twice (below {}: --spectral=auto renders RGB)",
            crate::integrator::SPECTRAL_AUTO_SHARE
        ));
    }
    SceneReport {
        path: path.to_path_buf(),
        triangles: scene.triangle_count(),
        lights: scene.lights.len(),
        materials: scene.materials.len(),
        textures: got.textures,
        memory,
        problems,
        notes,
    }
}

/// Checks every scene, printing each report; an error (exit code 2) if any has a problem.
pub fn run(opts: &CheckOptions) -> Result<(), ToolError> {
    let mut bad = 0;
    let mut scenes = Vec::new();
    for path in &opts.scenes {
        if path.is_dir() {
            let before = scenes.len();
            scenes_under(path, &mut scenes)?;
            if scenes.len() == before {
                return Err(ToolError(format!(
                    "{}: no scene file (.pbrt with a WorldBegin) under this folder",
                    path.display()
                )));
            }
        } else {
            scenes.push(path.clone());
        }
    }
    for path in &scenes {
        let report = check_scene(path);
        say!("{report}");
        bad += usize::from(!report.problems.is_empty());
    }
    if bad > 0 {
        return Err(ToolError(format!(
            "{bad} of {} scenes have problems",
            scenes.len()
        )));
    }
    Ok(())
}
