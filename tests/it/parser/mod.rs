//! Tests of the pbrt-v4 loader: the three shared scenes, every supported directive against
//! hand-computed values, and every error path with its exact `file:line`. One file per family
//! of directives; the helpers they share are here.
//!
//! Scenes written by the tests go to a fresh directory under the system temp dir.

mod camera_film_sampler;
mod includes;
mod integrator_options;
mod lights;
mod materials;
mod scenes;
mod shapes;
mod syntax_errors;
mod textures;
mod transforms;

use photon::material::*;
use photon::math::{Mat4, Vec2, Vec3};
use photon::scene::loader::load;
use photon::scene::{FilterDesc, Light, Material, MaterialKind, Scene, SceneError};
use photon::spectrum::Spectrum;
use std::f32::consts::PI;
use std::path::{Path, PathBuf};

use crate::support as common;
use common::TempDir;

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
        Metal::Reflectance(r) => {
            let k = photon::bsdf::k_from_reflectance(Spectrum::from_rgb(r.constant()?));
            (Vec3::ONE, k.rgb())
        }
    };
    let (au, av) = roughness.constant()?;
    Some((eta, k, au, av))
}

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
