//! The anisotropic Trowbridge-Reitz (GGX) microfacet distribution as pbrt-v4 defines it:
//! the normal distribution `D`, Smith's `Lambda`, `G1` and the height-correlated `G`, the
//! distribution of visible normals `D_w(wm) = G1(w) max(0, w.wm) D(wm) / |cos w|` and its
//! exact sampling (Heitz 2018, in pbrt-v4's formulation `Sample_wm`).
//!
//! Directions are in the local shading frame (z = normal); `alpha_x`/`alpha_y` are the
//! roughnesses along the local x and y axes (already remapped from pbrt's `roughness`).
use super::warp::square_to_uniform_disk_polar;
use crate::math::{Vec2, Vec3};
use std::f32::consts::PI;

/// Below this roughness (in both directions) the surface is treated as a perfect specular
/// one (pbrt-v4's `EffectivelySmooth`).
pub const SMOOTH_ALPHA: f32 = 1e-3;

/// Smallest roughness kept for a rough surface, to avoid numerical trouble (as pbrt-v4).
const MIN_ALPHA: f32 = 1e-4;

/// Anisotropic Trowbridge-Reitz distribution of microfacet normals.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TrowbridgeReitz {
    alpha_x: f32,
    alpha_y: f32,
}

impl TrowbridgeReitz {
    /// A distribution with roughness `alpha_x` along local x and `alpha_y` along local y.
    /// Negative or non-finite values are read as 0; if the surface is not effectively smooth,
    /// both are raised to at least 1e-4.
    pub fn new(alpha_x: f32, alpha_y: f32) -> Self {
        let clean = |a: f32| if a.is_finite() && a > 0.0 { a } else { 0.0 };
        let mut d = TrowbridgeReitz {
            alpha_x: clean(alpha_x),
            alpha_y: clean(alpha_y),
        };
        if !d.effectively_smooth() {
            d.alpha_x = d.alpha_x.max(MIN_ALPHA);
            d.alpha_y = d.alpha_y.max(MIN_ALPHA);
        }
        d
    }

    pub fn alpha_x(&self) -> f32 {
        self.alpha_x
    }

    pub fn alpha_y(&self) -> f32 {
        self.alpha_y
    }

    /// True when both roughnesses are below [`SMOOTH_ALPHA`]: sample it as a delta lobe.
    pub fn effectively_smooth(&self) -> bool {
        self.alpha_x.max(self.alpha_y) < SMOOTH_ALPHA
    }

    /// Microfacet normal density `D(wm)` (per unit solid angle, normalised so that
    /// `integral D(wm) cos(theta_m) dwm = 1`). `wm` is a unit vector.
    ///
    /// Uses `1 / (pi ax ay (x^2/ax^2 + y^2/ay^2 + z^2)^2)`, algebraically identical to pbrt's
    /// `1 / (pi ax ay cos^4 (1 + tan^2 (cos^2 phi / ax^2 + sin^2 phi / ay^2))^2)` for unit `wm`.
    pub fn d(&self, wm: Vec3) -> f32 {
        let cos2 = wm.z * wm.z;
        if cos2 * cos2 < 1e-16 {
            return 0.0;
        }
        let sx = wm.x / self.alpha_x;
        let sy = wm.y / self.alpha_y;
        let s = sx * sx + sy * sy + cos2;
        1.0 / (PI * self.alpha_x * self.alpha_y * s * s)
    }

