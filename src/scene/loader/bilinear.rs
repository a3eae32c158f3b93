//! `Shape "bilinearmesh"` (pbrt-v4's `BilinearPatchMesh`), tessellated into triangles.
//!
//! ```text
//! Shape "bilinearmesh" "point3 P" [ p00 p10 p01 p11 ... ] "integer indices" [ 0 1 2 3 ... ]
//!     "normal N" [ ... ] "point2 uv" [ ... ] "integer faceIndices" [ ... ]
//! Shape "bilinearmesh" "point3 P" [ 0 0 0  1 0 0  0 1 0  1 1 1 ]   # one patch, no indices
//! ```
//! Each patch is four points in pbrt-v4's order `p00 p10 p01 p11`; its surface is
//! `P(u, v) = lerp(u, lerp(v, p00, p01), lerp(v, p10, p11))` for (u, v) in [0, 1]^2, its normal
//! `dP/du x dP/dv` (at (0, 0): `(p10 - p00) x (p01 - p00)`; negated by `ReverseOrientation` and
//! by a CTM that swaps handedness, as pbrt-v4's). photon renders triangles, so every patch of
//! a mesh becomes an `n x n` grid of cells of two triangles each, with the same `n` for the
//! whole mesh so that neighbouring patches share their edges' vertices (no cracks; an edge's
//! points are computed from its two end points in one order whichever patch asks):
//!
//! - `n` is the smallest whose triangles stay within [`MAX_DEVIATION`] of the patch's diagonal
//!   of the surface: a cell of a patch with twist `c = p00 - p10 - p01 + p11` deviates from its
//!   two triangles by at most `|c . m| / (4 n^2)`, `m` the unit normal of the patch's two
//!   diagonals (the in-plane part of `c` only moves points within the surface). A planar patch
//!   (`c . m = 0`, also one whose corners are no parallelogram) is exactly its two triangles:
//!   `n = 1` (the triangles `p00 p10 p11` and `p00 p11 p01`), unless a curved patch of the
//!   same mesh needs more. `n` is at most [`MAX_CELLS`], and at most what keeps the mesh
//!   within [`MAX_TRIANGLES`]. The area comes out within about as much: +4.1e-4 on the
//!   patch z = uv over the unit square (16 x 16 cells), measured against the integral.
//! - The grid's vertices lie on the patch. Without `N`, a curved patch's vertices get the
//!   surface's analytic normal there (so shading is smooth, as pbrt-v4's patch); a mesh of
//!   planar patches gets none (flat triangles, as a `trianglemesh`). With `N`, the normals
//!   are interpolated bilinearly, as pbrt-v4 does at a hit; with `uv`, the uvs are, and without
//!   it each patch's vertices get its own (u, v), pbrt-v4's default. Inside a cell photon
//!   interpolates linearly over each triangle where pbrt-v4 interpolates bilinearly over the
//!   patch: on a planar patch whose corners are no parallelogram the uv (and `N`) inside the
//!   patch differ slightly from pbrt-v4's, the geometry does not.
//! - `faceIndices` (one per patch, for pbrt-v4's Ptex textures, which photon does not have) is
//!   checked and ignored; pbrt-v4's `emissionfilename` is not supported (an unused parameter).
//!
//! Errors (each at its parameter): no `P`; `indices` missing with other than 4 points, not a
//! multiple of 4, or out of range; `N`, `uv` not one per point; `faceIndices` not one per
//! patch; a zero normal.
use super::params::ParamSet;
use super::shapes::ObjMesh;
use crate::math::{Vec2, Vec3};
use crate::scene::{Loc, SceneError};

/// A curved patch's triangles stay within this fraction of its longer diagonal of the
/// surface.
pub const MAX_DEVIATION: f32 = 5e-4;
/// Cells per side of a patch at most.
pub const MAX_CELLS: u32 = 64;
/// Triangles of one tessellated mesh at most (a mesh of many curved patches gets fewer cells
/// per patch than [`MAX_DEVIATION`] asks for).
pub const MAX_TRIANGLES: u64 = 1 << 21;

