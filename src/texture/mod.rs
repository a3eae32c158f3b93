//! Textures with pbrt-v4's classes, parameters and lookup rules, evaluated at a (u, v) point.
//!
//! ```text
//! Texture "wood" "spectrum" "imagemap" "string filename" "wood.png"
//!     "string encoding" "sRGB" "string wrap" "repeat" "float scale" 1 "bool invert" false
//!     "float uscale" 4 "float vscale" 4 "float udelta" 0 "float vdelta" 0
//! Texture "checks" "spectrum" "checkerboard" "rgb tex1" [ 1 1 1 ] "texture tex2" "wood"
//! Texture "k" "float" "constant" "float value" 0.5
//! Texture "half" "spectrum" "scale" "texture tex" "wood" "float scale" 0.5
//! Texture "m" "spectrum" "mix" "texture tex1" "wood" "rgb tex2" [ 0 0 1 ] "float amount" 0.3
//! ```
//!
//! The loader parses and stores them ([`crate::scene::Scene::textures`]); materials hold
//! texture-valued parameters as [`Tex`], evaluated per hit at a [`TexCoord`] (the point's uv and
//! its screen-space derivatives, from [`crate::interaction::SurfaceInteraction`]).
//! A shape's `alpha` reads a float texture at the hit's uv, inside both ray-query backends (see
//! [`crate::accel`]).
//!
//! Lookups follow pbrt-v4:
//! - `uv` mapping: (s, t) = (uscale u + udelta, vscale v + vdelta); image textures then flip
//!   t (t = 1 - t) because image rows run top to bottom.
//! - image lookups (`filter` `bilinear`, the default; `point` is the nearest texel):
//!   x = s w - 1/2, y = t h - 1/2, the four texels around (x, y) weighted by their
//!   fractional distances, each texel address wrapped by `wrap`: `repeat` (modulo), `clamp`
//!   (to the edge), `black` (0 outside).
//! - `trilinear` (and `ewa`, which is looked up trilinearly) reads a MIP pyramid
//!   ([`Pyramid`]: each level halves the previous one, rounding up, by averaging 2x2 texels with
//!   clamped edges): the filter width is `w = 2 max(|ds/dx|, |ds/dy|, |dt/dx|, |dt/dy|)` (pbrt-v4)
//!   and the level `L = n - 1 + log2 w` for n levels; the lookup interpolates bilinear lookups
//!   in levels floor(L) and floor(L) + 1 (level 0 below 0, the coarsest above n - 1).
//! - `encoding` decodes a PNG's 8- and 16-bit values: `sRGB` (the IEC 61966-2-1 curve, the
//!   default), `linear`, `gamma G` (v^G). As in pbrt-v4's `Image::Read`, the other 8-bit formats
//!   (TGA, JPEG) are always sRGB and float images (EXR, PFM) linear, whatever `encoding` says.
//! - `imagemap`: scale times the lookup, then `invert` gives max(0, 1 - v); a float imagemap
//!   reads the first (red) channel of an RGB image, as pbrt-v4 does.
//! - `checkerboard` (2D): `tex1` where floor(s) + floor(t) is even, else `tex2`, filtered over
//!   the lookup's footprint as pbrt-v4 does: a tent of radius `rs = 1.5 max(|ds/dx|, |ds/dy|)`
//!   in s (and `rt` alike in t) gives the share `ps` of odd cells in s (`odd_fraction`), and
//!   the value is `(1 - p) tex1 + p tex2` with `p = ps + pt - 2 ps pt` (odd cells are where
//!   exactly one of s, t is odd); `mix`: (1 - amount) tex1 + amount tex2;
//!   `scale`: tex times scale; `constant`: value.
//!
//! Float textures are [`Texture`]s whose three channels are equal.

mod params;

pub use params::{named_texture, texture_param, value};

use crate::math::{Vec2, Vec3};
use std::collections::HashMap;
use std::fmt;
use std::sync::Arc;

/// A scene's named textures: spectrum and float textures are separate namespaces.
#[derive(Clone, Debug, Default)]
pub struct Textures {
    pub spectrum: HashMap<String, Arc<Texture>>,
    pub float: HashMap<String, Arc<Texture>>,
}

