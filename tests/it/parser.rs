//! Tests of the pbrt-v4 loader: the three shared scenes, every supported directive against
//! hand-computed values, and every error path with its exact `file:line`.
//!
//! Scenes written by the tests go to a fresh directory under the system temp dir.

use photon::material::*;
use photon::math::{Mat4, Vec2, Vec3};
use photon::scene::loader::load;
use photon::scene::{FilterDesc, Light, Material, MaterialKind, Scene, SceneError};
use std::f32::consts::PI;
use std::path::{Path, PathBuf};

use crate::support as common;
use common::TempDir;

// ---------------------------------------------------------------------------------------------
// helpers

/// Loads `src` written as `scene.pbrt` in a fresh directory.
fn load_src(src: &str) -> Result<Scene, SceneError> {
    let dir = TempDir::new("photon-parser");
    load(&dir.write("scene.pbrt", src))
}

/// Loads a scene that must load.
fn ok(src: &str) -> Scene {
    match load_src(src) {
        Ok(s) => s,
        Err(e) => panic!("scene failed to load: {e}"),
    }
}

/// Checks that `r` failed at `file_suffix:line` with a one-line message containing `needles`.
#[track_caller]
fn assert_err(r: Result<Scene, SceneError>, file_suffix: &str, line: u32, needles: &[&str]) {
    let e = match r {
        Ok(_) => panic!("expected an error at {file_suffix}:{line}, the scene loaded"),
        Err(e) => e,
    };
    let text = e.to_string();
    let loc = e
        .loc
        .as_ref()
        .unwrap_or_else(|| panic!("no location in: {text}"));
    assert!(
        loc.file.to_string_lossy().ends_with(file_suffix),
        "wrong file in: {text}"
    );
    assert_eq!(loc.line, line, "wrong line in: {text}");
    assert!(text.starts_with(&format!(
        "{}:{}:{}: ",
        loc.file.display(),
        loc.line,
        loc.col
    )));
    assert!(!text.contains('\n'), "message is not one line: {text:?}");
    for n in needles {
        assert!(text.contains(n), "{text:?} does not mention {n:?}");
    }
}

/// Checks an error of a scene given as source text, written as `scene.pbrt`.
#[track_caller]
fn assert_src_err(src: &str, line: u32, needles: &[&str]) {
    assert_err(load_src(src), "scene.pbrt", line, needles);
}

fn close(a: f32, b: f32, tol: f32) -> bool {
    (a - b).abs() <= tol * b.abs().max(1.0)
}

#[track_caller]
fn assert_vec(a: Vec3, b: Vec3, tol: f32) {
    assert!((a - b).abs().max_element() <= tol, "{a:?} != {b:?}");
}

/// The mesh vertices of the only mesh of a scene.
fn only_mesh(s: &Scene) -> &photon::scene::Mesh {
    assert_eq!(s.meshes.len(), 1);
    &s.meshes[0]
}

const TRI: &str =
    r#"Shape "trianglemesh" "point3 P" [ 1 0 0  0 1 0  0 0 1 ] "integer indices" [ 0 1 2 ]"#;

fn shared(p: &str) -> PathBuf {
    Path::new("../shared/scenes").join(p)
}

/// Every number inside the `[ ... ]` following each occurrence of `key` in `text`: a separate,
/// simple reading of the file to compare the loader with.
fn lists_after(text: &str, key: &str) -> Vec<Vec<f64>> {
    let mut out = Vec::new();
    let mut rest = text;
    while let Some(i) = rest.find(key) {
        rest = &rest[i + key.len()..];
        let open = rest.find('[').unwrap();
        let close = rest.find(']').unwrap();
        out.push(
            rest[open + 1..close]
                .split_whitespace()
                .map(|w| w.parse().unwrap())
                .collect(),
        );
    }
    out
}

// ---------------------------------------------------------------------------------------------
// the shared scenes

#[test]
fn cornell_box_loads() {
    let path = shared("cornell-box/scene-v4.pbrt");
    let text = std::fs::read_to_string(&path).unwrap();
    let s = load(&path).unwrap_or_else(|e| panic!("{e}"));

    let tris: usize = lists_after(&text, "\"integer indices\"")
        .iter()
        .map(|l| l.len() / 3)
        .sum();
    assert_eq!(s.triangle_count(), tris);
    assert_eq!(s.meshes.len(), text.matches("Shape ").count());
    assert_eq!(s.materials.len(), text.matches("MakeNamedMaterial").count());
    assert_eq!(s.materials.len(), 8);
    assert_eq!(s.lights.len(), 1);
    let Light::Area { mesh, l, two_sided } = &s.lights[0] else {
        panic!("not an area light: {:?}", s.lights[0]);
    };
    assert_eq!(*l, Vec3::new(17.0, 12.0, 4.0));
    assert!(!two_sided);
    assert_eq!(s.meshes[*mesh as usize].area_light, Some(0));
    assert_eq!(
        s.materials[s.meshes[*mesh as usize].material as usize],
        diffuse(Vec3::ZERO)
    );
    // The light is the last shape: 0.47 x 0.38 at y = 1.98.
    let lm = &s.meshes[*mesh as usize];
    let area: f32 = (0..2).map(|t| lm.area(t)).sum();
    assert!(close(area, 0.47 * 0.38, 1e-5));
    // Floor material: LeftWall colour appears on the left wall.
    let red = diffuse(Vec3::new(0.63, 0.065, 0.05));
    assert_eq!(s.materials.iter().filter(|m| **m == red).count(), 1);

    let cam = s.camera.world_from_camera;
    assert_vec(
        cam.transform_point3(Vec3::ZERO),
        Vec3::new(0.0, 1.0, 6.8),
        1e-5,
    );
    assert_vec(
        cam.transform_vector3(Vec3::Z),
        Vec3::new(0.0, 0.0, -1.0),
        1e-6,
    );
    assert_eq!(s.camera.fov_deg, 19.5);
    assert_eq!((s.film.xres, s.film.yres), (1024, 1024));
    assert_eq!(s.film.filename.as_deref(), Some("cornell-box.png"));
    assert_eq!(s.filter, FilterDesc::Triangle { radius: Vec2::ONE });
    assert_eq!(
        (s.sampler.name.as_str(), s.sampler.pixel_samples),
        ("sobol", 64)
    );
    assert_eq!(s.integrator.name, "path");
    assert_eq!(s.integrator.loc.as_ref().unwrap().line, 1);
    let mut ip = s.integrator.params.clone();
    assert!(
        ip.check_unused().is_err(),
        "the loader must leave integrator params unread"
    );
    assert_eq!(ip.get_int("maxdepth", 5).unwrap(), 65);
    ip.check_unused().unwrap();
    // Shading normals as given (unit, the floor's is +y).
    let floor = &s.meshes[0];
    assert_vec(floor.normals.as_ref().unwrap()[0], Vec3::Y, 1e-6);
    assert_eq!(floor.uvs.as_ref().unwrap()[2], Vec2::new(1.0, 1.0));
}

#[test]
fn veach_mis_loads() {
    let path = shared("veach-mis/scene-v4.pbrt");
    let text = std::fs::read_to_string(&path).unwrap();
    let s = load(&path).unwrap_or_else(|e| panic!("{e}"));

    let n_area = text.matches("AreaLightSource").count();
    assert_eq!(n_area, 3, "the shared copy has three sphere lights");
    assert_eq!(s.lights.len(), n_area);
    // (centre, radius, L) read off the file by hand.
    let want = [
        (Vec3::new(0.0, 6.5, -2.8), 1.0, 7.599088),
        (Vec3::new(0.0, 6.5, 0.0), 0.5, 30.396353),
        (Vec3::new(0.0, 6.5, 2.7), 0.05, 3039.6353),
    ];
    for (light, (c, r, lv)) in s.lights.iter().zip(want) {
        let Light::Area { mesh, l, .. } = light else {
            panic!("{light:?}")
        };
        assert_eq!(*l, Vec3::splat(lv));
        let m = &s.meshes[*mesh as usize];
        let (mc, mr) = m.sphere.expect("sphere light keeps its analytic sphere");
        assert_vec(mc, c, 1e-6);
        assert!(close(mr, r, 1e-6));
        let area: f64 = (0..m.indices.len() as u32).map(|t| m.area(t) as f64).sum();
        let exact = 4.0 * std::f64::consts::PI * (r as f64).powi(2);
        let rel = (area - exact).abs() / exact;
        assert!(rel < 1e-3, "tessellated area off by {rel}");
        for p in &m.positions {
            assert!(((*p - c).length() - r).abs() < 1e-5 * r.max(1.0));
        }
    }
    // Conductors, copper RGB, alpha = roughness since remaproughness is false.
    let mut alphas: Vec<f32> = s
        .materials
        .iter()
        .filter_map(conductor)
        .map(|(eta, k, alpha_u, alpha_v)| {
            assert_eq!(eta, Vec3::new(0.200438, 0.924033, 1.102212));
            assert_eq!(k, Vec3::new(3.912949, 2.452848, 2.142188));
            assert_eq!(alpha_u, alpha_v);
            alpha_u
        })
        .collect();
    alphas.sort_by(f32::total_cmp);
    assert_eq!(alphas, vec![0.01, 0.05, 0.1, 0.25]);
    assert_eq!((s.film.xres, s.film.yres), (1280, 720));
    assert!(close(s.camera.fov_deg, 20.114292, 1e-7));
    // Camera: Transform column 3 is (0, -3.5, 28.2792); the camera sits where it maps to 0.
    let cam_from_world = s.camera.world_from_camera.inverse();
    let eye = s.camera.world_from_camera.transform_point3(Vec3::ZERO);
    assert_vec(cam_from_world.transform_point3(eye), Vec3::ZERO, 1e-4);
    assert_vec(eye, Vec3::new(28.2792, 3.5, 0.0), 1e-3);
}

#[test]
fn cornell_spheres_loads() {
    let path = shared("cornell-spheres/scene.pbrt");
    let s = load(&path).unwrap_or_else(|e| panic!("{e}"));
    let plys: Vec<_> = s
        .meshes
        .iter()
        .filter(|m| m.indices.len() == 20480)
        .collect();
    assert_eq!(plys.len(), 2);
    assert_eq!(s.triangle_count(), 5 * 2 + 2 * 20480 + 2);
    for m in plys {
        assert_eq!(m.positions.len(), 10242);
        let (lo, hi) = m.positions.iter().fold(
            (Vec3::splat(f32::MAX), Vec3::splat(f32::MIN)),
            |(lo, hi), p| (lo.min(*p), hi.max(*p)),
        );
        let c = 0.5 * (lo + hi);
        for p in &m.positions {
            let d = (*p - c).length();
            assert!((d - 0.1).abs() < 1e-4, "vertex at distance {d} from {c:?}");
        }
        // resting on the floor (the file leaves a 0.5 mm gap)
        assert!(lo.y >= 0.0 && lo.y < 1e-3, "lowest point {}", lo.y);
        assert!(m.normals.is_none() && m.sphere.is_none());
    }
    let glass = dielectric(1.5);
    assert!(s.materials.contains(&glass));
    let mirror = s
        .materials
        .iter()
        .find_map(conductor)
        .map(|(eta, k, alpha_u, _)| (eta, k, alpha_u));
    let (eta, k, alpha) = mirror.expect("mirror conductor");
    assert_eq!(eta, Vec3::ONE);
    let k_expect = 2.0 * (1.0f64 - 1e-7).sqrt() / 1e-7f64.sqrt();
    assert!(close(k.x, k_expect as f32, 1e-3), "k {k:?} vs {k_expect}");
    assert_eq!(alpha, 0.0);
    // Scale -1 1 1 before LookAt: camera +x is world +x (red wall on the left of the image).
    let cam = s.camera.world_from_camera;
    assert_vec(
        cam.transform_point3(Vec3::ZERO),
        Vec3::new(0.0, 0.28, 1.08),
        1e-6,
    );
    assert_vec(
        cam.transform_vector3(Vec3::Z),
        Vec3::new(0.0, 0.0, -1.0),
        1e-6,
    );
    assert_vec(cam.transform_vector3(Vec3::X), Vec3::X, 1e-6);
    assert_vec(cam.transform_vector3(Vec3::Y), Vec3::Y, 1e-6);
    assert_eq!(
        s.filter,
        FilterDesc::Box {
            radius: Vec2::splat(0.5)
        }
    );
    assert_eq!(s.lights.len(), 1);
    assert!(matches!(s.lights[0], Light::Area { l, .. } if l == Vec3::splat(20.0)));
}

#[test]
fn shared_scenes_load_quickly() {
    for p in [
        "cornell-box/scene-v4.pbrt",
        "veach-mis/scene-v4.pbrt",
        "cornell-spheres/scene.pbrt",
    ] {
        let t = std::time::Instant::now();
        let s = load(&shared(p)).unwrap();
        let ms = t.elapsed().as_secs_f64() * 1e3;
        println!("load {p}: {ms:.2} ms, {} triangles", s.triangle_count());
    }
}

// ---------------------------------------------------------------------------------------------
// transforms

/// The world positions of the unit triangle (1,0,0) (0,1,0) (0,0,1) after `prefix`.
fn tri_after(prefix: &str) -> Vec<Vec3> {
    let s = ok(&format!("WorldBegin\n{prefix}\n{TRI}\n"));
    only_mesh(&s).positions.clone()
}

#[test]
fn translate_then_rotate_post_multiplies() {
    // CTM = T(1,0,0) R_z(90): a point is rotated first, then translated.
    let p = tri_after("Translate 1 0 0\nRotate 90 0 0 1");
    assert_vec(p[0], Vec3::new(1.0, 1.0, 0.0), 1e-6);
    assert_vec(p[1], Vec3::new(0.0, 0.0, 0.0), 1e-6);
    assert_vec(p[2], Vec3::new(1.0, 0.0, 1.0), 1e-6);
    // Rotate about a non-unit axis (normalised): 120 degrees about (1,1,1) cycles x->y->z.
    let p = tri_after("Rotate 120 2 2 2");
    assert_vec(p[0], Vec3::Y, 1e-6);
    assert_vec(p[1], Vec3::Z, 1e-6);
}

#[test]
fn scale_and_identity() {
    let p = tri_after("Scale 2 3 4");
    assert_vec(p[0], Vec3::new(2.0, 0.0, 0.0), 0.0);
    assert_vec(p[2], Vec3::new(0.0, 0.0, 4.0), 0.0);
    let p = tri_after("Translate 5 5 5\nIdentity");
    assert_vec(p[1], Vec3::Y, 0.0);
}

#[test]
fn transform_replaces_and_concat_post_multiplies() {
    // Transform = translation (5,6,7) (elements 12..14), then ConcatTransform scale 2:
    // CTM = T S, so (1,0,0) -> (2,0,0) + (5,6,7).
    let p = tri_after(
        "Translate 100 0 0\nTransform [1 0 0 0 0 1 0 0 0 0 1 0 5 6 7 1]\n\
         ConcatTransform [2 0 0 0 0 2 0 0 0 0 2 0 0 0 0 1]",
    );
    assert_vec(p[0], Vec3::new(7.0, 6.0, 7.0), 1e-6);
    assert_vec(p[2], Vec3::new(5.0, 6.0, 9.0), 1e-6);
    // Column-major: a shear matrix whose column 0 is (1, 2, 0): x feeds y.
    let p = tri_after("Transform [1 2 0 0  0 1 0 0  0 0 1 0  0 0 0 1]");
    assert_vec(p[0], Vec3::new(1.0, 2.0, 0.0), 0.0);
    assert_vec(p[1], Vec3::new(0.0, 1.0, 0.0), 0.0);
}

