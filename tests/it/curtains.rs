//! Light through a curtain: a closed room whose only light sits behind a `diffusetransmission`
//! curtain spanning the room (Bitterli's bedroom: its two window lights are behind such
//! curtains). The photon mapper against our path tracer.
//!
//! All the room's light crosses the curtain, as photons that land on its back and leave from
//! its front. The photon mapper's estimates at a diffuse point took only the photons arriving
//! on the side the point is seen from, weighted by the reflectance: a final-gather ray from
//! the room that hit the curtain read the curtain's dim room side and nothing of its lit back,
//! and the room came out at 0.45-0.6 of the path tracer's (bedroom: 0.84 overall).

use crate::support as common;
use common::TempDir;

fn scene(integrator: &str, spp: u32) -> String {
    let photons = if integrator == "photonmap" {
        r#" "integer globalphotons" [ 200000 ] "integer causticphotons" [ 0 ]"#
    } else {
        ""
    };
    let room = common::CLOSED_ROOM;
    format!(
        r#"LookAt 1.8 1.7 -1.7  -1 0.8 0.8  0 1 0
Camera "perspective" "float fov" [ 75 ]
Film "rgb" "integer xresolution" [ 32 ] "integer yresolution" [ 24 ]
PixelFilter "box" "float xradius" [ 0.5 ] "float yradius" [ 0.5 ]
Sampler "independent" "integer pixelsamples" [ {spp} ]
Integrator "{integrator}" "integer maxdepth" [ 8 ]{photons}
WorldBegin
Material "diffuse" "rgb reflectance" [ 0.6 0.6 0.6 ]
#  room 4 x 2.5 x 4: x, z in [-2, 2], y in [0, 2.5]
{room}Material "diffuse" "rgb reflectance" [ 0.5 0.35 0.2 ]
#  a low box on the floor
Shape "trianglemesh" "point3 P" [ 0 0.5 -0.5  1 0.5 -0.5  1 0.5 0.5  0 0.5 0.5
                                  0 0 -0.5  1 0 -0.5  1 0 0.5  0 0 0.5 ]
    "integer indices" [ 0 2 1 0 3 2  0 1 5 0 5 4  1 2 6 1 6 5  2 3 7 2 7 6  3 0 4 3 4 7 ]
#  the curtain, from wall to wall and floor to ceiling, 0.3 in front of the light's wall
Material "diffusetransmission" "rgb reflectance" [ 0.45 0.45 0.45 ] "rgb transmittance" [ 0.45 0.45 0.45 ]
Shape "trianglemesh" "point3 P" [ -1.6 0 -2  -1.6 0 2  -1.6 2.5 2  -1.6 2.5 -2 ] "integer indices" [ 0 1 2 0 2 3 ]
#  the window light behind it
AttributeBegin
AreaLightSource "diffuse" "rgb L" [ 8 8 8 ] "bool twosided" true
Material "diffuse" "rgb reflectance" [ 0 0 0 ]
Shape "trianglemesh" "point3 P" [ -1.95 0.6 -1  -1.95 0.6 1  -1.95 2 1  -1.95 2 -1 ] "integer indices" [ 0 1 2 0 2 3 ]
AttributeEnd
"#
    )
}

/// Mean and the 4x4 block means of the photon mapper (200k photons, 64 spp) against the path
/// tracer (1024 spp).
#[test]
fn light_through_a_diffuse_transmitter_against_the_path_tracer() {
    let dir = TempDir::new("curtain-room");
    let (mean, lo, hi) = common::photonmap_against_path(&dir, scene, 1024, 64);
    assert!((mean - 1.0).abs() < 0.03, "mean ratio {mean}");
    assert!(lo > 0.85 && hi < 1.15, "blocks {lo}..{hi}");
}
