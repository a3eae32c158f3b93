//! Denoising through Intel Open Image Denoise 2 (feature `denoise`; the `oidn` crate's raw C
//! API, `oidn::sys`): the "RT" filter in HDR mode on a linear RGB image, guided by the albedo
//! and the shading normal of the first non-specular hit when the render has them (Cycles' and
//! pbrt-v4's convention, what the filter was trained on).
//!
//! The guides are *prefiltered* the way OIDN 2 recommends: the albedo and the normal are each
//! denoised alone first (an RT filter with only that image as input, into itself), then the
//! beauty is filtered with them and `cleanAux` set, which keeps the guides' own noise (a
//! glossy or depth-of-field guide averages several samples) out of the result.
//!
//! Without the feature [`denoise`] and [`available`] return [`NOT_BUILT`], one line that says
//! how to get it. The library is linked (the `oidn` crate's build finds it through pkg-config
//! or `OIDN_DIR`; build.rs puts its folder in the rpath); its CPU device is a module OIDN
//! loads at run time from the same folder, and a missing module is a one-line error here.
//!
//! The `oidn` crate's safe `RayTracing` wrapper is not used: it cannot run a guide alone
//! (it always sets `color`) and names the clean-guides flag `clean_aux`, which OIDN 2 ignores
//! (the parameter is `cleanAux`). The few C calls needed live in the private `ffi` module.

/// The one-line error of a photon built without the `denoise` feature.
pub const NOT_BUILT: &str = "this photon was built without the \"denoise\" feature \
     (bash .ci/install, then cargo build --release --features denoise)";

/// Which guides [`denoise`] uses: the albedo if given, the normal only with an albedo (OIDN
/// takes a normal only beside an albedo). For messages.
pub fn guides_used(albedo: bool, normal: bool) -> &'static str {
    match (albedo, normal) {
        (true, true) => "albedo and normal guides (prefiltered)",
        (true, false) => "albedo guide (prefiltered)",
        (false, true) => "no guides (a normal guide needs an albedo guide beside it)",
        (false, false) => "no guides",
    }
}

/// Denoises the linear RGB image `beauty` (`width * height` pixels, RGB interleaved, row-major)
/// with OIDN's RT filter in HDR mode, guided by `albedo` (in [0, 1]) and `normal` (any
/// length, world or camera space) when given: both prefiltered (see the module doc). A normal
/// without an albedo is ignored. Non-finite samples are read as 0, albedos are clamped to
/// [0, 1] and normals to [-1, 1]. Errors: wrong buffer sizes, the library's own errors, and
/// [`NOT_BUILT`] without the feature.
pub fn denoise(
    beauty: &[f32],
    albedo: Option<&[f32]>,
    normal: Option<&[f32]>,
    width: usize,
    height: usize,
) -> Result<Vec<f32>, String> {
    let n = width
        .checked_mul(height)
        .and_then(|p| p.checked_mul(3))
        .filter(|&n| n > 0)
        .ok_or_else(|| format!("cannot denoise a {width}x{height} image"))?;
    for (what, len) in [
        ("beauty", Some(beauty.len())),
        ("albedo", albedo.map(<[f32]>::len)),
    ]
    .into_iter()
    .chain([("normal", normal.map(<[f32]>::len))])
    {
        if let Some(len) = len.filter(|&l| l != n) {
            return Err(format!(
                "the {what} holds {len} samples, a {width}x{height} RGB image has {n}"
            ));
        }
    }
    let color = cleaned(beauty, 0.0, f32::INFINITY);
    let albedo = albedo.map(|a| cleaned(a, 0.0, 1.0));
    let normal = normal
        .filter(|_| albedo.is_some())
        .map(|v| cleaned(v, -1.0, 1.0));
    run(color, albedo, normal, width, height)
}

/// Succeeds when the denoiser can run here: built with the feature, and OIDN creates its CPU
/// device (the library found its device module). Lets a render fail before it starts.
pub fn available() -> Result<(), String> {
    #[cfg(feature = "denoise")]
    {
        ffi::Device::cpu().map(drop)
    }
    #[cfg(not(feature = "denoise"))]
    {
        Err(NOT_BUILT.to_string())
    }
}

/// A copy of `v` with non-finite samples set to 0 and the others clamped to `[lo, hi]`.
fn cleaned(v: &[f32], lo: f32, hi: f32) -> Vec<f32> {
    v.iter()
        .map(|&x| if x.is_finite() { x.clamp(lo, hi) } else { 0.0 })
        .collect()
}

