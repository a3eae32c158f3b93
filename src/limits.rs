//! Limits on every count and size a scene file or the command line gives (a leaf: the loader,
//! the settings and the CLI read it, it reads nothing of the crate), the memory budget a render
//! must fit ([`default_budget`], `--max-memory`), the loader's budget for the data files it
//! decodes ([`LoadBudget`], [`read_capped`]), and the range checks and size parsing the loader
//! and the flags share.
//!
//! ```text
//! Film "rgb" "integer xresolution" [ 1024 ] "integer yresolution" [ 1024 ]   # 1..=32768 each
//! Integrator "photonmap" "integer globalphotons" [ 200000 ]   # 0..=2^32-1, and the budget
//!     "integer gathersamples" [ 2 ]  "integer globallookup" [ 100 ]   # see the constants below
//! ```
//! and on the command line `photon render ... --max-memory 8G` (default: [`DEFAULT_FRACTION`]
//! of `MemTotal` in /proc/meminfo, or of what an address-space limit leaves, whichever is
//! smaller). The memory model the budget is checked against is [`crate::memory`].
use std::path::Path;

/// Largest image side, in pixels.
pub const MAX_RESOLUTION: u32 = 32768;
/// Largest samples per pixel.
pub const MAX_SPP: u32 = 1 << 20;
/// Longest duration a flag takes (`--time`, `--every`): a year.
pub const MAX_SECONDS: f64 = 365.0 * 24.0 * 3600.0;
/// Largest pass number + 1 of a render in passes (`--passes A..B`, a `--resume` file's range,
/// `--time` with passes): as many passes as samples per pixel, and the radius schedule of the
/// last one (a product over the passes before it) takes milliseconds, not days.
pub const MAX_PASSES: u64 = 1 << 20;
/// Largest final-gather rays per diffuse point.
pub const MAX_GATHER_SAMPLES: u32 = 4096;
/// Largest shadow rays per shading point.
pub const MAX_LIGHT_SAMPLES: u32 = 4096;
/// Largest photons per lookup.
pub const MAX_LOOKUP: usize = 100_000;
/// Largest photon count per map (sample streams index photons with 32 bits).
pub const MAX_PHOTONS: u64 = u32::MAX as u64;
/// Largest `maxdepth` and `maxphotonbounces`: a path that is still alive after this many
/// bounces contributes nothing measurable, and time grows linearly with it.
pub const MAX_DEPTH: u32 = 1000;
/// Largest worker-thread count.
pub const MAX_THREADS: usize = 1024;
/// Largest lookup radius, as a fraction of the scene's bounding radius.
pub const MAX_RADIUS: f32 = 4.0;
/// Largest |PNG exposure| in stops.
pub const MAX_EXPOSURE: f32 = 64.0;
/// Largest scene or included file, in bytes.
pub const MAX_SCENE_FILE: u64 = 1 << 30;
/// Most pixels an image file may have (EXR, PFM, PNG, ...), checked from its header before it
/// is decoded: 2^28 pixels is 3.2 GB as linear RGB f32.
pub const MAX_IMAGE_PIXELS: u64 = 1 << 28;
/// Largest PLY file, in bytes.
pub const MAX_PLY_FILE: u64 = 4 << 30;
/// Largest input read from something that is not a regular file (a FIFO, a device such as
/// /dev/zero that never ends): its size is not known before reading.
pub const MAX_STREAM_FILE: u64 = 64 << 20;
/// Pending gather or shadow rays per tile before they are traced (a batch); a point adds at most
/// [`MAX_GATHER_SAMPLES`] or [`MAX_LIGHT_SAMPLES`] more before the next flush.
pub const BATCH: usize = 1 << 14;
/// Default budget: this fraction of physical memory.
pub const DEFAULT_FRACTION: f64 = 0.8;

/// Where a budget came from, for the message.
#[derive(Clone, Debug)]
pub struct Budget {
    pub bytes: u64,
    pub source: String,
}

impl Budget {
    /// `--max-memory` when given, else [`default_budget`] as it stands now.
    pub fn resolve(max_memory: Option<u64>) -> Budget {
        match max_memory {
            Some(bytes) => Budget {
                bytes,
                source: "--max-memory".to_string(),
            },
            None => default_budget(),
        }
    }
}

/// `"integer NAME" v` must lie in `lo..=hi`: the message when it does not.
pub fn check_range<T: PartialOrd + std::fmt::Display>(v: T, lo: T, hi: T) -> Result<T, String> {
    if v >= lo && v <= hi {
        Ok(v)
    } else {
        Err(format!("must be in {lo}..={hi}, got {v}"))
    }
}