impl Textures {
    /// Bytes the decoded images and their MIP pyramids take, each image counted once however
    /// many textures share it (12 bytes a texel).
    pub fn decoded_bytes(&self) -> u64 {
        let mut images: Vec<(Arc<Image>, bool)> = Vec::new();
        for t in self.spectrum.values().chain(self.float.values()) {
            t.for_each_image(&mut |m| images.push((m.image.clone(), m.pyramid.is_some())));
        }
        images.sort_by_key(|(im, p)| (Arc::as_ptr(im), !p));
        images.dedup_by_key(|(im, _)| Arc::as_ptr(im));
        images
            .iter()
            .map(|(im, pyramid)| {
                let (w, h) = (im.width, im.height);
                let extra = if *pyramid {
                    Pyramid::texel_count(w, h)
                } else {
                    0
                };
                (w * h + extra) as u64 * 12
            })
            .sum()
    }
}

/// How texel addresses outside the image are treated.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Wrap {
    Repeat,
    Clamp,
    Black,
}

impl Wrap {
    /// pbrt-v4's name (`repeat`, `clamp`, `black`).
    pub fn from_name(s: &str) -> Option<Wrap> {
        match s {
            "repeat" => Some(Wrap::Repeat),
            "clamp" => Some(Wrap::Clamp),
            "black" => Some(Wrap::Black),
            _ => None,
        }
    }
}

/// How 8- and 16-bit texel values become linear values.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Encoding {
    Linear,
    Srgb,
    Gamma(f32),
}

impl Encoding {
    /// pbrt-v4's `encoding` string: `sRGB`, `linear`, `gamma G`.
    pub fn from_name(s: &str) -> Option<Encoding> {
        match s {
            "sRGB" => Some(Encoding::Srgb),
            "linear" => Some(Encoding::Linear),
            _ => {
                let g: f32 = s.strip_prefix("gamma ")?.trim().parse().ok()?;
                (g.is_finite() && g > 0.0).then_some(Encoding::Gamma(g))
            }
        }
    }

    /// The linear value of an encoded value `v` in [0, 1].
    pub fn decode(self, v: f32) -> f32 {
        match self {
            Encoding::Linear => v,
            Encoding::Srgb if v <= 0.04045 => v / 12.92,
            Encoding::Srgb => ((v + 0.055) / 1.055).powf(2.4),
            Encoding::Gamma(g) => v.powf(g),
        }
    }
}

/// Nearest texel, bilinear interpolation of the four around the lookup point, or trilinear
/// interpolation between two MIP levels chosen by the lookup's footprint.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Filter {
    Point,
    Bilinear,
    Trilinear,
}

/// Where a texture is looked up: surface coordinates `uv` and their derivatives with respect to
/// the image's x and y (one pixel step), zero when unknown (an unfiltered lookup).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct TexCoord {
    pub uv: Vec2,
    pub duvdx: Vec2,
    pub duvdy: Vec2,
    /// The wavelengths the colours looked up here are wanted at (materials uplift their RGB
    /// values to them, [`crate::spectrum`]); [`Lambda::Rgb`](crate::spectrum::Lambda::Rgb)
    /// leaves them RGB.
    pub lambda: crate::spectrum::Lambda,
}

impl TexCoord {
    /// A lookup at `uv` with no footprint.
    pub fn point(uv: Vec2) -> TexCoord {
        TexCoord {
            uv,
            ..Default::default()
        }
    }
}

/// A decoded (linear) RGB image, row 0 at the top.
#[derive(Clone, PartialEq)]
pub struct Image {
    pub width: usize,
    pub height: usize,
    pub texels: Vec<Vec3>,
}

impl fmt::Debug for Image {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "Image {}x{}", self.width, self.height)
    }
}

impl Image {
    /// An image from encoded 8-bit RGB rows (row 0 at the top), decoded with `encoding`.
    pub fn from_rgb8(width: usize, height: usize, bytes: &[u8], encoding: Encoding) -> Image {
        let texels = bytes
            .chunks_exact(3)
            .map(|c| {
                let d = |b: u8| encoding.decode(b as f32 / 255.0);
                Vec3::new(d(c[0]), d(c[1]), d(c[2]))
            })
            .collect();
        Image {
            width,
            height,
            texels,
        }
    }

    /// The texel at integer address (x, y) after wrapping; `None` outside a `black` image.
    fn texel(&self, x: i64, y: i64, wrap: Wrap) -> Option<Vec3> {
        let (w, h) = (self.width as i64, self.height as i64);
        let (x, y) = match wrap {
            Wrap::Repeat => (x.rem_euclid(w), y.rem_euclid(h)),
            Wrap::Clamp => (x.clamp(0, w - 1), y.clamp(0, h - 1)),
            Wrap::Black if x < 0 || y < 0 || x >= w || y >= h => return None,
            Wrap::Black => (x, y),
        };
        Some(self.texels[(y * w + x) as usize])
    }