/// Prefilters the guides, then filters the beauty with them (feature `denoise`).
#[cfg(feature = "denoise")]
fn run(
    mut color: Vec<f32>,
    mut albedo: Option<Vec<f32>>,
    mut normal: Option<Vec<f32>>,
    width: usize,
    height: usize,
) -> Result<Vec<f32>, String> {
    let device = ffi::Device::cpu()?;
    let size = (width, height);
    for (name, guide) in [("albedo", albedo.as_mut()), ("normal", normal.as_mut())] {
        if let Some(g) = guide {
            let filter = device.rt_filter()?;
            filter.in_place(name, g, size);
            filter.execute(&device)?;
        }
    }
    let mut out = vec![0.0f32; color.len()];
    let clean_guides = albedo.is_some();
    let filter = device.rt_filter()?;
    filter.image("color", &mut color, size);
    if let Some(a) = albedo.as_mut() {
        filter.image("albedo", a, size);
    }
    if let Some(n) = normal.as_mut() {
        filter.image("normal", n, size);
    }
    filter.image("output", &mut out, size);
    filter.flag("hdr", true);
    filter.flag("cleanAux", clean_guides);
    filter.execute(&device)?;
    drop(filter);
    Ok(out)
}

/// Without the feature: [`NOT_BUILT`].
#[cfg(not(feature = "denoise"))]
fn run(
    _: Vec<f32>,
    _: Option<Vec<f32>>,
    _: Option<Vec<f32>>,
    _: usize,
    _: usize,
) -> Result<Vec<f32>, String> {
    Err(NOT_BUILT.to_string())
}

/// The few OIDN C calls [`run`] needs, behind owning handles (the only `unsafe` of the
/// denoiser). Images are shared with the filter (host memory, which the CPU device reads and
/// writes in place): each [`Filter`] borrows its images until it is dropped.
#[cfg(feature = "denoise")]
mod ffi {
    use oidn::sys;
    use std::ffi::{c_char, CStr, CString};
    use std::marker::PhantomData;

    /// An OIDN CPU device, released on drop.
    pub struct Device(sys::OIDNDevice);