/// A float that must be finite and in `(lo, hi]` (`lo` excluded when `open`).
pub fn check_float(v: f32, lo: f32, hi: f32, open: bool) -> Result<f32, String> {
    let low_ok = if open { v > lo } else { v >= lo };
    if v.is_finite() && low_ok && v <= hi {
        Ok(v)
    } else {
        let l = if open { "(" } else { "[" };
        Err(format!(
            "must be a finite number in {l}{lo}, {hi}], got {v}"
        ))
    }
}

/// Bytes as a short human string: `512 B`, `3.2 MB`, `110 GB` (powers of 1000).
pub fn human(bytes: u64) -> String {
    let b = bytes as f64;
    for (unit, scale) in [("TB", 1e12), ("GB", 1e9), ("MB", 1e6), ("kB", 1e3)] {
        if b >= scale {
            let v = b / scale;
            return if v >= 100.0 {
                format!("{v:.0} {unit}")
            } else {
                format!("{v:.1} {unit}")
            };
        }
    }
    format!("{bytes} B")
}

/// Parses a size: bytes, or with a suffix `k`, `M`, `G`, `T` (powers of 1024; `KiB`, `GB`, ...
/// accepted alike).
pub fn parse_size(s: &str) -> Result<u64, String> {
    let t = s.trim();
    let digits = t
        .find(|c: char| !(c.is_ascii_digit() || c == '.'))
        .unwrap_or(t.len());
    let (num, unit) = t.split_at(digits);
    let shift = match unit
        .trim()
        .to_ascii_lowercase()
        .trim_end_matches(['b', 'i'])
    {
        "" => 0,
        "k" => 10,
        "m" => 20,
        "g" => 30,
        "t" => 40,
        _ => return Err(format!("expected a size such as 512M or 8G, got {s:?}")),
    };
    match num.parse::<f64>() {
        Ok(v) if v.is_finite() && v > 0.0 && v * ((1u64 << shift) as f64) < 1.8e19 => {
            Ok((v * (1u64 << shift) as f64) as u64)
        }
        _ => Err(format!(
            "expected a positive size such as 512M or 8G, got {s:?}"
        )),
    }
}

/// A `kB` field of a /proc file (`MemTotal:  24576000 kB`), in bytes.
fn proc_kb(text: &str, key: &str) -> Option<u64> {
    let line = text.lines().find(|l| l.starts_with(key))?;
    let kb: u64 = line[key.len()..]
        .trim()
        .trim_end_matches("kB")
        .trim()
        .parse()
        .ok()?;
    Some(kb.saturating_mul(1024))
}

/// The soft address-space limit of this process (`ulimit -v`, `prlimit --as`), if any.
fn address_space_limit() -> Option<u64> {
    let text = std::fs::read_to_string("/proc/self/limits").ok()?;
    let line = text.lines().find(|l| l.starts_with("Max address space"))?;
    line.split_whitespace().nth(3)?.parse().ok()
}

/// The default budget: [`DEFAULT_FRACTION`] of physical memory, or of what an address-space
/// limit leaves beyond what is mapped now (libraries, thread stacks), whichever is smaller.
pub fn default_budget() -> Budget {
    let meminfo = std::fs::read_to_string("/proc/meminfo").unwrap_or_default();
    let physical = proc_kb(&meminfo, "MemTotal:").unwrap_or(8 << 30);
    let mut budget = Budget {
        bytes: (physical as f64 * DEFAULT_FRACTION) as u64,
        source: format!(
            "{:.0}% of physical {}",
            DEFAULT_FRACTION * 100.0,
            human(physical)
        ),
    };
    if let Some(limit) = address_space_limit() {
        let status = std::fs::read_to_string("/proc/self/status").unwrap_or_default();
        let mapped = proc_kb(&status, "VmSize:").unwrap_or(0);
        let left = (limit.saturating_sub(mapped) as f64 * DEFAULT_FRACTION) as u64;
        if left < budget.bytes {
            budget = Budget {
                bytes: left,
                source: format!(
                    "{:.0}% of what address-space limit {} leaves",
                    DEFAULT_FRACTION * 100.0,
                    human(limit)
                ),
            };
        }
    }
    budget
}

/// This process's peak resident memory (`VmHWM` in /proc/self/status), in bytes.
pub fn peak_resident() -> Option<u64> {
    proc_kb(
        &std::fs::read_to_string("/proc/self/status").ok()?,
        "VmHWM:",
    )
}

