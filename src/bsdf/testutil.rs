//! Test helpers for the BSDF unit tests: a small deterministic random generator
//! (SplitMix64) and uniform sphere directions, quadrature and chi-square tests, and f64
//! reference optics (Fresnel, Snell, Henyey-Greenstein, a brute-force coated slab).
use crate::math::{Frame, Vec2, Vec3};
use crate::sampling::warp::square_to_cosine_hemisphere;
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

/// `ln Gamma(x)` for `x > 0` (Lanczos, g = 7, 9 terms; about 1e-15 relative).
fn ln_gamma(x: f64) -> f64 {
    const C: [f64; 9] = [
        0.999_999_999_999_809_9,
        676.520_368_121_885_1,
        -1_259.139_216_722_402_8,
        771.323_428_777_653_1,
        -176.615_029_162_140_6,
        12.507_343_278_686_905,
        -0.138_571_095_265_720_12,
        9.984_369_578_019_572e-6,
        1.505_632_735_149_311_6e-7,
    ];
    if x < 0.5 {
        let pi = std::f64::consts::PI;
        return (pi / (pi * x).sin()).ln() - ln_gamma(1.0 - x);
    }
    let x = x - 1.0;
    let t = x + 7.5;
    let s = C[1..]
        .iter()
        .enumerate()
        .fold(C[0], |s, (i, c)| s + c / (x + i as f64 + 1.0));
    0.5 * (2.0 * std::f64::consts::PI).ln() + (x + 0.5) * t.ln() - t + s.ln()
}

/// The regularised upper incomplete gamma function `Q(a, x)`: series below `a + 1`, Lentz's
/// continued fraction above (Numerical Recipes' method).
pub(crate) fn gamma_q(a: f64, x: f64) -> f64 {
    if x <= 0.0 {
        return 1.0;
    }
    let front = (-x + a * x.ln() - ln_gamma(a)).exp();
    if x < a + 1.0 {
        let (mut term, mut sum, mut ap) = (1.0 / a, 1.0 / a, a);
        while term.abs() > sum.abs() * 1e-15 {
            ap += 1.0;
            term *= x / ap;
            sum += term;
        }
        return 1.0 - sum * front;
    }
    let tiny = 1e-300;
    let mut b = x + 1.0 - a;
    let mut c = 1.0 / tiny;
    let mut d = 1.0 / b;
    let mut h = d;
    for i in 1..10_000 {
        let an = -(i as f64) * (i as f64 - a);
        b += 2.0;
        d = an * d + b;
        d = if d.abs() < tiny { tiny } else { d };
        c = b + an / c;
        c = if c.abs() < tiny { tiny } else { c };
        d = 1.0 / d;
        let delta = d * c;
        h *= delta;
        if (delta - 1.0).abs() < 1e-15 {
            break;
        }
    }
    front * h
}

/// Bins of the unit sphere of equal solid angle: `n_z` bands of `cos(theta)` times `n_phi`
/// sectors of azimuth.
#[derive(Clone, Copy)]
pub(crate) struct SphereBins {
    pub n_z: usize,
    pub n_phi: usize,
}

impl SphereBins {
    pub(crate) fn count(&self) -> usize {
        self.n_z * self.n_phi
    }

    pub(crate) fn index(&self, w: Vec3) -> usize {
        let z = ((w.z as f64 + 1.0) * 0.5 * self.n_z as f64) as usize;
        let phi = (w.y as f64)
            .atan2(w.x as f64)
            .rem_euclid(2.0 * std::f64::consts::PI);
        let p = (phi / (2.0 * std::f64::consts::PI) * self.n_phi as f64) as usize;
        z.min(self.n_z - 1) * self.n_phi + p.min(self.n_phi - 1)
    }

