//! The perspective camera (pbrt-v4 conventions): a pinhole, or a thin lens.
//!
//! ```text
//! LookAt 0 1 6.8  0 1 0  0 1 0     # or Transform / Scale ... before Camera
//! Camera "perspective" "float fov" [ 19.5 ]
//!     "float lensradius" [ 0.05 ] "float focaldistance" [ 6.8 ]   # depth of field
//!     "float screenwindow" [ -1 1 -1 1 ]      # or "float frameaspectratio" [ 1.5 ]
//! ```
//! `fov` spans the shorter axis of the screen window, which is `[-a, a] x [-1, 1]` for an
//! image wider than tall (`a` = width / height, or `frameaspectratio`) unless `screenwindow`
//! gives it. Raster `y` grows downwards, and camera space looks down `+z` with `+y` up; raster
//! `x` maps to camera `+x` (which pbrt's left-handed LookAt points to the viewer's left of
//! world `+x`: published scenes add `Scale -1 1 1` to flip it).
//!
//! With `lensradius` > 0 a ray starts at a point of the lens disk (a concentric-disk warp of
//! the pixel sample's lens dimensions, scaled by the radius, at z = 0 in camera space) and
//! passes through the point where the pinhole ray meets the plane in focus, z =
//! `focaldistance`: points on that plane are sharp, others blur into the image of the lens.
use crate::math::{Mat4, Ray, Vec2, Vec3};
use crate::sampling::warp::square_to_disk_concentric;
use crate::scene::CameraDesc;

#[derive(Clone, Debug)]
pub struct Camera {
    world_from_camera: Mat4,
    camera_from_world: Mat4,
    origin: Vec3,
    /// Centre and half extents of the screen window at z = 1 in camera space.
    centre: Vec2,
    half: Vec2,
    res: Vec2,
    lens_radius: f32,
    focal_distance: f32,
}

impl Camera {
    /// A camera for an image of `width x height` pixels.
    pub fn new(desc: &CameraDesc, width: u32, height: u32) -> Camera {
        let tan_half = (desc.fov_deg.to_radians() * 0.5).tan();
        let (centre, window) = screen_window(desc, width, height);
        Camera {
            world_from_camera: desc.world_from_camera,
            camera_from_world: desc.world_from_camera.inverse(),
            origin: desc.world_from_camera.transform_point3(Vec3::ZERO),
            centre: centre * tan_half,
            half: window * tan_half,
            res: Vec2::new(width as f32, height as f32),
            lens_radius: desc.lens_radius,
            focal_distance: desc.focal_distance,
        }
    }

    /// Whether rays start on a lens (and [`Self::generate_ray_lens`] needs a lens sample).
    pub fn has_lens(&self) -> bool {
        self.lens_radius > 0.0
    }

    /// The camera-space direction (z = 1) of the pinhole ray through raster position `p`.
    fn pinhole_dir(&self, p: Vec2) -> Vec3 {
        let ndc = p / self.res;
        Vec3::new(
            (2.0 * ndc.x - 1.0) * self.half.x + self.centre.x,
            (1.0 - 2.0 * ndc.y) * self.half.y + self.centre.y,
            1.0,
        )
    }

    /// The pinhole ray through continuous raster position `p` (pixel `(x, y)` covers
    /// `[x, x+1) x [y, y+1)`), with a unit direction.
    pub fn generate_ray(&self, p: Vec2) -> Ray {
        let d = self
            .world_from_camera
            .transform_vector3(self.pinhole_dir(p))
            .normalize();
        Ray::new(self.origin, d)
    }

    /// The ray through raster position `p` from the lens point that `u_lens` (in [0, 1)^2)
    /// picks, with a unit direction; the pinhole ray without a lens.
    pub fn generate_ray_lens(&self, p: Vec2, u_lens: Vec2) -> Ray {
        if !self.has_lens() {
            return self.generate_ray(p);
        }
        let lens = square_to_disk_concentric(u_lens) * self.lens_radius;
        let o = Vec3::new(lens.x, lens.y, 0.0);
        // The pinhole direction has z = 1: scaled by the focal distance it ends in the plane.
        let focus = self.pinhole_dir(p) * self.focal_distance;
        let d = self
            .world_from_camera
            .transform_vector3(focus - o)
            .normalize();
        if !d.is_finite() {
            // A focal distance so large that the focus point overflows: the pinhole ray.
            return self.generate_ray(p);
        }
        Ray::new(self.world_from_camera.transform_point3(o), d)
    }

