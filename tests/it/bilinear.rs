//! `Shape "bilinearmesh"` (pbrt-v4's bilinear patches, tessellated into triangles):
//! - a planar patch is the two triangles `p00 p10 p11`, `p00 p11 p01`: a room whose floor and
//!   one-sided area light are bilinear patches renders bit for bit the image of the same room
//!   written as `trianglemesh`es (with the patches' default uvs), with the photon mapper and
//!   the path tracer;
//! - a curved patch's tessellated area (its world-space triangles, through a CTM scaling by 2)
//!   is the integral of `|dP/du x dP/dv|` within 6e-4, and it emits power by that area;
//! - bad input is one located line: indices not a multiple of 4, out of range, missing with
//!   other than 4 points, `N`/`uv`/`faceIndices` of the wrong count, unknown parameters.
use crate::support as common;

use common::{render_with, TempDir};
use photon::accel::BackendKind;
use photon::integrator::IntegratorKind;
use photon::scene::{loader, Scene};

fn load(dir: &TempDir, text: &str) -> Result<Scene, String> {
    loader::load(&dir.write("scene.pbrt", text)).map_err(|e| e.to_string())
}

/// A box room seen from the front; `floor` and `light` are the shapes (in the room's
/// coordinates: floor y = 0 over [-1, 1]^2, light y = 1.99 over [-0.3, 0.3]^2 facing down).
fn room(floor: &str, light: &str) -> String {
    format!(
        r#"LookAt 0 1 3.5  0 1 0  0 1 0
Camera "perspective" "float fov" [ 45 ]
Film "rgb" "integer xresolution" [ 24 ] "integer yresolution" [ 24 ]
WorldBegin
Material "diffuse" "rgb reflectance" [ 0.6 0.5 0.4 ]
{floor}
Shape "trianglemesh" "point3 P" [ -1 0 -1  -1 2 -1  1 2 -1  1 0 -1 ] "integer indices" [ 0 1 2 0 2 3 ]
Shape "trianglemesh" "point3 P" [ -1 0 -1  -1 0 1  -1 2 1  -1 2 -1 ] "integer indices" [ 0 1 2 0 2 3 ]
AttributeBegin
AreaLightSource "diffuse" "rgb L" [ 5 5 5 ]
{light}
AttributeEnd
"#
    )
}

