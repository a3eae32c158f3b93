//! RGB to spectrum by Jakob & Hanika's sigmoid-polynomial fit ("A Low-Dimensional Function
//! Space for Efficient Spectral Upsampling", 2019), as pbrt-v4 uplifts every RGB value.
//!
//! A reflectance is `s(t) = sigmoid(a t^2 + b t + c)` with `t = (lambda - 360) / 470` and
//! `sigmoid(x) = 1/2 + x / (2 sqrt(1 + x^2))`, always in `[0, 1]`. The three coefficients of
//! an RGB colour are those whose spectrum, lit by the colour space's illuminant (D65) and
//! seen through the CIE 1931 observer, has the same CIELAB colour (Gauss-Newton on the
//! CIELAB difference). [`Table`] holds them on a `RES^3` grid per largest channel (the other
//! two as fractions of it, the largest one on a grid that is denser near 0 and 1) and
//! interpolates trilinearly; equal channels have an exact constant spectrum.

/// Grid points per axis of the coefficient table.
pub const RES: usize = 32;

/// Quadrature step of the fit (nm).
const STEP: usize = 10;
/// Quadrature points from 360 nm to 830 nm.
const N: usize = (830 - 360) / STEP + 1;

/// `1/2 + x / (2 sqrt(1 + x^2))`, with the limits 0 and 1 at infinities.
pub fn sigmoid(x: f32) -> f32 {
    if x.is_infinite() {
        return if x > 0.0 { 1.0 } else { 0.0 };
    }
    0.5 + x / (2.0 * (1.0 + x * x).sqrt())
}

/// The spectrum of coefficients `c` at wavelength `lambda` (nm).
pub fn eval(c: [f32; 3], lambda: f32) -> f32 {
    let t = (lambda - 360.0) / 470.0;
    sigmoid((c[0] * t + c[1]) * t + c[2])
}

/// What the fit compares: the linear RGB seen of a spectrum (the weights per quadrature
/// point) and the CIELAB conversion.
struct Observer {
    /// `rgb_j = sum_i w[j][i] s(t_i)`; a constant 1 gives (1, 1, 1).
    w: [[f64; N]; 3],
    t: [f64; N],
    rgb_to_xyz: [[f64; 3]; 3],
    white: [f64; 3],
}

impl Observer {
    fn new(rgb_to_xyz: [[f64; 3]; 3], xyz_to_rgb: [[f64; 3]; 3]) -> Observer {
        let mut w = [[0.0; N]; 3];
        let mut t = [0.0; N];
        let mut sum = [0.0f64; 3];
        for (i, ti) in t.iter_mut().enumerate() {
            let lambda = 360 + i * STEP;
            *ti = (lambda as f64 - 360.0) / 470.0;
            let cmf = super::cie::CMF[lambda - 360];
            let d65 = super::d65_raw(lambda as f32) as f64;
            for j in 0..3 {
                let v: f64 = (0..3).map(|k| xyz_to_rgb[j][k] * cmf[k] as f64).sum();
                w[j][i] = v * d65;
                sum[j] += w[j][i];
            }
        }
        for j in 0..3 {
            for v in &mut w[j] {
                *v /= sum[j];
            }
        }
        let white = mul(&rgb_to_xyz, [1.0; 3]);
        Observer {
            w,
            t,
            rgb_to_xyz,
            white,
        }
    }

    fn lab(&self, rgb: [f64; 3]) -> [f64; 3] {
        let xyz = mul(&self.rgb_to_xyz, rgb);
        let f = |v: f64| {
            let d = 6.0 / 29.0;
            if v > d * d * d {
                v.cbrt()
            } else {
                v / (3.0 * d * d) + 4.0 / 29.0
            }
        };
        let (fx, fy, fz) = (
            f(xyz[0] / self.white[0]),
            f(xyz[1] / self.white[1]),
            f(xyz[2] / self.white[2]),
        );
        [116.0 * fy - 16.0, 500.0 * (fx - fy), 200.0 * (fy - fz)]
    }

    /// CIELAB of the target minus CIELAB of the spectrum of `c`.
    fn residual(&self, c: [f64; 3], target_lab: [f64; 3]) -> [f64; 3] {
        let mut rgb = [0.0; 3];
        for i in 0..N {
            let t = self.t[i];
            let x = (c[0] * t + c[1]) * t + c[2];
            let s = if x.is_infinite() {
                (x > 0.0) as u8 as f64
            } else {
                0.5 + x / (2.0 * (1.0 + x * x).sqrt())
            };
            for (j, v) in rgb.iter_mut().enumerate() {
                *v += self.w[j][i] * s;
            }
        }
        let lab = self.lab(rgb);
        [
            target_lab[0] - lab[0],
            target_lab[1] - lab[1],
            target_lab[2] - lab[2],
        ]
    }