    /// Smith's auxiliary function `Lambda(w) = (sqrt(1 + alpha^2 tan^2 theta) - 1) / 2` with
    /// the direction's projected roughness `alpha^2 = ax^2 cos^2 phi + ay^2 sin^2 phi`.
    /// Returns 0 for a direction exactly in the tangent plane (as pbrt-v4).
    pub fn lambda(&self, w: Vec3) -> f32 {
        let cos2 = w.z * w.z;
        if cos2 == 0.0 {
            return 0.0;
        }
        let ax = self.alpha_x * w.x;
        let ay = self.alpha_y * w.y;
        // alpha^2 tan^2(theta) = (ax^2 x^2 + ay^2 y^2) / z^2.
        let a = (ax * ax + ay * ay) / cos2;
        if !a.is_finite() {
            return 0.0;
        }
        // (sqrt(1 + a) - 1) / 2 without the cancellation for small a.
        0.5 * a / ((1.0 + a).sqrt() + 1.0)
    }

    /// Smith's masking function `G1(w) = 1 / (1 + Lambda(w))`.
    pub fn g1(&self, w: Vec3) -> f32 {
        1.0 / (1.0 + self.lambda(w))
    }

    /// Height-correlated masking-shadowing `G(wo, wi) = 1 / (1 + Lambda(wo) + Lambda(wi))`.
    pub fn g(&self, wo: Vec3, wi: Vec3) -> f32 {
        1.0 / (1.0 + self.lambda(wo) + self.lambda(wi))
    }

    /// Distribution of normals visible from `w`:
    /// `D_w(wm) = G1(w) / |cos(theta_w)| * D(wm) * max(0, w . wm)` (pbrt-v4's `D(w, wm)`,
    /// which uses `|w . wm|`; identical for the normals `sample_wm` produces).
    pub fn d_visible(&self, w: Vec3, wm: Vec3) -> f32 {
        let cos_w = w.z.abs();
        if cos_w == 0.0 {
            return 0.0;
        }
        self.g1(w) / cos_w * self.d(wm) * w.dot(wm).abs()
    }

    /// Density (per solid angle of `wm`) with which [`Self::sample_wm`] returns `wm` from `w`.
    pub fn pdf(&self, w: Vec3, wm: Vec3) -> f32 {
        self.d_visible(w, wm)
    }

