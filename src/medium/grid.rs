//! The sampled grids of pbrt-v4's `uniformgrid` and `rgbgrid` media, and the box that places a
//! grid (or a `cloud`) in the scene.
//!
//! ```text
//! AttributeBegin
//!   Translate 0 1 0                       # the CTM here places the grid (pbrt-v4's
//!   MakeNamedMedium "smoke" "string type" "uniformgrid"   # renderFromMedium)
//!       "integer nx" 2 "integer ny" 2 "integer nz" 1 "float density" [ 0 1 2 3 ]
//!       "point3 p0" [ 0 0 0 ] "point3 p1" [ 1 1 1 ]
//!       "rgb sigma_a" [ 1 1 1 ] "rgb sigma_s" [ 1 1 1 ] "float scale" 1
//!       "rgb Le" [ 1 0.5 0 ] "float Lescale" [ 0 1 1 0 ]   # or "float temperature" [ ... ]
//!   MakeNamedMedium "tinted" "string type" "rgbgrid" "integer nx" 2
//!       "rgb sigma_a" [ 1 0 0  0 1 0 ] "rgb sigma_s" [ 1 1 1  1 1 1 ]
//!       "rgb Le" [ 0 0 0  4 4 4 ] "float Lescale" 1 "float scale" 2
//! AttributeEnd
//! ```
//!
//! A grid value at a point is pbrt-v4's `SampledGrid` lookup: samples at voxel centres of the
//! box `p0..p1` (x fastest, then y, then z), trilinear between them, and 0 beyond the outer
//! samples (so a value fades towards the box's faces). As in pbrt-v4 a ray sees the medium
//! only inside the box. Rays in such a medium are tracked against a [`MajorantGrid`] (as in
//! pbrt-v4: the box cut into 16^3 cells, each with the largest `sigma_t` its samples can give,
//! crossed cell by cell by a 3D DDA, so that a dense puff in thin air does not make every ray
//! take the puff's tiny steps): interactions by spectral tracking (Kutz et al. 2017: a tentative
//! collision is a scattering one with probability `mean(sigma_s(x)) / majorant`, else a null
//! one, each weighing the throughput per channel so that the estimate stays unbiased),
//! transmittance by ratio tracking, emission by ratio tracking's points, and the beam
//! estimates' transmittance by marching half a voxel at a time.
use crate::math::{Mat4, Vec3};
use crate::params::{Loc, ParamSet, SceneError};
use std::ops::{Add, Mul};

/// The box `p0..p1` of a medium's space, placed in the world by the CTM at `MakeNamedMedium`.
#[derive(Clone, Debug, PartialEq)]
pub struct Region {
    pub p0: Vec3,
    pub p1: Vec3,
    /// World (render) space to the medium's space (the inverse CTM at `MakeNamedMedium`).
    pub medium_from_world: Mat4,
}

impl Region {
    /// World point `p` in the medium's space.
    #[inline]
    pub fn local(&self, p: Vec3) -> Vec3 {
        self.medium_from_world.transform_point3(p)
    }

    /// World point `p` relative to the box (0 at `p0`, 1 at `p1`).
    #[inline]
    pub fn unit(&self, p: Vec3) -> Vec3 {
        (self.local(p) - self.p0) / (self.p1 - self.p0)
    }

    /// The part `[t0, t1]` of the ray `o + t d` (world space, `t >= 0`) inside the box;
    /// `t0 > t1` when it misses.
    pub fn clip(&self, o: Vec3, d: Vec3) -> (f32, f32) {
        let om = self.local(o);
        let dm = self.medium_from_world.transform_vector3(d);
        let inv = dm.recip();
        let (a, b) = ((self.p0 - om) * inv, (self.p1 - om) * inv);
        let t0 = a.min(b).max_element().max(0.0);
        let t1 = a.max(b).min_element();
        if t0.is_nan() || t1.is_nan() {
            return (1.0, 0.0);
        }
        (t0, t1)
    }

