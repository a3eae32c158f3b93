//! `Shape`: spheres, triangle meshes, PLY files (ASCII, binary, and their errors), disks and
//! cylinders (analytic area, bounds and normals).

use super::*;

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