    /// Samples a microfacet normal visible from `w` (unit) with density [`Self::pdf`]; `u` is
    /// uniform in `[0,1)^2`. The result is in the upper hemisphere; a `w` below the surface is
    /// treated as its mirror image, as pbrt-v4 does.
    pub fn sample_wm(&self, w: Vec3, u: Vec2) -> Vec3 {
        // Stretch w to the configuration where the roughness is 1 (a hemisphere).
        let mut wh = Vec3::new(self.alpha_x * w.x, self.alpha_y * w.y, w.z).normalize();
        if wh.z < 0.0 {
            wh = -wh;
        }
        // An orthonormal basis around wh.
        let t1 = if wh.z < 0.99999 {
            Vec3::Z.cross(wh).normalize()
        } else {
            Vec3::X
        };
        let t2 = wh.cross(t1);
        // Uniform disc, then squash the half of it hidden behind the projected hemisphere.
        let mut p = square_to_uniform_disk_polar(u);
        let h = (1.0 - p.x * p.x).max(0.0).sqrt();
        let s = 0.5 * (1.0 + wh.z);
        p.y = (1.0 - s) * h + s * p.y;
        // Reproject onto the hemisphere and unstretch.
        let pz = (1.0 - p.length_squared()).max(0.0).sqrt();
        let nh = p.x * t1 + p.y * t2 + pz * wh;
        Vec3::new(self.alpha_x * nh.x, self.alpha_y * nh.y, nh.z.max(1e-6)).normalize()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bsdf::testutil::{integrate_normals, spherical, Rng};

    const ALPHAS: [(f32, f32); 7] = [
        (0.05, 0.05),
        (0.1, 0.1),
        (0.3, 0.3),
        (1.0, 1.0),
        (0.05, 0.3),
        (0.5, 0.1),
        (0.2, 1.0),
    ];

    #[test]
    fn d_is_normalised_in_the_projected_sense() {
        for &(ax, ay) in &ALPHAS {
            let d = TrowbridgeReitz::new(ax, ay);
            let integral =
                integrate_normals(ax.min(ay), 4000, 512, |wm| d.d(wm) as f64 * wm.z as f64);
            println!("alpha ({ax}, {ay}): integral D cos = {integral:.6}");
            assert!(
                (integral - 1.0).abs() < 2e-3,
                "alpha ({ax}, {ay}): {integral}"
            );
        }
    }

    #[test]
    fn visible_normals_are_normalised_for_every_direction() {
        // integral G1(w) max(0, w.wm) D(wm) dwm = cos(theta_w): checks Lambda against D.
        for &(ax, ay) in &ALPHAS {
            let d = TrowbridgeReitz::new(ax, ay);
            for (theta, phi) in [(0.0f32, 0.0f32), (0.6, 0.3), (1.2, 2.0), (1.5, 4.0)] {
                let w = spherical(theta, phi);
                let integral = integrate_normals(ax.min(ay), 3000, 512, |wm| {
                    if w.dot(wm) > 0.0 {
                        d.pdf(w, wm) as f64
                    } else {
                        0.0
                    }
                });
                assert!(
                    (integral - 1.0).abs() < 3e-3,
                    "alpha ({ax}, {ay}) theta {theta}: {integral}"
                );
            }
        }
    }

    #[test]
    fn lambda_matches_closed_form_isotropic() {
        // Isotropic GGX: Lambda = (-1 + sqrt(1 + alpha^2 tan^2 theta)) / 2 (Walter et al. 2007).
        for &alpha in &[0.1f32, 0.5, 1.0] {
            let d = TrowbridgeReitz::new(alpha, alpha);
            for &theta in &[0.1f32, 0.7, 1.3, 1.55] {
                let t = (theta as f64).tan() * alpha as f64;
                let want = 0.5 * (-1.0 + (1.0 + t * t).sqrt());
                let got = d.lambda(spherical(theta, 0.9)) as f64;
                assert!((got - want).abs() < 1e-4 * (1.0 + want), "{got} vs {want}");
            }
        }
    }

    #[test]
    fn sampled_normals_follow_the_visible_distribution() {
        // E[g(wm) / pdf(wm)] = integral of g over the visible side, for g = 1 and g = wm.z^4.
        let mut rng = Rng::new(3);
        for &(ax, ay) in &[(0.1f32, 0.1f32), (0.3, 0.3), (0.2, 0.8), (1.0, 1.0)] {
            let d = TrowbridgeReitz::new(ax, ay);
            for theta in [0.2f32, 1.0, 1.45] {
                let w = spherical(theta, 0.7);
                let g = |wm: Vec3| (wm.z as f64).powi(4) + wm.x.max(0.0) as f64;
                let want = integrate_normals(ax.min(ay), 3000, 512, |wm| {
                    if w.dot(wm) > 0.0 {
                        g(wm) * d.pdf(w, wm) as f64
                    } else {
                        0.0
                    }
                });
                let n = 200_000;
                let xs: Vec<f64> = (0..n)
                    .map(|_| {
                        let wm = d.sample_wm(w, rng.vec2());
                        assert!(wm.z > 0.0 && w.dot(wm) >= -1e-4);
                        g(wm)
                    })
                    .collect();
                let (mean, se) = crate::bsdf::testutil::mean_and_stderr(&xs);
                assert!(
                    (mean - want).abs() < 3.0 * se + 2e-3,
                    "alpha ({ax},{ay}) theta {theta}: {mean} +- {se} vs {want}"
                );
            }
        }
    }

    #[test]
    fn bad_roughness_is_sanitised() {
        let d = TrowbridgeReitz::new(f32::NAN, -1.0);
        assert!(d.effectively_smooth());
        let d = TrowbridgeReitz::new(0.0, 0.5);
        assert!(!d.effectively_smooth());
        assert_eq!(d.alpha_x(), MIN_ALPHA);
        assert!(d.d(Vec3::Z).is_finite());
    }
}
