//! Blackbody emission as photon's RGB: `"blackbody L" [ T ]` on area, distant and infinite
//! lights and `"blackbody I" [ T ]` on point and spot lights.
//!
//! ```text
//! AreaLightSource "diffuse" "blackbody L" [ 3000 ] "float scale" 20
//! LightSource "point" "blackbody I" [ 5500 ] "float power" 100
//! ```
//!
//! What pbrt-v4 renders: the light's spectrum is Planck's law normalised to peak 1
//! (`BlackbodySpectrum`), and every light divides its `scale` by `SpectrumToPhotometric` of the
//! spectrum (the integral of y-bar times it), so the light has luminance Y = `scale` (before
//! `power`/`illuminance`, which then work as for an RGB light). The default `cie1931` film
//! sensor turns spectral radiance into XYZ with the CIE 1931 matching functions and writes
//! `XYZ -> sRGB` of it, without white balance. So a blackbody light is the RGB
//! `M_srgb * XYZ(T) / Y(T)` times `scale`, where XYZ(T) integrates Planck's law against the CIE
//! 1931 2-degree matching functions over pbrt-v4's 360..830 nm. An `rgb L` light already is
//! that RGB in pbrt-v4 (its spectrum is the RGB's reflectance curve times the colour space's
//! D65 normalised to luminance 1, and `scale` is divided by that D65's luminance), which is
//! how photon reads it. A temperature of 6504 K comes out near white, at low temperatures
//! the blue (negative in sRGB below ~1900 K) is clamped to 0.
//!
//! The matching functions are every fifth row of [`crate::spectrum::cie::CMF`] (the CIE's 5 nm
//! table); the integral is a 5 nm sum (against the 1 nm sums pbrt-v4 uses, chromaticity within
//! 1e-5 from 1000 to 10000 K). XYZ to sRGB is [`crate::spectrum`]'s matrix (sRGB's primaries,
//! the white of the D65 table), as the spectral renderer's film uses.

use crate::math::Vec3;

/// First wavelength of the 5 nm rows and their step, in nm.
const LAMBDA_MIN: f64 = 360.0;
const LAMBDA_STEP: f64 = 5.0;

/// The CIE 1931 2-degree matching functions at 360, 365, ..., 830 nm.
fn cmf_5nm() -> impl Iterator<Item = [f64; 3]> {
    (crate::spectrum::cie::CMF.iter().step_by(5)).map(|c| c.map(f64::from))
}

/// The natural log of Planck's spectral radiance at `lambda_nm` for temperature `t` (K), up to
/// a constant (pbrt-v4's constants). In logs so that no temperature overflows or underflows.
fn ln_planck(lambda_nm: f64, t: f64) -> f64 {
    const C: f64 = 299_792_458.0;
    const H: f64 = 6.626_069_57e-34;
    const KB: f64 = 1.380_648_8e-23;
    let l = lambda_nm * 1e-9;
    let x = H * C / (l * KB * t);
    // ln(e^x - 1): x + ln(1 - e^-x), exact for large x too.
    -5.0 * l.ln() - (x + (-(-x).exp()).ln_1p())
}

/// CIE 1931 XYZ of Planck's law at temperature `t` (K), scaled so that the largest term is 1
/// (only ratios matter). `None` unless `t` is finite and > 0.
pub fn xyz(t: f64) -> Option<[f64; 3]> {
    if !(t.is_finite() && t > 0.0) {
        return None;
    }
    let ln: Vec<f64> = (0..cmf_5nm().count())
        .map(|i| ln_planck(LAMBDA_MIN + LAMBDA_STEP * i as f64, t))
        .collect();
    let top = ln.iter().fold(f64::NEG_INFINITY, |a, &b| a.max(b));
    let mut sum = [0.0; 3];
    for (cmf, l) in cmf_5nm().zip(&ln) {
        let b = (l - top).exp();
        for c in 0..3 {
            sum[c] += cmf[c] * b;
        }
    }
    Some(sum)
}

