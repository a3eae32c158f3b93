//! Turns `Shape` directives into world-space triangle [`Mesh`]es.
//!
//! ```text
//! Shape "trianglemesh" "point3 P" [ ... ] "integer indices" [ ... ]   # "normal N", "point2 uv"
//! Shape "plymesh" "string filename" "meshes/bunny.ply"                  # relative to the main file
//! Shape "sphere" "float radius" 0.5                                     # tessellated, see below
//! Shape "disk" "float radius" 1 "float innerradius" 0.2 "float height" 0 "float phimax" 360
//! Shape "cylinder" "float radius" 1 "float zmin" -1 "float zmax" 1 "float phimax" 360
//! Shape "trianglemesh" ... "float alpha" 0.5          # any shape: a constant alpha in [0, 1]
//! Shape "plymesh" ... "texture alpha" "leafmask"      # or a float texture
//! ```
//!
//! `alpha` ([`alpha`]) follows pbrt-v4's `GetAlphaTexture`: a `"texture alpha"` names a float
//! texture defined earlier; a `"float alpha"` below 1 becomes a constant texture and 1 means no
//! alpha. Unlike pbrt-v4, which takes any number (below 0 acting as 0), a constant outside
//! [0, 1] is an error. How hits are cut out is in [`crate::accel`]. Emitting shapes
//! (`AreaLightSource`) with alpha are errors for now (pbrt-v4 also masks their emission).
//!
//! Positions go through the CTM, normals through its inverse transpose (renormalised) and are
//! negated under `ReverseOrientation`, as pbrt-v4's `TriangleMesh` does. Every triangle is kept,
//! even a degenerate one.
//!
//! Spheres become a latitude-longitude mesh of `n` rings x `2n` segments of quads (triangles
//! at the poles) whose vertices lie exactly on the sphere, with the analytic normals and pbrt's
//! (u, v) = (phi / 2pi, (pi - theta) / pi). `n` is [`SPHERE_RINGS`] (16,128 triangles, area
//! 0.050% short of 4 pi r^2, every point within 6.0e-4 r of the sphere) unless the sphere is
//! not an emitter (whose power goes with its area), small (under 1% of the scene's radius) and
//! far from the camera: then the fewest rings, down to [`MIN_SPHERE_RINGS`] (224 triangles),
//! whose error ([`tessellation_error`]) projects to at most 0.1 pixel at 1024 pixels (see
//! [`sphere_rings`]). Tessellation waits for the end of the file, when the scene's size is
//! known. The CTM must be a similarity (uniform scale, rotation, mirror, translation);
//! `Mesh::sphere` holds the world centre and radius.
//!
//! Disks (in the plane z = `height`, normal +z) and cylinders (around the z axis, normal
//! outward) become [`SWEEP_SEGMENTS`] segments per full turn (fewer for a partial `phimax`),
//! one band of quads from the outer to the inner rim (a fan of triangles when `innerradius` is
//! 0) or from `zmin` to `zmax`. Their vertices lie exactly on the surface, with the analytic
//! normals and pbrt-v4's (u, v): disk (phi / phimax, (radius - r) / (radius - innerradius)),
//! cylinder (phi / phimax, (z - zmin) / (zmax - zmin)). The polygonal rim makes the area short
//! by 1 - sin(d)/d (disk) and 1 - sin(d/2)/(d/2) (cylinder) for a segment angle d: 0.040% and
//! 0.010% at 128 segments. They go to world space like meshes with normals, so the normal is
//! the transformed analytic normal, negated under `ReverseOrientation` (as pbrt-v4's quadrics).
//!
//! Sphere orientation follows pbrt-v4's sphere, whose normal is outward, inward under
//! `ReverseOrientation`, and stays outward under a mirroring CTM (pbrt flips its
//! cross-product normal there, and a similarity maps outward to outward). So the world-space
//! triangles always wind outward (`cross(p1 - p0, p2 - p0)` points away from the centre; the
//! vertex order is swapped under a mirror), the normals are outward, and both turn inward only
//! through `ReverseOrientation`: `flip_normals` is `reverse_orientation` alone for spheres,
//! which keeps the winding rule and the normals in agreement.

