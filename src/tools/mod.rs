//! The subcommands of the `photon` binary, one module each, callable from tests too.

/// `println!` that a closed or failing standard output does not stop: `photon render | head
/// -1` loses the rest of the text, not the render (`println!` panics on EPIPE). Silent after
/// [`set_quiet`].
macro_rules! say {
    ($($arg:tt)*) => {{
        use std::io::Write as _;
        if !$crate::tools::quiet() {
            let _ = writeln!(std::io::stdout(), $($arg)*);
        }
    }};
}

/// `print!` that a closed or failing standard output does not stop (see `say!`).
macro_rules! say_part {
    ($($arg:tt)*) => {{
        use std::io::Write as _;
        if !$crate::tools::quiet() {
            let mut out = std::io::stdout();
            let _ = write!(out, $($arg)*);
            let _ = out.flush();
        }
    }};
}

static QUIET: std::sync::atomic::AtomicBool = std::sync::atomic::AtomicBool::new(false);

/// `render --quiet`: from now on the subcommands print nothing on standard output (errors and
/// warnings still go to standard error).
pub fn set_quiet(quiet: bool) {
    QUIET.store(quiet, std::sync::atomic::Ordering::Relaxed);
}

/// True after [`set_quiet`]`(true)`.
pub fn quiet() -> bool {
    QUIET.load(std::sync::atomic::Ordering::Relaxed)
}

/// `eprintln!` that a closed or failing standard error does not stop (see `say!`).
macro_rules! say_err {
    ($($arg:tt)*) => {{
        use std::io::Write as _;
        let _ = writeln!(std::io::stderr(), $($arg)*);
    }};
}

pub mod bench;
pub mod check;
pub mod compare;
pub mod converge;
pub mod convert;
pub mod crosscheck;
pub mod denoise;
pub mod display;
pub mod job;
pub mod merge;
pub mod output;
pub mod progress;
pub mod render;
pub mod render_passes;
pub mod upgrade;

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
    let max = crate::limits::MAX_RESOLUTION;
    if w == 0 || h == 0 || w > max || h > max {
        return Err(format!("resolution {w}x{h} out of range (1..={max} each)"));
    }
    Ok((w, h))
}

/// A clap value parser for an integer in `lo..=hi`.
pub fn usize_in(lo: usize, hi: usize) -> impl Fn(&str) -> Result<usize, String> + Clone {
    move |s| {
        let v: usize = s
            .trim()
            .parse()
            .map_err(|_| format!("expected an integer in {lo}..={hi}, got {s:?}"))?;
        crate::limits::check_range(v, lo, hi)
    }
}

/// A clap value parser for a finite float in `[lo, hi]` (`(lo, hi]` when `open`).
pub fn float_in(lo: f32, hi: f32, open: bool) -> impl Fn(&str) -> Result<f32, String> + Clone {
    move |s| {
        let v: f32 = s
            .trim()
            .parse()
            .map_err(|_| format!("expected a number, got {s:?}"))?;
        crate::limits::check_float(v, lo, hi, open)
    }
}

pub use job::thread_pool;