    /// The ray parameter step that moves `frac` of the box's smallest extent divided by `n`
    /// along world direction `d` (half a voxel for a grid of `n` samples per axis).
    pub fn step(&self, d: Vec3, n: [usize; 3], frac: f32) -> f32 {
        let dm = self.medium_from_world.transform_vector3(d);
        let voxel = (self.p1 - self.p0).abs() / Vec3::new(n[0] as f32, n[1] as f32, n[2] as f32);
        frac * voxel.min_element() / dm.length().max(1e-30)
    }
}

/// Samples of a value (a density, an RGB coefficient) at the voxel centres of a box.
#[derive(Clone, Debug, PartialEq)]
pub struct SampledGrid<T> {
    /// Samples along x, y, z.
    pub n: [usize; 3],
    /// `n[0] * n[1] * n[2]` values, x fastest.
    pub values: Vec<T>,
}

impl<T: Copy + Default + Add<Output = T> + Mul<f32, Output = T>> SampledGrid<T> {
    /// A grid of one value everywhere in its box.
    pub fn constant(v: T) -> Self {
        SampledGrid {
            n: [1, 1, 1],
            values: vec![v],
        }
    }

    /// The value at `u` (relative to the box, see [`Region::unit`]).
    pub fn lookup(&self, u: Vec3) -> T {
        let s = [
            u.x * self.n[0] as f32 - 0.5,
            u.y * self.n[1] as f32 - 0.5,
            u.z * self.n[2] as f32 - 0.5,
        ];
        if !(s[0].is_finite() && s[1].is_finite() && s[2].is_finite()) {
            return T::default();
        }
        let i = s.map(|v| v.floor());
        let f = [s[0] - i[0], s[1] - i[1], s[2] - i[2]];
        let at = |x: f32, y: f32, z: f32| -> T {
            let (x, y, z) = (x as i64, y as i64, z as i64);
            if x < 0
                || y < 0
                || z < 0
                || x >= self.n[0] as i64
                || y >= self.n[1] as i64
                || z >= self.n[2] as i64
            {
                return T::default();
            }
            self.values[(z as usize * self.n[1] + y as usize) * self.n[0] + x as usize]
        };
        let lerp = |a: T, b: T, t: f32| a * (1.0 - t) + b * t;
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
}

/// `nx`, `ny`, `nz` (each >= 1, default 1).
pub fn read_dims(params: &mut ParamSet, loc: &Loc) -> Result<[usize; 3], SceneError> {
    let mut n = [0usize; 3];
    for (k, name) in ["nx", "ny", "nz"].iter().enumerate() {
        let v = params.get_int(name, 1)?;
        if v < 1 {
            return Err(SceneError::at(
                &at(params, name, loc),
                format!("{name} must be >= 1, got {v}"),
            ));
        }
        n[k] = v as usize;
    }
    Ok(n)
}

/// `p0` and `p1` (defaults 0 and 1 on every axis) placed by the CTM's inverse.
pub fn read_region(
    params: &mut ParamSet,
    loc: &Loc,
    medium_from_world: Mat4,
) -> Result<Region, SceneError> {
    let p0 = params.get_point3("p0", Vec3::ZERO)?;
    let p1 = params.get_point3("p1", Vec3::ONE)?;
    if !((p1 - p0).min_element() > 0.0 && (p1 - p0).is_finite() && p0.is_finite()) {
        return Err(SceneError::at(
            &at(params, "p1", loc),
            "p1 must exceed p0 on every axis",
        ));
    }
    if !medium_from_world.is_finite() {
        return Err(SceneError::at(
            loc,
            "the transform at MakeNamedMedium is singular",
        ));
    }
    Ok(Region {
        p0,
        p1,
        medium_from_world,
    })
}

/// Where parameter `name` was written (else the directive).
fn at(params: &ParamSet, name: &str, loc: &Loc) -> Loc {
    params.loc(name).cloned().unwrap_or_else(|| loc.clone())
}

/// Checks that grid parameter `name` has `nx * ny * nz` values, each finite and >= 0.
fn check_values<T: Copy>(
    params: &ParamSet,
    name: &str,
    loc: &Loc,
    n: [usize; 3],
    values: &[T],
    ok: impl Fn(T) -> bool,
) -> Result<(), SceneError> {
    let want = n[0].checked_mul(n[1]).and_then(|v| v.checked_mul(n[2]));
    if want != Some(values.len()) {
        return Err(SceneError::at(
            &at(params, name, loc),
            format!(
                "\"{name}\" has {} values, nx * ny * nz = {} x {} x {} wants {}",
                values.len(),
                n[0],
                n[1],
                n[2],
                want.map_or("more than fit".to_string(), |w| w.to_string())
            ),
        ));
    }
    if !values.iter().all(|v| ok(*v)) {
        return Err(SceneError::at(
            &at(params, name, loc),
            format!("\"{name}\" values must be finite and >= 0"),
        ));
    }
    Ok(())
}

fn finite_nonneg(v: f32) -> bool {
    v.is_finite() && v >= 0.0
}

fn finite_nonneg3(v: Vec3) -> bool {
    v.is_finite() && v.min_element() >= 0.0
}

/// A `uniformgrid`'s own parameters: `density` over `nx`/`ny`/`nz`, `p0`/`p1`, and its
/// emission: `Le` (`le`, already read by the caller) times the `Lescale` grid, or a
/// `temperature` grid (`temperatureoffset` (alias `temperaturecutoff`), `temperaturescale`)
/// emitting pbrt-v4's peak-normalised blackbody times `Lescale`.
pub fn read_uniform(
    params: &mut ParamSet,
    loc: &Loc,
    medium_from_world: Mat4,
    le: Option<Vec3>,
) -> Result<super::Field, SceneError> {
    let n = read_dims(params, loc)?;
    let Some(values) = params.get_floats("density")? else {
        return Err(SceneError::at(
            loc,
            "a \"uniformgrid\" medium needs \"float density\"",
        ));
    };
    check_values(params, "density", loc, n, &values, finite_nonneg)?;
    let density = SampledGrid { n, values };
    let le_scale = match params.get_floats("Lescale")? {
        None => SampledGrid::constant(1.0),
        Some(v) => {
            check_values(params, "Lescale", loc, n, &v, finite_nonneg)?;
            SampledGrid { n, values: v }
        }
    };
    let temperature = match params.get_floats("temperature")? {
        None => None,
        Some(v) => {
            if le.is_some() {
                return Err(SceneError::at(
                    &at(params, "temperature", loc),
                    "both \"Le\" and \"temperature\" are given (pbrt-v4 takes one)",
                ));
            }
            if v.len() != density.values.len() || v.iter().any(|t| !t.is_finite()) {
                return Err(SceneError::at(
                    &at(params, "temperature", loc),
                    format!(
                        "\"temperature\" needs {} finite values (one per density), got {}",
                        density.values.len(),
                        v.len()
                    ),
                ));
            }
            let cutoff = params.get_float("temperaturecutoff", 0.0)?;
            let offset = params.get_float("temperatureoffset", cutoff)?;
            let scale = params.get_float("temperaturescale", 1.0)?;
            if !(offset.is_finite() && scale.is_finite()) {
                return Err(SceneError::at(
                    &at(params, "temperaturescale", loc),
                    "temperatureoffset and temperaturescale must be finite",
                ));
            }
            Some(Temperature::new(
                SampledGrid { n, values: v },
                offset,
                scale,
            ))
        }
    };
    let region = read_region(params, loc, medium_from_world)?;
    Ok(super::Field::Density {
        region,
        density,
        le_scale,
        temperature,
    })
}

/// An `rgbgrid`'s own parameters: `sigma_a`, `sigma_s` (at least one; an absent one is 1
/// everywhere) and `Le` (needs `sigma_a`) as RGB grids over `nx`/`ny`/`nz`, `Lescale`,
/// `p0`/`p1`.
pub fn read_rgb(
    params: &mut ParamSet,
    loc: &Loc,
    medium_from_world: Mat4,
) -> Result<super::Field, SceneError> {
    let n = read_dims(params, loc)?;
    let sigma_a = params.get_rgbs("sigma_a")?;
    let sigma_s = params.get_rgbs("sigma_s")?;
    let le = params.get_rgbs("Le")?;
    if sigma_a.is_none() && sigma_s.is_none() {
        return Err(SceneError::at(
            loc,
            "an \"rgbgrid\" medium needs \"rgb sigma_a\" and/or \"rgb sigma_s\"",
        ));
    }
    if le.is_some() && sigma_a.is_none() {
        return Err(SceneError::at(
            &at(params, "Le", loc),
            "an \"rgbgrid\" medium with \"Le\" needs \"rgb sigma_a\"",
        ));
    }
    let grid = |name: &str, v: Option<Vec<Vec3>>| -> Result<_, SceneError> {
        v.map(|values| {
            check_values(params, name, loc, n, &values, finite_nonneg3)?;
            Ok(SampledGrid { n, values })
        })
        .transpose()
    };
    let (sigma_a, sigma_s, le) = (
        grid("sigma_a", sigma_a)?,
        grid("sigma_s", sigma_s)?,
        grid("Le", le)?,
    );
    let le_scale = params.get_float("Lescale", 1.0)?;
    if !finite_nonneg(le_scale) {
        return Err(SceneError::at(
            &at(params, "Lescale", loc),
            "Lescale must be finite and >= 0",
        ));
    }
    let region = read_region(params, loc, medium_from_world)?;
    Ok(super::Field::Rgb {
        region,
        sigma_a,
        sigma_s,
        le,
        le_scale,
    })
}

/// A `uniformgrid`'s temperature grid and the blackbody colours it takes.
#[derive(Clone, Debug, PartialEq)]
pub struct Temperature {
    pub grid: SampledGrid<f32>,
    pub offset: f32,
    pub scale: f32,
    /// Linear sRGB of pbrt-v4's peak-normalised blackbody at `lo + k (hi - lo) / (len - 1)`,
    /// as pbrt-v4's film records it (unnormalised: luminance times
    /// [`crate::spectrum::blackbody::CIE_Y_INTEGRAL`]).
    table: Vec<Vec3>,
    lo: f32,
    hi: f32,
}

/// Below this temperature (kelvin, after offset and scale) a voxel emits nothing, as in
/// pbrt-v4.
pub const MIN_EMITTING_KELVIN: f32 = 100.0;

impl Temperature {
    fn new(grid: SampledGrid<f32>, offset: f32, scale: f32) -> Temperature {
        let k = |v: f32| (v - offset) * scale;
        let (mut lo, mut hi) = (f32::INFINITY, f32::NEG_INFINITY);
        // Trilinear lookups lie between the samples and 0 (the fade outside).
        for v in grid.values.iter().copied().chain([0.0]) {
            lo = lo.min(k(v));
            hi = hi.max(k(v));
        }
        lo = lo.max(MIN_EMITTING_KELVIN);
        let len = if hi > lo { 1024 } else { 1 };
        let table = (0..len)
            .map(|i| {
                let t = if len == 1 {
                    lo
                } else {
                    lo + (hi - lo) * i as f32 / (len - 1) as f32
                } as f64;
                use crate::spectrum::blackbody::{peak_normalized_luminance, rgb, CIE_Y_INTEGRAL};
                match (rgb(t), peak_normalized_luminance(t)) {
                    (Some(c), Some(y)) => c * (y * CIE_Y_INTEGRAL) as f32,
                    _ => Vec3::ZERO,
                }
            })
            .collect();
        Temperature {
            grid,
            offset,
            scale,
            table,
            lo,
            hi,
        }
    }