    /// The next MIP level: half the size (rounded up), each texel the mean of the 2x2 texels
    /// above it (addresses clamped at odd edges); `None` for a 1x1 image.
    fn halved(&self) -> Option<Image> {
        if self.width <= 1 && self.height <= 1 {
            return None;
        }
        let (w, h) = (self.width.div_ceil(2), self.height.div_ceil(2));
        let mut texels = Vec::with_capacity(w * h);
        for y in 0..h as i64 {
            for x in 0..w as i64 {
                let t = |i: i64, j: i64| {
                    self.texel(2 * x + i, 2 * y + j, Wrap::Clamp)
                        .unwrap_or(Vec3::ZERO)
                };
                texels.push((t(0, 0) + t(1, 0) + t(0, 1) + t(1, 1)) * 0.25);
            }
        }
        Some(Image {
            width: w,
            height: h,
            texels,
        })
    }

    /// The image at continuous coordinates `st` in [0, 1]^2 (s to the right, t down).
    pub fn lookup(&self, st: Vec2, wrap: Wrap, filter: Filter) -> Vec3 {
        let x = st.x * self.width as f32 - 0.5;
        let y = st.y * self.height as f32 - 0.5;
        if filter == Filter::Point {
            let (xi, yi) = (x.round() as i64, y.round() as i64);
            return self.texel(xi, yi, wrap).unwrap_or(Vec3::ZERO);
        }
        let (xf, yf) = (x.floor(), y.floor());
        let (dx, dy) = (x - xf, y - yf);
        let (xi, yi) = (xf as i64, yf as i64);
        let t = |i: i64, j: i64| self.texel(xi + i, yi + j, wrap).unwrap_or(Vec3::ZERO);
        t(0, 0) * ((1.0 - dx) * (1.0 - dy))
            + t(1, 0) * (dx * (1.0 - dy))
            + t(0, 1) * ((1.0 - dx) * dy)
            + t(1, 1) * (dx * dy)
    }
}

/// The coarser MIP levels of an image: `levels[0]` is half the image (rounded up), each next
/// level half the one before, down to 1x1.
#[derive(Clone, PartialEq)]
pub struct Pyramid {
    pub levels: Vec<Image>,
}

impl fmt::Debug for Pyramid {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "Pyramid of {} levels", self.levels.len())
    }
}

impl Pyramid {
    /// The levels below `image`, each averaging 2x2 texels of the one above (clamped at odd
    /// edges).
    pub fn build(image: &Image) -> Pyramid {
        let mut levels: Vec<Image> = Vec::new();
        while let Some(next) = levels.last().unwrap_or(image).halved() {
            levels.push(next);
        }
        Pyramid { levels }
    }

    /// Texels the pyramid of a `width` x `height` image holds (for memory estimates).
    pub fn texel_count(width: usize, height: usize) -> usize {
        let (mut w, mut h, mut n) = (width, height, 0);
        while w > 1 || h > 1 {
            (w, h) = (w.div_ceil(2), h.div_ceil(2));
            n += w * h;
        }
        n
    }

    /// A trilinear lookup of `image` (level 0) and this pyramid at `st` with filter width
    /// `width` (in s, t units).
    pub fn lookup(&self, image: &Image, st: Vec2, width: f32, wrap: Wrap) -> Vec3 {
        let n = self.levels.len() + 1;
        let level = (n - 1) as f32 + width.max(1e-8).log2();
        let at = |l: usize| match l {
            0 => image.lookup(st, wrap, Filter::Bilinear),
            l => self.levels[l - 1].lookup(st, wrap, Filter::Bilinear),
        };
        if level <= 0.0 {
            return at(0);
        }
        if level >= (n - 1) as f32 {
            return at(n - 1);
        }
        let l0 = level.floor() as usize;
        let f = level - l0 as f32;
        at(l0) * (1.0 - f) + at(l0 + 1) * f
    }
}

/// pbrt-v4's `uv` mapping: (s, t) = (uscale u + udelta, vscale v + vdelta).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct UvMapping {
    pub scale: Vec2,
    pub delta: Vec2,
}

impl Default for UvMapping {
    fn default() -> Self {
        UvMapping {
            scale: Vec2::ONE,
            delta: Vec2::ZERO,
        }
    }
}

impl UvMapping {
    pub fn map(&self, uv: Vec2) -> Vec2 {
        self.scale * uv + self.delta
    }
}

/// An image texture's settings.
#[derive(Clone, Debug, PartialEq)]
pub struct ImageMap {
    pub image: Arc<Image>,
    pub mapping: UvMapping,
    pub wrap: Wrap,
    pub filter: Filter,
    pub scale: f32,
    pub invert: bool,
    /// A `float` texture: the first channel (R), as pbrt-v4's `MIPMap::Texel<Float>` reads
    /// an RGB image.
    pub float: bool,
    /// The MIP levels, present for the `trilinear` filter.
    pub pyramid: Option<Arc<Pyramid>>,
}

