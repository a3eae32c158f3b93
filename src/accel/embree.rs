//! The Embree 3 backend: a small safe, owning layer over `photon-embree-sys`, and
//! [`EmbreeAccel`], which answers [`RayQuery`] with it.
//!
//! One Rust type per Embree object, each releasing its handle on `Drop`:
//! - [`Device`]: `rtcNewDevice` plus an error callback that records Embree's errors into state
//!   the device owns, so that every fallible call below returns `Err` with Embree's code and
//!   message instead of carrying on with a broken object;
//! - [`Geometry`]: a committed triangle geometry (vertex buffer `FLOAT3`, padded so the last
//!   vertex can be read with a 16-byte load; index buffer `UINT3`);
//! - [`SceneBuilder`]: a scene being assembled; [`SceneBuilder::commit`] consumes it and returns
//!   a [`CommittedScene`], the only type that can be queried (the pattern of `embree-rs`).
//!
//! Geometry ids are mesh indices (`Scene::meshes`): meshes are attached with
//! `rtcAttachGeometryByID`, empty meshes are skipped.
//!
//! A mesh with alpha (see [`super`]) gets `alpha_filter` as its intersection and occlusion
//! filter callback, with its [`AlphaMask`] as the geometry's user data; other geometries have
//! no callback, so scenes without alpha pay nothing. The [`Geometry`] holds the mask until
//! [`SceneBuilder::attach`] hands it to the scene, and the [`CommittedScene`] keeps it as long
//! as Embree may call the callback with its address.
//!
//! This file and the EXR layer are the only `unsafe` code outside `sys/`. Every `unsafe`
//! block states what it relies on.
use super::{
    face_normals, query_interval, validate_meshes, AccelError, AccelOptions, AlphaMask, Hit,
    RayQuery,
};
use crate::math::{Ray, Vec3};
use crate::scene::Scene;
use photon_embree_sys as sys;
use std::ffi::{c_char, c_void, CStr, CString};
use std::pin::Pin;
use std::ptr::NonNull;
use std::sync::{Arc, Mutex};

/// Rays per Embree packet call.
const PACKET: usize = 8;

/// The first Embree error reported since the last check: code and message.
type Recorded = Option<(sys::RTCError, String)>;

/// Where the error callback writes. Boxed and pinned inside [`Device`] so its address, handed
/// to Embree as the callback's user pointer, stays valid for the device's whole life. The
/// callback may run on Embree's worker threads, hence the mutex.
struct ErrorSink {
    first: Mutex<Recorded>,
}

/// Embree's error callback: keeps the first error until [`Device::check`] takes it.
unsafe extern "C" fn record_error(user: *mut c_void, code: sys::RTCError, msg: *const c_char) {
    if user.is_null() {
        return;
    }
    // SAFETY: `user` is the address of the `ErrorSink` pinned in the `Device` that registered
    // this callback; the device outlives every call Embree makes on it.
    let sink = unsafe { &*(user as *const ErrorSink) };
    let text = if msg.is_null() {
        String::new()
    } else {
        // SAFETY: Embree passes a NUL-terminated string valid for the duration of the call.
        unsafe { CStr::from_ptr(msg) }
            .to_string_lossy()
            .into_owned()
    };
    if let Ok(mut first) = sink.first.lock() {
        first.get_or_insert((code, text));
    }
}

/// Formats an Embree error as an [`AccelError`]: `embree: <what>: <CODE>: <message>`.
fn embree_error(what: &str, code: sys::RTCError, msg: &str) -> AccelError {
    AccelError(format!("embree: {what}: {code:?}: {msg}"))
}

/// An Embree device (`RTCDevice`) with an error callback.
pub struct Device {
    raw: NonNull<sys::RTCDeviceTy>,
    errors: Pin<Box<ErrorSink>>,
}

