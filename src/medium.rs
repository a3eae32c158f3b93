//! Participating media, first step (issue 18): pbrt-v4's `homogeneous` medium when it only
//! absorbs (Beer's law: coloured glass, tea, wine), bound to shapes by `MediumInterface`.
//!
//! ```text
//! MakeNamedMedium "tea" "string type" "homogeneous"
//!     "rgb sigma_a" [ 0.15 0.32 0.74 ] "rgb sigma_s" [ 0 0 0 ] "float scale" 1
//! AttributeBegin
//!   MediumInterface "tea" ""     # inside, outside ("" = vacuum); one name: both sides
//!   Material "dielectric" "float eta" 1.33
//!   Shape "plymesh" "string filename" "tea.ply"
//! AttributeEnd
//! ```
//!
//! Parameters follow pbrt-v4's `HomogeneousMedium::Create`: `sigma_a` and `sigma_s` (rgb,
//! default 1 each, per unit of scene length), `scale` (multiplies both), `g`, `Le` and
//! `Lescale`. As in pbrt-v4, a surface's inside is the side its geometric normal points away
//! from.
//!
//! **What is supported, and why it is exact there.** A medium here absorbs and nothing else
//! (`sigma_s = 0`, no `Le`): a scattering or emitting medium is a located error, as are other
//! medium types, `preset`s, a camera or a light inside a medium, a surface with one medium on
//! both sides and the `interface` material. Within those limits every medium is a region
//! closed by the surfaces that name it, and the camera, every light and therefore every
//! unoccluded shadow ray lie outside all of them (a shadow ray cannot leave a closed region:
//! its boundary is a surface). So a ray segment is inside a medium exactly when it ends on a
//! boundary surface from that medium's side, and its transmittance is
//! `exp(-sigma_a * length)` ([`crate::scene::Scene::transmittance`]): no integrator keeps a
//! medium stack, and photons, camera paths, gather rays and bidirectional subpaths all take
//! the same factor at every hit. A segment that ends on a surface naming no media (a closed
//! object immersed in the tea without its own `MediumInterface`) is taken as vacuum: pbrt-v4
//! would attenuate it. The photon mapper's volume map and scattering media are still to come.
use crate::math::Vec3;
use crate::params::{Loc, ParamSet, SceneError};

/// A homogeneous, purely absorbing medium.
#[derive(Clone, Debug, PartialEq)]
pub struct Medium {
    /// The name `MakeNamedMedium` gave it.
    pub name: String,
    /// Absorption coefficient per unit length, per RGB channel (`scale` folded in).
    pub sigma_a: Vec3,
}

impl Medium {
    /// `MakeNamedMedium name "string type" ...` with its parameters (`loc`: the directive).
    pub fn create(name: &str, params: &mut ParamSet, loc: &Loc) -> Result<Medium, SceneError> {
        let ty = params.get_string("type", "")?;
        let at = params.loc("type").cloned().unwrap_or_else(|| loc.clone());
        match ty.as_str() {
            "homogeneous" => {}
            "" => {
                return Err(SceneError::at(
                    loc,
                    "MakeNamedMedium needs a \"string type\"",
                ))
            }
            "uniformgrid" | "rgbgrid" | "cloud" | "nanovdb" => {
                return Err(SceneError::at(
                    &at,
                    format!(
                        "medium type \"{ty}\" is not supported yet (only absorbing \
                         \"homogeneous\" media are)"
                    ),
                ))
            }
            other => {
                return Err(SceneError::at(
                    &at,
                    format!("unknown medium type \"{other}\""),
                ))
            }
        }
        if let Some(p) = params.loc("preset").cloned() {
            params.get_string_opt("preset")?;
            return Err(SceneError::at(
                &p,
                "medium presets are not supported yet (give sigma_a and sigma_s)",
            ));
        }
        let scale = params.get_float("scale", 1.0)?;
        let sigma_a = params.get_rgb("sigma_a", Vec3::ONE)? * scale;
        let sigma_s = params.get_rgb("sigma_s", Vec3::ONE)? * scale;
        let g = params.get_float("g", 0.0)?;
        let le = params.get_rgb("Le", Vec3::ZERO)? * params.get_float("Lescale", 1.0)?;
        params.check_unused()?;
        let bad = |name: &str, msg: String| {
            let at = params.loc(name).cloned().unwrap_or_else(|| loc.clone());
            Err(SceneError::at(&at, msg))
        };
        if !(sigma_a.is_finite() && sigma_a.min_element() >= 0.0) {
            return bad("sigma_a", "sigma_a must be finite and >= 0".into());
        }
        if !(sigma_s.is_finite() && sigma_s.min_element() >= 0.0) {
            return bad("sigma_s", "sigma_s must be finite and >= 0".into());
        }
        if !(g > -1.0 && g < 1.0) {
            return bad("g", format!("g must lie in (-1, 1), got {g}"));
        }
        if sigma_s != Vec3::ZERO {
            return bad(
                "sigma_s",
                format!(
                    "medium \"{name}\" scatters (sigma_s {} {} {}, pbrt-v4's default is 1): \
                     scattering media are not supported yet, only absorbing ones (sigma_s 0)",
                    sigma_s.x, sigma_s.y, sigma_s.z
                ),
            );
        }
        if le != Vec3::ZERO {
            return bad(
                "Le",
                "emitting media are not supported yet (Le must be 0)".into(),
            );
        }
        Ok(Medium {
            name: name.to_string(),
            sigma_a,
        })
    }

