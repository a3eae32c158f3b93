//! Participating media (issue 18): pbrt-v4's `homogeneous`, `uniformgrid`, `rgbgrid` and
//! `cloud` media, absorbing, scattering (Henyey-Greenstein phase function) and emitting, bound
//! to shapes and the camera by `MediumInterface`.
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
//! default 1 each, per unit of scene length), or a `preset` naming one of pbrt-v4's measured
//! media ([`presets`], per millimetre), `scale` (multiplies both), `g`, and emission `Le`
//! (rgb or blackbody, read as a light's `L` is) times `Lescale`: a medium emits
//! `sigma_a * Le` per unit length, as in pbrt-v4's `volpath`. As in pbrt-v4, a surface's
//! inside is the side its geometric normal points away from; a surface naming one medium for
//! both sides is no boundary.
//!
//! Heterogeneous media ([`Field`]): `uniformgrid` (a density grid, with `Le` times an
//! `Lescale` grid or a `temperature` grid's blackbody) and `rgbgrid` (RGB grids of
//! `sigma_a`, `sigma_s` and `Le`) in [`grid`], and the procedural `cloud` in [`cloud`]. Each
//! lives in a box placed by the CTM at `MakeNamedMedium`; rays in grids are tracked against
//! a [`grid::MajorantGrid`] of local bounds (a cloud against one bound, as in pbrt-v4):
//! spectral, ratio and emission tracking.
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
//!   ([`crate::photon::volume`]) and go on to their hit dimmed by the transmittance; a
//!   later scattering point reads the light scattered there from the same map by a point
//!   estimate and ends the path; purely diffuse surfaces read the caustic photons that
//!   reached them through the media (`L S+ D`), and the traced paths those cover are left
//!   out ([`crate::integrator::path`]). The global surface map is not built there.
//! - `--integrator direct` tracks them as the path tracer does where the scene needs it, and
//!   ends each path at its first scattering point (single scattering: light samples through
//!   the phase function, MIS against one phase-sampled ray that looks for emission only).
//! - Otherwise (and in the bidirectional integrators) the first step's rule holds: a
//!   medium absorbs only and is a region closed by the surfaces that name it,
//!   with the camera and every light outside, so a ray segment is inside a medium exactly when
//!   it ends on a boundary surface from that medium's side, and its transmittance is
//!   `exp(-sigma_a * length)` ([`crate::accel::transmittance`]); photons, camera paths, gather
//!   rays and bidirectional subpaths all take that factor at every hit. A scene outside that
//!   rule (scattering, the camera or a light in a medium, `interface` shapes, immersed
//!   surfaces) is refused by the bidirectional integrators with the line of the first reason
//!   ([`crate::scene::Scene::media_need_tracking`]).
//!
//! Emitting media are found by the path segments that cross them (the closed form of
//! `integral T sigma_a Le` in a homogeneous medium, ratio tracking in a field), not sampled as
//! lights, as in pbrt-v4; the photon mapper samples scattering in them as the path tracer
//! does (its volume map holds no light they emit). Like heterogeneous media they need
//! tracking, so the bidirectional integrators refuse them.
//!
//! `nanovdb` media are located errors.
pub mod cloud;
pub mod grid;
pub mod presets;

use crate::math::{Mat4, Vec3};
use crate::params::{Loc, ParamSet, SceneError};
use grid::{Region, Rng, SampledGrid, MAX_COLLISIONS};

/// What varies over space in a heterogeneous medium.
#[derive(Clone, Debug, PartialEq)]
pub enum Field {
    /// `uniformgrid`: a density scaling `sigma_a` and `sigma_s`; emission `Le` (the medium's
    /// [`Medium::le`]) times the `Lescale` grid, or a temperature grid's blackbody times it.
    Density {
        region: Region,
        density: SampledGrid<f32>,
        le_scale: SampledGrid<f32>,
        temperature: Option<grid::Temperature>,
    },
    /// `rgbgrid`: RGB grids of `sigma_a` and `sigma_s` (1 where absent; both times the
    /// medium's scale, held in [`Medium::sigma_a`] and [`Medium::sigma_s`]), and of `Le` times
    /// `le_scale`.
    Rgb {
        region: Region,
        sigma_a: Option<SampledGrid<Vec3>>,
        sigma_s: Option<SampledGrid<Vec3>>,
        le: Option<SampledGrid<Vec3>>,
        le_scale: f32,
    },
    /// `cloud`: a procedural density in [0, 1] scaling `sigma_a` and `sigma_s`.
    Cloud { region: Region, cloud: cloud::Cloud },
}

impl Field {
    fn region(&self) -> &Region {
        match self {
            Field::Density { region, .. }
            | Field::Rgb { region, .. }
            | Field::Cloud { region, .. } => region,
        }
    }
}

/// The coefficients at a point of a medium.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Coefficients {
    pub sigma_a: Vec3,
    pub sigma_s: Vec3,
    /// Emitted radiance per unit length, `sigma_a * Le`.
    pub emission: Vec3,
}