// SAFETY: Embree's device API is thread-safe (Embree's documentation: all API calls on a device
// may be made from several threads, except concurrent modification of one object), and the
// error sink is behind a mutex.
unsafe impl Send for Device {}
// SAFETY: as for `Send`; shared references only read the handle or lock the sink.
unsafe impl Sync for Device {}

impl Device {
    /// Creates a device from an Embree configuration string (e.g. `""` or `"threads=2"`;
    /// see Embree's `rtcNewDevice`). An invalid string is an error.
    pub fn new(config: &str) -> Result<Arc<Device>, AccelError> {
        let c = CString::new(config)
            .map_err(|_| AccelError("embree: device config contains a NUL byte".into()))?;
        // SAFETY: `c` is a valid NUL-terminated string for the duration of the call.
        let raw = unsafe { sys::rtcNewDevice(c.as_ptr()) };
        let Some(raw) = NonNull::new(raw) else {
            // SAFETY: a null device asks for the calling thread's last error.
            let code = unsafe { sys::rtcGetDeviceError(std::ptr::null_mut()) };
            return Err(embree_error(
                &format!("rtcNewDevice({config:?})"),
                code,
                "device creation failed",
            ));
        };
        let device = Device {
            raw,
            errors: Box::pin(ErrorSink {
                first: Mutex::new(None),
            }),
        };
        let user = &*device.errors as *const ErrorSink as *mut c_void;
        // SAFETY: `raw` is a live device; `user` points to the pinned sink, which lives as long
        // as `device` (the callback is never called after `rtcReleaseDevice` in `Drop`).
        unsafe { sys::rtcSetDeviceErrorFunction(device.raw(), Some(record_error), user) };
        device.check("rtcSetDeviceErrorFunction")?;
        Ok(Arc::new(device))
    }

    fn raw(&self) -> sys::RTCDevice {
        self.raw.as_ptr()
    }

    /// Takes the first error Embree reported since the last check, as `Err` naming `what`.
    /// Also asks `rtcGetDeviceError`, which the callback would have seen too.
    fn check(&self, what: &str) -> Result<(), AccelError> {
        // SAFETY: `raw` is a live device. This clears Embree's own per-thread error code.
        let code = unsafe { sys::rtcGetDeviceError(self.raw()) };
        let recorded = match self.errors.first.lock() {
            Ok(mut first) => first.take(),
            Err(_) => Some((
                sys::RTCError::RTC_ERROR_UNKNOWN,
                "error sink poisoned".into(),
            )),
        };
        match (recorded, code) {
            (Some((c, msg)), _) => Err(embree_error(what, c, &msg)),
            (None, sys::RTCError::RTC_ERROR_NONE) => Ok(()),
            (None, c) => Err(embree_error(what, c, "(no message)")),
        }
    }
}

impl Drop for Device {
    fn drop(&mut self) {
        // SAFETY: we own one reference to the device; scenes and geometries hold an
        // `Arc<Device>`, so none of them outlives this call.
        unsafe { sys::rtcReleaseDevice(self.raw()) };
    }
}

/// A committed Embree triangle geometry, ready to attach to a scene.
pub struct Geometry {
    raw: NonNull<sys::RTCGeometryTy>,
    device: Arc<Device>,
    /// The alpha mask whose address the filter callbacks receive, if any.
    alpha: Option<Arc<AlphaMask>>,
}

