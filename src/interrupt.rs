//! SIGINT / SIGTERM as a flag the render loop polls, instead of the default "die at once".
//!
//! [`install`] registers handlers (through `signal-hook`, which only stores the signal number in
//! an atomic: nothing else runs inside the handler). Long loops call [`requested`] between units
//! of work (tiles, passes) and, when it returns a signal, stop, clean up (remove temporary files,
//! write a checkpoint) and exit with [`Signal::exit_code`] (130 for SIGINT, 143 for SIGTERM, as a
//! shell reports a process killed by them).
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::{Arc, Once};

/// The signal that asked the process to stop.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Signal {
    Interrupt,
    Terminate,
}

impl Signal {
    /// The conventional exit status: 128 + signal number.
    pub fn exit_code(self) -> u8 {
        match self {
            Signal::Interrupt => 130,
            Signal::Terminate => 143,
        }
    }

    pub fn name(self) -> &'static str {
        match self {
            Signal::Interrupt => "SIGINT",
            Signal::Terminate => "SIGTERM",
        }
    }
}

static INSTALL: Once = Once::new();
static RAISED: std::sync::OnceLock<Arc<AtomicUsize>> = std::sync::OnceLock::new();

fn flag() -> &'static Arc<AtomicUsize> {
    RAISED.get_or_init(|| Arc::new(AtomicUsize::new(0)))
}

/// Registers the SIGINT and SIGTERM handlers (once per process; later calls do nothing). A
/// registration failure leaves the default behaviour (the process dies) and is not an error.
pub fn install() {
    INSTALL.call_once(|| {
        use signal_hook::consts::{SIGINT, SIGTERM};
        for sig in [SIGINT, SIGTERM] {
            let _ = signal_hook::flag::register_usize(sig, Arc::clone(flag()), sig as usize);
        }
    });
}

/// The signal received since [`install`], if any.
pub fn requested() -> Option<Signal> {
    match flag().load(Ordering::Relaxed) {
        0 => None,
        s if s == signal_hook::consts::SIGTERM as usize => Some(Signal::Terminate),
        _ => Some(Signal::Interrupt),
    }
}

/// The signal received since [`install`], clearing the flag: for a caller that saves its work
/// after a signal and must still notice a second one (it [`raise`]s the first again after).
pub fn take() -> Option<Signal> {
    let s = requested();
    flag().store(0, Ordering::Relaxed);
    s
}

/// Sets the flag as a signal would (for tests and for code that wants a clean stop).
pub fn raise(sig: Signal) {
    let n = match sig {
        Signal::Interrupt => signal_hook::consts::SIGINT,
        Signal::Terminate => signal_hook::consts::SIGTERM,
    };
    flag().store(n as usize, Ordering::Relaxed);
}
