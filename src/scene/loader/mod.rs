//! STUB: the pbrt-v4 loader is being written.
pub mod params;

use super::{Scene, SceneError};
use std::path::Path;

/// Loads a pbrt-v4 scene file (and everything it includes) into a [`Scene`].
pub fn load(path: &Path) -> Result<Scene, SceneError> {
    Err(SceneError::new(format!(
        "{}: loader not yet implemented",
        path.display()
    )))
}
