//! The integration tests: one binary (`cargo test --release --test it`), one module per area,
//! helpers in [`support`]. `tests/output_signal.rs` stays a binary of its own: it raises the
//! process-wide SIGINT/SIGTERM flag, which every other test's render would then see.
//!
//! Run one area with a filter: `cargo test --release --test it hostile::`.
mod support;

mod alpha;
mod aovs;
mod backends;
mod bench;
mod bidirectional;
mod bilinear;
mod camera_film;
mod check;
mod cli;
mod coated;
mod converge;
mod crosscheck;
mod curtains;
mod denoise;
mod direct_light;
mod display;
mod envlight;
mod exr;
mod fuzz;
mod glossy_paths;
mod hard_cases;
mod hostile;
mod image_tools;
mod kdtree;
mod lamp_can;
mod layers;
mod maxdepth;
mod media;
mod orthographic;
mod parser;
mod passes;
mod path_tracer;
mod photonmap;
mod regression;
mod render_scenes;
mod sky_lit;
mod spectral;
mod textures;
mod thin_tubes;
mod upgrade;
mod windows;
