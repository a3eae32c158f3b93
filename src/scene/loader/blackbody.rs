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
//! The matching functions are the CIE's 5 nm table ([`CIE_XYZ_5NM`], made by
//! `scripts/cie_table.py` from the 1 nm table in pbrt-v4's `spectrum.cpp`); the integral is a
//! 5 nm sum (against the 1 nm sums pbrt-v4 uses, chromaticity within 1e-5 from 1000 to
//! 10000 K).

use crate::math::Vec3;

/// First wavelength of [`CIE_XYZ_5NM`] and its step, in nm.
const LAMBDA_MIN: f64 = 360.0;
const LAMBDA_STEP: f64 = 5.0;

/// IEC 61966-2-1's XYZ to linear sRGB matrix (rows), as in `scripts/named_spectra.py`.
const XYZ_TO_SRGB: [[f64; 3]; 3] = [
    [3.2404542, -1.5371385, -0.4985314],
    [-0.969266, 1.8760108, 0.041556],
    [0.0556434, -0.2040259, 1.0572252],
];

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
    let ln: Vec<f64> = (0..CIE_XYZ_5NM.len())
        .map(|i| ln_planck(LAMBDA_MIN + LAMBDA_STEP * i as f64, t))
        .collect();
    let top = ln.iter().fold(f64::NEG_INFINITY, |a, &b| a.max(b));
    let mut sum = [0.0; 3];
    for (cmf, l) in CIE_XYZ_5NM.iter().zip(&ln) {
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
    let row = |r: [f64; 3]| (r[0] * v[0] + r[1] * v[1] + r[2] * v[2]).max(0.0) as f32;
    Some(Vec3::new(
        row(XYZ_TO_SRGB[0]),
        row(XYZ_TO_SRGB[1]),
        row(XYZ_TO_SRGB[2]),
    ))
}

/// Luminance of pbrt-v4's `BlackbodySpectrum(T)` itself (Planck's law divided by its value at
/// the peak wavelength, Wien's 2.8977721e-3 m K / T): `SpectrumToXYZ(s).Y`, the integral of
/// y-bar times it over the integral of y-bar (106.856895). pbrt-v4's portal infinite light
/// converts its `L` to RGB this way, without the one-nit normalisation of other lights.
/// `None` unless `t` is finite and > 0.
pub fn peak_normalized_luminance(t: f64) -> Option<f64> {
    if !(t.is_finite() && t > 0.0) {
        return None;
    }
    const CIE_Y_INTEGRAL: f64 = 106.856895;
    let peak = ln_planck(2.897_772_1e-3 / t * 1e9, t);
    let sum: f64 = CIE_XYZ_5NM
        .iter()
        .enumerate()
        .map(|(i, cmf)| cmf[1] * (ln_planck(LAMBDA_MIN + LAMBDA_STEP * i as f64, t) - peak).exp())
        .sum();
    Some(sum * LAMBDA_STEP / CIE_Y_INTEGRAL)
}