use super::params::ParamSet;
use super::ply::read_ply;
use crate::math::{Mat3, Mat4, Vec2, Vec3};
use crate::scene::{clip_for_message, Loc, Mesh, SceneError};
use crate::texture::named_texture;
use crate::texture::{Texture, Textures};
use std::f32::consts::PI;
use std::path::Path;
use std::sync::Arc;

/// Latitude rings of a tessellated sphere.
pub const SPHERE_RINGS: u32 = 64;
/// Longitude segments of a tessellated sphere (SPHERE_RINGS x SPHERE_SEGMENTS gives
/// 2 * 128 * 63 = 16128 triangles and an area deficit of 0.050%).
pub const SPHERE_SEGMENTS: u32 = 128;

/// Segments of a disk or cylinder per full turn of `phimax`.
pub const SWEEP_SEGMENTS: u32 = 128;

/// A triangle mesh in object space, as a shape or a PLY file gives it.
#[derive(Clone, Debug, Default)]
pub struct ObjMesh {
    pub positions: Vec<Vec3>,
    pub normals: Option<Vec<Vec3>>,
    pub uvs: Option<Vec<Vec2>>,
    pub indices: Vec<[u32; 3]>,
}

/// `Shape "trianglemesh"`: `point3 P` (required), `integer indices` (optional only for exactly
/// three points), `normal N` and `point2 uv` (one per point).
pub fn triangle_mesh(params: &mut ParamSet, loc: &Loc) -> Result<ObjMesh, SceneError> {
    let Some(positions) = params.get_point3s("P")? else {
        return Err(SceneError::at(loc, "trianglemesh needs \"point3 P\""));
    };
    let n = positions.len();
    let indices = match params.get_ints("indices")? {
        Some(ix) => {
            triangles_from_ints(&ix, n).map_err(|m| param_err(params, "indices", loc, m))?
        }
        None if n == 3 => vec![[0, 1, 2]],
        None => {
            return Err(SceneError::at(
                loc,
                format!("trianglemesh needs \"integer indices\" ({n} points given, not 3)"),
            ))
        }
    };
    let normals = params.get_normals("N")?;
    if let Some(nn) = &normals {
        check_count(params, "N", loc, nn.len(), n)?;
        if let Some(i) = nn.iter().position(|v| v.length_squared() == 0.0) {
            return Err(param_err(params, "N", loc, format!("normal {i} is zero")));
        }
    }
    let uvs = params.get_point2s("uv")?;
    if let Some(uv) = &uvs {
        check_count(params, "uv", loc, uv.len(), n)?;
    }
    Ok(ObjMesh {
        positions,
        normals,
        uvs,
        indices,
    })
}

/// A shape's `alpha`: the float texture `"texture alpha"` names, or `"float alpha"` as a
/// constant texture when below 1; `None` without alpha (or with alpha 1). A constant must be
/// in [0, 1]; an unknown texture name is an error at the parameter.
pub fn alpha(
    params: &mut ParamSet,
    textures: &Textures,
) -> Result<Option<Arc<Texture>>, SceneError> {
    if let Some(t) = named_texture(params, "alpha", false, textures)? {
        return Ok(Some(t));
    }
    match params.get_float_opt("alpha")? {
        Some(a) if !(0.0..=1.0).contains(&a) => {
            let p = params.peek("alpha").expect("just read");
            Err(p.err(format!("alpha {a} is outside [0, 1]")))
        }
        Some(a) if a < 1.0 => Ok(Some(Arc::new(Texture::Constant(Vec3::splat(a))))),
        _ => Ok(None),
    }
}