/// A participating medium: homogeneous, or with coefficients that vary over a [`Field`].
#[derive(Clone, Debug, PartialEq)]
pub struct Medium {
    /// The name `MakeNamedMedium` gave it.
    pub name: String,
    /// Absorption coefficient per unit length, per RGB channel (`scale` folded in); a field
    /// scales it at each point.
    pub sigma_a: Vec3,
    /// Scattering coefficient per unit length, per RGB channel (`scale` folded in).
    pub sigma_s: Vec3,
    /// Henyey-Greenstein asymmetry in (-1, 1).
    pub g: f32,
    /// Emitted radiance `Le * Lescale` (homogeneous and `uniformgrid` media); the medium
    /// emits `sigma_a * le` per unit length.
    pub le: Vec3,
    /// Where the coefficients vary; `None` for a homogeneous medium.
    pub field: Option<Field>,
    /// A bound of `sigma_t` at every point and channel (the trackers' majorant).
    majorant: f32,
    /// Local bounds over a grid's box (`None`: the one bound `majorant` everywhere).
    majorants: Option<grid::MajorantGrid>,
}

impl Medium {
    /// `MakeNamedMedium name "string type" ...` with its parameters (`loc`: the directive;
    /// `medium_from_world`: the inverse of the CTM there, which places a grid or a cloud).
    pub fn create(
        name: &str,
        params: &mut ParamSet,
        loc: &Loc,
        medium_from_world: Mat4,
        le: Option<Vec3>,
    ) -> Result<Medium, SceneError> {
        let ty = params.get_string("type", "")?;
        let at = params.loc("type").cloned().unwrap_or_else(|| loc.clone());
        let bad = |params: &ParamSet, name: &str, msg: String| {
            let at = params.loc(name).cloned().unwrap_or_else(|| loc.clone());
            Err(SceneError::at(&at, msg))
        };
        // pbrt-v4 reads sigma_a and sigma_s (default 1 each) unless a preset gave them.
        let preset = match ty.as_str() {
            "homogeneous" => match params.get_string_opt("preset")? {
                None => None,
                Some(p) => match presets::lookup(&p) {
                    Some(v) => Some(v),
                    None => {
                        return bad(
                            params,
                            "preset",
                            format!(
                                "unknown medium preset \"{p}\" (pbrt-v4's measured media: {})",
                                presets::names().collect::<Vec<_>>().join(", ")
                            ),
                        )
                    }
                },
            },
            _ => None,
        };
        // `le`: the caller read `Le` (rgb or blackbody, as a light's `L`) for the types
        // that take one value.
        let field = match ty.as_str() {
            "homogeneous" => None,
            "uniformgrid" => Some(grid::read_uniform(params, loc, medium_from_world, le)?),
            "rgbgrid" => Some(grid::read_rgb(params, loc, medium_from_world)?),
            "cloud" => {
                let cloud = cloud::Cloud {
                    density: params.get_float("density", 1.0)?,
                    wispiness: params.get_float("wispiness", 1.0)?,
                    frequency: params.get_float("frequency", 5.0)?,
                };
                for (name, v) in [
                    ("density", cloud.density),
                    ("wispiness", cloud.wispiness),
                    ("frequency", cloud.frequency),
                ] {
                    if !v.is_finite() {
                        return bad(params, name, format!("{name} must be finite, got {v}"));
                    }
                }
                let region = grid::read_region(params, loc, medium_from_world)?;
                Some(Field::Cloud { region, cloud })
            }
            "" => {
                return Err(SceneError::at(
                    loc,
                    "MakeNamedMedium needs a \"string type\"",
                ))
            }
            "nanovdb" => {
                return Err(SceneError::at(
                    &at,
                    "medium type \"nanovdb\" is not supported yet (\"homogeneous\", \
                     \"uniformgrid\", \"rgbgrid\" and \"cloud\" media are)",
                ))
            }
            other => {
                return Err(SceneError::at(
                    &at,
                    format!("unknown medium type \"{other}\""),
                ))
            }
        };
        let scale = params.get_float("scale", 1.0)?;
        let (sigma_a, sigma_s) = match (&field, preset) {
            (Some(Field::Rgb { .. }), _) => (Vec3::ONE, Vec3::ONE),
            (_, Some((s, a))) => (a, s),
            _ => (
                params.get_rgb("sigma_a", Vec3::ONE)?,
                params.get_rgb("sigma_s", Vec3::ONE)?,
            ),
        };
        let (sigma_a, sigma_s) = (sigma_a * scale, sigma_s * scale);
        let g = params.get_float("g", 0.0)?;
        let le_scale = match ty.as_str() {
            "homogeneous" => params.get_float("Lescale", 1.0)?,
            _ => 1.0,
        };
        params.check_unused()?;
        if !(scale.is_finite() && scale >= 0.0) {
            return bad(
                params,
                "scale",
                format!("scale must be finite and >= 0, got {scale}"),
            );
        }
        if !(sigma_a.is_finite() && sigma_a.min_element() >= 0.0) {
            return bad(params, "sigma_a", "sigma_a must be finite and >= 0".into());
        }
        if !(sigma_s.is_finite() && sigma_s.min_element() >= 0.0) {
            return bad(params, "sigma_s", "sigma_s must be finite and >= 0".into());
        }
        if !(g > -1.0 && g < 1.0) {
            return bad(params, "g", format!("g must lie in (-1, 1), got {g}"));
        }
        if !(le_scale.is_finite() && le_scale >= 0.0) {
            return bad(
                params,
                "Lescale",
                format!("Lescale must be finite and >= 0, got {le_scale}"),
            );
        }
        let mut medium = Medium {
            name: name.to_string(),
            sigma_a,
            sigma_s,
            g,
            le: le.unwrap_or(Vec3::ZERO) * le_scale,
            field,
            majorant: 0.0,
            majorants: None,
        };
        medium.majorant = medium.bound();
        medium.majorants = medium.majorant_grid();
        if let Some((steps, size)) = medium.steps_per_cell() {
            // The trackers step by the majorant: beyond this optical depth per cell they
            // would take more steps than a render can afford (and such a cell is opaque).
            if steps.is_nan() || steps > MAX_VOXEL_DEPTH {
                let name = if matches!(medium.field, Some(Field::Cloud { .. })) {
                    "density"
                } else {
                    "sigma_s"
                };
                return bad(
                    params,
                    name,
                    format!(
                        "the medium is {steps:e} optical depths thick across a {size} (majorant x \
                         size); at most {MAX_VOXEL_DEPTH:e} are tracked"
                    ),
                );
            }
        }
        Ok(medium)
    }

