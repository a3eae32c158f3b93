//! photon as a Python module (`import photon`), built with maturin:
//!
//! ```python
//! import photon
//! scene = photon.load("scene.pbrt", spp=16)          # a loading error raises photon.PhotonError
//! layers = scene.render(resolution=(256, 256), seed=1) # {"beauty": HxWx3 float32, "direct": ...}
//! ```
//!
//! Options are `photon render`'s flags as keywords (`max_depth=3` is `--max-depth 3`,
//! `resolution=(w, h)` is `--res WxH`, `passes=8` or `range(4, 8)` is `--passes`, a plain
//! flag takes `True`); they are parsed and checked by the command line's own parser, so the
//! values, limits and messages are the CLI's, and an image rendered here equals the CLI's EXR
//! at the same seed bit for bit. `load`'s keywords apply to every render of the scene,
//! `render`'s replace them for one render. Options about files and the console (`output`,
//! `checkpoint`, `display_server`, ...) are refused.
//!
//! `render` releases the GIL while it renders; the calling thread wakes every 50 ms to let
//! Python handle signals: Ctrl-C (KeyboardInterrupt) or an exception from the `progress`
//! callback stops the render within a tile or a pass and is raised again.
use numpy::{PyArray1, PyArrayMethods, PyUntypedArrayMethods};
use photon::imageio::{read_linear, RgbImage};
use photon::integrator::{Observer, RenderOutput};
use photon::interrupt::{self, Signal};
use photon::scene::Scene;
use photon::tools::job::Job;
use photon::tools::render::{self, RenderOptions};
use photon::tools::render_passes::{pass_end, render_in_memory};
use photon::tools::ToolError;
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList, PyRange, PyRangeMethods, PyTuple};
use std::path::PathBuf;
use std::sync::atomic::{AtomicU64, Ordering::Relaxed};
use std::sync::{mpsc, Arc};
use std::time::{Duration, Instant};

pyo3::create_exception!(
    photon,
    PhotonError,
    PyValueError,
    "A scene that does not load or an option that is wrong; the message is the command \
     line's (file:line:column for scene errors)."
);

/// `photon render`'s options, parsed from keywords turned into arguments.
#[derive(clap::Parser, Debug)]
#[command(name = "render", no_binary_name = true)]
struct RenderCli {
    #[command(flatten)]
    opts: RenderOptions,
}

/// Options that name files or talk to the console: the command line's alone.
const REFUSED: &[&str] = &[
    "output",
    "png",
    "no-png",
    "checkpoint",
    "resume",
    "every",
    "display-server",
    "exposure",
    "half",
    "stats",
    "denoise",
];

/// One option given as a keyword: its long flag name and the arguments it becomes.
type Given = (String, Vec<String>);

/// The long flag a keyword stands for (`max_depth` -> `max-depth`, `resolution` -> `res`).
fn long_name(key: &str) -> String {
    match key {
        "resolution" => "res".to_string(),
        k => k.replace('_', "-"),
    }
}

/// The arguments of the keyword `key=value` (`None`: the option is left out).
fn arguments(key: &str, value: &Bound<'_, PyAny>) -> PyResult<Option<Given>> {
    let long = long_name(key);
    if REFUSED.contains(&long.as_str()) {
        return Err(PhotonError::new_err(format!(
            "{key}: a file or console option of the command line, not available here"
        )));
    }
    use clap::CommandFactory;
    let command = RenderCli::command();
    let Some(arg) = command
        .get_arguments()
        .find(|a| a.get_long() == Some(long.as_str()))
    else {
        return Err(PhotonError::new_err(format!(
            "{key}: no such option (the options are photon render's flags: `photon render --help`)"
        )));
    };
    let flag = format!("--{long}");
    let is_switch = matches!(arg.get_action(), clap::ArgAction::SetTrue);
    if value.is_none() {
        return Ok(None);
    }
    if let Ok(b) = value.cast::<pyo3::types::PyBool>() {
        let b = b.is_true();
        return Ok(match (is_switch, b) {
            (true, true) => Some((long, vec![flag])),
            (true, false) => None,
            // `--x=v`: some options take their value only after an equals sign.
            (false, _) => Some((long, vec![format!("{flag}={b}")])),
        });
    }
    if is_switch {
        return Err(PhotonError::new_err(format!(
            "{key}: a switch: give True or False"
        )));
    }
    let text = if let Ok(r) = value.cast::<PyRange>() {
        if r.step()? != 1 {
            return Err(PhotonError::new_err(format!("{key}: a range with step 1")));
        }
        format!("{}..{}", r.start()?, r.stop()?)
    } else if value.is_instance_of::<PyTuple>() || value.is_instance_of::<PyList>() {
        let parts: Vec<String> = value
            .try_iter()?
            .map(|v| v.and_then(|v| v.str().map(|s| s.to_string())))
            .collect::<PyResult<_>>()?;
        let sep = if long == "passes" { ".." } else { "x" };
        parts.join(sep)
    } else {
        value.str()?.to_string()
    };
    Ok(Some((long, vec![format!("{flag}={text}")])))
}