/// The four corners `p00 p10 p01 p11` as a bilinear patch and as the two triangles it is.
fn both(p: [[f32; 3]; 4]) -> (String, String) {
    let pts = p
        .iter()
        .map(|v| format!("{} {} {}", v[0], v[1], v[2]))
        .collect::<Vec<_>>()
        .join("  ");
    (
        format!(r#"Shape "bilinearmesh" "point3 P" [ {pts} ] "integer indices" [ 0 1 2 3 ]"#),
        format!(
            r#"Shape "trianglemesh" "point3 P" [ {pts} ] "integer indices" [ 0 1 3 0 3 2 ] "point2 uv" [ 0 0 1 0 0 1 1 1 ]"#
        ),
    )
}

#[test]
fn planar_patches_render_as_their_triangles_bit_for_bit() {
    let dir = TempDir::new("photon-bilinear");
    // A floor whose corners are no parallelogram (still planar), and the light facing down:
    // (p10 - p00) x (p01 - p00) = +x x +z = -y.
    let (floor_b, floor_t) = both([
        [-1.0, 0.0, 1.0],
        [1.0, 0.0, 1.0],
        [-1.0, 0.0, -1.0],
        [1.2, 0.0, -0.8],
    ]);
    let (light_b, light_t) = both([
        [-0.3, 1.99, -0.3],
        [0.3, 1.99, -0.3],
        [-0.3, 1.99, 0.3],
        [0.3, 1.99, 0.3],
    ]);
    let b = load(&dir, &room(&floor_b, &light_b)).unwrap();
    let t = load(&dir, &room(&floor_t, &light_t)).unwrap();
    for kind in [IntegratorKind::Photonmap, IntegratorKind::Path] {
        let render = |s: &Scene| render_with(s, kind, BackendKind::Embree, (24, 24, 4), 0, 5);
        let (ib, it) = (render(&b).image, render(&t).image);
        let lit = ib.pixels.iter().filter(|p| p[1] > 0.0).count();
        assert!(lit > 24 * 24 / 2, "{kind:?}: only {lit} pixels lit");
        assert!(ib.pixels == it.pixels, "{kind:?}: the images differ");
    }
}

/// The saddle `z = uv` over the unit square, scaled by 2 by the CTM, as an emitter.
const SADDLE: &str = r#"Scale 2 2 2
AreaLightSource "diffuse" "rgb L" [ 1 1 1 ]
Shape "bilinearmesh" "point3 P" [ 0 0 0  1 0 0  0 1 0  1 1 1 ]"#;

#[test]
fn curved_patch_area_matches_the_integral() {
    let dir = TempDir::new("photon-bilinear");
    let s = load(&dir, &format!("WorldBegin\n{SADDLE}\n")).unwrap();
    assert_eq!(s.meshes.len(), 1);
    let m = &s.meshes[0];
    let area: f64 = m
        .indices
        .iter()
        .map(|t| {
            let [a, b, c] = t.map(|i| m.positions[i as usize].as_dvec3());
            0.5 * (b - a).cross(c - a).length()
        })
        .sum();
    // 4 x the integral of sqrt(1 + u^2 + v^2) over the unit square (midpoint rule, 2000^2).
    let k = 2000u64;
    let exact = 4.0
        * (0..k * k)
            .map(|i| {
                let u = ((i % k) as f64 + 0.5) / k as f64;
                let v = ((i / k) as f64 + 0.5) / k as f64;
                (1.0 + u * u + v * v).sqrt()
            })
            .sum::<f64>()
        / (k * k) as f64;
    let rel = area / exact - 1.0;
    println!(
        "saddle: {} triangles, area {area:.6} against {exact:.6} ({rel:+.2e})",
        m.indices.len()
    );
    assert_eq!(m.indices.len(), 2 * 16 * 16);
    assert!(rel.abs() < 6e-4, "{rel}");
    // Smooth shading: every vertex has the surface's unit normal.
    let nn = m.normals.as_ref().expect("analytic normals");
    assert!(nn.iter().all(|n| (n.length() - 1.0).abs() < 1e-5));
    // The emitter's power is pi L times that area.
    let lights = s.emitters();
    let power: f32 = lights.powers().iter().sum();
    let want = std::f64::consts::PI * area;
    assert!(
        (power as f64 / want - 1.0).abs() < 1e-4,
        "power {power} against pi * area {want}"
    );
}

#[test]
fn bad_bilinear_meshes_are_located_errors() {
    let dir = TempDir::new("photon-bilinear-err");
    let cases: [(&str, &str); 8] = [
        (
            r#"Shape "bilinearmesh" "point3 P" [ 0 0 0  1 0 0  0 1 0  1 1 0  2 0 0 ] "integer indices" [ 0 1 2 3 4 ]"#,
            "not a positive multiple of 4",
        ),
        (
            r#"Shape "bilinearmesh" "point3 P" [ 0 0 0  1 0 0  0 1 0  1 1 0 ] "integer indices" [ 0 1 2 4 ]"#,
            "out of range",
        ),
        (
            r#"Shape "bilinearmesh" "point3 P" [ 0 0 0  1 0 0  0 1 0  1 1 0  2 0 0 ]"#,
            "needs \"integer indices\"",
        ),
        (
            r#"Shape "bilinearmesh" "integer indices" [ 0 1 2 3 ]"#,
            "needs \"point3 P\"",
        ),
        (
            r#"Shape "bilinearmesh" "point3 P" [ 0 0 0  1 0 0  0 1 0  1 1 0 ] "normal N" [ 0 0 1 ]"#,
            "1 values given for 4 points",
        ),
        (
            r#"Shape "bilinearmesh" "point3 P" [ 0 0 0  1 0 0  0 1 0  1 1 0 ] "point2 uv" [ 0 0 1 1 ]"#,
            "2 values given for 4 points",
        ),
        (
            r#"Shape "bilinearmesh" "point3 P" [ 0 0 0  1 0 0  0 1 0  1 1 0 ] "integer faceIndices" [ 0 1 ]"#,
            "2 face indices given for 1 patches",
        ),
        (
            r#"Shape "bilinearmesh" "point3 P" [ 0 0 0  1 0 0  0 1 0  1 1 0 ] "string emissionfilename" "x.exr""#,
            "emissionfilename",
        ),
    ];
    for (shape, needle) in cases {
        let e = load(&dir, &format!("WorldBegin\n\n{shape}\n")).expect_err(shape);
        assert!(
            e.contains("scene.pbrt:3:") && e.contains(needle),
            "{shape}: {e}"
        );
        assert_eq!(e.lines().count(), 1, "{e}");
    }
    // faceIndices of the right count is accepted (and ignored); four points need no indices.
    let ok = r#"Shape "bilinearmesh" "point3 P" [ 0 0 0  1 0 0  0 1 0  1 1 0 ] "integer faceIndices" [ 7 ]"#;
    let s = load(&dir, &format!("WorldBegin\n{ok}\n")).unwrap();
    assert_eq!(s.meshes[0].indices.len(), 2);
}
