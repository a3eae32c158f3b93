//! Participating media (issue 18): pbrt-v4's `homogeneous` and `uniformgrid` media, absorbing
//! and scattering (Henyey-Greenstein phase function), bound to shapes and the camera by
//! `MediumInterface`.
//!
//! ```text
//! MakeNamedMedium "fog" "string type" "homogeneous" "float g" 0.3
//!     "rgb sigma_a" [ 0.01 0.01 0.01 ] "rgb sigma_s" [ 0.5 0.5 0.5 ] "float scale" 1
//! AttributeBegin
//!   MediumInterface "fog" ""     # inside, outside ("" = vacuum); one name: both sides
//!   Material "interface"         # a boundary without a surface
//!   Shape "sphere" "float radius" 2
//! AttributeEnd
//! ```
//!
//! Parameters follow pbrt-v4's `HomogeneousMedium::Create`: `sigma_a` and `sigma_s` (rgb,
//! default 1 each, per unit of scene length), `scale` (multiplies both), `g`, `Le` and
//! `Lescale`. As in pbrt-v4, a surface's inside is the side its geometric normal points away
//! from; a surface naming one medium for both sides is no boundary.
//!
//! **Two ways the integrators see media.**
//! - `--integrator path` tracks them as pbrt-v4's `volpath` does: every ray carries the medium
//!   it travels in (the camera's from a `MediumInterface` before `Camera`), a surface with a
//!   `MediumInterface` hands a ray leaving it the medium of the side it leaves to, any other
//!   surface keeps the ray's medium, and `interface` surfaces are crossed without a bounce.
//!   In a scattering medium each segment samples its first interaction
//!   ([`Medium::sample_distance`]: a channel picked at random, the density averaged over the
//!   three channels); at a scattering point the path takes a light sample through the phase
//!   function (MIS against phase sampling) and continues in a phase-sampled direction. Shadow
//!   rays pass `interface` surfaces and take each medium's transmittance on the way.
//! - `--integrator photonmap` renders such scenes as the path tracer does, except that camera
//!   segments (and those after delta bounces) in a scattering medium read all the light it
//!   scatters towards them from the volume photon map by a beam estimate
//!   ([`crate::photon::volume`]) and go on to their hit dimmed by the transmittance; the
//!   surface photon maps are not built there.
//! - The other integrators (direct, the bidirectional ones), and the photon mapper in scenes
//!   within it, keep the first step's rule: a medium absorbs only and is a region closed by the surfaces that name it,
//!   with the camera and every light outside, so a ray segment is inside a medium exactly when
//!   it ends on a boundary surface from that medium's side, and its transmittance is
//!   `exp(-sigma_a * length)` ([`crate::accel::transmittance`]); photons, camera paths, gather
//!   rays and bidirectional subpaths all take that factor at every hit. A scene outside that
//!   rule (scattering, the camera or a light in a medium, `interface` shapes, immersed
//!   surfaces) is refused by them with the line of the first reason
//!   ([`crate::scene::Scene::media_need_tracking`]).
//!
//! `uniformgrid` media ([`grid`]) scale the coefficients by a density grid; rays in them are
//! tracked against a majorant (spectral tracking for interactions, ratio tracking for
//! transmittance), so only the path tracer and the photon mapper render them.
//!
//! Emitting media, `rgbgrid`, `cloud` and `nanovdb` media and `preset`s are located errors.
pub mod grid;

use crate::math::{Mat4, Vec3};
use crate::params::{Loc, ParamSet, SceneError};
use grid::{DensityGrid, Rng, MAX_COLLISIONS};

/// A homogeneous medium, or one whose coefficients a density grid scales.
#[derive(Clone, Debug, PartialEq)]
pub struct Medium {
    /// The name `MakeNamedMedium` gave it.
    pub name: String,
    /// Absorption coefficient per unit length, per RGB channel (`scale` folded in).
    pub sigma_a: Vec3,
    /// Scattering coefficient per unit length, per RGB channel (`scale` folded in).
    pub sigma_s: Vec3,
    /// Henyey-Greenstein asymmetry in (-1, 1).
    pub g: f32,
    /// `uniformgrid`: the density that scales `sigma_a` and `sigma_s` at each point.
    pub density: Option<DensityGrid>,
}