/// An error at parameter `name` (or at `loc` if it somehow is not there).
fn param_err(params: &ParamSet, name: &str, loc: &Loc, msg: impl std::fmt::Display) -> SceneError {
    match params.peek(name) {
        Some(p) => p.err(msg),
        None => SceneError::at(loc, msg.to_string()),
    }
}

/// Per-vertex data must have one value per point.
fn check_count(
    params: &ParamSet,
    name: &str,
    loc: &Loc,
    got: usize,
    want: usize,
) -> Result<(), SceneError> {
    if got == want {
        return Ok(());
    }
    Err(param_err(
        params,
        name,
        loc,
        format!("{got} values given for {want} points"),
    ))
}

/// Groups vertex indices in threes, checking each names one of `n` points.
fn triangles_from_ints(ix: &[i32], n: usize) -> Result<Vec<[u32; 3]>, String> {
    if !ix.len().is_multiple_of(3) {
        return Err(format!("{} indices is not a multiple of 3", ix.len()));
    }
    if let Some(pos) = ix.iter().position(|&i| i < 0 || i as usize >= n) {
        return Err(format!(
            "index {} (entry {pos}) out of range: there are {n} points",
            ix[pos]
        ));
    }
    Ok(ix
        .chunks_exact(3)
        .map(|c| [c[0] as u32, c[1] as u32, c[2] as u32])
        .collect())
}

/// `Shape "plymesh"`: `string filename`, relative to `base_dir` (the main file's directory).
/// Errors name the Shape's location and the PLY file.
pub fn ply_mesh(
    params: &mut ParamSet,
    loc: &Loc,
    base_dir: &Path,
    budget: &super::LoadBudget,
) -> Result<ObjMesh, SceneError> {
    let Some(name) = params.get_string_opt("filename")? else {
        return Err(SceneError::at(loc, "plymesh needs \"string filename\""));
    };
    let path = base_dir.join(&name);
    let mesh = read_ply(&path, budget).map_err(|m| {
        SceneError::at(
            loc,
            format!("plymesh \"{}\": {m}", clip_for_message(&name, 60)),
        )
    })?;
    if let Some(nn) = &mesh.normals {
        if let Some(i) = nn.iter().position(|v| v.length_squared() == 0.0) {
            return Err(SceneError::at(
                loc,
                format!(
                    "plymesh \"{}\": normal of vertex {i} is zero",
                    clip_for_message(&name, 60)
                ),
            ));
        }
    }
    Ok(mesh)
}

/// Applies a possibly projective transform to a point.
pub fn xform_point(m: &Mat4, p: Vec3) -> Vec3 {
    let v = *m * p.extend(1.0);
    if v.w == 1.0 {
        v.truncate()
    } else {
        v.truncate() / v.w
    }
}

/// Every world-space vertex must be finite (a zero or projective `Transform`, or translations
/// that overflow, make them infinite or NaN).
fn check_finite(positions: &[Vec3], loc: &Loc) -> Result<(), SceneError> {
    match positions.iter().position(|p| !p.is_finite()) {
        None => Ok(()),
        Some(i) => Err(SceneError::at(
            loc,
            format!(
                "vertex {i} is not finite after the current transform ({}): check Transform, Scale and Translate",
                positions[i]
            ),
        )),
    }
}

/// Whether `m` swaps handedness (its linear part has a negative determinant).
pub fn swaps_handedness(m: &Mat4) -> bool {
    Mat3::from_mat4(*m).determinant() < 0.0
}