/// `given` with `more` replacing the options both have.
fn merged(given: &[Given], kwargs: Option<&Bound<'_, PyDict>>) -> PyResult<Vec<Given>> {
    let mut all = given.to_vec();
    if let Some(kw) = kwargs {
        for (k, v) in kw.iter() {
            let key: String = k.extract()?;
            let long = long_name(&key);
            all.retain(|(l, _)| *l != long);
            if let Some(g) = arguments(&key, &v)? {
                all.push(g);
            }
        }
    }
    Ok(all)
}

/// Parses `given` as `photon render SCENE ...` would.
fn parse(scene: &std::path::Path, given: &[Given]) -> PyResult<RenderOptions> {
    use clap::Parser;
    let mut argv: Vec<std::ffi::OsString> = vec![scene.as_os_str().to_owned()];
    argv.extend(given.iter().flat_map(|(_, a)| a.iter().map(Into::into)));
    match RenderCli::try_parse_from(argv) {
        Ok(cli) => Ok(cli.opts),
        Err(e) => {
            let text = e.render().to_string();
            let line = text.lines().next().unwrap_or("bad option");
            Err(PhotonError::new_err(
                line.trim_start_matches("error: ").to_string(),
            ))
        }
    }
}

fn tool_error(e: ToolError) -> PyErr {
    PhotonError::new_err(e.0)
}

/// A loaded scene: render it any number of times with different options.
#[pyclass(name = "Scene", module = "photon", frozen, weakref)]
struct PyScene {
    scene: Arc<Scene>,
    path: PathBuf,
    given: Vec<Given>,
}

/// Loads the pbrt-v4 scene at `path`; `overrides` are render options kept for every render.
#[pyfunction]
#[pyo3(signature = (path, **overrides))]
fn load(py: Python<'_>, path: PathBuf, overrides: Option<&Bound<'_, PyDict>>) -> PyResult<PyScene> {
    let given = merged(&[], overrides)?;
    let opts = parse(&path, &given)?;
    let job = py
        .detach(|| Job::load(&path, opts.max_memory))
        .map_err(tool_error)?;
    Ok(PyScene {
        scene: Arc::new(job.scene.into_owned()),
        path,
        given,
    })
}

/// What the render thread reports to the calling one: how far the render is.
struct Progress {
    /// Tiles of the pass in progress: finished, and in all.
    done: AtomicU64,
    tiles: AtomicU64,
    /// Passes finished, and in all (0 until known; 1 for a render in one go).
    passes_done: AtomicU64,
    passes: AtomicU64,
    /// A time budget's seconds: then the fraction is the time spent.
    budget: Option<f64>,
    start: Instant,
}

impl Progress {
    fn new(budget: Option<f64>) -> Progress {
        Progress {
            done: AtomicU64::new(0),
            tiles: AtomicU64::new(0),
            passes_done: AtomicU64::new(0),
            passes: AtomicU64::new(0),
            budget,
            start: Instant::now(),
        }
    }

    /// The fraction of the render done, in [0, 1].
    fn fraction(&self) -> f64 {
        if let Some(b) = self.budget {
            return (self.start.elapsed().as_secs_f64() / b).min(1.0);
        }
        let passes = self.passes.load(Relaxed);
        if passes == 0 {
            return 0.0;
        }
        let tiles = self.tiles.load(Relaxed);
        let in_pass = match tiles {
            0 => 0.0,
            t => self.done.load(Relaxed).min(t) as f64 / t as f64,
        };
        let done = self.passes_done.load(Relaxed) as f64 + in_pass;
        (done / passes as f64).min(1.0)
    }
}