    /// Integral of `g` over each bin by a midpoint rule in `(theta, phi)` (with the
    /// `sin theta` weight): `sub` steps per bin in `phi`, steps of equal `theta` (at least
    /// `4 sub` per bin), which resolves lobes near the poles better than steps in `cos theta`.
    pub(crate) fn integrate(&self, sub: usize, mut g: impl FnMut(Vec3) -> f64) -> Vec<f64> {
        use std::f64::consts::PI;
        let dphi = 2.0 * PI / (self.n_phi * sub) as f64;
        let mut out = vec![0.0; self.count()];
        for i in 0..self.n_z {
            // Band i spans cos theta in [z0, z1], theta in [t1, t0].
            let z0 = -1.0 + 2.0 * i as f64 / self.n_z as f64;
            let z1 = -1.0 + 2.0 * (i + 1) as f64 / self.n_z as f64;
            let (t0, t1) = (z0.clamp(-1.0, 1.0).acos(), z1.clamp(-1.0, 1.0).acos());
            // Steps of at most a quarter of a sub-cell's mean height in theta: the bands
            // at the poles are wide in theta and hold the sharpest lobes.
            let steps = ((t0 - t1) / (PI / (4 * sub * self.n_z) as f64)).ceil() as usize;
            let dt = (t0 - t1) / steps as f64;
            for a in 0..steps {
                let theta = t1 + (a as f64 + 0.5) * dt;
                let (st, ct) = theta.sin_cos();
                for j in 0..self.n_phi * sub {
                    let phi = (j as f64 + 0.5) * dphi;
                    let w = Vec3::new((st * phi.cos()) as f32, (st * phi.sin()) as f32, ct as f32);
                    out[i * self.n_phi + j / sub] += g(w) * st * dt * dphi;
                }
            }
        }
        out
    }
}

/// Pearson's chi-square test of observed counts against expected ones (Mitsuba's recipe:
/// cells expected below 5 are pooled into one). Returns `(p value, statistic, degrees of
/// freedom)`; a cell observed but expected 0 gives p = 0.
pub(crate) fn chi2_test(observed: &[f64], expected: &[f64]) -> (f64, f64, usize) {
    let (mut stat, mut cells) = (0.0, 0usize);
    let (mut pool_obs, mut pool_exp) = (0.0, 0.0);
    for (&o, &e) in observed.iter().zip(expected) {
        if e < 5.0 {
            pool_obs += o;
            pool_exp += e;
        } else {
            stat += (o - e) * (o - e) / e;
            cells += 1;
        }
    }
    if pool_exp > 0.0 {
        stat += (pool_obs - pool_exp) * (pool_obs - pool_exp) / pool_exp;
        cells += 1;
    } else if pool_obs > 0.0 {
        return (0.0, f64::INFINITY, cells);
    }
    let dof = cells.saturating_sub(1).max(1);
    (gamma_q(dof as f64 / 2.0, stat / 2.0), stat, dof)
}

/// Chi-square test of a direction sampler against a density over the sphere: `n` draws of
/// `sample` (None counts as "no sample", whose expected share is `1 - integral pdf`) binned
/// in `bins`, against `n` times `pdf` integrated over each bin. Returns the p value.
pub(crate) fn chi2_sampler(
    n: usize,
    bins: SphereBins,
    mut sample: impl FnMut() -> Option<Vec3>,
    pdf: impl FnMut(Vec3) -> f64,
) -> f64 {
    let mut observed = vec![0.0; bins.count() + 1];
    for _ in 0..n {
        match sample() {
            Some(w) => observed[bins.index(w)] += 1.0,
            None => observed[bins.count()] += 1.0,
        }
    }
    let mut expected: Vec<f64> = bins
        .integrate(10, pdf)
        .into_iter()
        .map(|p| p * n as f64)
        .collect();
    let total: f64 = expected.iter().sum();
    expected.push((n as f64 - total).max(0.0));
    let (p, stat, dof) = chi2_test(&observed, &expected);
    println!(
        "  chi2 {stat:.1} dof {dof} p {p:.4} (pdf integral {:.4}, failed {})",
        total / n as f64,
        observed[bins.count()]
    );
    p
}

/// Monte Carlo albedo `E[f |cos wi| / pdf]` of one channel of a sampler, with its standard
/// error and largest weight.
pub(crate) fn sampled_albedo(
    n: usize,
    mut sample: impl FnMut() -> Option<super::BsdfSample>,
    channel: usize,
) -> (f64, f64, f64) {
    let mut max_w = 0.0f64;
    let xs: Vec<f64> = (0..n)
        .map(|_| {
            let Some(s) = sample().filter(super::BsdfSample::is_valid) else {
                return 0.0;
            };
            let w = (s.f[channel] * s.wi.z.abs() / s.pdf) as f64;
            max_w = max_w.max(w);
            w
        })
        .collect();
    let (m, se) = mean_and_stderr(&xs);
    (m, se, max_w)
}

/// Unpolarised Fresnel reflectance from Hecht's s/p amplitudes (f64), from index `n1` into `n2`.
pub(crate) fn fresnel_reference(cos_i: f64, n1: f64, n2: f64) -> f64 {
    let sin_t = n1 / n2 * (1.0 - cos_i * cos_i).max(0.0).sqrt();
    if sin_t >= 1.0 {
        return 1.0;
    }
    let cos_t = (1.0 - sin_t * sin_t).sqrt();
    let rs = (n1 * cos_i - n2 * cos_t) / (n1 * cos_i + n2 * cos_t);
    let rp = (n2 * cos_i - n1 * cos_t) / (n2 * cos_i + n1 * cos_t);
    0.5 * (rs * rs + rp * rp)
}

