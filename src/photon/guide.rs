//! Photon-guided final gathering (Jensen 1995, "Importance driven path tracing using the photon
//! map"): gather directions drawn in proportion to the indirect light the nearest global
//! photons say arrives from each direction, instead of by the cosine alone.
//!
//! Why: where a small, bright patch lights a room (a pool of light under a lamp, a ceiling lit
//! through a shade), cosine-distributed gather rays rarely hit it and each hit is worth a lot:
//! the indirect component turns to speckle. The photons that landed near the gather point
//! came from that patch, so their directions say where to look.
//!
//! How:
//! - the global photons that took a diffuse bounce (those flagged `DIRECT`, `CAUSTIC` or
//!   `GLOSSY` carry light that shadow rays and the caustic estimates give, which gather rays
//!   count as zero) get a kd-tree of their own ([`indirect_map`]), so that finding the nearest
//!   of them does not wade through the others;
//! - the `GUIDE_PHOTONS` nearest of them that arrive from the gather point's side are binned
//!   by their incoming direction on an `N x N` grid over the unit square, mapped to the
//!   hemisphere by the same cosine-weighted concentric warp the plain gather uses; each counts
//!   one (photons are shot in proportion to the lights' power and rouletted to similar powers,
//!   so counts follow the flux; weighting by the stored power, rounded to 8-bit mantissas, let
//!   a light 1e6 times brighter move some samples across cell edges, and the image was no
//!   longer exactly 1e6 times brighter pixel by pixel);
//! - the grid's density is a mixture of uniform and the bins' shares, with the uniform share
//!   `eps = N^2 / (n + N^2)` for `n` photons (Laplace's add-one smoothing: one pseudo-photon
//!   per cell) and never below `DEFENSIVE`. Every direction the cosine sampler
//!   reaches keeps a density of at least `eps` times the cosine's, so the estimate stays
//!   unbiased and its variance bounded; and a histogram of few photons, which is mostly noise
//!   where indirect light is even, leans towards the plain cosine (without the smoothing the
//!   Cornell box's error tripled: BENCHMARKS.md, "Design measurements");
//! - a stratified point `u` of the square is moved by the inverse CDF of this piecewise
//!   constant density (rows, then columns within the row), which keeps the strata; the
//!   direction's density is `q(u') cos / pi` and the gather's weight `f pi / q(u')`.
//!
//! With fewer than `MIN_PHOTONS` such photons the gather stays cosine-distributed.
//!
//! A pixel's later samples reuse the guide of an earlier one that landed within its photons'
//! radius on a surface facing the same way ([`GuideSlot`]): any density is
//! unbiased as long as sampling and the MIS weights read the same one, and it is the lookup
//! that costs (about 4.5 us a guide on a loaded machine, against 0.3 us for a 1-NN).
use super::{KnnResult, Photon, PhotonMap};
use crate::math::{Frame, Vec2, Vec3};
use std::f32::consts::{FRAC_PI_2, FRAC_PI_4, PI};

/// Grid cells per side of the unit square.
pub const N: usize = 8;
/// Photons looked up per gather point.
pub const GUIDE_PHOTONS: usize = 64;
/// Fewest photons worth guiding by.
pub const MIN_PHOTONS: usize = 8;
/// Least share of the uniform (plain cosine) density in the mixture.
pub const DEFENSIVE: f32 = 0.25;

/// A piecewise-constant density on the unit square, `N x N` cells, integrating to 1.
#[derive(Clone, Debug)]
pub struct GatherGuide {
    /// Cell probabilities, row-major (row = y).
    cells: [f32; N * N],
    /// Row probabilities (sums of their cells).
    rows: [f32; N],
}

