//! Build script of the root `photon` crate: raw bindings to OpenEXR's C API (OpenEXRCore).
//!
//! Why here and not in a `-sys` crate: the root package is the only user of OpenEXRCore (through
//! the safe layer in `src/imageio/exr.rs`), so a separate crate would only add a manifest. Embree's
//! bindings live in `sys/` because several modules and benches use them.
//!
//! Steps: find `openexr.h` (include paths from `pkg-config --cflags OpenEXR`, else
//! `/usr/include/OpenEXR`, or `OPENEXR_INCLUDE_DIR`), run bindgen over it into
//! `$OUT_DIR/openexr.rs` (only `exr_*` / `EXR_*` items), and link `libOpenEXRCore` alone.
//! `pkg-config --libs OpenEXR` is deliberately not used: it lists the whole C++ stack
//! (OpenEXR, Iex, IlmThread, Imath), none of which the C API needs.
//!
//! With `--features denoise`, the `oidn` crate links `libOpenImageDenoise` (found through
//! `OIDN_DIR` or pkg-config, as `.ci/install` sets it up from PyPI's `pyoidn` wheel); this
//! script adds that library's folder as the binaries' and tests' rpath, so they run without
//! `LD_LIBRARY_PATH` (OIDN loads its CPU device module from the same folder at run time).
use std::path::{Path, PathBuf};
use std::process::Command;

/// The header the bindings are generated from, relative to an include directory.
const HEADER: &str = "openexr.h";

fn main() {
    // Tight rerun rules: without any `rerun-if-changed`, Cargo would rerun this script (and
    // bindgen) whenever any file of the root package changes.
    println!("cargo:rerun-if-changed=build.rs");
    println!("cargo:rerun-if-env-changed=OPENEXR_INCLUDE_DIR");
    println!("cargo:rerun-if-env-changed=PKG_CONFIG_PATH");
    println!("cargo:rerun-if-env-changed=OIDN_DIR");
    if std::env::var_os("CARGO_FEATURE_DENOISE").is_some() {
        oidn_rpath();
    }

    let include_dirs = include_dirs();
    let Some(header_dir) = include_dirs.iter().find(|d| d.join(HEADER).is_file()) else {
        panic!(
            "OpenEXR C API header `OpenEXR/{HEADER}` not found in {include_dirs:?}: install \
             Debian's `libopenexr-dev` (apt-get install libopenexr-dev) or set \
             OPENEXR_INCLUDE_DIR to the directory holding openexr.h"
        );
    };
    watch_headers(header_dir);

    println!("cargo:rustc-link-lib=OpenEXRCore");

    let mut builder = bindgen::Builder::default()
        .header(header_dir.join(HEADER).to_string_lossy())
        .allowlist_function("exr_.*")
        .allowlist_type("exr_.*")
        .allowlist_var("EXR_.*")
        .prepend_enum_name(false)
        .derive_default(true)
        .derive_debug(true)
        .layout_tests(false);
    for dir in &include_dirs {
        builder = builder.clang_arg(format!("-I{}", dir.display()));
    }
    let bindings = builder
        .generate()
        .expect("bindgen failed on OpenEXR/openexr.h (is libclang-dev installed?)");
    let out = PathBuf::from(std::env::var("OUT_DIR").expect("OUT_DIR not set by cargo"));
    bindings
        .write_to_file(out.join("openexr.rs"))
        .expect("cannot write OpenEXR bindings into OUT_DIR");
}

/// Include directories to search: `OPENEXR_INCLUDE_DIR` if set, else the `-I` paths of
/// `pkg-config --cflags OpenEXR`, always followed by Debian's `/usr/include/OpenEXR`.
fn include_dirs() -> Vec<PathBuf> {
    if let Some(dir) = std::env::var_os("OPENEXR_INCLUDE_DIR") {
        return vec![PathBuf::from(dir)];
    }
    let mut dirs: Vec<PathBuf> = Command::new("pkg-config")
        .args(["--cflags", "OpenEXR"])
        .output()
        .ok()
        .filter(|o| o.status.success())
        .map(|o| {
            String::from_utf8_lossy(&o.stdout)
                .split_whitespace()
                .filter_map(|flag| flag.strip_prefix("-I"))
                .map(PathBuf::from)
                .collect()
        })
        .unwrap_or_default();
    let fallback = PathBuf::from("/usr/include/OpenEXR");
    if !dirs.contains(&fallback) {
        dirs.push(fallback);
    }
    dirs
}

/// Asks Cargo to rerun the script only when one of the C API headers changes.
fn watch_headers(dir: &Path) {
    let Ok(entries) = std::fs::read_dir(dir) else {
        return;
    };
    for entry in entries.flatten() {
        let name = entry.file_name();
        let name = name.to_string_lossy();
        if name.starts_with("openexr") && name.ends_with(".h") {
            println!("cargo:rerun-if-changed={}", entry.path().display());
        }
    }
}

/// `--features denoise`: the folder of `libOpenImageDenoise` (`$OIDN_DIR/lib`, else
/// `pkg-config --variable=libdir OpenImageDenoise`) as rpath of every linked target.
fn oidn_rpath() {
    let dir = match std::env::var_os("OIDN_DIR").filter(|d| !d.is_empty()) {
        Some(d) => Some(PathBuf::from(d).join("lib")),
        None => Command::new("pkg-config")
            .args(["--variable=libdir", "OpenImageDenoise"])
            .output()
            .ok()
            .filter(|o| o.status.success())
            .map(|o| PathBuf::from(String::from_utf8_lossy(&o.stdout).trim())),
    };
    match dir.filter(|d| d.join("libOpenImageDenoise.so").exists()) {
        Some(dir) => println!("cargo:rustc-link-arg=-Wl,-rpath,{}", dir.display()),
        None => panic!(
            "feature `denoise`: libOpenImageDenoise.so not found through OIDN_DIR or \
             pkg-config (OpenImageDenoise.pc): run `bash .ci/install` (it installs Open Image \
             Denoise 2.5.1 from PyPI's pyoidn wheel), or build without --features denoise"
        ),
    }
}