    /// Gauss-Newton from `c` towards the coefficients of `rgb`; returns the residual's norm.
    fn solve(&self, rgb: [f64; 3], c: &mut [f64; 3]) -> f64 {
        let target = self.lab(rgb);
        let mut norm = f64::INFINITY;
        for _ in 0..15 {
            let r = self.residual(*c, target);
            norm = (r[0] * r[0] + r[1] * r[1] + r[2] * r[2]).sqrt();
            if norm < 1e-6 {
                break;
            }
            // Forward differences: three more residuals per step instead of six.
            let mut jac = [[0.0; 3]; 3];
            let eps = 1e-6;
            for k in 0..3 {
                let mut hi = *c;
                hi[k] += eps;
                let rh = self.residual(hi, target);
                for j in 0..3 {
                    jac[j][k] = (rh[j] - r[j]) / eps;
                }
            }
            let Some(inv) = invert(&jac) else { break };
            let step = mul(&inv, r);
            for k in 0..3 {
                c[k] -= step[k];
            }
            let max = c.iter().fold(0.0f64, |m, v| m.max(v.abs()));
            if max > 200.0 {
                for v in c.iter_mut() {
                    *v *= 200.0 / max;
                }
            }
        }
        norm
    }
}

fn mul(m: &[[f64; 3]; 3], v: [f64; 3]) -> [f64; 3] {
    [0, 1, 2].map(|j| m[j][0] * v[0] + m[j][1] * v[1] + m[j][2] * v[2])
}

/// The inverse of a 3x3 matrix; `None` when it is singular.
pub(super) fn invert(m: &[[f64; 3]; 3]) -> Option<[[f64; 3]; 3]> {
    let c =
        |r0: usize, c0: usize, r1: usize, c1: usize| m[r0][c0] * m[r1][c1] - m[r0][c1] * m[r1][c0];
    let cof = [
        [c(1, 1, 2, 2), -c(1, 0, 2, 2), c(1, 0, 2, 1)],
        [-c(0, 1, 2, 2), c(0, 0, 2, 2), -c(0, 0, 2, 1)],
        [c(0, 1, 1, 2), -c(0, 0, 1, 2), c(0, 0, 1, 1)],
    ];
    let det = m[0][0] * cof[0][0] + m[0][1] * cof[0][1] + m[0][2] * cof[0][2];
    if det.abs() < 1e-300 || !det.is_finite() {
        return None;
    }
    // inverse = adjugate / det; the adjugate is the transposed cofactor matrix.
    Some([0, 1, 2].map(|i| [0, 1, 2].map(|j| cof[j][i] / det)))
}

/// The coefficients of one colour `rgb` (channels in `[0, 1]`) fitted directly, without the
/// table: Gauss-Newton from the flat spectrum of its mean towards it in four steps (each
/// starting from the last one's solution). Microseconds, for one-off questions about a few
/// colours ([`super::two_bounce_discrepancy`]) that should not pay for the whole table.
pub fn fit_one(rgb: [f32; 3], rgb_to_xyz: [[f64; 3]; 3], xyz_to_rgb: [[f64; 3]; 3]) -> [f32; 3] {
    let obs = Observer::new(rgb_to_xyz, xyz_to_rgb);
    let rgb = rgb.map(|v| {
        if v.is_nan() {
            0.0
        } else {
            v.clamp(0.0, 1.0) as f64
        }
    });
    let mean = ((rgb[0] + rgb[1] + rgb[2]) / 3.0).clamp(0.01, 0.99);
    let mut c = [0.0, 0.0, (mean - 0.5) / (mean * (1.0 - mean)).sqrt()];
    for step in 1..=4 {
        let t = step as f64 / 4.0;
        obs.solve(rgb.map(|v| mean + t * (v - mean)), &mut c);
    }
    c.map(|v| v as f32)
}

/// Position of the largest-channel axis's grid point `k` (denser near 0 and 1).
fn z_node(k: usize) -> f32 {
    let smooth = |x: f32| x * x * (3.0 - 2.0 * x);
    smooth(smooth(k as f32 / (RES - 1) as f32))
}

