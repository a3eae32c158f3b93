//! Film: the pixel filter, per-pixel accumulation, the crop window's pixels and the sensor's
//! per-sample clamp.
//!
//! ```text
//! PixelFilter "triangle" "float xradius" [ 1 ] "float yradius" [ 1 ]
//! Film "rgb" "integer xresolution" [ 256 ] "integer yresolution" [ 256 ]
//!     "float iso" [ 100 ] "float maxcomponentvalue" [ 10 ] "float cropwindow" [ 0 .5 0 1 ]
//! ```
//! Like pbrt-v4, filters are applied by importance sampling: each camera sample is offset from
//! its pixel centre by a draw from the filter's own distribution and counts with weight 1 in
//! that pixel only, so a pixel is the plain mean of its samples and tiles never share pixels.
//! Box and triangle filters are sampled exactly; the Gaussian (pbrt's, `g(x) - g(radius)`)
//! through a tabulated tabulated CDF.
use crate::math::{Mat3, Vec2, Vec3};

/// `PixelFilter`: radii in pixels.
#[derive(Clone, Debug, PartialEq)]
pub enum FilterDesc {
    Box { radius: Vec2 },
    Triangle { radius: Vec2 },
    Gaussian { radius: Vec2, sigma: f32 },
}

/// The part of the image a render computes: pbrt-v4's `cropwindow` (fractions of the image,
/// `Film "float cropwindow"` or `--cropwindow`) or `pixelbounds` (pixels, `Film "integer
/// pixelbounds"` or `--pixelbounds`; it wins where both are given, as in pbrt-v4).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Crop {
    /// `[x0, x1, y0, y1]` as fractions of the image, each axis ordered and within [0, 1].
    Window([f32; 4]),
    /// `[x0, x1, y0, y1]` in pixels, half-open, each axis ordered.
    Pixels([u32; 4]),
}

impl Crop {
    /// `[x0, x1, y0, y1]` as given (comma- or space-separated numbers), for `--cropwindow`
    /// (`pixels` false: fractions, ordered and clamped to [0, 1] per axis as pbrt-v4 does) or
    /// `--pixelbounds` (`pixels` true: non-negative integers with x0 < x1 and y0 < y1).
    pub fn parse(text: &str, pixels: bool) -> Result<Crop, String> {
        let fields: Vec<&str> = text
            .split(|c: char| c == ',' || c.is_whitespace())
            .filter(|f| !f.is_empty())
            .collect();
        if fields.len() != 4 {
            return Err(format!(
                "expected four values x0,x1,y0,y1, got {}",
                fields.len()
            ));
        }
        if pixels {
            let mut v = [0u32; 4];
            for (v, f) in v.iter_mut().zip(&fields) {
                *v = f
                    .parse()
                    .map_err(|_| format!("expected a pixel index, got \"{}\"", clip(f)))?;
            }
            if v[0] >= v[1] || v[2] >= v[3] {
                return Err(format!(
                    "no pixel in [{}, {}) x [{}, {}): expected x0 < x1 and y0 < y1",
                    v[0], v[1], v[2], v[3]
                ));
            }
            return Ok(Crop::Pixels(v));
        }
        let mut v = [0f32; 4];
        for (v, f) in v.iter_mut().zip(&fields) {
            *v = f
                .parse::<f32>()
                .ok()
                .filter(|x| x.is_finite())
                .ok_or_else(|| format!("expected a finite number, got \"{}\"", clip(f)))?;
        }
        Ok(Crop::window(v))
    }

    /// A crop window from four fractions, each axis ordered and clamped to [0, 1].
    pub fn window(c: [f32; 4]) -> Crop {
        let axis = |a: f32, b: f32| [a.min(b).clamp(0.0, 1.0), a.max(b).clamp(0.0, 1.0)];
        let ([x0, x1], [y0, y1]) = (axis(c[0], c[1]), axis(c[2], c[3]));
        Crop::Window([x0, x1, y0, y1])
    }
}

/// At most 24 characters of a flag's value, for a message.
fn clip(text: &str) -> String {
    text.chars().take(24).collect()
}