/// Reads at most `cap` bytes of `path`: a larger file (or a device such as /dev/zero that never
/// ends) is an error without reading past the cap. A directory is an error too.
pub fn read_capped(path: &Path, cap: u64) -> std::io::Result<Vec<u8>> {
    use std::io::{Error, ErrorKind, Read};
    let file = std::fs::File::open(path)?;
    let meta = file.metadata()?;
    let too_big = |cap: u64| {
        Error::new(
            ErrorKind::InvalidData,
            format!("larger than the limit of {}", human(cap)),
        )
    };
    if meta.is_dir() {
        return Err(Error::new(ErrorKind::InvalidInput, "is a directory"));
    }
    let cap = if meta.is_file() {
        cap
    } else {
        cap.min(MAX_STREAM_FILE)
    };
    if meta.is_file() && meta.len() > cap {
        return Err(too_big(cap));
    }
    let mut bytes = Vec::new();
    if meta.is_file() {
        bytes
            .try_reserve_exact(meta.len() as usize)
            .map_err(|_| Error::new(ErrorKind::OutOfMemory, "not enough memory to read it"))?;
    }
    file.take(cap + 1).read_to_end(&mut bytes)?;
    if bytes.len() as u64 > cap {
        return Err(too_big(cap));
    }
    Ok(bytes)
}

/// What the loader may allocate for the data files a scene names (decoded images, PLY meshes,
/// instanced copies): every size read from a file header is reserved here before the
/// allocation it implies, so that a 249 kB PNG declaring 16000x16000 pixels or 20,000
/// instances of a large object is an error naming the file, not gigabytes allocated before the
/// render's memory check. Shared by reference (a `Cell`) through the loader's contexts.
#[derive(Debug)]
pub struct LoadBudget {
    limit: u64,
    held: std::cell::Cell<u64>,
    peak: std::cell::Cell<u64>,
}

impl LoadBudget {
    /// A budget of `limit` bytes (the render's `--max-memory`, or the default budget).
    pub fn new(limit: u64) -> LoadBudget {
        LoadBudget {
            limit,
            held: std::cell::Cell::new(0),
            peak: std::cell::Cell::new(0),
        }
    }

    /// Bytes reserved now.
    pub fn held(&self) -> u64 {
        self.held.get()
    }

    /// The most bytes reserved at once (a decode's transient peak included).
    pub fn peak(&self) -> u64 {
        self.peak.get()
    }

    /// Reserves `bytes` for `what` ("decoding it", "its 20000 copies"), or says why not.
    pub fn reserve(&self, bytes: u64, what: &str) -> Result<(), String> {
        let held = self.held.get();
        if held.saturating_add(bytes) > self.limit {
            return Err(format!(
                "{what} needs {}, and with the {} loaded before that is more than the memory \
                 budget of {} (--max-memory)",
                human(bytes),
                human(held),
                human(self.limit)
            ));
        }
        self.held.set(held + bytes);
        self.peak.set(self.peak.get().max(held + bytes));
        Ok(())
    }

    /// Gives back `bytes` of an earlier reservation (a decode's transient peak).
    pub fn release(&self, bytes: u64) {
        self.held.set(self.held.get().saturating_sub(bytes));
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sizes_parse() {
        assert_eq!(parse_size("512"), Ok(512));
        assert_eq!(parse_size("4k"), Ok(4096));
        assert_eq!(parse_size("1.5G"), Ok(3 << 29));
        assert_eq!(parse_size("2GiB"), Ok(2 << 30));
        assert_eq!(parse_size("8gb"), Ok(8 << 30));
        assert!(parse_size("-1G").is_err());
        assert!(parse_size("NaN").is_err());
        assert!(parse_size("1e400").is_err());
        assert!(parse_size("3 parsecs").is_err());
        assert!(parse_size("99999999T").is_err());
    }

    #[test]
    fn human_sizes() {
        assert_eq!(human(512), "512 B");
        assert_eq!(human(3_200_000), "3.2 MB");
        assert_eq!(human(110_000_000_000), "110 GB");
    }

    #[test]
    fn ranges() {
        assert_eq!(check_range(5u32, 1, 10), Ok(5));
        assert_eq!(
            check_range(0u32, 1, 10),
            Err("must be in 1..=10, got 0".into())
        );
        assert!(check_float(f32::NAN, 0.0, 1.0, true).is_err());
        assert!(check_float(0.0, 0.0, 1.0, true).is_err());
        assert!(check_float(0.0, 0.0, 1.0, false).is_ok());
        assert!(check_float(-0.5, 0.0, 1.0, false).is_err());
        assert!(check_float(f32::INFINITY, 0.0, f32::MAX, true).is_err());
    }

    #[test]
    fn proc_fields() {
        let text = "MemTotal:       24576000 kB\nMemFree: 1 kB\n";
        assert_eq!(proc_kb(text, "MemTotal:"), Some(24576000 * 1024));
        assert_eq!(proc_kb(text, "Nope:"), None);
    }
}
