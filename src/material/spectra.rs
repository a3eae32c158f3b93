//! pbrt-v4's named spectra as photon's RGB values: the conductor `eta`/`k` of every named metal
//! and the dielectric `eta` of every named glass.
//!
//! ```text
//! Material "conductor" "spectrum eta" "metal-Ag-eta" "spectrum k" [ "metal-Ag-k" ]
//! Material "dielectric" "spectrum eta" "glass-BK7"
//! ```
//!
//! How the numbers were made (`scripts/named_spectra.py`, run on pbrt-v4's
//! `src/pbrt/util/spectrum.cpp`, which holds both the spectral tables and the CIE data):
//!
//! - metals: each (wavelength, value) table as pbrt-v4's piecewise-linear spectrum (0 outside
//!   its range) integrated at 1 nm over 360..830 nm against the CIE 1931 2-degree matching
//!   functions, divided by the integral of y-bar (XYZ), then the IEC 61966-2-1 XYZ-to-linear-sRGB
//!   matrix, negative results clamped to 0. This is pbrt-v3's `SampledSpectrum::ToRGB`, the
//!   source of the RGB values of copper, gold, silver and aluminium published with many
//!   converted scenes and renderers; it does not white-balance, so a flat spectrum c comes out as
//!   c * (1.205, 0.948, 0.909) (this matters for the nearly flat `MgO` and `TiO2`).
//! - glasses: the spectrum's value at 550 nm (photon has one index of refraction per material,
//!   so there is no dispersion).

use crate::math::Vec3;

/// The RGB of pbrt-v4's named metal spectra (`metal-{Ag,Al,Au,Cu,CuZn,MgO,TiO2}-{eta,k}`).
pub const METALS: [(&str, Vec3); 14] = [
    ("metal-Ag-eta", Vec3::new(0.155263, 0.116724, 0.13837)),
    ("metal-Ag-k", Vec3::new(4.82831, 3.122276, 2.146786)),
    ("metal-Al-eta", Vec3::new(1.657447, 0.880376, 0.521188)),
    ("metal-Al-k", Vec3::new(9.223812, 6.269582, 4.836629)),
    ("metal-Au-eta", Vec3::new(0.143123, 0.374943, 1.44239)),
    ("metal-Au-k", Vec3::new(3.983146, 2.385749, 1.603085)),
    ("metal-Cu-eta", CU_ETA),
    ("metal-Cu-k", CU_K),
    ("metal-CuZn-eta", Vec3::new(0.519765, 0.488511, 1.041926)),
    ("metal-CuZn-k", Vec3::new(4.330553, 2.548131, 1.591764)),
    ("metal-MgO-eta", Vec3::new(2.089575, 1.650738, 1.594754)),
    ("metal-MgO-k", Vec3::new(0.0, 0.0, 0.0)),
    ("metal-TiO2-eta", Vec3::new(3.456598, 2.801735, 2.904926)),
    ("metal-TiO2-k", Vec3::new(0.000103, 0.0, 0.000635)),
];

/// pbrt-v4's copper (`metal-Cu-eta`/`-k`), the conductor's default.
pub const CU_ETA: Vec3 = Vec3::new(0.200414, 0.924056, 1.102127);
pub const CU_K: Vec3 = Vec3::new(3.912917, 2.452863, 2.142027);

/// The index of refraction at 550 nm of pbrt-v4's named glasses.
pub const GLASSES: [(&str, f32); 7] = [
    ("glass-BK7", 1.518537),
    ("glass-BAF10", 1.673051),
    ("glass-FK51A", 1.487796),
    ("glass-LASF9", 1.855809),
    ("glass-F5", 1.677089),
    ("glass-F10", 1.733574),
    ("glass-F11", 1.791119),
];

/// The RGB of the named metal spectrum `name`, if there is one.
pub fn metal(name: &str) -> Option<Vec3> {
    METALS.iter().find(|(n, _)| *n == name).map(|(_, v)| *v)
}

