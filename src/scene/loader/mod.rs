//! The pbrt-v4 scene loader: [`load`] reads a scene file (and the files it includes and the
//! PLY meshes it names) into a [`Scene`].
//!
//! ```text
//! LookAt 0 1 6.8  0 1 0  0 1 0
//! Camera "perspective" "float fov" [ 19.5 ]
//! Film "rgb" "integer xresolution" [ 1024 ] "integer yresolution" [ 1024 ]
//! Sampler "independent" "integer pixelsamples" [ 64 ]
//! WorldBegin
//! AttributeBegin
//!     AreaLightSource "diffuse" "rgb L" [ 17 12 4 ]
//!     Shape "trianglemesh" "point3 P" [ -1 2 -1  1 2 -1  1 2 1 ]
//! AttributeEnd
//! Shape "plymesh" "string filename" "meshes/bunny.ply"
//! ```
//!
//! Modules: [`tokenizer`] (tokens with line and column), [`params`] (parameter lists with
//! used-tracking), [`parser`] (directives and graphics state; materials are [`crate::material`], named spectra
//! `material/spectra.rs`), [`blackbody`] (blackbody emission as RGB), [`textures`]
//! (`Texture` directives, image files), [`lights`], [`shapes`] (meshes, spheres, disks,
//! cylinders) and [`ply`] (PLY files).
//!
//! Whatever the scene says that photon would not render as written is an error, one line,
//! `file:line:column: what is wrong`: an unknown or unsupported directive or type, a parameter
//! that is given but never read, a wrong type or count of values, a missing or malformed file.
//! See the README for the supported subset.
//!
//! Scene and PLY files whose names end in `.gz` are decompressed ([`read_input`]), under the
//! same size caps as plain files.
//!
//! [`load`] stops at the first error; [`load_collecting`] (for `photon check`) records each
//! error, skips the directive it is in and reads on, so one pass lists every problem.
pub mod bilinear;
pub mod extent;
pub mod lights;
pub use crate::params;
pub mod parser;
pub mod ply;
pub mod shapes;
pub mod textures;
pub mod tokenizer;

pub use crate::limits::{read_capped, LoadBudget};

use super::{Scene, SceneError};
use std::path::Path;

/// Reads a scene or PLY file as [`read_capped`] does, and when its name ends in `.gz` (as
/// pbrt-v4 decides) decompresses it, at most `cap` bytes of output too: a gzip bomb is an error
/// ("decompresses to more than the limit"), not an allocation failure.
pub fn read_input(path: &Path, cap: u64) -> std::io::Result<Vec<u8>> {
    let bytes = read_capped(path, cap)?;
    if path.extension().is_some_and(|e| e == "gz") {
        return gunzip_capped(&bytes, cap);
    }
    Ok(bytes)
}

/// Decompresses gzip data (every member, as zlib's `gzread` does) into at most `cap` bytes.
pub fn gunzip_capped(gz: &[u8], cap: u64) -> std::io::Result<Vec<u8>> {
    use std::io::{Error, ErrorKind, Read};
    let mut out = Vec::new();
    flate2::read::MultiGzDecoder::new(gz)
        .take(cap + 1)
        .read_to_end(&mut out)
        .map_err(|e| Error::new(ErrorKind::InvalidData, format!("not valid gzip data: {e}")))?;
    if out.len() as u64 > cap {
        return Err(Error::new(
            ErrorKind::InvalidData,
            format!(
                "decompresses to more than the limit of {}",
                crate::limits::human(cap)
            ),
        ));
    }
    Ok(out)
}

/// Loads a pbrt-v4 scene file (and everything it includes) into a [`Scene`], its data files
/// within the default memory budget ([`crate::limits::default_budget`]).
pub fn load(path: &Path) -> Result<Scene, SceneError> {
    load_within(path, crate::limits::default_budget().bytes)
}

/// [`load`] with the data files' allocations held to `max_memory` bytes ([`LoadBudget`]).
pub fn load_within(path: &Path, max_memory: u64) -> Result<Scene, SceneError> {
    parser::Builder::new(path).budget(max_memory).run()
}

/// What [`load_collecting`] found: the scene as far as it could be read, every error in file
/// order, and how many `Texture` directives there were.
#[derive(Debug)]
pub struct Collected {
    pub scene: Scene,
    pub errors: Vec<SceneError>,
    pub textures: usize,
}

/// Loads a scene the way [`load`] does, but records every error and goes on past it: a
/// directive with an error is skipped (a material that fails becomes the default diffuse so
/// that later references to it do not fail too). An error that leaves the rest of a file
/// unreadable (an unterminated string) ends that file.
pub fn load_collecting(path: &Path) -> Collected {
    parser::Builder::new(path).collecting().run_collecting()
}
