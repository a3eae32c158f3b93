//! Warps from the unit square to the domains the renderer samples, each with its density.
use crate::math::{Vec2, Vec3};
use std::f32::consts::{FRAC_PI_2, FRAC_PI_4, PI};

/// Concentric (Shirley-Chiu) map of [0,1)^2 onto the unit disc.
pub fn square_to_disk_concentric(u: Vec2) -> Vec2 {
    let o = 2.0 * u - Vec2::ONE;
    if o.x == 0.0 && o.y == 0.0 {
        return Vec2::ZERO;
    }
    let (r, theta) = if o.x.abs() > o.y.abs() {
        (o.x, FRAC_PI_4 * (o.y / o.x))
    } else {
        (o.y, FRAC_PI_2 - FRAC_PI_4 * (o.x / o.y))
    };
    r * Vec2::new(theta.cos(), theta.sin())
}

/// Cosine-weighted direction about +z; density `cos(theta) / pi`.
pub fn square_to_cosine_hemisphere(u: Vec2) -> Vec3 {
    let d = square_to_disk_concentric(u);
    let z = (1.0 - d.length_squared()).max(0.0).sqrt();
    Vec3::new(d.x, d.y, z)
}

pub fn cosine_hemisphere_pdf(cos_theta: f32) -> f32 {
    cos_theta.max(0.0) / PI
}

/// Uniform direction on the unit sphere; density `1 / (4 pi)`.
pub fn square_to_uniform_sphere(u: Vec2) -> Vec3 {
    let z = 1.0 - 2.0 * u.x;
    let r = (1.0 - z * z).max(0.0).sqrt();
    let phi = 2.0 * PI * u.y;
    Vec3::new(r * phi.cos(), r * phi.sin(), z)
}

/// Uniform direction in the cone about +z with `cos(theta) >= cos_max`; density
/// `1 / (2 pi (1 - cos_max))`.
pub fn square_to_uniform_cone(u: Vec2, cos_max: f32) -> Vec3 {
    let z = 1.0 - u.x * (1.0 - cos_max);
    let r = (1.0 - z * z).max(0.0).sqrt();
    let phi = 2.0 * PI * u.y;
    Vec3::new(r * phi.cos(), r * phi.sin(), z)
}

/// Uniform barycentrics `(b1, b2)` on a triangle (weights `1 - b1 - b2, b1, b2`).
pub fn square_to_triangle(u: Vec2) -> Vec2 {
    // Heitz's low-distortion warp (2019): area-preserving, keeps stratification.
    let (mut b0, mut b1);
    if u.x < u.y {
        b0 = u.x / 2.0;
        b1 = u.y - b0;
    } else {
        b1 = u.y / 2.0;
        b0 = u.x - b1;
    }
    b0 = b0.clamp(0.0, 1.0);
    b1 = b1.clamp(0.0, 1.0 - b0);
    Vec2::new(b1, 1.0 - b0 - b1)
}

/// Discrete distribution over `n` items by weight, sampled by inverting its CDF.
#[derive(Clone, Debug, Default)]
pub struct Distribution1D {
    cdf: Vec<f32>,
    total: f32,
}

impl Distribution1D {
    /// `weights` must be finite and non-negative; an all-zero list samples nothing.
    pub fn new(weights: &[f32]) -> Self {
        let mut cdf = Vec::with_capacity(weights.len());
        let mut acc = 0.0f64;
        for &w in weights {
            acc += w.max(0.0) as f64;
            cdf.push(acc as f32);
        }
        Distribution1D {
            cdf,
            total: acc as f32,
        }
    }

    pub fn total(&self) -> f32 {
        self.total
    }

    pub fn len(&self) -> usize {
        self.cdf.len()
    }

    pub fn is_empty(&self) -> bool {
        self.cdf.is_empty()
    }

    /// Probability of item `i`.
    pub fn pmf(&self, i: usize) -> f32 {
        if self.total <= 0.0 {
            return 0.0;
        }
        let lo = if i == 0 { 0.0 } else { self.cdf[i - 1] };
        (self.cdf[i] - lo) / self.total
    }

    /// Picks an item for `u` in [0, 1); returns `(index, probability, u remapped to [0, 1))`.
    pub fn sample(&self, u: f32) -> Option<(usize, f32, f32)> {
        if self.total <= 0.0 {
            return None;
        }
        let target = u * self.total;
        let i = self
            .cdf
            .partition_point(|&c| c <= target)
            .min(self.cdf.len() - 1);
        let lo = if i == 0 { 0.0 } else { self.cdf[i - 1] };
        let w = self.cdf[i] - lo;
        if w <= 0.0 {
            return None;
        }
        let rem = ((target - lo) / w).clamp(0.0, super::ONE_MINUS_EPSILON);
        Some((i, w / self.total, rem))
    }
}

/// Piecewise-constant density over `[0,1]^2` on a `width x height` grid of non-negative values
/// (pbrt-v4's `PiecewiseConstant2D`): a row by its sum (marginal), then a column within it
/// (conditional). Cell `(x, y)` has density `f(x, y) / mean(f)`.
#[derive(Clone, Debug, Default)]
pub struct Distribution2D {
    width: usize,
    height: usize,
    rows: Vec<Distribution1D>,
    marginal: Distribution1D,
}

impl Distribution2D {
    /// `f` holds `width * height` values row by row (row 0 first). An all-zero grid samples
    /// nothing.
    pub fn new(f: &[f32], width: usize, height: usize) -> Distribution2D {
        let rows: Vec<Distribution1D> = f
            .chunks_exact(width.max(1))
            .take(height)
            .map(Distribution1D::new)
            .collect();
        let sums: Vec<f32> = rows.iter().map(|r| r.total()).collect();
        Distribution2D {
            width,
            height,
            rows,
            marginal: Distribution1D::new(&sums),
        }
    }