    /// The fraction of light that crosses `dist` units of this medium.
    #[inline]
    pub fn transmittance(&self, dist: f32) -> Vec3 {
        (-self.sigma_a * dist).exp()
    }
}

/// The media on the two sides of a surface (indices into `Scene::media`, `None` = vacuum);
/// stored on a mesh only where they differ (a medium boundary).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct MediumInterface {
    /// The side the geometric normal points away from.
    pub inside: Option<u32>,
    /// The side the geometric normal points to.
    pub outside: Option<u32>,
}

impl MediumInterface {
    /// The medium a ray along `d` travelled through to reach this surface with geometric
    /// normal `ng`: the outside one when it arrives against the normal.
    #[inline]
    pub fn arriving(&self, d: Vec3, ng: Vec3) -> Option<u32> {
        if d.dot(ng) < 0.0 {
            self.outside
        } else {
            self.inside
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::loader::parser::read_params;
    use crate::scene::loader::tokenizer::Tokenizer;
    use std::sync::Arc;

    fn create(text: &str) -> Result<Medium, SceneError> {
        let mut tok = Tokenizer::new(text, Arc::new("m.pbrt".into()));
        let mut params = read_params(&mut tok).unwrap();
        let loc = Loc {
            file: Arc::new("m.pbrt".into()),
            line: 1,
            col: 1,
        };
        Medium::create("m", &mut params, &loc)
    }

    #[test]
    fn absorbing_media_follow_beers_law() {
        let m = create(r#""string type" "homogeneous" "rgb sigma_a" [1 2 0] "rgb sigma_s" [0 0 0] "float scale" 0.5"#)
            .unwrap();
        assert_eq!(m.sigma_a, Vec3::new(0.5, 1.0, 0.0));
        let t = m.transmittance(2.0);
        assert!((t.x - (-1.0f32).exp()).abs() < 1e-6, "{t}");
        assert!((t.y - (-2.0f32).exp()).abs() < 1e-6, "{t}");
        assert_eq!(t.z, 1.0);
    }

    #[test]
    fn what_is_not_supported_is_a_located_error() {
        // pbrt-v4's default sigma_s is 1: a medium naming only sigma_a scatters.
        let e = create(r#""string type" "homogeneous" "rgb sigma_a" [1 1 1]"#).unwrap_err();
        assert!(e.to_string().contains("scatter"), "{e}");
        let e = create(r#""string type" "homogeneous" "rgb sigma_s" [0 0.5 0]"#).unwrap_err();
        assert!(e.to_string().contains("m.pbrt:1:"), "{e}");
        for (text, want) in [
            (r#""string type" "cloud""#, "not supported yet"),
            (r#""string type" "fog""#, "unknown medium type"),
            (r#""rgb sigma_s" [0 0 0]"#, "needs a \"string type\""),
            (
                r#""string type" "homogeneous" "string preset" "Wine""#,
                "presets",
            ),
            (
                r#""string type" "homogeneous" "rgb sigma_s" [0 0 0] "rgb Le" [1 1 1]"#,
                "emitting",
            ),
            (
                r#""string type" "homogeneous" "rgb sigma_s" [0 0 0] "float density" 1"#,
                "unused",
            ),
            (
                r#""string type" "homogeneous" "rgb sigma_s" [0 0 0] "rgb sigma_a" [-1 0 0]"#,
                ">= 0",
            ),
        ] {
            let e = create(text).unwrap_err().to_string();
            assert!(e.contains(want), "{text}: {e}");
        }
    }

    #[test]
    fn a_ray_arriving_against_the_normal_comes_from_outside() {
        let mi = MediumInterface {
            inside: Some(3),
            outside: None,
        };
        assert_eq!(mi.arriving(Vec3::NEG_Z, Vec3::Z), None);
        assert_eq!(mi.arriving(Vec3::Z, Vec3::Z), Some(3));
    }
}
