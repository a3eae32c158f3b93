//! Environment light: `LightSource "infinite"`, radiance arriving from every direction at
//! infinity, constant or from an image in pbrt-v4's equal-area octahedral parameterisation.
//!
//! ```text
//! AttributeBegin
//!   Rotate -90 1 0 0                       # the CTM orients the map
//!   LightSource "infinite" "string filename" "sky.exr" "float scale" 2
//! AttributeEnd
//! LightSource "infinite" "rgb L" [ 0.5 0.5 0.5 ]
//! ```
//! (the loader, `scene/loader/lights.rs`, reads the parameters.)
//!
//! A constant `L` is a 1x1 map, so one code path serves both (the equal-area map makes a
//! uniform square sample a uniform sphere sample). As in pbrt-v4's `ImageInfiniteLight`:
//! - `Le(w)`: the direction in the light's frame (`light_from_world w`) goes to the square by
//!   [`equal_area_sphere_to_square`] and reads the *nearest* texel (so radiance is constant
//!   over each texel, and each texel covers a solid angle of `4 pi / N` for `N` texels);
//! - light sampling draws a point of the square from a [`Distribution2D`] over the texels
//!   (by luminance here, where pbrt-v4 weighs texels by their channel average), with
//!   solid-angle density `pdf_square / (4 pi)`; a texel of zero weight has zero radiance, so
//!   the density covers all the light;
//! - caustic photons are aimed at the specular and glossy objects
//!   ([`super::Lights::emit_caustic`]);
//! - photons (`SampleLe`): a direction from the same distribution and an origin uniform on a
//!   disc of the scene's bounding-sphere radius `R` perpendicular to it, outside the scene:
//!   flux `Le / (pdf_dir * 1 / (pi R^2))`; the light's power is `4 pi^2 R^2 mean(L)`.
//!
//! With a portal (`"point3 portal" [ 4 corners ]`, pbrt-v4's `PortalImageInfiniteLight`) the
//! light reaches the scene only through that rectangle ([`Portal`]): `Le` is zero for a ray
//! that does not leave through it, and a photon whose line does not enter through it is
//! dropped (counted as emitted). Sampling stays over the whole map (pbrt-v4 samples within
//! the portal: same expectation, less noise).
use super::scalar_power;
use crate::math::{luminance, Mat3, Vec2, Vec3};
use crate::sampling::warp::{
    equal_area_sphere_to_square, equal_area_square_to_sphere, Distribution2D,
};
use crate::texture::Image;
use std::f32::consts::PI;
use std::fmt;

/// An environment map ready to evaluate and sample.
#[derive(Clone)]
pub struct EnvMap {
    res: usize,
    /// Radiance per texel (scale applied), row `y` covering `v` in `[y, y + 1) / res`.
    texels: Vec<Vec3>,
    dist: Distribution2D,
    world_from_light: Mat3,
    light_from_world: Mat3,
    mean: Vec3,
    /// A hash of the texels (so that scenes with different maps hash differently).
    hash: u64,
    /// pbrt-v4's portal: the light reaches the scene only through this rectangle.
    portal: Option<Portal>,
}

/// The rectangle of a portal infinite light (pbrt-v4's `PortalImageInfiniteLight`), in world
/// space: pbrt-v4's `Le` is zero for a ray whose line from its origin does not pass through
/// it towards the portal's outside (+z of its frame, z = (p3 - p0) x (p1 - p0)).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Portal {
    p0: Vec3,
    /// `p1 - p0` and `p3 - p0`.
    e1: Vec3,
    e3: Vec3,
    /// Unit normal towards the outside.
    n: Vec3,
}

