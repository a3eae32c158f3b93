//! pbrt-v4's `cloud` medium: a procedural cloud whose density comes from Perlin noise.
//!
//! ```text
//! MakeNamedMedium "sky" "string type" "cloud" "float density" 1 "float wispiness" 1
//!     "float frequency" 5 "point3 p0" [ 0 0 0 ] "point3 p1" [ 1 1 1 ]
//!     "rgb sigma_a" [ 1 1 1 ] "rgb sigma_s" [ 1 1 1 ] "float g" 0
//! ```
//!
//! The density at a point `p` of the medium's space (the CTM at `MakeNamedMedium` places it;
//! the medium exists only inside the box `p0..p1`) is pbrt-v4's `CloudMedium::Density`: the
//! lookup point `frequency * p` is pushed twice along the gradient of noise (when
//! `wispiness > 0`), five octaves of Perlin noise are summed (weights 1/2, 1/4..., frequencies
//! 1, 1.99, 1.99^2...), the sum is scaled by `(1 - p.y) * 4.5 * density` and clamped to [0, 1],
//! `2 * max(0, 0.5 - p.y)` is added and the result clamped to [0, 1] again. It scales
//! `sigma_a` and `sigma_s`, so the medium's majorant is `max(sigma_t)`.
//!
//! The noise is Perlin's improved noise (2002) on his published permutation table, as pbrt
//! evaluates it (quintic fade, twelve gradient directions folded into sixteen, coordinates
//! wrapped to 2^30 first), so that a cloud here has pbrt-v4's shape.
use crate::math::Vec3;

/// The cloud's parameters.
#[derive(Clone, Debug, PartialEq)]
pub struct Cloud {
    pub density: f32,
    pub wispiness: f32,
    pub frequency: f32,
}

impl Cloud {
    /// The density (in [0, 1]) at `p`, a point of the medium's space.
    pub fn density(&self, p: Vec3) -> f32 {
        let mut pp = p * self.frequency;
        if self.wispiness > 0.0 {
            let (mut omega, mut lambda) = (0.05 * self.wispiness, 10.0f32);
            for _ in 0..2 {
                pp += dnoise(pp * lambda) * omega;
                omega *= 0.5;
                lambda *= 1.99;
            }
        }
        let (mut d, mut omega, mut lambda) = (0.0f32, 0.5f32, 1.0f32);
        for _ in 0..5 {
            d += omega * noise(pp * lambda);
            omega *= 0.5;
            lambda *= 1.99;
        }
        let d = ((1.0 - p.y) * 4.5 * self.density * d).clamp(0.0, 1.0);
        (d + 2.0 * (0.5 - p.y).max(0.0)).clamp(0.0, 1.0)
    }
}

/// Ken Perlin's permutation of 0..255 (from his reference implementation of improved noise).
const PERM: [u8; 256] = [
    151, 160, 137, 91, 90, 15, 131, 13, 201, 95, 96, 53, 194, 233, 7, 225, 140, 36, 103, 30, 69,
    142, 8, 99, 37, 240, 21, 10, 23, 190, 6, 148, 247, 120, 234, 75, 0, 26, 197, 62, 94, 252, 219,
    203, 117, 35, 11, 32, 57, 177, 33, 88, 237, 149, 56, 87, 174, 20, 125, 136, 171, 168, 68, 175,
    74, 165, 71, 134, 139, 48, 27, 166, 77, 146, 158, 231, 83, 111, 229, 122, 60, 211, 133, 230,
    220, 105, 92, 41, 55, 46, 245, 40, 244, 102, 143, 54, 65, 25, 63, 161, 1, 216, 80, 73, 209, 76,
    132, 187, 208, 89, 18, 169, 200, 196, 135, 130, 116, 188, 159, 86, 164, 100, 109, 198, 173,
    186, 3, 64, 52, 217, 226, 250, 124, 123, 5, 202, 38, 147, 118, 126, 255, 82, 85, 212, 207, 206,
    59, 227, 47, 16, 58, 17, 182, 189, 28, 42, 223, 183, 170, 213, 119, 248, 152, 2, 44, 154, 163,
    70, 221, 153, 101, 155, 167, 43, 172, 9, 129, 22, 39, 253, 19, 98, 108, 110, 79, 113, 224, 232,
    178, 185, 112, 104, 218, 246, 97, 228, 251, 34, 242, 193, 238, 210, 144, 12, 191, 179, 162,
    241, 81, 51, 145, 235, 249, 14, 239, 107, 49, 192, 214, 31, 181, 199, 106, 157, 184, 84, 204,
    176, 115, 121, 50, 45, 127, 4, 150, 254, 138, 236, 205, 93, 222, 114, 67, 29, 24, 72, 243, 141,
    128, 195, 78, 66, 215, 61, 156, 180,
];

