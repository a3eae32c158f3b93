//! Transforms: `Translate`/`Rotate`/`Scale`/`Transform`/`ConcatTransform`/`LookAt`,
//! coordinate systems, attribute and transform blocks, orientation, normals; object instancing;
//! `ActiveTransform`.

use super::*;

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