/// The 550 nm index of refraction of the named glass `name`, if there is one.
pub fn glass(name: &str) -> Option<f32> {
    GLASSES.iter().find(|(n, _)| *n == name).map(|(_, v)| *v)
}

/// The error message for a spectrum name that is not in the tables: a spectrum file (pbrt-v4
/// reads `"spectrum eta" "spds/Au.eta.spd"` from disk) or an unknown name.
pub fn unsupported(name: &str) -> String {
    if name.ends_with(".spd") {
        format!("spectrum files are not supported (\"{name}\"); give RGB or a named spectrum")
    } else {
        format!("unsupported named spectrum \"{name}\"")
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The RGB values of pbrt-v3's `ToRGB` for Cu/Au/Ag/Al as published with pbrt-v3-era scenes
    /// and renderers (e.g. copper's `0.200438 0.924033 1.10221` / `3.91295 2.45285 2.14219`):
    /// computed from pbrt-v3's own resampled tables, so they agree to ~1e-4, not exactly.
    const PUBLISHED: [(&str, [f32; 3]); 8] = [
        ("metal-Cu-eta", [0.200438, 0.924033, 1.102212]),
        ("metal-Cu-k", [3.912949, 2.452848, 2.142188]),
        ("metal-Au-eta", [0.143119, 0.374957, 1.44248]),
        ("metal-Au-k", [3.98316, 2.38572, 1.60322]),
        ("metal-Ag-eta", [0.155265, 0.116723, 0.138342]),
        ("metal-Ag-k", [4.82835, 3.12225, 2.14696]),
        ("metal-Al-eta", [1.65746, 0.880369, 0.521229]),
        ("metal-Al-k", [9.22387, 6.26952, 4.837]),
    ];

    #[test]
    fn metals_match_published_rgb() {
        for (name, want) in PUBLISHED {
            let got = metal(name).unwrap();
            for (g, w) in got.to_array().into_iter().zip(want) {
                assert!((g - w).abs() <= 3e-4 * w, "{name}: {got} against {want:?}");
            }
        }
    }

    /// MgO's index is 1.7374 at 589 nm and 1.7408 at 546 nm (Stephens & Malitson 1952), nearly
    /// flat over the visible: without white balance the RGB is that flat value times the
    /// projection of a constant spectrum, (1.2049, 0.9482, 0.9092) (from the CIE integrals and
    /// the sRGB matrix), to within the residual dispersion (~1%).
    #[test]
    fn flat_spectra_follow_the_unbalanced_white() {
        let white = Vec3::new(1.2049, 0.9482, 0.9092);
        let got = metal("metal-MgO-eta").unwrap() / white;
        for c in got.to_array() {
            assert!((c - 1.74).abs() < 0.015, "MgO eta / white = {got}");
        }
        assert_eq!(metal("metal-MgO-k"), Some(Vec3::ZERO));
        assert!(metal("metal-TiO2-k").unwrap().max_element() < 1e-3);
    }

    /// The glasses against the Sellmeier fits of the Schott and Ohara catalogues at 550 nm:
    /// n^2 = 1 + sum B_i l^2 / (l^2 - C_i), l in micrometres.
    #[test]
    fn glasses_match_sellmeier_at_550nm() {
        let sellmeier = |b: [f64; 3], c: [f64; 3]| {
            let l2 = 0.55f64 * 0.55;
            (1.0 + (0..3).map(|i| b[i] * l2 / (l2 - c[i])).sum::<f64>()).sqrt()
        };
        let bk7 = sellmeier(
            [1.03961212, 0.231792344, 1.01046945],
            [0.00600069867, 0.0200179144, 103.560653],
        );
        let sf11 = sellmeier(
            [1.73759695, 0.313747346, 1.89878101],
            [0.013188707, 0.0623068142, 155.23629],
        );
        assert!(
            (glass("glass-BK7").unwrap() as f64 - bk7).abs() < 2e-4,
            "{bk7}"
        );
        assert!(
            (glass("glass-F11").unwrap() as f64 - sf11).abs() < 2e-4,
            "{sf11}"
        );
        assert_eq!(glass("glass-XYZ"), None);
    }
}