/// The pixels `[x0, x1) x [y0, y1)` (returned as `[x0, x1, y0, y1]`) a render of a `w x h`
/// image computes: all of them, those of the crop window (each bound `ceil(resolution *
/// fraction)`, as pbrt-v4 rounds), or the pixel bounds clipped to the image.
pub fn pixel_bounds(crop: Option<Crop>, w: u32, h: u32) -> [u32; 4] {
    match crop {
        None => [0, w, 0, h],
        Some(Crop::Window(c)) => {
            let at = |res: u32, f: f32| ((res as f32 * f).ceil() as u32).min(res);
            [at(w, c[0]), at(w, c[1]), at(h, c[2]), at(h, c[3])]
        }
        Some(Crop::Pixels(p)) => [p[0].min(w), p[1].min(w), p[2].min(h), p[3].min(h)],
    }
}

/// Resolution of the tabulated Gaussian tabulated CDF.
const TABLE: usize = 1024;

/// A separable pixel filter that can be sampled.
#[derive(Clone, Debug)]
pub enum Filter {
    Box {
        radius: Vec2,
    },
    Triangle {
        radius: Vec2,
    },
    /// CDFs over `[-radius, radius]` for x and y.
    Tabulated {
        radius: Vec2,
        cdf_x: Vec<f32>,
        cdf_y: Vec<f32>,
    },
}

impl Filter {
    pub fn new(desc: &FilterDesc) -> Filter {
        match desc {
            FilterDesc::Box { radius } => Filter::Box { radius: *radius },
            FilterDesc::Triangle { radius } => Filter::Triangle { radius: *radius },
            FilterDesc::Gaussian { radius, sigma } => Filter::Tabulated {
                radius: *radius,
                cdf_x: gaussian_cdf(radius.x, *sigma),
                cdf_y: gaussian_cdf(radius.y, *sigma),
            },
        }
    }

    /// Offset from the pixel centre for a uniform sample `u` in [0, 1)^2.
    pub fn sample(&self, u: Vec2) -> Vec2 {
        match self {
            Filter::Box { radius } => (2.0 * u - Vec2::ONE) * *radius,
            Filter::Triangle { radius } => Vec2::new(tent(u.x, radius.x), tent(u.y, radius.y)),
            Filter::Tabulated {
                radius,
                cdf_x,
                cdf_y,
            } => Vec2::new(invert(cdf_x, radius.x, u.x), invert(cdf_y, radius.y, u.y)),
        }
    }
}

impl Filter {
    /// The filter's radii in pixels.
    pub fn radius(&self) -> Vec2 {
        match self {
            Filter::Box { radius }
            | Filter::Triangle { radius }
            | Filter::Tabulated { radius, .. } => *radius,
        }
    }

    /// The density [`Self::sample`] draws offset `d` with (the filter normalised to
    /// integrate to 1): the weight a light path's splat at raster offset `d` from a pixel's
    /// centre gets in that pixel.
    pub fn density(&self, d: Vec2) -> f32 {
        let r = self.radius();
        if d.x.abs() > r.x || d.y.abs() > r.y || r.x <= 0.0 || r.y <= 0.0 {
            return 0.0;
        }
        match self {
            Filter::Box { .. } => 1.0 / (4.0 * r.x * r.y),
            Filter::Triangle { .. } => {
                (r.x - d.x.abs()) * (r.y - d.y.abs()) / (r.x * r.x * r.y * r.y)
            }
            Filter::Tabulated { cdf_x, cdf_y, .. } => {
                table_density(cdf_x, r.x, d.x) * table_density(cdf_y, r.y, d.y)
            }
        }
    }
}

/// The piecewise-constant density of a tabulated CDF over `[-r, r]` at `x`.
fn table_density(cdf: &[f32], r: f32, x: f32) -> f32 {
    let bins = cdf.len() - 1;
    let i = (((x + r) / (2.0 * r)) * bins as f32).clamp(0.0, bins as f32 - 1.0) as usize;
    (cdf[i + 1] - cdf[i]) * bins as f32 / (2.0 * r)
}

/// Inverts the CDF of the tent `max(0, r - |x|)`.
fn tent(u: f32, r: f32) -> f32 {
    if u < 0.5 {
        -r + r * (2.0 * u).sqrt()
    } else {
        r - r * (2.0 - 2.0 * u).max(0.0).sqrt()
    }
}