impl Portal {
    /// The portal of corners `p` in order; as in pbrt-v4 they must form a rectangle: opposite
    /// edges parallel and adjacent ones perpendicular, within 0.001 in cosines.
    pub fn new(p: [Vec3; 4]) -> Result<Portal, String> {
        let unit = |a: Vec3, b: Vec3| (b - a).normalize_or_zero();
        let (p01, p12, p32, p03) = (
            unit(p[0], p[1]),
            unit(p[1], p[2]),
            unit(p[3], p[2]),
            unit(p[0], p[3]),
        );
        let parallel = (p01.dot(p32) - 1.0).abs() <= 1e-3 && (p12.dot(p03) - 1.0).abs() <= 1e-3;
        let square = [(p01, p12), (p12, p32), (p32, p03), (p03, p01)]
            .iter()
            .all(|(a, b)| a.dot(*b).abs() <= 1e-3);
        let n = (p[3] - p[0]).cross(p[1] - p[0]).normalize_or_zero();
        if !(parallel && square) || n == Vec3::ZERO {
            return Err("the 4 portal points must form a rectangle (pbrt-v4's test)".to_string());
        }
        Ok(Portal {
            p0: p[0],
            e1: p[1] - p[0],
            e3: p[3] - p[0],
            n,
        })
    }

    /// Where the ray `o + t d` meets the rectangle, if it does (`t` of either sign).
    fn hit(&self, o: Vec3, d: Vec3) -> Option<f32> {
        let dn = d.dot(self.n);
        if dn == 0.0 {
            return None;
        }
        let t = (self.p0 - o).dot(self.n) / dn;
        let q = o + d * t - self.p0;
        let a = q.dot(self.e1) / self.e1.length_squared();
        let b = q.dot(self.e3) / self.e3.length_squared();
        ((0.0..=1.0).contains(&a) && (0.0..=1.0).contains(&b)).then_some(t)
    }

    /// Whether light from direction `w` (towards the environment) reaches point `o`: the ray
    /// from `o` along `w` leaves through the portal, outwards.
    pub fn admits(&self, o: Vec3, w: Vec3) -> bool {
        w.dot(self.n) > 0.0 && self.hit(o, w).is_some_and(|t| t > 0.0)
    }

    /// Whether a photon leaving `p` (outside the scene) along `dir` enters through the portal.
    pub fn admits_photon(&self, p: Vec3, dir: Vec3) -> bool {
        dir.dot(self.n) < 0.0 && self.hit(p, dir).is_some_and(|t| t > 0.0)
    }
}

impl fmt::Debug for EnvMap {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "EnvMap {}x{} texels {:016x} world_from_light {:?}",
            self.res, self.res, self.hash, self.world_from_light
        )
    }
}

impl PartialEq for EnvMap {
    fn eq(&self, other: &EnvMap) -> bool {
        self.res == other.res
            && self.hash == other.hash
            && self.world_from_light == other.world_from_light
            && self.portal == other.portal
    }
}

impl EnvMap {
    /// A map from a square image times `scale` (negative and non-finite texels count as 0;
    /// the loader rejects non-finite ones first), oriented by the rotation `world_from_light`.
    /// Takes the image's texels (no copy: an environment image can be large).
    pub fn new(image: Image, scale: f32, world_from_light: Mat3) -> EnvMap {
        debug_assert_eq!(image.width, image.height);
        let res = image.width;
        let mut texels = image.texels;
        for t in texels.iter_mut() {
            let v = *t * scale;
            *t = if v.is_finite() {
                v.max(Vec3::ZERO)
            } else {
                Vec3::ZERO
            };
        }
        let weights: Vec<f32> = texels.iter().map(|&t| luminance(t).max(0.0)).collect();
        let sum = texels
            .iter()
            .fold(glam::DVec3::ZERO, |a, t| a + t.as_dvec3());
        let hash = texels.iter().fold(0u64, |h, t| {
            crate::sampling::hash(&[
                h,
                t.x.to_bits() as u64,
                t.y.to_bits() as u64,
                t.z.to_bits() as u64,
            ])
        });
        EnvMap {
            res,
            dist: Distribution2D::new(&weights, res, res),
            mean: (sum / texels.len().max(1) as f64).as_vec3(),
            texels,
            world_from_light,
            light_from_world: world_from_light.transpose(),
            hash,
            portal: None,
        }
    }

    /// The map restricted to light through `portal`.
    pub fn with_portal(mut self, portal: Portal) -> EnvMap {
        self.portal = Some(portal);
        self
    }

    /// Whether light from direction `w` reaches `o` (always, without a portal).
    pub fn admits(&self, o: Vec3, w: Vec3) -> bool {
        self.portal.is_none_or(|p| p.admits(o, w))
    }