/// The permutation, indexed past 255 by wrapping (the table doubled).
#[inline]
fn perm(i: usize) -> usize {
    PERM[i & 255] as usize
}

/// The dot product of the corner's pseudo-random gradient with the offset `(x, y, z)`.
#[inline]
fn gradient(ix: usize, iy: usize, iz: usize, x: f32, y: f32, z: f32) -> f32 {
    let h = perm(perm(perm(ix) + iy) + iz) & 15;
    let a = if h < 8 || h == 12 || h == 13 { x } else { y };
    let b = if h < 4 || h == 12 || h == 13 { y } else { z };
    (if h & 1 != 0 { -a } else { a }) + (if h & 2 != 0 { -b } else { b })
}

/// Perlin's quintic fade `6t^5 - 15t^4 + 10t^3`.
#[inline]
fn fade(t: f32) -> f32 {
    t * t * t * (t * (t * 6.0 - 15.0) + 10.0)
}

/// Perlin noise at `p` (0 at integer lattice points, about [-1, 1]).
pub fn noise(p: Vec3) -> f32 {
    let wrap = (1u32 << 30) as f32;
    let c = [p.x % wrap, p.y % wrap, p.z % wrap];
    let fl = c.map(|v| v.floor());
    let d = [c[0] - fl[0], c[1] - fl[1], c[2] - fl[2]];
    let i = fl.map(|v| (v as i64 & 255) as usize);
    let g = |a: usize, b: usize, e: usize| {
        gradient(
            i[0] + a,
            i[1] + b,
            i[2] + e,
            d[0] - a as f32,
            d[1] - b as f32,
            d[2] - e as f32,
        )
    };
    let (wx, wy, wz) = (fade(d[0]), fade(d[1]), fade(d[2]));
    let lerp = |t: f32, a: f32, b: f32| (1.0 - t) * a + t * b;
    let x00 = lerp(wx, g(0, 0, 0), g(1, 0, 0));
    let x10 = lerp(wx, g(0, 1, 0), g(1, 1, 0));
    let x01 = lerp(wx, g(0, 0, 1), g(1, 0, 1));
    let x11 = lerp(wx, g(0, 1, 1), g(1, 1, 1));
    lerp(wz, lerp(wy, x00, x10), lerp(wy, x01, x11))
}