/// Snell's law at a flat interface: the direction `d`'s tangential part scaled by `n1 / n2`.
pub(crate) fn snell(d: [f64; 3], n1: f64, n2: f64) -> [f64; 3] {
    let (x, y) = (d[0] * n1 / n2, d[1] * n1 / n2);
    let z = (1.0 - x * x - y * y).max(0.0).sqrt();
    [x, y, z.copysign(d[2])]
}

/// Textbook Henyey-Greenstein deflection of the propagation direction `d` (g > 0 forward).
pub(crate) fn hg_deflect(d: [f64; 3], g: f64, u: (f64, f64)) -> [f64; 3] {
    let cos = if g.abs() < 1e-3 {
        1.0 - 2.0 * u.0
    } else {
        let s = (1.0 - g * g) / (1.0 - g + 2.0 * g * u.0);
        (1.0 + g * g - s * s) / (2.0 * g)
    };
    let sin = (1.0 - cos * cos).max(0.0).sqrt();
    let phi = 2.0 * std::f64::consts::PI * u.1;
    let f = Frame::from_normal(Vec3::new(d[0] as f32, d[1] as f32, d[2] as f32));
    let t = [f.s, f.t];
    let mut out = [0.0; 3];
    for k in 0..3 {
        out[k] = sin * phi.cos() * t[0][k] as f64 + sin * phi.sin() * t[1][k] as f64 + cos * d[k];
    }
    out
}

/// Photon-by-photon simulation of the slab `[eta, r, thickness, albedo, g]` lit along `-wo`.
///
/// The slab is a smooth coat of index `eta` over a Lambertian floor of reflectance `r`, a
/// medium of unit extinction, `albedo` and `g`, of height `thickness`; the coat's own mirror
/// reflection is excluded. Returns the exit directions of the light that leaves through the coat
/// after entering it, each of weight 1 (absorption by roulette).
pub(crate) fn brute_force_slab(wo: Vec3, slab: [f64; 5], n: usize, rng: &mut Rng) -> Vec<Vec3> {
    let [eta, r, thickness, albedo, g] = slab;
    let mut exits = vec![];
    let mut u = || rng.f32() as f64;
    let cos_o = wo.z as f64;
    for _ in 0..n {
        if u() < fresnel_reference(cos_o, 1.0, eta) {
            continue; // the coat's specular reflection
        }
        let mut d = snell([-wo.x as f64, -wo.y as f64, -cos_o], 1.0, eta);
        let mut z = thickness;
        loop {
            // Free flight along d (unit extinction), vertical distance t |d.z|.
            let t = -(1.0 - u()).ln();
            let zn = z + t * d[2];
            if zn > 0.0 && zn < thickness {
                if u() >= albedo {
                    break; // absorbed in the medium
                }
                z = zn;
                d = hg_deflect(d, g, (u(), u()));
                continue;
            }
            if zn <= 0.0 {
                if u() >= r {
                    break; // absorbed by the floor
                }
                let c = square_to_cosine_hemisphere(Vec2::new(u() as f32, u() as f32));
                d = [c.x as f64, c.y as f64, c.z as f64];
                z = 0.0;
                continue;
            }
            // At the coat from inside.
            if u() < fresnel_reference(d[2].abs(), eta, 1.0) {
                d[2] = -d[2];
                z = thickness;
                continue;
            }
            let out = snell(d, eta, 1.0);
            exits.push(Vec3::new(out[0] as f32, out[1] as f32, out[2] as f32));
            break;
        }
    }
    exits
}

#[test]
fn gamma_q_matches_known_chi2_tails() {
    // Chi-square survival: P(X > 3.841) = 0.05 with 1 dof, P(X > 18.307) = 0.05 with 10 dof,
    // P(X > 124.342) = 0.05 with 100 dof (standard tables); Q(1, x) = exp(-x).
    for (k, x, p) in [
        (1.0, 3.841_458_8, 0.05),
        (10.0, 18.307_038, 0.05),
        (100.0, 124.342_13, 0.05),
    ] {
        let q = gamma_q(k / 2.0, x / 2.0);
        assert!((q - p).abs() < 1e-6, "dof {k}: {q}");
    }
    assert!((gamma_q(1.0, 2.5) - (-2.5f64).exp()).abs() < 1e-14);
}