/// The fitted coefficients on the grid (see the module docs).
pub struct Table {
    /// `[largest channel][z][y][x]`.
    coeffs: Vec<[f32; 3]>,
    z: [f32; RES],
}

fn index(l: usize, k: usize, y: usize, x: usize) -> usize {
    ((l * RES + k) * RES + y) * RES + x
}

impl Table {
    /// Fits every grid point in parallel. Each column of the
    /// grid is solved from the middle outwards, each point starting from its neighbour's
    /// solution, as the paper does (0.5 s on one core, 0.3 s on two).
    pub fn build(rgb_to_xyz: [[f64; 3]; 3], xyz_to_rgb: [[f64; 3]; 3]) -> Table {
        use rayon::prelude::*;
        let obs = Observer::new(rgb_to_xyz, xyz_to_rgb);
        let z: [f32; RES] = std::array::from_fn(z_node);
        let columns: Vec<Vec<[f32; 3]>> = (0..3 * RES * RES)
            .into_par_iter()
            .map(|col| {
                let (l, y, x) = (col / (RES * RES), (col / RES) % RES, col % RES);
                let (fx, fy) = (x as f64 / (RES - 1) as f64, y as f64 / (RES - 1) as f64);
                let rgb_at = |k: usize| {
                    let zz = z[k] as f64;
                    let mut rgb = [0.0; 3];
                    rgb[l] = zz;
                    rgb[(l + 1) % 3] = fx * zz;
                    rgb[(l + 2) % 3] = fy * zz;
                    rgb
                };
                let mut out = vec![[0.0f32; 3]; RES];
                let start = RES / 5;
                let mut c = [0.0f64; 3];
                for (k, o) in out.iter_mut().enumerate().skip(start) {
                    obs.solve(rgb_at(k), &mut c);
                    *o = c.map(|v| v as f32);
                }
                c = out[start].map(|v| v as f64);
                for k in (0..start).rev() {
                    obs.solve(rgb_at(k), &mut c);
                    out[k] = c.map(|v| v as f32);
                }
                out
            })
            .collect();
        let mut coeffs = vec![[0.0f32; 3]; 3 * RES * RES * RES];
        for (col, out) in columns.into_iter().enumerate() {
            let (l, y, x) = (col / (RES * RES), (col / RES) % RES, col % RES);
            for (k, c) in out.into_iter().enumerate() {
                coeffs[index(l, k, y, x)] = c;
            }
        }
        Table { coeffs, z }
    }

    /// The coefficients of `rgb` (each channel in `[0, 1]`).
    pub fn coeffs(&self, rgb: [f32; 3]) -> [f32; 3] {
        let rgb = rgb.map(|v| if v.is_nan() { 0.0 } else { v.clamp(0.0, 1.0) });
        if rgb[0] == rgb[1] && rgb[1] == rgb[2] {
            let v = rgb[0];
            return [0.0, 0.0, (v - 0.5) / (v * (1.0 - v)).sqrt()];
        }
        let l = if rgb[0] >= rgb[1] && rgb[0] >= rgb[2] {
            0
        } else if rgb[1] >= rgb[2] {
            1
        } else {
            2
        };
        let zv = rgb[l];
        let scale = (RES - 1) as f32 / zv;
        let x = rgb[(l + 1) % 3] * scale;
        let y = rgb[(l + 2) % 3] * scale;
        let cell = |v: f32| (v.max(0.0) as usize).min(RES - 2);
        let (xi, yi) = (cell(x), cell(y));
        let zi = self.z.partition_point(|&n| n <= zv).clamp(1, RES - 1) - 1;
        let (dx, dy) = (x - xi as f32, y - yi as f32);
        let dz = (zv - self.z[zi]) / (self.z[zi + 1] - self.z[zi]);
        let mut out = [0.0f32; 3];
        for (c, o) in out.iter_mut().enumerate() {
            let at = |k: usize, j: usize, i: usize| self.coeffs[index(l, k, j, i)][c];
            let lerp = |t: f32, a: f32, b: f32| a + t * (b - a);
            let plane = |k: usize| {
                lerp(
                    dy,
                    lerp(dx, at(k, yi, xi), at(k, yi, xi + 1)),
                    lerp(dx, at(k, yi + 1, xi), at(k, yi + 1, xi + 1)),
                )
            };
            *o = lerp(dz, plane(zi), plane(zi + 1));
        }
        out
    }
}