    pub fn position(&self) -> Vec3 {
        self.origin
    }

    /// Where the pinhole camera sees world point `p`: its continuous raster position and
    /// the factor that turns a density per unit of raster area into one per unit solid angle
    /// at the camera (`1 / (A cos^3)`, `A` a pixel's area on the plane z = 1 in camera
    /// space, `cos` the angle to the optical axis). `None` behind the camera or off the
    /// screen window widened by `margin` pixels on every side (a pixel filter's radius: the
    /// samples of the edge pixels reach that far). What light paths splat to the film with
    /// (the camera's importance).
    pub fn project(&self, p: Vec3, margin: Vec2) -> Option<(Vec2, f32)> {
        let c = self.camera_from_world.transform_point3(p);
        if c.z <= 0.0 || !c.is_finite() {
            return None;
        }
        let d = c / c.z;
        let ndc = Vec2::new(
            ((d.x - self.centre.x) / self.half.x + 1.0) * 0.5,
            (1.0 - (d.y - self.centre.y) / self.half.y) * 0.5,
        );
        let raster = ndc * self.res;
        let (lo, hi) = (-margin, self.res + margin);
        if !(raster.cmpge(lo).all() && raster.cmplt(hi).all()) {
            return None;
        }
        let cos = c.z / c.length();
        Some((raster, self.raster_to_solid_angle(cos)))
    }

    /// [`Self::project`] through the point of the lens that `u_lens` (in [0, 1)^2) picks, as
    /// [`Self::generate_ray_lens`] uses it: the raster position whose lens ray from that point
    /// passes through `p`, the density factor, and the lens point in world space (what `p`
    /// must see). The pinhole's projection without a lens.
    pub fn project_through_lens(
        &self,
        p: Vec3,
        u_lens: Vec2,
        margin: Vec2,
    ) -> Option<(Vec2, f32, Vec3)> {
        if !self.has_lens() {
            let (raster, f) = self.project(p, margin)?;
            return Some((raster, f, self.origin));
        }
        let c = self.camera_from_world.transform_point3(p);
        let lens = square_to_disk_concentric(u_lens) * self.lens_radius;
        let o = Vec3::new(lens.x, lens.y, 0.0);
        let d = c - o;
        if d.z <= 0.0 || !d.is_finite() {
            return None;
        }
        // Where the ray from the lens point through p meets the plane in focus, scaled back
        // to z = 1: the pinhole direction of the raster position that generates this ray.
        let q = o / self.focal_distance + d / d.z;
        let ndc = Vec2::new(
            ((q.x - self.centre.x) / self.half.x + 1.0) * 0.5,
            (1.0 - (q.y - self.centre.y) / self.half.y) * 0.5,
        );
        let raster = ndc * self.res;
        let (lo, hi) = (-margin, self.res + margin);
        if !(raster.is_finite() && raster.cmpge(lo).all() && raster.cmplt(hi).all()) {
            return None;
        }
        let cos = d.z / d.length();
        let world = self.world_from_camera.transform_point3(o);
        Some((raster, self.raster_to_solid_angle(cos), world))
    }

    /// `1 / (A cos^3)` of [`Self::project`] for a ray at angle `acos(cos)` to the axis.
    pub fn raster_to_solid_angle(&self, cos: f32) -> f32 {
        let pixel_area = 4.0 * self.half.x * self.half.y / (self.res.x * self.res.y);
        1.0 / (pixel_area * cos * cos * cos)
    }

    /// The cosine between unit world direction `d` (leaving the camera) and the optical axis.
    pub fn cos_to_axis(&self, d: Vec3) -> f32 {
        let c = self.camera_from_world.transform_vector3(d);
        c.z / c.length()
    }
}