impl GatherGuide {
    /// The guide at `p` (shading frame `frame`, z the side gathered) from the photons of
    /// `map` (an [`indirect_map`]) within squared radius `max_r2`; `None` when too few photons
    /// say anything. `buf` is left holding the photons used.
    pub fn build(
        map: &PhotonMap,
        p: Vec3,
        frame: &Frame,
        max_r2: f32,
        buf: &mut KnnResult,
    ) -> Option<GatherGuide> {
        let n = frame.n;
        map.knn_by(p, GUIDE_PHOTONS, max_r2, buf, |ph, _, d2| {
            (ph.dir().dot(n) < 0.0).then_some(d2)
        });
        let found = buf.neighbors();
        if found.len() < MIN_PHOTONS {
            return None;
        }
        let mut bins = [0.0f32; N * N];
        for nb in found {
            let ph = map.photon(nb.idx);
            let local = frame.to_local(-ph.dir());
            let u = cosine_hemisphere_to_square(local);
            bins[cell_of(u)] += 1.0;
        }
        GatherGuide::from_bins(&bins, found.len())
    }

    /// The mixture density from per-cell weights of `photons` photons; `None` when they sum
    /// to nothing.
    pub fn from_bins(bins: &[f32; N * N], photons: usize) -> Option<GatherGuide> {
        let total: f32 = bins.iter().map(|b| b.max(0.0)).sum();
        if !(total > 0.0 && total.is_finite()) {
            return None;
        }
        let cells_n = (N * N) as f32;
        let eps = (cells_n / (photons as f32 + cells_n)).max(DEFENSIVE);
        let uniform = eps / cells_n;
        let mut cells = [0.0f32; N * N];
        let mut rows = [0.0f32; N];
        for (i, c) in cells.iter_mut().enumerate() {
            *c = uniform + (1.0 - eps) * bins[i].max(0.0) / total;
            rows[i / N] += *c;
        }
        Some(GatherGuide { cells, rows })
    }

    /// Moves `u` (uniform on the square) to a point distributed by this density; returns it
    /// with its density.
    pub fn sample(&self, u: Vec2) -> (Vec2, f32) {
        let (row, fy) = pick(&self.rows, 1.0, u.y);
        let cols = &self.cells[row * N..(row + 1) * N];
        let (col, fx) = pick(cols, self.rows[row], u.x);
        let v = Vec2::new((col as f32 + fx) / N as f32, (row as f32 + fy) / N as f32);
        (v, self.cells[row * N + col] * (N * N) as f32)
    }

    /// The density at `u` on the square.
    pub fn pdf(&self, u: Vec2) -> f32 {
        self.cells[cell_of(u)] * (N * N) as f32
    }
}

/// A pixel's guide, kept for its later samples.
#[derive(Clone, Debug)]
pub struct GuideSlot {
    p: Vec3,
    n: Vec3,
    reuse_r2: f32,
    guide: Option<GatherGuide>,
}

impl GuideSlot {
    /// The guide at `p` (facing normal `frame.n`): `slot`'s when it was built close enough,
    /// else a new one (kept in `slot`).
    pub fn get(
        slot: &mut Option<GuideSlot>,
        map: &PhotonMap,
        p: Vec3,
        frame: &Frame,
        max_r2: f32,
        buf: &mut KnnResult,
    ) -> Option<GatherGuide> {
        if let Some(s) = slot {
            if (p - s.p).length_squared() <= s.reuse_r2 && s.n.dot(frame.n) >= 0.99 {
                return s.guide.clone();
            }
        }
        let guide = GatherGuide::build(map, p, frame, max_r2, buf);
        let r2 = buf
            .neighbors()
            .iter()
            .map(|nb| nb.d2)
            .fold(0.0f32, f32::max);
        *slot = Some(GuideSlot {
            p,
            n: frame.n,
            reuse_r2: r2,
            guide: guide.clone(),
        });
        guide
    }
}

/// The photons of `global` that took a diffuse bounce (not `DIRECT`, `CAUSTIC` or `GLOSSY`)
/// in a kd-tree of their own; `None` when there are none.
pub fn indirect_map(global: Option<&PhotonMap>) -> Option<PhotonMap> {
    global?.subset(|ph| ph.flags() & (Photon::DIRECT | Photon::CAUSTIC | Photon::GLOSSY) == 0)
}