impl ImageMap {
    /// The lookup at `tc`: mapped, t flipped, filtered, scaled, inverted.
    fn eval(&self, tc: &TexCoord) -> Vec3 {
        let st = self.mapping.map(tc.uv);
        let st = Vec2::new(st.x, 1.0 - st.y);
        let v = match (&self.pyramid, self.filter) {
            (Some(p), Filter::Trilinear) => {
                let (dx, dy) = (self.mapping.scale * tc.duvdx, self.mapping.scale * tc.duvdy);
                let width = 2.0 * dx.abs().max(dy.abs()).max_element();
                p.lookup(&self.image, st, width, self.wrap)
            }
            (_, Filter::Point) => self.image.lookup(st, self.wrap, Filter::Point),
            _ => self.image.lookup(st, self.wrap, Filter::Bilinear),
        };
        let v = if self.float { Vec3::splat(v.x) } else { v } * self.scale;
        if self.invert {
            (Vec3::ONE - v).max(Vec3::ZERO)
        } else {
            v
        }
    }
}

/// The share of odd cells (floor odd) seen through a tent filter of radius `r` centred at `s`
/// (`r = 0`: 1 if floor(s) is odd), as pbrt-v4's checkerboard filters. The square wave
/// `c` (+1 on even cells, -1 on odd ones) integrated twice is
/// `D(x) = x/2 + y (1 - 2|y|)` with `y = x/2 - floor(x/2) - 1/2`, the tent-filtered wave is the
/// second difference `(D(s + r) - 2 D(s) + D(s - r)) / r^2`, and the odd share `(1 - that) / 2`.
/// In f64: the second difference of values near `s/2` loses `log2(s / r^2)` bits (pbrt-v4's
/// f32 gives noise for `s` in the thousands at fine footprints).
fn odd_fraction(s: f32, r: f32) -> f32 {
    let parity = |x: f64| (x.floor() as i64).rem_euclid(2) as f32;
    let (s, r) = (f64::from(s), f64::from(r));
    if r <= 0.0 || !r.is_finite() || (s - r).floor() == (s + r).floor() {
        return parity(s);
    }
    let d = |x: f64| {
        let y = x / 2.0 - (x / 2.0).floor() - 0.5;
        x / 2.0 + y * (1.0 - 2.0 * y.abs())
    };
    let c = (d(s + r) - 2.0 * d(s) + d(s - r)) / (r * r);
    ((1.0 - c) / 2.0).clamp(0.0, 1.0) as f32
}

/// A material parameter: a constant or a texture (spectrum: RGB; float: three equal channels).
#[derive(Clone, Debug, PartialEq)]
pub enum Tex {
    Const(Vec3),
    Map(Arc<Texture>),
}

impl Tex {
    /// The mean of its values over an 8x8 grid of texture coordinates (a constant's value).
    pub fn mean(&self) -> Vec3 {
        match self {
            Tex::Const(v) => *v,
            Tex::Map(t) => {
                let at = |i: u32| (i as f32 + 0.5) / 8.0;
                let sum: Vec3 = (0..64)
                    .map(|k| t.eval(Vec2::new(at(k % 8), at(k / 8))))
                    .sum();
                sum / 64.0
            }
        }
    }

    /// Whether every value it takes is a grey ([`Texture::is_grey`]).
    pub fn is_grey(&self) -> bool {
        match self {
            Tex::Const(v) => v.x == v.y && v.y == v.z,
            Tex::Map(t) => t.is_grey(),
        }
    }
}

impl From<Vec3> for Tex {
    fn from(v: Vec3) -> Tex {
        Tex::Const(v)
    }
}

impl From<f32> for Tex {
    fn from(v: f32) -> Tex {
        Tex::Const(Vec3::splat(v))
    }
}

impl Tex {
    /// The value at `tc`.
    #[inline]
    pub fn eval(&self, tc: &TexCoord) -> Vec3 {
        match self {
            Tex::Const(v) => *v,
            Tex::Map(t) => t.eval_at(tc),
        }
    }

    /// A float parameter's value at `tc` (the first channel).
    #[inline]
    pub fn eval_float(&self, tc: &TexCoord) -> f32 {
        self.eval(tc).x
    }

    /// The value when it is the same everywhere.
    pub fn constant(&self) -> Option<Vec3> {
        match self {
            Tex::Const(v) => Some(*v),
            Tex::Map(t) => match **t {
                Texture::Constant(v) => Some(v),
                _ => None,
            },
        }
    }

