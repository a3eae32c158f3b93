//! Generates raw bindings for Embree 3's `rtcore.h` into `OUT_DIR` and links `libembree3`.
//!
//! Debian's `libembree-dev` ships no pkg-config file, so the header is looked up in the
//! standard include directories (or `EMBREE_INCLUDE_DIR`), and the library by name.
use std::path::PathBuf;

fn main() {
    println!("cargo:rerun-if-env-changed=EMBREE_INCLUDE_DIR");
    println!("cargo:rerun-if-changed=wrapper.h");
    let include_dirs: Vec<PathBuf> = match std::env::var_os("EMBREE_INCLUDE_DIR") {
        Some(dir) => vec![PathBuf::from(dir)],
        None => vec![
            PathBuf::from("/usr/include"),
            PathBuf::from("/usr/local/include"),
        ],
    };
    let Some(include) = include_dirs
        .iter()
        .find(|d| d.join("embree3/rtcore.h").exists())
    else {
        panic!(
            "embree3/rtcore.h not found in {include_dirs:?}: install Debian's `libembree-dev` \
             (apt-get install libembree-dev) or set EMBREE_INCLUDE_DIR"
        );
    };
    println!("cargo:rustc-link-lib=embree3");

    let bindings = bindgen::Builder::default()
        .header("wrapper.h")
        .clang_arg(format!("-I{}", include.display()))
        .allowlist_function("rtc.*")
        .allowlist_type("RTC.*")
        .allowlist_var("RTC_.*")
        .rustified_enum("RTCError")
        .prepend_enum_name(false)
        .derive_default(true)
        .derive_debug(true)
        .layout_tests(true)
        .generate()
        .expect("bindgen failed on embree3/rtcore.h");
    let out = PathBuf::from(std::env::var("OUT_DIR").unwrap()).join("embree3.rs");
    bindings
        .write_to_file(out)
        .expect("cannot write Embree bindings");
}