/// The centre and half extents of the camera's screen window, before the `fov` scale.
fn screen_window(desc: &CameraDesc, width: u32, height: u32) -> (Vec2, Vec2) {
    if let Some([x0, x1, y0, y1]) = desc.screen_window {
        let centre = Vec2::new(0.5 * (x0 + x1), 0.5 * (y0 + y1));
        return (centre, Vec2::new(0.5 * (x1 - x0), 0.5 * (y1 - y0)));
    }
    let aspect = width as f32 / height as f32;
    let window = if aspect > 1.0 {
        Vec2::new(aspect, 1.0)
    } else {
        Vec2::new(1.0, 1.0 / aspect)
    };
    (Vec2::ZERO, window)
}

/// The image a texture footprint is one pixel of: the render's resolution (the whole film, a
/// crop window included) and samples per pixel, which `--res`, `--spp` and the pass settings
/// may change from the file's.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Footprint {
    pub res: (u32, u32),
    pub spp: u32,
}

impl Footprint {
    /// The file's own film and sampler (for lookups outside a render: tests, tools).
    pub fn of_file(scene: &crate::scene::Scene) -> Footprint {
        Footprint {
            res: (scene.film.xres, scene.film.yres),
            spp: scene.sampler.pixel_samples,
        }
    }
}

