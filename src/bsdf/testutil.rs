//! Test helpers for the BSDF unit tests: a small deterministic random generator
//! (SplitMix64) and uniform sphere directions.
use crate::math::{Vec2, Vec3};
use std::f32::consts::PI;

/// SplitMix64 (Steele, Lea, Flood 2014): tiny, seedable, good enough for Monte Carlo checks.
pub(crate) struct Rng(u64);

impl Rng {
    pub(crate) fn new(seed: u64) -> Self {
        Rng(seed.wrapping_mul(0x9E37_79B9_7F4A_7C15) ^ 0x2545_F491_4F6C_DD1D)
    }

    pub(crate) fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }

    /// Uniform in `[0, 1)`.
    pub(crate) fn f32(&mut self) -> f32 {
        (self.next_u64() >> 40) as f32 * (1.0 / (1u64 << 24) as f32)
    }

    pub(crate) fn vec2(&mut self) -> Vec2 {
        Vec2::new(self.f32(), self.f32())
    }

    /// Uniform direction on the unit sphere.
    pub(crate) fn sphere(&mut self) -> Vec3 {
        let z = 1.0 - 2.0 * self.f32();
        let r = (1.0 - z * z).max(0.0).sqrt();
        let phi = 2.0 * PI * self.f32();
        Vec3::new(r * phi.cos(), r * phi.sin(), z)
    }

    /// Uniform direction on the upper (+z) hemisphere.
    pub(crate) fn hemisphere(&mut self) -> Vec3 {
        let w = self.sphere();
        Vec3::new(w.x, w.y, w.z.abs())
    }
}

/// Mean and standard error of the mean of a sample set.
pub(crate) fn mean_and_stderr(xs: &[f64]) -> (f64, f64) {
    let n = xs.len() as f64;
    let mean = xs.iter().sum::<f64>() / n;
    let var = xs.iter().map(|x| (x - mean) * (x - mean)).sum::<f64>() / (n - 1.0);
    (mean, (var / n).sqrt())
}

/// A unit direction at polar angle `theta` (from +z) and azimuth `phi`.
pub(crate) fn spherical(theta: f32, phi: f32) -> Vec3 {
    Vec3::new(
        theta.sin() * phi.cos(),
        theta.sin() * phi.sin(),
        theta.cos(),
    )
}

/// Integrates `g(wm)` over the upper hemisphere of microfacet normals with a midpoint rule
/// in `(s, phi)`, where `tan(theta) = alpha * s / (1 - s)`: the substitution concentrates
/// the nodes where a lobe of width `alpha` lives, so peaky distributions integrate well.
pub(crate) fn integrate_normals(
    alpha: f32,
    n_s: usize,
    n_phi: usize,
    g: impl Fn(Vec3) -> f64,
) -> f64 {
    let alpha = alpha as f64;
    let mut sum = 0.0;
    for i in 0..n_s {
        let s = (i as f64 + 0.5) / n_s as f64;
        let x = s / (1.0 - s);
        let dx_ds = 1.0 / ((1.0 - s) * (1.0 - s));
        let theta = (alpha * x).atan();
        let dtheta_dx = alpha / (1.0 + alpha * alpha * x * x);
        let jac = theta.sin() * dtheta_dx * dx_ds / n_s as f64
            * (2.0 * std::f64::consts::PI / n_phi as f64);
        for j in 0..n_phi {
            let phi = (j as f64 + 0.5) / n_phi as f64 * 2.0 * std::f64::consts::PI;
            let wm = spherical(theta as f32, phi as f32);
            sum += g(wm) * jac;
        }
    }
    sum
}
