//! How `photon render` shows [`crate::progress`]: a bar per stage on a terminal, or a plain
//! line on standard error every few seconds otherwise (a farm's log is never silent for
//! long), nothing with `--quiet`. Lines start with `progress: `, so that a log reader (and the
//! tests) tell them from the one line of an error, which starts with `photon: `.
//!
//! ```text
//! progress: global photons 1.20M/2.00M (60%), 812.0k/s, eta 1s
//! progress: image tiles 96/320 (30%), 24/s, eta 9s
//! ```
use crate::progress::{self, Snapshot};
use indicatif::{ProgressBar, ProgressStyle};
use std::io::IsTerminal;
use std::sync::atomic::{AtomicBool, Ordering::Relaxed};
use std::sync::Arc;
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

/// How progress is shown.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Mode {
    /// Nothing (`--quiet`).
    Off,
    /// A bar per stage on standard error (a terminal).
    Bar,
    /// A line on standard error every so many seconds (no terminal, or `--verbose`).
    Lines(f64),
}

impl Mode {
    /// The mode for `quiet` and `verbose` (`-v`: lines every second, even on a terminal):
    /// a bar on a terminal, else a line every [`LOG_EVERY`] seconds.
    pub fn pick(quiet: bool, verbose: bool) -> Mode {
        match (quiet, verbose) {
            (true, _) => Mode::Off,
            (false, true) => Mode::Lines(1.0),
            (false, false) if std::io::stderr().is_terminal() => Mode::Bar,
            _ => Mode::Lines(LOG_EVERY),
        }
    }
}

/// Seconds between progress lines without a terminal.
pub const LOG_EVERY: f64 = 5.0;

/// Shows progress until dropped (a thread polling [`progress::snapshot`]).
pub struct Reporter {
    stop: Arc<AtomicBool>,
    thread: Option<JoinHandle<()>>,
}

impl Reporter {
    /// Starts showing progress in `mode` (nothing for [`Mode::Off`]).
    pub fn start(mode: Mode) -> Reporter {
        let stop = Arc::new(AtomicBool::new(false));
        let thread = (mode != Mode::Off).then(|| {
            let stop = stop.clone();
            std::thread::spawn(move || show(mode, &stop))
        });
        Reporter { stop, thread }
    }
}

impl Drop for Reporter {
    fn drop(&mut self) {
        self.stop.store(true, Relaxed);
        if let Some(t) = self.thread.take() {
            let _ = t.join();
        }
        progress::end();
    }
}

/// The reporter's loop: polls every 100 ms until `stop`.
fn show(mode: Mode, stop: &AtomicBool) {
    let mut bar: Option<(u64, ProgressBar)> = None;
    let mut last_line = Instant::now();
    while !stop.load(Relaxed) {
        std::thread::sleep(Duration::from_millis(100));
        let Some(s) = progress::snapshot() else {
            continue;
        };
        match mode {
            Mode::Bar => draw(&mut bar, &s),
            Mode::Lines(every) if last_line.elapsed().as_secs_f64() >= every => {
                say_err!("progress: {}", s.line());
                last_line = Instant::now();
            }
            _ => {}
        }
    }
    if let Some((_, b)) = bar {
        b.finish_and_clear();
    }
}

/// Updates the bar of stage `s` (a new bar when a new stage began).
fn draw(bar: &mut Option<(u64, ProgressBar)>, s: &Snapshot) {
    if bar.as_ref().is_none_or(|(g, _)| *g != s.generation) {
        if let Some((_, old)) = bar.take() {
            old.finish_and_clear();
        }
        let b = ProgressBar::new(s.total.max(1));
        b.set_style(
            ProgressStyle::with_template(
                "{msg:>16} {elapsed_precise} [{bar:40}] {human_pos}/{human_len} {per_sec} eta {eta}",
            )
            .unwrap_or_else(|_| ProgressStyle::default_bar()),
        );
        b.set_message(s.name);
        *bar = Some((s.generation, b));
    }
    if let Some((_, b)) = bar {
        b.set_length(s.total.max(1));
        b.set_position(s.done.min(s.total));
    }
}