/// How far one pixel step moves a point `p` on a surface with normal `n` (pbrt-v4's
/// `Camera::Approximate_dp_dxy`, which every hit uses for texture filtering and bump mapping):
/// the camera rays one pixel right and down from the ray through `p` are approximated by
/// offsets of `r * spread` along the camera's x and y axes (`r` the distance to the camera,
/// `spread` the angle one pixel spans at the image centre), projected along the view ray onto
/// the tangent plane, and scaled by `max(1/8, 1/sqrt(spp))` since pixels take several samples.
/// With a thin lens this is still the pinhole footprint, as in pbrt-v4 (whose minimum
/// differentials are those of the ray through the lens centre): defocus blur is not filtered.
/// With a `screenwindow`, each axis uses its own pixel step.
pub fn approximate_dp_dxy(
    desc: &CameraDesc,
    res: (u32, u32),
    spp: u32,
    p: Vec3,
    n: Vec3,
) -> (Vec3, Vec3) {
    let origin = desc.world_from_camera.transform_point3(Vec3::ZERO);
    let to_p = p - origin;
    let r = to_p.length();
    let d = to_p / r;
    let tan_half = (desc.fov_deg.to_radians() * 0.5).tan();
    let spread = match desc.screen_window {
        None => Vec2::splat(2.0 * tan_half / res.0.min(res.1).max(1) as f32),
        Some([x0, x1, y0, y1]) => Vec2::new(
            (x1 - x0) * tan_half / res.0.max(1) as f32,
            (y1 - y0) * tan_half / res.1.max(1) as f32,
        ),
    };
    let scale = (1.0 / (spp.max(1) as f32).sqrt()).max(0.125) * r * spread;
    let along = |axis: Vec3, scale: f32| {
        let e = desc
            .world_from_camera
            .transform_vector3(axis)
            .normalize_or_zero()
            * scale;
        // Slide e along d until it lies in the tangent plane: e - d (n.e)/(n.d).
        let nd = n.dot(d);
        let nd = if nd.abs() < 1e-4 {
            1e-4f32.copysign(nd)
        } else {
            nd
        };
        e - d * (n.dot(e) / nd)
    };
    let (dx, dy) = (along(Vec3::X, scale.x), along(Vec3::Y, scale.y));
    if dx.is_finite() && dy.is_finite() {
        (dx, dy)
    } else {
        (Vec3::ZERO, Vec3::ZERO)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn desc(fov: f32) -> CameraDesc {
        CameraDesc::pinhole(Mat4::IDENTITY, fov)
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

    /// Every lens ray through a raster point meets the pinhole ray through it on the plane in
    /// focus; the lens centre gives the pinhole ray itself; lens points fill the disk.
    #[test]
    fn lens_rays_meet_on_the_focal_plane() {
        let mut d = desc(50.0);
        d.world_from_camera = Mat4::from_translation(Vec3::new(1.0, 2.0, 3.0));
        (d.lens_radius, d.focal_distance) = (0.3, 4.0);
        let cam = Camera::new(&d, 64, 48);
        let p = Vec2::new(10.3, 40.7);
        let pin = cam.generate_ray(p);
        let focus = pin.at(4.0 / pin.d.z);
        let centre = cam.generate_ray_lens(p, Vec2::splat(0.5));
        assert!((centre.o - pin.o).length() < 1e-6 && (centre.d - pin.d).length() < 1e-6);
        let mut max_r = 0.0f32;
        for i in 0..64 {
            let u = Vec2::new((i % 8) as f32 / 8.0 + 0.05, (i / 8) as f32 / 8.0 + 0.05);
            let r = cam.generate_ray_lens(p, u);
            assert!((r.o.z - 3.0).abs() < 1e-6 && (r.d.length() - 1.0).abs() < 1e-5);
            let lens = r.o - Vec3::new(1.0, 2.0, 3.0);
            assert!(lens.length() <= 0.3 + 1e-6);
            max_r = max_r.max(lens.length());
            let hit = r.at((focus.z - r.o.z) / r.d.z);
            assert!((hit - focus).length() < 1e-4, "{hit} {focus}");
        }
        assert!(max_r > 0.25, "{max_r}");
    }

    /// A screen window moves and scales the image: its centre column looks through the
    /// window's centre, and the default window is `[-a, a] x [-1, 1]`.
    #[test]
    fn screen_window_maps_onto_the_raster() {
        let mut d = desc(90.0);
        d.screen_window = Some([0.0, 2.0, -1.0, 0.0]);
        let cam = Camera::new(&d, 100, 50);
        let r = cam.generate_ray(Vec2::new(50.0, 25.0));
        let want = Vec3::new(1.0, -0.5, 1.0).normalize();
        assert!((r.d - want).length() < 1e-6, "{}", r.d);
        d.screen_window = Some([-2.0, 2.0, -1.0, 1.0]);
        let a = Camera::new(&d, 100, 50).generate_ray(Vec2::new(3.0, 7.0));
        let b = Camera::new(&desc(90.0), 100, 50).generate_ray(Vec2::new(3.0, 7.0));
        assert!((a.d - b.d).length() < 1e-6);
    }

    /// Raster top-left looks towards camera (-x, +y).
    #[test]
    fn raster_orientation() {
        let cam = Camera::new(&desc(90.0), 100, 100);
        let r = cam.generate_ray(Vec2::ZERO);
        assert!(r.d.x < 0.0 && r.d.y > 0.0 && r.d.z > 0.0);
    }

    /// At the image centre, the approximate footprint equals the step between the hit points of
    /// the rays through two neighbouring pixel centres, on a facing and on a tilted plane.
    #[test]
    fn footprint_matches_neighbouring_rays() {
        let d = desc(40.0);
        let cam = Camera::new(&d, 200, 100);
        // The approximation is first order in the pixel angle (0.0073 rad here): exact to
        // rounding on the facing plane, off by about that angle times tan 45 on the tilted one.
        for (n, tol) in [
            (Vec3::new(0.0, 0.0, -1.0), 1e-4),
            (Vec3::new(1.0, 0.0, -1.0).normalize(), 1e-2),
        ] {
            // The plane through (0, 0, 10) with normal n.
            let hit = |x: f32, y: f32| {
                let r = cam.generate_ray(Vec2::new(x, y));
                let t = n.dot(Vec3::new(0.0, 0.0, 10.0) - r.o) / n.dot(r.d);
                r.o + r.d * t
            };
            let centre = hit(100.0, 50.0);
            let (dx, dy) = approximate_dp_dxy(&d, (200, 100), 1, centre, n);
            let want_x = hit(101.0, 50.0) - centre;
            let want_y = hit(100.0, 51.0) - centre;
            assert!(
                (dx - want_x).length() < tol * want_x.length(),
                "{dx} {want_x}"
            );
            // Raster y grows downwards, camera y upwards: the step is the opposite vector.
            assert!(
                (dy + want_y).length() < tol * want_y.length(),
                "{dy} {want_y}"
            );
            // 16 samples per pixel: a quarter of the step; 1000: capped at an eighth.
            let (dx16, _) = approximate_dp_dxy(&d, (200, 100), 16, centre, n);
            assert!((dx16 * 4.0 - dx).length() < 1e-6 * dx.length().max(1.0));
            let (dx1k, _) = approximate_dp_dxy(&d, (200, 100), 1000, centre, n);
            assert!((dx1k * 8.0 - dx).length() < 1e-6 * dx.length().max(1.0));
        }
    }
}