    /// The blackbody radiance at `u` (relative to the box): 0 at or below
    /// [`MIN_EMITTING_KELVIN`].
    pub fn radiance(&self, u: Vec3) -> Vec3 {
        let t = (self.grid.lookup(u) - self.offset) * self.scale;
        if t.is_nan() || t <= MIN_EMITTING_KELVIN {
            return Vec3::ZERO;
        }
        if self.table.len() == 1 {
            return self.table[0];
        }
        let x = ((t - self.lo) / (self.hi - self.lo) * (self.table.len() - 1) as f32)
            .clamp(0.0, (self.table.len() - 1) as f32);
        let i = (x as usize).min(self.table.len() - 2);
        let f = x - i as f32;
        self.table[i] * (1.0 - f) + self.table[i + 1] * f
    }
}

/// Cells per axis of a [`MajorantGrid`] (pbrt-v4's choice).
pub const MAJORANT_CELLS: usize = 16;

/// Local bounds of `sigma_t` over a medium's box: `n` cells per axis (x fastest), each with
/// the largest `sigma_t` (any channel) the grid's lookups can return inside it.
#[derive(Clone, Debug, PartialEq)]
pub struct MajorantGrid {
    pub n: [usize; 3],
    pub values: Vec<f32>,
}

impl MajorantGrid {
    /// The bounds for a grid of `samples` per axis (trilinear between voxel centres, as
    /// [`SampledGrid::lookup`]); `bound(i)` is the largest `sigma_t` sample `i` gives. A cell
    /// takes the maximum over every sample whose interpolation reaches into it.
    pub fn from_samples(samples: [usize; 3], bound: impl Fn(usize) -> f32) -> MajorantGrid {
        let n = samples.map(|s| s.clamp(1, MAJORANT_CELLS));
        // Samples `lo..=hi` along an axis of `s` samples reach into cell `c` of `cells`.
        let range = |c: usize, cells: usize, s: usize| {
            let a = c as f64 / cells as f64 * s as f64 - 0.5;
            let b = (c + 1) as f64 / cells as f64 * s as f64 - 0.5;
            let lo = (a.floor().max(0.0) as usize).min(s - 1);
            let hi = ((b.floor() + 1.0).max(0.0) as usize).min(s - 1);
            (lo, hi)
        };
        let mut values = Vec::with_capacity(n[0] * n[1] * n[2]);
        for cz in 0..n[2] {
            let (z0, z1) = range(cz, n[2], samples[2]);
            for cy in 0..n[1] {
                let (y0, y1) = range(cy, n[1], samples[1]);
                for cx in 0..n[0] {
                    let (x0, x1) = range(cx, n[0], samples[0]);
                    let mut m = 0.0f32;
                    for z in z0..=z1 {
                        for y in y0..=y1 {
                            for x in x0..=x1 {
                                m = m.max(bound((z * samples[1] + y) * samples[0] + x));
                            }
                        }
                    }
                    values.push(m);
                }
            }
        }
        MajorantGrid { n, values }
    }