    /// An RT filter on a device, released on drop; `'a` is the life of the images it shares.
    pub struct Filter<'a>(sys::OIDNFilter, PhantomData<&'a mut [f32]>);

    impl Device {
        /// Creates and commits a CPU device.
        pub fn cpu() -> Result<Device, String> {
            // SAFETY: plain constructor; a null handle is checked below.
            let raw = unsafe { sys::oidnNewDevice(sys::OIDNDeviceType_OIDN_DEVICE_TYPE_CPU) };
            if raw.is_null() {
                return Err(format!(
                    "Open Image Denoise has no CPU device ({}): its module \
                     libOpenImageDenoise_device_cpu.so must sit beside libOpenImageDenoise.so \
                     (bash .ci/install installs both from PyPI's pyoidn 2.5.1)",
                    last_error(std::ptr::null_mut()).unwrap_or_else(|| "no message".into())
                ));
            }
            let device = Device(raw);
            // SAFETY: live device handle.
            unsafe { sys::oidnCommitDevice(device.0) };
            device.check("creating the CPU device")?;
            Ok(device)
        }

        /// A new "RT" filter on this device.
        pub fn rt_filter<'a>(&self) -> Result<Filter<'a>, String> {
            // SAFETY: live device; the type name is a NUL-terminated literal.
            let raw = unsafe { sys::oidnNewFilter(self.0, c"RT".as_ptr()) };
            self.check("creating the RT filter")?;
            match raw.is_null() {
                true => Err("Open Image Denoise: no RT filter".to_string()),
                false => Ok(Filter(raw, PhantomData)),
            }
        }

        /// The device's pending error as a one-line message about `what`.
        fn check(&self, what: &str) -> Result<(), String> {
            match last_error(self.0) {
                None => Ok(()),
                Some(m) => Err(format!("Open Image Denoise failed {what}: {m}")),
            }
        }
    }

    impl Drop for Device {
        fn drop(&mut self) {
            // SAFETY: live handle, not used after this.
            unsafe { sys::oidnReleaseDevice(self.0) };
        }
    }

    impl<'a> Filter<'a> {
        /// Shares the float RGB image `pixels` (`size.0 * size.1` pixels) as image `name`
        /// (an input, or `output`).
        pub fn image(&self, name: &str, pixels: &'a mut [f32], size: (usize, usize)) {
            self.share(name, pixels, size);
        }

        /// Shares `pixels` as input `name` and as the output: the filter works in place.
        pub fn in_place(&self, name: &str, pixels: &'a mut [f32], size: (usize, usize)) {
            self.share(name, pixels, size);
            self.share("output", pixels, size);
        }

        /// Points image `name` at `pixels`; the public callers hold them for 'a.
        fn share(&self, name: &str, pixels: &mut [f32], size: (usize, usize)) {
            assert_eq!(pixels.len(), 3 * size.0 * size.1, "image size");
            let name = CString::new(name).unwrap_or_default();
            // SAFETY: live filter; `pixels` holds width * height packed float3 pixels and is
            // borrowed by the caller for the filter's life ('a); OIDN copies the name.
            unsafe {
                sys::oidnSetSharedFilterImage(
                    self.0,
                    name.as_ptr(),
                    pixels.as_mut_ptr().cast(),
                    sys::OIDNFormat_OIDN_FORMAT_FLOAT3,
                    size.0,
                    size.1,
                    0,
                    0,
                    0,
                )
            };
        }

        /// Sets the boolean parameter `name` (`hdr`, `cleanAux`).
        pub fn flag(&self, name: &str, value: bool) {
            let name = CString::new(name).unwrap_or_default();
            // SAFETY: live filter; OIDN copies the name.
            unsafe { sys::oidnSetFilterBool(self.0, name.as_ptr(), value) };
        }

        /// Commits the parameters and runs the filter to completion.
        pub fn execute(&self, device: &Device) -> Result<(), String> {
            // SAFETY: live filter whose images are alive ('a).
            unsafe { sys::oidnCommitFilter(self.0) };
            device.check("setting up the RT filter")?;
            // SAFETY: as above; the call is synchronous.
            unsafe { sys::oidnExecuteFilter(self.0) };
            device.check("filtering")
        }
    }

    impl Drop for Filter<'_> {
        fn drop(&mut self) {
            // SAFETY: live handle, not used after this.
            unsafe { sys::oidnReleaseFilter(self.0) };
        }
    }

    /// The pending error of `device` (null: the thread's last device creation), if any.
    fn last_error(device: sys::OIDNDevice) -> Option<String> {
        let mut msg: *const c_char = std::ptr::null();
        // SAFETY: a live device or null, and a valid out-pointer.
        let code = unsafe { sys::oidnGetDeviceError(device, &mut msg) };
        if code == sys::OIDNError_OIDN_ERROR_NONE {
            return None;
        }
        // SAFETY: a non-null message is a NUL-terminated string OIDN keeps until its next call.
        let text = (!msg.is_null()).then(|| unsafe { CStr::from_ptr(msg) }.to_string_lossy());
        Some(match text {
            Some(t) if !t.is_empty() => format!("{t} (error {code})"),
            _ => format!("error {code}"),
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sizes_are_checked_before_anything_runs() {
        let e = denoise(&[0.0; 6], None, None, 2, 2).unwrap_err();
        assert!(e.contains("beauty holds 6 samples"), "{e}");
        let e = denoise(&[0.0; 12], Some(&[0.0; 3]), None, 2, 2).unwrap_err();
        assert!(e.contains("albedo holds 3"), "{e}");
        assert!(denoise(&[], None, None, 0, 4).is_err());
    }

    #[test]
    fn guides_are_cleaned() {
        assert_eq!(
            cleaned(&[f32::NAN, -1.0, 2.0, 0.5], 0.0, 1.0),
            vec![0.0, 0.0, 1.0, 0.5]
        );
        assert_eq!(
            guides_used(false, true),
            "no guides (a normal guide needs an albedo guide beside it)"
        );
    }

    #[cfg(feature = "denoise")]
    #[test]
    fn a_flat_noisy_image_comes_out_flat() {
        // Grey 0.5 with +-50% white noise: the filter must land near 0.5 everywhere.
        let (w, h) = (64, 64);
        let mut state = 1u32;
        let beauty: Vec<f32> = (0..w * h * 3)
            .map(|_| {
                state = state.wrapping_mul(1_664_525).wrapping_add(1_013_904_223);
                0.5 * (0.5 + (state >> 8) as f32 / (1u32 << 24) as f32)
            })
            .collect();
        let albedo = vec![0.8f32; w * h * 3];
        let normal: Vec<f32> = (0..w * h).flat_map(|_| [0.0, 0.0, 1.0]).collect();
        for (a, n) in [(None, None), (Some(&albedo[..]), Some(&normal[..]))] {
            let out = denoise(&beauty, a, n, w, h).unwrap();
            let mse = |img: &[f32]| img.iter().map(|v| (v - 0.5).powi(2)).sum::<f32>();
            let (after, before) = (mse(&out), mse(&beauty));
            assert!(
                after < before / 20.0,
                "squared error {after} (input {before})"
            );
        }
    }
}