    /// Whether lookups read the footprint (`TexCoord`'s derivatives).
    pub fn needs_differentials(&self) -> bool {
        matches!(self, Tex::Map(t) if t.needs_differentials())
    }
}

/// A texture (spectrum textures as RGB; float textures with three equal channels).
#[derive(Clone, Debug, PartialEq)]
pub enum Texture {
    Constant(Vec3),
    Image(ImageMap),
    Checkerboard {
        mapping: UvMapping,
        tex1: Arc<Texture>,
        tex2: Arc<Texture>,
    },
    Scale {
        tex: Arc<Texture>,
        scale: Arc<Texture>,
    },
    Mix {
        tex1: Arc<Texture>,
        tex2: Arc<Texture>,
        amount: Arc<Texture>,
    },
}

impl Texture {
    /// Whether every value the texture takes has equal channels (a grey; spectrally flat).
    pub fn is_grey(&self) -> bool {
        let grey = |v: &Vec3| v.x == v.y && v.y == v.z;
        match self {
            Texture::Constant(v) => grey(v),
            Texture::Image(m) => m.float || m.image.texels.iter().all(grey),
            Texture::Checkerboard { tex1, tex2, .. } => tex1.is_grey() && tex2.is_grey(),
            Texture::Scale { tex, scale } => tex.is_grey() && scale.is_grey(),
            Texture::Mix { tex1, tex2, .. } => tex1.is_grey() && tex2.is_grey(),
        }
    }

    /// The texture's value at surface coordinates `uv`, unfiltered (no footprint).
    pub fn eval(&self, uv: Vec2) -> Vec3 {
        self.eval_at(&TexCoord::point(uv))
    }

    /// The texture's value at `tc`, filtered over its footprint where the texture filters.
    pub fn eval_at(&self, tc: &TexCoord) -> Vec3 {
        match self {
            Texture::Constant(v) => *v,
            Texture::Image(m) => m.eval(tc),
            Texture::Checkerboard {
                mapping,
                tex1,
                tex2,
            } => {
                let st = mapping.map(tc.uv);
                let (dx, dy) = (mapping.scale * tc.duvdx, mapping.scale * tc.duvdy);
                let d = dx.abs().max(dy.abs()) * 1.5;
                let (ps, pt) = (odd_fraction(st.x, d.x), odd_fraction(st.y, d.y));
                let p = ps + pt - 2.0 * ps * pt;
                if p <= 0.0 {
                    tex1.eval_at(tc)
                } else if p >= 1.0 {
                    tex2.eval_at(tc)
                } else {
                    tex1.eval_at(tc) * (1.0 - p) + tex2.eval_at(tc) * p
                }
            }
            Texture::Scale { tex, scale } => tex.eval_at(tc) * scale.eval_at(tc),
            Texture::Mix { tex1, tex2, amount } => {
                let a = amount.eval_at(tc);
                (Vec3::ONE - a) * tex1.eval_at(tc) + a * tex2.eval_at(tc)
            }
        }
    }

    /// Calls `f` on every image texture in this texture's tree.
    pub fn for_each_image(&self, f: &mut impl FnMut(&ImageMap)) {
        match self {
            Texture::Constant(_) => {}
            Texture::Image(m) => f(m),
            Texture::Checkerboard { tex1, tex2, .. } => {
                tex1.for_each_image(f);
                tex2.for_each_image(f);
            }
            Texture::Scale { tex, scale } => {
                tex.for_each_image(f);
                scale.for_each_image(f);
            }
            Texture::Mix { tex1, tex2, amount } => {
                tex1.for_each_image(f);
                tex2.for_each_image(f);
                amount.for_each_image(f);
            }
        }
    }

