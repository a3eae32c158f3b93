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
//! The loader parses and stores them ([`crate::scene::Scene::textures`]); the integrators do
//! not read them yet (that needs per-hit BSDFs), so a material that names a texture is still an
//! error, "textures are parsed but not yet applied", and nothing renders silently wrong.
//!
//! Lookups follow pbrt-v4:
//! - `uv` mapping: (s, t) = (uscale u + udelta, vscale v + vdelta); image textures then flip
//!   t (t = 1 - t) because image rows run top to bottom.
//! - image lookups (`filter` `bilinear`, the default; `point` is the nearest texel; `trilinear`
//!   and `ewa` are looked up bilinearly from the full-resolution image until ray differentials
//!   exist): x = s w - 1/2, y = t h - 1/2, the four texels around (x, y) weighted by their
//!   fractional distances, each texel address wrapped by `wrap`: `repeat` (modulo), `clamp`
//!   (to the edge), `black` (0 outside).
//! - `encoding` decodes 8- and 16-bit images: `sRGB` (the IEC 61966-2-1 curve; the default for
//!   PNG files), `linear` (the default for other files), `gamma G` (v^G). Float images (EXR,
//!   PFM) are linear.
//! - `imagemap`: scale times the lookup, then `invert` gives max(0, 1 - v); a float imagemap
//!   reads the mean of the three channels.
//! - `checkerboard` (2D): `tex1` where floor(s) + floor(t) is even, else `tex2` (pbrt-v4's
//!   filtered checkerboard at zero filter width); `mix`: (1 - amount) tex1 + amount tex2;
//!   `scale`: tex times scale; `constant`: value.
//!
//! Float textures are [`Texture`]s whose three channels are equal.

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

/// Nearest texel or bilinear interpolation of the four around the lookup point.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Filter {
    Point,
    Bilinear,
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
    /// A `float` texture: the mean of the channels.
    pub float: bool,
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
    /// The texture's value at surface coordinates `uv`.
    pub fn eval(&self, uv: Vec2) -> Vec3 {
        match self {
            Texture::Constant(v) => *v,
            Texture::Image(m) => {
                let st = m.mapping.map(uv);
                let v = m
                    .image
                    .lookup(Vec2::new(st.x, 1.0 - st.y), m.wrap, m.filter);
                let v = if m.float {
                    Vec3::splat(v.element_sum() / 3.0)
                } else {
                    v
                } * m.scale;
                if m.invert {
                    (Vec3::ONE - v).max(Vec3::ZERO)
                } else {
                    v
                }
            }
            Texture::Checkerboard {
                mapping,
                tex1,
                tex2,
            } => {
                let st = mapping.map(uv);
                let odd = (st.x.floor() as i64 + st.y.floor() as i64).rem_euclid(2) == 1;
                if odd {
                    tex2.eval(uv)
                } else {
                    tex1.eval(uv)
                }
            }
            Texture::Scale { tex, scale } => tex.eval(uv) * scale.eval(uv),
            Texture::Mix { tex1, tex2, amount } => {
                let a = amount.eval(uv);
                (Vec3::ONE - a) * tex1.eval(uv) + a * tex2.eval(uv)
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
        // A float imagemap reads the channel mean.
        near(
            map(UvMapping::default(), 1.0, false, true).eval(Vec2::new(0.25, 0.75)),
            Vec3::splat(1.0 / 3.0),
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
}
