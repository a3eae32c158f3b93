//! Spectral rendering as pbrt-v4 does it (`--spectral`): each camera sample carries four
//! wavelengths, every RGB value of the scene is uplifted to a spectrum where it is used, and
//! the film turns each sample's values back into linear sRGB through the CIE 1931 observer.
//!
//! An RGB renderer multiplies colours channel by channel, which is not what light does: a
//! saturated wall lit by an orange light, seen after two bounces, differs by several percent
//! between the two (the Cornell box's red wall is 7-11% brighter in RGB than in pbrt-v4).
//!
//! - Wavelengths ([`Lambda::sample`]): pbrt-v4's visible-wavelength density over 360-830 nm,
//!   four stratified samples per camera sample, as pbrt-v4 takes ([`Spectrum`]'s lanes).
//! - Uplifting (pbrt-v4's `RGBAlbedoSpectrum`, `RGBUnboundedSpectrum`,
//!   `RGBIlluminantSpectrum`): reflectances by the sigmoid-polynomial fit ([`fit`]);
//!   unbounded values (a conductor's `eta` and `k`) as `2 m` times the fit of `rgb / 2m`
//!   (`m` the largest channel); emission the same times the colour space's illuminant (D65,
//!   normalised to luminance 1), so a white light is D65.
//! - Film ([`Lambda::to_rgb`]): XYZ by the colour matching functions over the wavelengths'
//!   density, then sRGB's matrix (primaries of IEC 61966-2-1, white point that of the D65
//!   table), as pbrt-v4's default `cie1931` sensor.
//!
//! [`Lambda::Rgb`] leaves every value as it is: the renderer's RGB mode.
pub mod blackbody;
pub mod cie;
pub mod fit;
mod value;

pub use value::Spectrum;

use crate::math::Vec3;
use std::sync::OnceLock;

/// The shortest and longest wavelengths sampled (nm).
pub const LAMBDA_MIN: f32 = 360.0;
pub const LAMBDA_MAX: f32 = 830.0;

/// Wavelengths per camera sample.
pub const N_LAMBDA: usize = 4;

/// What a camera sample's values mean: linear sRGB channels, or radiance at four sampled
/// wavelengths (nm) with their densities.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub enum Lambda {
    #[default]
    Rgb,
    Sampled {
        nm: [f32; N_LAMBDA],
        pdf: [f32; N_LAMBDA],
    },
}

/// pbrt-v4's density of visible wavelengths (`VisibleWavelengthsPDF`), 0 outside 360-830 nm.
pub fn visible_pdf(nm: f32) -> f32 {
    if !(LAMBDA_MIN..=LAMBDA_MAX).contains(&nm) {
        return 0.0;
    }
    let c = (0.0072 * (nm - 538.0)).cosh();
    0.003_939_804 / (c * c)
}

/// The wavelength at `u` in `[0, 1)` of [`visible_pdf`]'s inverse distribution.
pub fn sample_visible(u: f32) -> f32 {
    538.0 - 138.888_89 * (0.856_910_6 - 1.827_502 * u).atanh()
}

impl Lambda {
    /// Four wavelengths stratified from `u` in `[0, 1)` (`u`, `u + 1/4`, `u + 1/2`, `u + 3/4`,
    /// wrapped).
    pub fn sample(u: f32) -> Lambda {
        let nm: [f32; N_LAMBDA] = std::array::from_fn(|i| {
            let v = u + i as f32 / N_LAMBDA as f32;
            let v = if v >= 1.0 { v - 1.0 } else { v };
            sample_visible(v).clamp(LAMBDA_MIN, LAMBDA_MAX)
        });
        Lambda::Sampled {
            nm,
            pdf: nm.map(visible_pdf),
        }
    }

    /// A reflectance in `[0, 1]` per channel at these wavelengths.
    pub fn albedo(&self, rgb: Vec3) -> Spectrum {
        match self {
            Lambda::Rgb => Spectrum::from_rgb(rgb),
            Lambda::Sampled { nm, .. } => {
                let c = coeffs(rgb.to_array());
                Spectrum::from_array(nm.map(|l| fit::eval(c, l)))
            }
        }
    }