/// Embree's intersection and occlusion filter for geometries with alpha: rejects (clears
/// `valid[i]`) each active lane whose candidate hit [`AlphaMask::keeps`] refuses, reading the
/// ray's origin and direction and the hit's barycentrics and triangle from Embree's
/// structure-of-arrays layout for `N` rays (`RTCRayN_*`/`RTCHitN_*` in `rtcore_ray.h`: field
/// `k` of lane `i` is 4-byte word `k * N + i`). Works for single rays (`N = 1`) and packets.
unsafe extern "C" fn alpha_filter(args: *const sys::RTCFilterFunctionNArguments) {
    // SAFETY: Embree passes valid arguments for the duration of the call.
    let Some(args) = (unsafe { args.as_ref() }) else {
        return;
    };
    let n = args.N as usize;
    if args.geometryUserPtr.is_null() || args.valid.is_null() || n == 0 {
        return;
    }
    // SAFETY: the user pointer is the `AlphaMask` set in `Geometry::triangles`, kept alive by
    // the `CommittedScene` being queried (see the module docs); it is only read.
    let mask = unsafe { &*(args.geometryUserPtr as *const AlphaMask) };
    // SAFETY: `valid` holds `N` ints; the ray holds 12 and the hit at least 7 arrays of `N`
    // 4-byte words (Embree's RTCRayN / RTCHitN layouts), all live during the call. The ray
    // and hit are only read; only `valid` is written.
    let (valid, ray, hit) = unsafe {
        (
            std::slice::from_raw_parts_mut(args.valid, n),
            std::slice::from_raw_parts(args.ray as *const f32, 12 * n),
            std::slice::from_raw_parts(args.hit as *const f32, 7 * n),
        )
    };
    for (i, lane) in valid.iter_mut().enumerate() {
        if *lane == 0 {
            continue;
        }
        let at = |src: &[f32], k: usize| src[k * n + i];
        let o = Vec3::new(at(ray, 0), at(ray, 1), at(ray, 2));
        let d = Vec3::new(at(ray, 4), at(ray, 5), at(ray, 6));
        let prim = at(hit, 5).to_bits();
        // A panic must not unwind into Embree: one that cannot happen reads as "keep".
        let keep = std::panic::catch_unwind(|| mask.keeps(prim, at(hit, 3), at(hit, 4), o, d));
        if !keep.unwrap_or(true) {
            *lane = 0;
        }
    }
}

impl Geometry {
    /// Creates a triangle geometry from `positions` and `indices` (copied into Embree-owned
    /// buffers) with build quality `quality` and, given `alpha`, the alpha filter callbacks
    /// (an error when this Embree was built without filter functions), and commits it.
    ///
    /// Every index must be `< positions.len()` (checked: Embree does not) and `indices` must
    /// not be empty.
    pub fn triangles(
        device: &Arc<Device>,
        positions: &[Vec3],
        indices: &[[u32; 3]],
        quality: sys::RTCBuildQuality,
        alpha: Option<Arc<AlphaMask>>,
    ) -> Result<Geometry, AccelError> {
        let n = positions.len();
        if indices.is_empty() || indices.iter().flatten().any(|&i| i as usize >= n) {
            return Err(AccelError(
                "embree: triangle geometry needs triangles whose indices name vertices".into(),
            ));
        }
        // SAFETY: the device is live; the type is a valid geometry type.
        let raw = unsafe { sys::rtcNewGeometry(device.raw(), sys::RTC_GEOMETRY_TYPE_TRIANGLE) };
        device.check("rtcNewGeometry")?;
        let raw = NonNull::new(raw)
            .ok_or_else(|| AccelError("embree: rtcNewGeometry returned null".into()))?;
        let geom = Geometry {
            raw,
            device: device.clone(),
            alpha,
        };
        geom.fill_vertices(positions)?;
        geom.fill_indices(indices)?;
        geom.set_alpha_filter()?;
        // SAFETY: live geometry; both buffers are set.
        unsafe {
            sys::rtcSetGeometryBuildQuality(geom.raw(), quality);
            sys::rtcCommitGeometry(geom.raw());
        }
        device.check("rtcCommitGeometry")?;
        Ok(geom)
    }

    fn raw(&self) -> sys::RTCGeometry {
        self.raw.as_ptr()
    }

