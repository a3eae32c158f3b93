//! The perspective and orthographic cameras (pbrt-v4 conventions): a pinhole, or a thin lens.
//!
//! ```text
//! LookAt 0 1 6.8  0 1 0  0 1 0     # or Transform / Scale ... before Camera
//! Camera "perspective" "float fov" [ 19.5 ]
//!     "float lensradius" [ 0.05 ] "float focaldistance" [ 6.8 ]   # depth of field
//!     "float screenwindow" [ -1 1 -1 1 ]      # or "float frameaspectratio" [ 1.5 ]
//! Camera "orthographic" "float screenwindow" [ -2 2 -1 1 ]   # camera-space units
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
//!
//! An orthographic camera's rays start at the screen-window point `s` of the raster position
//! on the plane z = 0 (the window is in camera-space units, moved and scaled by the camera
//! transform like everything else) and run along +z. With a lens, the ray starts at `s` plus
//! the lens point and passes through `s` moved to z = `focaldistance` (a telecentric thin
//! lens). pbrt-v4 starts that ray at the lens point alone, around the axis (mmp/pbrt-v3#315,
//! inherited by v4), so that a lens makes its image a perspective one away from the plane in
//! focus; photon does not copy that.
//!
//! Importance (what light paths splat to the film with, [`Camera::project_through_lens`]): a
//! perspective camera samples directions, `1 / (A cos^3)` per unit solid angle for `A` a
//! pixel's area on the plane z = 1; an orthographic one samples ray origins, `1 / A` per unit
//! area of the plane z = 0 (`A` a pixel's area there, in world units) with one direction per
//! lens point: a point `p` is seen along the one ray of that direction through it, from its
//! projection onto the plane z = 0.
use crate::math::{Mat4, Ray, Vec2, Vec3};
use crate::sampling::warp::square_to_disk_concentric;
use crate::scene::{CameraDesc, Projection};

#[derive(Clone, Debug)]
pub struct Camera {
    world_from_camera: Mat4,
    camera_from_world: Mat4,
    origin: Vec3,
    /// Centre and half extents of the screen window: at z = 1 in camera space for a
    /// perspective camera (the `fov` scale applied), on the plane z = 0 for an orthographic one.
    centre: Vec2,
    half: Vec2,
    res: Vec2,
    lens_radius: f32,
    focal_distance: f32,
    /// Orthographic: a pixel's area on the plane z = 0 in world units, and the world direction
    /// of camera +z (unit).
    ortho: Option<(f32, Vec3)>,
}

impl Camera {
    /// A camera for an image of `width x height` pixels.
    pub fn new(desc: &CameraDesc, width: u32, height: u32) -> Camera {
        let (centre, window) = screen_window(desc, width, height);
        let res = Vec2::new(width as f32, height as f32);
        let (scale, ortho) = match desc.projection {
            Projection::Perspective => ((desc.fov_deg.to_radians() * 0.5).tan(), None),
            Projection::Orthographic => {
                let w = &desc.world_from_camera;
                let (ex, ey) = (w.transform_vector3(Vec3::X), w.transform_vector3(Vec3::Y));
                let pixel = 4.0 * window.x * window.y / (res.x * res.y);
                let z = w.transform_vector3(Vec3::Z).normalize();
                (1.0, Some((pixel * ex.cross(ey).length(), z)))
            }
        };
        Camera {
            world_from_camera: desc.world_from_camera,
            camera_from_world: desc.world_from_camera.inverse(),
            origin: desc.world_from_camera.transform_point3(Vec3::ZERO),
            centre: centre * scale,
            half: window * scale,
            res,
            lens_radius: desc.lens_radius,
            focal_distance: desc.focal_distance,
            ortho,
        }
    }

    /// Whether rays start on a lens (and [`Self::generate_ray_lens`] needs a lens sample).
    pub fn has_lens(&self) -> bool {
        self.lens_radius > 0.0
    }

    /// Whether the camera is orthographic.
    pub fn is_orthographic(&self) -> bool {
        self.ortho.is_some()
    }