/// The item of `weights` (summing to `total`) that `u` falls in, and where in it (in [0, 1)).
fn pick(weights: &[f32], total: f32, u: f32) -> (usize, f32) {
    let target = u * total;
    let mut acc = 0.0;
    for (i, &w) in weights.iter().enumerate() {
        if target < acc + w || i == weights.len() - 1 {
            let f = if w > 0.0 { (target - acc) / w } else { 0.5 };
            return (i, f.clamp(0.0, crate::sampling::ONE_MINUS_EPSILON));
        }
        acc += w;
    }
    unreachable!("weights is not empty")
}

/// The grid cell of a point of the unit square.
fn cell_of(u: Vec2) -> usize {
    let c = |x: f32| ((x * N as f32) as usize).min(N - 1);
    c(u.y) * N + c(u.x)
}

/// The inverse of [`crate::sampling::warp::square_to_cosine_hemisphere`]: the point of the
/// unit square that maps to the direction `w` (z > 0; only its x, y are read).
pub fn cosine_hemisphere_to_square(w: Vec3) -> Vec2 {
    let r = (w.x * w.x + w.y * w.y).sqrt().min(1.0);
    if r == 0.0 {
        return Vec2::splat(0.5);
    }
    let phi = atan2(w.y, w.x);
    let k = 4.0 / PI;
    // Invert Shirley-Chiu's concentric map wedge by wedge (see square_to_disk_concentric).
    let o = if phi.abs() <= FRAC_PI_4 {
        Vec2::new(r, r * phi * k)
    } else if phi.abs() >= 3.0 * FRAC_PI_4 {
        let theta = if phi > 0.0 { phi - PI } else { phi + PI };
        Vec2::new(-r, -r * theta * k)
    } else if phi > 0.0 {
        Vec2::new(r * (FRAC_PI_2 - phi) * k, r)
    } else {
        Vec2::new(r * (FRAC_PI_2 + phi) * k, -r)
    };
    ((o + Vec2::ONE) * 0.5).clamp(Vec2::ZERO, Vec2::splat(crate::sampling::ONE_MINUS_EPSILON))
}