    /// With an alpha mask: makes it the geometry's user data and sets [`alpha_filter`] for
    /// intersection and occlusion queries. Without one: nothing.
    fn set_alpha_filter(&self) -> Result<(), AccelError> {
        let Some(mask) = &self.alpha else {
            return Ok(());
        };
        let dev = &self.device;
        // SAFETY: live device; a property query.
        let supported = unsafe {
            sys::rtcGetDeviceProperty(
                dev.raw(),
                sys::RTC_DEVICE_PROPERTY_FILTER_FUNCTION_SUPPORTED,
            )
        };
        if supported == 0 {
            return Err(AccelError(
                "embree: this Embree has no filter functions, which shape alpha needs (use \
                 --backend obvhs)"
                    .into(),
            ));
        }
        let user = Arc::as_ptr(mask) as *mut c_void;
        // SAFETY: live geometry, not yet committed. `user` points to the mask this geometry
        // holds and hands on to the scene it is attached to, which keeps it while queries can
        // run; the callback only reads it.
        unsafe {
            sys::rtcSetGeometryUserData(self.raw(), user);
            sys::rtcSetGeometryIntersectFilterFunction(self.raw(), Some(alpha_filter));
            sys::rtcSetGeometryOccludedFilterFunction(self.raw(), Some(alpha_filter));
        }
        dev.check("rtcSetGeometryIntersectFilterFunction")
    }

    /// Copies `positions` into a new `FLOAT3` vertex buffer with 4 bytes of padding after the
    /// last vertex, so that Embree's 16-byte loads stay inside the allocation.
    fn fill_vertices(&self, positions: &[Vec3]) -> Result<(), AccelError> {
        let bytes = positions.len() * 12 + 4;
        let floats: Vec<f32> = positions.iter().flat_map(|p| p.to_array()).collect();
        // SAFETY: `floats` holds `positions.len() * 3` f32 (12 bytes per vertex) and the buffer
        // has `bytes` >= that many bytes.
        unsafe {
            self.fill_buffer(
                sys::RTC_BUFFER_TYPE_VERTEX,
                sys::RTC_FORMAT_FLOAT3,
                12,
                positions.len(),
                bytes,
                floats.as_ptr().cast(),
            )
        }
    }

    /// Copies `indices` into a new `UINT3` index buffer.
    fn fill_indices(&self, indices: &[[u32; 3]]) -> Result<(), AccelError> {
        let bytes = indices.len() * 12;
        // SAFETY: `[u32; 3]` is 12 bytes with no padding, so `indices` is `bytes` bytes.
        unsafe {
            self.fill_buffer(
                sys::RTC_BUFFER_TYPE_INDEX,
                sys::RTC_FORMAT_UINT3,
                12,
                indices.len(),
                bytes,
                indices.as_ptr().cast(),
            )
        }
    }

    /// Creates an Embree buffer of `bytes` bytes, copies `count * stride` bytes from `src` into
    /// it and binds it to slot 0 of `kind` with `format`.
    ///
    /// # Safety
    /// `src` must be valid for reads of `count * stride` bytes, and `count * stride <= bytes`.
    unsafe fn fill_buffer(
        &self,
        kind: sys::RTCBufferType,
        format: sys::RTCFormat,
        stride: usize,
        count: usize,
        bytes: usize,
        src: *const u8,
    ) -> Result<(), AccelError> {
        let dev = &self.device;
        // SAFETY: live device.
        let buf = unsafe { sys::rtcNewBuffer(dev.raw(), bytes) };
        dev.check("rtcNewBuffer")?;
        if buf.is_null() {
            return Err(AccelError("embree: rtcNewBuffer returned null".into()));
        }
        // SAFETY: `buf` is a live buffer of `bytes` bytes; the caller guarantees `src` has
        // `count * stride <= bytes` readable bytes; the regions do not overlap (fresh buffer).
        // The geometry retains the buffer, so releasing our reference afterwards is right.
        let ok = unsafe {
            let dst = sys::rtcGetBufferData(buf) as *mut u8;
            if !dst.is_null() {
                std::ptr::copy_nonoverlapping(src, dst, count * stride);
                std::ptr::write_bytes(dst.add(count * stride), 0, bytes - count * stride);
                sys::rtcSetGeometryBuffer(self.raw(), kind, 0, format, buf, 0, stride, count);
            }
            sys::rtcReleaseBuffer(buf);
            !dst.is_null()
        };
        dev.check("rtcSetGeometryBuffer")?;
        if ok {
            Ok(())
        } else {
            Err(AccelError("embree: rtcGetBufferData returned null".into()))
        }
    }
}

