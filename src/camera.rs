//! The perspective pinhole camera (pbrt-v4 conventions).
//!
//! ```text
//! LookAt 0 1 6.8  0 1 0  0 1 0     # or Transform / Scale ... before Camera
//! Camera "perspective" "float fov" [ 19.5 ]
//! ```
//! `fov` spans the shorter image axis. pbrt's screen window is `[-a, a] x [-1, 1]` for an image
//! wider than tall (`a` = width / height), raster `y` grows downwards, and camera space looks
//! down `+z` with `+y` up; raster `x` maps to camera `+x` (which pbrt's left-handed LookAt
//! points to the viewer's left of world `+x`: published scenes add `Scale -1 1 1` to flip it).
use crate::math::{Mat4, Ray, Vec2, Vec3};
use crate::scene::CameraDesc;

#[derive(Clone, Debug)]
pub struct Camera {
    world_from_camera: Mat4,
    origin: Vec3,
    /// Half extents of the screen window at z = 1 in camera space.
    half: Vec2,
    res: Vec2,
}

impl Camera {
    /// A camera for an image of `width x height` pixels.
    pub fn new(desc: &CameraDesc, width: u32, height: u32) -> Camera {
        let aspect = width as f32 / height as f32;
        let tan_half = (desc.fov_deg.to_radians() * 0.5).tan();
        let window = if aspect > 1.0 {
            Vec2::new(aspect, 1.0)
        } else {
            Vec2::new(1.0, 1.0 / aspect)
        };
        Camera {
            world_from_camera: desc.world_from_camera,
            origin: desc.world_from_camera.transform_point3(Vec3::ZERO),
            half: window * tan_half,
            res: Vec2::new(width as f32, height as f32),
        }
    }

    /// The ray through continuous raster position `p` (pixel `(x, y)` covers
    /// `[x, x+1) x [y, y+1)`), with a unit direction.
    pub fn generate_ray(&self, p: Vec2) -> Ray {
        let ndc = p / self.res;
        let d_cam = Vec3::new(
            (2.0 * ndc.x - 1.0) * self.half.x,
            (1.0 - 2.0 * ndc.y) * self.half.y,
            1.0,
        );
        let d = self.world_from_camera.transform_vector3(d_cam).normalize();
        Ray::new(self.origin, d)
    }

    pub fn position(&self) -> Vec3 {
        self.origin
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn desc(fov: f32) -> CameraDesc {
        CameraDesc {
            world_from_camera: Mat4::IDENTITY,
            fov_deg: fov,
        }
    }

    /// The centre ray looks down +z; the edge of the shorter axis is fov/2 off-axis.
    #[test]
    fn fov_spans_the_shorter_axis() {
        for (w, h) in [(200u32, 100u32), (100, 200), (64, 64)] {
            let cam = Camera::new(&desc(60.0), w, h);
            let c = cam.generate_ray(Vec2::new(w as f32 / 2.0, h as f32 / 2.0));
            assert!((c.d - Vec3::Z).length() < 1e-6);
            let edge = if w >= h {
                cam.generate_ray(Vec2::new(w as f32 / 2.0, 0.0))
            } else {
                cam.generate_ray(Vec2::new(0.0, h as f32 / 2.0))
            };
            let angle = edge.d.dot(Vec3::Z).acos().to_degrees();
            assert!((angle - 30.0).abs() < 1e-3, "{w}x{h}: {angle}");
        }
    }

    /// Raster top-left looks towards camera (-x, +y).
    #[test]
    fn raster_orientation() {
        let cam = Camera::new(&desc(90.0), 100, 100);
        let r = cam.generate_ray(Vec2::ZERO);
        assert!(r.d.x < 0.0 && r.d.y > 0.0 && r.d.z > 0.0);
    }
}