    /// A homogeneous medium that does not emit.
    pub fn homogeneous(name: &str, sigma_a: Vec3, sigma_s: Vec3, g: f32) -> Medium {
        let mut m = Medium {
            name: name.to_string(),
            sigma_a,
            sigma_s,
            g,
            le: Vec3::ZERO,
            field: None,
            majorant: 0.0,
            majorants: None,
        };
        m.majorant = m.bound();
        m
    }

    /// The local bounds of a grid medium (see [`grid::MajorantGrid::from_samples`]).
    fn majorant_grid(&self) -> Option<grid::MajorantGrid> {
        match &self.field {
            Some(Field::Density { density, .. }) => {
                let st = self.sigma_t().max_element();
                Some(grid::MajorantGrid::from_samples(density.n, |i| {
                    st * density.values[i]
                }))
            }
            Some(Field::Rgb {
                sigma_a, sigma_s, ..
            }) => {
                let n = sigma_a.as_ref().or(sigma_s.as_ref())?.n;
                let (ka, ks) = (self.sigma_a, self.sigma_s);
                let val = |g: &Option<SampledGrid<Vec3>>, i: usize| {
                    g.as_ref().map_or(Vec3::ONE, |g| g.values[i])
                };
                Some(grid::MajorantGrid::from_samples(n, |i| {
                    (val(sigma_a, i) * ka + val(sigma_s, i) * ks).max_element()
                }))
            }
            _ => None,
        }
    }

    /// The trackers' bound of `sigma_t` at world point `p`: the local bound of its cell for
    /// a grid medium, the one majorant otherwise.
    pub fn majorant_at(&self, p: Vec3) -> f32 {
        match (&self.majorants, &self.field) {
            (Some(m), Some(f)) => m.at(f.region().unit(p)),
            _ => self.majorant,
        }
    }

    /// Walks the tentative collisions of the ray `o + t d` (unit `d`) up to `dist` inside the
    /// medium's box: exponential steps by the local majorant, restarted at each cell of the
    /// majorant grid (memorylessness makes that exact). Calls `visit(t, majorant, rng)` at
    /// each; `visit` returning false stops the walk.
    fn track(
        &self,
        o: Vec3,
        d: Vec3,
        dist: f32,
        rng: &mut Rng,
        mut visit: impl FnMut(f32, f32, &mut Rng) -> bool,
    ) -> Walk {
        let (t0, t1) = self.clip(o, d);
        let end = dist.min(t1);
        let mut collisions = 0u32;
        let mut run = |a: f32, b: f32, maj: f32| -> Option<Walk> {
            if maj <= 0.0 {
                return None;
            }
            let mut t = a;
            loop {
                t -= (1.0 - rng.uniform()).ln() / maj;
                if t >= b {
                    return None;
                }
                collisions += 1;
                if collisions > MAX_COLLISIONS {
                    return Some(Walk::GaveUp);
                }
                if !visit(t, maj, rng) {
                    return Some(Walk::Stopped);
                }
            }
        };
        let r = match (&self.majorants, &self.field) {
            (Some(m), Some(f)) => m.segments(f.region(), o, d, (t0, end), run),
            _ if end > t0 => run(t0, end, self.majorant),
            _ => None,
        };
        r.unwrap_or(Walk::Ended)
    }