    /// Whether lookups read the footprint: a trilinear image or a checkerboard anywhere in it.
    pub fn needs_differentials(&self) -> bool {
        match self {
            Texture::Constant(_) => false,
            Texture::Image(m) => m.filter == Filter::Trilinear,
            Texture::Checkerboard { .. } => true,
            Texture::Scale { tex, scale } => {
                tex.needs_differentials() || scale.needs_differentials()
            }
            Texture::Mix { tex1, tex2, amount } => {
                tex1.needs_differentials()
                    || tex2.needs_differentials()
                    || amount.needs_differentials()
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// 2x2 image, linear: top row red (1,0,0) and green (0,1,0); bottom row blue and white.
    fn quad() -> Image {
        Image::from_rgb8(
            2,
            2,
            &[255, 0, 0, 0, 255, 0, 0, 0, 255, 255, 255, 255],
            Encoding::Linear,
        )
    }

    #[track_caller]
    fn near(a: Vec3, b: Vec3) {
        assert!((a - b).abs().max_element() < 1e-5, "{a} != {b}");
    }

    #[test]
    fn bilinear_hits_texel_centres_and_averages_between_them() {
        let im = quad();
        let (r, g, b, w) = (Vec3::X, Vec3::Y, Vec3::Z, Vec3::ONE);
        near(
            im.lookup(Vec2::new(0.25, 0.25), Wrap::Clamp, Filter::Bilinear),
            r,
        );
        near(
            im.lookup(Vec2::new(0.75, 0.25), Wrap::Clamp, Filter::Bilinear),
            g,
        );
        near(
            im.lookup(Vec2::new(0.25, 0.75), Wrap::Clamp, Filter::Bilinear),
            b,
        );
        // The centre of the image: the mean of all four.
        near(
            im.lookup(Vec2::new(0.5, 0.5), Wrap::Clamp, Filter::Bilinear),
            (r + g + b + w) / 4.0,
        );
        // A quarter of the way from red to green: x = 0.375 * 2 - 0.5 = 0.25.
        near(
            im.lookup(Vec2::new(0.375, 0.25), Wrap::Clamp, Filter::Bilinear),
            0.75 * r + 0.25 * g,
        );
        // Point sampling picks the nearest texel.
        near(
            im.lookup(Vec2::new(0.7, 0.9), Wrap::Clamp, Filter::Point),
            w,
        );
    }

    #[test]
    fn wrap_modes() {
        let im = quad();
        let (r, g) = (Vec3::X, Vec3::Y);
        // s = 0 on the top row sits between texel -1 and texel 0 (x = -0.5).
        let at = |s: f32, wrap| im.lookup(Vec2::new(s, 0.25), wrap, Filter::Bilinear);
        near(at(0.0, Wrap::Repeat), 0.5 * r + 0.5 * g); // texel -1 is green
        near(at(0.0, Wrap::Clamp), r); // texel -1 is red again
        near(at(0.0, Wrap::Black), 0.5 * r); // texel -1 is black
                                             // Repeat is periodic; black is zero far outside.
        near(at(-0.8, Wrap::Repeat), at(0.2, Wrap::Repeat));
        near(at(3.0, Wrap::Black), Vec3::ZERO);
        near(at(7.0, Wrap::Clamp), g);
    }

    #[test]
    fn encodings_decode_to_the_published_values() {
        // sRGB 128/255 is 0.21586 linear (IEC 61966-2-1); 10/255 is on the linear segment.
        assert!((Encoding::Srgb.decode(128.0 / 255.0) - 0.215861).abs() < 1e-5);
        assert!((Encoding::Srgb.decode(10.0 / 255.0) - 10.0 / 255.0 / 12.92).abs() < 1e-7);
        assert_eq!(Encoding::Srgb.decode(1.0), 1.0);
        assert_eq!(Encoding::from_name("gamma 2.2"), Some(Encoding::Gamma(2.2)));
        assert!((Encoding::Gamma(2.2).decode(0.5) - 0.217638).abs() < 1e-5);
        assert_eq!(Encoding::from_name("gamma -1"), None);
        assert_eq!(Encoding::from_name("srgb"), None, "pbrt spells it sRGB");
        let im = Image::from_rgb8(1, 1, &[128, 10, 255], Encoding::Srgb);
        near(im.texels[0], Vec3::new(0.215861, 10.0 / 255.0 / 12.92, 1.0));
    }

    #[test]
    fn image_texture_flips_t_and_applies_mapping_scale_invert() {
        let map = |mapping, scale, invert, float| {
            Texture::Image(ImageMap {
                image: Arc::new(quad()),
                mapping,
                wrap: Wrap::Repeat,
                filter: Filter::Bilinear,
                scale,
                invert,
                float,
                pyramid: None,
            })
        };
        let plain = map(UvMapping::default(), 1.0, false, false);
        // v = 0.75 is the top row of the image (t = 1 - v = 0.25).
        near(plain.eval(Vec2::new(0.25, 0.75)), Vec3::X);
        near(plain.eval(Vec2::new(0.25, 0.25)), Vec3::Z);
        // uscale 2, udelta 0.25: u = 0.25 maps to s = 0.75 (green).
        let mapped = UvMapping {
            scale: Vec2::new(2.0, 1.0),
            delta: Vec2::new(0.25, 0.0),
        };
        near(
            map(mapped, 1.0, false, false).eval(Vec2::new(0.25, 0.75)),
            Vec3::Y,
        );
        // scale 0.5 then invert: 1 - 0.5 (1, 0, 0) = (0.5, 1, 1).
        near(
            map(UvMapping::default(), 0.5, true, false).eval(Vec2::new(0.25, 0.75)),
            Vec3::new(0.5, 1.0, 1.0),
        );
        // A float imagemap reads the red channel (pbrt-v4's MIPMap::Texel<Float>).
        near(
            map(UvMapping::default(), 1.0, false, true).eval(Vec2::new(0.25, 0.75)),
            Vec3::splat(1.0),
        );
        near(
            map(UvMapping::default(), 1.0, false, true).eval(Vec2::new(0.75, 0.75)),
            Vec3::splat(0.0),
        );
    }

    #[test]
    fn checkerboard_scale_mix_constant() {
        let c = |v: f32| Arc::new(Texture::Constant(Vec3::splat(v)));
        let checks = Texture::Checkerboard {
            mapping: UvMapping {
                scale: Vec2::splat(2.0),
                delta: Vec2::ZERO,
            },
            tex1: c(1.0),
            tex2: c(0.0),
        };
        // (s, t) = 2 (u, v): cells (0,0) and (1,1) are tex1, (1,0) and (0,1) tex2.
        near(checks.eval(Vec2::new(0.25, 0.25)), Vec3::ONE);
        near(checks.eval(Vec2::new(0.75, 0.25)), Vec3::ZERO);
        near(checks.eval(Vec2::new(0.25, 0.75)), Vec3::ZERO);
        near(checks.eval(Vec2::new(0.75, 0.75)), Vec3::ONE);
        near(checks.eval(Vec2::new(-0.25, 0.25)), Vec3::ZERO);
        let scaled = Texture::Scale {
            tex: Arc::new(Texture::Constant(Vec3::new(0.2, 0.4, 0.8))),
            scale: c(0.5),
        };
        near(scaled.eval(Vec2::ZERO), Vec3::new(0.1, 0.2, 0.4));
        let mix = Texture::Mix {
            tex1: c(1.0),
            tex2: Arc::new(Texture::Constant(Vec3::new(0.0, 0.0, 3.0))),
            amount: c(0.25),
        };
        near(mix.eval(Vec2::ZERO), Vec3::new(0.75, 0.75, 1.5));
    }

    /// A 4x4 image with texel (x, y) = x + 4 y, and its pyramid: 2x2 block means, then 7.5.
    fn ramp() -> (Image, Pyramid) {
        let texels = (0..16).map(|i| Vec3::splat(i as f32)).collect();
        let im = Image {
            width: 4,
            height: 4,
            texels,
        };
        let p = Pyramid::build(&im);
        (im, p)
    }

    #[test]
    fn pyramid_levels_are_block_means() {
        let (im, p) = ramp();
        assert_eq!(p.levels.len(), 2);
        let l1: Vec<f32> = p.levels[0].texels.iter().map(|t| t.x).collect();
        assert_eq!(l1, vec![2.5, 4.5, 10.5, 12.5]);
        assert_eq!(p.levels[1].texels, vec![Vec3::splat(7.5)]);
        assert_eq!(Pyramid::texel_count(4, 4), 5);
        // Odd sizes clamp: [0 3 6] -> [(0+3)/2, 6] -> [3.75].
        let odd = Image {
            width: 3,
            height: 1,
            texels: vec![Vec3::ZERO, Vec3::splat(3.0), Vec3::splat(6.0)],
        };
        let po = Pyramid::build(&odd);
        let xs: Vec<f32> = po
            .levels
            .iter()
            .flat_map(|l| l.texels.iter().map(|t| t.x))
            .collect();
        assert_eq!(xs, vec![1.5, 6.0, 3.75]);
        assert_eq!(Pyramid::texel_count(3, 1), 3);
        // The full-resolution image is level 0 of a lookup.
        assert_eq!(
            im.lookup(Vec2::splat(0.125), Wrap::Clamp, Filter::Bilinear)
                .x,
            0.0
        );
    }

    #[test]
    fn trilinear_picks_the_level_from_the_footprint() {
        let (im, p) = ramp();
        let map = ImageMap {
            image: Arc::new(im),
            mapping: UvMapping::default(),
            wrap: Wrap::Clamp,
            filter: Filter::Trilinear,
            scale: 1.0,
            invert: false,
            float: false,
            pyramid: Some(Arc::new(p)),
        };
        let tex = Texture::Image(map);
        // uv (0.125, 0.875) is st (0.125, 0.125): texel (0, 0)'s centre in level 0 (value 0);
        // in level 1 it lies a quarter texel outside the first centre, clamped: 2.5.
        // Width w = 2 |du/dx| selects level 2 + log2 w of the 3 levels.
        let at = |w: f32| {
            tex.eval_at(&TexCoord {
                uv: Vec2::new(0.125, 0.875),
                duvdx: Vec2::new(w / 2.0, 0.0),
                duvdy: Vec2::new(0.0, w / 8.0),
                ..Default::default()
            })
            .x
        };
        near(Vec3::splat(at(0.0)), Vec3::ZERO);
        near(Vec3::splat(at(0.25)), Vec3::ZERO); // level 0 exactly
        near(Vec3::splat(at(0.5)), Vec3::splat(2.5)); // level 1
        near(Vec3::splat(at(2f32.powf(-1.5))), Vec3::splat(1.25)); // halfway 0..1
        near(
            Vec3::splat(at(0.75)),
            Vec3::splat(2.5 + (0.75f32.log2() + 1.0) * 5.0),
        ); // 1..2
        near(Vec3::splat(at(4.0)), Vec3::splat(7.5)); // beyond the coarsest
                                                      // Bilinear ignores the footprint.
        let Texture::Image(mut m) = tex.clone() else {
            unreachable!()
        };
        m.filter = Filter::Bilinear;
        let bilinear = Texture::Image(m);
        let far = TexCoord {
            uv: Vec2::new(0.125, 0.875),
            duvdx: Vec2::splat(4.0),
            duvdy: Vec2::ZERO,
            ..Default::default()
        };
        near(bilinear.eval_at(&far), Vec3::ZERO);
        assert!(tex.needs_differentials() && !bilinear.needs_differentials());
    }

    #[test]
    fn checkerboard_is_tent_filtered_over_the_footprint() {
        let c = |v: f32| Arc::new(Texture::Constant(Vec3::splat(v)));
        let checks = Texture::Checkerboard {
            mapping: UvMapping::default(),
            tex1: c(1.0),
            tex2: c(0.0),
        };
        // Tent radius 1.5 |d/dx|: 0.5 for a step of 1/3.
        let at = |u: f32, v: f32, dx: f32, dy: f32| {
            checks
                .eval_at(&TexCoord {
                    uv: Vec2::new(u, v),
                    duvdx: Vec2::new(dx, 0.0),
                    duvdy: Vec2::new(0.0, dy),
                    ..Default::default()
                })
                .x
        };
        let third = 1.0 / 3.0;
        assert_eq!(at(0.5, 0.5, 0.0, 0.0), 1.0);
        assert_eq!(at(1.5, 0.5, 0.0, 0.0), 0.0);
        // A tent centred on a cell edge sees half of each cell.
        assert!((at(1.0, 0.5, third, 0.0) - 0.5).abs() < 1e-6);
        // Centred at 0.75 with radius 0.5: the odd cell [1, 1.25] holds the tent's last
        // quarter, 1/8 of its weight (a box would give 1/4).
        assert!((at(0.75, 0.5, third, 0.0) - 0.875).abs() < 1e-6);
        // The same in t: exactly one of s, t odd with weight 2 (1/8)(7/8).
        assert!((at(0.75, 0.75, third, third) - 0.78125).abs() < 1e-6);
        // A footprint of many cells averages to one half.
        assert!((at(0.3, 0.7, 40.3, 25.1) - 0.5).abs() < 0.02);
        // Brute force (f64 tent weights on a grid) over footprints not symmetric about a cell
        // edge, one of them far from the origin, where an f32 second difference is noise.
        let tent_odd = |s: f64, r: f64| {
            let n = 20000;
            let (mut odd, mut total) = (0.0, 0.0);
            for i in 0..n {
                let t = -r + 2.0 * r * (i as f64 + 0.5) / n as f64;
                let w = r - t.abs();
                total += w;
                if ((s + t).floor() as i64).rem_euclid(2) == 1 {
                    odd += w;
                }
            }
            odd / total
        };
        for (u, v, rs, rt) in [
            (0.37f32, 1.81f32, 0.8f32, 0.45f32),
            (4097.9, -3000.05, 0.2, 0.1),
            (2.2, 0.4, 3.7, 0.05),
        ] {
            let (ps, pt) = (tent_odd(u as f64, rs as f64), tent_odd(v as f64, rt as f64));
            let brute = 1.0 - (ps + pt - 2.0 * ps * pt);
            let got = at(u, v, rs / 1.5, rt / 1.5) as f64;
            assert!((got - brute).abs() < 1e-3, "({u}, {v}): {got} vs {brute}");
        }
    }
}
