//! pbrt-v4's `uniformgrid` medium: a density grid scaling `sigma_a` and `sigma_s`.
//!
//! ```text
//! AttributeBegin
//!   Translate 0 1 0                       # the CTM here places the grid (pbrt-v4's
//!   MakeNamedMedium "smoke" "string type" "uniformgrid"   # renderFromMedium)
//!       "integer nx" 2 "integer ny" 2 "integer nz" 1 "float density" [ 0 1 2 3 ]
//!       "point3 p0" [ 0 0 0 ] "point3 p1" [ 1 1 1 ]
//!       "rgb sigma_a" [ 1 1 1 ] "rgb sigma_s" [ 1 1 1 ] "float scale" 1
//! AttributeEnd
//! ```
//!
//! The density at a point is pbrt-v4's `SampledGrid` lookup: samples at voxel centres of the
//! box `p0..p1` (x fastest, then y, then z), trilinear between them, and 0 beyond the outer
//! samples (so the density fades to half at the box's faces and to 0 half a voxel outside).
//! Rays in such a medium are tracked against one majorant, `max(sigma_t) * max(density)`:
//! interactions by spectral tracking (Kutz et al. 2017: a tentative collision is a scattering
//! one with probability `mean(sigma_s(x)) / majorant`, else a null one, each weighing the
//! throughput per channel so that the estimate stays unbiased), transmittance by ratio
//! tracking, and the beam estimates' transmittance by marching half a voxel at a time.
use crate::math::{Mat4, Vec3};

/// The density grid of a `uniformgrid` medium.
#[derive(Clone, Debug, PartialEq)]
pub struct DensityGrid {
    /// Samples along x, y, z.
    pub n: [usize; 3],
    /// `n[0] * n[1] * n[2]` densities, x fastest.
    pub values: Vec<f32>,
    /// The box the samples span, in the medium's space.
    pub p0: Vec3,
    pub p1: Vec3,
    /// World (render) space to the medium's space (the inverse CTM at `MakeNamedMedium`).
    pub medium_from_world: Mat4,
    /// The largest density.
    pub max: f32,
}

impl DensityGrid {
    /// The density at world point `p`.
    pub fn density(&self, p: Vec3) -> f32 {
        let q = self.medium_from_world.transform_point3(p);
        let u = (q - self.p0) / (self.p1 - self.p0);
        let s = [
            u.x * self.n[0] as f32 - 0.5,
            u.y * self.n[1] as f32 - 0.5,
            u.z * self.n[2] as f32 - 0.5,
        ];
        if !(s[0].is_finite() && s[1].is_finite() && s[2].is_finite()) {
            return 0.0;
        }
        let i = s.map(|v| v.floor());
        let f = [s[0] - i[0], s[1] - i[1], s[2] - i[2]];
        let at = |x: f32, y: f32, z: f32| -> f32 {
            let (x, y, z) = (x as i64, y as i64, z as i64);
            if x < 0
                || y < 0
                || z < 0
                || x >= self.n[0] as i64
                || y >= self.n[1] as i64
                || z >= self.n[2] as i64
            {
                return 0.0;
            }
            self.values[(z as usize * self.n[1] + y as usize) * self.n[0] + x as usize]
        };
        let lerp = |a: f32, b: f32, t: f32| a + (b - a) * t;
        let c = |dy: f32, dz: f32| {
            lerp(
                at(i[0], i[1] + dy, i[2] + dz),
                at(i[0] + 1.0, i[1] + dy, i[2] + dz),
                f[0],
            )
        };
        lerp(
            lerp(c(0.0, 0.0), c(1.0, 0.0), f[1]),
            lerp(c(0.0, 1.0), c(1.0, 1.0), f[1]),
            f[2],
        )
    }

    /// The part `[t0, t1]` of the ray `o + t d` (world space) where the density may be non-zero
    /// (the box `p0..p1` grown by half a voxel); `t0 > t1` when it misses.
    pub fn clip(&self, o: Vec3, d: Vec3) -> (f32, f32) {
        let om = self.medium_from_world.transform_point3(o);
        let dm = self.medium_from_world.transform_vector3(d);
        let half = (self.p1 - self.p0)
            / Vec3::new(self.n[0] as f32, self.n[1] as f32, self.n[2] as f32)
            * 0.5;
        let (lo, hi) = (self.p0 - half, self.p1 + half);
        let inv = dm.recip();
        let (a, b) = ((lo - om) * inv, (hi - om) * inv);
        let t0 = a.min(b).max_element().max(0.0);
        let t1 = a.max(b).min_element();
        if t0.is_nan() || t1.is_nan() {
            return (1.0, 0.0);
        }
        (t0, t1)
    }

    /// The ray parameter step that moves half the smallest voxel along world direction `d`
    /// (the beam estimates' marching step).
    pub fn half_voxel_step(&self, d: Vec3) -> f32 {
        let dm = self.medium_from_world.transform_vector3(d);
        let voxel = (self.p1 - self.p0).abs()
            / Vec3::new(self.n[0] as f32, self.n[1] as f32, self.n[2] as f32);
        0.5 * voxel.min_element() / dm.length().max(1e-30)
    }
}

/// A small deterministic random stream (SplitMix64), for the many numbers tracking takes
/// beyond the sampler's two per segment.
pub struct Rng(u64);

impl Rng {
    /// A stream keyed by `key`.
    pub fn new(key: u64) -> Rng {
        Rng(key)
    }

    /// The next uniform float in [0, 1).
    pub fn uniform(&mut self) -> f32 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        crate::sampling::to_unit(crate::sampling::mix64(self.0))
    }
}

/// Tentative collisions a tracker takes before it gives up on a segment (its throughput is
/// then taken as 0: a majorant this far above the ray's real density would be a scene error).
pub const MAX_COLLISIONS: u32 = 100_000;

#[cfg(test)]
mod tests {
    use super::*;

    fn grid(n: [usize; 3], values: Vec<f32>) -> DensityGrid {
        let max = values.iter().cloned().fold(0.0, f32::max);
        DensityGrid {
            n,
            values,
            p0: Vec3::ZERO,
            p1: Vec3::ONE,
            medium_from_world: Mat4::IDENTITY,
            max,
        }
    }

    #[test]
    fn lookups_are_trilinear_between_voxel_centres_and_fade_outside() {
        // Density x * 4 sampled at x centres 1/8, 3/8, 5/8, 7/8: linear inside.
        let g = grid([4, 1, 1], vec![0.5, 1.5, 2.5, 3.5]);
        for x in [0.125f32, 0.3, 0.5, 0.8, 0.875] {
            let d = g.density(Vec3::new(x, 0.5, 0.5));
            assert!((d - 4.0 * x).abs() < 1e-5, "{x}: {d}");
        }
        // Half a voxel outside the last centre it fades linearly: at the face, half.
        assert!((g.density(Vec3::new(1.0, 0.5, 0.5)) - 1.75).abs() < 1e-5);
        assert_eq!(g.density(Vec3::new(1.2, 0.5, 0.5)), 0.0);
        assert_eq!(g.density(Vec3::new(0.5, 1.6, 0.5)), 0.0);
        // The CTM moves it.
        let mut m = g.clone();
        m.medium_from_world = Mat4::from_translation(Vec3::new(-10.0, 0.0, 0.0));
        assert!((m.density(Vec3::new(10.5, 0.5, 0.5)) - 2.0).abs() < 1e-5);
    }
}
