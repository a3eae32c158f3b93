//! The subcommands of the `photon` binary, one module each, callable from tests too.
pub mod bench;
pub mod check;
pub mod compare;
pub mod converge;
pub mod crosscheck;
pub mod meshgen;
pub mod rays;
pub mod render;

use std::fmt;

/// An error a subcommand reports as one line (exit code 2).
#[derive(Debug)]
pub struct ToolError(pub String);

impl fmt::Display for ToolError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.0)
    }
}

impl std::error::Error for ToolError {}

macro_rules! from_error {
    ($($t:ty),*) => {$(
        impl From<$t> for ToolError {
            fn from(e: $t) -> Self {
                ToolError(e.to_string())
            }
        }
    )*};
}
from_error!(
    crate::scene::SceneError,
    crate::accel::AccelError,
    crate::imageio::ImageError
);

/// Parses `WxH` (e.g. `256x256`).
pub fn parse_resolution(s: &str) -> Result<(u32, u32), String> {
    let (w, h) = s
        .split_once(['x', 'X'])
        .ok_or_else(|| format!("expected WxH, got {s:?}"))?;
    let w: u32 = w
        .trim()
        .parse()
        .map_err(|_| format!("bad width in {s:?}"))?;
    let h: u32 = h
        .trim()
        .parse()
        .map_err(|_| format!("bad height in {s:?}"))?;
    if w == 0 || h == 0 || w > 1 << 15 || h > 1 << 15 {
        return Err(format!("resolution {w}x{h} out of range (1..32768)"));
    }
    Ok((w, h))
}

/// A rayon pool of `threads` workers (0 = all cores) with flush-to-zero set on each.
pub fn thread_pool(threads: usize) -> Result<rayon::ThreadPool, ToolError> {
    rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .start_handler(|_| crate::accel::embree::enable_flush_denormals())
        .build()
        .map_err(|e| ToolError(format!("cannot start {threads} threads: {e}")))
}