/// The CIE 1931 2-degree colour matching functions (x-bar, y-bar, z-bar) at 360, 365, ..., 830 nm.
#[rustfmt::skip]
pub const CIE_XYZ_5NM: [[f64; 3]; 95] = [
    [0.0001299, 3.917e-06, 0.0006061], // 360 nm
    [0.0002321, 6.965e-06, 0.001086], // 365 nm
    [0.0004149, 1.239e-05, 0.001946], // 370 nm
    [0.0007416, 2.202e-05, 0.003486], // 375 nm
    [0.001368, 3.9e-05, 0.006450001], // 380 nm
    [0.002236, 6.4e-05, 0.01054999], // 385 nm
    [0.004243, 0.00012, 0.02005001], // 390 nm
    [0.00765, 0.000217, 0.03621], // 395 nm
    [0.01431, 0.000396, 0.06785001], // 400 nm
    [0.02319, 0.00064, 0.1102], // 405 nm
    [0.04351, 0.00121, 0.2074], // 410 nm
    [0.07763, 0.00218, 0.3713], // 415 nm
    [0.13438, 0.004, 0.6456], // 420 nm
    [0.21477, 0.0073, 1.0390501], // 425 nm
    [0.2839, 0.0116, 1.3856], // 430 nm
    [0.3285, 0.01684, 1.62296], // 435 nm
    [0.34828, 0.023, 1.74706], // 440 nm
    [0.34806, 0.0298, 1.7826], // 445 nm
    [0.3362, 0.038, 1.77211], // 450 nm
    [0.3187, 0.048, 1.7441], // 455 nm
    [0.2908, 0.06, 1.6692], // 460 nm
    [0.2511, 0.0739, 1.5281], // 465 nm
    [0.19536, 0.09098, 1.28764], // 470 nm
    [0.1421, 0.1126, 1.0419], // 475 nm
    [0.09564, 0.13902, 0.8129501], // 480 nm
    [0.05795001, 0.1693, 0.6162], // 485 nm
    [0.03201, 0.20802, 0.46518], // 490 nm
    [0.0147, 0.2586, 0.3533], // 495 nm
    [0.0049, 0.323, 0.272], // 500 nm
    [0.0024, 0.4073, 0.2123], // 505 nm
    [0.0093, 0.503, 0.1582], // 510 nm
    [0.0291, 0.6082, 0.1117], // 515 nm
    [0.06327, 0.71, 0.07824999], // 520 nm
    [0.1096, 0.7932, 0.05725001], // 525 nm
    [0.1655, 0.862, 0.04216], // 530 nm
    [0.2257499, 0.9148501, 0.02984], // 535 nm
    [0.2904, 0.954, 0.0203], // 540 nm
    [0.3597, 0.9803, 0.0134], // 545 nm
    [0.4334499, 0.9949501, 0.008749999], // 550 nm
    [0.5120501, 1.0, 0.005749999], // 555 nm
    [0.5945, 0.995, 0.0039], // 560 nm
    [0.6784, 0.9786, 0.002749999], // 565 nm
    [0.7621, 0.952, 0.0021], // 570 nm
    [0.8425, 0.9154, 0.0018], // 575 nm
    [0.9163, 0.87, 0.001650001], // 580 nm
    [0.9786, 0.8163, 0.0014], // 585 nm
    [1.0263, 0.757, 0.0011], // 590 nm
    [1.0567, 0.6949, 0.001], // 595 nm
    [1.0622, 0.631, 0.0008], // 600 nm
    [1.0456, 0.5668, 0.0006], // 605 nm
    [1.0026, 0.503, 0.00034], // 610 nm
    [0.9384, 0.4412, 0.00024], // 615 nm
    [0.8544499, 0.381, 0.00019], // 620 nm
    [0.7514, 0.321, 0.0001], // 625 nm
    [0.6424, 0.265, 4.999999e-05], // 630 nm
    [0.5419, 0.217, 3e-05], // 635 nm
    [0.4479, 0.175, 2e-05], // 640 nm
    [0.3608, 0.1382, 1e-05], // 645 nm
    [0.2835, 0.107, 0.0], // 650 nm
    [0.2187, 0.0816, 0.0], // 655 nm
    [0.1649, 0.061, 0.0], // 660 nm
    [0.1212, 0.04458, 0.0], // 665 nm
    [0.0874, 0.032, 0.0], // 670 nm
    [0.0636, 0.0232, 0.0], // 675 nm
    [0.04677, 0.017, 0.0], // 680 nm
    [0.0329, 0.01192, 0.0], // 685 nm
    [0.0227, 0.00821, 0.0], // 690 nm
    [0.01584, 0.005723, 0.0], // 695 nm
    [0.01135916, 0.004102, 0.0], // 700 nm
    [0.008110916, 0.002929, 0.0], // 705 nm
    [0.005790346, 0.002091, 0.0], // 710 nm
    [0.004109457, 0.001484, 0.0], // 715 nm
    [0.002899327, 0.001047, 0.0], // 720 nm
    [0.00204919, 0.00074, 0.0], // 725 nm
    [0.001439971, 0.00052, 0.0], // 730 nm
    [0.0009999493, 0.0003611, 0.0], // 735 nm
    [0.0006900786, 0.0002492, 0.0], // 740 nm
    [0.0004760213, 0.0001719, 0.0], // 745 nm
    [0.0003323011, 0.00012, 0.0], // 750 nm
    [0.0002348261, 8.48e-05, 0.0], // 755 nm
    [0.0001661505, 6e-05, 0.0], // 760 nm
    [0.000117413, 4.24e-05, 0.0], // 765 nm
    [8.307527e-05, 3e-05, 0.0], // 770 nm
    [5.870652e-05, 2.12e-05, 0.0], // 775 nm
    [4.150994e-05, 1.499e-05, 0.0], // 780 nm
    [2.935326e-05, 1.06e-05, 0.0], // 785 nm
    [2.067383e-05, 7.4657e-06, 0.0], // 790 nm
    [1.455977e-05, 5.2578e-06, 0.0], // 795 nm
    [1.025398e-05, 3.7029e-06, 0.0], // 800 nm
    [7.221456e-06, 2.6078e-06, 0.0], // 805 nm
    [5.085868e-06, 1.8366e-06, 0.0], // 810 nm
    [3.581652e-06, 1.2934e-06, 0.0], // 815 nm
    [2.522525e-06, 9.1093e-07, 0.0], // 820 nm
    [1.776509e-06, 6.4153e-07, 0.0], // 825 nm
    [1.251141e-06, 4.5181e-07, 0.0], // 830 nm
];

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
