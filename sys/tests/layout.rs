//! Layout facts the safe layer relies on (measured on Debian 12's Embree 3.13.5).
use photon_embree_sys::*;
use std::mem::{align_of, size_of};

#[test]
fn rayhit_layout() {
    assert_eq!(size_of::<RTCRay>(), 48);
    assert_eq!(align_of::<RTCRay>(), 16);
    assert_eq!(size_of::<RTCHit>(), 32);
    assert_eq!(size_of::<RTCRayHit>(), 80);
    assert_eq!(align_of::<RTCRayHit>(), 16);
}

#[test]
fn packet_layout() {
    assert_eq!(size_of::<RTCRayHit8>(), 640);
    assert_eq!(align_of::<RTCRayHit8>(), 32);
    assert_eq!(size_of::<RTCRay8>(), 384);
    assert_eq!(align_of::<Valid8>(), 32);
}

#[test]
fn invalid_id_and_context() {
    assert_eq!(RTC_INVALID_GEOMETRY_ID, !0u32);
    let ctx = rtc_intersect_context();
    assert!(ctx.filter.is_none());
    assert!(ctx.instID.iter().all(|&id| id == RTC_INVALID_GEOMETRY_ID));
}