#[test]
fn look_at_camera_and_coordinate_systems() {
    let s = ok(r#"LookAt 1 2 3  1 2 0  0 1 0
Camera "perspective" "float fov" 45
WorldBegin
CoordSysTransform "camera"
LightSource "point" "point3 from" [ 0 0 1 ]
Translate 0 5 0
CoordinateSystem "mine"
Identity
CoordSysTransform "mine"
LightSource "point" "point3 from" [ 1 0 0 ]
"#);
    let cam = s.camera.world_from_camera;
    assert_vec(
        cam.transform_point3(Vec3::ZERO),
        Vec3::new(1.0, 2.0, 3.0),
        1e-6,
    );
    // pbrt's LookAt: camera +z = dir, +x = cross(up, dir), +y = cross(dir, right).
    assert_vec(
        cam.transform_vector3(Vec3::Z),
        Vec3::new(0.0, 0.0, -1.0),
        1e-6,
    );
    assert_vec(
        cam.transform_vector3(Vec3::X),
        Vec3::new(-1.0, 0.0, 0.0),
        1e-6,
    );
    assert_vec(
        cam.transform_vector3(Vec3::Y),
        Vec3::new(0.0, 1.0, 0.0),
        1e-6,
    );
    assert_eq!(s.camera.fov_deg, 45.0);
    // "camera": one unit in front of the eye.
    let Light::Point(photon::light::PointLight { pos, .. }) = s.lights[0] else {
        panic!()
    };
    assert_vec(pos, Vec3::new(1.0, 2.0, 2.0), 1e-6);
    // "mine" = world_from_camera * T(0,5,0): camera-space (1,5,0) is eye - 1 x + 5 y.
    let Light::Point(photon::light::PointLight { pos, .. }) = s.lights[1] else {
        panic!()
    };
    assert_vec(pos, Vec3::new(0.0, 7.0, 3.0), 1e-5);
}

#[test]
fn transform_and_attribute_blocks_restore_state() {
    let s = ok(&format!(
        r#"TransformBegin
Translate 9 9 9
TransformEnd
WorldBegin
Material "diffuse" "rgb reflectance" [ 0.1 0.2 0.3 ]
AttributeBegin
  Translate 0 0 10
  Material "dielectric"
  ReverseOrientation
  AreaLightSource "diffuse"
  TransformBegin
    Translate 0 0 10
  TransformEnd
  {TRI}
AttributeEnd
{TRI}
"#
    ));
    assert_eq!(s.meshes.len(), 2);
    let (inner, outer) = (&s.meshes[0], &s.meshes[1]);
    assert_vec(inner.positions[0], Vec3::new(1.0, 0.0, 10.0), 0.0);
    assert_eq!(s.materials[inner.material as usize], dielectric(1.5));
    assert!(inner.flip_normals && inner.area_light == Some(0));
    assert_vec(outer.positions[0], Vec3::X, 0.0);
    let want = diffuse(Vec3::new(0.1, 0.2, 0.3));
    assert_eq!(s.materials[outer.material as usize], want);
    assert!(!outer.flip_normals && outer.area_light.is_none());
    assert_eq!(s.lights.len(), 1);
}

#[test]
fn reverse_orientation_and_handedness_flip() {
    let n = r#""normal N" [ 0 0 1  0 0 1  0 0 1 ]"#;
    let s = ok(&format!(
        "WorldBegin\n{TRI}\nAttributeBegin\nReverseOrientation\n{TRI}\n\
         Shape \"trianglemesh\" \"point3 P\" [0 0 0 1 0 0 0 1 0] {n}\nAttributeEnd\n\
         AttributeBegin\nScale -1 1 1\n{TRI}\nReverseOrientation\n{TRI}\nAttributeEnd\n"
    ));
    let flips: Vec<bool> = s.meshes.iter().map(|m| m.flip_normals).collect();
    assert_eq!(flips, vec![false, true, true, true, false]);
    // The unit triangle's winding normal is (1,1,1)/sqrt 3; reversed it is the opposite.
    let g = |i: usize| s.meshes[i].geometric_normal(0, 0.3, 0.3);
    let k = 1.0 / 3f32.sqrt();
    assert_vec(g(0), Vec3::splat(k), 1e-6);
    assert_vec(g(1), Vec3::splat(-k), 1e-6);
    // Given normals are negated by ReverseOrientation (pbrt-v4's TriangleMesh).
    assert_vec(s.meshes[2].normals.as_ref().unwrap()[0], -Vec3::Z, 0.0);
    // Mirrored by Scale -1 1 1 the winding normal is (1,-1,-1)/sqrt 3; the handedness flip
    // turns it to (-1,1,1)/sqrt 3, the mirror image of the original normal.
    assert_vec(g(3), Vec3::new(-k, k, k), 1e-6);
    assert_vec(g(4), Vec3::new(k, -k, -k), 1e-6);
}

#[test]
fn normals_use_the_inverse_transpose() {
    // Plane x + y = 1 scaled by (1, 2, 1): its normal (1,1,0) becomes (1, 1/2, 0), normalised.
    let s = ok(r#"WorldBegin
Scale 1 2 1
Shape "trianglemesh" "point3 P" [ 1 0 0  0 1 0  0 1 1 ] "normal N" [ 1 1 0  1 1 0  1 1 0 ]
"#);
    let m = only_mesh(&s);
    let n = m.normals.as_ref().unwrap()[0];
    assert_vec(
        n,
        Vec3::new(2.0 / 5f32.sqrt(), 1.0 / 5f32.sqrt(), 0.0),
        1e-6,
    );
    // It is perpendicular to the transformed surface.
    assert!(n.dot(m.positions[1] - m.positions[0]).abs() < 1e-6);
    assert_eq!(m.indices, vec![[0, 1, 2]], "three points need no indices");
}

// ---------------------------------------------------------------------------------------------
// options

#[test]
fn options_and_defaults() {
    let s = ok("WorldBegin\n");
    assert_eq!(s.integrator.name, "default");
    assert!(s.integrator.params.is_empty() && s.integrator.loc.is_none());
    assert_eq!(
        (s.film.xres, s.film.yres, s.film.filename.clone()),
        (1280, 720, None)
    );
    assert_eq!(
        s.filter,
        FilterDesc::Gaussian {
            radius: Vec2::splat(1.5),
            sigma: 0.5
        }
    );
    assert_eq!(s.camera.fov_deg, 90.0);
    assert_eq!(s.camera.world_from_camera, Mat4::IDENTITY);
    assert_eq!(s.sampler.pixel_samples, 16);
    assert!(s.meshes.is_empty() && s.materials.is_empty() && s.lights.is_empty());

    let s = ok(
        r#"Sampler "stratified" "integer xsamples" 2 "integer ysamples" [ 3 ] "bool jitter" "false"
PixelFilter "gaussian" "float xradius" 2 "float sigma" 0.25
Film "rgb" "integer xresolution" 64 "string filename" "out.exr"
Camera "perspective" "float lensradius" 0
Integrator "photonmap" "integer photons" 1000 "float radius" 0.1
WorldBegin
"#,
    );
    assert_eq!(
        (s.sampler.name.as_str(), s.sampler.pixel_samples),
        ("stratified", 6)
    );
    assert_eq!(
        s.filter,
        FilterDesc::Gaussian {
            radius: Vec2::new(2.0, 1.5),
            sigma: 0.25
        }
    );
    assert_eq!((s.film.xres, s.film.yres), (64, 720));
    assert_eq!(s.film.filename.as_deref(), Some("out.exr"));
    assert_eq!(s.integrator.name, "photonmap");
    assert_eq!(s.integrator.loc.as_ref().unwrap().line, 5);
    let mut p = s.integrator.params.clone();
    assert_eq!(p.get_int("photons", 0).unwrap(), 1000);
    assert_eq!(p.get_float("radius", 0.0).unwrap(), 0.1);
    p.check_unused().unwrap();

    let s =
        ok("PixelFilter \"triangle\"\nSampler \"halton\" \"integer pixelsamples\" 7\nWorldBegin\n");
    assert_eq!(
        s.filter,
        FilterDesc::Triangle {
            radius: Vec2::splat(2.0)
        }
    );
    assert_eq!(
        (s.sampler.name.as_str(), s.sampler.pixel_samples),
        ("halton", 7)
    );
    let s = ok("PixelFilter \"box\" \"float yradius\" 1\nWorldBegin\n");
    assert_eq!(
        s.filter,
        FilterDesc::Box {
            radius: Vec2::new(0.5, 1.0)
        }
    );
}

// ---------------------------------------------------------------------------------------------
// materials

/// The material of the single shape of a world whose body is `body`.
fn material_of(body: &str) -> Material {
    let s = ok(&format!("WorldBegin\n{body}\n{TRI}\n"));
    s.materials[only_mesh(&s).material as usize].clone()
}

/// A diffuse material with a constant reflectance and no bump map.
fn diffuse(r: Vec3) -> Material {
    MaterialKind::Diffuse(DiffuseMaterial {
        reflectance: r.into(),
    })
    .into()
}

/// A smooth dielectric.
fn dielectric(eta: f32) -> Material {
    MaterialKind::Dielectric(DielectricMaterial {
        eta,
        // As a file without roughness says: 0, remapped (pbrt-v4's default).
        roughness: photon::material::Roughness {
            u: 0.0.into(),
            v: 0.0.into(),
            remap: true,
        },
    })
    .into()
}

/// A conductor's constant (eta, k, alpha_u, alpha_v), or `None` for another material; a
/// `reflectance` conductor reads as pbrt-v4 converts it (eta 1, k from r).
fn conductor(m: &Material) -> Option<(Vec3, Vec3, f32, f32)> {
    let MaterialKind::Conductor(ConductorMaterial { metal, roughness }) = &m.kind else {
        return None;
    };
    let (eta, k) = match metal {
        Metal::EtaK { eta, k } => (eta.constant()?, k.constant()?),
        Metal::Reflectance(r) => (Vec3::ONE, photon::bsdf::k_from_reflectance(r.constant()?)),
    };
    let (au, av) = roughness.constant()?;
    Some((eta, k, au, av))
}

#[test]
fn materials() {
    assert_eq!(material_of(""), diffuse(Vec3::splat(0.5)));
    assert_eq!(
        material_of(r#"Material "dielectric" "float eta" 1.33"#),
        dielectric(1.33)
    );
    assert_eq!(
        material_of(r#"Material "dielectric" "spectrum eta" [ 1.7 ] "float roughness" 0"#),
        dielectric(1.7)
    );
    assert_eq!(
        material_of(r#"Material "dielectric" "spectrum eta" [ 400 1.6 700 1.6 ]"#),
        dielectric(1.6)
    );
    // Default conductor: copper, smooth (the published RGB of pbrt's copper; ours are computed
    // from pbrt-v4's tables by the same method and agree to 1e-4).
    let Some((eta, k, 0.0, 0.0)) = conductor(&material_of(r#"Material "conductor""#)) else {
        panic!("not a smooth conductor")
    };
    assert_vec(eta, Vec3::new(0.200438, 0.924033, 1.102212), 3e-4);
    assert_vec(k, Vec3::new(3.912949, 2.452848, 2.142188), 3e-4);
    // Named glasses: the index at 550 nm (BK7: 1.51852 from Schott's Sellmeier fit).
    let MaterialKind::Dielectric(DielectricMaterial { eta, .. }) =
        material_of(r#"Material "dielectric" "spectrum eta" [ "glass-BK7" ]"#).kind
    else {
        panic!("not a dielectric")
    };
    assert!(close(eta, 1.51852, 1e-4), "{eta}");
    // reflectance 0.64: eta 1, k = 2 * 0.8 / 0.6; roughness 0.09 remapped to alpha 0.3.
    let Some((eta, k, alpha_u, alpha_v)) = conductor(&material_of(
        r#"Material "conductor" "rgb reflectance" [ 0.64 0 0.36 ] "float roughness" 0.09"#,
    )) else {
        panic!()
    };
    assert_eq!(eta, Vec3::ONE);
    assert_vec(k, Vec3::new(2.0 * 0.8 / 0.6, 0.0, 2.0 * 0.6 / 0.8), 1e-5);
    assert!(close(alpha_u, 0.3, 1e-6) && close(alpha_v, 0.3, 1e-6));
    // Anisotropic, not remapped; named gold spectra, with and without brackets (published
    // RGB of gold).
    for src in [
        r#""spectrum eta" "metal-Au-eta" "spectrum k" "metal-Au-k""#,
        r#""spectrum eta" [ "metal-Au-eta" ] "spectrum k" ["metal-Au-k"]"#,
    ] {
        let Some((eta, k, 0.2, 0.04)) = conductor(&material_of(&format!(
            r#"Material "conductor" {src}
               "float uroughness" 0.2 "float vroughness" 0.04 "bool remaproughness" false"#
        ))) else {
            panic!("not gold with alpha 0.2 x 0.04: {src}")
        };
        assert_vec(eta, Vec3::new(0.143119, 0.374957, 1.44248), 3e-4);
        assert_vec(k, Vec3::new(3.98316, 2.38572, 1.60322), 3e-4);
    }
    let Some((eta, k, alpha_u, alpha_v)) = conductor(&material_of(
        r#"Material "conductor" "spectrum eta" "metal-Al-eta" "rgb k" [1 2 3] "float uroughness" 0.25"#,
    )) else {
        panic!()
    };
    assert_vec(eta, Vec3::new(1.65746, 0.880369, 0.521229), 3e-4);
    assert_eq!(k, Vec3::new(1.0, 2.0, 3.0));
    assert!(close(alpha_u, 0.5, 1e-6) && alpha_v == 0.0);
    // Named materials keep their index; "color" is an alias of rgb.
    let s = ok(&format!(
        r#"WorldBegin
MakeNamedMaterial "a" "string type" "diffuse" "color reflectance" [ 0.2 0.2 0.2 ]
MakeNamedMaterial "b" "string type" "conductor" "spectrum eta" "metal-Ag-eta" "spectrum k" "metal-Ag-k"
NamedMaterial "b"
{TRI}
NamedMaterial "a"
{TRI}
Material "diffuse"
{TRI}
"#
    ));
    let mats: Vec<&Material> = s
        .meshes
        .iter()
        .map(|m| &s.materials[m.material as usize])
        .collect();
    assert!(
        matches!(conductor(mats[0]), Some((eta, ..)) if (eta - Vec3::new(0.155265, 0.116723, 0.138342)).abs().max_element() < 1e-4)
    );
    assert_eq!(*mats[1], diffuse(Vec3::splat(0.2)));
    assert_eq!(*mats[2], diffuse(Vec3::splat(0.5)));
    assert_eq!(
        s.materials.len(),
        3,
        "the default material is added only when used"
    );
}

// ---------------------------------------------------------------------------------------------
// lights

#[test]
fn point_spot_distant_lights() {
    let s = ok(r#"WorldBegin
Translate 1 0 0
LightSource "point" "point3 from" [ 1 2 3 ] "rgb I" [ 1 2 3 ] "float scale" 2
LightSource "point" "float power" 100
Identity
Rotate 90 0 0 1
LightSource "spot" "point3 from" [ 0 5 0 ] "point3 to" [ 0 0 0 ] "float coneangle" 30 "float conedeltaangle" 10
LightSource "spot" "float power" 10
Identity
LightSource "distant" "point3 from" [ 0 10 0 ] "point3 to" [ 0 0 0 ] "rgb L" [ 1 1 1 ] "float scale" 2
"#);
    assert_eq!(
        s.lights[0],
        Light::Point(photon::light::PointLight {
            pos: Vec3::new(2.0, 2.0, 3.0),
            intensity: Vec3::new(2.0, 4.0, 6.0)
        })
    );
    let Light::Point(photon::light::PointLight { pos, intensity }) = s.lights[1] else {
        panic!()
    };
    assert_eq!(pos, Vec3::X);
    assert_vec(intensity, Vec3::splat(100.0 / (4.0 * PI)), 1e-5);
    // R_z(90) maps (x, y) to (-y, x).
    let Light::Spot(photon::light::SpotLight {
        pos,
        dir,
        intensity,
        cos_falloff_start,
        cos_falloff_end,
    }) = s.lights[2]
    else {
        panic!()
    };
    assert_vec(pos, Vec3::new(-5.0, 0.0, 0.0), 1e-6);
    assert_vec(dir, Vec3::X, 1e-6);
    assert_eq!(intensity, Vec3::ONE);
    assert!(close(cos_falloff_end, 0.866_025_4, 1e-6));
    assert!(close(cos_falloff_start, 0.939_692_6, 1e-6));
    // Defaults 30 / 5 degrees; power 10 over pbrt-v4's k_e = 2 pi (1 - (cs + ce) / 2).
    let Light::Spot(photon::light::SpotLight {
        dir,
        intensity,
        cos_falloff_start,
        cos_falloff_end,
        ..
    }) = s.lights[3]
    else {
        panic!()
    };
    assert_vec(dir, Vec3::Z, 1e-6); // (0,0,1) is not moved by R_z
    let (cs, ce) = (25f32.to_radians().cos(), 30f32.to_radians().cos());
    assert!(close(cos_falloff_start, cs, 1e-6) && close(cos_falloff_end, ce, 1e-6));
    let k = 10.0 / (2.0 * PI * (1.0 - 0.5 * (cs + ce)));
    assert_vec(intensity, Vec3::splat(k), 1e-3);
    assert_eq!(
        s.lights[4],
        Light::Distant(photon::light::DistantLight {
            dir: -Vec3::Y,
            l: Vec3::splat(2.0)
        })
    );
}

#[test]
fn area_lights() {
    let quad = r#"Shape "trianglemesh" "point3 P" [ 0 0 0 2 0 0 2 1 0 0 1 0 ] "integer indices" [ 0 1 2 0 2 3 ]"#;
    let s = ok(&format!(
        r#"WorldBegin
AttributeBegin
AreaLightSource "diffuse" "rgb L" [ 1 2 3 ] "float scale" 3 "bool twosided" true
{quad}
{quad}
AttributeEnd
{quad}
AttributeBegin
AreaLightSource "diffuse" "float power" 10 "bool twosided" true
{quad}
AttributeEnd
AttributeBegin
AreaLightSource "diffuse" "float power" 10
Scale 2 2 2
Shape "sphere" "float radius" 0.5
AttributeEnd
"#
    ));
    assert_eq!(s.lights.len(), 4);
    assert_eq!(s.meshes.len(), 5);
    for (i, light) in s.lights.iter().enumerate() {
        let Light::Area { mesh, .. } = light else {
            panic!()
        };
        assert_eq!(s.meshes[*mesh as usize].area_light, Some(i as u32));
    }
    assert_eq!(
        s.lights[0],
        Light::Area {
            mesh: 0,
            l: Vec3::new(3.0, 6.0, 9.0),
            two_sided: true
        }
    );
    assert!(matches!(s.lights[1], Light::Area { mesh: 1, .. }));
    assert!(s.meshes[2].area_light.is_none());
    // power 10 over a two-sided 2 x 1 quad: L = 10 / (pi * 2 * 2).
    let Light::Area {
        mesh: 3,
        l,
        two_sided: true,
    } = s.lights[2]
    else {
        panic!()
    };
    assert_vec(l, Vec3::splat(10.0 / (4.0 * PI)), 1e-5);
    // power 10 over a one-sided sphere of world radius 1: L = 10 / (pi * 4 pi).
    let Light::Area {
        mesh: 4,
        l,
        two_sided: false,
    } = s.lights[3]
    else {
        panic!()
    };
    assert_vec(l, Vec3::splat(10.0 / (4.0 * PI * PI)), 1e-5);
}

// ---------------------------------------------------------------------------------------------
// shapes

#[test]
fn spheres() {
    let s = ok(r#"WorldBegin
AttributeBegin
Translate 1 2 3
Scale 2 2 2
Rotate 30 1 0 0
Shape "sphere" "float radius" 0.5 "float zmin" -0.5 "float phimax" 360
AttributeEnd
AttributeBegin
ReverseOrientation
Shape "sphere"
AttributeEnd
AttributeBegin
Scale -1 1 1
Shape "sphere"
AttributeEnd
"#);
    for (i, m) in s.meshes.iter().enumerate() {
        let (c, r) = m.sphere.unwrap();
        if i == 0 {
            assert_vec(c, Vec3::new(1.0, 2.0, 3.0), 1e-6);
            assert!(close(r, 1.0, 1e-6));
        } else {
            assert_eq!((c, r), (Vec3::ZERO, 1.0));
        }
        let inward = i == 1;
        assert_eq!(m.flip_normals, inward);
        let normals = m.normals.as_ref().unwrap();
        for (p, n) in m.positions.iter().zip(normals) {
            assert!(((*p - c).length() - r).abs() < 1e-5);
            let out = (*p - c) / r;
            assert_vec(*n, if inward { -out } else { out }, 1e-5);
        }
        for t in 0..m.indices.len() as u32 {
            // Winding normal agrees with the shading normals' side.
            let [p0, p1, p2] = m.triangle(t);
            let w = (p1 - p0).cross(p2 - p0);
            assert!(
                w.dot(p0 + p1 + p2 - 3.0 * c) > 0.0,
                "mesh {i} triangle {t} winds inward"
            );
            let g = m.geometric_normal(t, 0.3, 0.3);
            assert_eq!(g.dot(p0 - c) > 0.0, !inward);
        }
        assert_eq!(m.uvs.as_ref().map(|u| u.len()), Some(m.positions.len()));
    }
}

/// An ASCII PLY with one quad (split in two), normals and (s, t) coordinates.
const ASCII_PLY: &str = "ply
format ascii 1.0
comment a unit quad
element vertex 4
property float x
property float y
property float z
property float nx
property float ny
property float nz
property float s
property float t
element face 1
property list uchar int vertex_indices
end_header
0 0 0 0 0 1 0 0
1 0 0 0 0 1 1 0
1 1 0 0 0 1 1 1
0 1 0 0 0 1 0 1
4 0 1 2 3
";

/// A binary PLY: `n` vertices (x y z as f64) and triangle faces with the given index type.
fn binary_ply(big_endian: bool, verts: &[[f64; 3]], faces: &[Vec<u16>]) -> Vec<u8> {
    let fmt = if big_endian {
        "binary_big_endian"
    } else {
        "binary_little_endian"
    };
    let mut out = format!(
        "ply\nformat {fmt} 1.0\nelement vertex {}\nproperty double x\nproperty double y\n\
         property double z\nproperty uchar red\nelement face {}\n\
         property list uchar ushort vertex_indices\nend_header\n",
        verts.len(),
        faces.len()
    )
    .into_bytes();
    for v in verts {
        for c in v {
            out.extend(if big_endian {
                c.to_be_bytes()
            } else {
                c.to_le_bytes()
            });
        }
        out.push(200);
    }
    for f in faces {
        out.push(f.len() as u8);
        for i in f {
            out.extend(if big_endian {
                i.to_be_bytes()
            } else {
                i.to_le_bytes()
            });
        }
    }
    out
}

#[test]
fn ply_meshes() {
    let dir = TempDir::new("photon-parser");
    dir.write("meshes/quad.ply", ASCII_PLY);
    let verts = [
        [0.0, 0.0, 0.0],
        [1.0, 0.0, 0.0],
        [0.0, 1.0, 0.0],
        [0.0, 0.0, 1.0],
    ];
    let faces = vec![vec![0, 1, 2], vec![0, 2, 3], vec![1, 2, 3, 0]];
    dir.write("be.ply", binary_ply(true, &verts, &faces));
    dir.write("le.ply", binary_ply(false, &verts, &faces));
    let scene = dir.write(
        "scene.pbrt",
        r#"WorldBegin
Translate 0 0 5
Shape "plymesh" "string filename" "meshes/quad.ply"
Shape "plymesh" "string filename" "be.ply"
Shape "plymesh" "string filename" "le.ply"
"#,
    );
    let s = load(&scene).unwrap_or_else(|e| panic!("{e}"));
    let q = &s.meshes[0];
    assert_eq!(q.indices, vec![[0, 1, 2], [0, 2, 3]]);
    assert_vec(q.positions[2], Vec3::new(1.0, 1.0, 5.0), 0.0);
    assert_eq!(q.normals.as_ref().unwrap()[3], Vec3::Z);
    assert_eq!(q.uvs.as_ref().unwrap()[2], Vec2::new(1.0, 1.0));
    for m in &s.meshes[1..] {
        assert_eq!(m.indices, vec![[0, 1, 2], [0, 2, 3], [1, 2, 3], [1, 3, 0]]);
        assert_vec(m.positions[3], Vec3::new(0.0, 0.0, 6.0), 0.0);
        assert!(m.normals.is_none() && m.uvs.is_none());
    }
}

// ---------------------------------------------------------------------------------------------
// syntax

#[test]
fn syntax_details() {
    // Comments, bare and quoted bools, single values without brackets, strings with escapes,
    // include and import relative to the main file's directory (also from a subdirectory).
    let dir = TempDir::new("photon-parser");
    dir.write(
        "sub/a.pbrt",
        "# included\nMakeNamedMaterial \"m\" \"string type\" \"diffuse\"\nImport \"sub/b.pbrt\"\n",
    );
    dir.write("sub/b.pbrt", format!("NamedMaterial \"m\"\n{TRI}\n"));
    let scene = dir.write(
        "scene.pbrt",
        format!(
            "Film \"rgb\" \"string filename\" \"a\\\"b.exr\" # comment \"not a string\n\
         WorldBegin # ok\nInclude \"sub/a.pbrt\"\n\
         AreaLightSource \"diffuse\" \"bool twosided\" true\n\
         Shape \"trianglemesh\" \"point P\" [1 0 0 0 1 0 0 0 1]\n\
         AreaLightSource \"diffuse\" \"bool twosided\" [ \"false\" ]\n{TRI}\n"
        ),
    );
    let s = load(&scene).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(s.film.filename.as_deref(), Some("a\"b.exr"));
    assert_eq!(s.meshes.len(), 3);
    assert_eq!(
        s.materials[s.meshes[0].material as usize],
        diffuse(Vec3::splat(0.5))
    );
    assert!(matches!(
        s.lights[0],
        Light::Area {
            two_sided: true,
            ..
        }
    ));
    assert!(matches!(
        s.lights[1],
        Light::Area {
            two_sided: false,
            ..
        }
    ));
    assert_eq!(s.path, scene);
}

// ---------------------------------------------------------------------------------------------
// errors

#[test]
fn error_unknown_and_unsupported_directives() {
    assert_src_err(
        "WorldBegin\n\n  Shap \"sphere\"\n",
        3,
        &["unknown directive \"Shap\""],
    );
    assert_src_err(
        "WorldBegin\nTexture \"t\" \"spectrum\" \"imagemap\"\n",
        2,
        &["imagemap needs \"string filename\""],
    );
    assert_src_err(
        "WorldBegin\nAttribute \"shape\" \"float radius\" 2\n",
        2,
        &["unsupported directive \"Attribute\""],
    );
    assert_src_err("WorldBegin\nWorldEnd\n", 2, &["\"WorldEnd\""]);
    assert_src_err(
        "WorldBegin\nShape \"hyperboloid\"\n",
        2,
        &["unsupported shape type \"hyperboloid\""],
    );
    assert_src_err(
        "WorldBegin\nMaterial \"hair\"\n",
        2,
        &["unsupported material type \"hair\""],
    );
    assert_src_err(
        "WorldBegin\nMakeNamedMaterial \"x\"\n \"string type\" \"interface\"\n",
        3,
        &["\"interface\""],
    );
    assert_src_err(
        "WorldBegin\nLightSource \"goniometric\"\n",
        2,
        &["unsupported light type \"goniometric\""],
    );
    assert_src_err("WorldBegin\nAreaLightSource \"spot\"\n", 2, &["\"spot\""]);
    assert_src_err(
        "Camera \"orthographic\"\nWorldBegin\n",
        1,
        &["\"orthographic\""],
    );
    assert_src_err("Film \"spectral\"\nWorldBegin\n", 1, &["\"spectral\""]);
    assert_src_err(
        "PixelFilter \"mitchell\"\nWorldBegin\n",
        1,
        &["\"mitchell\""],
    );
    assert_src_err("Sampler \"magic\"\nWorldBegin\n", 1, &["\"magic\""]);
    assert_src_err("WorldBegin\n[ 1 ]\n", 2, &["expected a directive"]);
    assert_src_err(
        "Shape \"sphere\"\nWorldBegin\n",
        1,
        &["only allowed after WorldBegin"],
    );
    assert_src_err(
        "WorldBegin\nCamera \"perspective\"\n",
        2,
        &["not allowed after WorldBegin"],
    );
    assert_src_err("WorldBegin\nWorldBegin\n", 2, &["WorldBegin given twice"]);
    assert_src_err("Camera \"perspective\"\n", 2, &["no WorldBegin"]);
}

#[test]
fn error_parameter_types_and_values() {
    assert_src_err(
        "Camera \"perspective\"\n    \"integer fov\" 30\nWorldBegin\n",
        2,
        &["\"integer fov\"", "expected float"],
    );
    assert_src_err(
        "WorldBegin\nMaterial \"diffuse\"\n  \"rgb reflectance\" [ 0.5 0.5 ]\n",
        3,
        &["\"rgb reflectance\"", "expected 3 numbers, got 2"],
    );
    assert_src_err(
        "WorldBegin\nMaterial \"diffuse\" \"texture reflectance\" \"t\"\n",
        2,
        &["\"texture reflectance\"", "unknown spectrum texture \"t\""],
    );
    assert_src_err(
        "WorldBegin\nLightSource \"point\"\n \"blackbody I\" 0\n",
        3,
        &["blackbody", "temperature"],
    );
    assert_src_err(
        "WorldBegin\nMaterial \"diffuse\" \"rgb reflectance\" [ 1.5 0 0 ]\n",
        2,
        &["[0, 1]"],
    );
    assert_src_err(
        "Film \"rgb\"\n \"integer xresolution\" [ 1.5 ]\nWorldBegin\n",
        2,
        &["expected an integer, found number 1.5"],
    );
    assert_src_err(
        "Film \"rgb\" \"integer xresolution\" [ 0 ]\nWorldBegin\n",
        1,
        &["must be positive"],
    );
    assert_src_err(
        "WorldBegin\nMaterial \"diffuse\" \"colour reflectance\" [ 1 1 1 ]\n",
        2,
        &["unknown parameter type \"colour\""],
    );
    assert_src_err(
        "WorldBegin\nMaterial \"diffuse\" \"reflectance\" [ 1 1 1 ]\n",
        2,
        &["\"type name\""],
    );
    assert_src_err(
        "WorldBegin\nLightSource \"point\" \"float scale\" 1\n\"float scale\" 2\n",
        3,
        &["given twice"],
    );
    assert_src_err(
        "WorldBegin\nLightSource \"point\" \"bool x\" maybe\n",
        2,
        &["true or false"],
    );
    assert_src_err(
        "WorldBegin\nLightSource \"point\" \"float scale\" [ 1 [ 2 ] ]\n",
        2,
        &["\"[\" inside"],
    );
    assert_src_err(
        "WorldBegin\nLightSource \"point\"\n \"float scale\" [ 1 2\n",
        4,
        &["unexpected end of file"],
    );
    assert_src_err(
        "WorldBegin\nTranslate 1 2\n",
        3,
        &["unexpected end of file", "number"],
    );
    assert_src_err("WorldBegin\nTranslate 1 x 2\n", 2, &["expected a number"]);
    assert_src_err(
        "WorldBegin\nTransform [ 1 0 0 ]\n",
        2,
        &["expected a number, found \"]\""],
    );
    assert_src_err("WorldBegin\nRotate 10 0 0 0\n", 2, &["zero axis"]);
    assert_src_err("LookAt 0 0 0 0 0 1 0 0 1\nWorldBegin\n", 1, &["up vector"]);
    assert_src_err(
        "WorldBegin\nLightSource \"distant\" \"float illuminance\" 3\n",
        2,
        &["\"illuminance\""],
    );
    assert_src_err(
        "Camera \"perspective\"\n \"float lensradius\" -0.1\nWorldBegin\n",
        2,
        &["\"float lensradius\"", "must lie in [0, "],
    );
    assert_src_err(
        "WorldBegin\nMaterial \"dielectric\"\n \"float roughness\" -0.1\n",
        3,
        &["roughness must be finite and not negative"],
    );
    assert_src_err(
        "WorldBegin\nMaterial \"dielectric\"\n \"spectrum eta\" \"glass-XYZ\"\n",
        3,
        &["glass-XYZ"],
    );
    assert_src_err(
        "WorldBegin\nMaterial \"conductor\"\n \"spectrum eta\" \"metal-Pt-eta\"\n",
        3,
        &["metal-Pt-eta"],
    );
    assert_src_err(
        "WorldBegin\nMaterial \"conductor\" \"rgb reflectance\" [1 1 1]\n \"rgb k\" [1 1 1]\n",
        3,
        &["not both"],
    );
    assert_src_err(
        "WorldBegin\nMakeNamedMaterial \"x\" \"rgb reflectance\" [1 1 1]\n",
        2,
        &["\"string type\""],
    );
    assert_src_err("WorldBegin\nMakeNamedMaterial \"x\" \"string type\" \"diffuse\"\nMakeNamedMaterial \"x\" \"string type\" \"diffuse\"\n", 3, &["redefined"]);
    assert_src_err(
        "WorldBegin\nCoordSysTransform \"nowhere\"\n",
        2,
        &["unknown coordinate system \"nowhere\""],
    );
}

#[test]
fn error_unused_parameters() {
    assert_src_err(
        "WorldBegin\nLightSource \"point\"\n  \"rgb I\" [ 1 1 1 ]\n  \"float foo\" 1\n",
        4,
        &["unused parameter \"float foo\""],
    );
    assert_src_err(
        "Camera \"perspective\" \"float aperturediameter\" [ 1 ]\nWorldBegin\n",
        1,
        &["unused parameter \"float aperturediameter\""],
    );
    // pbrt-v3's Film "scale" is not a pbrt-v4 parameter (pbrt-v4 reports it unused too).
    assert_src_err(
        "Film \"rgb\"\n\"float scale\" 2\nWorldBegin\n",
        2,
        &["unused parameter \"float scale\""],
    );
    assert_src_err(
        "Sampler \"stratified\" \"integer pixelsamples\" 4\nWorldBegin\n",
        1,
        &["unused parameter \"integer pixelsamples\""],
    );
    assert_src_err(
        "PixelFilter \"box\" \"float sigma\" 1\nWorldBegin\n",
        1,
        &["unused parameter \"float sigma\""],
    );
    assert_src_err(
        "WorldBegin\nMaterial \"diffuse\" \"texture normalmap\" \"n\"\n",
        2,
        &["\"texture normalmap\": a texture is not supported for this parameter"],
    );
    assert_src_err("WorldBegin\nMaterial \"conductor\" \"float uroughness\" 0.1 \"float vroughness\" 0.1\n \"float roughness\" 0.2\n", 3, &["unused parameter \"float roughness\""]);
    // (`alpha` is read since shapes take it; a sphere's `radius` is not a mesh's.)
    assert_src_err(
        &format!("WorldBegin\n{TRI}\n  \"float radius\" 0.5\n"),
        3,
        &["unused parameter \"float radius\""],
    );
    assert_src_err(
        "WorldBegin\nShape \"sphere\" \"float radius\" 1\n \"float zmax\" 0.5\n",
        3,
        &["partial spheres"],
    );
    assert_src_err(
        "WorldBegin\nAreaLightSource \"diffuse\" \"string filename\" \"x.exr\"\n",
        2,
        &["unused parameter \"string filename\""],
    );
    assert_src_err("WorldBegin\nShape \"plymesh\" \"string filename\" \"x.ply\"\n\"texture displacement\" \"d\"\n", 3, &["\"texture displacement\": a texture is not supported for this parameter"]);
}

#[test]
fn error_named_material_and_blocks() {
    assert_src_err(
        "WorldBegin\nMakeNamedMaterial \"a\" \"string type\" \"diffuse\"\n\nNamedMaterial \"b\"\n",
        4,
        &["unknown named material \"b\""],
    );
    assert_src_err(
        "WorldBegin\nAttributeBegin\nAttributeEnd\nAttributeEnd\n",
        4,
        &["AttributeEnd without AttributeBegin"],
    );
    assert_src_err(
        "TransformEnd\nWorldBegin\n",
        1,
        &["TransformEnd without TransformBegin"],
    );
    assert_src_err(
        "WorldBegin\nAttributeBegin\nTransformBegin\nAttributeEnd\n",
        4,
        &["does not match the block opened at line 3"],
    );
    assert_src_err(
        "WorldBegin\nShape \"sphere\"\nAttributeBegin\n",
        3,
        &["AttributeBegin without a matching AttributeEnd"],
    );
}

#[test]
fn error_shapes() {
    assert_src_err(
        "WorldBegin\nShape \"trianglemesh\" \"point3 P\" [ 0 0 0 1 0 0 0 1 0 ]\n  \"integer indices\" [ 0 1 5 ]\n",
        3,
        &["\"integer indices\"", "index 5", "out of range"],
    );
    assert_src_err("WorldBegin\nShape \"trianglemesh\" \"point3 P\" [ 0 0 0 1 0 0 0 1 0 ]\n \"integer indices\" [ 0 -1 2 ]\n", 3, &["index -1"]);
    assert_src_err("WorldBegin\nShape \"trianglemesh\" \"point3 P\" [ 0 0 0 1 0 0 0 1 0 ]\n \"integer indices\" [ 0 1 ]\n", 3, &["multiple of 3"]);
    assert_src_err(
        "WorldBegin\nShape \"trianglemesh\"\n \"point3 P\" [ 0 0 0 1 0 0 0 1 0 0 ]\n",
        3,
        &["multiple of 3"],
    );
    assert_src_err(
        "WorldBegin\nShape \"trianglemesh\" \"point3 P\" [ 0 0 0 1 0 0 0 1 0 1 1 1 ]\n",
        2,
        &["\"integer indices\""],
    );
    assert_src_err(
        "WorldBegin\nShape \"trianglemesh\" \"integer indices\" [ 0 1 2 ]\n",
        2,
        &["\"point3 P\""],
    );
    assert_src_err("WorldBegin\nShape \"trianglemesh\" \"point3 P\" [ 0 0 0 1 0 0 0 1 0 ]\n \"normal N\" [ 0 0 1 ]\n", 3, &["1 values given for 3 points"]);
    assert_src_err("WorldBegin\nShape \"trianglemesh\" \"point3 P\" [ 0 0 0 1 0 0 0 1 0 ]\n \"point2 uv\" [ 0 0 1 0 1 ]\n", 3, &["multiple of 2"]);
    assert_src_err("WorldBegin\nShape \"trianglemesh\" \"point3 P\" [ 0 0 0 1 0 0 0 1 0 ]\n \"normal P\" [ 0 0 1 ]\n", 3, &["given twice"]);
    assert_src_err(
        "WorldBegin\nScale 1 2 1\nShape \"sphere\"\n",
        3,
        &["similarity"],
    );
    assert_src_err("WorldBegin\nAreaLightSource \"diffuse\" \"float power\" 1\nShape \"trianglemesh\" \"point3 P\" [ 0 0 0 1 0 0 2 0 0 ]\n", 3, &["zero area"]);
}

#[test]
fn error_unterminated_string() {
    let r = load_src("WorldBegin\nMaterial \"diffuse\"\n  Shape \"trianglemesh\n");
    assert_err(r, "scene.pbrt", 3, &["unterminated string"]);
    let e = load_src("WorldBegin\nNamedMaterial \"abc").unwrap_err();
    assert_eq!(
        (e.loc.as_ref().unwrap().line, e.loc.as_ref().unwrap().col),
        (2, 15)
    );
    assert!(e.msg.contains("unterminated string"));
}

#[test]
fn error_includes() {
    let dir = TempDir::new("photon-parser");
    let main = dir.write("scene.pbrt", "WorldBegin\n\nInclude \"missing.pbrt\"\n");
    assert_err(
        load(&main),
        "scene.pbrt",
        3,
        &["missing.pbrt", "cannot read"],
    );
    // An error inside an included file names that file and its line.
    dir.write(
        "parts/inc.pbrt",
        "# part\nAttributeBegin\n  Shape \"cone\"\nAttributeEnd\n",
    );
    let main = dir.write("scene2.pbrt", "WorldBegin\nInclude \"parts/inc.pbrt\"\n");
    assert_err(
        load(&main),
        "parts/inc.pbrt",
        3,
        &["unsupported shape type \"cone\""],
    );
    // A cycle stops at the depth limit, at an Include line.
    let main = dir.write("loop.pbrt", "WorldBegin\nImport \"loop2.pbrt\"\n");
    dir.write("loop2.pbrt", "\nInclude \"loop3.pbrt\"\n");
    dir.write("loop3.pbrt", "Include \"loop2.pbrt\"\n");
    let e = load(&main).unwrap_err();
    assert!(e.msg.contains("nested more than"), "{e}");
    // A missing main file is an error (without a line).
    assert!(load(&dir.0.join("nope.pbrt"))
        .unwrap_err()
        .msg
        .contains("nope.pbrt"));
}

/// A scene with one plymesh named `file` on line 3.
fn ply_scene(dir: &TempDir, file: &str) -> PathBuf {
    dir.write(
        "scene.pbrt",
        format!(
            "WorldBegin\nMaterial \"diffuse\"\nShape \"plymesh\" \"string filename\" \"{file}\"\n"
        ),
    )
}

#[test]
fn error_ply_files() {
    let dir = TempDir::new("photon-parser");
    let scene = ply_scene(&dir, "none.ply");
    assert_err(load(&scene), "scene.pbrt", 3, &["none.ply", "cannot open"]);

    // Truncated binary: every cut inside the payload is an error naming the file, no panic.
    let verts = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]];
    let full = binary_ply(false, &verts, &[vec![0, 1, 2]]);
    let header_len = full.windows(11).position(|w| w == b"end_header\n").unwrap() + 11;
    for cut in header_len..full.len() {
        dir.write("cut.ply", &full[..cut]);
        let scene = ply_scene(&dir, "cut.ply");
        assert_err(load(&scene), "scene.pbrt", 3, &["cut.ply", "truncated"]);
    }
    // and every cut inside the header is an error too.
    for cut in 0..header_len {
        dir.write("cut.ply", &full[..cut]);
        assert_err(
            load(&ply_scene(&dir, "cut.ply")),
            "scene.pbrt",
            3,
            &["cut.ply"],
        );
    }

    dir.write(
        "hdr.ply",
        "ply\nformat ascii 1.0\nelement vertex 1\nproperty floot x\nend_header\n0\n",
    );
    assert_err(
        load(&ply_scene(&dir, "hdr.ply")),
        "scene.pbrt",
        3,
        &["hdr.ply", "malformed header"],
    );
    dir.write(
        "bad.ply",
        ASCII_PLY.replace("1 1 0 0 0 1 1 1", "1 1 0 0 0 1 x 1"),
    );
    assert_err(
        load(&ply_scene(&dir, "bad.ply")),
        "scene.pbrt",
        3,
        &["bad.ply", "malformed"],
    );
    dir.write("range.ply", ASCII_PLY.replace("4 0 1 2 3", "4 0 1 2 4"));
    assert_err(
        load(&ply_scene(&dir, "range.ply")),
        "scene.pbrt",
        3,
        &["range.ply", "index 4 out of range"],
    );
    dir.write("penta.ply", ASCII_PLY.replace("4 0 1 2 3", "5 0 1 2 3 0"));
    assert_err(
        load(&ply_scene(&dir, "penta.ply")),
        "scene.pbrt",
        3,
        &["penta.ply", "5 vertices"],
    );
    dir.write("noface.ply", "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\nproperty float z\nend_header\n0 0 0\n");
    assert_err(
        load(&ply_scene(&dir, "noface.ply")),
        "scene.pbrt",
        3,
        &["noface.ply", "face"],
    );
    let huge = "ply\nformat binary_little_endian 1.0\nelement vertex 4000000000\nproperty float x\nproperty float y\nproperty float z\nend_header\n\0\0";
    dir.write("huge.ply", huge);
    assert_err(
        load(&ply_scene(&dir, "huge.ply")),
        "scene.pbrt",
        3,
        &["huge.ply", "truncated"],
    );
}

// ---------------------------------------------------------------------------------------------
// robustness

#[test]
fn never_panics_on_cut_or_mangled_input() {
    let text = std::fs::read(shared("cornell-box/scene-v4.pbrt")).unwrap();
    let dir = TempDir::new("photon-parser");
    let path = dir.0.join("fuzz.pbrt");
    let mut loaded = 0;
    for cut in (0..text.len()).step_by(37) {
        std::fs::write(&path, &text[..cut]).unwrap();
        if load(&path).is_ok() {
            loaded += 1;
        }
    }
    // A simple LCG flips bytes to characters that matter to the syntax.
    let mut state = 12345u64;
    let specials = b"[]\"#\n -.e0x";
    for _ in 0..300 {
        let mut t = text.clone();
        for _ in 0..3 {
            state = state
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            let at = (state >> 33) as usize % t.len();
            t[at] = specials[(state >> 20) as usize % specials.len()];
        }
        std::fs::write(&path, &t).unwrap();
        let _ = load(&path);
    }
    // Files cut before WorldBegin fail; the complete file loads.
    assert!(loaded < text.len() / 37);
    std::fs::write(&path, &text).unwrap();
    assert!(load(&path).is_ok());
}

#[test]
fn multi_megabyte_scene_loads() {
    // 200k points (about 7 MB of text), with comments and line breaks inside the lists.
    let n = 200_000usize;
    let mut src = String::from("WorldBegin\nShape \"trianglemesh\" \"point3 P\" [\n");
    for i in 0..n {
        let v = i as f32 * 0.25;
        src.push_str(&format!("{v} {} -{v} # point {i}\n", i % 7));
    }
    src.push_str("] \"integer indices\" [\n");
    for i in 0..n - 2 {
        src.push_str(&format!("{i} {} {}\n", i + 1, i + 2));
    }
    src.push_str("]\n");
    let dir = TempDir::new("photon-parser");
    let path = dir.write("big.pbrt", &src);
    let t = std::time::Instant::now();
    let s = load(&path).unwrap_or_else(|e| panic!("{e}"));
    let secs = t.elapsed().as_secs_f64();
    println!(
        "{:.1} MB loaded in {:.1} ms ({:.0} MB/s)",
        src.len() as f64 / 1e6,
        secs * 1e3,
        src.len() as f64 / 1e6 / secs
    );
    let m = only_mesh(&s);
    assert_eq!(m.indices.len(), n - 2);
    assert_eq!(m.indices[1234], [1234, 1235, 1236]);
    assert_eq!(m.positions[1001], Vec3::new(250.25, 0.0, -250.25));
}

#[test]
fn param_set_is_clone_debug_send_sync() {
    fn check<T: Clone + std::fmt::Debug + Send + Sync>() {}
    check::<photon::scene::ParamSet>();
    check::<Scene>();
}

#[test]
fn repo_scenes_load() {
    let mut n = 0;
    for entry in std::fs::read_dir("scenes").unwrap() {
        let path = entry.unwrap().path();
        if path.extension().is_some_and(|e| e == "pbrt") {
            let s = load(&path).unwrap_or_else(|e| panic!("{e}"));
            assert!(
                s.triangle_count() > 0 && !s.lights.is_empty(),
                "{}",
                path.display()
            );
            n += 1;
        }
    }
    assert!(n > 0, "no scenes in scenes/");
}

// ---------------------------------------------------------------------------------------------
// disks and cylinders (analytic area, bounds and normals)

/// Total triangle area and bounds of the only mesh.
fn area_and_bounds(s: &Scene) -> (f64, Vec3, Vec3) {
    let m = only_mesh(s);
    let area = (0..m.indices.len() as u32).map(|t| m.area(t) as f64).sum();
    let (lo, hi) = s.bounds();
    (area, lo, hi)
}

/// `area` is short of `exact` by less than 0.1% (a polygon inscribed in the curve).
#[track_caller]
fn assert_area(area: f64, exact: f64) {
    let deficit = 1.0 - area / exact;
    assert!(
        (0.0..1e-3).contains(&deficit),
        "area {area} against {exact}"
    );
}

#[test]
fn disk_area_bounds_and_normals() {
    // Annulus r 2, inner 0.5 at height 1, moved up 3: area pi (4 - 0.25).
    let s = ok(r#"WorldBegin
Translate 0 0 3
Shape "disk" "float radius" 2 "float innerradius" 0.5 "float height" 1"#);
    let (area, lo, hi) = area_and_bounds(&s);
    assert_area(area, std::f64::consts::PI * 3.75);
    assert_vec(lo, Vec3::new(-2.0, -2.0, 4.0), 1e-5);
    assert_vec(hi, Vec3::new(2.0, 2.0, 4.0), 1e-5);
    let m = only_mesh(&s);
    for (i, p) in m.positions.iter().enumerate() {
        let r = p.truncate().length();
        assert!(
            close(r, 2.0, 1e-6) || close(r, 0.5, 1e-6),
            "vertex {i} at r {r}"
        );
        assert_eq!(m.normals.as_ref().unwrap()[i], Vec3::Z);
    }
    for t in 0..m.indices.len() as u32 {
        assert_vec(m.geometric_normal(t, 0.3, 0.3), Vec3::Z, 1e-5);
    }
    // pbrt's uv: u = phi / phimax, v = (radius - r) / (radius - innerradius).
    let uv = m.uvs.as_ref().unwrap();
    for (p, uv) in m.positions.iter().zip(uv) {
        let v = (2.0 - p.truncate().length()) / 1.5;
        assert!(close(uv.y, v, 1e-5), "{uv} at {p}");
        let phi = p.y.atan2(p.x).rem_euclid(2.0 * PI);
        assert!(close(uv.x, phi / (2.0 * PI), 1e-5) || (uv.x == 1.0 && phi < 1e-5));
    }
    // A quarter disk without a hole, its normal turned by ReverseOrientation.
    let s = ok(r#"WorldBegin
ReverseOrientation
Shape "disk" "float radius" 3 "float phimax" 90"#);
    let (area, lo, hi) = area_and_bounds(&s);
    assert_area(area, std::f64::consts::PI * 9.0 / 4.0);
    assert_vec(lo, Vec3::ZERO, 1e-6);
    assert_vec(hi, Vec3::new(3.0, 3.0, 0.0), 1e-5);
    let m = only_mesh(&s);
    assert!(m.normals.as_ref().unwrap().iter().all(|n| *n == -Vec3::Z));
    assert_vec(m.geometric_normal(0, 0.2, 0.2), -Vec3::Z, 1e-6);
}

#[test]
fn cylinder_area_bounds_and_normals() {
    // Half a cylinder, zmin/zmax given the wrong way round (pbrt orders them), rotated so the
    // axis is +x: area = height * radius * phimax = 3 * 0.5 * pi.
    let s = ok(r#"WorldBegin
Rotate 90 0 1 0
Shape "cylinder" "float radius" 0.5 "float zmin" 2 "float zmax" -1 "float phimax" 180"#);
    let (area, lo, hi) = area_and_bounds(&s);
    assert_area(area, 1.5 * std::f64::consts::PI);
    // Object (x, y, z) -> world (z, y, -x): x in [-1, 2], y in [0, 0.5], z in [-0.5, 0.5].
    assert_vec(lo, Vec3::new(-1.0, 0.0, -0.5), 1e-5);
    assert_vec(hi, Vec3::new(2.0, 0.5, 0.5), 1e-5);
    let m = only_mesh(&s);
    for (p, n) in m.positions.iter().zip(m.normals.as_ref().unwrap()) {
        let radial = Vec3::new(0.0, p.y, p.z);
        assert!(close(radial.length(), 0.5, 1e-6), "{p}");
        assert_vec(*n, radial / 0.5, 1e-5);
    }
    for t in 0..m.indices.len() as u32 {
        let c = m.point(t, 1.0 / 3.0, 1.0 / 3.0);
        let outward = Vec3::new(0.0, c.y, c.z).normalize();
        assert!(m.geometric_normal(t, 1.0 / 3.0, 1.0 / 3.0).dot(outward) > 0.99);
    }
    // The full default cylinder closes its seam exactly: 2 pi r h = 4 pi.
    let s = ok("WorldBegin\nShape \"cylinder\"");
    let (area, lo, hi) = area_and_bounds(&s);
    assert_area(area, 4.0 * std::f64::consts::PI);
    assert_vec(lo, Vec3::new(-1.0, -1.0, -1.0), 1e-5);
    assert_vec(hi, Vec3::new(1.0, 1.0, 1.0), 1e-5);
    let m = only_mesh(&s);
    let ring = m.positions.len() / 2;
    assert_eq!(m.positions[0], m.positions[ring - 1], "seam");
}

#[test]
fn disk_and_cylinder_errors() {
    assert_src_err(
        "WorldBegin\nShape \"disk\" \"float radius\" 1\n \"float innerradius\" 1\n",
        3,
        &["innerradius must lie in [0, radius)"],
    );
    assert_src_err(
        "WorldBegin\nShape \"disk\"\n \"float radius\" 0\n",
        3,
        &["radius must be positive"],
    );
    assert_src_err(
        "WorldBegin\nShape \"cylinder\" \"float zmin\" 1\n \"float zmax\" 1\n",
        3,
        &["zmin and zmax must differ"],
    );
    assert_src_err(
        "WorldBegin\nShape \"cylinder\"\n \"float phimax\" -5\n",
        3,
        &["phimax must be positive"],
    );
    assert_src_err(
        "WorldBegin\nShape \"cylinder\"\n \"float height\" 1\n",
        3,
        &["unused parameter \"float height\""],
    );
}

// ---------------------------------------------------------------------------------------------
// directives accepted and ignored, with notes; unsupported ones

#[test]
fn accelerator_option_colorspace_are_accepted_with_notes() {
    let s = ok(
        r#"Accelerator "bvh" "integer maxnodeprims" 4 "string splitmethod" "sah"
Option "bool wavefront" true
ColorSpace "srgb"
WorldBegin
MediumInterface "" ""
ColorSpace "srgb"
"#,
    );
    assert_eq!(s.notes.len(), 2, "{:?}", s.notes);
    assert!(s.notes[0].contains("scene.pbrt:1:1: Accelerator \"bvh\""));
    assert!(s.notes[0].contains("\"integer maxnodeprims\", \"string splitmethod\""));
    assert!(s.notes[1].contains(":2:8: Option \"bool wavefront\" ignored"));
    assert_src_err(
        "WorldBegin\nAccelerator \"bvh\"\n",
        2,
        &["Accelerator is not allowed after WorldBegin"],
    );
    assert_src_err("\nColorSpace \"aces2065-1\"\n", 2, &["\"aces2065-1\""]);
    assert_src_err(
        "Option \"bool forcediffuse\" true\n",
        1,
        &["\"bool forcediffuse\": unsupported Option"],
    );
}

#[test]
fn other_integrators_parameters_are_ignored_with_a_note() {
    let s = ok(
        r#"Integrator "sppm" "float radius" 0.01 "integer maxdepth" 7
    "integer photonsperiteration" 1000
WorldBegin
"#,
    );
    assert_eq!(s.notes.len(), 1, "{:?}", s.notes);
    assert!(
        s.notes[0].ends_with("ignores \"float radius\", \"integer photonsperiteration\""),
        "{}",
        s.notes[0]
    );
    // maxdepth stays for the render to read, and nothing else is left unread.
    let mut p = s.integrator.params.clone();
    assert!(p.check_unused().is_err());
    assert_eq!(p.get_int("maxdepth", 5).unwrap(), 7);
    p.check_unused().unwrap();
    // "regularize" of volpath too; a parameter volpath does not have stays unread (an error
    // when the render reads the settings).
    let s = ok("Integrator \"volpath\" \"bool regularize\" true \"float radius\" 1\nWorldBegin\n");
    assert!(s.notes[0].contains("\"bool regularize\""));
    let e = photon::integrator::RenderSettings::from_scene(&s).unwrap_err();
    assert!(
        e.to_string().contains("unused parameter \"float radius\""),
        "{e}"
    );
    // The photon mapper's own parameters are not "foreign".
    let s = ok("Integrator \"photonmap\" \"integer globalphotons\" 10\nWorldBegin\n");
    assert!(s.notes.is_empty());
    let settings = photon::integrator::RenderSettings::from_scene(&s).unwrap();
    assert_eq!(settings.photon.trace.global_photons, 10);
}

/// Each integrator reads its own parameters: the photon mapper's on another integrator's line
/// are an error at the parameter (they rendered silently before, issue 16), whichever
/// integrator the command line then picks.
#[test]
fn photon_map_parameters_belong_to_the_photonmap_line() {
    for (line, key) in [
        (
            "Integrator \"path\"\n  \"integer globallookup\" [ 7 ] \"bool progressive\" true",
            "globallookup",
        ),
        (
            "Integrator \"sppm\" \"bool progressive\" true",
            "progressive",
        ),
        ("Integrator \"volpath\" \"float alpha\" 0.5", "alpha"),
    ] {
        let s = ok(&format!("{line}\nWorldBegin\n"));
        let e = photon::integrator::RenderSettings::from_scene(&s).unwrap_err();
        let row = if key == "globallookup" { 2 } else { 1 };
        assert!(
            e.to_string().contains(&format!("scene.pbrt:{row}:"))
                && e.to_string().contains(&format!(
                    "\"{key}\" is a parameter of Integrator \"photonmap\""
                )),
            "{e}"
        );
    }
    // maxdepth and passspp belong to every integrator.
    let s = ok("Integrator \"path\" \"integer maxdepth\" 3 \"integer passspp\" 2\nWorldBegin\n");
    let settings = photon::integrator::RenderSettings::from_scene(&s).unwrap();
    assert_eq!((settings.max_depth, settings.pass_spp), (3, 2));
}

#[test]
fn media_textures_and_curves_are_clear_errors() {
    assert_src_err(
        "WorldBegin\n\nMakeNamedMedium \"fog\" \"string type\" \"homogeneous\"\n",
        3,
        &["participating media are not supported (MakeNamedMedium)"],
    );
    assert_src_err(
        "WorldBegin\nMediumInterface \"\" \"fog\"\n",
        2,
        &["participating media are not supported (MediumInterface \"\" \"fog\")"],
    );
    assert_src_err(
        "WorldBegin\nShape \"curve\" \"point3 P\" [0 0 0 1 0 0 2 0 0 3 0 0]\n",
        2,
        &["curves and hair are not supported"],
    );
}

#[test]
fn every_named_metal_loads_with_and_without_brackets() {
    for metal in ["Ag", "Al", "Au", "Cu", "CuZn", "MgO", "TiO2"] {
        let plain = material_of(&format!(
            r#"Material "conductor" "spectrum eta" "metal-{metal}-eta" "spectrum k" "metal-{metal}-k""#
        ));
        let bracketed = material_of(&format!(
            r#"Material "conductor" "spectrum eta" [ "metal-{metal}-eta" ] "spectrum k" [ "metal-{metal}-k" ]"#
        ));
        assert_eq!(plain, bracketed, "{metal}");
        let Some((eta, k, ..)) = conductor(&plain) else {
            panic!("{metal}")
        };
        assert!(
            eta.min_element() > 0.1 && k.min_element() >= 0.0,
            "{metal}: {eta} {k}"
        );
    }
    // Brass (CuZn) is yellow: its k falls from red to blue, as in the table (3.52 at 630 nm,
    // 1.92 at 465 nm).
    let Some((_, k, ..)) = conductor(&material_of(
        r#"Material "conductor" "spectrum k" "metal-CuZn-k" "spectrum eta" "metal-CuZn-eta""#,
    )) else {
        panic!()
    };
    assert!(k.x > 3.5 && k.z < 2.0, "{k}");
    assert_src_err(
        "WorldBegin\nMaterial \"conductor\"\n \"spectrum eta\" [ \"metal-Cu-eta\" \"metal-Au-eta\" ]\n",
        3,
        &["expected one named spectrum"],
    );
    assert_src_err(
        "WorldBegin\nMaterial \"conductor\"\n \"spectrum k\" [ \"spds/Au.k.spd\" ]\n",
        3,
        &["spectrum files are not supported (\"spds/Au.k.spd\")"],
    );
}

// ---------------------------------------------------------------------------------------------
// textures: parsed and stored (not applied)

/// Writes a 2x1 RGB image: left texel (128, 10, 255), right texel (0, 255, 64).
fn write_image(dir: &TempDir, name: &str) {
    let img = image::RgbImage::from_raw(2, 1, vec![128, 10, 255, 0, 255, 64]).unwrap();
    img.save(dir.0.join(name)).unwrap();
}

#[test]
fn textures_are_parsed_with_pbrt_defaults_and_one_copy_per_image() {
    let dir = TempDir::new("photon-parser");
    write_image(&dir, "t.png");
    write_image(&dir, "t.tga");
    let scene = dir.write(
        "scene.pbrt",
        r#"WorldBegin
Texture "a" "spectrum" "imagemap" "string filename" "t.png" "string wrap" "clamp"
Texture "b" "spectrum" "imagemap" "string filename" "t.png" "float uscale" 2 "string filter" "point"
Texture "c" "spectrum" "imagemap" "string filename" "t.tga"
Texture "g" "float" "imagemap" "string filename" "t.png" "string encoding" "gamma 2.2"
Texture "half" "float" "constant" "float value" 0.5
Texture "s" "spectrum" "scale" "texture tex" "c" "texture scale" "half"
Texture "m" "spectrum" "mix" "texture tex1" "c" "rgb tex2" [ 0 0 1 ] "float amount" 0.25
Texture "k" "spectrum" "checkerboard" "rgb tex1" [ 1 1 1 ] "texture tex2" "s"
    "float uscale" 4 "float vscale" 4
"#,
    );
    let s = load(&scene).unwrap();
    let (sp, fl) = (&s.textures.spectrum, &s.textures.float);
    assert_eq!((sp.len(), fl.len()), (6, 2));
    let at = |t: &photon::texture::Texture, u: f32| t.eval(Vec2::new(u, 0.5));
    // PNG defaults to sRGB: 128 -> 0.215861, 10 -> 10 / 255 / 12.92, 255 -> 1 (IEC 61966-2-1).
    let left_srgb = Vec3::new(0.215861, 10.0 / 255.0 / 12.92, 1.0);
    assert_vec(at(&sp["a"], 0.25), left_srgb, 1e-5);
    // Clamp: u = 0 is the left texel's centre's left half, still the left texel.
    assert_vec(at(&sp["a"], 0.0), left_srgb, 1e-5);
    // uscale 2 with point filtering: u = 0.3 -> s = 0.6, the right texel (0, 1, 64 decoded).
    let right_srgb = Vec3::new(0.0, 1.0, 0.051269);
    assert_vec(at(&sp["b"], 0.3), right_srgb, 1e-5);
    // A TGA is sRGB too, as pbrt-v4's Image::Read decodes every 8-bit stb format.
    let left_linear = left_srgb;
    assert_vec(at(&sp["c"], 0.25), left_linear, 1e-5);
    // Float imagemap: the red channel (pbrt-v4's MIPMap::Texel<Float>), gamma-2.2-decoded.
    let g = (128.0f32 / 255.0).powf(2.2);
    assert_vec(at(&fl["g"], 0.25), Vec3::splat(g), 1e-5);
    assert_vec(at(&sp["s"], 0.25), left_linear * 0.5, 1e-5);
    assert_vec(
        at(&sp["m"], 0.25),
        0.75 * left_linear + Vec3::new(0.0, 0.0, 0.25),
        1e-5,
    );
    // Checkerboard 4x4: (u, v) = (0.1, 0.5) -> cell (0, 2), even: tex1; (0.3, 0.5) odd: "s".
    assert_vec(at(&sp["k"], 0.1), Vec3::ONE, 0.0);
    assert_vec(at(&sp["k"], 0.3), at(&sp["s"], 0.3), 0.0);
    // "a" and "b" share one decoded t.png (same encoding); "g" decoded it separately.
    let image = |t: &photon::texture::Texture| match t {
        photon::texture::Texture::Image(m) => m.image.clone(),
        other => panic!("not an image texture: {other:?}"),
    };
    assert!(std::sync::Arc::ptr_eq(&image(&sp["a"]), &image(&sp["b"])));
    assert!(!std::sync::Arc::ptr_eq(&image(&sp["a"]), &image(&fl["g"])));
}

#[test]
fn texture_errors() {
    let dir = TempDir::new("photon-parser");
    write_image(&dir, "t.png");
    let err = |body: &str| {
        let p = dir.write("scene.pbrt", format!("WorldBegin\n{body}\n"));
        load(&p).unwrap_err().to_string()
    };
    let e = err(r#"Texture "a" "spectrum" "imagemap" "string filename" "nope.png""#);
    assert!(
        e.contains("scene.pbrt:2:24: imagemap") && e.contains("nope.png"),
        "{e}"
    );
    let e = err(r#"Texture "a" "color" "constant""#);
    assert!(e.contains("\"spectrum\" or \"float\""), "{e}");
    let e = err(r#"Texture "a" "spectrum" "scale" "texture tex" "missing""#);
    assert!(e.contains("unknown spectrum texture \"missing\""), "{e}");
    // Namespaces: a float texture is not a spectrum texture.
    let e = err("Texture \"f\" \"float\" \"constant\"\nTexture \"a\" \"spectrum\" \"scale\" \"texture tex\" \"f\"");
    assert!(e.contains("unknown spectrum texture \"f\""), "{e}");
    let e = err("Texture \"f\" \"float\" \"constant\"\nTexture \"f\" \"float\" \"constant\"");
    assert!(
        e.contains("scene.pbrt:3:9: float texture \"f\" redefined"),
        "{e}"
    );
    let e = err(r#"Texture "a" "spectrum" "checkerboard" "integer dimension" 3"#);
    assert!(e.contains("only 2D checkerboards"), "{e}");
    let e = err(r#"Texture "a" "spectrum" "checkerboard" "string mapping" "spherical""#);
    assert!(
        e.contains("unsupported texture mapping \"spherical\""),
        "{e}"
    );
    let e = err(
        r#"Texture "a" "spectrum" "imagemap" "string filename" "t.png" "string wrap" "mirror""#,
    );
    assert!(
        e.contains("\"mirror\" is not repeat, clamp or black"),
        "{e}"
    );
    let e = err(
        r#"Texture "a" "spectrum" "imagemap" "string filename" "t.png" "string encoding" "gamma x""#,
    );
    assert!(e.contains("is not an encoding"), "{e}");
    let e = err(r#"Texture "a" "spectrum" "wrinkled""#);
    assert!(e.contains("unsupported texture class \"wrinkled\""), "{e}");
    let e = err(r#"Texture "a" "spectrum" "constant" "float uscale" 2"#);
    assert!(e.contains("unused parameter \"float uscale\""), "{e}");
    // A float texture where a spectrum one is wanted, and the other way round.
    let e = err(
        "Texture \"a\" \"float\" \"constant\"\nMaterial \"diffuse\" \"texture reflectance\" \"a\"",
    );
    assert!(
        e.contains(
            "scene.pbrt:3:20: parameter \"texture reflectance\": unknown spectrum texture \"a\""
        ),
        "{e}"
    );
    let e = err("Texture \"a\" \"spectrum\" \"constant\"\nMaterial \"conductor\" \"texture roughness\" \"a\"");
    assert!(e.contains("unknown float texture \"a\""), "{e}");
    // A light's colour cannot be a texture.
    let e =
        err("Texture \"a\" \"spectrum\" \"constant\"\nLightSource \"point\" \"texture I\" \"a\"");
    assert!(
        e.contains("\"texture I\": a texture is not supported for this parameter"),
        "{e}"
    );
}

// ---------------------------------------------------------------------------------------------
// object instancing

#[test]
fn object_instances_compose_transforms_and_keep_materials() {
    // Defined under Translate 0 0 1 with a red material; instanced plain and under Scale 2.
    let s = ok(r#"WorldBegin
AttributeBegin
  Translate 0 0 1
  ObjectBegin "thing"
    Material "diffuse" "rgb reflectance" [ 0.8 0 0 ]
    Shape "trianglemesh" "point3 P" [ 1 0 0  0 1 0  0 0 1 ] "normal N" [ 0 0 1  0 0 1  0 0 1 ]
    AreaLightSource "diffuse" "rgb L" [ 1 1 1 ]
    Shape "sphere" "float radius" 0.5
  ObjectEnd
AttributeEnd
Material "diffuse" "rgb reflectance" [ 0 0 0.8 ]
ObjectInstance "thing"
Scale 2 2 -2
ObjectInstance "thing"
"#);
    assert_eq!(s.meshes.len(), 4);
    assert!(s.lights.is_empty(), "area lights in instances are ignored");
    assert_eq!(s.notes.len(), 1);
    assert!(s.notes[0].contains(":8:11: area light ignored inside object \"thing\""));
    let red = diffuse(Vec3::new(0.8, 0.0, 0.0));
    assert!(s
        .meshes
        .iter()
        .all(|m| s.materials[m.material as usize] == red));
    // Plain instance: the definition's transform.
    assert_vec(s.meshes[0].positions[0], Vec3::new(1.0, 0.0, 1.0), 0.0);
    assert_eq!(s.meshes[1].sphere, Some((Vec3::new(0.0, 0.0, 1.0), 0.5)));
    // Scale 2 2 -2 times Translate 0 0 1: (1, 0, 1) -> (2, 0, -2); a mirror, so the triangle
    // mesh flips its orientation and its normal follows the inverse transpose (0, 0, -1).
    let tri = &s.meshes[2];
    assert_vec(tri.positions[0], Vec3::new(2.0, 0.0, -2.0), 0.0);
    assert_vec(tri.normals.as_ref().unwrap()[0], -Vec3::Z, 1e-6);
    assert!(tri.flip_normals && !s.meshes[0].flip_normals);
    // The sphere: centre (0, 0, -2), radius 1, still wound outward.
    let sphere = &s.meshes[3];
    assert_eq!(sphere.sphere, Some((Vec3::new(0.0, 0.0, -2.0), 1.0)));
    for t in 0..sphere.indices.len() as u32 {
        let [p0, p1, p2] = sphere.triangle(t);
        let outward = (p0 + p1 + p2) / 3.0 - Vec3::new(0.0, 0.0, -2.0);
        assert!((p1 - p0).cross(p2 - p0).dot(outward) > 0.0, "triangle {t}");
    }
}

#[test]
fn object_instancing_errors() {
    assert_src_err(
        "WorldBegin\n\nObjectInstance \"nope\"\n",
        3,
        &["unknown object \"nope\""],
    );
    assert_src_err(
        "WorldBegin\nObjectEnd\n",
        2,
        &["ObjectEnd without ObjectBegin"],
    );
    assert_src_err(
        "WorldBegin\nObjectBegin \"a\"\nObjectBegin \"b\"\n",
        3,
        &["ObjectBegin inside the definition of \"a\" (line 2)"],
    );
    assert_src_err(
        "WorldBegin\nObjectBegin \"a\"\nObjectEnd\nObjectBegin \"b\"\nObjectInstance \"a\"\n",
        5,
        &["ObjectInstance inside the definition of \"b\""],
    );
    assert_src_err(
        "WorldBegin\nObjectBegin \"a\"\nObjectEnd\nObjectBegin \"a\"\nObjectEnd\n",
        5,
        &["object \"a\" redefined"],
    );
    assert_src_err(
        "WorldBegin\nObjectBegin \"a\"\n",
        2,
        &["ObjectBegin without a matching ObjectEnd"],
    );
    assert_src_err(
        &format!(
            "WorldBegin\nObjectBegin \"a\"\n{TRI}\nObjectEnd\nScale 1 0 1\nObjectInstance \"a\"\n"
        ),
        6,
        &["object \"a\": the instance transform is singular"],
    );
}

/// The materials of issue 9 with pbrt-v4's defaults, explicit values, and textures where
/// pbrt-v4 allows them; each lands in the BSDF it names.
#[test]
fn coated_rough_and_translucent_materials() {
    use photon::bsdf::{Bsdf, BxdfFlags as F};
    use photon::material::{Coat, Roughness};
    use photon::texture::TexCoord;
    let tc = TexCoord::default();
    let bsdf = |m: &Material| m.kind.bsdf(&tc);
    let constant = |u: f32, remap: bool| Roughness {
        u: u.into(),
        v: u.into(),
        remap,
    };

    // Rough dielectric: roughness remapped (alpha = sqrt), u/v separately, remap off.
    let m = material_of(r#"Material "dielectric" "float roughness" 0.04"#);
    assert_eq!(
        m.kind,
        MaterialKind::Dielectric(DielectricMaterial {
            eta: 1.5,
            roughness: constant(0.04, true)
        })
    );
    let Bsdf::Dielectric(d) = bsdf(&m) else {
        panic!("{m:?}")
    };
    assert!((d.distrib.alpha_x() - 0.2).abs() < 1e-6 && !d.is_smooth());
    assert_eq!(
        bsdf(&m).flags(),
        F::REFLECTION | F::TRANSMISSION | F::GLOSSY
    );
    assert_eq!(m.kind.flags(), bsdf(&m).flags());
    let m = material_of(
        r#"Material "dielectric" "float uroughness" 0.1 "float vroughness" 0.3 "bool remaproughness" false "float eta" 1.33"#,
    );
    let Bsdf::Dielectric(d) = bsdf(&m) else {
        panic!("{m:?}")
    };
    assert_eq!(
        (d.eta, d.distrib.alpha_x(), d.distrib.alpha_y()),
        (1.33, 0.1, 0.3)
    );

    // Thin dielectric.
    let m = material_of(r#"Material "thindielectric""#);
    assert_eq!(
        m.kind,
        MaterialKind::ThinDielectric(ThinDielectricMaterial { eta: 1.5 })
    );
    assert!(bsdf(&m).flags().is_specular_only());
    let m = material_of(r#"Material "thindielectric" "spectrum eta" "glass-BK7""#);
    let MaterialKind::ThinDielectric(ThinDielectricMaterial { eta }) = m.kind else {
        panic!("{m:?}")
    };
    assert!((eta - 1.5185).abs() < 1e-3, "{eta}");

    // Diffuse transmission: defaults 0.25 and 0.25, scale multiplies, clamped per hit.
    let m = material_of(r#"Material "diffusetransmission""#);
    let Bsdf::DiffuseTransmission(d) = bsdf(&m) else {
        panic!("{m:?}")
    };
    assert_eq!(
        (d.reflectance, d.transmittance),
        (Vec3::splat(0.25), Vec3::splat(0.25))
    );
    let m = material_of(
        r#"Material "diffusetransmission" "rgb reflectance" [0.2 0.4 0.6] "rgb transmittance" [0.5 0.5 0.5] "float scale" 2"#,
    );
    let Bsdf::DiffuseTransmission(d) = bsdf(&m) else {
        panic!("{m:?}")
    };
    assert_eq!(d.reflectance, Vec3::new(0.4, 0.8, 1.0));
    assert_eq!(d.transmittance, Vec3::ONE);
    assert_eq!(
        bsdf(&m).flags(),
        F::REFLECTION | F::TRANSMISSION | F::DIFFUSE
    );

    // Coated diffuse: pbrt-v4's defaults.
    let m = material_of(r#"Material "coateddiffuse""#);
    let want_coat = Coat {
        eta: 1.5,
        thickness: 0.01.into(),
        albedo: Vec3::ZERO.into(),
        g: 0.0.into(),
        max_depth: 10,
        n_samples: 1,
    };
    assert_eq!(
        m.kind,
        MaterialKind::CoatedDiffuse(CoatedDiffuseMaterial {
            reflectance: Vec3::splat(0.5).into(),
            roughness: constant(0.0, true),
            coat: want_coat.clone(),
        })
    );
    let Bsdf::CoatedDiffuse(c) = bsdf(&m) else {
        panic!("{m:?}")
    };
    assert_eq!(
        (c.thickness, c.g, c.max_depth, c.n_samples),
        (0.01, 0.0, 10, 1)
    );
    assert_eq!(bsdf(&m).flags(), F::REFLECTION | F::SPECULAR | F::DIFFUSE);
    assert_eq!(m.kind.flags(), bsdf(&m).flags());
    let m = material_of(
        r#"Material "coateddiffuse" "rgb reflectance" [0.1 0.2 0.3] "float roughness" 0.09 "float thickness" 0.2 "float eta" 1.4 "rgb albedo" [0.5 0.5 0.5] "float g" -0.3 "integer maxdepth" 4 "integer nsamples" 3"#,
    );
    let Bsdf::CoatedDiffuse(c) = bsdf(&m) else {
        panic!("{m:?}")
    };
    assert_eq!(c.bottom.reflectance, Vec3::new(0.1, 0.2, 0.3));
    assert!((c.top.distrib.alpha_x() - 0.3).abs() < 1e-6 && c.top.eta == 1.4);
    assert_eq!(
        (c.thickness, c.g, c.max_depth, c.n_samples),
        (0.2, -0.3, 4, 3)
    );
    assert_eq!(c.albedo, Vec3::splat(0.5));
    assert_eq!(bsdf(&m).flags(), F::REFLECTION | F::DIFFUSE);

    // Coated conductor: copper under the coat by default, its index divided by the coat's.
    let m = material_of(r#"Material "coatedconductor""#);
    let Bsdf::CoatedConductor(c) = bsdf(&m) else {
        panic!("{m:?}")
    };
    let cu = material_of(r#"Material "conductor""#);
    let Bsdf::Conductor(plain) = bsdf(&cu) else {
        panic!()
    };
    assert_vec(c.bottom.eta, plain.eta / 1.5, 1e-6);
    assert_vec(c.bottom.k, plain.k / 1.5, 1e-6);
    assert_eq!(bsdf(&m).flags(), F::REFLECTION | F::SPECULAR);
    let m = material_of(
        r#"Material "coatedconductor" "float interface.roughness" 0.01 "float interface.eta" 1.2 "spectrum conductor.eta" "metal-Au-eta" "spectrum conductor.k" "metal-Au-k" "float conductor.uroughness" 0.04 "float conductor.vroughness" 0.16"#,
    );
    let Bsdf::CoatedConductor(c) = bsdf(&m) else {
        panic!("{m:?}")
    };
    assert!((c.top.distrib.alpha_x() - 0.1).abs() < 1e-6 && c.top.eta == 1.2);
    assert!((c.bottom.distrib.alpha_x() - 0.2).abs() < 1e-6);
    assert!((c.bottom.distrib.alpha_y() - 0.4).abs() < 1e-6);
    assert_eq!(bsdf(&m).flags(), F::REFLECTION | F::GLOSSY);
    assert_eq!(m.kind.flags(), bsdf(&m).flags());
    let m = material_of(r#"Material "coatedconductor" "rgb reflectance" [0.9 0.5 0.1]"#);
    assert!(matches!(
        m.kind,
        MaterialKind::CoatedConductor(CoatedConductorMaterial {
            metal: Metal::Reflectance(_),
            ..
        })
    ));

    // Textures where pbrt-v4 allows them.
    let m = material_of(
        "Texture \"r\" \"spectrum\" \"checkerboard\"\nTexture \"t\" \"float\" \"constant\" \"float value\" 0.3\nMaterial \"coateddiffuse\" \"texture reflectance\" \"r\" \"texture thickness\" \"t\" \"texture roughness\" \"t\"",
    );
    let MaterialKind::CoatedDiffuse(CoatedDiffuseMaterial {
        coat,
        reflectance,
        roughness,
    }) = &m.kind
    else {
        panic!("{m:?}")
    };
    assert_eq!(reflectance.constant(), None, "the checkerboard varies");
    // A constant texture is folded into its value.
    assert_eq!(coat.thickness.constant(), Some(Vec3::splat(0.3)));
    assert_eq!(roughness.u.constant(), Some(Vec3::splat(0.3)));
}

#[test]
fn bad_coated_and_translucent_parameters_are_located_errors() {
    for (body, needle) in [
        (r#""float thickness" -1"#, "thickness must lie in"),
        (r#""float g" 1.5"#, "g must lie in [-1, 1]"),
        (r#""integer maxdepth" -1"#, "maxdepth must lie in 0..=1000"),
        (r#""integer nsamples" 0"#, "nsamples must lie in 1..=1024"),
        (r#""rgb albedo" [2 0 0]"#, "must lie in [0, 1]"),
        (r#""float eta" 0"#, "eta must be positive"),
        (
            r#""float roughness" -0.5"#,
            "roughness must be finite and not negative",
        ),
        (
            r#""float conductor.roughness" 0.1"#,
            "unused parameter \"float conductor.roughness\"",
        ),
    ] {
        assert_src_err(
            &format!("WorldBegin\nMaterial \"coateddiffuse\"\n {body}\n"),
            3,
            &[needle],
        );
    }
    assert_src_err(
        "WorldBegin\nMaterial \"coatedconductor\"\n \"rgb reflectance\" [0.5 0.5 0.5] \"spectrum conductor.eta\" \"metal-Au-eta\"\n",
        3,
        &["not both"],
    );
    assert_src_err(
        "WorldBegin\nMaterial \"coatedconductor\"\n \"float interface.eta\" -1\n",
        3,
        &["interface.eta must be positive"],
    );
    assert_src_err(
        "WorldBegin\nMaterial \"diffusetransmission\"\n \"float scale\" -1\n",
        3,
        &["scale must lie in"],
    );
    assert_src_err(
        "WorldBegin\nMaterial \"thindielectric\"\n \"float roughness\" 0.1\n",
        3,
        &["unused parameter \"float roughness\""],
    );
}

/// `interface` materials bound media: a clear error naming why, at the type.
#[test]
fn interface_material_names_media() {
    let dir = TempDir::new("photon-interface");
    let path = dir.write(
        "s.pbrt",
        "WorldBegin\nMaterial \"interface\"\nShape \"sphere\"\n",
    );
    let e = load(&path).unwrap_err().to_string();
    assert!(
        e.contains("s.pbrt:2:10: material \"interface\" only bounds participating media"),
        "{e}"
    );
}

/// `mix` names two materials defined earlier; anything else is an error at the parameter.
#[test]
fn mix_material_errors() {
    let dir = TempDir::new("photon-mix-err");
    let cases = [
        (
            "MakeNamedMaterial \"a\" \"string type\" \"diffuse\"\nMaterial \"mix\" \"string materials\" [ \"a\" \"b\" ]\n",
            "unknown named material \"b\"",
        ),
        (
            "MakeNamedMaterial \"a\" \"string type\" \"diffuse\"\nMaterial \"mix\" \"string materials\" [ \"a\" ]\n",
            "expected two material names",
        ),
        ("Material \"mix\"\n", "mix needs \"string materials\""),
    ];
    for (i, (body, want)) in cases.iter().enumerate() {
        let path = dir.write(&format!("m{i}.pbrt"), format!("WorldBegin\n{body}"));
        let e = load(&path).unwrap_err().to_string();
        assert!(
            e.contains(want) && e.contains(&format!("m{i}.pbrt:")),
            "{e}"
        );
    }
}

#[test]
fn camera_lens_screen_window_and_shutter() {
    let s = ok(
        r#"Camera "perspective" "float fov" 30 "float lensradius" 0.25 "float focaldistance" 7
    "float screenwindow" [ -2 1 -0.5 1.5 ] "float shutteropen" 0.5 "float shutterclose" 2
WorldBegin
"#,
    );
    let c = &s.camera;
    assert_eq!((c.lens_radius, c.focal_distance), (0.25, 7.0));
    assert_eq!(c.screen_window, Some([-2.0, 1.0, -0.5, 1.5]));
    assert_eq!(c.exposure_time, 1.5);
    // pbrt-v4's defaults: a pinhole focused at 1e6, the image's own window, exposure 1.
    let s =
        ok("Camera \"perspective\" \"float focaldistance\" 3 \"float lensradius\" 0\nWorldBegin\n");
    assert_eq!((s.camera.lens_radius, s.camera.focal_distance), (0.0, 3.0));
    assert_eq!(
        (s.camera.screen_window, s.camera.exposure_time),
        (None, 1.0)
    );
    assert_eq!(ok("WorldBegin\n").camera.focal_distance, 1e6);
    // frameaspectratio: [-f, f] x [-1, 1] when wider than tall, else [-1, 1] x [-1/f, 1/f].
    let s = ok("Camera \"perspective\" \"float frameaspectratio\" 2\nWorldBegin\n");
    assert_eq!(s.camera.screen_window, Some([-2.0, 2.0, -1.0, 1.0]));
    let s = ok("Camera \"perspective\" \"float frameaspectratio\" 0.5\nWorldBegin\n");
    assert_eq!(s.camera.screen_window, Some([-1.0, 1.0, -2.0, 2.0]));
    for (params, needle) in [
        (
            "\"float focaldistance\" 0",
            "\"float focaldistance\": must be positive",
        ),
        (
            "\"float screenwindow\" [ -1 1 -1 ]",
            "expected four values xmin xmax ymin ymax",
        ),
        ("\"float screenwindow\" [ 1 -1 -1 1 ]", "min < max"),
        ("\"float frameaspectratio\" -1", "must be positive"),
        (
            "\"float shutteropen\" 1 \"float shutterclose\" 1",
            "must be after",
        ),
    ] {
        assert_src_err(
            &format!("Camera \"perspective\"\n {params}\nWorldBegin\n"),
            2,
            &[needle],
        );
    }
}

/// A Camera that fails to load still defines the "camera" coordinate system (pbrt-v4 defines it
/// in the directive's handler), so a later `CoordSysTransform "camera"` is not an error too.
#[test]
fn rejected_camera_still_defines_its_coordinate_system() {
    let dir = TempDir::new("photon-parser");
    let path = dir.write(
        "scene.pbrt",
        r#"Translate 0 0 -4
Camera "realistic" "string lensfile" "wide.dat"
WorldBegin
CoordSysTransform "camera"
LightSource "point" "point3 from" [ 0 0 0 ]
"#,
    );
    let got = photon::scene::loader::load_collecting(&path);
    let errs: Vec<String> = got.errors.iter().map(|e| e.to_string()).collect();
    assert_eq!(errs.len(), 1, "{errs:?}");
    assert!(errs[0].contains("scene.pbrt:2:8") && errs[0].contains("\"realistic\""));
    // Camera space is the inverse of the CTM: the eye is at world (0, 0, 4).
    let Light::Point(photon::light::PointLight { pos, .. }) = got.scene.lights[0] else {
        panic!()
    };
    assert_vec(pos, Vec3::new(0.0, 0.0, 4.0), 1e-6);
}

#[test]
fn film_sensor_crop_and_gbuffer() {
    let s = ok(
        r#"Film "rgb" "float iso" 250 "string sensor" "cie1931" "float whitebalance" 0
    "float maxcomponentvalue" 10 "float cropwindow" [ 0.9 0.1 1.5 -0.2 ]
Camera "perspective" "float shutterclose" 0.5
WorldBegin
"#,
    );
    assert_eq!((s.film.iso, s.film.max_component), (250.0, 10.0));
    // Ordered and clamped to [0, 1] per axis, as pbrt-v4 does.
    assert_eq!(s.film.crop, Some([0.1, 0.9, 0.0, 1.0]));
    assert_eq!(s.film.imaging_ratio(s.camera.exposure_time), 1.25);
    assert_eq!(s.film.white_balance, 0.0);
    let s = ok("Film \"rgb\" \"float whitebalance\" 9000\nWorldBegin\n");
    assert_eq!(s.film.white_balance, 9000.0);
    let s = ok("Film \"rgb\"\nWorldBegin\n");
    assert_eq!(
        (s.film.iso, s.film.max_component, s.film.crop),
        (100.0, f32::INFINITY, None)
    );
    assert!(s.notes.is_empty());
    // gbuffer: an RGB film, with a note that the extra channels are not written.
    let s = ok("Film \"gbuffer\" \"string coordinatesystem\" \"world\" \"string filename\" \"a.exr\" \"integer xresolution\" 32\nWorldBegin\n");
    assert_eq!(s.film.xres, 32);
    assert_eq!(s.notes.len(), 1, "{:?}", s.notes);
    assert!(s.notes[0].contains("scene.pbrt:1:6") && s.notes[0].contains("not written"));
    for (film, needle) in [
        (
            "\"string sensor\" \"nikon_d850\"",
            "sensor \"nikon_d850\" is not supported",
        ),
        (
            "\"float whitebalance\" 3000",
            "must be 0 (none) or a daylight temperature in [3998, 100000] K",
        ),
        ("\"float iso\" 0", "\"float iso\": must be positive"),
        ("\"float maxcomponentvalue\" 0", "must be positive"),
        ("\"float cropwindow\" [ 0 1 0 ]", "four finite values"),
        (
            "\"float cropwindow\" [ 0.5 0.5 0 1 ]",
            "no pixel of the 1280x720 image",
        ),
    ] {
        assert_src_err(
            &format!("Film \"rgb\"\n {film}\nWorldBegin\n"),
            2,
            &[needle],
        );
    }
    assert_src_err(
        "Film \"gbuffer\"\n \"string coordinatesystem\" \"screen\"\nWorldBegin\n",
        2,
        &["unknown coordinate system \"screen\""],
    );
    assert_src_err(
        "Film \"gbuffer\"\n \"string filename\" \"a.png\"\nWorldBegin\n",
        2,
        &["EXR only"],
    );
}
// ---------------------------------------------------------------------------------------------
// blackbody lights, ActiveTransform, forward named materials, gzip

/// Luminance of a linear sRGB value (the Y row of IEC 61966-2-1's sRGB-to-XYZ matrix).
fn luminance(c: Vec3) -> f32 {
    0.2126 * c.x + 0.7152 * c.y + 0.0722 * c.z
}

/// Blackbody `L`/`I` on every light type: luminance `scale` (pbrt-v4 divides by the spectrum's
/// photometric integral), then `power`/`illuminance` as for RGB; the colour of 2856 K is CIE
/// illuminant A.
#[test]
fn blackbody_lights() {
    let s = ok(r#"WorldBegin
LightSource "point" "blackbody I" [ 2856 ] "float scale" 2
LightSource "point" "blackbody I" 6504 "float power" 100
LightSource "spot" "blackbody I" [ 3000 ]
LightSource "distant" "blackbody L" [ 5000 ] "float scale" 0.5
LightSource "infinite" "blackbody L" [ 8000 ] "float illuminance" 3.14159265
AttributeBegin
AreaLightSource "diffuse" "blackbody L" [ 4000 ] "float scale" 7
Shape "trianglemesh" "point3 P" [ 0 0 0 1 0 0 0 1 0 ] "integer indices" [ 0 1 2 ]
AttributeEnd
"#);
    let Light::Point(photon::light::PointLight { intensity, .. }) = s.lights[0] else {
        panic!()
    };
    assert!(close(luminance(intensity), 2.0, 1e-3), "{intensity}");
    let xyz = Vec3::new(
        0.4124 * intensity.x + 0.3576 * intensity.y + 0.1805 * intensity.z,
        luminance(intensity),
        0.0193 * intensity.x + 0.1192 * intensity.y + 0.9505 * intensity.z,
    );
    let (x, y) = (xyz.x / xyz.element_sum(), xyz.y / xyz.element_sum());
    assert!(
        (x - 0.44757).abs() < 1e-3 && (y - 0.40745).abs() < 1e-3,
        "({x}, {y})"
    );
    let Light::Point(photon::light::PointLight { intensity, .. }) = s.lights[1] else {
        panic!()
    };
    assert!(close(luminance(intensity), 100.0 / (4.0 * PI), 1e-3));
    assert!(
        (intensity / luminance(intensity) - Vec3::ONE)
            .abs()
            .max_element()
            < 0.05
    );
    let Light::Spot(photon::light::SpotLight { intensity, .. }) = s.lights[2] else {
        panic!()
    };
    assert!(close(luminance(intensity), 1.0, 1e-3) && intensity.x > 1.5 * intensity.z);
    let Light::Distant(photon::light::DistantLight { l, .. }) = s.lights[3] else {
        panic!()
    };
    assert!(close(luminance(l), 0.5, 1e-3));
    let Light::Infinite { map } = &s.lights[4] else {
        panic!()
    };
    assert!(close(luminance(map.le(Vec3::Y)), 1.0, 1e-3)); // illuminance pi: L = 1
    let Light::Area { l, .. } = s.lights[5] else {
        panic!()
    };
    assert!(close(luminance(l), 7.0, 1e-3));

    assert_src_err(
        "WorldBegin\nLightSource \"point\"\n \"blackbody I\" [ -5 ]\n",
        3,
        &["\"blackbody I\"", "temperature must be finite and > 0"],
    );
    assert_src_err(
        "WorldBegin\nLightSource \"point\"\n \"blackbody I\" [ 3000 1 ]\n",
        3,
        &["\"blackbody I\""],
    );
    assert_src_err(
        "WorldBegin\nMaterial \"diffuse\" \"blackbody reflectance\" 3000\n",
        2,
        &["only supported for light emission"],
    );
}

/// `ActiveTransform StartTime` / `EndTime` / `All`: transforms change the active CTMs only;
/// photon renders the shutter-open (start) CTM and notes once that the scene moves.
#[test]
fn active_transform() {
    let s = ok(&format!(
        "WorldBegin\nAttributeBegin\nActiveTransform StartTime\nTranslate 1 0 0\nActiveTransform EndTime\nTranslate 0 5 0\nActiveTransform All\nTranslate 0 0 2\n{TRI}\nAttributeEnd\n{TRI}\n"
    ));
    // The first triangle moved by (1, 0, 2) (the EndTime translation is not in the start pose),
    // the second not at all (AttributeEnd restored both CTMs).
    assert_vec(s.meshes[0].positions[0], Vec3::new(2.0, 0.0, 2.0), 1e-6);
    assert_vec(s.meshes[1].positions[0], Vec3::new(1.0, 0.0, 0.0), 1e-6);
    let moving: Vec<_> = s
        .notes
        .iter()
        .filter(|n| n.contains("motion blur"))
        .collect();
    assert_eq!(moving.len(), 1, "{:?}", s.notes);
    assert!(moving[0].contains("scene.pbrt:9:"), "{}", moving[0]);
    // Start and end changed alike: nothing moves, no note.
    let s = ok(&format!(
        "WorldBegin\nActiveTransform StartTime\nTranslate 1 0 0\nActiveTransform EndTime\nTranslate 1 0 0\nActiveTransform All\n{TRI}\n"
    ));
    assert_vec(s.meshes[0].positions[0], Vec3::new(2.0, 0.0, 0.0), 1e-6);
    assert!(
        s.notes.iter().all(|n| !n.contains("motion")),
        "{:?}",
        s.notes
    );
    // CoordSysTransform "camera" without ActiveTransform (killeroo-gold's distant light): not
    // moving, whatever the rounding of the camera's inverse.
    let s = ok("LookAt 200 250 70  0 33 -50  0 0 1\nCamera \"perspective\" \"float fov\" 38\nWorldBegin\nCoordSysTransform \"camera\"\nLightSource \"distant\" \"rgb L\" [ 0.2 0.2 0.2 ]\n");
    assert!(
        s.notes.iter().all(|n| !n.contains("motion")),
        "{:?}",
        s.notes
    );
    assert_src_err(
        "WorldBegin\n\nActiveTransform Sometimes\n",
        3,
        &[
            "ActiveTransform takes All, StartTime or EndTime",
            "Sometimes",
        ],
    );
}

/// The ActiveTransform of killeroo-moving (pbrt-v4-scenes) in collect mode: no error at all,
/// in particular no "unknown directive StartTime" from skipping its argument.
#[test]
fn active_transform_collect_mode_reads_its_argument() {
    let dir = TempDir::new("photon-parser");
    let path = dir.write(
        "scene.pbrt",
        format!("WorldBegin\nActiveTransform StartTime\nTransformTimes 0 1\nActiveTransform All\n{TRI}\n"),
    );
    let got = photon::scene::loader::load_collecting(&path);
    let msgs: Vec<String> = got.errors.iter().map(|e| e.to_string()).collect();
    assert_eq!(msgs.len(), 1, "{msgs:?}");
    assert!(
        msgs[0].contains(":3:1: unsupported directive \"TransformTimes\""),
        "{msgs:?}"
    );
    assert_eq!(got.scene.meshes.len(), 1);
}

/// `NamedMaterial` before its `MakeNamedMaterial` (the definition later, here in an Include):
/// resolved after parsing as pbrt-v4 does; never defined: an error at the first use.
#[test]
fn named_material_forward_reference() {
    let dir = TempDir::new("photon-parser");
    dir.write(
        "materials.pbrt",
        "MakeNamedMaterial \"light\" \"string type\" \"diffuse\" \"rgb reflectance\" [ 0.1 0.2 0.3 ]\n",
    );
    let main = dir.write(
        "scene.pbrt",
        format!("WorldBegin\nNamedMaterial \"light\"\n{TRI}\nNamedMaterial \"light\"\n{TRI}\nInclude \"materials.pbrt\"\nNamedMaterial \"light\"\n{TRI}\n"),
    );
    let s = load(&main).unwrap();
    let m = s.meshes[0].material;
    assert!(s.meshes.iter().all(|x| x.material == m));
    assert_eq!(s.materials[m as usize], diffuse(Vec3::new(0.1, 0.2, 0.3)));
    assert_src_err(
        &format!("WorldBegin\n{TRI}\nNamedMaterial \"ghost\"\n{TRI}\nNamedMaterial \"ghost\"\n"),
        3,
        &["unknown named material \"ghost\"", "no MakeNamedMaterial"],
    );
    assert_src_err(
        "WorldBegin\nNamedMaterial \"a\"\nMakeNamedMaterial \"a\" \"string type\" \"diffuse\"\nMakeNamedMaterial \"a\" \"string type\" \"diffuse\"\n",
        4,
        &["named material \"a\" redefined"],
    );
}

/// Writes `bytes` gzipped (flate2, default level) as `name` in `dir`.
fn write_gz(dir: &TempDir, name: &str, bytes: &[u8]) -> PathBuf {
    use std::io::Write;
    let mut enc = flate2::write::GzEncoder::new(Vec::new(), flate2::Compression::default());
    enc.write_all(bytes).unwrap();
    dir.write(name, enc.finish().unwrap())
}

/// `Include "x.pbrt.gz"` and `plymesh` `"x.ply.gz"` load exactly as the plain files.
#[test]
fn gzip_include_and_ply() {
    let dir = TempDir::new("photon-parser");
    let part = format!("Material \"diffuse\" \"rgb reflectance\" [ 0.2 0.3 0.4 ]\n{TRI}\n");
    dir.write("part.pbrt", &part);
    write_gz(&dir, "part.pbrt.gz", part.as_bytes());
    let verts = [
        [0.0, 0.0, 0.0],
        [1.0, 0.0, 0.0],
        [0.0, 1.0, 0.0],
        [1.0, 1.0, 0.5],
    ];
    let ply = binary_ply(false, &verts, &[vec![0, 1, 2], vec![1, 3, 2]]);
    dir.write("m.ply", &ply);
    write_gz(&dir, "m.ply.gz", &ply);
    let load_with = |ext: &str| {
        let src = format!(
            "WorldBegin\nInclude \"part.pbrt{ext}\"\nShape \"plymesh\" \"string filename\" \"m.ply{ext}\"\n"
        );
        load(&dir.write(&format!("scene{ext}.pbrt"), src)).unwrap()
    };
    let (plain, gz) = (load_with(""), load_with(".gz"));
    assert_eq!(gz.meshes.len(), 2);
    for (a, b) in plain.meshes.iter().zip(&gz.meshes) {
        assert_eq!((&a.positions, &a.indices), (&b.positions, &b.indices));
    }
    assert_eq!(plain.materials, gz.materials);
    assert_eq!(gz.meshes[1].positions[3], Vec3::new(1.0, 1.0, 0.5));

    // A corrupt .gz: a one-line error naming the file, at the Include / Shape.
    let mut bad = std::fs::read(dir.0.join("part.pbrt.gz")).unwrap();
    let n = bad.len();
    bad[n / 2] ^= 0xff;
    bad.truncate(n - 4);
    dir.write("bad.pbrt.gz", &bad);
    dir.write("bad.ply.gz", b"not gzip at all");
    assert_src_err_in(
        &dir,
        "WorldBegin\n\nInclude \"bad.pbrt.gz\"\n",
        3,
        &["bad.pbrt.gz", "gzip"],
    );
    assert_src_err_in(
        &dir,
        "WorldBegin\nShape \"plymesh\" \"string filename\" \"bad.ply.gz\"\n",
        2,
        &["bad.ply.gz", "gzip"],
    );
}

/// Checks an error of `src` written as `scene.pbrt` in `dir` (so it can name files there).
#[track_caller]
fn assert_src_err_in(dir: &TempDir, src: &str, line: u32, needles: &[&str]) {
    assert_err(
        load(&dir.write("scene.pbrt", src)),
        "scene.pbrt",
        line,
        needles,
    );
}

/// A gzip bomb (10 MB of zeros in ~10 KB) against a 1 MiB cap: a clean error, and the
/// decompressed size is bounded by the cap, not by what the data claims.
#[test]
fn gzip_bomb_is_capped() {
    use photon::scene::loader::gunzip_capped;
    use std::io::Write;
    let mut enc = flate2::write::GzEncoder::new(Vec::new(), flate2::Compression::best());
    enc.write_all(&vec![0u8; 10 << 20]).unwrap();
    let bomb = enc.finish().unwrap();
    assert!(bomb.len() < 64 << 10, "{}", bomb.len());
    let e = gunzip_capped(&bomb, 1 << 20).unwrap_err().to_string();
    assert!(
        e.contains("decompresses to more than the limit of 1.0 MB"),
        "{e}"
    );
    assert_eq!(gunzip_capped(&bomb, 10 << 20).unwrap().len(), 10 << 20);
}

/// A sphere whose `Shape` fails after it was read (alpha on an emitter, as kroken's
/// `lights.pbrt` has) is skipped in collect mode without a panic at the end (the sphere was
/// queued for tessellation without its mesh before).
#[test]
fn failed_emitting_sphere_is_skipped_in_collect_mode() {
    let dir = TempDir::new("photon-parser");
    let path = dir.write(
        "scene.pbrt",
        "WorldBegin\nAttributeBegin\nAreaLightSource \"diffuse\" \"blackbody L\" 6500\nShape \"sphere\" \"float radius\" 90 \"float alpha\" 0.5\nAttributeEnd\nShape \"sphere\"\n",
    );
    let got = photon::scene::loader::load_collecting(&path);
    let msgs: Vec<String> = got.errors.iter().map(|e| e.to_string()).collect();
    assert_eq!(msgs.len(), 1, "{msgs:?}");
    assert!(msgs[0].contains(":4:") && msgs[0].contains("alpha other than 0 on an emitting shape"));
    assert_eq!(got.scene.meshes.len(), 1);
    assert!(!got.scene.meshes[0].indices.is_empty());
}

/// pbrt-v4's area light emits nothing where its shape's alpha masks it, and rays pass there:
/// an emitting sphere of constant alpha 0 (kroken's sun) is left out, with a note, and the
/// scene keeps its other shapes and lights.
#[test]
fn emitting_shape_with_alpha_zero_is_left_out() {
    let dir = TempDir::new("photon-parser");
    let path = dir.write(
        "scene.pbrt",
        "WorldBegin\nLightSource \"point\" \"rgb I\" [ 1 1 1 ]\nAttributeBegin\nAreaLightSource \"diffuse\" \"blackbody L\" 6500\nShape \"sphere\" \"float radius\" 90 \"float alpha\" 0\nAttributeEnd\nShape \"sphere\"\n",
    );
    let got = photon::scene::loader::load_collecting(&path);
    assert!(got.errors.is_empty(), "{:?}", got.errors);
    let scene = got.scene;
    assert_eq!(scene.meshes.len(), 1, "only the plain sphere");
    assert!(scene.meshes[0].area_light.is_none());
    assert_eq!(scene.lights.len(), 1, "only the point light");
    assert!(
        scene
            .notes
            .iter()
            .any(|n| n.contains(":5:") && n.contains("alpha 0")),
        "{:?}",
        scene.notes
    );
}

/// pbrt-v4's spot light reads `conedeltaangle` (lights.cpp, `SpotLight::Create`), so a
/// `conedelta` is an unused parameter there and here.
#[test]
fn spot_conedelta_is_conedeltaangle() {
    assert_src_err(
        "WorldBegin\nLightSource \"spot\"\n \"float conedelta\" 5\n",
        3,
        &["unused parameter \"float conedelta\""],
    );
}

/// kroken's sky: `"blackbody L" 6500 "float scale" 7.5` with a portal. pbrt-v4's portal light
/// converts `L` with `SpectrumToXYZ` and no one-nit normalisation, so its luminance is that of
/// the peak-normalised Planck spectrum, 0.88589 at 6500 K (pbrt-v4's 1 nm CIE table summed in
/// Python), times 7.5; without the portal it is 7.5.
#[test]
fn portal_blackbody_is_not_normalised() {
    let lum = |portal: &str| {
        let s = ok(&format!(
            "WorldBegin\nLightSource \"infinite\" {portal} \"blackbody L\" 6500 \"float scale\" 7.5\n"
        ));
        let Light::Infinite { map } = &s.lights[0] else {
            panic!()
        };
        luminance(map.le(Vec3::Y))
    };
    let with = lum("\"point3 portal\" [ 0 0 0  0 1 0  1 1 0  1 0 0 ]");
    assert!(close(with, 7.5 * 0.885_888_6, 2e-3), "{with}");
    assert!(close(lum(""), 7.5, 1e-3));
}

/// The loader's memory budget gives back what a failed read reserved, keeps what a loaded
/// mesh or image holds, and refuses what passes its limit (issue 22).
#[test]
fn load_budget_accounts_for_failed_and_finished_reads() {
    use photon::scene::loader::{ply::read_ply, textures::read_image, LoadBudget};
    use photon::texture::Encoding;
    let dir = TempDir::new("photon-budget");
    let budget = LoadBudget::new(1 << 30);
    // A truncated PLY (its counts need more data than it holds) and a corrupt PNG.
    dir.write(
        "short.ply",
        "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n\
         property float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n",
    );
    assert!(read_ply(&dir.0.join("short.ply"), &budget).is_err());
    assert_eq!(budget.held(), 0, "a failed PLY read keeps nothing");
    let mut png = Vec::new();
    image::RgbImage::new(4, 4)
        .write_to(&mut std::io::Cursor::new(&mut png), image::ImageFormat::Png)
        .unwrap();
    png.truncate(png.len() - 20);
    std::fs::write(dir.0.join("bad.png"), &png).unwrap();
    assert!(read_image(&dir.0.join("bad.png"), Encoding::Srgb, &budget).is_err());
    assert_eq!(budget.held(), 0, "a failed decode keeps nothing");
    // A good mesh keeps 32 B a vertex and 24 B a face; a good 4x4 image 12 B a texel.
    dir.write(
        "tri.ply",
        "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n\
         property float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n\
         0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n",
    );
    read_ply(&dir.0.join("tri.ply"), &budget).unwrap();
    assert_eq!(budget.held(), 3 * 32 + 24);
    let good = dir.0.join("good.png");
    image::RgbImage::new(4, 4).save(&good).unwrap();
    let fresh = LoadBudget::new(1 << 30);
    read_image(&good, Encoding::Srgb, &fresh).unwrap();
    assert_eq!(fresh.held(), 16 * 12);
    // The decode's peak was reserved first: 16 texels x (3 + 12 + 12) B.
    assert_eq!(fresh.peak(), 16 * 27);
    let tight = LoadBudget::new(100);
    let err = read_image(&good, Encoding::Srgb, &tight).unwrap_err();
    assert!(err.contains("decoding it needs 432 B"), "{err}");
    assert_eq!(tight.held(), 0);
}