    /// A non-negative value without upper bound (a conductor's index) at these wavelengths.
    pub fn unbounded(&self, rgb: Vec3) -> Spectrum {
        match self {
            Lambda::Rgb => Spectrum::from_rgb(rgb),
            Lambda::Sampled { nm, .. } => {
                let rgb = rgb.max(Vec3::ZERO);
                let m = rgb.max_element();
                if m <= 0.0 || !m.is_finite() {
                    return Spectrum::ZERO;
                }
                let c = coeffs((rgb / (2.0 * m)).to_array());
                Spectrum::from_array(nm.map(|l| 2.0 * m * fit::eval(c, l)))
            }
        }
    }

    /// Emitted radiance (a light's RGB) at these wavelengths: [`Self::unbounded`] times the
    /// illuminant D65 of luminance 1.
    pub fn illuminant(&self, rgb: Vec3) -> Spectrum {
        match self {
            Lambda::Rgb => Spectrum::from_rgb(rgb),
            Lambda::Sampled { nm, .. } => {
                let t = tables();
                self.unbounded(rgb) * Spectrum::from_array(nm.map(|l| t.d65(l)))
            }
        }
    }

    /// Linear sRGB of one sample's values `v` at these wavelengths (the film's sensor).
    pub fn to_rgb(&self, v: Spectrum) -> Vec3 {
        match self {
            Lambda::Rgb => v.rgb(),
            Lambda::Sampled { nm, pdf } => {
                let v = v.to_array();
                let mut xyz = Vec3::ZERO;
                for i in 0..N_LAMBDA {
                    if pdf[i] > 0.0 {
                        xyz += cmf(nm[i]) * (v[i] / pdf[i]);
                    }
                }
                tables().xyz_to_rgb * (xyz / N_LAMBDA as f32)
            }
        }
    }
}

/// How far RGB rendering is from spectral for light of colour `light` reflected twice by
/// reflectance `albedo` (a wall lighting itself through the room): the largest channel of
/// `|film(albedo(lambda)^2 light(lambda)) - albedo^2 light|` over the largest channel of the
/// spectral answer (1-nm integration; the two colours fitted one by one, [`fit::fit_one`],
/// so that asking costs no table). The Cornell box's red wall under its orange light: 0.10;
/// a grey: 0.
pub fn two_bounce_discrepancy(albedo: Vec3, light: Vec3) -> f32 {
    let t = tables();
    let fit = |rgb: Vec3| fit::fit_one(rgb.to_array(), t.rgb_to_xyz_rows, t.xyz_to_rgb_rows);
    let m = light.max_element();
    if m <= 0.0 || !m.is_finite() {
        return 0.0;
    }
    let ca = fit(albedo.clamp(Vec3::ZERO, Vec3::ONE));
    let cl = fit(light.max(Vec3::ZERO) / (2.0 * m));
    let mut xyz = Vec3::ZERO;
    for (i, c) in cie::CMF.iter().enumerate() {
        let nm = LAMBDA_MIN + i as f32;
        let a = fit::eval(ca, nm);
        let l = 2.0 * m * fit::eval(cl, nm) * t.d65(nm);
        xyz += Vec3::from(*c) * (a * a * l);
    }
    let spectral = t.xyz_to_rgb * xyz;
    let rgb = albedo * albedo * light;
    ((spectral - rgb).abs().max_element() / spectral.max_element().max(1e-6)).min(1.0)
}

/// [`fit::Table::coeffs`] of `rgb`, remembered per thread: a render asks for the same few
/// colours (its constant materials and lights) at almost every vertex. A pure function's
/// memo, so images do not depend on it.
fn coeffs(rgb: [f32; 3]) -> [f32; 3] {
    use std::cell::RefCell;
    const SLOTS: usize = 64;
    type Slot = Option<([u32; 3], [f32; 3])>;
    thread_local! {
        static MEMO: RefCell<[Slot; SLOTS]> = const { RefCell::new([None; SLOTS]) };
    }
    let key = rgb.map(f32::to_bits);
    let h = key[0]
        .wrapping_mul(0x9e37_79b1)
        .wrapping_add(key[1].wrapping_mul(0x85eb_ca77))
        .wrapping_add(key[2].wrapping_mul(0xc2b2_ae3d));
    let slot = (h >> 26) as usize % SLOTS;
    MEMO.with(|m| {
        let mut m = m.borrow_mut();
        match m[slot] {
            Some((k, c)) if k == key => c,
            _ => {
                let c = fit_table().coeffs(rgb);
                m[slot] = Some((key, c));
                c
            }
        }
    })
}