impl Drop for Geometry {
    fn drop(&mut self) {
        // SAFETY: we own one reference; a scene it was attached to holds its own.
        unsafe { sys::rtcReleaseGeometry(self.raw()) };
    }
}

/// Scene construction settings.
#[derive(Clone, Copy, Debug, Default)]
pub struct SceneConfig {
    /// `RTC_SCENE_FLAG_ROBUST` (Embree then builds at medium quality); otherwise
    /// `RTC_BUILD_QUALITY_HIGH`.
    pub robust: bool,
}

/// An Embree scene being assembled. Cannot be queried: [`SceneBuilder::commit`] it.
pub struct SceneBuilder {
    raw: NonNull<sys::RTCSceneTy>,
    device: Arc<Device>,
    /// The alpha masks of the attached geometries (their filters' user data).
    alpha: Vec<Arc<AlphaMask>>,
}

impl SceneBuilder {
    /// A new, empty scene on `device` with the flags and build quality of `config`.
    pub fn new(device: &Arc<Device>, config: SceneConfig) -> Result<SceneBuilder, AccelError> {
        // SAFETY: live device.
        let raw = unsafe { sys::rtcNewScene(device.raw()) };
        device.check("rtcNewScene")?;
        let raw = NonNull::new(raw)
            .ok_or_else(|| AccelError("embree: rtcNewScene returned null".into()))?;
        let builder = SceneBuilder {
            raw,
            device: device.clone(),
            alpha: Vec::new(),
        };
        let (flags, quality) = if config.robust {
            (sys::RTC_SCENE_FLAG_ROBUST, sys::RTC_BUILD_QUALITY_MEDIUM)
        } else {
            (sys::RTC_SCENE_FLAG_NONE, sys::RTC_BUILD_QUALITY_HIGH)
        };
        // SAFETY: live scene, valid flag and quality values.
        unsafe {
            sys::rtcSetSceneFlags(builder.raw.as_ptr(), flags);
            sys::rtcSetSceneBuildQuality(builder.raw.as_ptr(), quality);
        }
        device.check("rtcSetSceneFlags")?;
        Ok(builder)
    }

    /// Attaches `geometry` under id `id` (which must be unused) and releases it: the scene
    /// keeps its own reference, and the geometry's alpha mask.
    pub fn attach(&mut self, mut geometry: Geometry, id: u32) -> Result<(), AccelError> {
        if !Arc::ptr_eq(&geometry.device, &self.device) || id == sys::RTC_INVALID_GEOMETRY_ID {
            return Err(AccelError(
                "embree: geometry from another device or invalid id".into(),
            ));
        }
        // SAFETY: live scene and geometry of the same device; Embree reports a used id as an
        // error, which `check` returns.
        unsafe { sys::rtcAttachGeometryByID(self.raw.as_ptr(), geometry.raw(), id) };
        self.device.check("rtcAttachGeometryByID")?;
        self.alpha.extend(geometry.alpha.take());
        Ok(())
    }

    /// Builds the acceleration structure. Consumes the builder: only the committed scene can
    /// be queried.
    pub fn commit(mut self) -> Result<CommittedScene, AccelError> {
        // SAFETY: live scene; no other thread can touch it (we own the builder).
        unsafe { sys::rtcCommitScene(self.raw.as_ptr()) };
        self.device.check("rtcCommitScene")?;
        // The committed scene takes its own reference; the builder's is released when `self`
        // drops at the end of this function.
        // SAFETY: live scene.
        unsafe { sys::rtcRetainScene(self.raw.as_ptr()) };
        Ok(CommittedScene {
            raw: self.raw,
            _device: self.device.clone(),
            _alpha: std::mem::take(&mut self.alpha),
        })
    }
}