/// `Shape "bilinearmesh"` tessellated in object space (see the module docs).
pub fn bilinear_mesh(params: &mut ParamSet, loc: &Loc) -> Result<ObjMesh, SceneError> {
    let err_at = |params: &ParamSet, name: &str, msg: String| match params.peek(name) {
        Some(p) => p.err(msg),
        None => SceneError::at(loc, msg),
    };
    let Some(p) = params.get_point3s("P")? else {
        return Err(SceneError::at(loc, "bilinearmesh needs \"point3 P\""));
    };
    let n = p.len();
    let indices = match params.get_ints("indices")? {
        Some(ix) => {
            if ix.is_empty() || !ix.len().is_multiple_of(4) {
                let msg = format!(
                    "{} indices is not a positive multiple of 4 (p00 p10 p01 p11 per patch)",
                    ix.len()
                );
                return Err(err_at(params, "indices", msg));
            }
            if let Some(k) = ix.iter().position(|&i| i < 0 || i as usize >= n) {
                let msg = format!(
                    "index {} (entry {k}) out of range: there are {n} points",
                    ix[k]
                );
                return Err(err_at(params, "indices", msg));
            }
            ix.iter().map(|&i| i as usize).collect::<Vec<_>>()
        }
        None if n == 4 => vec![0, 1, 2, 3],
        None => {
            return Err(SceneError::at(
                loc,
                format!("bilinearmesh needs \"integer indices\" ({n} points given, not 4)"),
            ))
        }
    };
    let patches = indices.len() / 4;
    let normals = params.get_normals("N")?;
    if let Some(nn) = &normals {
        if nn.len() != n {
            let msg = format!("{} values given for {n} points", nn.len());
            return Err(err_at(params, "N", msg));
        }
        if let Some(i) = nn.iter().position(|v| v.length_squared() == 0.0) {
            return Err(err_at(params, "N", format!("normal {i} is zero")));
        }
    }
    let uvs = params.get_point2s("uv")?;
    if let Some(uv) = &uvs {
        if uv.len() != n {
            let msg = format!("{} values given for {n} points", uv.len());
            return Err(err_at(params, "uv", msg));
        }
    }
    if let Some(f) = params.get_ints("faceIndices")? {
        if f.len() != patches {
            let msg = format!("{} face indices given for {patches} patches", f.len());
            return Err(err_at(params, "faceIndices", msg));
        }
    }
    let corners = |k: usize| -> [usize; 4] {
        [
            indices[4 * k],
            indices[4 * k + 1],
            indices[4 * k + 2],
            indices[4 * k + 3],
        ]
    };
    let cells = (0..patches)
        .map(|k| {
            let c = corners(k);
            cells_for([p[c[0]], p[c[1]], p[c[2]], p[c[3]]])
        })
        .max()
        .unwrap_or(1);
    // The triangle budget: 2 n^2 per patch.
    let budget = ((MAX_TRIANGLES / (2 * patches as u64).max(1)) as f64).sqrt() as u32;
    let cells = cells.min(budget).max(1);
    Ok(tessellate(
        &p,
        &indices,
        normals.as_deref(),
        uvs.as_deref(),
        cells,
    ))
}

/// Cells per side that keep patch `[p00, p10, p01, p11]` within [`MAX_DEVIATION`] (1 for a
/// planar or degenerate one).
pub fn cells_for([p00, p10, p01, p11]: [Vec3; 4]) -> u32 {
    let (d1, d2) = (p11 - p00, p01 - p10);
    let m = d1.cross(d2);
    let len = d1.length().max(d2.length());
    // (NaN compares false: a patch with non-finite points is "degenerate" too.)
    let usable = m.length_squared() > 0.0 && len > 0.0;
    if !usable {
        return 1;
    }
    let twist = (p00 - p10 - p01 + p11).dot(m.normalize()).abs();
    let n = (twist / (4.0 * MAX_DEVIATION * len)).sqrt().ceil();
    if n.is_finite() {
        (n as u32).clamp(1, MAX_CELLS)
    } else {
        MAX_CELLS
    }
}