/// The colour matching functions at `nm` (linear between the 1-nm table's entries).
pub fn cmf(nm: f32) -> Vec3 {
    let x = (nm - LAMBDA_MIN).clamp(0.0, LAMBDA_MAX - LAMBDA_MIN);
    let i = (x as usize).min(cie::CMF.len() - 2);
    let f = x - i as f32;
    let (a, b) = (Vec3::from(cie::CMF[i]), Vec3::from(cie::CMF[i + 1]));
    a + (b - a) * f
}

/// D65's tabulated relative power at `nm` (linear between the 5-nm entries from 300 nm).
pub(crate) fn d65_raw(nm: f32) -> f32 {
    let x = ((nm - 300.0) / 5.0).clamp(0.0, (cie::D65.len() - 1) as f32);
    let i = (x as usize).min(cie::D65.len() - 2);
    let f = x - i as f32;
    cie::D65[i] + (cie::D65[i + 1] - cie::D65[i]) * f
}

/// The colorimetry derived from the CIE tables once per process.
pub struct Tables {
    /// D65 scaled to luminance 1 (`sum ybar D65` over the 1-nm grid is 1).
    d65_scale: f32,
    pub xyz_to_rgb: crate::math::Mat3,
    pub rgb_to_xyz: crate::math::Mat3,
    /// The same matrices in f64, rows first.
    pub xyz_to_rgb_rows: [[f64; 3]; 3],
    pub rgb_to_xyz_rows: [[f64; 3]; 3],
}

impl Tables {
    /// D65 of luminance 1 at `nm`.
    pub fn d65(&self, nm: f32) -> f32 {
        d65_raw(nm) * self.d65_scale
    }
}

/// sRGB's primaries (x, y).
const PRIMARIES: [[f64; 2]; 3] = [[0.64, 0.33], [0.30, 0.60], [0.15, 0.06]];

/// The process's colorimetry (built on first use, in microseconds).
pub fn tables() -> &'static Tables {
    static T: OnceLock<Tables> = OnceLock::new();
    T.get_or_init(|| {
        let y_sum: f64 = (0..cie::CMF.len())
            .map(|i| cie::CMF[i][1] as f64 * d65_raw(LAMBDA_MIN + i as f32) as f64)
            .sum();
        let mut white = [0.0f64; 3];
        for (i, c) in cie::CMF.iter().enumerate() {
            let d = d65_raw(LAMBDA_MIN + i as f32) as f64 / y_sum;
            for k in 0..3 {
                white[k] += c[k] as f64 * d;
            }
        }
        let (rgb_to_xyz, xyz_to_rgb) = srgb_matrices(white);
        let to_mat = |m: [[f64; 3]; 3]| {
            crate::math::Mat3::from_cols_array_2d(
                &[0, 1, 2].map(|c| [0, 1, 2].map(|r| m[r][c] as f32)),
            )
        };
        Tables {
            d65_scale: (1.0 / y_sum) as f32,
            xyz_to_rgb: to_mat(xyz_to_rgb),
            rgb_to_xyz: to_mat(rgb_to_xyz),
            xyz_to_rgb_rows: xyz_to_rgb,
            rgb_to_xyz_rows: rgb_to_xyz,
        }
    })
}

/// The process's RGB-to-spectrum coefficients (fitted on first use, 0.3-0.5 s).
pub fn fit_table() -> &'static fit::Table {
    static T: OnceLock<fit::Table> = OnceLock::new();
    T.get_or_init(|| {
        let t = tables();
        fit::Table::build(t.rgb_to_xyz_rows, t.xyz_to_rgb_rows)
    })
}

