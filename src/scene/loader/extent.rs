//! The range of scene sizes photon renders correctly, checked once the whole scene is read.
//!
//! ```text
//! WorldBegin
//! Scale 1e-8 1e-8 1e-8          # the Cornell box at 1e-8 of its size: fine
//! Shape "trianglemesh" ...      # every vertex within MAX_COORDINATE of the origin,
//!                               # the geometry's bounding radius within MIN_RADIUS..MAX_RADIUS
//! ```
//!
//! Ray origins are offset by error bounds relative to the vertices, photon radii are fractions
//! of the scene radius and every quantity is an f32, so the image does not depend on the
//! scene's scale within this range (the Cornell box at 1e-8 and 1e8 renders within relMSE
//! 3e-4 of scale 1; `tests/it/hostile.rs`). Outside it squared distances and areas leave f32's
//! normal range (at 1e-10 the box renders black, at 1e10 loses its indirect light, at 1e12 its
//! emitter's area overflows), so a scene there is an error naming the shape that goes furthest
//! (or the first shape, for a scene too small), rather than a wrong image.
use crate::math::Vec3;
use crate::scene::{Loc, Mesh, SceneError};

/// Smallest bounding radius of the geometry.
pub const MIN_RADIUS: f32 = 1e-9;
/// Largest bounding radius of the geometry.
pub const MAX_RADIUS: f32 = 1e9;
/// Largest |coordinate| of a vertex.
pub const MAX_COORDINATE: f32 = 1e9;
/// Smallest ratio of the scene's radius to its largest |coordinate| (f32 keeps 7 digits: a
/// scene far from the origin for its size loses its detail).
pub const MIN_RADIUS_TO_OFFSET: f32 = 1e-5;

/// Errors (at `loc`) when a vertex of `mesh` (or its sphere) lies beyond [`MAX_COORDINATE`]:
/// checked for each shape as it is read, before its emission is computed.
pub fn check_shape(mesh: &Mesh, loc: &Loc) -> Result<(), SceneError> {
    let far = match mesh.sphere {
        Some((c, r)) => c.abs().max_element() + r,
        None => mesh
            .positions
            .iter()
            .map(|p| p.abs().max_element())
            .fold(0.0, f32::max),
    };
    if far > MAX_COORDINATE {
        return Err(SceneError::at(
            loc,
            format!("the scene is too large: a vertex at distance {far:e} from the origin (photon supports coordinates up to {MAX_COORDINATE:e}; scale the scene down)"),
        ));
    }
    Ok(())
}

/// Errors unless the geometry of `meshes` (written at `locs`) lies in the supported range.
pub fn check(meshes: &[Mesh], locs: &[Loc]) -> Result<(), SceneError> {
    let mut lo = Vec3::splat(f32::INFINITY);
    let mut hi = Vec3::splat(f32::NEG_INFINITY);
    let mut far = (0.0f32, 0usize);
    for (i, m) in meshes.iter().enumerate() {
        for p in &m.positions {
            lo = lo.min(*p);
            hi = hi.max(*p);
            let a = p.abs().max_element();
            if a > far.0 {
                far = (a, i);
            }
        }
    }
    if meshes.iter().all(|m| m.positions.is_empty()) {
        return Ok(());
    }
    let radius = 0.5 * (hi - lo).as_dvec3().length() as f32;
    let at = |i: usize| locs.get(i).cloned();
    let err = |i: usize, msg: String| SceneError { loc: at(i), msg };
    if far.0 > MAX_COORDINATE || radius > MAX_RADIUS {
        return Err(err(
            far.1,
            format!(
                "the scene is too large: a vertex at distance {:e} from the origin, bounding radius {radius:e} (photon supports coordinates up to {MAX_COORDINATE:e} and radii {MIN_RADIUS:e}..{MAX_RADIUS:e}; scale the scene down)",
                far.0
            ),
        ));
    }
    if radius > 0.0 && radius < MIN_RADIUS {
        return Err(err(
            0,
            format!(
                "the scene is too small: its geometry's bounding radius is {radius:e} (photon supports {MIN_RADIUS:e}..{MAX_RADIUS:e}; scale the scene up)"
            ),
        ));
    }
    if radius < MIN_RADIUS_TO_OFFSET * far.0 {
        return Err(err(
            far.1,
            format!(
                "the scene's geometry (bounding radius {radius:e}) lies {:e} from the origin, too far for f32 precision (at most {:e} times its radius; move it towards the origin)",
                far.0,
                1.0 / MIN_RADIUS_TO_OFFSET
            ),
        ));
    }
    Ok(())
}