/// `(1 - t) a + t b`, exact at both ends, and the same whichever end is `a` (an edge's points
/// are computed in one order, by the bits of the ends, so neighbouring patches share them).
fn edge_point(a: Vec3, b: Vec3, k: u32, n: u32) -> Vec3 {
    let key = |v: Vec3| [v.x.to_bits(), v.y.to_bits(), v.z.to_bits()];
    let (a, b, k) = if key(a) <= key(b) {
        (a, b, k)
    } else {
        (b, a, n - k)
    };
    if k == 0 {
        return a;
    }
    if k == n {
        return b;
    }
    let t = k as f32 / n as f32;
    a * (1.0 - t) + b * t
}

fn lerp<T>(t: f32, a: T, b: T) -> T
where
    T: std::ops::Mul<f32, Output = T> + std::ops::Add<Output = T>,
{
    a * (1.0 - t) + b * t
}

/// The mesh of `n x n` cells per patch (vertices of each patch of their own: a patch's
/// default uvs are its own parameters).
fn tessellate(
    p: &[Vec3],
    indices: &[usize],
    normals: Option<&[Vec3]>,
    uvs: Option<&[Vec2]>,
    n: u32,
) -> ObjMesh {
    let patches = indices.len() / 4;
    let per_patch = ((n + 1) * (n + 1)) as usize;
    let mut out = ObjMesh {
        positions: Vec::with_capacity(patches * per_patch),
        indices: Vec::with_capacity(patches * 2 * (n * n) as usize),
        uvs: Some(Vec::with_capacity(patches * per_patch)),
        normals: None,
    };
    let curved = n > 1;
    let mut out_normals = Vec::new();
    for c in indices.chunks_exact(4) {
        let [p00, p10, p01, p11] = [p[c[0]], p[c[1]], p[c[2]], p[c[3]]];
        let base = out.positions.len() as u32;
        for j in 0..=n {
            let v = j as f32 / n as f32;
            // The patch's edges u = 0 and u = 1 at this v, shared with neighbours.
            let (left, right) = (edge_point(p00, p01, j, n), edge_point(p10, p11, j, n));
            for i in 0..=n {
                let u = i as f32 / n as f32;
                let pos = if j == 0 {
                    edge_point(p00, p10, i, n)
                } else if j == n {
                    edge_point(p01, p11, i, n)
                } else if i == 0 {
                    left
                } else if i == n {
                    right
                } else {
                    lerp(u, left, right)
                };
                out.positions.push(pos);
                let uv = match uvs {
                    Some(t) => lerp(u, lerp(v, t[c[0]], t[c[2]]), lerp(v, t[c[1]], t[c[3]])),
                    None => Vec2::new(u, v),
                };
                out.uvs.as_mut().expect("set above").push(uv);
                match normals {
                    Some(nn) => out_normals.push(lerp(
                        u,
                        lerp(v, nn[c[0]], nn[c[2]]),
                        lerp(v, nn[c[1]], nn[c[3]]),
                    )),
                    None if curved => {
                        let dpdu = lerp(v, p10, p11) - lerp(v, p00, p01);
                        let dpdv = lerp(u, p01, p11) - lerp(u, p00, p10);
                        out_normals.push(dpdu.cross(dpdv));
                    }
                    None => {}
                }
            }
        }
        for j in 0..n {
            for i in 0..n {
                let v00 = base + j * (n + 1) + i;
                let (v10, v01, v11) = (v00 + 1, v00 + n + 1, v00 + n + 2);
                out.indices.push([v00, v10, v11]);
                out.indices.push([v00, v11, v01]);
            }
        }
    }
    if normals.is_some() || curved {
        // Unit normals; where the surface's normal vanishes (a degenerate corner) or the given
        // ones cancel, the triangle's own orientation decides (a zero normal means flat).
        out.normals = Some(fix_normals(&out, out_normals));
    }
    out
}