/// sRGB's RGB-to-XYZ matrix and its inverse (rows) for the white point `white` (Y = 1).
fn srgb_matrices(white: [f64; 3]) -> ([[f64; 3]; 3], [[f64; 3]; 3]) {
    let xyz = |p: [f64; 2]| [p[0] / p[1], 1.0, (1.0 - p[0] - p[1]) / p[1]];
    let cols = PRIMARIES.map(xyz);
    let p = [0, 1, 2].map(|r| [0, 1, 2].map(|c| cols[c][r]));
    let inv = fit::invert(&p).expect("sRGB's primaries are independent");
    let s = [0, 1, 2].map(|r| (0..3).map(|k| inv[r][k] * white[k]).sum::<f64>());
    let m = [0, 1, 2].map(|r| [0, 1, 2].map(|c| p[r][c] * s[c]));
    let m_inv = fit::invert(&m).expect("sRGB's matrix is invertible");
    (m, m_inv)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The wavelength density integrates to 1 and the sampler inverts its distribution.
    #[test]
    fn visible_density_and_sampler_agree() {
        let n = 47000;
        let total: f64 = (0..n)
            .map(|i| {
                visible_pdf(360.0 + 470.0 * (i as f32 + 0.5) / n as f32) as f64 * 470.0 / n as f64
            })
            .sum();
        assert!((total - 1.0).abs() < 2e-3, "density integrates to {total}");
        // The fraction of samples below 500 nm against the density's integral up to there.
        let m = 100_000;
        let below = (0..m)
            .filter(|&i| sample_visible((i as f32 + 0.5) / m as f32) < 500.0)
            .count() as f64
            / m as f64;
        let integral: f64 = (0..14000)
            .map(|i| visible_pdf(360.0 + 140.0 * (i as f32 + 0.5) / 14000.0) as f64 * 0.01)
            .sum();
        assert!((below - integral).abs() < 2e-3, "{below} vs {integral}");
    }

    /// sRGB's matrix against the published one (IEC 61966-2-1, 4 decimals): the white point of
    /// the D65 table is the standard's to that precision.
    #[test]
    fn srgb_matrix_matches_the_standard() {
        let t = tables();
        let m = t.xyz_to_rgb.to_cols_array_2d();
        let want = [
            [3.2406, -1.5372, -0.4986],
            [-0.9689, 1.8758, 0.0415],
            [0.0557, -0.2040, 1.0570],
        ];
        for r in 0..3 {
            for c in 0..3 {
                assert!(
                    (m[c][r] - want[r][c]).abs() < 2e-3,
                    "{r},{c}: {} vs {}",
                    m[c][r],
                    want[r][c]
                );
            }
        }
    }

    /// Expected film RGB of `f(lambda)` over many stratified wavelength samples.
    fn film_mean(f: impl Fn(&Lambda) -> Spectrum) -> Vec3 {
        let n = 20_000;
        let mut sum = Vec3::ZERO;
        for i in 0..n {
            let l = Lambda::sample((i as f32 + 0.5) / n as f32);
            sum += l.to_rgb(f(&l));
        }
        sum / n as f32
    }

    /// A white light seen directly is white; a coloured one keeps its colour; a reflectance
    /// under white light gives back its RGB (the fit's round trip).
    #[test]
    fn uplift_round_trips_through_the_film() {
        let white = film_mean(|l| l.illuminant(Vec3::ONE));
        assert!((white - Vec3::ONE).abs().max_element() < 2e-3, "{white}");
        for rgb in [
            Vec3::new(17.0, 12.0, 4.0),
            Vec3::new(0.2, 0.5, 0.9),
            Vec3::new(1.0, 0.378_676, 0.013_473),
        ] {
            let light = film_mean(|l| l.illuminant(rgb));
            let err = ((light - rgb) / rgb.max_element()).abs().max_element();
            assert!(err < 5e-3, "light {rgb}: {light}");
        }
        for rgb in [
            Vec3::new(0.63, 0.065, 0.05),
            Vec3::new(0.14, 0.45, 0.091),
            Vec3::new(1.0, 0.378_676, 0.013_473),
            Vec3::new(0.5, 0.5, 0.5),
            Vec3::new(0.9, 0.9, 0.2),
        ] {
            let seen = film_mean(|l| l.albedo(rgb) * l.illuminant(Vec3::ONE));
            assert!(
                (seen - rgb).abs().max_element() < 5e-3,
                "albedo {rgb}: {seen}"
            );
        }
    }

    /// The colour noise of one camera sample's wavelengths: a white light on a flat
    /// reflectance, the squared coefficient of variation of each sRGB channel of the film's
    /// estimate over the wavelength offset. A path's noise is multiplied by `1 + cv^2`. With
    /// three wavelengths per sample (photon before 12-07) coffee's orange gave 0.22 in red
    /// and a grey 0.78 in blue; pbrt-v4's four give 0.036 and 0.34.
    #[test]
    fn four_wavelengths_keep_colour_noise_low() {
        let n = 20_000;
        let cv2 = |rgb: Vec3| {
            let (mut s, mut s2) = (Vec3::ZERO, Vec3::ZERO);
            for i in 0..n {
                let l = Lambda::sample((i as f32 + 0.5) / n as f32);
                let e = l.to_rgb(l.albedo(rgb) * l.illuminant(Vec3::ONE));
                (s, s2) = (s + e, s2 + e * e);
            }
            let mean = s / n as f32;
            (s2 / n as f32 - mean * mean) / (mean * mean)
        };
        let orange = cv2(Vec3::new(1.0, 0.378_676, 0.013_473));
        let grey = cv2(Vec3::splat(0.58));
        println!("cv^2 orange {orange}, grey {grey}");
        assert!(orange.x < 0.05 && orange.y < 0.02, "{orange}");
        assert!(grey.x < 0.05 && grey.y < 0.005 && grey.z < 0.45, "{grey}");
    }

    /// Reflectances stay in [0, 1]; a grey one is flat; RGB mode changes nothing.
    #[test]
    fn albedo_is_bounded_and_grey_is_flat() {
        for u in [0.0, 0.3, 0.77] {
            let l = Lambda::sample(u);
            for rgb in [
                Vec3::new(1.0, 0.0, 0.0),
                Vec3::new(0.0, 1.0, 1.0),
                Vec3::splat(0.25),
            ] {
                let s = l.albedo(rgb);
                assert!(
                    s.min_element() >= 0.0 && s.max_element() <= 1.0,
                    "{rgb} -> {s}"
                );
            }
            let g = l.albedo(Vec3::splat(0.25));
            assert!(
                (g - Spectrum::splat(0.25)).abs().max_element() < 1e-6,
                "{g}"
            );
        }
        let rgb = Vec3::new(0.3, 0.2, 0.1);
        assert_eq!(Lambda::Rgb.albedo(rgb), Spectrum::from_rgb(rgb));
        assert_eq!(Lambda::Rgb.illuminant(rgb), Spectrum::from_rgb(rgb));
        assert_eq!(Lambda::Rgb.to_rgb(Spectrum::from_rgb(rgb)), rgb);
    }
}