    /// The bound in the cell holding unit-box point `u` (0 outside the box).
    pub fn at(&self, u: Vec3) -> f32 {
        let mut idx = [0usize; 3];
        for a in 0..3 {
            if !(u[a] >= 0.0 && u[a] <= 1.0) {
                return 0.0;
            }
            idx[a] = ((u[a] * self.n[a] as f32) as usize).min(self.n[a] - 1);
        }
        self.values[(idx[2] * self.n[1] + idx[1]) * self.n[0] + idx[0]]
    }

    /// Calls `f(t_start, t_end, majorant)` for the cells the ray `o + t d` (world space)
    /// crosses between `t0` and `t1` (inside `region`'s box), in order, by a 3D DDA; stops
    /// early when `f` returns `Some`, and returns that.
    pub fn segments<R>(
        &self,
        region: &Region,
        o: Vec3,
        d: Vec3,
        (t0, t1): (f32, f32),
        mut f: impl FnMut(f32, f32, f32) -> Option<R>,
    ) -> Option<R> {
        if t0.is_nan() || t1.is_nan() || t1 <= t0 {
            return None;
        }
        let size = region.p1 - region.p0;
        let cells = Vec3::new(self.n[0] as f32, self.n[1] as f32, self.n[2] as f32);
        // Grid coordinates along the ray: og + dg t.
        let og = (region.local(o) - region.p0) / size * cells;
        let dg = region.medium_from_world.transform_vector3(d) / size * cells;
        let start = og + dg * t0;
        let mut cell = [0i64; 3];
        let mut next = [f32::INFINITY; 3];
        let mut delta = [f32::INFINITY; 3];
        let mut step = [0i64; 3];
        for a in 0..3 {
            let n = self.n[a] as i64;
            cell[a] = (start[a].floor() as i64).clamp(0, n - 1);
            if dg[a] > 0.0 {
                next[a] = t0 + ((cell[a] + 1) as f32 - start[a]) / dg[a];
                delta[a] = 1.0 / dg[a];
                step[a] = 1;
            } else if dg[a] < 0.0 {
                next[a] = t0 + (cell[a] as f32 - start[a]) / dg[a];
                delta[a] = -1.0 / dg[a];
                step[a] = -1;
            }
        }
        let mut t = t0;
        // A ray crosses at most n0 + n1 + n2 cells.
        for _ in 0..(self.n[0] + self.n[1] + self.n[2] + 3) {
            let a = if next[0] <= next[1] && next[0] <= next[2] {
                0
            } else if next[1] <= next[2] {
                1
            } else {
                2
            };
            let end = next[a].min(t1);
            let idx =
                (cell[2] as usize * self.n[1] + cell[1] as usize) * self.n[0] + cell[0] as usize;
            if end > t {
                if let Some(r) = f(t, end, self.values[idx]) {
                    return Some(r);
                }
            }
            if end >= t1 {
                return None;
            }
            t = end;
            cell[a] += step[a];
            if cell[a] < 0 || cell[a] >= self.n[a] as i64 {
                return None;
            }
            next[a] += delta[a];
        }
        None
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

    fn unit_box() -> Region {
        Region {
            p0: Vec3::ZERO,
            p1: Vec3::ONE,
            medium_from_world: Mat4::IDENTITY,
        }
    }

    #[test]
    fn lookups_are_trilinear_between_voxel_centres_and_fade_outside() {
        // Density x * 4 sampled at x centres 1/8, 3/8, 5/8, 7/8: linear inside.
        let g = SampledGrid {
            n: [4, 1, 1],
            values: vec![0.5f32, 1.5, 2.5, 3.5],
        };
        let r = unit_box();
        for x in [0.125f32, 0.3, 0.5, 0.8, 0.875] {
            let d = g.lookup(r.unit(Vec3::new(x, 0.5, 0.5)));
            assert!((d - 4.0 * x).abs() < 1e-5, "{x}: {d}");
        }
        // Half a voxel outside the last centre it fades linearly: at the face, half.
        assert!((g.lookup(Vec3::new(1.0, 0.5, 0.5)) - 1.75).abs() < 1e-5);
        assert_eq!(g.lookup(Vec3::new(1.2, 0.5, 0.5)), 0.0);
        assert_eq!(g.lookup(Vec3::new(0.5, 1.6, 0.5)), 0.0);
        // RGB values interpolate per channel.
        let c = SampledGrid {
            n: [2, 1, 1],
            values: vec![Vec3::new(1.0, 0.0, 2.0), Vec3::new(3.0, 1.0, 2.0)],
        };
        assert!((c.lookup(Vec3::new(0.5, 0.5, 0.5)) - Vec3::new(2.0, 0.5, 2.0)).length() < 1e-6);
        // The CTM moves the box.
        let moved = Region {
            medium_from_world: Mat4::from_translation(Vec3::new(-10.0, 0.0, 0.0)),
            ..unit_box()
        };
        assert!((g.lookup(moved.unit(Vec3::new(10.5, 0.5, 0.5))) - 2.0).abs() < 1e-5);
        // Rays see the box only.
        let (t0, t1) = moved.clip(Vec3::new(0.0, 0.5, 0.5), Vec3::X);
        assert!(
            (t0 - 10.0).abs() < 1e-5 && (t1 - 11.0).abs() < 1e-5,
            "{t0} {t1}"
        );
    }

    #[test]
    fn temperatures_emit_pbrts_peak_normalised_blackbody() {
        let t = Temperature::new(
            SampledGrid {
                n: [2, 1, 1],
                values: vec![50.0, 3000.0],
            },
            0.0,
            2.0,
        );
        // 2 x 3000 K at the second sample's centre.
        use crate::spectrum::blackbody::{peak_normalized_luminance, rgb, CIE_Y_INTEGRAL};
        let want = rgb(6000.0).unwrap()
            * (peak_normalized_luminance(6000.0).unwrap() * CIE_Y_INTEGRAL) as f32;
        let got = t.radiance(Vec3::new(0.75, 0.5, 0.5));
        assert!(
            (got - want).abs().max_element() < 2e-3 * want.max_element(),
            "{got} vs {want}"
        );
        // 2 x 50 K = 100 K does not emit.
        assert_eq!(t.radiance(Vec3::new(0.25, 0.5, 0.5)), Vec3::ZERO);
    }
}