/// Moves an object-space mesh to world space through `ctm`; `reverse` is the
/// `ReverseOrientation` state.
pub fn to_world(obj: ObjMesh, ctm: &Mat4, reverse: bool, loc: &Loc) -> Result<Mesh, SceneError> {
    let positions: Vec<Vec3> = obj.positions.iter().map(|&p| xform_point(ctm, p)).collect();
    check_finite(&positions, loc)?;
    let normals = match obj.normals {
        Some(nn) => {
            // In f64: the determinant of a 1e20 scale overflows f32.
            let lin = Mat3::from_mat4(*ctm).as_dmat3();
            if lin.determinant() == 0.0 || !lin.determinant().is_finite() {
                return Err(SceneError::at(
                    loc,
                    "cannot transform normals: the CTM is singular",
                ));
            }
            let nm = lin.inverse().transpose();
            let sign = if reverse { -1.0 } else { 1.0 };
            Some(
                nn.iter()
                    .map(|&n| sign * (nm * n.as_dvec3()).normalize().as_vec3())
                    .collect(),
            )
        }
        None => None,
    };
    Ok(Mesh {
        positions,
        normals,
        uvs: obj.uvs,
        indices: obj.indices,
        flip_normals: reverse ^ swaps_handedness(ctm),
        ..Mesh::default()
    })
}

/// A world-space mesh moved by `m` (an object instance): positions through `m`, normals
/// through its inverse transpose; an analytic sphere stays one under a similarity and keeps
/// its outward winding under a mirror (see the module docs), other meshes flip their
/// orientation when `m` swaps handedness. The copy's arrays are reserved fallibly.
pub fn transform_mesh(mesh: &Mesh, m: &Mat4) -> Result<Mesh, String> {
    let lin = Mat3::from_mat4(*m);
    if lin.determinant() == 0.0 || !lin.determinant().is_finite() {
        return Err("the instance transform is singular".to_string());
    }
    let oom = |_| "out of memory copying the instance".to_string();
    let mut positions = Vec::new();
    positions
        .try_reserve_exact(mesh.positions.len())
        .map_err(oom)?;
    positions.extend(mesh.positions.iter().map(|&p| xform_point(m, p)));
    let mut indices = Vec::new();
    indices.try_reserve_exact(mesh.indices.len()).map_err(oom)?;
    indices.extend_from_slice(&mesh.indices);
    let normals = match &mesh.normals {
        Some(nn) => {
            let nm = lin.inverse().transpose();
            let mut out = Vec::new();
            out.try_reserve_exact(nn.len()).map_err(oom)?;
            out.extend(nn.iter().map(|&n| (nm * n).normalize()));
            Some(out)
        }
        None => None,
    };
    let mirror = swaps_handedness(m);
    let sphere = mesh
        .sphere
        .and_then(|(c, r)| similarity_scale(m).map(|s| (xform_point(m, c), r * s)));
    let flip_normals = if mesh.sphere.is_some() {
        if mirror {
            indices.iter_mut().for_each(|t| t.swap(1, 2));
        }
        mesh.flip_normals
    } else {
        mesh.flip_normals ^ mirror
    };
    Ok(Mesh {
        positions,
        normals,
        uvs: mesh.uvs.clone(),
        indices,
        material: mesh.material,
        area_light: None,
        flip_normals,
        sphere,
        alpha: mesh.alpha.clone(),
        interface: mesh.interface,
    })
}

/// The uniform scale of `m` if it is a similarity (orthogonal linear part times a scale, no
/// projective row), else `None`.
pub fn similarity_scale(m: &Mat4) -> Option<f32> {
    let row3 = m.row(3);
    if row3.x.abs() > 1e-6 || row3.y.abs() > 1e-6 || row3.z.abs() > 1e-6 || row3.w <= 0.0 {
        return None;
    }
    let lin = Mat3::from_mat4(*m) * (1.0 / row3.w);
    let gram = lin.transpose() * lin;
    let s2 = (gram.x_axis.x + gram.y_axis.y + gram.z_axis.z) / 3.0;
    if !(s2 > 0.0 && s2.is_finite()) {
        return None;
    }
    let err = (gram - Mat3::from_diagonal(Vec3::splat(s2))).to_cols_array();
    if err.iter().any(|e| e.abs() > 1e-4 * s2) {
        return None;
    }
    Some(s2.sqrt())
}