    /// The largest `sigma_t` anywhere (any channel).
    fn bound(&self) -> f32 {
        let st = self.sigma_t();
        let max = |g: &SampledGrid<f32>| g.values.iter().cloned().fold(0.0, f32::max);
        let max3 = |g: &Option<SampledGrid<Vec3>>| {
            g.as_ref().map_or(1.0, |g| {
                g.values.iter().fold(0.0f32, |m, v| m.max(v.max_element()))
            })
        };
        match &self.field {
            None | Some(Field::Cloud { .. }) => st.max_element(),
            Some(Field::Density { density, .. }) => st.max_element() * max(density),
            Some(Field::Rgb {
                sigma_a, sigma_s, ..
            }) => self.sigma_a.x * max3(sigma_a) + self.sigma_s.x * max3(sigma_s),
        }
    }

    /// For a field: the majorant times the size of a voxel (a grid) or of the box (a cloud),
    /// the tracker's expected steps across it, and what was measured.
    fn steps_per_cell(&self) -> Option<(f32, &'static str)> {
        let region = self.field.as_ref()?.region();
        let size = (region.p1 - region.p0).min_element();
        Some(match &self.field {
            Some(Field::Density { density, .. }) => (
                self.majorant * size / density.n.iter().max().copied().unwrap_or(1) as f32,
                "voxel",
            ),
            Some(Field::Rgb {
                sigma_a, sigma_s, ..
            }) => {
                let n = sigma_a
                    .as_ref()
                    .or(sigma_s.as_ref())
                    .map_or(1, |g| g.n.iter().max().copied().unwrap_or(1));
                (self.majorant * size / n as f32, "voxel")
            }
            _ => (self.majorant * size, "box"),
        })
    }

    /// A scalar bound of `sigma_t` at every point and channel (the trackers' majorant).
    pub fn majorant(&self) -> f32 {
        self.majorant
    }

    /// Whether the coefficients are the same everywhere.
    #[inline]
    pub fn is_homogeneous(&self) -> bool {
        self.field.is_none()
    }

    /// Whether the medium emits light anywhere.
    pub fn emits(&self) -> bool {
        match &self.field {
            None => self.le.max_element() > 0.0 && self.sigma_a.max_element() > 0.0,
            Some(Field::Density { temperature, .. }) => {
                temperature.is_some() || self.le.max_element() > 0.0
            }
            Some(Field::Rgb { le, le_scale, .. }) => le.is_some() && *le_scale > 0.0,
            Some(Field::Cloud { .. }) => false,
        }
    }

    /// The coefficients at world point `p` (for a field, meaningful inside its box only:
    /// [`Medium::clip`]).
    pub fn at(&self, p: Vec3) -> Coefficients {
        match &self.field {
            None => Coefficients {
                sigma_a: self.sigma_a,
                sigma_s: self.sigma_s,
                emission: self.sigma_a * self.le,
            },
            Some(Field::Density {
                region,
                density,
                le_scale,
                temperature,
            }) => {
                let u = region.unit(p);
                let d = density.lookup(u);
                let sigma_a = self.sigma_a * d;
                let le = match temperature {
                    Some(t) => t.radiance(u),
                    None => self.le,
                };
                let emission = if le == Vec3::ZERO {
                    Vec3::ZERO
                } else {
                    sigma_a * le * le_scale.lookup(u)
                };
                Coefficients {
                    sigma_a,
                    sigma_s: self.sigma_s * d,
                    emission,
                }
            }
            Some(Field::Rgb {
                region,
                sigma_a,
                sigma_s,
                le,
                le_scale,
            }) => {
                let u = region.unit(p);
                let a = sigma_a.as_ref().map_or(Vec3::ONE, |g| g.lookup(u)) * self.sigma_a;
                let s = sigma_s.as_ref().map_or(Vec3::ONE, |g| g.lookup(u)) * self.sigma_s;
                // pbrt-v4 takes these RGBs as illuminant spectra that no light normalises.
                let k = *le_scale * crate::spectrum::blackbody::CIE_Y_INTEGRAL as f32;
                let e = le.as_ref().map_or(Vec3::ZERO, |g| a * g.lookup(u) * k);
                Coefficients {
                    sigma_a: a,
                    sigma_s: s,
                    emission: e,
                }
            }
            Some(Field::Cloud { region, cloud }) => {
                let d = cloud.density(region.local(p));
                Coefficients {
                    sigma_a: self.sigma_a * d,
                    sigma_s: self.sigma_s * d,
                    emission: Vec3::ZERO,
                }
            }
        }
    }

    /// The part `[t0, t1]` of the ray `o + t d` (`t >= 0`) where the medium may have
    /// extinction: all of it for a homogeneous medium, a field's box otherwise.
    pub fn clip(&self, o: Vec3, d: Vec3) -> (f32, f32) {
        match &self.field {
            None => (0.0, f32::INFINITY),
            Some(f) => f.region().clip(o, d),
        }
    }

