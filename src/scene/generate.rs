//! Generated test and benchmark geometry: a bumpy UV sphere of any size, and a complete scene
//! around it (floor, point light, camera) that every pass of the renderer can run on.
//!
//! The scene is built in memory, not read from a file; written as pbrt-v4 it would be
//! ```text
//! LookAt 0 -4.5 1.2  0 0 0  0 0 1
//! Camera "perspective" "float fov" [ 40 ]
//! Film "rgb" "integer xresolution" [ 256 ] "integer yresolution" [ 256 ]
//! WorldBegin
//! LightSource "point" "rgb I" [ 30 30 30 ] "point3 from" [ 2 -2 4 ]
//! Material "diffuse" "rgb reflectance" [ 0.6 0.6 0.6 ]
//! Shape "trianglemesh" ...   # the bumpy sphere (radius ~1, centre 0)
//! Shape "trianglemesh" ...   # floor z = -1.1, 8 x 8
//! ```
use crate::math::{Mat4, Vec3};
use crate::scene::{CameraDesc, Light, Material, MaterialKind, Mesh, Scene};
use std::path::PathBuf;

/// A bumpy UV sphere of `2 * nlat * nlon + 3` triangles around the origin (radius 1 +- 5 %).
/// The pole rows are zero-area (their two top or bottom corners coincide), and three explicit
/// zero-area triangles (collinear and coincident corners) cross the middle: the degenerate
/// cases a backend must never report as hits.
pub fn bumpy_sphere(nlat: u32, nlon: u32) -> Mesh {
    let (nlat, nlon) = (nlat.max(1), nlon.max(3));
    let mut positions = Vec::with_capacity(((nlat + 1) * (nlon + 1) + 4) as usize);
    for i in 0..=nlat {
        let theta = std::f32::consts::PI * i as f32 / nlat as f32;
        for j in 0..=nlon {
            let phi = std::f32::consts::TAU * j as f32 / nlon as f32;
            let r = 1.0 + 0.05 * (7.0 * theta).sin() * (11.0 * phi).cos();
            positions.push(
                r * Vec3::new(
                    theta.sin() * phi.cos(),
                    theta.sin() * phi.sin(),
                    theta.cos(),
                ),
            );
        }
    }
    let w = nlon + 1;
    let mut indices = Vec::with_capacity((2 * nlat * nlon + 3) as usize);
    for i in 0..nlat {
        for j in 0..nlon {
            let (a, b) = (i * w + j, i * w + j + 1);
            let (c, d) = ((i + 1) * w + j, (i + 1) * w + j + 1);
            indices.push([a, c, b]);
            indices.push([b, c, d]);
        }
    }
    let base = positions.len() as u32;
    positions.extend([
        Vec3::new(-2.0, 0.0, 0.0),
        Vec3::new(0.0, 0.0, 0.0),
        Vec3::new(2.0, 0.0, 0.0),
        Vec3::new(0.0, 0.0, 0.3),
    ]);
    indices.extend([
        [base, base + 1, base + 2],
        [base + 3, base + 3, base + 3],
        [base + 1, base + 3, base + 3],
    ]);
    Mesh {
        positions,
        indices,
        ..Default::default()
    }
}

/// Grid size `(nlat, nlon)` of a bumpy sphere with at least `triangles` triangles.
pub fn sphere_grid(triangles: usize) -> (u32, u32) {
    let n = ((triangles as f64 / 2.0).sqrt().ceil() as u32).max(3);
    (n, n)
}

/// A complete scene around a bumpy sphere of at least `triangles` triangles: a floor under
/// it, one point light, a camera looking at it (see the module docs), 256 x 256, 1 spp, the
/// photon-mapping integrator with default parameters. Named `sphere-<triangles>`.
pub fn sphere_scene(triangles: usize) -> Scene {
    let (nlat, nlon) = sphere_grid(triangles);
    let mut sphere = bumpy_sphere(nlat, nlon);
    sphere.sphere = None;
    let floor = Mesh {
        positions: vec![
            Vec3::new(-4.0, -4.0, -1.1),
            Vec3::new(4.0, -4.0, -1.1),
            Vec3::new(4.0, 4.0, -1.1),
            Vec3::new(-4.0, 4.0, -1.1),
        ],
        indices: vec![[0, 1, 2], [0, 2, 3]],
        ..Default::default()
    };
    let eye = Vec3::new(0.0, -4.5, 1.2);
    // pbrt's LookAt: camera +z towards the target, +x = up x dir, +y = dir x right.
    let dir = (Vec3::ZERO - eye).normalize();
    let right = Vec3::Z.cross(dir).normalize();
    let up = dir.cross(right);
    let world_from_camera = Mat4::from_cols(
        right.extend(0.0),
        up.extend(0.0),
        dir.extend(0.0),
        eye.extend(1.0),
    );
    Scene {
        camera: CameraDesc::pinhole(world_from_camera, 40.0),
        path: PathBuf::from(format!("sphere-{}", short_count(triangles))),
        ..Scene::with_geometry(
            vec![sphere, floor],
            vec![Material::from(MaterialKind::Diffuse(
                crate::material::DiffuseMaterial {
                    reflectance: Vec3::splat(0.6).into(),
                },
            ))],
            vec![Light::Point(crate::light::PointLight {
                pos: Vec3::new(2.0, -2.0, 4.0),
                intensity: Vec3::splat(30.0),
            })],
        )
    }
}

/// `100000` -> `100k`, `1000000` -> `1M`, others as they are.
pub fn short_count(n: usize) -> String {
    if n >= 1_000_000 && n.is_multiple_of(1_000_000) {
        format!("{}M", n / 1_000_000)
    } else if n >= 1000 && n.is_multiple_of(1000) {
        format!("{}k", n / 1000)
    } else {
        n.to_string()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sizes_reach_the_target() {
        for t in [10usize, 1000, 100_000] {
            let s = sphere_scene(t);
            let n = s.meshes[0].indices.len();
            // 2 n^2 + 3 with n = ceil(sqrt(t / 2)): at least t, less than t + 4 sqrt(2 t) + 8.
            assert!(n >= t, "{t}: {n}");
            assert!((n as f64) < t as f64 + 4.0 * (2.0 * t as f64).sqrt() + 8.0);
            assert_eq!(s.triangle_count(), n + 2);
        }
        assert_eq!(short_count(1_000_000), "1M");
        assert_eq!(short_count(100_000), "100k");
        assert_eq!(short_count(1234), "1234");
    }

    #[test]
    fn sphere_vertices_are_near_the_unit_sphere() {
        let m = bumpy_sphere(16, 16);
        let n = m.positions.len() - 4;
        for p in &m.positions[..n] {
            assert!((p.length() - 1.0).abs() <= 0.0501, "{p}");
        }
    }
}