/// A sphere as the scene gives it, waiting for its tessellation (which depends on the whole
/// scene's size and the camera: see [`sphere_rings`]).
#[derive(Clone, Debug)]
pub struct SphereSpec {
    pub centre: Vec3,
    pub radius: f32,
    /// The CTM's rotation (and mirror) without its scale.
    rot: Mat3,
    mirror: bool,
    reverse: bool,
}

/// `Shape "sphere"`: `float radius` (default 1); `zmin`, `zmax`, `phimax` only at their
/// full-sphere defaults. Returns the world-space sphere and an untessellated mesh with
/// `Mesh::sphere` set ([`tessellate`] fills it in).
pub fn sphere(
    params: &mut ParamSet,
    loc: &Loc,
    ctm: &Mat4,
    reverse: bool,
) -> Result<(SphereSpec, Mesh), SceneError> {
    let r = params.get_float("radius", 1.0)?;
    if r.is_nan() || r <= 0.0 {
        return Err(param_err(
            params,
            "radius",
            loc,
            "the radius must be positive",
        ));
    }
    for (name, full) in [("zmin", -r), ("zmax", r), ("phimax", 360.0)] {
        let v = params.get_float(name, full)?;
        if (v - full).abs() > 1e-6 * full.abs().max(1.0) {
            return Err(param_err(
                params,
                name,
                loc,
                "partial spheres are not supported",
            ));
        }
    }
    let Some(s) = similarity_scale(ctm) else {
        return Err(SceneError::at(
            loc,
            "a sphere's transform must be a similarity (uniform scale, rotation, translation)",
        ));
    };
    let centre = xform_point(ctm, Vec3::ZERO);
    let radius = r * s;
    if !centre.is_finite() || !radius.is_finite() {
        return Err(SceneError::at(
            loc,
            "the sphere is not finite after the current transform: check Transform, Scale and Translate",
        ));
    }
    let spec = SphereSpec {
        centre,
        radius,
        rot: Mat3::from_mat4(*ctm) * (1.0 / (s * ctm.row(3).w)),
        mirror: swaps_handedness(ctm),
        reverse,
    };
    let mesh = Mesh {
        flip_normals: reverse,
        sphere: Some((centre, radius)),
        ..Mesh::default()
    };
    Ok((spec, mesh))
}

/// Largest distance between the tessellation of `unit_sphere(rings)` and the unit sphere
/// (at the middle of the widest quads, whose corners lie on the sphere): `1 - cos^2(pi / 2n)`.
/// 6.0e-4 at 64 rings, 3.8e-2 at 8.
pub fn tessellation_error(rings: u32) -> f32 {
    let h = (std::f64::consts::PI / (2.0 * rings as f64)).cos();
    (1.0 - h * h) as f32
}

/// Fewest latitude rings of a sphere (segments are twice as many).
pub const MIN_SPHERE_RINGS: u32 = 8;
/// A sphere of at least this fraction of the scene's bounding radius always gets
/// [`SPHERE_RINGS`] (its tessellation error stays below 6.0e-4 of its radius).
pub const FULL_SPHERE_FRACTION: f32 = 0.01;
/// Otherwise its tessellation error, seen from the camera, stays below this many pixels at
/// [`REFERENCE_PIXELS`] across the shorter image side (or the Film's, if larger).
pub const MAX_SCREEN_ERROR: f32 = 0.1;
pub const REFERENCE_PIXELS: u32 = 1024;

