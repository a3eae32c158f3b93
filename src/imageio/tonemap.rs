//! Tone mapping of linear HDR values to 8-bit sRGB, for PNG output (`photon convert`,
//! [`super::png::write_png_tonemapped`]) and for the LDR-FLIP inputs of `photon compare`.
//!
//! Each channel `v` is first scaled by the exposure, `x = max(v * 2^stops, 0)` (NaN becomes 0),
//! then mapped by one curve `f` to [0, 1], then encoded with the exact sRGB OETF and rounded to
//! 8 bits ([`super::png::encode_srgb8`]):
//!
//! * `clamp`: `f(x) = min(x, 1)`, the plain sRGB clip of the render's PNG preview.
//! * `aces`: Krzysztof Narkowicz's fit of the ACES filmic RRT+ODT (2015), applied per channel
//!   with no pre-scale: `f(x) = min(x (2.51 x + 0.03) / (x (2.43 x + 0.59) + 0.14), 1)`. Its
//!   derivative's numerator is `1.408 x^2 + 0.7028 x + 0.0042 > 0`, so it rises from `f(0) = 0`
//!   and reaches 1 at `x = 7.24`.
//! * `filmic`: Reinhard's extended operator per channel with white point `W = 4` (two stops
//!   above display white): `f(x) = min(x (1 + x / W^2) / (1 + x), 1)`, so `f(0) = 0`, `f(W) = 1`,
//!   and the highlights roll off instead of clipping.
//!
//! Every curve maps 0 to 0 and is non-decreasing, so tone mapping never reorders values.
use super::png::encode_srgb8;

/// The tone curve of [`to_srgb8`].
#[derive(clap::ValueEnum, Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Tonemap {
    /// Plain sRGB clip at 1 (the render's PNG preview).
    #[default]
    Clamp,
    /// Narkowicz's ACES filmic fit.
    Aces,
    /// Reinhard extended, white point 4.
    Filmic,
}

/// The white point of [`Tonemap::Filmic`]: the linear value that maps to 1.
pub const FILMIC_WHITE: f32 = 4.0;

impl Tonemap {
    /// The name `--tonemap` takes.
    pub fn name(self) -> &'static str {
        match self {
            Tonemap::Clamp => "clamp",
            Tonemap::Aces => "aces",
            Tonemap::Filmic => "filmic",
        }
    }

    /// The curve of the module's doc applied to an exposed linear value `x`: a value in [0, 1]
    /// (negative values and NaN give 0).
    pub fn curve(self, x: f32) -> f32 {
        // NaN fails `x > 0` and becomes 0.
        let x = if x > 0.0 { x } else { 0.0 };
        let y = match self {
            Tonemap::Clamp => x,
            Tonemap::Aces => {
                if x.is_infinite() {
                    1.0
                } else {
                    x * (2.51 * x + 0.03) / (x * (2.43 * x + 0.59) + 0.14)
                }
            }
            Tonemap::Filmic => {
                if x.is_infinite() {
                    1.0
                } else {
                    x * (1.0 + x / (FILMIC_WHITE * FILMIC_WHITE)) / (1.0 + x)
                }
            }
        };
        y.min(1.0)
    }
}

/// One linear sample to an 8-bit sRGB code: exposure `scale` (`2^stops`), the curve, the OETF.
pub fn encode(v: f32, scale: f32, tonemap: Tonemap) -> u8 {
    encode_srgb8(tonemap.curve(v * scale), 1.0)
}

/// `pixels` (linear RGB) as tightly packed 8-bit sRGB RGB bytes after exposure `stops` and the
/// curve `tonemap`.
pub fn to_srgb8(pixels: &[[f32; 3]], stops: f32, tonemap: Tonemap) -> Vec<u8> {
    let scale = stops.exp2();
    pixels
        .iter()
        .flat_map(|p| p.map(|v| encode(v, scale, tonemap)))
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    const ALL: [Tonemap; 3] = [Tonemap::Clamp, Tonemap::Aces, Tonemap::Filmic];

    #[test]
    fn curves_map_zero_to_zero_and_never_decrease() {
        for t in ALL {
            assert_eq!(t.curve(0.0), 0.0, "{t:?}");
            assert_eq!(t.curve(-3.0), 0.0, "{t:?}");
            assert_eq!(t.curve(f32::NAN), 0.0, "{t:?}");
            assert_eq!(t.curve(f32::INFINITY), 1.0, "{t:?}");
            let mut last = 0.0;
            // 0 .. 1000 in steps growing geometrically (fine near 0, wide in the highlights).
            let mut x = 1e-6f32;
            while x < 1000.0 {
                let y = t.curve(x);
                assert!((0.0..=1.0).contains(&y), "{t:?}({x}) = {y}");
                assert!(y >= last, "{t:?} decreases at {x}: {y} < {last}");
                last = y;
                x *= 1.01;
            }
            assert_eq!(last, 1.0, "{t:?} reaches white");
        }
    }

    #[test]
    fn curves_have_their_documented_shape() {
        // Below white, the clip is the identity.
        assert_eq!(Tonemap::Clamp.curve(0.25), 0.25);
        assert_eq!(Tonemap::Clamp.curve(7.0), 1.0);
        // Narkowicz's fit of mid grey: 0.18 -> about 0.267; it still rises at 4.
        let g = Tonemap::Aces.curve(0.18);
        assert!((g - 0.2669).abs() < 1e-3, "{g}");
        assert!(Tonemap::Aces.curve(4.0) < Tonemap::Aces.curve(8.0));
        // Reinhard extended reaches 1 exactly at its white point and is below x under it.
        assert!((Tonemap::Filmic.curve(FILMIC_WHITE) - 1.0).abs() < 1e-6);
        assert!(Tonemap::Filmic.curve(0.5) < 0.5);
        // Encoding: the clip of 1 is code 255, of 0.5 the sRGB code 188.
        assert_eq!(encode(1.0, 1.0, Tonemap::Clamp), 255);
        assert_eq!(encode(0.25, 2.0, Tonemap::Clamp), 188);
        assert_eq!(
            to_srgb8(&[[0.0, 1.0, 2.0]], 0.0, Tonemap::Clamp),
            [0, 255, 255]
        );
    }
}