    /// Whether a photon from `p` along `dir` enters the scene (always, without a portal).
    pub fn admits_photon(&self, p: Vec3, dir: Vec3) -> bool {
        self.portal.is_none_or(|p_| p_.admits_photon(p, dir))
    }

    /// A constant radiance `l` (a 1x1 map).
    pub fn constant(l: Vec3) -> EnvMap {
        let image = Image {
            width: 1,
            height: 1,
            texels: vec![l],
        };
        EnvMap::new(image, 1.0, Mat3::IDENTITY)
    }

    /// Whether the map sends the same radiance from every direction (a constant `L`, or an
    /// image of one colour) with no portal: pbrt-v4's `UniformInfiniteLight`, which its path
    /// tracers leave to BSDF sampling ([`super::Receiver::sky_by_bsdf`]).
    pub fn is_uniform(&self) -> bool {
        self.portal.is_none() && self.texels.iter().all(|&t| t == self.texels[0])
    }

    /// Texels per side.
    pub fn resolution(&self) -> usize {
        self.res
    }

    /// The mean radiance over the sphere (texels have equal solid angles).
    pub fn mean(&self) -> Vec3 {
        self.mean
    }

    /// Bytes held: the texels and the sampling distribution.
    pub fn bytes(&self) -> u64 {
        (self.texels.len() * 12) as u64 + self.dist.bytes()
    }

    /// Radiance of texel `(x, y)`.
    pub fn texel(&self, x: usize, y: usize) -> Vec3 {
        self.texels[y * self.res + x]
    }

    /// The point of the square a world direction `w` (towards the environment) falls on.
    pub fn square_point(&self, w: Vec3) -> Vec2 {
        equal_area_sphere_to_square((self.light_from_world * w).normalize_or_zero())
    }

    /// The world direction of point `p` of the square.
    pub fn direction(&self, p: Vec2) -> Vec3 {
        (self.world_from_light * equal_area_square_to_sphere(p)).normalize_or_zero()
    }

    /// Radiance arriving from direction `w` (unit, pointing towards the environment).
    pub fn le(&self, w: Vec3) -> Vec3 {
        let (x, y) = self.dist.cell(self.square_point(w));
        self.texel(x, y)
    }

    /// Solid-angle density with which [`Self::sample`] returns `w`.
    pub fn pdf(&self, w: Vec3) -> f32 {
        self.dist.pdf(self.square_point(w)) / (4.0 * PI)
    }

    /// A direction towards the environment, its radiance and its solid-angle density.
    pub fn sample(&self, u: Vec2) -> Option<(Vec3, Vec3, f32)> {
        let (p, pdf, (x, y)) = self.dist.sample(u)?;
        let w = self.direction(p);
        (pdf > 0.0).then(|| (w, self.texel(x, y), pdf / (4.0 * PI)))
    }

    /// Emitted power through the scene's bounding sphere of radius `radius` (computed in f64,
    /// at most `f32::MAX`: a huge scene under a bright sky must not make it infinite).
    pub fn power(&self, radius: f32) -> f32 {
        let r = radius as f64;
        let p = 4.0 * std::f64::consts::PI.powi(2) * r * r * scalar_power(self.mean) as f64;
        p.min(f32::MAX as f64) as f32
    }

    /// Illuminance (the cosine-weighted integral of `L`) on a surface facing `+z` of the
    /// light's frame, with pbrt-v4's rule: the texels whose centre lies above the horizon, each
    /// of solid angle `4 pi / N` (pbrt-v4's code weighs them `2 pi / N`, which is half the
    /// integral: see the loader). Luminance of the texels.
    pub fn upper_illuminance(image: &Image) -> f64 {
        let n = image.width;
        let mut sum = 0.0f64;
        for y in 0..image.height {
            for x in 0..n {
                let p = Vec2::new(
                    (x as f32 + 0.5) / n as f32,
                    (y as f32 + 0.5) / image.height as f32,
                );
                let w = equal_area_square_to_sphere(p);
                if w.z > 0.0 {
                    sum += (luminance(image.texels[y * n + x]) * w.z) as f64;
                }
            }
        }
        sum * 4.0 * std::f64::consts::PI / (n * image.height) as f64
    }
}