impl Medium {
    /// `MakeNamedMedium name "string type" ...` with its parameters (`loc`: the directive;
    /// `medium_from_world`: the inverse of the CTM there, which places a grid).
    pub fn create(
        name: &str,
        params: &mut ParamSet,
        loc: &Loc,
        medium_from_world: Mat4,
    ) -> Result<Medium, SceneError> {
        let ty = params.get_string("type", "")?;
        let at = params.loc("type").cloned().unwrap_or_else(|| loc.clone());
        let mut density = None;
        match ty.as_str() {
            "homogeneous" => {}
            "uniformgrid" => density = Some(read_grid(params, loc, medium_from_world)?),
            "" => {
                return Err(SceneError::at(
                    loc,
                    "MakeNamedMedium needs a \"string type\"",
                ))
            }
            "rgbgrid" | "cloud" | "nanovdb" => {
                return Err(SceneError::at(
                    &at,
                    format!(
                        "medium type \"{ty}\" is not supported yet (\"homogeneous\" and \
                         \"uniformgrid\" media are)"
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
        if le != Vec3::ZERO {
            return bad(
                "Le",
                "emitting media are not supported yet (Le must be 0)".into(),
            );
        }
        if let Some(grid) = &density {
            // The trackers step by the majorant: beyond this optical depth per voxel they would
            // take more steps than a render can afford (and such a voxel is opaque anyway).
            let voxel = ((grid.p1 - grid.p0)
                / Vec3::new(grid.n[0] as f32, grid.n[1] as f32, grid.n[2] as f32))
            .min_element();
            let depth = (sigma_a + sigma_s).max_element() * grid.max * voxel;
            if depth.is_nan() || depth > MAX_VOXEL_DEPTH {
                return bad(
                    "density",
                    format!(
                        "the densest voxel is {depth:e} optical depths thick (sigma_t x density x \
                         voxel size); at most {MAX_VOXEL_DEPTH:e} are tracked"
                    ),
                );
            }
        }
        Ok(Medium {
            name: name.to_string(),
            sigma_a,
            sigma_s,
            g,
            density,
        })
    }

    /// A scalar bound of `sigma_t` at every point and channel (the trackers' majorant).
    pub fn majorant(&self) -> f32 {
        let d = self.density.as_ref().map_or(1.0, |g| g.max);
        self.sigma_t().max_element() * d
    }

    /// The fraction of light that crosses `dist` units from `o` along unit `d`: Beer's law in
    /// a homogeneous medium, ratio tracking (reading `rng`) in a grid.
    pub fn transmittance_along(&self, o: Vec3, d: Vec3, dist: f32, rng: &mut Rng) -> Vec3 {
        let Some(grid) = &self.density else {
            return self.transmittance(dist);
        };
        let maj = self.majorant();
        if maj <= 0.0 {
            return Vec3::ONE;
        }
        let st = self.sigma_t();
        // Nothing to cross outside the grid's box.
        let (t0, t1) = grid.clip(o, d);
        let end = dist.min(t1);
        let (mut t, mut tr) = (t0, Vec3::ONE);
        for _ in 0..MAX_COLLISIONS {
            t -= (1.0 - rng.uniform()).ln() / maj;
            if t >= end {
                return tr;
            }
            tr *= Vec3::ONE - st * (grid.density(o + d * t) / maj);
            if tr.max_element() <= 0.0 {
                return Vec3::ZERO;
            }
        }
        Vec3::ZERO
    }

    /// Samples where a ray from `o` along unit `d` first interacts within `dist` (may be
    /// infinite): [`Medium::sample_distance`] in a homogeneous medium (`u_channel`, `u`), spectral
    /// tracking in a grid (a stream keyed by the two numbers).
    pub fn sample_interaction(
        &self,
        o: Vec3,
        d: Vec3,
        dist: f32,
        u_channel: f32,
        u: f32,
    ) -> MediumEvent {
        let Some(grid) = &self.density else {
            return self.sample_distance(dist, u_channel, u);
        };
        let maj = self.majorant();
        if maj <= 0.0 {
            return MediumEvent::Pass { weight: Vec3::ONE };
        }
        let mut rng = Rng::new(crate::sampling::hash(&[
            u_channel.to_bits() as u64,
            u.to_bits() as u64,
        ]));
        let (st, ss) = (self.sigma_t(), self.sigma_s);
        // Outside the grid's box every collision would be a null one of weight 1.
        let (t0, t1) = grid.clip(o, d);
        let end = dist.min(t1);
        let (mut t, mut w) = (t0, Vec3::ONE);
        for _ in 0..MAX_COLLISIONS {
            t -= (1.0 - rng.uniform()).ln() / maj;
            if t >= end {
                return MediumEvent::Pass { weight: w };
            }
            let rho = grid.density(o + d * t);
            let ps = (ss * rho).element_sum() / 3.0 / maj;
            if ps > 0.0 && rng.uniform() < ps {
                w *= ss * rho / (maj * ps);
                return MediumEvent::Scatter { t, weight: w };
            }
            w *= (Vec3::splat(maj) - st * rho) / (maj * (1.0 - ps));
            if w.max_element() <= 0.0 {
                return MediumEvent::Pass { weight: Vec3::ZERO };
            }
        }
        MediumEvent::Pass { weight: Vec3::ZERO }
    }

    /// The transmittance from `o` along unit `d` as a function of the distance, up to
    /// `t_max`, for the beam estimates: Beer's law, or in a grid the optical depth marched
    /// half a voxel at a time (midpoint rule) and interpolated.
    pub fn transmittance_table(&self, o: Vec3, d: Vec3, t_max: f32) -> TransmittanceTable {
        let st = self.sigma_t();
        let Some(grid) = &self.density else {
            return TransmittanceTable::Beer(st);
        };
        let step = grid.half_voxel_step(d);
        // Marched to the end of the grid's box (no density beyond), in at most 4096 steps.
        let end = t_max.min(grid.clip(o, d).1).max(0.0);
        if !end.is_finite() || end <= 0.0 {
            return TransmittanceTable::Beer(Vec3::ZERO); // the segment misses the grid
        }
        let steps = ((end / step).ceil() as usize).clamp(1, 4096);
        let h = end / steps as f32;
        let mut depth = Vec::with_capacity(steps + 1);
        let mut acc = Vec3::ZERO;
        depth.push(acc);
        for k in 0..steps {
            acc += st * grid.density(o + d * ((k as f32 + 0.5) * h)) * h;
            depth.push(acc);
        }
        TransmittanceTable::Marched { h, depth }
    }

    /// Extinction `sigma_a + sigma_s` per unit length.
    #[inline]
    pub fn sigma_t(&self) -> Vec3 {
        self.sigma_a + self.sigma_s
    }

    /// Whether light scatters in this medium (else it only absorbs).
    #[inline]
    pub fn scatters(&self) -> bool {
        self.sigma_s.max_element() > 0.0
    }

    /// The fraction of light that crosses `dist` units of this medium.
    #[inline]
    pub fn transmittance(&self, dist: f32) -> Vec3 {
        beer(self.sigma_t(), dist)
    }

    /// Samples where a ray travelling `dist` units through this medium first interacts
    /// (`dist` may be infinite). One RGB channel is picked with `u_channel` and a free-flight
    /// distance drawn from its extinction with `u`; the density used for the weight is the
    /// mean over the three channels' densities (one-sample MIS with the balance heuristic, so a
    /// chromatic medium gets no channel whose weight explodes). A channel without extinction
    /// never scatters.
    pub fn sample_distance(&self, dist: f32, u_channel: f32, u: f32) -> MediumEvent {
        let st = self.sigma_t();
        let c = ((u_channel * 3.0) as usize).min(2);
        let t = if st[c] > 0.0 {
            -(1.0 - u).ln() / st[c]
        } else {
            f32::INFINITY
        };
        if t < dist {
            let tr = (-st * t).exp();
            let pdf = (st * tr).element_sum() / 3.0;
            MediumEvent::Scatter {
                t,
                weight: self.sigma_s * tr / pdf,
            }
        } else {
            let tr = beer(st, dist);
            let p = tr.element_sum() / 3.0;
            MediumEvent::Pass {
                weight: if p > 0.0 { tr / p } else { Vec3::ZERO },
            }
        }
    }
}

/// [`Medium::transmittance_table`]'s answer.
pub enum TransmittanceTable {
    /// Homogeneous: `sigma_t`.
    Beer(Vec3),
    /// Optical depth at multiples of `h` from the origin.
    Marched { h: f32, depth: Vec<Vec3> },
}

impl TransmittanceTable {
    /// The transmittance from the origin to distance `t`.
    pub fn at(&self, t: f32) -> Vec3 {
        match self {
            TransmittanceTable::Beer(st) => beer(*st, t),
            TransmittanceTable::Marched { h, depth } => {
                let x = (t / h).max(0.0);
                let i = (x as usize).min(depth.len() - 1);
                let j = (i + 1).min(depth.len() - 1);
                let f = (x - i as f32).clamp(0.0, 1.0);
                let tau = depth[i] + (depth[j] - depth[i]) * f;
                (-tau).exp()
            }
        }
    }
}

/// A `uniformgrid`'s `density`, `nx`/`ny`/`nz` and `p0`/`p1`.
fn read_grid(
    params: &mut ParamSet,
    loc: &Loc,
    medium_from_world: Mat4,
) -> Result<DensityGrid, SceneError> {
    let at =
        |params: &ParamSet, name: &str| params.loc(name).cloned().unwrap_or_else(|| loc.clone());
    let mut n = [0usize; 3];
    for (k, name) in ["nx", "ny", "nz"].iter().enumerate() {
        let v = params.get_int(name, 1)?;
        if v < 1 {
            return Err(SceneError::at(
                &at(params, name),
                format!("{name} must be >= 1, got {v}"),
            ));
        }
        n[k] = v as usize;
    }
    let p0 = params.get_point3("p0", Vec3::ZERO)?;
    let p1 = params.get_point3("p1", Vec3::ONE)?;
    if (p1 - p0).min_element() <= 0.0 {
        return Err(SceneError::at(
            &at(params, "p1"),
            "p1 must exceed p0 on every axis",
        ));
    }
    let Some(values) = params.get_floats("density")? else {
        return Err(SceneError::at(
            loc,
            "a \"uniformgrid\" medium needs \"float density\"",
        ));
    };
    let want = n[0].checked_mul(n[1]).and_then(|v| v.checked_mul(n[2]));
    if want != Some(values.len()) {
        return Err(SceneError::at(
            &at(params, "density"),
            format!(
                "\"density\" has {} values, nx * ny * nz = {} x {} x {} wants {}",
                values.len(),
                n[0],
                n[1],
                n[2],
                want.map_or("more than fit".to_string(), |w| w.to_string())
            ),
        ));
    }
    if values.iter().any(|v| !v.is_finite() || *v < 0.0) {
        return Err(SceneError::at(
            &at(params, "density"),
            "densities must be finite and >= 0",
        ));
    }
    for name in ["temperature", "Lescale"] {
        if params.loc(name).is_some() && name == "temperature" {
            return Err(SceneError::at(
                &at(params, name),
                "emitting grid media (temperature) are not supported yet",
            ));
        }
    }
    if !medium_from_world.is_finite() {
        return Err(SceneError::at(
            loc,
            "the transform at MakeNamedMedium is singular",
        ));
    }
    let max = values.iter().cloned().fold(0.0, f32::max);
    Ok(DensityGrid {
        n,
        values,
        p0,
        p1,
        medium_from_world,
        max,
    })
}

/// The optical depth across one voxel of a grid medium's densest voxel that the trackers
/// accept (their steps average `1 / majorant`).
pub const MAX_VOXEL_DEPTH: f32 = 1e4;

/// `exp(-sigma_t dist)` per channel, 1 where `sigma_t` is 0 (also for an infinite `dist`).
#[inline]
fn beer(sigma_t: Vec3, dist: f32) -> Vec3 {
    Vec3::select(
        sigma_t.cmpgt(Vec3::ZERO),
        (-sigma_t * dist).exp(),
        Vec3::ONE,
    )
}

/// The outcome of [`Medium::sample_distance`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum MediumEvent {
    /// The ray scatters `t` units along it; `weight` is `sigma_s T(t) / pdf(t)`.
    Scatter { t: f32, weight: Vec3 },
    /// The ray reaches its end; `weight` is `T(dist) / P(no interaction)`.
    Pass { weight: Vec3 },
}

/// The Henyey-Greenstein phase function (pbrt-v4's convention): the density of scattering
/// into `wi` for light travelling along `-wo`, as a function of `cos = wo . wi`; `g > 0`
/// scatters forward (towards `wi = -wo`). Integrates to 1 over the sphere.
#[inline]
pub fn henyey_greenstein(cos: f32, g: f32) -> f32 {
    let denom = 1.0 + g * g + 2.0 * g * cos;
    (1.0 - g * g) / (4.0 * std::f32::consts::PI * denom * denom.max(0.0).sqrt())
}

/// Samples `wi` in proportion to [`henyey_greenstein`] for unit `wo`; returns `(wi, pdf)`.
pub fn sample_henyey_greenstein(wo: Vec3, g: f32, u: crate::math::Vec2) -> (Vec3, f32) {
    let cos = if g.abs() < 1e-3 {
        1.0 - 2.0 * u.x
    } else {
        let s = (1.0 - g * g) / (1.0 + g - 2.0 * g * u.x);
        -(1.0 + g * g - s * s) / (2.0 * g)
    }
    .clamp(-1.0, 1.0);
    let sin = (1.0 - cos * cos).max(0.0).sqrt();
    let phi = 2.0 * std::f32::consts::PI * u.y;
    let frame = crate::math::Frame::from_normal(wo);
    let wi = frame.to_world(Vec3::new(sin * phi.cos(), sin * phi.sin(), cos));
    (wi, henyey_greenstein(cos, g))
}

/// The media on the two sides of a surface (indices into `Scene::media`, `None` = vacuum);
/// stored on a mesh only where they differ (a medium boundary).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
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

    /// The medium a ray along `d` leaving this surface (geometric normal `ng`) travels into:
    /// the inside one when it goes against the normal.
    #[inline]
    pub fn leaving(&self, d: Vec3, ng: Vec3) -> Option<u32> {
        if d.dot(ng) < 0.0 {
            self.inside
        } else {
            self.outside
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
        Medium::create("m", &mut params, &loc, Mat4::IDENTITY)
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

    /// Standard Henyey-Greenstein in the angle between the light's directions of travel
    /// before (`-wi`) and after (`wo`) scattering, written apart from the renderer's.
    fn hg_textbook(cos_travel: f64, g: f64) -> f64 {
        (1.0 - g * g)
            / (4.0 * std::f64::consts::PI * (1.0 + g * g - 2.0 * g * cos_travel).powf(1.5))
    }

    #[test]
    fn henyey_greenstein_is_normalised_and_matches_the_textbook_form() {
        for g in [-0.9f32, -0.3, 0.0, 0.5, 0.95] {
            // Integral over the sphere: 2 pi times the integral over cos in [-1, 1].
            let n = 200_000;
            let sum: f64 = (0..n)
                .map(|i| {
                    let c = -1.0 + 2.0 * (i as f64 + 0.5) / n as f64;
                    henyey_greenstein(c as f32, g) as f64
                })
                .sum();
            let integral = 2.0 * std::f64::consts::PI * sum * 2.0 / n as f64;
            assert!((integral - 1.0).abs() < 1e-3, "g {g}: {integral}");
            for c in [-0.9f32, 0.0, 0.7] {
                let want = hg_textbook(-c as f64, g as f64);
                let got = henyey_greenstein(c, g) as f64;
                assert!(
                    (got / want - 1.0).abs() < 1e-4,
                    "g {g} cos {c}: {got} vs {want}"
                );
            }
        }
    }

    #[test]
    fn henyey_greenstein_sampling_passes_chi_square() {
        // 20 bins in cos(wo, wi) x 8 in azimuth, 200k samples; expected counts from the
        // textbook density integrated over each bin. 159 degrees of freedom: the 99.9th
        // percentile of chi-square is about 219.
        let wo = Vec3::new(0.3, -0.5, 0.8).normalize();
        let frame = crate::math::Frame::from_normal(wo);
        let (nc, np, n) = (20usize, 8usize, 200_000u32);
        for g in [-0.6f32, 0.0, 0.4, 0.85] {
            let mut counts = vec![0f64; nc * np];
            for i in 0..n {
                let h = crate::sampling::hash(&[i as u64, g.to_bits() as u64]);
                let u = crate::math::Vec2::new(
                    crate::sampling::to_unit(h),
                    crate::sampling::to_unit(crate::sampling::mix64(h)),
                );
                let (wi, pdf) = sample_henyey_greenstein(wo, g, u);
                assert!((wi.length() - 1.0).abs() < 1e-4);
                let want = henyey_greenstein(wo.dot(wi), g);
                assert!((pdf - want).abs() <= 1e-4 * want, "{pdf} vs {want}");
                let l = frame.to_local(wi);
                let ci = (((l.z + 1.0) / 2.0 * nc as f32) as usize).min(nc - 1);
                let phi = l.y.atan2(l.x).rem_euclid(2.0 * std::f32::consts::PI);
                let pi = ((phi / (2.0 * std::f32::consts::PI) * np as f32) as usize).min(np - 1);
                counts[ci * np + pi] += 1.0;
            }
            let mut chi2 = 0.0;
            for ci in 0..nc {
                // Midpoint rule over 1000 sub-steps of the bin.
                let (a, b) = (
                    -1.0 + 2.0 * ci as f64 / nc as f64,
                    -1.0 + 2.0 * (ci + 1) as f64 / nc as f64,
                );
                let steps = 1000;
                let p: f64 = (0..steps)
                    .map(|k| {
                        hg_textbook(-(a + (b - a) * (k as f64 + 0.5) / steps as f64), g as f64)
                    })
                    .sum::<f64>()
                    * (b - a)
                    / steps as f64
                    * 2.0
                    * std::f64::consts::PI
                    / np as f64;
                for pi in 0..np {
                    let e = p * n as f64;
                    let o = counts[ci * np + pi];
                    chi2 += (o - e) * (o - e) / e;
                }
            }
            assert!(chi2 < 219.0, "g {g}: chi-square {chi2}");
        }
    }

    #[test]
    fn distance_sampling_weights_average_to_the_transport_terms() {
        // Over u, E[weight * [scatter before d]] = integral_0^d sigma_s T(t) dt per channel,
        // and E[weight * [pass]] = T(d).
        let m = Medium {
            name: "m".into(),
            sigma_a: Vec3::new(0.5, 0.0, 0.2),
            sigma_s: Vec3::new(1.0, 0.3, 0.0),
            g: 0.0,
            density: None,
        };
        let d = 1.7;
        let st = m.sigma_t();
        let (mut scat, mut pass) = (Vec3::ZERO, Vec3::ZERO);
        let n = 300;
        for i in 0..n {
            for j in 0..n {
                let uc = (i as f32 + 0.5) / n as f32;
                let u = (j as f32 + 0.5) / n as f32;
                match m.sample_distance(d, uc, u) {
                    MediumEvent::Scatter { weight, t } => {
                        assert!(t < d);
                        scat += weight
                    }
                    MediumEvent::Pass { weight } => pass += weight,
                }
            }
        }
        let nn = (n * n) as f32;
        let want_scat = m.sigma_s * (Vec3::ONE - (-st * d).exp()) / st;
        let want_pass = (-st * d).exp();
        for c in 0..3 {
            assert!(
                (scat[c] / nn - want_scat[c]).abs() < 3e-3,
                "{c}: {} vs {}",
                scat / nn,
                want_scat
            );
            assert!(
                (pass[c] / nn - want_pass[c]).abs() < 3e-3,
                "{c}: {} vs {}",
                pass / nn,
                want_pass
            );
        }
        // An infinite segment never passes where every channel has extinction.
        assert_eq!(m.transmittance(f32::INFINITY), Vec3::ZERO);
        let clear = Medium {
            sigma_a: Vec3::new(0.0, 1.0, 1.0),
            sigma_s: Vec3::ZERO,
            ..m
        };
        assert_eq!(clear.transmittance(f32::INFINITY), Vec3::new(1.0, 0.0, 0.0));
    }

    #[test]
    fn grid_trackers_average_to_the_transport_terms() {
        // A grid of density 2 everywhere the rays go (the box reaches far past them), with the
        // coefficients halved: the homogeneous medium of the test above, tracked.
        let m = Medium {
            name: "m".into(),
            sigma_a: Vec3::new(0.25, 0.0, 0.1),
            sigma_s: Vec3::new(0.5, 0.15, 0.0),
            g: 0.0,
            density: Some(DensityGrid {
                n: [2, 2, 2],
                values: vec![2.0; 8],
                p0: Vec3::splat(-100.0),
                p1: Vec3::splat(100.0),
                medium_from_world: Mat4::IDENTITY,
                max: 2.0,
            }),
        };
        let (o, dir, d) = (Vec3::new(1.0, 2.0, 3.0), Vec3::new(0.6, 0.0, 0.8), 1.7);
        let st = (m.sigma_a + m.sigma_s) * 2.0;
        let (mut scat, mut pass, mut tr) = (Vec3::ZERO, Vec3::ZERO, Vec3::ZERO);
        let n = 200_000;
        for i in 0..n {
            let h = crate::sampling::hash(&[i as u64]);
            let (uc, u) = (
                crate::sampling::to_unit(h),
                crate::sampling::to_unit(crate::sampling::mix64(h)),
            );
            match m.sample_interaction(o, dir, d, uc, u) {
                MediumEvent::Scatter { weight, t } => {
                    assert!(t < d);
                    scat += weight
                }
                MediumEvent::Pass { weight } => pass += weight,
            }
            tr += m.transmittance_along(o, dir, d, &mut Rng::new(h ^ 0x55));
        }
        let nn = n as f32;
        let want_scat = m.sigma_s * 2.0 * (Vec3::ONE - (-st * d).exp()) / st;
        let want_pass = (-st * d).exp();
        for c in 0..3 {
            assert!(
                (scat[c] / nn - want_scat[c]).abs() < 5e-3,
                "{c}: {} vs {want_scat}",
                scat / nn
            );
            assert!(
                (pass[c] / nn - want_pass[c]).abs() < 5e-3,
                "{c}: {} vs {want_pass}",
                pass / nn
            );
            assert!(
                (tr[c] / nn - want_pass[c]).abs() < 5e-3,
                "{c}: {} vs {want_pass}",
                tr / nn
            );
        }
        // The beams' marched table is exact for a constant density.
        let table = m.transmittance_table(o, dir, d);
        assert!((table.at(1.0) - (-st).exp()).abs().max_element() < 1e-4);
    }

    #[test]
    fn uniformgrid_parameters_are_checked_where_they_are_written() {
        let ok = create(r#""string type" "uniformgrid" "integer nx" 2 "float density" [ 0 1 ]"#)
            .unwrap();
        assert_eq!(
            ok.density.as_ref().map(|g| (g.n, g.max)),
            Some(([2, 1, 1], 1.0))
        );
        for (text, want) in [
            (r#""string type" "uniformgrid""#, "needs \"float density\""),
            (
                r#""string type" "uniformgrid" "integer nx" 3 "float density" [ 0 1 ]"#,
                "wants 3",
            ),
            (
                r#""string type" "uniformgrid" "float density" [ -1 ]"#,
                ">= 0",
            ),
            (
                r#""string type" "uniformgrid" "integer ny" 0 "float density" [ 1 ]"#,
                "ny must be >= 1",
            ),
            (
                r#""string type" "uniformgrid" "float density" [ 1 ] "point3 p1" [ 1 0 1 ]"#,
                "p1 must exceed p0",
            ),
            (
                r#""string type" "uniformgrid" "float density" [ 1e38 1 ] "integer nx" 2"#,
                "optical depths thick",
            ),
        ] {
            let e = create(text).unwrap_err().to_string();
            assert!(e.contains(want) && e.contains("m.pbrt:1:"), "{text}: {e}");
        }
    }

    #[test]
    fn what_is_not_supported_is_a_located_error() {
        // pbrt-v4's default sigma_s is 1: a medium naming only sigma_a scatters.
        let m = create(r#""string type" "homogeneous" "rgb sigma_a" [1 1 1]"#).unwrap();
        assert!(m.scatters() && m.sigma_s == Vec3::ONE);
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