    /// A point of the square for `u`, its density and its cell `(x, y)` (the point can round
    /// onto the next cell's edge); keeps `u`'s stratification (each coordinate is re-stretched
    /// inside its cell).
    pub fn sample(&self, u: Vec2) -> Option<(Vec2, f32, (usize, usize))> {
        let (y, py, ry) = self.marginal.sample(u.y)?;
        let (x, px, rx) = self.rows[y].sample(u.x)?;
        let p = Vec2::new(
            (x as f32 + rx) / self.width as f32,
            (y as f32 + ry) / self.height as f32,
        );
        let pdf = py * px * (self.width * self.height) as f32;
        Some((p.min(Vec2::splat(super::ONE_MINUS_EPSILON)), pdf, (x, y)))
    }

    /// The cell holding `p` (clamped to the grid).
    pub fn cell(&self, p: Vec2) -> (usize, usize) {
        let at = |v: f32, n: usize| ((v * n as f32).max(0.0) as usize).min(n.max(1) - 1);
        (at(p.x, self.width), at(p.y, self.height))
    }

    /// Density of [`Self::sample`] at `p`.
    pub fn pdf(&self, p: Vec2) -> f32 {
        if self.marginal.total() <= 0.0 {
            return 0.0;
        }
        let (x, y) = self.cell(p);
        self.marginal.pmf(y) * self.rows[y].pmf(x) * (self.width * self.height) as f32
    }

    /// Bytes held (one f32 per cell and per row).
    pub fn bytes(&self) -> u64 {
        ((self.width + 1) * self.height * 4) as u64
    }
}

/// pbrt-v4's equal-area octahedral map of the unit square onto the sphere (Clarberg): the
/// inner diamond `|2u-1| + |2v-1| < 1` is the upper hemisphere (z > 0), the corners the lower
/// one; equal areas of the square map to equal solid angles (4 pi times the area).
pub fn equal_area_square_to_sphere(p: Vec2) -> Vec3 {
    let (u, v) = (2.0 * p.x - 1.0, 2.0 * p.y - 1.0);
    let (up, vp) = (u.abs(), v.abs());
    let signed = 1.0 - (up + vp);
    let r = 1.0 - signed.abs();
    let phi = if r == 0.0 { 1.0 } else { (vp - up) / r + 1.0 } * FRAC_PI_4;
    let z = (1.0 - r * r).copysign(signed);
    let s = r * (2.0 - r * r).max(0.0).sqrt();
    Vec3::new(phi.cos().copysign(u) * s, phi.sin().copysign(v) * s, z)
}

/// The inverse of [`equal_area_square_to_sphere`] for a unit vector `d` (exact `atan`, where
/// pbrt-v4 uses a polynomial fit of it).
pub fn equal_area_sphere_to_square(d: Vec3) -> Vec2 {
    let (x, y, z) = (d.x.abs(), d.y.abs(), d.z.abs());
    let r = (1.0 - z).max(0.0).sqrt();
    let (a, b) = (x.max(y), x.min(y));
    let b = if a == 0.0 { 0.0 } else { b / a };
    let mut phi = b.atan() * (2.0 / PI);
    if x < y {
        phi = 1.0 - phi;
    }
    let mut v = phi * r;
    let mut u = r - v;
    if d.z < 0.0 {
        (u, v) = (1.0 - v, 1.0 - u);
    }
    let (u, v) = (u.copysign(d.x), v.copysign(d.y));
    Vec2::new(0.5 * (u + 1.0), 0.5 * (v + 1.0))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn warps_land_in_their_domains() {
        for i in 0..32 {
            for j in 0..32 {
                let u = Vec2::new((i as f32 + 0.5) / 32.0, (j as f32 + 0.5) / 32.0);
                assert!(square_to_disk_concentric(u).length() <= 1.0 + 1e-6);
                let h = square_to_cosine_hemisphere(u);
                assert!(h.z >= 0.0 && (h.length() - 1.0).abs() < 1e-5);
                assert!((square_to_uniform_sphere(u).length() - 1.0).abs() < 1e-5);
                assert!(square_to_uniform_cone(u, 0.9).z >= 0.9 - 1e-6);
                let b = square_to_triangle(u);
                assert!(b.x >= 0.0 && b.y >= 0.0 && b.x + b.y <= 1.0 + 1e-6);
            }
        }
    }

    /// The triangle warp is area-preserving: the mean of the barycentrics is 1/3 each.
    #[test]
    fn triangle_warp_is_uniform() {
        let n = 256;
        let mut m = Vec2::ZERO;
        for i in 0..n {
            for j in 0..n {
                m += square_to_triangle(Vec2::new(
                    (i as f32 + 0.5) / n as f32,
                    (j as f32 + 0.5) / n as f32,
                ));
            }
        }
        m /= (n * n) as f32;
        assert!(
            (m - Vec2::splat(1.0 / 3.0)).abs().max_element() < 1e-3,
            "{m:?}"
        );
    }

    #[test]
    fn distribution_samples_by_weight() {
        let d = Distribution1D::new(&[1.0, 0.0, 3.0]);
        assert_eq!(d.sample(0.1).unwrap().0, 0);
        assert_eq!(d.sample(0.3).unwrap().0, 2);
        assert!((d.pmf(2) - 0.75).abs() < 1e-6 && d.pmf(1) == 0.0);
        assert!(Distribution1D::new(&[0.0, 0.0]).sample(0.5).is_none());
    }
}