/// Rings for `spec` in a scene of bounding radius `scene_radius`, seen by `camera` on `film`:
/// [`SPHERE_RINGS`] for a sphere that is not small in the scene or that the camera is close
/// to; for a small distant one the fewest (down to [`MIN_SPHERE_RINGS`]) whose
/// [`tessellation_error`] projects to at most [`MAX_SCREEN_ERROR`] pixels. So 10,000 tiny
/// spheres cost 224 triangles each instead of 16,128.
pub fn sphere_rings(
    spec: &SphereSpec,
    scene_radius: f32,
    camera: &crate::scene::CameraDesc,
    film: &crate::scene::FilmDesc,
) -> u32 {
    if spec.radius >= FULL_SPHERE_FRACTION * scene_radius {
        return SPHERE_RINGS;
    }
    let pixels = film.xres.min(film.yres).max(REFERENCE_PIXELS) as f32;
    let w = &camera.world_from_camera;
    let projected = if camera.projection == crate::scene::Projection::Orthographic {
        // The radius over the world width of one pixel across the window's shorter side.
        let side = camera
            .screen_window
            .map_or(2.0, |[x0, x1, y0, y1]| (x1 - x0).min(y1 - y0));
        let scale = w.transform_vector3(Vec3::X).length();
        spec.radius * pixels / (side * scale)
    } else {
        let eye = w.transform_point3(Vec3::ZERO);
        let dist = (spec.centre - eye).length() - spec.radius;
        if dist.is_nan() || dist <= spec.radius {
            return SPHERE_RINGS;
        }
        let focal = 0.5 * pixels / (0.5 * camera.fov_deg.to_radians()).tan();
        spec.radius / dist * focal
    };
    if !projected.is_finite() {
        return SPHERE_RINGS;
    }
    (MIN_SPHERE_RINGS..SPHERE_RINGS)
        .find(|&n| projected * tessellation_error(n) <= MAX_SCREEN_ERROR)
        .unwrap_or(SPHERE_RINGS)
}

/// Fills `mesh` (made by [`sphere`]) with the world-space tessellation of `spec` at `rings`
/// latitude rings and `2 rings` segments.
pub fn tessellate(spec: &SphereSpec, rings: u32, mesh: &mut Mesh) {
    let mut m = unit_sphere(rings, 2 * rings);
    let sign = if spec.reverse { -1.0 } else { 1.0 };
    let mut normals = Vec::with_capacity(m.positions.len());
    for p in m.positions.iter_mut() {
        let n = (spec.rot * *p).normalize();
        *p = spec.centre + spec.radius * n;
        normals.push(sign * n);
    }
    // Object-space outward winding becomes inward in world space under a mirror: swap.
    if spec.mirror {
        for t in m.indices.iter_mut() {
            t.swap(1, 2);
        }
    }
    mesh.positions = m.positions;
    mesh.normals = Some(normals);
    mesh.uvs = m.uvs;
    mesh.indices = m.indices;
}

/// `phimax` of a disk or cylinder in radians: degrees clamped to [0, 360] as pbrt-v4 does, and
/// positive.
fn phi_max(params: &mut ParamSet, loc: &Loc) -> Result<f32, SceneError> {
    let deg = params.get_float("phimax", 360.0)?;
    if deg.is_nan() || deg <= 0.0 {
        return Err(param_err(params, "phimax", loc, "phimax must be positive"));
    }
    Ok(deg.min(360.0).to_radians())
}

/// A `float` parameter that must be positive.
fn positive(params: &mut ParamSet, name: &str, default: f32, loc: &Loc) -> Result<f32, SceneError> {
    let v = params.get_float(name, default)?;
    if v.is_nan() || v <= 0.0 {
        return Err(param_err(
            params,
            name,
            loc,
            format!("{name} must be positive"),
        ));
    }
    Ok(v)
}

