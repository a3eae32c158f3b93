//! CPU floating-point state: flush-to-zero and denormals-are-zero for tracing threads. A
//! hardware interface layer like the FFI modules: its `unsafe` is two instructions (`stmxcsr`,
//! `ldmxcsr`) that Rust has no safe wrapper for.

/// Sets flush-to-zero and denormals-are-zero in MXCSR for the calling thread (Embree's advice
/// for tracing threads). A no-op on other architectures.
///
/// Call it once per thread that traces rays (for rayon: in a `start_handler`). Denormal inputs
/// and results become zero on this thread for all SSE arithmetic, Rust's included.
///
/// Caveat: Rust documents changing MXCSR as undefined behaviour, because LLVM assumes the
/// default floating-point environment (e.g. it may constant-fold an expression to a denormal
/// that the same expression computed at run time would flush). We accept that on purpose, as
/// every Embree application does; a renderer does not depend on denormals.
pub fn enable_flush_denormals() {
    #[cfg(target_arch = "x86_64")]
    {
        const FTZ: u32 = 1 << 15;
        const DAZ: u32 = 1 << 6;
        let mut csr: u32 = 0;
        // SAFETY: `stmxcsr`/`ldmxcsr` read and write the 4-byte `csr`, which is live and
        // aligned; SSE is part of the x86_64 baseline. Only the FTZ and DAZ bits change.
        unsafe {
            std::arch::asm!("stmxcsr [{}]", in(reg) &mut csr, options(nostack, preserves_flags));
            csr |= FTZ | DAZ;
            std::arch::asm!("ldmxcsr [{}]", in(reg) &csr, options(nostack, preserves_flags));
        }
    }
}