impl Observer for Progress {
    fn tile_done(&self, done: u64, total: u64) {
        self.tiles.store(total, Relaxed);
        self.done.fetch_max(done, Relaxed);
    }

    fn image(&self, _: &RgbImage, _: &[(&'static str, RgbImage)], _: u64) {
        // After the pass's last tile: the next pass starts from none.
        self.done.store(0, Relaxed);
        self.passes_done.fetch_add(1, Relaxed);
    }
}

/// Loads, prepares and renders as `photon render` does, in memory.
fn render_scene(
    scene: &Scene,
    opts: &RenderOptions,
    progress: &Progress,
) -> Result<RenderOutput, ToolError> {
    let mut job = Job::borrowing(scene)?.with(&opts.overrides());
    render::configure(&mut job, opts);
    let mut prepared = render::prepare(&mut job, opts)?;
    if opts.passes.active(opts.time.is_some()) {
        let start = opts.passes.passes.as_ref().map_or(0, |r| r.start);
        let passes = pass_end(opts, &job.settings) - start;
        progress.passes.store(passes, Relaxed);
        let p = &prepared;
        Ok(render_in_memory(
            opts,
            &job.scene,
            &p.accel,
            &job.settings,
            &p.pool,
            progress,
        ))
    } else {
        progress.passes.store(1, Relaxed);
        render::render_image(&job, &mut prepared, opts, progress)
    }
}

/// An image as a float32 array of shape (height, width, 3).
fn to_array<'py>(py: Python<'py>, image: &RgbImage) -> PyResult<Bound<'py, PyAny>> {
    let flat: Vec<f32> = image.pixels.iter().flatten().copied().collect();
    let a = PyArray1::from_vec(py, flat).reshape([image.height, image.width, 3])?;
    Ok(a.into_any())
}

#[pymethods]
impl PyScene {
    /// Renders the scene; keywords are `photon render`'s options (see the module's doc).
    /// `progress(fraction)` is called from this thread with the fraction done, in [0, 1] (of
    /// the tiles, of the passes' tiles, or of a `time=` budget), at most every 50 ms when it
    /// grew, and with 1.0 at the end; an exception it raises stops the render and propagates. Returns a dict of float32
    /// arrays (height, width, 3): "beauty" and the component layers, which sum to it.
    #[pyo3(signature = (progress=None, **options))]
    fn render<'py>(
        &self,
        py: Python<'py>,
        progress: Option<Bound<'py, PyAny>>,
        options: Option<&Bound<'py, PyDict>>,
    ) -> PyResult<Bound<'py, PyDict>> {
        let given = merged(&self.given, options)?;
        let opts = parse(&self.path, &given)?;
        let watch = Progress::new(opts.time);
        interrupt::take();
        let mut stop: Option<PyErr> = None;
        let mut reported = -1.0f64;
        let out = std::thread::scope(|s| {
            let (tx, mut rx) = mpsc::channel::<()>();
            let (scene, opts, watch) = (&*self.scene, &opts, &watch);
            let worker = s.spawn(move || {
                let out = render_scene(scene, opts, watch);
                let _ = tx.send(());
                out
            });
            loop {
                // The receiver moves to the GIL-free wait and back (it is not Sync).
                let finished;
                (finished, rx) = py.detach(move || {
                    let wait = rx.recv_timeout(Duration::from_millis(50));
                    (!matches!(wait, Err(mpsc::RecvTimeoutError::Timeout)), rx)
                });
                if stop.is_none() {
                    // 1.0 only once the render has finished (a budget's clock runs out first).
                    let now = if finished {
                        1.0
                    } else {
                        watch.fraction().min(0.999)
                    };
                    let called = match &progress {
                        Some(cb) if now > reported => {
                            reported = now;
                            cb.call1((now,)).map(drop)
                        }
                        _ => Ok(()),
                    };
                    if let Err(e) = called.and_then(|_| py.check_signals()) {
                        interrupt::raise(Signal::Interrupt);
                        stop = Some(e);
                    }
                }
                if finished {
                    break;
                }
            }
            worker.join()
        });
        interrupt::take();
        if let Some(e) = stop {
            return Err(e);
        }
        let out = match out {
            Ok(r) => r.map_err(tool_error)?,
            Err(_) => return Err(PhotonError::new_err("the render failed (a panic)")),
        };
        let dict = PyDict::new(py);
        dict.set_item("beauty", to_array(py, &out.image)?)?;
        for (name, layer) in &out.components {
            dict.set_item(*name, to_array(py, layer)?)?;
        }
        Ok(dict)
    }

    /// The scene file.
    #[getter]
    fn path(&self) -> PathBuf {
        self.path.clone()
    }

    /// (width, height) of a render with the load-time options.
    #[getter]
    fn resolution(&self) -> PyResult<(u32, u32)> {
        let opts = parse(&self.path, &self.given)?;
        let job = Job::borrowing(&self.scene)
            .map_err(tool_error)?
            .with(&opts.overrides());
        Ok(job.settings.image_size())
    }

    fn __repr__(&self) -> String {
        format!(
            "photon.Scene({:?}: {} meshes, {} triangles, {} lights)",
            self.path.display().to_string(),
            self.scene.meshes.len(),
            self.scene.triangle_count(),
            self.scene.lights.len()
        )
    }
}