/// The noise's gradient by forward differences of 0.01 (as pbrt's `DNoise`).
pub fn dnoise(p: Vec3) -> Vec3 {
    let delta = 0.01;
    let n = noise(p);
    (Vec3::new(
        noise(p + Vec3::new(delta, 0.0, 0.0)),
        noise(p + Vec3::new(0.0, delta, 0.0)),
        noise(p + Vec3::new(0.0, 0.0, delta)),
    ) - Vec3::splat(n))
        / delta
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Perlin's improved noise written out from his 2002 paper's reference code, in f64 and
    /// with the doubled table, apart from the renderer's.
    fn reference(x: f64, y: f64, z: f64) -> f64 {
        let p: Vec<usize> = PERM
            .iter()
            .chain(PERM.iter())
            .map(|&v| v as usize)
            .collect();
        let (xi, yi, zi) = (
            (x.floor() as i64 & 255) as usize,
            (y.floor() as i64 & 255) as usize,
            (z.floor() as i64 & 255) as usize,
        );
        let (x, y, z) = (x - x.floor(), y - y.floor(), z - z.floor());
        let f = |t: f64| t * t * t * (t * (t * 6.0 - 15.0) + 10.0);
        let (u, v, w) = (f(x), f(y), f(z));
        let grad = |h: usize, x: f64, y: f64, z: f64| {
            let h = h & 15;
            let u = if h < 8 { x } else { y };
            let v = if h < 4 {
                y
            } else if h == 12 || h == 14 {
                x
            } else {
                z
            };
            (if h & 1 == 0 { u } else { -u }) + (if h & 2 == 0 { v } else { -v })
        };
        let lerp = |t: f64, a: f64, b: f64| a + t * (b - a);
        let a = p[xi] + yi;
        let (aa, ab) = (p[a] + zi, p[a + 1] + zi);
        let b = p[xi + 1] + yi;
        let (ba, bb) = (p[b] + zi, p[b + 1] + zi);
        lerp(
            w,
            lerp(
                v,
                lerp(u, grad(p[aa], x, y, z), grad(p[ba], x - 1.0, y, z)),
                lerp(
                    u,
                    grad(p[ab], x, y - 1.0, z),
                    grad(p[bb], x - 1.0, y - 1.0, z),
                ),
            ),
            lerp(
                v,
                lerp(
                    u,
                    grad(p[aa + 1], x, y, z - 1.0),
                    grad(p[ba + 1], x - 1.0, y, z - 1.0),
                ),
                lerp(
                    u,
                    grad(p[ab + 1], x, y - 1.0, z - 1.0),
                    grad(p[bb + 1], x - 1.0, y - 1.0, z - 1.0),
                ),
            ),
        )
    }

    #[test]
    fn noise_matches_perlins_reference_where_their_gradients_agree() {
        // Of the four padding gradients (hashes 12-15) pbrt picks two differently from
        // Perlin's reference (13 and 14); both are valid. Compare at points whose eight
        // corner hashes avoid those two.
        let mut compared = 0;
        for k in 0..4000u64 {
            let h = crate::sampling::hash(&[k]);
            let q = |s: u64| crate::sampling::to_unit(crate::sampling::mix64(h ^ s)) * 40.0 - 20.0;
            let p = Vec3::new(q(1), q(2), q(3));
            let corners_plain = (0..8).all(|c| {
                let i = [p.x, p.y, p.z].map(|v| (v.floor() as i64 & 255) as usize);
                let (a, b, e) = (c & 1, (c >> 1) & 1, c >> 2);
                let h = perm(perm(perm(i[0] + a) + i[1] + b) + i[2] + e) & 15;
                h != 13 && h != 14
            });
            if !corners_plain {
                continue;
            }
            compared += 1;
            let want = reference(p.x as f64, p.y as f64, p.z as f64);
            let got = noise(p) as f64;
            assert!((got - want).abs() < 1e-5, "{p}: {got} vs {want}");
        }
        assert!(compared > 300, "{compared}");
        // Zero at lattice points, bounded.
        assert_eq!(noise(Vec3::new(3.0, -7.0, 11.0)), 0.0);
    }

    #[test]
    fn cloud_density_follows_pbrts_altitude_rule() {
        let c = Cloud {
            density: 1.0,
            wispiness: 1.0,
            frequency: 5.0,
        };
        // Below y = 0 the added term 2 * (0.5 - y) >= 1: solid.
        assert_eq!(c.density(Vec3::new(0.3, -0.1, 0.7)), 1.0);
        // At y = 1 the noise term vanishes and the altitude term is 0.
        assert_eq!(c.density(Vec3::new(0.3, 1.0, 0.7)), 0.0);
        // In between the density lies in [0, 1] and varies.
        let v: Vec<f32> = (0..64)
            .map(|i| c.density(Vec3::new(i as f32 / 64.0, 0.7, 0.4)))
            .collect();
        assert!(v.iter().all(|d| (0.0..=1.0).contains(d)));
        let spread = v.iter().cloned().fold(0.0, f32::max) - v.iter().cloned().fold(1.0, f32::min);
        assert!(spread > 0.1, "{spread}");
    }
}