/// Tabulates the CDF of pbrt's truncated Gaussian `g(x) - g(r)` on `[-r, r]` in `TABLE`
/// equal bins (piecewise-constant density), normalised to end at 1.
fn gaussian_cdf(r: f32, sigma: f32) -> Vec<f32> {
    let g = |x: f64| (-x * x / (2.0 * (sigma as f64).powi(2))).exp();
    let width = 2.0 * r as f64 / TABLE as f64;
    let mut cdf = vec![0.0f64; TABLE + 1];
    for i in 0..TABLE {
        let mid = -(r as f64) + (i as f64 + 0.5) * width;
        cdf[i + 1] = cdf[i] + (g(mid) - g(r as f64)).max(0.0);
    }
    let total = cdf[TABLE].max(f64::MIN_POSITIVE);
    cdf.iter().map(|c| (c / total) as f32).collect()
}

/// Inverts a tabulated CDF over `[-r, r]`: the bin by binary search, linear inside it.
fn invert(cdf: &[f32], r: f32, u: f32) -> f32 {
    let bins = cdf.len() - 1;
    let i = cdf.partition_point(|&c| c <= u).clamp(1, bins) - 1;
    let (c0, c1) = (cdf[i], cdf[i + 1]);
    let t = if c1 > c0 {
        ((u - c0) / (c1 - c0)).clamp(0.0, 1.0)
    } else {
        0.5
    };
    -r + 2.0 * r * (i as f32 + t) / bins as f32
}

/// The space of `Film "gbuffer"`'s position and normal channels (its `coordinatesystem`;
/// written by [`crate::integrator::aov`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Space {
    Camera,
    World,
}

/// The parts radiance is split into (Jensen's split), each written as its own image layer.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Component {
    /// Emitters seen directly plus direct lighting by shadow rays.
    Direct,
    /// Light arriving through specular/glossy bounces traced by rays.
    Specular,
    /// The caustic estimates of visible points.
    Caustic,
    /// Indirect diffuse light (final gathering, or the path tracer's further bounces).
    Indirect,
}

impl Component {
    /// Every component, in layer order.
    pub const ALL: [Component; 4] = [
        Component::Direct,
        Component::Specular,
        Component::Caustic,
        Component::Indirect,
    ];
    /// The layer names, in the order of [`Self::ALL`].
    pub const NAMES: [&'static str; 4] = ["direct", "specular", "caustic", "indirect"];

    /// The layer name.
    pub fn name(self) -> &'static str {
        Self::NAMES[self as usize]
    }
}

/// The per-component radiance of one camera sample (the parts sum to the total), indexed by
/// [`Component`]: RGB on the film (`Radiance`), [`Spectrum`]s while a sample's paths are in
/// flight (`Radiance<Spectrum>`, turned into RGB by [`crate::spectrum::Lambda::to_rgb`]).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Radiance<T = Vec3>(pub [T; 4]);

impl<T: Copy + std::ops::Add<Output = T>> Radiance<T> {
    pub fn total(&self) -> T {
        let [d, s, c, i] = self.0;
        d + s + c + i
    }

    /// `f` applied to each component.
    pub fn map<U>(&self, f: impl Fn(T) -> U) -> Radiance<U> {
        Radiance(self.0.map(f))
    }
}

impl<T> std::ops::Index<Component> for Radiance<T> {
    type Output = T;
    fn index(&self, c: Component) -> &T {
        &self.0[c as usize]
    }
}

impl<T> std::ops::IndexMut<Component> for Radiance<T> {
    fn index_mut(&mut self, c: Component) -> &mut T {
        &mut self.0[c as usize]
    }
}

impl<T: Copy + std::ops::AddAssign> std::ops::AddAssign for Radiance<T> {
    fn add_assign(&mut self, o: Radiance<T>) {
        for (a, b) in self.0.iter_mut().zip(o.0) {
            *a += b;
        }
    }
}

impl<T: Copy + std::ops::Add<Output = T> + std::ops::Mul<f32, Output = T>> std::ops::Mul<f32>
    for Radiance<T>
{
    type Output = Radiance<T>;
    fn mul(self, s: f32) -> Radiance<T> {
        self.map(|v| v * s)
    }
}

/// A matrix from its rows.
fn rows(r: [[f32; 3]; 3]) -> Mat3 {
    Mat3::from_cols_array_2d(&r).transpose()
}

/// CIE XYZ of a linear sRGB colour ([`crate::spectrum`]'s matrix: sRGB's primaries, the
/// white of the D65 table).
pub fn xyz_from_srgb(c: Vec3) -> Vec3 {
    crate::spectrum::tables().rgb_to_xyz * c
}