impl Drop for SceneBuilder {
    fn drop(&mut self) {
        // SAFETY: we own one reference to the scene.
        unsafe { sys::rtcReleaseScene(self.raw.as_ptr()) };
    }
}

/// What Embree says about a hit, before it is turned into a [`Hit`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RawHit {
    pub t: f32,
    pub geom: u32,
    pub prim: u32,
    pub u: f32,
    pub v: f32,
}

/// A committed Embree scene: the only queryable type.
///
/// `Send + Sync`: after `rtcCommitScene` returns, Embree's scene is immutable here (we never
/// expose a way to modify or recommit it) and Embree documents ray queries on a committed
/// scene as thread-safe: each query only reads the scene and writes the caller's own ray
/// structures. The handle is released exactly once, in `Drop`, which needs `&mut self`, so no
/// query can run concurrently with it.
pub struct CommittedScene {
    raw: NonNull<sys::RTCSceneTy>,
    /// Keeps the device alive at least as long as the scene.
    _device: Arc<Device>,
    /// The alpha masks the filter callbacks read; dropped after the scene is released.
    _alpha: Vec<Arc<AlphaMask>>,
}

// SAFETY: see the type's documentation.
unsafe impl Send for CommittedScene {}
// SAFETY: see the type's documentation.
unsafe impl Sync for CommittedScene {}

impl Drop for CommittedScene {
    fn drop(&mut self) {
        // SAFETY: we own one reference to the scene; the device (an Arc field) is released
        // after this body runs.
        unsafe { sys::rtcReleaseScene(self.raw.as_ptr()) };
    }
}

/// An `RTCRayHit` for `rtcIntersect1`: mask all ones, ids invalid (ffi-facts: a zeroed
/// structure has mask 0, which never hits, and geomID 0, which looks like a hit).
fn ray_hit1(ray: &Ray, tmin: f32, tmax: f32) -> sys::RTCRayHit {
    sys::RTCRayHit {
        ray: sys::RTCRay {
            org_x: ray.o.x,
            org_y: ray.o.y,
            org_z: ray.o.z,
            tnear: tmin,
            dir_x: ray.d.x,
            dir_y: ray.d.y,
            dir_z: ray.d.z,
            time: 0.0,
            tfar: tmax,
            mask: u32::MAX,
            id: 0,
            flags: 0,
        },
        hit: sys::RTCHit {
            primID: sys::RTC_INVALID_GEOMETRY_ID,
            geomID: sys::RTC_INVALID_GEOMETRY_ID,
            instID: [sys::RTC_INVALID_GEOMETRY_ID],
            ..Default::default()
        },
    }
}

/// Writes `ray` into lane `i` of a packet ray.
fn set_lane(r: &mut sys::RTCRay8, i: usize, ray: &Ray, tmin: f32, tmax: f32) {
    (r.org_x[i], r.org_y[i], r.org_z[i]) = (ray.o.x, ray.o.y, ray.o.z);
    (r.dir_x[i], r.dir_y[i], r.dir_z[i]) = (ray.d.x, ray.d.y, ray.d.z);
    (r.tnear[i], r.tfar[i], r.time[i]) = (tmin, tmax, 0.0);
    (r.mask[i], r.id[i], r.flags[i]) = (u32::MAX, i as u32, 0);
}

/// Fills a packet from up to 8 rays; lanes without a queryable ray are switched off.
fn packet_rays(rays: &[Ray], r: &mut sys::RTCRay8) -> sys::Valid8 {
    let mut valid = sys::Valid8([0; PACKET]);
    for (i, ray) in rays.iter().enumerate().take(PACKET) {
        if let Some((tmin, tmax)) = query_interval(ray) {
            set_lane(r, i, ray, tmin, tmax);
            valid.0[i] = -1;
        }
    }
    valid
}

