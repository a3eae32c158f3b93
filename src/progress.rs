//! Progress of the long stages of a render, for whoever shows it (`photon render`'s bar or
//! log lines, see `tools::progress`): photon tracing, the volume photons, the irradiance
//! cache, the image's tiles and the passes each report `done` of `total` units of one stage.
//!
//! The state is process-wide (one render per process shows progress; counters only, never
//! read by the rendering itself, so images do not depend on it). A stage begins with
//! [`begin`], advances with [`add`] from any thread, and [`snapshot`] reads it.
use std::sync::atomic::{AtomicU64, Ordering::Relaxed};
use std::sync::Mutex;
use std::time::Instant;

/// The stage in progress: its name, when it began, and its generation (bumped by [`begin`],
/// so a display notices a new stage even with the same name).
struct Current {
    name: &'static str,
    start: Instant,
    generation: u64,
}

static CURRENT: Mutex<Option<Current>> = Mutex::new(None);
static DONE: AtomicU64 = AtomicU64::new(0);
static TOTAL: AtomicU64 = AtomicU64::new(0);

/// What a display shows of the stage in progress.
#[derive(Clone, Debug, PartialEq)]
pub struct Snapshot {
    pub name: &'static str,
    pub done: u64,
    pub total: u64,
    /// Seconds since the stage began.
    pub elapsed: f64,
    pub generation: u64,
}

impl Snapshot {
    /// Units per second so far.
    pub fn rate(&self) -> f64 {
        self.done as f64 / self.elapsed.max(1e-9)
    }

    /// Seconds left at the rate so far (`None` before any unit is done).
    pub fn eta(&self) -> Option<f64> {
        (self.done > 0).then(|| self.total.saturating_sub(self.done) as f64 / self.rate())
    }

    /// One line: `photons 1.20M/2.00M (60%), 812k/s, eta 1s`.
    pub fn line(&self) -> String {
        let pct = 100.0 * self.done as f64 / self.total.max(1) as f64;
        let eta = self
            .eta()
            .map_or("eta ?".to_string(), |s| format!("eta {}", seconds(s)));
        format!(
            "{} {}/{} ({pct:.0}%), {}/s, {eta}",
            self.name,
            count(self.done as f64),
            count(self.total as f64),
            count(self.rate())
        )
    }
}

/// A count as `812`, `81.2k`, `1.20M`, `3.40G`.
pub fn count(v: f64) -> String {
    match v {
        v if v >= 1e9 => format!("{:.2}G", v / 1e9),
        v if v >= 1e6 => format!("{:.2}M", v / 1e6),
        v if v >= 1e4 => format!("{:.1}k", v / 1e3),
        v => format!("{v:.0}"),
    }
}

/// Seconds as `42s`, `3m05s`, `2h07m`.
pub fn seconds(s: f64) -> String {
    let s = s.max(0.0).round() as u64;
    match s {
        s if s >= 3600 => format!("{}h{:02}m", s / 3600, s / 60 % 60),
        s if s >= 60 => format!("{}m{:02}s", s / 60, s % 60),
        s => format!("{s}s"),
    }
}

fn current() -> std::sync::MutexGuard<'static, Option<Current>> {
    CURRENT.lock().unwrap_or_else(|e| e.into_inner())
}

/// Starts stage `name` of `total` units (0 done).
pub fn begin(name: &'static str, total: u64) {
    let mut c = current();
    let generation = c.as_ref().map_or(1, |c| c.generation + 1);
    DONE.store(0, Relaxed);
    TOTAL.store(total, Relaxed);
    *c = Some(Current {
        name,
        start: Instant::now(),
        generation,
    });
}

/// `n` more units of the stage in progress are done.
pub fn add(n: u64) {
    DONE.fetch_add(n, Relaxed);
}

/// `done` of `total` units of stage `name`: begins it if another stage is in progress
/// (finished tiles arrive in any order, so `done` only grows).
pub fn set(name: &'static str, done: u64, total: u64) {
    if current().as_ref().is_none_or(|c| c.name != name) {
        begin(name, total);
    }
    TOTAL.store(total, Relaxed);
    DONE.fetch_max(done, Relaxed);
}

/// Ends the stage in progress (a display shows nothing until the next one begins).
pub fn end() {
    *current() = None;
}

/// The stage in progress, if any.
pub fn snapshot() -> Option<Snapshot> {
    let c = current();
    c.as_ref().map(|c| Snapshot {
        name: c.name,
        done: DONE.load(Relaxed),
        total: TOTAL.load(Relaxed),
        elapsed: c.start.elapsed().as_secs_f64(),
        generation: c.generation,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lines_rates_and_etas() {
        let s = Snapshot {
            name: "photons",
            done: 1_200_000,
            total: 2_000_000,
            elapsed: 2.0,
            generation: 1,
        };
        assert_eq!(s.line(), "photons 1.20M/2.00M (60%), 600.0k/s, eta 1s");
        assert_eq!(seconds(185.0), "3m05s");
        assert_eq!(seconds(7620.0), "2h07m");
        let none = Snapshot { done: 0, ..s };
        assert_eq!(none.eta(), None);
        assert!(none.line().ends_with("eta ?"), "{}", none.line());
    }
}