/// Linear sRGB of a blackbody at temperature `t` (K) with luminance 1 (before clamping a
/// negative component to 0); `None` unless `t` is finite and > 0.
pub fn rgb(t: f64) -> Option<Vec3> {
    let [x, y, z] = xyz(t)?;
    if y.is_nan() || y <= 0.0 {
        return None;
    }
    let v = [x / y, 1.0, z / y];
    let m = crate::spectrum::tables().xyz_to_rgb_rows;
    let row = |r: [f64; 3]| (r[0] * v[0] + r[1] * v[1] + r[2] * v[2]).max(0.0) as f32;
    Some(Vec3::new(row(m[0]), row(m[1]), row(m[2])))
}

/// The integral of the CIE 1931 y-bar over wavelength in nm (pbrt-v4's `CIE_Y_integral`). pbrt-v4's
/// film sensor integrates spectral radiance against y-bar without dividing by it, so a
/// spectrum that no light normalises (a grid medium's blackbody, an `rgbgrid`'s `Le`) reaches
/// the image this many times brighter than its luminance as written here.
pub const CIE_Y_INTEGRAL: f64 = 106.856895;

/// Luminance of pbrt-v4's `BlackbodySpectrum(T)` itself (Planck's law divided by its value at
/// the peak wavelength, Wien's 2.8977721e-3 m K / T): `SpectrumToXYZ(s).Y`, the integral of
/// y-bar times it over the integral of y-bar (106.856895). pbrt-v4's portal infinite light
/// converts its `L` to RGB this way, without the one-nit normalisation of other lights.
/// `None` unless `t` is finite and > 0.
pub fn peak_normalized_luminance(t: f64) -> Option<f64> {
    if !(t.is_finite() && t > 0.0) {
        return None;
    }
    let peak = ln_planck(2.897_772_1e-3 / t * 1e9, t);
    let sum: f64 = cmf_5nm()
        .enumerate()
        .map(|(i, cmf)| cmf[1] * (ln_planck(LAMBDA_MIN + LAMBDA_STEP * i as f64, t) - peak).exp())
        .sum();
    Some(sum * LAMBDA_STEP / CIE_Y_INTEGRAL)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The chromaticity (x, y) of `xyz`.
    fn xy(v: [f64; 3]) -> (f64, f64) {
        let s = v[0] + v[1] + v[2];
        (v[0] / s, v[1] / s)
    }

    /// Luminance by the Y row of the sRGB-to-XYZ matrix (IEC 61966-2-1).
    fn luminance(c: Vec3) -> f32 {
        0.2126 * c.x + 0.7152 * c.y + 0.0722 * c.z
    }

    /// CIE illuminant A is a 2856 K blackbody: x = 0.44757, y = 0.40745 (CIE 015:2004).
    #[test]
    fn illuminant_a_chromaticity() {
        let (x, y) = xy(xyz(2856.0).unwrap());
        assert!(
            (x - 0.44757).abs() < 2e-4 && (y - 0.40745).abs() < 2e-4,
            "({x}, {y})"
        );
    }

    /// An independent integration: Planck's law (written out here) against Wyman, Sloan and
    /// Shirley's multi-lobe Gaussian fit of the CIE 1931 functions (JCGT 2013), at 1 nm. The
    /// fit is good to ~1e-3 in chromaticity over these temperatures.
    #[test]
    fn matches_an_analytic_fit_of_the_matching_functions() {
        let g = |x: f64, mu: f64, s1: f64, s2: f64| {
            let s = if x < mu { s1 } else { s2 };
            (-0.5 * ((x - mu) / s).powi(2)).exp()
        };
        for t in [2856.0, 4000.0, 6504.0, 10000.0] {
            let mut sum = [0.0f64; 3];
            for l in 360..=830 {
                let l = l as f64;
                let m = l * 1e-9;
                let planck = 1.0 / (m.powi(5) * ((0.014387769 / (m * t)).exp() - 1.0));
                let fit = [
                    1.056 * g(l, 599.8, 37.9, 31.0) + 0.362 * g(l, 442.0, 16.0, 26.7)
                        - 0.065 * g(l, 501.1, 20.4, 26.2),
                    0.821 * g(l, 568.8, 46.9, 40.5) + 0.286 * g(l, 530.9, 16.3, 31.1),
                    1.217 * g(l, 437.0, 11.8, 36.0) + 0.681 * g(l, 459.0, 26.0, 13.8),
                ];
                for c in 0..3 {
                    sum[c] += fit[c] * planck;
                }
            }
            let (want, got) = (xy(sum), xy(xyz(t).unwrap()));
            assert!(
                (want.0 - got.0).abs() < 2e-3 && (want.1 - got.1).abs() < 2e-3,
                "{t} K: {got:?} against the fit's {want:?}"
            );
        }
    }

    /// 6504 K is near D65 (sRGB white) and every blackbody has luminance 1; red rises and blue
    /// falls as the temperature drops.
    #[test]
    fn luminance_one_and_white_near_6504k() {
        let white = rgb(6504.0).unwrap();
        assert!((white - Vec3::ONE).abs().max_element() < 0.05, "{white}");
        for t in [2000.0, 2856.0, 3000.0, 6504.0, 10000.0, 40000.0] {
            let c = rgb(t).unwrap();
            assert!((luminance(c) - 1.0).abs() < 1e-3, "{t} K: {c}");
        }
        let (warm, cool) = (rgb(3000.0).unwrap(), rgb(10000.0).unwrap());
        assert!(warm.x > 1.5 && warm.z < 0.4 && cool.z > 1.3 && cool.x < 0.95);
    }

    /// The luminance of the peak-normalised spectrum, against a 1 nm integration of Planck's
    /// law written out here with the analytic fit of y-bar (within the fit's ~1%): at 6500 K
    /// the peak (446 nm) is inside the visible range, so Y is below 1; at 3000 K it is at
    /// 966 nm, outside, and Y is small.
    #[test]
    fn peak_normalized_luminance_matches_planck() {
        let g = |x: f64, mu: f64, s1: f64, s2: f64| {
            let s = if x < mu { s1 } else { s2 };
            (-0.5 * ((x - mu) / s).powi(2)).exp()
        };
        let planck = |l: f64, t: f64| 1.0 / (l.powi(5) * ((0.014387769 / (l * t)).exp() - 1.0));
        for t in [3000.0, 6500.0] {
            let peak = planck(2.8977721e-3 / t, t);
            let y: f64 = (360..=830)
                .map(|l| {
                    let l = l as f64;
                    let ybar = 0.821 * g(l, 568.8, 46.9, 40.5) + 0.286 * g(l, 530.9, 16.3, 31.1);
                    ybar * planck(l * 1e-9, t) / peak
                })
                .sum::<f64>()
                / 106.856895;
            let got = peak_normalized_luminance(t).unwrap();
            assert!((got - y).abs() < 0.01 * y, "{t} K: {got} against {y}");
        }
        assert!(peak_normalized_luminance(6500.0).unwrap() < 1.0);
        assert_eq!(peak_normalized_luminance(0.0), None);
    }

    /// Extreme temperatures stay finite (computed in logs); invalid ones are refused.
    #[test]
    fn extreme_and_invalid_temperatures() {
        for t in [1.0, 100.0, 1e9] {
            let c = rgb(t).unwrap();
            assert!(c.is_finite() && c.min_element() >= 0.0, "{t} K: {c}");
        }
        for t in [0.0, -5.0, f64::NAN, f64::INFINITY] {
            assert_eq!(rgb(t), None, "{t}");
        }
    }
}