/// The lowest colour temperature `whitebalance` takes: pbrt-v4 uses a blackbody spectrum
/// instead of CIE daylight below a correlated colour temperature of 4000 K.
pub const MIN_WHITE_BALANCE: f32 = 4000.0 * 1.4380 / 1.4388;

/// pbrt-v4's `whitebalance` for the default `cie1931` sensor as a matrix on linear sRGB: the
/// sensor's XYZ go through a von Kries adaptation in Bradford's LMS space (pbrt-v4's
/// `WhiteBalance`) from the white of CIE daylight at `temperature` kelvin to sRGB's D65 white.
/// pbrt-v4 takes the daylight white from the spectrum it builds (with CIE's S0, S1, S2 tables)
/// for the daylight-locus chromaticity; photon takes that chromaticity itself (CIE 15's
/// formula on pbrt-v4's correlated temperature `T 1.4388 / 1.4380`), which the spectrum is
/// built to have. `temperature` must be at least [`MIN_WHITE_BALANCE`].
pub fn white_balance(temperature: f32) -> Mat3 {
    let cct = temperature as f64 * 1.4388 / 1.4380;
    let x = if cct <= 7000.0 {
        -4.607e9 / cct.powi(3) + 2.9678e6 / cct.powi(2) + 0.09911e3 / cct + 0.244063
    } else {
        -2.0064e9 / cct.powi(3) + 1.9018e6 / cct.powi(2) + 0.24748e3 / cct + 0.23704
    };
    let y = -3.0 * x * x + 2.870 * x - 0.275;
    let xyz = |x: f64, y: f64| Vec3::new((x / y) as f32, 1.0, ((1.0 - x - y) / y) as f32);
    let lms_from_xyz = rows([
        [0.8951, 0.2664, -0.1614],
        [-0.7502, 1.7135, 0.0367],
        [0.0389, -0.0685, 1.0296],
    ]);
    let (src, dst) = (lms_from_xyz * xyz(x, y), lms_from_xyz * xyz(0.3127, 0.3290));
    let adapt = lms_from_xyz.inverse() * Mat3::from_diagonal(dst / src) * lms_from_xyz;
    let t = crate::spectrum::tables();
    t.xyz_to_rgb * adapt * t.rgb_to_xyz
}

/// pbrt-v4's `maxcomponentvalue`: one camera sample's radiance, scaled (all components alike)
/// so that the largest of the sensor's values is at most `max`. The default `cie1931` sensor's
/// values are the CIE XYZ of the sample (times the imaging ratio, which the caller folds into
/// `max`), so the clamp acts on the XYZ of the RGB sum, not on the RGB.
pub fn clamp_sample(r: Radiance, max: f32) -> Radiance {
    let m = xyz_from_srgb(r.total()).max_element();
    if m > max {
        r * (max / m)
    } else {
        r
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn moments(f: &Filter) -> (f32, f32, f32) {
        let n = 200_000;
        let (mut m, mut m2, mut max) = (0.0f64, 0.0f64, 0.0f32);
        for i in 0..n {
            let u = Vec2::new((i as f32 + 0.5) / n as f32, 0.5);
            let x = f.sample(u).x;
            m += x as f64;
            m2 += (x * x) as f64;
            max = max.max(x.abs());
        }
        ((m / n as f64) as f32, (m2 / n as f64) as f32, max)
    }

    /// Sampled offsets have the analytic variance of each filter's distribution.
    #[test]
    fn filter_samples_have_the_right_spread() {
        let r = 1.5;
        let (m, v, max) = moments(&Filter::new(&FilterDesc::Box {
            radius: Vec2::splat(r),
        }));
        assert!(m.abs() < 1e-3 && (v - r * r / 3.0).abs() < 1e-3 && max <= r);
        let (m, v, max) = moments(&Filter::new(&FilterDesc::Triangle {
            radius: Vec2::splat(r),
        }));
        assert!(
            m.abs() < 1e-3 && (v - r * r / 6.0).abs() < 1e-3 && max <= r,
            "tent var {v}"
        );
        // Truncated Gaussian with a wide radius: variance ~ sigma^2.
        let g = Filter::new(&FilterDesc::Gaussian {
            radius: Vec2::splat(6.0),
            sigma: 0.5,
        });
        let (m, v, max) = moments(&g);
        assert!(
            m.abs() < 1e-3 && (v - 0.25).abs() < 3e-3 && max <= 6.0,
            "gauss var {v}"
        );
    }
}