#[cfg(test)]
mod discrepancy_tests {
    use super::*;

    /// A grey reflectance under white light is the same in RGB and spectrally; the Cornell
    /// box's red wall under its orange light is 10% off, coffee's orange plastic 18%.
    #[test]
    fn two_bounce_discrepancy_of_greys_and_saturated_colours() {
        assert!(two_bounce_discrepancy(Vec3::splat(0.7), Vec3::ONE) < 1e-3);
        let red = two_bounce_discrepancy(Vec3::new(0.63, 0.065, 0.05), Vec3::new(17.0, 12.0, 4.0));
        assert!((0.08..0.13).contains(&red), "{red}");
        let orange = two_bounce_discrepancy(Vec3::new(1.0, 0.378_676, 0.013_473), Vec3::ONE);
        assert!((0.15..0.22).contains(&orange), "{orange}");
        assert_eq!(two_bounce_discrepancy(Vec3::ONE, Vec3::ZERO), 0.0);
    }
}

#[cfg(test)]
mod grid_tests {
    use super::*;

    /// The RGB a reflectance spectrum shows under D65 (1-nm integration).
    fn seen(c: [f32; 3]) -> Vec3 {
        let t = tables();
        let mut xyz = Vec3::ZERO;
        for i in 0..cie::CMF.len() {
            let nm = LAMBDA_MIN + i as f32;
            xyz += Vec3::from(cie::CMF[i]) * (fit::eval(c, nm) * t.d65(nm));
        }
        t.xyz_to_rgb * xyz
    }

    /// Every colour of a 9^3 grid over the RGB cube comes back from its fitted spectrum within
    /// 0.005 (pbrt-v4's fit has the same limits: the saturated corners are the hardest).
    #[test]
    fn fit_round_trips_over_the_cube() {
        let mut worst = (0.0f32, Vec3::ZERO, Vec3::ZERO);
        for r in 0..9 {
            for g in 0..9 {
                for b in 0..9 {
                    let rgb = Vec3::new(r as f32, g as f32, b as f32) / 8.0;
                    let back = seen(fit_table().coeffs(rgb.to_array()));
                    let e = (back - rgb).abs().max_element();
                    if e > worst.0 {
                        worst = (e, rgb, back);
                    }
                }
            }
        }
        eprintln!("worst round trip {:?}", worst);
        assert!(worst.0 < 0.005, "{worst:?}");
    }
}