    /// The fraction of light that crosses `dist` units from `o` along unit `d`: Beer's law in
    /// a homogeneous medium, ratio tracking (reading `rng`) in a field.
    pub fn transmittance_along(&self, o: Vec3, d: Vec3, dist: f32, rng: &mut Rng) -> Vec3 {
        if self.field.is_none() {
            return self.transmittance(dist);
        }
        let mut tr = Vec3::ONE;
        let walk = self.track(o, d, dist, rng, |t, maj, _| {
            let c = self.at(o + d * t);
            tr *= Vec3::ONE - (c.sigma_a + c.sigma_s) / maj;
            tr.max_element() > 0.0
        });
        match walk {
            Walk::Ended => tr,
            Walk::Stopped | Walk::GaveUp => Vec3::ZERO,
        }
    }

    /// The light the medium emits towards `o` from the `dist` units along unit `d` (may be
    /// infinite), dimmed by the transmittance on the way: `integral T(t) sigma_a Le dt`. In
    /// closed form for a homogeneous medium; in a field, ratio tracking's tentative
    /// collisions each add `T_ratio sigma_a Le / majorant` (unbiased, reading `rng`).
    pub fn emitted_along(&self, o: Vec3, d: Vec3, dist: f32, rng: &mut Rng) -> Vec3 {
        if self.field.is_none() {
            let (st, e) = (self.sigma_t(), self.sigma_a * self.le);
            // A channel with emission has sigma_a > 0, hence sigma_t > 0.
            return Vec3::select(
                st.cmpgt(Vec3::ZERO),
                e * (Vec3::ONE - beer(st, dist)) / st,
                Vec3::ZERO,
            );
        }
        let (mut tr, mut sum) = (Vec3::ONE, Vec3::ZERO);
        self.track(o, d, dist, rng, |t, maj, _| {
            let c = self.at(o + d * t);
            sum += tr * c.emission / maj;
            tr *= Vec3::ONE - (c.sigma_a + c.sigma_s) / maj;
            tr.max_element() > 0.0
        });
        sum
    }

    /// Samples where a ray from `o` along unit `d` first interacts within `dist` (may be
    /// infinite): [`Medium::sample_distance`] in a homogeneous medium (`u_channel`, `u`), spectral
    /// tracking in a field (a stream keyed by the two numbers). `history` is the throughput
    /// of the path so far (any scale): as in Kutz et al.'s history-aware spectral tracking a
    /// tentative collision scatters with probability `max(sigma_s h) / (max(sigma_s h) +
    /// max(sigma_n h))`, `h` the throughput there, so that the colours the path still
    /// carries decide and the per-channel weights stay bounded in chromatic media (with
    /// probabilities from the mean `sigma_s` alone, a red-scattering cloud's red weights
    /// grew 1.7x per scattering and its image converged from below, 0.94 at 64 spp).
    pub fn sample_interaction(
        &self,
        o: Vec3,
        d: Vec3,
        dist: f32,
        u_channel: f32,
        u: f32,
        history: Vec3,
    ) -> MediumEvent {
        if self.field.is_none() {
            return self.sample_distance(dist, u_channel, u);
        }
        let mut rng = Rng::new(crate::sampling::hash(&[
            u_channel.to_bits() as u64,
            u.to_bits() as u64,
        ]));
        // Outside the field's box every collision would be a null one of weight 1.
        let mut w = Vec3::ONE;
        let mut scatter = None;
        let walk = self.track(o, d, dist, &mut rng, |t, maj, rng| {
            let c = self.at(o + d * t);
            let sigma_n = (Vec3::splat(maj) - c.sigma_a - c.sigma_s).max(Vec3::ZERO);
            let h = history * w;
            let (s, n) = ((c.sigma_s * h).max_element(), (sigma_n * h).max_element());
            if (s + n).is_nan() || s + n <= 0.0 {
                w = Vec3::ZERO;
                return false;
            }
            let ps = s / (s + n);
            if ps > 0.0 && rng.uniform() < ps {
                w *= c.sigma_s / (maj * ps);
                scatter = Some(t);
                return false;
            }
            w *= sigma_n / (maj * (1.0 - ps));
            true
        });
        match (walk, scatter) {
            (_, Some(t)) => MediumEvent::Scatter { t, weight: w },
            (Walk::Ended, None) => MediumEvent::Pass { weight: w },
            _ => MediumEvent::Pass { weight: Vec3::ZERO },
        }
    }