    /// The camera-space screen-window point of raster position `p`: at z = 1 (a perspective
    /// camera: the pinhole direction) or z = 0 (an orthographic one: the ray's origin).
    fn window_point(&self, p: Vec2) -> Vec3 {
        let ndc = p / self.res;
        Vec3::new(
            (2.0 * ndc.x - 1.0) * self.half.x + self.centre.x,
            (1.0 - 2.0 * ndc.y) * self.half.y + self.centre.y,
            if self.ortho.is_some() { 0.0 } else { 1.0 },
        )
    }

    /// The raster position of camera-space screen-window point `q` (its x and y).
    fn raster_of(&self, q: Vec3) -> Vec2 {
        let ndc = Vec2::new(
            ((q.x - self.centre.x) / self.half.x + 1.0) * 0.5,
            (1.0 - (q.y - self.centre.y) / self.half.y) * 0.5,
        );
        ndc * self.res
    }

    /// The ray through continuous raster position `p` (pixel `(x, y)` covers
    /// `[x, x+1) x [y, y+1)`) without a lens, with a unit direction.
    pub fn generate_ray(&self, p: Vec2) -> Ray {
        let q = self.window_point(p);
        if let Some((_, z)) = self.ortho {
            return Ray::new(self.world_from_camera.transform_point3(q), z);
        }
        let d = self.world_from_camera.transform_vector3(q).normalize();
        Ray::new(self.origin, d)
    }