/// Normalises `nn`; a zero one takes the normal of the first triangle that uses its vertex
/// (or +z when that is degenerate too).
fn fix_normals(mesh: &ObjMesh, mut nn: Vec<Vec3>) -> Vec<Vec3> {
    for t in &mesh.indices {
        let [a, b, c] = t.map(|i| mesh.positions[i as usize]);
        let face = (b - a).cross(c - a).normalize_or(Vec3::Z);
        for &i in t {
            let v = &mut nn[i as usize];
            if !(v.length_squared() > 0.0 && v.is_finite()) {
                *v = face;
            }
        }
    }
    nn.into_iter().map(|v| v.normalize_or(Vec3::Z)).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn area(m: &ObjMesh) -> f64 {
        m.indices
            .iter()
            .map(|t| {
                let [a, b, c] = t.map(|i| m.positions[i as usize].as_dvec3());
                0.5 * (b - a).cross(c - a).length()
            })
            .sum()
    }

    /// A planar patch (also a non-parallelogram one) is two triangles with the corners' own
    /// points; the hyperbolic paraboloid z = uv gets 16 cells and its area within 6e-4 of the
    /// integral of sqrt(1 + u^2 + v^2).
    #[test]
    fn planar_two_triangles_curved_grid() {
        let flat = [
            Vec3::ZERO,
            Vec3::new(2.0, 0.0, 0.0),
            Vec3::new(0.0, 1.0, 0.0),
            Vec3::new(3.0, 2.0, 0.0),
        ];
        assert_eq!(cells_for(flat), 1);
        let m = tessellate(&flat, &[0, 1, 2, 3], None, None, 1);
        assert_eq!(m.indices, vec![[0, 1, 3], [0, 3, 2]]);
        assert_eq!(m.positions, flat.to_vec());
        assert!(m.normals.is_none());
        let saddle = [Vec3::ZERO, Vec3::X, Vec3::Y, Vec3::new(1.0, 1.0, 1.0)];
        let n = cells_for(saddle);
        assert_eq!(n, 16);
        let m = tessellate(&saddle, &[0, 1, 2, 3], None, None, n);
        let k = 2000;
        let exact: f64 = (0..k * k)
            .map(|i| {
                let (u, v) = (
                    ((i % k) as f64 + 0.5) / k as f64,
                    ((i / k) as f64 + 0.5) / k as f64,
                );
                (1.0 + u * u + v * v).sqrt()
            })
            .sum::<f64>()
            / (k * k) as f64;
        // Measured: +4.08e-4 (the triangles' tilt across each cell; spheres: -5.0e-4).
        let rel = area(&m) / exact - 1.0;
        assert!(rel.abs() < 6e-4, "{rel}");
        // Analytic normals at the grid's vertices, upwards in z for z = uv at (0, 0).
        let nn = m.normals.as_ref().unwrap();
        assert!((nn[0] - Vec3::Z).length() < 1e-6, "{}", nn[0]);
    }

    /// Two patches sharing an edge (given in opposite directions) share its vertices exactly.
    #[test]
    fn shared_edges_are_identical() {
        let p = [
            Vec3::new(0.1, 0.0, 0.0),
            Vec3::new(1.0, 0.3, 0.2),
            Vec3::new(0.0, 1.0, 0.7),
            Vec3::new(1.3, 1.1, -0.4),
            Vec3::new(2.0, 0.0, 0.5),
            Vec3::new(2.2, 1.0, 0.1),
        ];
        // Patch A: 0 1 2 3 (edge u = 1 from p1 to p3); patch B: 3 5 1 4 (edge u = 0 from p3 to p1).
        let m = tessellate(&p, &[0, 1, 2, 3, 3, 5, 1, 4], None, None, 7);
        let (a, b) = m.positions.split_at(64);
        let edge_a: Vec<Vec3> = (0..8).map(|j| a[j * 8 + 7]).collect();
        let mut edge_b: Vec<Vec3> = (0..8).map(|j| b[j * 8]).collect();
        edge_b.reverse();
        assert_eq!(edge_a, edge_b);
    }
}