/// `Shape "disk"`: `radius` (1), `innerradius` (0), `height` (0), `phimax` (360), tessellated in
/// object space (see the module docs).
pub fn disk(params: &mut ParamSet, loc: &Loc) -> Result<ObjMesh, SceneError> {
    let radius = positive(params, "radius", 1.0, loc)?;
    let inner = params.get_float("innerradius", 0.0)?;
    if !(0.0..radius).contains(&inner) {
        return Err(param_err(
            params,
            "innerradius",
            loc,
            "innerradius must lie in [0, radius)",
        ));
    }
    let height = params.get_float("height", 0.0)?;
    let phi_max = phi_max(params, loc)?;
    Ok(band(phi_max, inner == 0.0, |c, s, u, ring| {
        let r = if ring == 0 { radius } else { inner };
        let v = if ring == 0 { 0.0 } else { 1.0 };
        (Vec3::new(r * c, r * s, height), Vec3::Z, Vec2::new(u, v))
    }))
}

/// `Shape "cylinder"`: `radius` (1), `zmin` (-1), `zmax` (1), `phimax` (360), tessellated in
/// object space (see the module docs). `zmin` and `zmax` are ordered as pbrt-v4 does.
pub fn cylinder(params: &mut ParamSet, loc: &Loc) -> Result<ObjMesh, SceneError> {
    let radius = positive(params, "radius", 1.0, loc)?;
    let (z0, z1) = (
        params.get_float("zmin", -1.0)?,
        params.get_float("zmax", 1.0)?,
    );
    if z0 == z1 {
        return Err(param_err(params, "zmax", loc, "zmin and zmax must differ"));
    }
    let (zmin, zmax) = (z0.min(z1), z0.max(z1));
    let phi_max = phi_max(params, loc)?;
    Ok(band(phi_max, false, |c, s, u, ring| {
        let (z, v) = if ring == 0 { (zmin, 0.0) } else { (zmax, 1.0) };
        (
            Vec3::new(radius * c, radius * s, z),
            Vec3::new(c, s, 0.0),
            Vec2::new(u, v),
        )
    }))
}

/// Two rings of vertices swept over `phi_max` (`vertex(cos phi, sin phi, u, ring)` gives the
/// position, normal and uv), joined by quads split as `(a b c)`, `(b d c)` with `a b` on ring 0
/// and `c d` on ring 1; `fan` keeps only `(a b c)` (ring 1 is a single point). A full turn
/// reuses the first angle's sine and cosine for the last vertices so the seam closes exactly.
fn band(
    phi_max: f32,
    fan: bool,
    vertex: impl Fn(f32, f32, f32, u32) -> (Vec3, Vec3, Vec2),
) -> ObjMesh {
    let full = phi_max >= 2.0 * PI;
    let segs = ((SWEEP_SEGMENTS as f32 * phi_max / (2.0 * PI)).ceil() as u32).max(1);
    let mut mesh = ObjMesh::default();
    let (mut normals, mut uvs) = (Vec::new(), Vec::new());
    for ring in 0..2 {
        for j in 0..=segs {
            let u = j as f32 / segs as f32;
            let phi = if full && j == segs { 0.0 } else { phi_max * u };
            let (p, n, uv) = vertex(phi.cos(), phi.sin(), u, ring);
            mesh.positions.push(p);
            normals.push(n);
            uvs.push(uv);
        }
    }
    let w = segs + 1;
    for j in 0..segs {
        let (a, b, c, d) = (j, j + 1, w + j, w + j + 1);
        mesh.indices.push([a, b, c]);
        if !fan {
            mesh.indices.push([b, d, c]);
        }
    }
    mesh.normals = Some(normals);
    mesh.uvs = Some(uvs);
    mesh
}