/// An image argument: an EXR, PNG or PFM path, or an array of shape (height, width, 3).
fn image_of(py: Python<'_>, x: &Bound<'_, PyAny>) -> PyResult<RgbImage> {
    let os = py.import("os")?;
    if x.is_instance(&os.getattr("PathLike")?)? || x.is_instance_of::<pyo3::types::PyString>() {
        let path: PathBuf = x.extract()?;
        return read_linear(&path, None).map_err(|e| PhotonError::new_err(e.to_string()));
    }
    let np = py.import("numpy")?;
    let a = np.call_method1("ascontiguousarray", (x, "float32"))?;
    let a = a.cast_into::<numpy::PyArray3<f32>>().map_err(|_| {
        PhotonError::new_err("an image is an EXR path or an array of shape (height, width, 3)")
    })?;
    let shape = a.shape().to_vec();
    if shape[2] != 3 {
        return Err(PhotonError::new_err(format!(
            "an image array has shape (height, width, 3), not {shape:?}"
        )));
    }
    let ro = a.readonly();
    let data = ro.as_slice()?;
    Ok(RgbImage {
        width: shape[1],
        height: shape[0],
        pixels: data.chunks_exact(3).map(|p| [p[0], p[1], p[2]]).collect(),
    })
}

/// `photon compare`'s metrics of `image` against `reference` (EXR, PNG or PFM paths, or
/// arrays), LDR-FLIP with its defaults included, as the dict `photon compare --json` prints.
#[pyfunction]
#[pyo3(signature = (image, reference, downsample=false, mask_above=None))]
fn compare<'py>(
    py: Python<'py>,
    image: &Bound<'py, PyAny>,
    reference: &Bound<'py, PyAny>,
    downsample: bool,
    mask_above: Option<f32>,
) -> PyResult<Bound<'py, PyAny>> {
    use photon::imageio::metrics;
    use photon::tools::compare;
    let (a, b) = (image_of(py, image)?, image_of(py, reference)?);
    let (a, b) = match downsample {
        true => metrics::match_sizes(a, b).map_err(PhotonError::new_err)?,
        false => (a, b),
    };
    let mask = metrics::MaskOptions { mask_above };
    let flip = metrics::FlipOptions::default();
    let (m, f) = compare::measure(&a, &b, mask, flip).map_err(PhotonError::new_err)?;
    let json = compare::to_json(&m, f, flip);
    py.import("json")?.call_method1("loads", (json,))
}

#[pymodule]
#[pyo3(name = "photon")]
fn photon_py(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(load, m)?)?;
    m.add_function(wrap_pyfunction!(compare, m)?)?;
    m.add_class::<PyScene>()?;
    m.add("PhotonError", m.py().get_type::<PhotonError>())?;
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    Ok(())
}