impl CommittedScene {
    /// Closest hit with `t` in `(tmin, tmax]` (Embree's convention), via `rtcIntersect1`.
    pub fn intersect1(&self, ray: &Ray) -> Option<RawHit> {
        let (tmin, tmax) = query_interval(ray)?;
        let mut rh = ray_hit1(ray, tmin, tmax);
        let mut ctx = sys::rtc_intersect_context();
        // SAFETY: committed scene; `ctx` and `rh` are valid, initialised and exclusively ours.
        unsafe { sys::rtcIntersect1(self.raw.as_ptr(), &mut ctx, &mut rh) };
        (rh.hit.geomID != sys::RTC_INVALID_GEOMETRY_ID).then_some(RawHit {
            t: rh.ray.tfar,
            geom: rh.hit.geomID,
            prim: rh.hit.primID,
            u: rh.hit.u,
            v: rh.hit.v,
        })
    }

    /// Whether anything is hit with `t` in `(tmin, tmax]`, via `rtcOccluded1`.
    pub fn occluded1(&self, ray: &Ray) -> bool {
        let Some((tmin, tmax)) = query_interval(ray) else {
            return false;
        };
        let mut r = ray_hit1(ray, tmin, tmax).ray;
        let mut ctx = sys::rtc_intersect_context();
        // SAFETY: as in `intersect1`.
        unsafe { sys::rtcOccluded1(self.raw.as_ptr(), &mut ctx, &mut r) };
        r.tfar == f32::NEG_INFINITY
    }

    /// Closest hits of up to 8 rays in one `rtcIntersect8` call (coherent context);
    /// `out[i]` answers `rays[i]`.
    pub fn intersect8(&self, rays: &[Ray], out: &mut [Option<RawHit>]) {
        let mut rh = sys::RTCRayHit8::default();
        let valid = packet_rays(rays, &mut rh.ray);
        rh.hit.geomID = [sys::RTC_INVALID_GEOMETRY_ID; PACKET];
        rh.hit.primID = [sys::RTC_INVALID_GEOMETRY_ID; PACKET];
        rh.hit.instID = [[sys::RTC_INVALID_GEOMETRY_ID; PACKET]];
        let mut ctx = sys::rtc_intersect_context();
        ctx.flags = sys::RTC_INTERSECT_CONTEXT_FLAG_COHERENT;
        if valid.0.iter().any(|&v| v != 0) {
            // SAFETY: `valid` is 32-byte aligned (`Valid8`), `rh` is a 32-byte aligned
            // `RTCRayHit8` (bindgen's `repr(align(32))`); inactive lanes are ignored by Embree.
            unsafe { sys::rtcIntersect8(valid.0.as_ptr(), self.raw.as_ptr(), &mut ctx, &mut rh) };
        }
        for (i, o) in out.iter_mut().enumerate().take(rays.len().min(PACKET)) {
            let hit = valid.0[i] != 0 && rh.hit.geomID[i] != sys::RTC_INVALID_GEOMETRY_ID;
            *o = hit.then_some(RawHit {
                t: rh.ray.tfar[i],
                geom: rh.hit.geomID[i],
                prim: rh.hit.primID[i],
                u: rh.hit.u[i],
                v: rh.hit.v[i],
            });
        }
    }

    /// Occlusion of up to 8 rays in one `rtcOccluded8` call (coherent context).
    pub fn occluded8(&self, rays: &[Ray], out: &mut [bool]) {
        let mut r = sys::RTCRay8::default();
        let valid = packet_rays(rays, &mut r);
        let mut ctx = sys::rtc_intersect_context();
        ctx.flags = sys::RTC_INTERSECT_CONTEXT_FLAG_COHERENT;
        if valid.0.iter().any(|&v| v != 0) {
            // SAFETY: as in `intersect8`.
            unsafe { sys::rtcOccluded8(valid.0.as_ptr(), self.raw.as_ptr(), &mut ctx, &mut r) };
        }
        for (i, o) in out.iter_mut().enumerate().take(rays.len().min(PACKET)) {
            *o = valid.0[i] != 0 && r.tfar[i] == f32::NEG_INFINITY;
        }
    }
}

