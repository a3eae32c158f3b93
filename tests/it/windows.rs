//! Light through a window: a room lit by a low sun and a sky only through an opening in one
//! wall, its floor set with thin tables and seats, inside a large dim ground that takes most of
//! the photons (as Bitterli's classroom does). The photon mapper against our path tracer.
//!
//! Few photons get in, so their k-nearest discs are wide, and the flattened search took
//! photons of a seat or table top into the floor below it (a quarter of a radius that reached
//! a metre); the final gather read that from the cache everywhere: the image came out 1.85x
//! the path tracer's (classroom: 1.19x). Gather hits now take the sun's and sky's direct light
//! by a shadow ray and the photons only for the rest.
//!
//! Of the sun's photons, shot over a disc covering the whole ground, 1 in 3000 met the window, so
//! its estimates stayed starved at any count a render affords; those lights now aim three
//! quarters of their photons at the sphere around what the camera sees (`photon::aim`).

use crate::support as common;
use common::TempDir;

fn scene(integrator: &str, spp: u32) -> String {
    // The photon mapper's parameters only on its own Integrator line.
    let photons = if integrator == "photonmap" {
        r#" "integer globalphotons" [ 1000000 ] "integer causticphotons" [ 0 ]"#
    } else {
        ""
    };
    format!(
        r#"LookAt 0.2 1.4 -1.8  0 0.6 1.2  0 1 0
Camera "perspective" "float fov" [ 70 ]
Film "rgb" "integer xresolution" [ 32 ] "integer yresolution" [ 24 ]
PixelFilter "box" "float xradius" [ 0.5 ] "float yradius" [ 0.5 ]
Sampler "independent" "integer pixelsamples" [ {spp} ]
Integrator "{integrator}" "integer maxdepth" [ 6 ]{photons}
WorldBegin
AttributeBegin
Material "diffuse" "rgb reflectance" [ 0.3 0.3 0.3 ]
Shape "trianglemesh" "point3 P" [ -30 -0.01 -30  30 -0.01 -30  30 -0.01 30  -30 -0.01 30 ] "integer indices" [ 0 2 1 0 3 2 ]
AttributeEnd
LightSource "distant" "point3 from" [ -1 0.7 0.3 ] "point3 to" [ 0 0 0 ] "rgb L" [ 6 6 6 ]
LightSource "infinite" "rgb L" [ 0.3 0.35 0.45 ]
Material "diffuse" "rgb reflectance" [ 0.7 0.7 0.7 ]
#  room 4 x 2.5 x 4, centred at x = 0, z in [-2, 2]; the wall at x = -2 has a window
Shape "trianglemesh" "point3 P" [ -2 0 -2  2 0 -2  2 0 2  -2 0 2 ] "integer indices" [ 0 2 1 0 3 2 ]
Shape "trianglemesh" "point3 P" [ -2 2.5 -2  2 2.5 -2  2 2.5 2  -2 2.5 2 ] "integer indices" [ 0 1 2 0 2 3 ]
Shape "trianglemesh" "point3 P" [ -2 0 2  2 0 2  2 2.5 2  -2 2.5 2 ] "integer indices" [ 0 1 2 0 2 3 ]
Shape "trianglemesh" "point3 P" [ -2 0 -2  2 0 -2  2 2.5 -2  -2 2.5 -2 ] "integer indices" [ 0 2 1 0 3 2 ]
Shape "trianglemesh" "point3 P" [ 2 0 -2  2 0 2  2 2.5 2  2 2.5 -2 ] "integer indices" [ 0 2 1 0 3 2 ]
#  the window wall: x = -2, an opening for y in [0.8, 2], z in [-1, 1]
Shape "trianglemesh" "point3 P" [ -2 0 -2  -2 0 2  -2 0.8 2  -2 0.8 -2
                                  -2 2 -2  -2 2 2  -2 2.5 2  -2 2.5 -2
                                  -2 0.8 -2  -2 0.8 -1  -2 2 -1  -2 2 -2
                                  -2 0.8 1  -2 0.8 2  -2 2 2  -2 2 1 ]
    "integer indices" [ 0 1 2 0 2 3  4 5 6 4 6 7  8 9 10 8 10 11  12 13 14 12 14 15 ]
Material "diffuse" "rgb reflectance" [ 0.6 0.45 0.3 ]
Shape "trianglemesh" "point3 P" [ -1.6 0.75 -1.5  -0.7999999999999999 0.75 -1.5  -0.7999999999999999 0.75 -0.8999999999999999  -1.6 0.75 -0.8999999999999999
                                  -1.6 0.72 -1.5  -0.7999999999999999 0.72 -1.5  -0.7999999999999999 0.72 -0.8999999999999999  -1.6 0.72 -0.8999999999999999 ]
    "integer indices" [ 0 2 1 0 3 2  4 5 6 4 6 7 ]
Shape "trianglemesh" "point3 P" [ -1.4 0.45 -0.85  -1.0 0.45 -0.85  -1.0 0.45 -0.5  -1.4 0.45 -0.5
                                  -1.4 0.42 -0.85  -1.0 0.42 -0.85  -1.0 0.42 -0.5  -1.4 0.42 -0.5 ]
    "integer indices" [ 0 2 1 0 3 2  4 5 6 4 6 7 ]
Shape "trianglemesh" "point3 P" [ -1.6 0.75 -0.09999999999999998  -0.7999999999999999 0.75 -0.09999999999999998  -0.7999999999999999 0.75 0.5  -1.6 0.75 0.5
                                  -1.6 0.72 -0.09999999999999998  -0.7999999999999999 0.72 -0.09999999999999998  -0.7999999999999999 0.72 0.5  -1.6 0.72 0.5 ]
    "integer indices" [ 0 2 1 0 3 2  4 5 6 4 6 7 ]
Shape "trianglemesh" "point3 P" [ -1.4 0.45 0.55  -1.0 0.45 0.55  -1.0 0.45 0.8999999999999999  -1.4 0.45 0.8999999999999999
                                  -1.4 0.42 0.55  -1.0 0.42 0.55  -1.0 0.42 0.8999999999999999  -1.4 0.42 0.8999999999999999 ]
    "integer indices" [ 0 2 1 0 3 2  4 5 6 4 6 7 ]
Shape "trianglemesh" "point3 P" [ -1.6 0.75 1.0999999999999999  -0.7999999999999999 0.75 1.0999999999999999  -0.7999999999999999 0.75 1.7  -1.6 0.75 1.7
                                  -1.6 0.72 1.0999999999999999  -0.7999999999999999 0.72 1.0999999999999999  -0.7999999999999999 0.72 1.7  -1.6 0.72 1.7 ]
    "integer indices" [ 0 2 1 0 3 2  4 5 6 4 6 7 ]
Shape "trianglemesh" "point3 P" [ -1.4 0.45 1.75  -1.0 0.45 1.75  -1.0 0.45 2.0999999999999996  -1.4 0.45 2.0999999999999996
                                  -1.4 0.42 1.75  -1.0 0.42 1.75  -1.0 0.42 2.0999999999999996  -1.4 0.42 2.0999999999999996 ]
    "integer indices" [ 0 2 1 0 3 2  4 5 6 4 6 7 ]
Shape "trianglemesh" "point3 P" [ -0.4 0.75 -1.5  0.4 0.75 -1.5  0.4 0.75 -0.8999999999999999  -0.4 0.75 -0.8999999999999999
                                  -0.4 0.72 -1.5  0.4 0.72 -1.5  0.4 0.72 -0.8999999999999999  -0.4 0.72 -0.8999999999999999 ]
    "integer indices" [ 0 2 1 0 3 2  4 5 6 4 6 7 ]
Shape "trianglemesh" "point3 P" [ -0.2 0.45 -0.85  0.2 0.45 -0.85  0.2 0.45 -0.5  -0.2 0.45 -0.5
                                  -0.2 0.42 -0.85  0.2 0.42 -0.85  0.2 0.42 -0.5  -0.2 0.42 -0.5 ]
    "integer indices" [ 0 2 1 0 3 2  4 5 6 4 6 7 ]
Shape "trianglemesh" "point3 P" [ -0.4 0.75 -0.09999999999999998  0.4 0.75 -0.09999999999999998  0.4 0.75 0.5  -0.4 0.75 0.5
                                  -0.4 0.72 -0.09999999999999998  0.4 0.72 -0.09999999999999998  0.4 0.72 0.5  -0.4 0.72 0.5 ]
    "integer indices" [ 0 2 1 0 3 2  4 5 6 4 6 7 ]
Shape "trianglemesh" "point3 P" [ -0.2 0.45 0.55  0.2 0.45 0.55  0.2 0.45 0.8999999999999999  -0.2 0.45 0.8999999999999999
                                  -0.2 0.42 0.55  0.2 0.42 0.55  0.2 0.42 0.8999999999999999  -0.2 0.42 0.8999999999999999 ]
    "integer indices" [ 0 2 1 0 3 2  4 5 6 4 6 7 ]
Shape "trianglemesh" "point3 P" [ -0.4 0.75 1.0999999999999999  0.4 0.75 1.0999999999999999  0.4 0.75 1.7  -0.4 0.75 1.7
                                  -0.4 0.72 1.0999999999999999  0.4 0.72 1.0999999999999999  0.4 0.72 1.7  -0.4 0.72 1.7 ]
    "integer indices" [ 0 2 1 0 3 2  4 5 6 4 6 7 ]
Shape "trianglemesh" "point3 P" [ -0.2 0.45 1.75  0.2 0.45 1.75  0.2 0.45 2.0999999999999996  -0.2 0.45 2.0999999999999996
                                  -0.2 0.42 1.75  0.2 0.42 1.75  0.2 0.42 2.0999999999999996  -0.2 0.42 2.0999999999999996 ]
    "integer indices" [ 0 2 1 0 3 2  4 5 6 4 6 7 ]
Shape "trianglemesh" "point3 P" [ 0.7999999999999999 0.75 -1.5  1.6 0.75 -1.5  1.6 0.75 -0.8999999999999999  0.7999999999999999 0.75 -0.8999999999999999
                                  0.7999999999999999 0.72 -1.5  1.6 0.72 -1.5  1.6 0.72 -0.8999999999999999  0.7999999999999999 0.72 -0.8999999999999999 ]
    "integer indices" [ 0 2 1 0 3 2  4 5 6 4 6 7 ]
Shape "trianglemesh" "point3 P" [ 1.0 0.45 -0.85  1.4 0.45 -0.85  1.4 0.45 -0.5  1.0 0.45 -0.5
                                  1.0 0.42 -0.85  1.4 0.42 -0.85  1.4 0.42 -0.5  1.0 0.42 -0.5 ]
    "integer indices" [ 0 2 1 0 3 2  4 5 6 4 6 7 ]
Shape "trianglemesh" "point3 P" [ 0.7999999999999999 0.75 -0.09999999999999998  1.6 0.75 -0.09999999999999998  1.6 0.75 0.5  0.7999999999999999 0.75 0.5
                                  0.7999999999999999 0.72 -0.09999999999999998  1.6 0.72 -0.09999999999999998  1.6 0.72 0.5  0.7999999999999999 0.72 0.5 ]
    "integer indices" [ 0 2 1 0 3 2  4 5 6 4 6 7 ]
Shape "trianglemesh" "point3 P" [ 1.0 0.45 0.55  1.4 0.45 0.55  1.4 0.45 0.8999999999999999  1.0 0.45 0.8999999999999999
                                  1.0 0.42 0.55  1.4 0.42 0.55  1.4 0.42 0.8999999999999999  1.0 0.42 0.8999999999999999 ]
    "integer indices" [ 0 2 1 0 3 2  4 5 6 4 6 7 ]
Shape "trianglemesh" "point3 P" [ 0.7999999999999999 0.75 1.0999999999999999  1.6 0.75 1.0999999999999999  1.6 0.75 1.7  0.7999999999999999 0.75 1.7
                                  0.7999999999999999 0.72 1.0999999999999999  1.6 0.72 1.0999999999999999  1.6 0.72 1.7  0.7999999999999999 0.72 1.7 ]
    "integer indices" [ 0 2 1 0 3 2  4 5 6 4 6 7 ]
Shape "trianglemesh" "point3 P" [ 1.0 0.45 1.75  1.4 0.45 1.75  1.4 0.45 2.0999999999999996  1.0 0.45 2.0999999999999996
                                  1.0 0.42 1.75  1.4 0.42 1.75  1.4 0.42 2.0999999999999996  1.0 0.42 2.0999999999999996 ]
    "integer indices" [ 0 2 1 0 3 2  4 5 6 4 6 7 ]
"#
    )
}

/// Mean and the 4x4 block means of the photon mapper (1M photons emitted, 64 spp) against
/// the path tracer (2048 spp): measured mean 1.000, blocks 0.92-1.09. Before the photons were
/// aimed (7f05ce7): mean 0.966 with a block at 0.73; before the gather's shadow rays to the
/// sun and sky: mean +88%, blocks up to 4.3x. At 100k photons (10k stored in the room) the
/// aimed maps give 0.947: too few photons for the room's corners.
#[test]
fn sun_and_sky_through_a_window_against_the_path_tracer() {
    let dir = TempDir::new("windows-room");
    let (mean, lo, hi) = common::photonmap_against_path(&dir, scene, 2048, 64);
    assert!((mean - 1.0).abs() < 0.03, "mean ratio {mean}");
    assert!(lo > 0.8 && hi < 1.2, "blocks {lo}..{hi}");
}
