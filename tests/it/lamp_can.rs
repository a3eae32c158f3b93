//! A lamp can against a wall: a point light inside a thin open-bottomed diffuse box hung
//! a hand's width from a room wall (Bitterli's veach-bidir has such a can beside its wall).
//! The photon mapper against our path tracer.
//!
//! Two leaks light the wall and ceiling around the can (at 256 spp, 4x4 block means against
//! the path tracer at 16384 spp; veach-bidir shows the same streak beside its can). Our path
//! tracer agrees with pbrt-v4 on this file (blocks 0.95-1.07, both at 16384 spp).
//! - Fixed: the irradiance cache served a gather hit from the nearest cache point whose
//!   normal agreed, anywhere within the global radius, so the ceiling took the inside of the
//!   can's lid (blocks above the can 2.6x, now 1.3x). A cache point now serves only points
//!   its own estimate covered (`photon::cache`'s unit test; veach-bidir at 128 px, 64 spp:
//!   relMSE 0.18 -> 0.11 against pbrt-v4).
//! - Open: photons on the inside of the can's side walls near an edge arrive against the
//!   front's normal and lie within the flattened disc, so the can's outer faces glow and the
//!   wall beside them sees that (blocks by the can 1.8-2.1x). Leaving out the photons behind
//!   the query's tangent plane whose surface normal is off by more than 60 degrees fixes this
//!   scene (blocks 0.94-1.06) but darkens `tests/windows.rs` (mean 0.996 -> 0.954 at 100k
//!   photons, 1.03 -> 1.01 at 4M): there, sparse photons make discs wider than a table's
//!   underside or the room, and those leaked photons were what filled them.

use crate::support as common;
use common::TempDir;

fn scene(integrator: &str, spp: u32) -> String {
    // The photon mapper's parameters only on its own Integrator line.
    let photons = if integrator == "photonmap" {
        r#" "integer globalphotons" [ 20000 ] "integer causticphotons" [ 0 ]"#
    } else {
        ""
    };
    format!(
        r#"LookAt 1.5 1.6 0  -2 1.5 0  0 1 0
Camera "perspective" "float fov" [ 50 ]
Film "rgb" "integer xresolution" [ 32 ] "integer yresolution" [ 24 ]
PixelFilter "box" "float xradius" [ 0.5 ] "float yradius" [ 0.5 ]
Sampler "independent" "integer pixelsamples" [ {spp} ]
Integrator "{integrator}" "integer maxdepth" [ 6 ]{photons}
WorldBegin
Material "diffuse" "rgb reflectance" [ 0.6 0.6 0.6 ]
#  room 4 x 2.5 x 4 around the origin's column
Shape "trianglemesh" "point3 P" [ -2 0 -2  2 0 -2  2 0 2  -2 0 2 ] "integer indices" [ 0 2 1 0 3 2 ]
Shape "trianglemesh" "point3 P" [ -2 2.5 -2  2 2.5 -2  2 2.5 2  -2 2.5 2 ] "integer indices" [ 0 1 2 0 2 3 ]
Shape "trianglemesh" "point3 P" [ -2 0 2  2 0 2  2 2.5 2  -2 2.5 2 ] "integer indices" [ 0 1 2 0 2 3 ]
Shape "trianglemesh" "point3 P" [ -2 0 -2  2 0 -2  2 2.5 -2  -2 2.5 -2 ] "integer indices" [ 0 2 1 0 3 2 ]
Shape "trianglemesh" "point3 P" [ 2 0 -2  2 0 2  2 2.5 2  2 2.5 -2 ] "integer indices" [ 0 2 1 0 3 2 ]
Shape "trianglemesh" "point3 P" [ -2 0 -2  -2 0 2  -2 2.5 2  -2 2.5 -2 ] "integer indices" [ 0 1 2 0 2 3 ]
#  the can: x in [-1.9, -1.6], z in [-0.15, 0.15], y in [1.5, 1.9], open below
Material "diffuse" "rgb reflectance" [ 0.7 0.7 0.7 ]
Shape "trianglemesh" "point3 P" [ -1.9 1.5 -0.15  -1.9 1.5 0.15  -1.9 1.9 0.15  -1.9 1.9 -0.15
                                  -1.6 1.5 -0.15  -1.6 1.5 0.15  -1.6 1.9 0.15  -1.6 1.9 -0.15 ]
    "integer indices" [ 0 1 2 0 2 3  4 5 6 4 6 7  0 4 7 0 7 3  1 5 6 1 6 2  3 2 6 3 6 7 ]
LightSource "point" "point3 from" [ -1.75 1.75 0 ] "rgb I" [ 2 2 2 ]
"#
    )
}

/// Mean and 4x4 block means of the photon mapper (20k photons, 256 spp) against the path
/// tracer (8192 spp, itself within 7% of 16384 spp per block).
#[test]
#[ignore = "open: the edge leak (module docs), blocks by the can 1.8-2.1x"]
fn lamp_can_beside_a_wall_against_the_path_tracer() {
    let dir = TempDir::new("lamp-can");
    let (mean, lo, hi) = common::photonmap_against_path(&dir, scene, 8192, 256);
    assert!((mean - 1.0).abs() < 0.03, "mean ratio {mean}");
    assert!(lo > 0.85 && hi < 1.15, "blocks {lo}..{hi}");
}