/// The Embree backend: a committed scene over all meshes, plus each triangle's unit
/// geometric normal to fill [`Hit::ng`].
pub struct EmbreeAccel {
    scene: CommittedScene,
    /// `normals[mesh][prim]`, from [`super::face_normals`].
    normals: Vec<Vec<Vec3>>,
}

impl EmbreeAccel {
    /// Builds over every mesh of `scene` on a new default device. Geometry id = mesh index.
    pub fn build(scene: &Scene, opts: AccelOptions) -> Result<Self, AccelError> {
        Self::build_on(&Device::new("")?, scene, opts)
    }

    /// Builds over every mesh of `scene` on `device`.
    pub fn build_on(
        device: &Arc<Device>,
        scene: &Scene,
        opts: AccelOptions,
    ) -> Result<Self, AccelError> {
        validate_meshes(scene)?;
        let config = SceneConfig {
            robust: opts.robust,
        };
        let mut builder = SceneBuilder::new(device, config)?;
        let quality = if opts.robust {
            sys::RTC_BUILD_QUALITY_MEDIUM
        } else {
            sys::RTC_BUILD_QUALITY_HIGH
        };
        for (id, mesh) in scene.meshes.iter().enumerate() {
            if mesh.indices.is_empty() {
                continue;
            }
            let id = u32::try_from(id)
                .ok()
                .filter(|&id| id != sys::RTC_INVALID_GEOMETRY_ID)
                .ok_or_else(|| AccelError("embree: too many meshes".into()))?;
            let alpha = AlphaMask::of(mesh).map(Arc::new);
            let geom = Geometry::triangles(device, &mesh.positions, &mesh.indices, quality, alpha)?;
            builder.attach(geom, id)?;
        }
        Ok(EmbreeAccel {
            scene: builder.commit()?,
            normals: scene.meshes.iter().map(face_normals).collect(),
        })
    }

    /// The committed scene, for raw queries.
    pub fn scene(&self) -> &CommittedScene {
        &self.scene
    }

    /// Turns Embree's answer into a [`Hit`]; `None` for ids that name no triangle (cannot
    /// happen with geometry id = mesh index, but costs nothing to check).
    #[inline]
    fn to_hit(&self, h: RawHit) -> Option<Hit> {
        let ng = *self.normals.get(h.geom as usize)?.get(h.prim as usize)?;
        Some(Hit {
            t: h.t,
            mesh: h.geom,
            prim: h.prim,
            u: h.u,
            v: h.v,
            ng,
        })
    }
}

impl RayQuery for EmbreeAccel {
    #[inline]
    fn intersect(&self, ray: &Ray) -> Option<Hit> {
        self.scene.intersect1(ray).and_then(|h| self.to_hit(h))
    }

    #[inline]
    fn occluded(&self, ray: &Ray) -> bool {
        self.scene.occluded1(ray)
    }

    /// Packets of 8 (`rtcIntersect8`, coherent flag); the last packet may be partial.
    fn intersect_batch(&self, rays: &[Ray], out: &mut [Option<Hit>]) {
        let mut raw = [None; PACKET];
        for (rs, os) in rays.chunks(PACKET).zip(out.chunks_mut(PACKET)) {
            self.scene.intersect8(rs, &mut raw);
            for (o, h) in os.iter_mut().zip(raw) {
                *o = h.and_then(|h| self.to_hit(h));
            }
        }
    }

    /// Packets of 8 (`rtcOccluded8`, coherent flag); the last packet may be partial.
    fn occluded_batch(&self, rays: &[Ray], out: &mut [bool]) {
        for (rs, os) in rays.chunks(PACKET).zip(out.chunks_mut(PACKET)) {
            self.scene.occluded8(rs, os);
        }
    }
}