    /// The ray through raster position `p` from the lens point that `u_lens` (in [0, 1)^2)
    /// picks, with a unit direction; the pinhole ray without a lens.
    pub fn generate_ray_lens(&self, p: Vec2, u_lens: Vec2) -> Ray {
        if !self.has_lens() {
            return self.generate_ray(p);
        }
        let lens = square_to_disk_concentric(u_lens) * self.lens_radius;
        let lens = Vec3::new(lens.x, lens.y, 0.0);
        let q = self.window_point(p);
        let (o, focus) = if self.ortho.is_some() {
            // From the window point moved by the lens point, through the window point on the
            // plane in focus.
            (q + lens, q + Vec3::Z * self.focal_distance)
        } else {
            // The pinhole direction has z = 1: scaled by the focal distance it ends in the plane.
            (lens, q * self.focal_distance)
        };
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

    /// The camera-space origin in world space (a perspective camera's pinhole; the centre of
    /// an orthographic camera's plane z = 0).
    pub fn position(&self) -> Vec3 {
        self.origin
    }

    /// Where the camera without a lens sees world point `p`: its continuous raster position and
    /// the camera's importance density there (see [`Self::project_through_lens`]). `None`
    /// behind the camera or off the screen window widened by `margin` pixels on every side.
    pub fn project(&self, p: Vec3, margin: Vec2) -> Option<(Vec2, f32, Vec3)> {
        self.project_through_lens(p, Vec2::splat(0.5), margin)
    }

    /// Where the camera sees world point `p` through the point of the lens that `u_lens` (in
    /// [0, 1)^2) picks, as [`Self::generate_ray_lens`] uses it: the raster position whose ray
    /// from that point passes through `p`; the factor `g` that turns a density per unit of
    /// raster area into one per unit area at `p` when multiplied by the cosine at `p` between
    /// its normal and the ray (perspective: `1 / (A cos^3 d^2)`, `A` a pixel's area on the
    /// plane z = 1, `cos` the ray's angle to the optical axis and `d` the distance;
    /// orthographic: `1 / (A cos)`, `A` a pixel's area on the plane z = 0 in world units); and
    /// the ray's origin in world space (what `p` must see). `None` behind the camera (for an
    /// orthographic camera: behind the plane z = 0) or off the screen window widened by
    /// `margin` pixels on every side (a pixel filter's radius: the samples of the edge pixels
    /// reach that far). What light paths splat to the film with (the camera's importance).
    pub fn project_through_lens(
        &self,
        p: Vec3,
        u_lens: Vec2,
        margin: Vec2,
    ) -> Option<(Vec2, f32, Vec3)> {
        let c = self.camera_from_world.transform_point3(p);
        let lens = if self.has_lens() {
            square_to_disk_concentric(u_lens) * self.lens_radius
        } else {
            Vec2::ZERO
        };
        let lens = Vec3::new(lens.x, lens.y, 0.0);
        let (q, o, d) = if self.ortho.is_some() {
            // The ray's direction is fixed by the lens point: (-lens, f) (+z without a lens).
            let d = if self.has_lens() {
                Vec3::new(-lens.x, -lens.y, self.focal_distance)
            } else {
                Vec3::Z
            };
            // Back along d from p to the plane z = 0: the ray's origin, minus the lens point:
            // the window point.
            let o = c - d * (c.z / d.z);
            (o - lens, o, d)
        } else {
            let d = c - lens;
            // Where the ray from the lens point through p meets the plane in focus, scaled back
            // to z = 1: the pinhole direction of the raster position that generates this ray.
            let q = if self.has_lens() {
                lens / self.focal_distance + d / d.z
            } else {
                d / d.z
            };
            (q, lens, d)
        };
        if c.z <= 0.0 || d.z <= 0.0 || !c.is_finite() || !d.is_finite() {
            return None;
        }
        let raster = self.raster_of(q);
        let (lo, hi) = (-margin, self.res + margin);
        if !(raster.is_finite() && raster.cmpge(lo).all() && raster.cmplt(hi).all()) {
            return None;
        }
        let cos = d.z / d.length();
        let world = self.world_from_camera.transform_point3(o);
        let g = match self.ortho {
            Some((pixel_area, _)) => 1.0 / (pixel_area * cos),
            None => self.raster_to_solid_angle(cos) / (world - p).length_squared(),
        };
        Some((raster, g, world))
    }

    /// The density of a camera ray with unit world direction `d` per unit of raster area, and
    /// whether the first segment's length converts it to a density per unit area at the first
    /// hit (with its cosine): per unit solid angle for a perspective camera (`1 / (A cos^3)`,
    /// true), per unit area of the plane z = 0 across the ray for an orthographic one
    /// (`1 / (A cos)`, false; only the cosine at the hit remains). What a camera subpath's
    /// MIS partial sums start from.
    pub fn ray_density(&self, d: Vec3) -> (f32, bool) {
        let cos = self.cos_to_axis(d);
        match self.ortho {
            Some((pixel_area, _)) => (1.0 / (pixel_area * cos), false),
            None => (self.raster_to_solid_angle(cos), true),
        }
    }

    /// The width of one pixel at distance `t` along a camera ray with unit world direction `d`
    /// (across the ray; an orthographic camera's is the same at every distance).
    pub fn pixel_width(&self, d: Vec3, t: f32) -> f32 {
        match self.ortho {
            Some((pixel_area, _)) => pixel_area.sqrt(),
            None => t / self.raster_to_solid_angle(self.cos_to_axis(d)).sqrt(),
        }
    }

    /// `1 / (A cos^3)` of a perspective camera for a ray at angle `acos(cos)` to the axis.
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
/// With a `screenwindow`, each axis uses its own pixel step. An orthographic camera's rays are
/// parallel: the offsets are one pixel's step on its plane z = 0, whatever the distance (the
/// differentials pbrt-v4 finds for it, without its rotation of the view axis towards `p`).
pub fn approximate_dp_dxy(
    desc: &CameraDesc,
    res: (u32, u32),
    spp: u32,
    p: Vec3,
    n: Vec3,
) -> (Vec3, Vec3) {
    let w = &desc.world_from_camera;
    let origin = w.transform_point3(Vec3::ZERO);
    let ortho = desc.projection == Projection::Orthographic;
    // An orthographic camera's neighbouring rays are parallel, one window step apart (in
    // camera-space units, so the camera transform's scale applies): `r` is that scale.
    let (d, r, tan_half) = if ortho {
        let d = w.transform_vector3(Vec3::Z).normalize();
        (d, w.transform_vector3(Vec3::X).length(), 1.0)
    } else {
        let to_p = p - origin;
        let r = to_p.length();
        (to_p / r, r, (desc.fov_deg.to_radians() * 0.5).tan())
    };
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

    fn ortho(window: [f32; 4], lens: f32) -> CameraDesc {
        let mut d = desc(45.0);
        d.projection = Projection::Orthographic;
        d.world_from_camera = Mat4::from_translation(Vec3::new(1.0, 2.0, 3.0))
            * Mat4::from_rotation_y(0.3)
            * Mat4::from_scale(Vec3::new(-2.0, 2.0, 2.0));
        d.screen_window = Some(window);
        (d.lens_radius, d.focal_distance) = (lens, 4.0);
        d
    }

    /// An orthographic camera's rays are parallel, start on the plane z = 0 at the window
    /// point (in camera units, scaled by the transform) and [`Camera::project_through_lens`]
    /// inverts [`Camera::generate_ray_lens`] (with and without a lens); its density is one
    /// over a pixel's world area.
    #[test]
    fn orthographic_rays_and_projection() {
        for lens in [0.0, 0.3] {
            let d = ortho([-1.0, 3.0, -1.0, 1.0], lens);
            let cam = Camera::new(&d, 80, 40);
            let z = d.world_from_camera.transform_vector3(Vec3::Z).normalize();
            let c = cam.generate_ray(Vec2::new(20.0, 20.0));
            // Raster (20, 20) is window (0, 0): the camera-space origin.
            assert!((c.o - Vec3::new(1.0, 2.0, 3.0)).length() < 1e-5, "{}", c.o);
            assert!((c.d - z).length() < 1e-6);
            let e = cam.generate_ray(Vec2::new(60.0, 20.0));
            // Two window units to the right: 4 world units (scale 2) along the transformed x.
            assert!(((e.o - c.o).length() - 4.0).abs() < 1e-4);
            assert!((e.d - z).length() < 1e-6);
            for (i, p) in [(3.3, 5.5), (70.1, 38.2), (40.0, 1.0)]
                .into_iter()
                .enumerate()
            {
                let p = Vec2::new(p.0, p.1);
                let u = Vec2::new(0.1 + 0.3 * i as f32, 0.8 - 0.25 * i as f32);
                let r = cam.generate_ray_lens(p, u);
                let world = r.at(7.0);
                let (raster, g, o) = cam
                    .project_through_lens(world, u, Vec2::ZERO)
                    .expect("in view");
                assert!((raster - p).length() < 2e-3, "{lens}: {raster} {p}");
                assert!((o - r.o).length() < 1e-3, "{lens}: {o} {}", r.o);
                let cos = cam.cos_to_axis(r.d);
                let pixel = 4.0 * 2.0 / (80.0 * 40.0) * 4.0;
                assert!((g * pixel * cos - 1.0).abs() < 1e-4, "{g}");
                let (density, finite) = cam.ray_density(r.d);
                assert!((density / g - 1.0).abs() < 1e-5 && !finite);
                // Behind the plane z = 0: not seen.
                assert!(cam.project_through_lens(r.o - r.d, u, Vec2::ZERO).is_none());
            }
        }
    }

    /// A perspective camera's projection factor is `1 / (A cos^3 d^2)`.
    #[test]
    fn perspective_projection_factor() {
        let cam = Camera::new(&desc(60.0), 64, 64);
        let r = cam.generate_ray(Vec2::new(10.5, 50.5));
        let p = r.at(3.0);
        let (raster, g, o) = cam.project(p, Vec2::ZERO).unwrap();
        assert!((raster - Vec2::new(10.5, 50.5)).length() < 1e-3);
        assert_eq!(o, Vec3::ZERO);
        let cos = cam.cos_to_axis(r.d);
        let want = cam.raster_to_solid_angle(cos) / 9.0;
        assert!((g / want - 1.0).abs() < 1e-4);
        assert_eq!(cam.ray_density(r.d), (cam.raster_to_solid_angle(cos), true));
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