/// `atan2(y, x)` to within 1e-5 rad, without libm: the octant's ratio through a minimax
/// polynomial for atan on [-1, 1] (binning photons spent a third of its time in libm's atan).
fn atan2(y: f32, x: f32) -> f32 {
    let (ax, ay) = (x.abs(), y.abs());
    let (z, swap) = if ay > ax {
        (ax / ay, true)
    } else {
        (ay / ax.max(f32::MIN_POSITIVE), false)
    };
    let z2 = z * z;
    let p = z
        * (0.999_977_26
            + z2 * (-0.332_623_47
                + z2 * (0.193_543_46
                    + z2 * (-0.116_432_87 + z2 * (0.052_653_32 - 0.011_721_2 * z2)))));
    let a = if swap { FRAC_PI_2 - p } else { p };
    let a = if x < 0.0 { PI - a } else { a };
    if y < 0.0 {
        -a
    } else {
        a
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::warp::square_to_cosine_hemisphere;

    #[test]
    fn fast_atan2_is_within_1e5() {
        let mut worst = 0.0f32;
        for i in 0..2000 {
            let a = i as f32 / 2000.0 * 2.0 * PI - PI;
            for r in [1e-3f32, 0.5, 1.0, 7.0] {
                let (y, x) = (r * a.sin(), r * a.cos());
                worst = worst.max((atan2(y, x) - y.atan2(x)).abs());
            }
        }
        assert!(worst < 1e-5, "{worst}");
    }

    #[test]
    fn inverse_warp_round_trips() {
        let n = 97;
        for i in 0..n {
            for j in 0..n {
                let u = Vec2::new((i as f32 + 0.5) / n as f32, (j as f32 + 0.5) / n as f32);
                let w = square_to_cosine_hemisphere(u);
                let back = cosine_hemisphere_to_square(w);
                assert!((back - u).length() < 2e-5, "{u} -> {w} -> {back}");
            }
        }
    }

    /// The density integrates to 1, sampling lands where the density says (chi-square-like
    /// check per cell with many points), and strata stay ordered (the map is monotone in each
    /// coordinate within a row).
    #[test]
    fn sampling_matches_the_density() {
        let mut bins = [0.0f32; N * N];
        bins[3 * N + 5] = 10.0;
        bins[7 * N] = 3.0;
        bins[N + 1] = 1.0;
        let g = GatherGuide::from_bins(&bins, 1000).unwrap();
        let total: f32 = (0..N * N).map(|i| g.cells[i]).sum();
        assert!((total - 1.0).abs() < 1e-5);
        // Uniform grid of points through the inverse CDF: the share landing in each cell is
        // its probability (to the grid's resolution).
        let m = 512;
        let mut hits = [0usize; N * N];
        for i in 0..m {
            for j in 0..m {
                let u = Vec2::new((i as f32 + 0.5) / m as f32, (j as f32 + 0.5) / m as f32);
                let (v, q) = g.sample(u);
                assert!((q - g.pdf(v)).abs() < 1e-4 * q.max(1.0), "{q} {}", g.pdf(v));
                hits[cell_of(v)] += 1;
            }
        }
        for (c, &h) in hits.iter().enumerate() {
            let share = h as f32 / (m * m) as f32;
            assert!(
                (share - g.cells[c]).abs() < 3e-3,
                "cell {c}: {share} vs {}",
                g.cells[c]
            );
        }
        // The defensive share: no cell below DEFENSIVE of the uniform density.
        assert!((0..N * N).all(|c| g.cells[c] * (N * N) as f32 >= DEFENSIVE - 1e-6));
        assert!(GatherGuide::from_bins(&[0.0; N * N], 10).is_none());
        // Few photons: the uniform share is N^2 / (n + N^2).
        let few = GatherGuide::from_bins(&bins, 64).unwrap();
        assert!((few.pdf(Vec2::new(0.01, 0.01)) - 0.5).abs() < 1e-5);
    }

    /// The estimator f pi / q over guided samples is unbiased: the mean of g(w) / (q cos/pi)
    /// over guided directions equals the integral of g over the hemisphere for a test
    /// integrand peaked where the guide is not (the defensive part carries it).
    #[test]
    fn guided_estimate_is_unbiased() {
        let mut bins = [0.0f32; N * N];
        bins[2 * N + 6] = 5.0;
        let g = GatherGuide::from_bins(&bins, 1000).unwrap();
        // Integrand on the hemisphere: h(w) = (1 + 3 w.x^2) cos(theta); exact integral
        // 2 pi/2 ... computed here by the plain cosine estimator with many strata.
        let h = |w: Vec3| (1.0 + 3.0 * w.x * w.x) * w.z;
        // Jittered strata: a regular grid would be a quadrature whose error (cells not lined
        // up with the grid) is not the estimator's.
        let m = 1000;
        let jitter =
            |i: u64, j: u64, d: u64| crate::sampling::to_unit(crate::sampling::hash(&[i, j, d]));
        let (mut plain, mut guided) = (0.0f64, 0.0f64);
        for i in 0..m {
            for j in 0..m {
                let u = Vec2::new(
                    (i as f32 + jitter(i, j, 0)) / m as f32,
                    (j as f32 + jitter(i, j, 1)) / m as f32,
                );
                let w = square_to_cosine_hemisphere(u);
                plain += (h(w) * PI / w.z.max(1e-12)) as f64;
                let (v, q) = g.sample(u);
                let w = square_to_cosine_hemisphere(v);
                guided += (h(w) * PI / (q * w.z.max(1e-12))) as f64;
            }
        }
        let n = (m * m) as f64;
        // Exact: integral of (1 + 3 x^2) cos over the hemisphere = pi + 3 * pi/4 = 7 pi / 4.
        let exact = 7.0 * std::f64::consts::PI / 4.0;
        assert!((plain / n - exact).abs() < 1e-3 * exact, "{}", plain / n);
        assert!((guided / n - exact).abs() < 3e-3 * exact, "{}", guided / n);
    }
}