/// The unit sphere tessellated in object space: positions are the unit normals.
fn unit_sphere(rings: u32, segs: u32) -> Mesh {
    let at = |theta: f32, phi: f32| {
        Vec3::new(
            theta.sin() * phi.cos(),
            theta.sin() * phi.sin(),
            theta.cos(),
        )
    };
    let mut positions = Vec::new();
    let mut uvs = Vec::new();
    // Poles: one vertex per segment so each pole triangle gets its own u.
    for (theta, v) in [(0.0f32, 1.0f32), (PI, 0.0)] {
        for j in 0..segs {
            positions.push(at(theta, 0.0));
            uvs.push(Vec2::new((j as f32 + 0.5) / segs as f32, v));
        }
    }
    // Inner rings 1..rings-1, each with segs + 1 vertices (the seam is duplicated for uv).
    let ring_base = positions.len() as u32;
    for i in 1..rings {
        let theta = PI * i as f32 / rings as f32;
        for j in 0..=segs {
            let u = j as f32 / segs as f32;
            positions.push(at(theta, 2.0 * PI * u));
            uvs.push(Vec2::new(u, 1.0 - i as f32 / rings as f32));
        }
    }
    let ring = |i: u32, j: u32| ring_base + (i - 1) * (segs + 1) + j;
    let mut indices = Vec::new();
    for i in 0..rings {
        for j in 0..segs {
            // a b on ring i (theta0), c d on ring i + 1 (theta1); (a c b) and (b c d) wind
            // outward since d(theta) x d(phi) is the outward normal.
            if i == 0 {
                indices.push([j, ring(1, j), ring(1, j + 1)]);
            } else if i == rings - 1 {
                indices.push([ring(i, j), segs + j, ring(i, j + 1)]);
            } else {
                let (a, b) = (ring(i, j), ring(i, j + 1));
                let (c, d) = (ring(i + 1, j), ring(i + 1, j + 1));
                indices.push([a, c, b]);
                indices.push([b, c, d]);
            }
        }
    }
    Mesh {
        positions,
        uvs: Some(uvs),
        indices,
        ..Mesh::default()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn unit_sphere_area_and_winding() {
        let m = unit_sphere(SPHERE_RINGS, SPHERE_SEGMENTS);
        let area: f64 = (0..m.indices.len() as u32).map(|t| m.area(t) as f64).sum();
        let deficit = 1.0 - area / (4.0 * std::f64::consts::PI);
        assert!(deficit > 0.0 && deficit < 1e-3, "deficit {deficit}");
        for t in 0..m.indices.len() as u32 {
            let [p0, p1, p2] = m.triangle(t);
            let c = (p1 - p0).cross(p2 - p0);
            assert!(c.dot(p0 + p1 + p2) > 0.0, "triangle {t} winds inward");
        }
    }

    /// Every point of every triangle (sampled on a barycentric grid) lies within
    /// `tessellation_error(n)` of the unit sphere, and the bound is tight within 10%.
    #[test]
    fn tessellation_error_bounds_the_distance_to_the_sphere() {
        for n in [MIN_SPHERE_RINGS, 12, 24, SPHERE_RINGS] {
            let m = unit_sphere(n, 2 * n);
            let bound = tessellation_error(n);
            let mut worst = 0.0f32;
            for t in 0..m.indices.len() as u32 {
                for i in 0..=8 {
                    for j in 0..=8 - i {
                        let p = m.point(t, i as f32 / 8.0, j as f32 / 8.0);
                        worst = worst.max(1.0 - p.length());
                    }
                }
            }
            assert!(worst <= bound * 1.0001, "{n} rings: {worst} > {bound}");
            assert!(worst > 0.9 * bound, "{n} rings: {worst} much below {bound}");
        }
        assert!((tessellation_error(64) - 6.0e-4).abs() < 1e-5);
    }

    #[test]
    fn similarity_detection() {
        let m = Mat4::from_scale_rotation_translation(
            Vec3::splat(2.0),
            glam::Quat::from_rotation_y(0.3),
            Vec3::ONE,
        );
        assert!((similarity_scale(&m).unwrap() - 2.0).abs() < 1e-5);
        assert!(
            (similarity_scale(&Mat4::from_scale(Vec3::new(-1.0, 1.0, 1.0))).unwrap() - 1.0).abs()
                < 1e-6
        );
        assert!(similarity_scale(&Mat4::from_scale(Vec3::new(1.0, 2.0, 1.0))).is_none());
    }
}