    /// The transmittance from `o` along unit `d` as a function of the distance, up to
    /// `t_max`, for the beam estimates: Beer's law, or in a field the optical depth marched
    /// (midpoint rule; half a voxel at a time in a grid, 1/256 of the box in a cloud) and
    /// interpolated.
    pub fn transmittance_table(&self, o: Vec3, d: Vec3, t_max: f32) -> TransmittanceTable {
        let Some(field) = &self.field else {
            return TransmittanceTable::Beer(self.sigma_t());
        };
        let region = field.region();
        let step = match field {
            Field::Density { density, .. } => region.step(d, density.n, 0.5),
            Field::Rgb {
                sigma_a, sigma_s, ..
            } => region.step(
                d,
                sigma_a
                    .as_ref()
                    .or(sigma_s.as_ref())
                    .map_or([1, 1, 1], |g| g.n),
                0.5,
            ),
            Field::Cloud { .. } => region.step(d, [256, 256, 256], 1.0),
        };
        let (t0, t1) = region.clip(o, d);
        let end = t_max.min(t1).max(0.0);
        if !end.is_finite() || end <= t0 {
            return TransmittanceTable::Beer(Vec3::ZERO); // the segment misses the box
        }
        // Marched from the origin (no extinction before t0), in at most 4096 steps.
        let steps = ((end / step).ceil() as usize).clamp(1, 4096);
        let h = end / steps as f32;
        let mut depth = Vec::with_capacity(steps + 1);
        let mut acc = Vec3::ZERO;
        depth.push(acc);
        for k in 0..steps {
            let t = (k as f32 + 0.5) * h;
            if t >= t0 {
                let c = self.at(o + d * t);
                acc += (c.sigma_a + c.sigma_s) * h;
            }
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

/// How [`Medium::track`]'s walk ended.
enum Walk {
    /// It passed the segment's end.
    Ended,
    /// The visitor stopped it.
    Stopped,
    /// It took [`MAX_COLLISIONS`] collisions.
    GaveUp,
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
        let ty = params
            .peek("type")
            .and_then(|p| p.strings())
            .and_then(|v| v.first().cloned());
        let le = match ty.as_deref() {
            Some("homogeneous" | "uniformgrid") => params.get_rgb_opt("Le").unwrap(),
            _ => None,
        };
        Medium::create("m", &mut params, &loc, Mat4::IDENTITY, le)
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
            le: Vec3::ZERO,
            field: None,
            majorant: 1.5,
            majorants: None,
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

    /// A 24^3 density grid of thin air (0.05) holding a dense puff (density 40 in a 3^3
    /// block) and a ramp, in a rotated and scaled box.
    fn puff() -> Medium {
        let n = 24;
        let mut values = vec![0.05f32; n * n * n];
        for z in 0..n {
            for y in 0..n {
                for x in 0..n {
                    let v = &mut values[(z * n + y) * n + x];
                    if (17..20).contains(&x) && (3..6).contains(&y) && (10..13).contains(&z) {
                        *v = 40.0;
                    } else if x < 4 {
                        *v = 0.05 + 0.5 * z as f32 / n as f32;
                    }
                }
            }
        }
        density_grid(
            (Vec3::new(0.3, 0.1, 0.2), Vec3::new(0.7, 0.9, 0.4)),
            Region {
                p0: Vec3::new(-1.0, -1.0, -1.0),
                p1: Vec3::new(1.0, 2.0, 1.5),
                medium_from_world: (Mat4::from_rotation_y(0.6)
                    * Mat4::from_scale(Vec3::new(0.5, 1.0, 1.0)))
                .inverse(),
            },
            SampledGrid {
                n: [n, n, n],
                values,
            },
        )
    }

    /// A `uniformgrid` medium with its bounds computed as `create` computes them.
    fn density_grid(
        (sigma_a, sigma_s): (Vec3, Vec3),
        region: Region,
        density: SampledGrid<f32>,
    ) -> Medium {
        let mut m = Medium {
            name: "grid".into(),
            sigma_a,
            sigma_s,
            g: 0.0,
            le: Vec3::ZERO,
            field: Some(Field::Density {
                region,
                density,
                le_scale: SampledGrid::constant(1.0),
                temperature: None,
            }),
            majorant: 0.0,
            majorants: None,
        };
        m.majorant = m.bound();
        m.majorants = m.majorant_grid();
        m
    }

    fn random_unit(i: u64) -> Vec3 {
        let mut r = Rng::new(crate::sampling::hash(&[i]));
        Vec3::new(r.uniform(), r.uniform(), r.uniform())
    }

    #[test]
    fn local_majorants_bound_the_medium_and_are_tight_in_thin_air() {
        let m = puff();
        let Some(Field::Density { region, .. }) = &m.field else {
            unreachable!()
        };
        let world_from_medium = region.medium_from_world.inverse();
        let (mut thin, mut total) = (0, 0);
        for i in 0..200_000u64 {
            // Points over the box and a little beyond, faces included.
            let u = random_unit(i) * 1.1 - Vec3::splat(0.05);
            let p = world_from_medium.transform_point3(region.p0 + u * (region.p1 - region.p0));
            let st = {
                let c = m.at(p);
                (c.sigma_a + c.sigma_s).max_element()
            };
            let bound = m.majorant_at(p);
            let inside = u.min_element() >= 0.0 && u.max_element() <= 1.0;
            if inside {
                assert!(st <= bound * (1.0 + 1e-5) + 1e-7, "{u}: {st} > {bound}");
                total += 1;
                if bound <= 0.05 * 1.0 + 1e-6 {
                    thin += 1;
                }
            }
        }
        // Most of the box is thin air whose bound is the air's, not the puff's 40.
        assert_eq!(m.majorant(), 40.0);
        assert!(
            thin * 2 > total,
            "{thin} of {total} points see the thin bound"
        );
    }

    #[test]
    fn majorant_cells_tile_each_ray_in_order() {
        let m = puff();
        let (Some(g), Some(f)) = (&m.majorants, &m.field) else {
            unreachable!()
        };
        for i in 0..2000u64 {
            let o = random_unit(i) * 6.0 - Vec3::splat(3.0);
            let d = (random_unit(i + 99_999) - Vec3::splat(0.5)).normalize();
            let (t0, t1) = f.region().clip(o, d);
            let mut at = t0;
            g.segments(f.region(), o, d, (t0, t1), |a, b, maj| {
                assert!((a - at).abs() <= 1e-4 * (1.0 + at.abs()), "gap {at} .. {a}");
                assert!(b > a);
                let mid = m.majorant_at(o + d * (0.5 * (a + b)));
                assert_eq!(maj, mid, "cell bound at the segment's middle");
                at = b;
                None::<()>
            });
            if t1 > t0 {
                assert!(
                    (at - t1).abs() <= 1e-4 * (1.0 + t1.abs()),
                    "{at} short of {t1}"
                );
            }
        }
    }

    #[test]
    fn trackers_stay_unbiased_across_majorant_cells() {
        // Rays through the ramp, the puff and the thin air: ratio tracking's and spectral
        // tracking's pass weights average to exp(-optical depth) marched finely.
        let m = puff();
        let Some(Field::Density { region, .. }) = &m.field else {
            unreachable!()
        };
        let world_from_medium = region.medium_from_world.inverse();
        let at_unit =
            |u: Vec3| world_from_medium.transform_point3(region.p0 + u * (region.p1 - region.p0));
        for (a, b) in [
            (Vec3::new(-0.1, 0.18, 0.45), Vec3::new(1.1, 0.18, 0.47)),
            (Vec3::new(0.1, -0.1, 0.2), Vec3::new(0.12, 1.1, 0.9)),
            (Vec3::new(0.5, 0.5, -0.1), Vec3::new(0.6, 0.5, 1.1)),
        ] {
            let (o, e) = (at_unit(a), at_unit(b));
            let (d, dist) = ((e - o).normalize(), (e - o).length());
            let steps = 200_000;
            let h = dist / steps as f32;
            let tau = (0..steps).fold(Vec3::ZERO, |acc, k| {
                let c = m.at(o + d * ((k as f32 + 0.5) * h));
                acc + (c.sigma_a + c.sigma_s) * h
            });
            let want = (-tau).exp();
            let n = 100_000;
            let (mut tr, mut pass, mut scat) = (Vec3::ZERO, Vec3::ZERO, 0u32);
            for i in 0..n {
                let key = crate::sampling::hash(&[i as u64, 7]);
                tr += m.transmittance_along(o, d, dist, &mut Rng::new(key));
                let (uc, u) = (
                    crate::sampling::to_unit(key),
                    crate::sampling::to_unit(key >> 11),
                );
                match m.sample_interaction(o, d, dist, uc, u, Vec3::ONE) {
                    MediumEvent::Pass { weight } => pass += weight,
                    MediumEvent::Scatter { .. } => scat += 1,
                }
            }
            let (tr, pass) = (tr / n as f32, pass / n as f32);
            assert!(scat > 0);
            for c in 0..3 {
                let tol = 4.0 * (want[c] * (1.0 - want[c]) / n as f32).sqrt() + 2e-3;
                assert!((tr[c] - want[c]).abs() < tol, "ratio {c}: {tr} vs {want}");
                assert!(
                    (pass[c] - want[c]).abs() < tol * 2.0,
                    "spectral {c}: {pass} vs {want}"
                );
            }
        }
    }

    #[test]
    fn grid_trackers_average_to_the_transport_terms() {
        // A grid of density 2 everywhere the rays go (the box reaches far past them), with the
        // coefficients halved: the homogeneous medium of the test above, tracked.
        let m = density_grid(
            (Vec3::new(0.25, 0.0, 0.1), Vec3::new(0.5, 0.15, 0.0)),
            Region {
                p0: Vec3::splat(-100.0),
                p1: Vec3::splat(100.0),
                medium_from_world: Mat4::IDENTITY,
            },
            SampledGrid {
                n: [2, 2, 2],
                values: vec![2.0; 8],
            },
        );
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
            match m.sample_interaction(o, dir, d, uc, u, Vec3::ONE) {
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
        match &ok.field {
            Some(Field::Density { density, .. }) => assert_eq!(density.n, [2, 1, 1]),
            other => panic!("{other:?}"),
        }
        assert_eq!(ok.majorant(), 2.0);
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
            (r#""string type" "nanovdb""#, "not supported yet"),
            (r#""string type" "fog""#, "unknown medium type"),
            (r#""rgb sigma_s" [0 0 0]"#, "needs a \"string type\""),
            (
                r#""string type" "homogeneous" "string preset" "Wine""#,
                "unknown medium preset \"Wine\"",
            ),
            (
                r#""string type" "homogeneous" "string preset" "Merlot" "rgb sigma_a" [1 1 1]"#,
                "unused parameter",
            ),
            (
                r#""string type" "rgbgrid" "integer nx" 2 "rgb Le" [1 1 1 1 1 1] "rgb sigma_s" [1 1 1 1 1 1]"#,
                "needs \"rgb sigma_a\"",
            ),
            (
                r#""string type" "rgbgrid" "integer nx" 2 "rgb sigma_a" [1 1 1]"#,
                "wants 2",
            ),
            (
                r#""string type" "uniformgrid" "float density" [1] "rgb Le" [1 1 1] "float temperature" [2000]"#,
                "both \"Le\" and \"temperature\"",
            ),
            (
                r#""string type" "cloud" "float wispiness" -1 "rgb Le" [1 1 1]"#,
                "unused parameter",
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
    fn presets_scale_and_emission_read_as_pbrt_v4_reads_them() {
        let m = create(r#""string type" "homogeneous" "string preset" "Ketchup" "float scale" 10"#)
            .unwrap();
        assert!((m.sigma_s - Vec3::new(1.8, 0.7, 0.3)).abs().max_element() < 1e-5);
        assert!((m.sigma_a - Vec3::new(0.61, 9.7, 14.5)).abs().max_element() < 1e-4);
        assert!(!m.emits());
        // Le times Lescale; emitted per unit length as sigma_a * Le.
        let m = create(
            r#""string type" "homogeneous" "rgb sigma_a" [1 0 2] "rgb sigma_s" [0 0 0] "rgb Le" [1 2 3] "float Lescale" 0.5"#,
        )
        .unwrap();
        assert!(m.emits() && m.le == Vec3::new(0.5, 1.0, 1.5));
        assert_eq!(m.at(Vec3::ZERO).emission, Vec3::new(0.5, 0.0, 3.0));
        // The closed form against a midpoint sum of T(t) sigma_a Le over 1.3 units.
        let got = m.emitted_along(Vec3::ZERO, Vec3::X, 1.3, &mut Rng::new(1));
        let n = 100_000;
        let mut want = Vec3::ZERO;
        for i in 0..n {
            let t = (i as f32 + 0.5) / n as f32 * 1.3;
            want += m.transmittance(t) * m.at(Vec3::ZERO).emission * (1.3 / n as f32);
        }
        assert!((got - want).abs().max_element() < 1e-4, "{got} vs {want}");
        // An rgbgrid's coefficients are its grids times scale; its Le times Lescale.
        let m = create(
            r#""string type" "rgbgrid" "integer nx" 2 "rgb sigma_a" [1 0 0  3 0 0] "rgb Le" [0 0 0  2 2 2] "float Lescale" 0.5 "float scale" 2"#,
        )
        .unwrap();
        let c = m.at(Vec3::new(0.5, 0.5, 0.5));
        assert!((c.sigma_a - Vec3::new(4.0, 0.0, 0.0)).abs().max_element() < 1e-5);
        assert_eq!(c.sigma_s, Vec3::splat(2.0)); // absent: 1 times scale
                                                 // 4 x 1 x 0.5, times pbrt-v4's unnormalised illuminant.
        let k = crate::spectrum::blackbody::CIE_Y_INTEGRAL as f32;
        assert!(
            (c.emission - Vec3::new(2.0 * k, 0.0, 0.0))
                .abs()
                .max_element()
                < 1e-3
        );
        assert_eq!(m.majorant(), 2.0 * 3.0 + 2.0 * 1.0);
    }

    #[test]
    fn field_emission_by_ratio_tracking_averages_to_the_integral() {
        // A uniformgrid of density 1 + x over x in [0, 2] (two samples at 0.5 and 1.5, linear
        // between, and exactly what a 1-D midpoint sum below reads).
        let m = create(
            r#""string type" "uniformgrid" "integer nx" 2 "float density" [1.5 2.5] "point3 p1" [2 1 1] "rgb sigma_a" [0.5 1 0] "rgb sigma_s" [0.5 0 0] "rgb Le" [2 1 4]"#,
        )
        .unwrap();
        let (o, d, dist) = (Vec3::new(0.5, 0.5, 0.5), Vec3::X, 1.0);
        let n = 200_000u64;
        let mut got = Vec3::ZERO;
        for i in 0..n {
            got += m.emitted_along(o, d, dist, &mut Rng::new(crate::sampling::hash(&[i])));
        }
        got /= n as f32;
        let steps = 10_000;
        let (mut want, mut tau) = (Vec3::ZERO, Vec3::ZERO);
        for k in 0..steps {
            let h = dist / steps as f32;
            let c = m.at(o + d * ((k as f32 + 0.5) * h));
            want += (-(tau + (c.sigma_a + c.sigma_s) * h * 0.5)).exp() * c.emission * h;
            tau += (c.sigma_a + c.sigma_s) * h;
        }
        assert!(
            (got - want).abs().max_element() < 4e-3 * want.max_element(),
            "{got} vs {want}"
        );
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
