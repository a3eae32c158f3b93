//! Lights: sampling for shadow rays (next-event estimation), emitted radiance of area lights
//! hit by rays, and power (for choosing a light in proportion to it).
//!
//! ```text
//! AttributeBegin
//!   AreaLightSource "diffuse" "rgb L" [ 17 12 4 ] "bool twosided" false
//!   Shape "trianglemesh" ...
//! AttributeEnd
//! LightSource "point" "rgb I" [ 10 10 10 ] "point3 from" [ 0 2 0 ]
//! LightSource "spot" "rgb I" [ 10 10 10 ] "point3 from" [ 0 2 0 ] "point3 to" [ 0 0 0 ]
//!     "float coneangle" [ 30 ] "float conedeltaangle" [ 5 ]
//! LightSource "distant" "rgb L" [ 3 3 3 ] "point3 from" [ 0 1 0 ] "point3 to" [ 0 0 0 ]
//! LightSource "infinite" "string filename" "sky.exr"
//! ```
//! One file per variant; [`Lights`] dispatches over the closed set.
//!
//! Photons and the bidirectional integrators' light subpaths pick a light in proportion to its
//! power through an alias table (pbrt-v4's `PowerLightSampler`); next-event estimation (in
//! every integrator) picks by what each light can send to the receiving point ([`select`],
//! pbrt-v4's light bounds); rays that leave the scene see the infinite lights
//! ([`Lights::escaped`]).
mod area;
mod distant;
mod infinite;
mod point;
mod select;
mod spot;

pub use area::AreaLight;
pub use distant::DistantLight;
pub use infinite::{EnvMap, Portal};
pub use point::PointLight;
pub use select::{Pick, Receiver, EXHAUSTIVE_MAX};
pub use spot::SpotLight;

use crate::math::{luminance, Frame, Vec2, Vec3};
use crate::mesh::Mesh;
use crate::sampling::alias::AliasTable;
use crate::sampling::warp::square_to_disk_concentric;
use crate::sampling::ONE_MINUS_EPSILON;
use std::f32::consts::PI;
use std::sync::Arc;

/// The closed set of lights. Radiometric values are linear RGB, already multiplied by `scale`.
#[derive(Clone, Debug, PartialEq)]
pub enum Light {
    /// `AreaLightSource "diffuse"` on mesh `mesh`: radiance `l` leaving the side of the
    /// geometric normal (both sides when `two_sided`).
    Area { mesh: u32, l: Vec3, two_sided: bool },
    /// `LightSource "point"`.
    Point(PointLight),
    /// `LightSource "spot"`.
    Spot(SpotLight),
    /// `LightSource "distant"`.
    Distant(DistantLight),
    /// `LightSource "infinite"`: radiance arriving from every direction at infinity, constant
    /// or from an equal-area image, oriented by the CTM (see [`EnvMap`]).
    Infinite { map: Arc<EnvMap> },
}

impl Light {
    /// A light with no surface in the scene (point, spot, distant, infinite): what final-gather
    /// hits take direct light from by shadow rays (`integrator::photonmap`).
    pub fn is_surfaceless(&self) -> bool {
        !matches!(self, Light::Area { .. })
    }
}

/// A light sample seen from a receiving point.
#[derive(Clone, Copy, Debug)]
pub struct LightSample {
    /// Radiance (area, distant) or intensity / distance^2 (point, spot) arriving along `wi`.
    pub li: Vec3,
    /// Unit direction from the receiver towards the light.
    pub wi: Vec3,
    /// Point on the light (for distant lights: a point far outside the scene along `wi`).
    pub p: Vec3,
    /// Geometric normal at `p` (area lights; zero otherwise).
    pub n: Vec3,
    /// Rounding-error bound of `p` (for spawning rays from it; zero off surfaces).
    pub err: Vec3,
    /// Density of choosing this sample: solid-angle density times the light's selection
    /// probability; for delta lights just the selection probability.
    pub pdf: f32,
    pub delta: bool,
}

/// One of the scene's lights, ready to sample (an area light with its triangle distribution).
#[derive(Clone, Debug)]
enum Emitter {
    Area(AreaLight),
    Point(PointLight),
    Spot(SpotLight),
    Distant(DistantLight),
    Infinite(Arc<EnvMap>),
}

/// The scene's lights, ready to sample; light `i` is the scene's light `i`.
#[derive(Clone, Debug)]
pub struct Lights {
    emitters: Vec<Emitter>,
    /// The infinite lights: (index in the scene's lights, map).
    envs: Vec<(usize, Arc<EnvMap>)>,
    /// Each light's bounds when it has a position (area, point, spot): see [`select`].
    bounds: Vec<Option<select::Bounds>>,
    /// How shadow rays pick lights ([`select`]): every light (whose power table is also the
    /// photons' and the bidirectional integrators' choice), and every light but the uniform
    /// skies (for receivers that leave those to the BSDF, [`Receiver::sky_by_bsdf`]).
    nee: select::Selection,
    nee_bsdf_sky: select::Selection,
    /// The lights without a surface (point, spot, distant, infinite) alone, by power: what
    /// final-gather hits take direct light from by shadow rays ([`Self::sample_surfaceless`]).
    surfaceless: AliasTable,
    /// Centre and radius of the scene's bounding sphere (distant lights start outside it).
    center: Vec3,
    radius: f32,
}

impl Lights {
    /// Lights `lights` of a scene with meshes `meshes` and bounds `(lo, hi)` (empty when
    /// `lo > hi`); see [`crate::scene::Scene::emitters`].
    pub fn new(lights: &[Light], meshes: &[Mesh], (lo, hi): (Vec3, Vec3)) -> Lights {
        let (center, radius) = if lo.x <= hi.x {
            ((lo + hi) * 0.5, ((hi - lo) * 0.5).length().max(1e-6))
        } else {
            (Vec3::ZERO, 1.0)
        };
        let emitters: Vec<Emitter> = lights
            .iter()
            .map(|l| match l {
                Light::Area { mesh, l, two_sided } => Emitter::Area(AreaLight::new(
                    &meshes[*mesh as usize],
                    *mesh,
                    *l,
                    *two_sided,
                )),
                Light::Point(p) => Emitter::Point(*p),
                Light::Spot(s) => Emitter::Spot(*s),
                Light::Distant(d) => Emitter::Distant(*d),
                Light::Infinite { map } => Emitter::Infinite(map.clone()),
            })
            .collect();
        let envs = lights
            .iter()
            .enumerate()
            .filter_map(|(i, l)| match l {
                Light::Infinite { map } => Some((i, map.clone())),
                _ => None,
            })
            .collect();
        let bounds: Vec<Option<select::Bounds>> =
            emitters.iter().map(|e| e.bounds(meshes)).collect();
        let mut out = Lights {
            emitters,
            envs,
            bounds,
            nee: select::Selection::default(),
            nee_bsdf_sky: select::Selection::default(),
            surfaceless: AliasTable::default(),
            center,
            radius,
        };
        let powers = out.powers();
        let surfaceless: Vec<f32> = powers
            .iter()
            .zip(lights)
            .map(|(&w, l)| if l.is_surfaceless() { w } else { 0.0 })
            .collect();
        out.nee = select::Selection::new(&powers, &out.bounds);
        let non_uniform: Vec<f32> = (0..powers.len())
            .map(|i| match &out.emitters[i] {
                Emitter::Infinite(map) if map.is_uniform() => 0.0,
                _ => powers[i],
            })
            .collect();
        out.nee_bsdf_sky = select::Selection::new(&non_uniform, &out.bounds);
        if surfaceless.iter().any(|&w| w > 0.0) {
            out.surfaceless = AliasTable::new(&surfaceless);
        }
        out
    }

    /// Whether the scene has an emitting light without a surface (point, spot, distant,
    /// infinite).
    pub fn has_surfaceless(&self) -> bool {
        !self.surfaceless.is_empty()
    }

    /// [`Self::sample`] restricted to the lights without a surface, picked by power among them
    /// (the sample's `pdf` includes that selection probability); `None` when there are none.
    pub fn sample_surfaceless(
        &self,
        meshes: &[Mesh],
        p: Vec3,
        u_sel: f32,
        u: Vec2,
    ) -> Option<LightSample> {
        let (i, pmf) = self.surfaceless.sample(u_sel)?;
        self.sample_light(meshes, i, pmf, p, u)
    }

    /// Emitted power (luminance of the RGB power, watts-like units).
    pub fn power(&self, i: usize) -> f32 {
        match &self.emitters[i] {
            Emitter::Area(a) => a.power(),
            Emitter::Point(p) => p.power(),
            Emitter::Spot(s) => s.power(),
            Emitter::Distant(d) => d.power(self.radius),
            Emitter::Infinite(map) => map.power(self.radius),
        }
    }

    /// Probability that `sample` picks light `i`.
    pub fn selection_pmf(&self, i: usize) -> f32 {
        self.nee.by_power().pmf(i)
    }

    pub fn is_empty(&self) -> bool {
        self.nee.by_power().is_empty()
    }

    /// Whether the scene has infinite lights (rays that leave it carry radiance).
    pub fn has_infinite(&self) -> bool {
        !self.envs.is_empty()
    }

    /// Radiance arriving along a ray from `o` that leaves the scene in unit direction `d`: the
    /// sum over the infinite lights of `Le(-d)` (zero from a portal light unless the ray
    /// leaves through its portal), each times `weight(pdf)` where `pdf` is the density with
    /// which a shadow ray from `o` would have taken that direction from that light, its
    /// selection counted as `pick` says, for MIS; `weight` returns 1 where there is no MIS.
    /// `weight(i, pdf)` also gets the light's index `i`.
    pub fn escaped(
        &self,
        o: Vec3,
        d: Vec3,
        pick: Pick,
        weight: impl Fn(usize, f32) -> f32,
    ) -> Vec3 {
        self.envs.iter().fold(Vec3::ZERO, |acc, (i, map)| {
            if !map.admits(o, d) {
                return acc;
            }
            let le = map.le(d);
            if le.max_element() <= 0.0 {
                return acc;
            }
            let pmf = match pick {
                Pick::At(r) => self.pmf_at(r, *i),
                Pick::Power => self.selection_pmf(*i),
            };
            acc + le * weight(*i, pmf * map.pdf(d))
        })
    }

    /// Picks a light by its importance at `r` (`u_sel`, [`Self::pick_at`]) and a point on it
    /// (`u`) as seen from `r.p`, for next-event estimation: a sphere light by the cone it
    /// subtends ([`AreaLight::sample_visible`]; [`Self::pdf_area`] is its density).
    pub fn sample(&self, meshes: &[Mesh], r: Receiver, u_sel: f32, u: Vec2) -> Option<LightSample> {
        let (i, pmf) = self.pick_at(r, u_sel)?;
        self.sample_by(meshes, (i, pmf), r.p, u, true)
    }

    /// The selection that receiver `r` picks by.
    fn selection(&self, r: Receiver) -> &select::Selection {
        if r.bsdf_sky {
            &self.nee_bsdf_sky
        } else {
            &self.nee
        }
    }

    /// Picks a light for a shadow ray from `r` (`u` in `[0, 1)`): the lights without a
    /// position by power within their share of the power, the rest by importance at `r`
    /// (see [`select`]); by power alone when there are more than [`EXHAUSTIVE_MAX`] positioned
    /// lights; never a uniform sky when `r` leaves those to the BSDF
    /// ([`Receiver::sky_by_bsdf`]). `None` when no light can reach `r`.
    pub fn pick_at(&self, r: Receiver, u: f32) -> Option<(usize, f32)> {
        self.selection(r).pick(&self.bounds, r, u)
    }

    /// The probability that [`Self::pick_at`] picks light `i` for `r`.
    pub fn pmf_at(&self, r: Receiver, i: usize) -> f32 {
        self.selection(r).pmf(&self.bounds, r, i)
    }

    /// Picks a light in proportion to power: its index and probability.
    pub fn pick(&self, u_sel: f32) -> Option<(usize, f32)> {
        self.nee.by_power().sample(u_sel)
    }

    /// Whether light `i` is an area light, point or spot light (a position a bidirectional
    /// path can start from); distant and infinite lights are not.
    pub fn is_finite(&self, i: usize) -> bool {
        !matches!(self.emitters[i], Emitter::Distant(_) | Emitter::Infinite(_))
    }

    /// Whether light `i` sits at one point (point and spot lights).
    pub fn is_delta_position(&self, i: usize) -> bool {
        matches!(self.emitters[i], Emitter::Point(_) | Emitter::Spot(_))
    }

    /// The densities with which [`Self::emit`] produces a photon of finite light `i` leaving
    /// a point with geometric normal `n` (zero for point-like lights) along unit `dir`: (the
    /// origin's area density, 1 for a point-like light; the direction's solid-angle density,
    /// 1 for a distant light). pbrt-v4's `PDF_Le`; distant and infinite lights start on the
    /// disc of [`Self::disc_origin`], their density at `p`'s projection ([`Self::disc_pdf`]).
    pub fn emit_pdfs(
        &self,
        i: usize,
        p: Vec3,
        n: Vec3,
        dir: Vec3,
        aim: Option<&Aim>,
    ) -> (f32, f32) {
        match &self.emitters[i] {
            Emitter::Area(a) => {
                let cos = n.dot(dir);
                if a.area() <= 0.0 || (cos <= 0.0 && !a.two_sided) {
                    return (0.0, 0.0);
                }
                let sides = if a.two_sided { 2.0 } else { 1.0 };
                (1.0 / a.area(), cos.abs() / (PI * sides))
            }
            Emitter::Point(_) => (1.0, 1.0 / (4.0 * PI)),
            Emitter::Spot(l) => {
                let cos_end = l.cos_falloff_end;
                if l.dir.dot(dir) < cos_end || cos_end >= 1.0 {
                    return (1.0, 0.0);
                }
                (1.0, 1.0 / (2.0 * PI * (1.0 - cos_end)))
            }
            Emitter::Distant(_) => (self.disc_pdf(dir, p, aim), 1.0),
            Emitter::Infinite(map) => (self.disc_pdf(dir, p, aim), map.pdf(-dir)),
        }
    }

    /// The area of the disc that photons of distant and infinite lights start from.
    pub fn disc_area(&self) -> f32 {
        PI * self.radius * self.radius
    }

    /// Whether light `i` is a distant light (one direction).
    pub fn is_delta_direction(&self, i: usize) -> bool {
        matches!(self.emitters[i], Emitter::Distant(_))
    }

    /// [`Self::sample`] with the light chosen already (`i`, with probability `pmf`): a
    /// sphere light by its cone, [`Self::pdf_area`] its density.
    pub fn sample_chosen(
        &self,
        meshes: &[Mesh],
        (i, pmf): (usize, f32),
        p: Vec3,
        u: Vec2,
    ) -> Option<LightSample> {
        self.sample_by(meshes, (i, pmf), p, u, true)
    }

    /// A point `u` on light `i`, chosen with probability `pmf`, as seen from `p`; area lights
    /// by area.
    pub fn sample_light(
        &self,
        meshes: &[Mesh],
        i: usize,
        pmf: f32,
        p: Vec3,
        u: Vec2,
    ) -> Option<LightSample> {
        self.sample_by(meshes, (i, pmf), p, u, false)
    }

    /// [`Self::sample_light`], a sphere light by its cone when `visible`
    /// ([`AreaLight::sample_visible`]).
    fn sample_by(
        &self,
        meshes: &[Mesh],
        (i, pmf): (usize, f32),
        p: Vec3,
        u: Vec2,
        visible: bool,
    ) -> Option<LightSample> {
        let mut s = match &self.emitters[i] {
            Emitter::Area(a) if visible => a.sample_visible(meshes, p, u)?,
            Emitter::Area(a) => a.sample(meshes, p, u)?,
            Emitter::Point(l) => l.sample(p)?,
            Emitter::Spot(l) => l.sample(p)?,
            Emitter::Distant(l) => l.sample(p, self.center, self.radius),
            Emitter::Infinite(map) => {
                let (wi, li, pdf) = map.sample(u)?;
                if !map.admits(p, wi) {
                    return None; // a portal light: this direction is dark from p
                }
                let far = (p - self.center).length() + 2.0 * self.radius;
                LightSample {
                    li,
                    wi,
                    p: p + wi * far,
                    n: Vec3::ZERO,
                    err: Vec3::ZERO,
                    pdf,
                    delta: false,
                }
            }
        };
        s.pdf *= pmf;
        (s.pdf > 0.0 && s.li.max_element() > 0.0).then_some(s)
    }

    /// Solid-angle density with which [`Self::sample`] would have produced the point `p_light`
    /// (normal `n_light`) on area light `i` for the receiver `r`; for MIS when a BSDF-sampled
    /// ray hits an emitter.
    pub fn pdf_area(&self, i: usize, r: Receiver, p_light: Vec3, n_light: Vec3) -> f32 {
        match self.area_light(i) {
            Some(a) => self.pmf_at(r, i) * a.pdf_visible(r.p, p_light, n_light),
            None => 0.0,
        }
    }

    /// Radiance leaving area light `i` at a point with geometric normal `n` along `w`.
    pub fn le(&self, i: usize, n: Vec3, w: Vec3) -> Vec3 {
        match self.area_light(i) {
            Some(a) => a.le(n, w),
            None => Vec3::ZERO,
        }
    }

    pub fn area_light(&self, i: usize) -> Option<&AreaLight> {
        match self.emitters.get(i) {
            Some(Emitter::Area(a)) => Some(a),
            _ => None,
        }
    }

    pub fn scene_sphere(&self) -> (Vec3, f32) {
        (self.center, self.radius)
    }
}

/// Power of a colour as a scalar for light selection.
pub(crate) fn scalar_power(c: Vec3) -> f32 {
    luminance(c).max(c.max_element() * 1e-3)
}

/// A photon leaving a light: origin, surface normal there (zero for point-like lights),
/// direction, and the flux it carries per sample (divide by the number of photons emitted).
#[derive(Clone, Copy, Debug)]
pub struct Emission {
    pub p: Vec3,
    pub n: Vec3,
    /// Rounding-error bound of `p` (zero for point-like lights).
    pub err: Vec3,
    pub dir: Vec3,
    pub flux: Vec3,
}

/// A sphere that the photons of the distant and infinite lights favour, and the share of
/// them it gets (see `photon::aim` and [`Lights::disc_origin`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Aim {
    pub center: Vec3,
    pub radius: f32,
    pub share: f32,
}

/// Which 2D sample of an emission a projection map restricts: the direction (area, point and
/// spot lights) or the position (distant lights: every photon travels the same way).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum EmissionDomain {
    Direction,
    Position,
}

impl Lights {
    /// Emits a photon from light `i`: `u_pos` picks the origin, `u_dir` the direction (each in
    /// [0,1)^2, so both can be stratified over the light's photons). The flux is
    /// `Le cos / (pdf_pos pdf_dir)`: the light's power for uniform cosine-weighted sampling.
    pub fn emit(&self, meshes: &[Mesh], i: usize, u_pos: Vec2, u_dir: Vec2) -> Option<Emission> {
        self.emit_aimed(meshes, i, u_pos, u_dir, None)
    }

    /// As [`Self::emit`]; a distant or infinite light draws the origin from the mixture of
    /// [`Self::disc_origin`] with `aim` (the other lights ignore it).
    pub fn emit_aimed(
        &self,
        meshes: &[Mesh],
        i: usize,
        u_pos: Vec2,
        u_dir: Vec2,
        aim: Option<&Aim>,
    ) -> Option<Emission> {
        match &self.emitters[i] {
            Emitter::Area(a) => a.emit(meshes, u_pos, u_dir),
            Emitter::Point(l) => Some(l.emit(u_dir)),
            Emitter::Spot(l) => l.emit(u_dir),
            Emitter::Distant(l) => {
                let (p, area) = self.disc_origin(l.dir, u_pos, aim)?;
                Some(l.emit(p, area))
            }
            Emitter::Infinite(map) => self.emit_env(map, u_pos, u_dir, aim),
        }
    }

    /// The origin of a photon of a light without a surface travelling along unit `dir`, on
    /// the plane `2R` upstream of the scene's centre (`R` its radius), and the inverse of its
    /// density on that plane: uniform on the disc of radius `R` that covers the scene, or with
    /// `aim` a mixture: with probability `aim.share` (taken from `u.x`, which keeps the
    /// strata) uniform on the disc that `aim`'s sphere casts, else on the scene's disc; the
    /// density is the mixture's at the origin, so the flux stays unbiased wherever the discs
    /// overlap. `None` for a degenerate density.
    pub fn disc_origin(&self, dir: Vec3, u: Vec2, aim: Option<&Aim>) -> Option<(Vec3, f32)> {
        let frame = Frame::from_normal(dir);
        let base = self.center - dir * (2.0 * self.radius);
        let big = self.radius;
        let at = |d: Vec2| base + frame.s * d.x + frame.t * d.y;
        let Some(aim) = aim.filter(|a| a.share > 0.0 && a.share < 1.0 && a.radius > 0.0) else {
            return Some((at(square_to_disk_concentric(u) * big), PI * big * big));
        };
        let off = aim.center - self.center;
        let a = Vec2::new(off.dot(frame.s), off.dot(frame.t));
        let small = aim.radius;
        let d = if u.x < aim.share {
            let v = Vec2::new((u.x / aim.share).min(ONE_MINUS_EPSILON), u.y);
            a + square_to_disk_concentric(v) * small
        } else {
            let v = Vec2::new(
                ((u.x - aim.share) / (1.0 - aim.share)).min(ONE_MINUS_EPSILON),
                u.y,
            );
            square_to_disk_concentric(v) * big
        };
        let pdf = self.mixture_pdf(d, a, aim);
        (pdf > 0.0 && pdf.is_finite()).then(|| (at(d), 1.0 / pdf))
    }

    /// The density on the emission plane of [`Self::disc_origin`]'s origin for a photon
    /// travelling along unit `dir` whose line passes through `p` (any point of the ray: the
    /// origin is `p`'s projection), so that a camera subpath's vertex can ask how likely a
    /// light subpath was to reach it.
    pub fn disc_pdf(&self, dir: Vec3, p: Vec3, aim: Option<&Aim>) -> f32 {
        let frame = Frame::from_normal(dir);
        let lateral = |q: Vec3| {
            let v = q - self.center;
            Vec2::new(v.dot(frame.s), v.dot(frame.t))
        };
        match aim.filter(|a| a.share > 0.0 && a.share < 1.0 && a.radius > 0.0) {
            Some(aim) => self.mixture_pdf(lateral(p), lateral(aim.center), aim),
            // Every point of the scene projects inside the scene's disc.
            None => 1.0 / self.disc_area(),
        }
    }

    /// The aimed mixture's density at `d` on the emission plane (offsets from the scene's
    /// centre), the aimed disc centred at `a`.
    fn mixture_pdf(&self, d: Vec2, a: Vec2, aim: &Aim) -> f32 {
        let (big, small) = (self.radius, aim.radius);
        // A hair of slack for points drawn on a disc's rim.
        let inside = |q: Vec2, r: f32| q.length_squared() <= r * r * (1.0 + 1e-5);
        let mut pdf = 0.0;
        if inside(d, big) {
            pdf += (1.0 - aim.share) / (PI * big * big);
        }
        if inside(d - a, small) {
            pdf += aim.share / (PI * small * small);
        }
        pdf
    }

    /// A photon from an infinite light (pbrt-v4's `SampleLe`): a direction from the map's
    /// distribution (`u_dir`), an origin uniform on the disc of the scene's radius `R` that
    /// faces it, outside the scene (`u_pos`); flux `Le pi R^2 / pdf_dir`.
    fn emit_env(
        &self,
        map: &EnvMap,
        u_pos: Vec2,
        u_dir: Vec2,
        aim: Option<&Aim>,
    ) -> Option<Emission> {
        let (w, le, pdf) = map.sample(u_dir)?;
        let dir = -w;
        let (p, area) = self.disc_origin(dir, u_pos, aim)?;
        if !map.admits_photon(p, dir) {
            return None; // counted as emitted: a portal light's photons enter only through it
        }
        Some(Emission {
            p,
            n: Vec3::ZERO,
            err: Vec3::ZERO,
            dir,
            flux: finite_flux(le, area as f64 / pdf as f64),
        })
    }

    /// A caustic photon from light `i`: as [`Self::emit`], except that an infinite light aims
    /// it at the bounding spheres `targets` of the specular objects (only photons whose first
    /// hit is specular can start a caustic path): the origin is uniform over the discs those
    /// spheres cast on the emission plane along the photon's direction, a disc chosen by its
    /// area with `u_pos.x`, and the flux divides by that density (`k / (pi sum r^2)` where `k`
    /// discs overlap at the origin).
    pub fn emit_caustic(
        &self,
        meshes: &[Mesh],
        i: usize,
        u_pos: Vec2,
        u_dir: Vec2,
        targets: &[(Vec3, f32)],
    ) -> Option<Emission> {
        let Emitter::Infinite(map) = &self.emitters[i] else {
            return self.emit(meshes, i, u_pos, u_dir);
        };
        let areas: Vec<f32> = targets.iter().map(|&(_, r)| r * r).collect();
        let (t, _, rem) = crate::sampling::warp::Distribution1D::new(&areas).sample(u_pos.x)?;
        let (w, le, pdf_dir) = map.sample(u_dir)?;
        let dir = -w;
        let frame = Frame::from_normal(dir);
        let (c, r) = targets[t];
        let d = square_to_disk_concentric(Vec2::new(rem, u_pos.y)) * r;
        // On the plane 2R upstream of the scene's centre, across from the target's centre.
        let upstream = (c - self.center).dot(dir) + 2.0 * self.radius;
        let p = c - dir * upstream + frame.s * d.x + frame.t * d.y;
        let covering = targets
            .iter()
            .filter(|&&(c, r)| {
                let v = c - p;
                (v - dir * v.dot(dir)).length_squared() <= r * r
            })
            .count()
            .max(1);
        let total = areas.iter().map(|&a| a as f64).sum::<f64>() * PI as f64;
        if !map.admits_photon(p, dir) {
            return None;
        }
        Some(Emission {
            p,
            n: Vec3::ZERO,
            err: Vec3::ZERO,
            dir,
            flux: finite_flux(le, total / (covering as f64 * pdf_dir as f64)),
        })
    }

    /// The sample domain a projection map of light `i` restricts.
    pub fn emission_domain(&self, i: usize) -> EmissionDomain {
        match self.emitters[i] {
            Emitter::Distant(_) => EmissionDomain::Position,
            _ => EmissionDomain::Direction,
        }
    }

    /// Whether a distant or infinite light shines (their photons can be aimed, see
    /// [`Self::disc_origin`]).
    pub fn has_distant_or_infinite(&self) -> bool {
        self.emitters
            .iter()
            .any(|e| matches!(e, Emitter::Distant(_) | Emitter::Infinite(_)))
    }

    /// Whether every photon of light `i` leaves with the same direction warp (so a cell of the
    /// direction domain maps to one cone of world directions): false for curved area lights.
    pub fn fixed_direction_frame(&self, i: usize) -> bool {
        match &self.emitters[i] {
            Emitter::Area(a) => a.plane_normal().is_some(),
            // Photons leave from anywhere on a disc that turns with the direction.
            Emitter::Infinite(_) => false,
            _ => true,
        }
    }

    /// Bounding sphere of the points light `i` emits from (radius 0 for point and spot).
    pub fn origin_bounds(&self, meshes: &[Mesh], i: usize) -> (Vec3, f32) {
        match &self.emitters[i] {
            Emitter::Area(a) => bounding_sphere(&meshes[a.mesh as usize].positions),
            Emitter::Point(PointLight { pos, .. }) | Emitter::Spot(SpotLight { pos, .. }) => {
                (*pos, 0.0)
            }
            Emitter::Distant(_) => (self.center, self.radius),
            Emitter::Infinite(_) => (self.center, 3.0 * self.radius),
        }
    }

    /// Photon-count weights: emitted power of each light (0 for lights that emit nothing).
    pub fn powers(&self) -> Vec<f32> {
        (0..self.emitters.len())
            .map(|i| self.power(i).max(0.0))
            .collect()
    }
}

impl Emitter {
    /// The light's bounds for importance-based selection ([`select`]); `None` for lights
    /// without a position.
    fn bounds(&self, meshes: &[Mesh]) -> Option<select::Bounds> {
        let point = |pos: Vec3, phi: f32| select::Bounds {
            lo: pos,
            hi: pos,
            phi,
            w: Vec3::Z,
            cos_o: -1.0,
            cos_e: 0.0,
            two_sided: false,
        };
        match self {
            Emitter::Area(a) => {
                let mesh = meshes.get(a.mesh as usize)?;
                let (mut lo, mut hi) = (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY));
                let (mut ns, mut ws) = (Vec::new(), Vec::new());
                for (t, tri) in mesh.indices.iter().enumerate() {
                    for &v in tri {
                        let p = mesh.positions[v as usize];
                        (lo, hi) = (lo.min(p), hi.max(p));
                    }
                    let area = mesh.area(t as u32);
                    if area > 0.0 {
                        ns.push(mesh.geometric_normal(t as u32, 1.0 / 3.0, 1.0 / 3.0));
                        ws.push(area);
                    }
                }
                if lo.x > hi.x || !(lo.is_finite() && hi.is_finite()) {
                    return None;
                }
                let (w, cos_o) = match a.plane_normal() {
                    Some(n) => (n, 1.0),
                    None => select::normal_cone(&ns, &ws),
                };
                Some(select::Bounds {
                    lo,
                    hi,
                    phi: a.power(),
                    w,
                    cos_o,
                    cos_e: 0.0,
                    two_sided: a.two_sided,
                })
            }
            // pbrt-v4's point and spot bounds: 4 pi I for both, the spot's cone around its axis.
            Emitter::Point(l) => Some(point(l.pos, l.power())),
            Emitter::Spot(l) => {
                let (start, end) = (l.cos_falloff_start, l.cos_falloff_end);
                let cos_e = (end.clamp(-1.0, 1.0).acos() - start.clamp(-1.0, 1.0).acos()).cos();
                Some(select::Bounds {
                    w: l.dir,
                    cos_o: start,
                    cos_e,
                    ..point(l.pos, 4.0 * PI * scalar_power(l.intensity))
                })
            }
            Emitter::Distant(_) | Emitter::Infinite(_) => None,
        }
    }
}

/// `le * k` computed in f64 and kept finite (at most `f32::MAX` per channel): an infinite
/// light's photon flux grows with the scene's area.
fn finite_flux(le: Vec3, k: f64) -> Vec3 {
    (le.as_dvec3() * k)
        .min(glam::DVec3::splat(f32::MAX as f64))
        .as_vec3()
}

/// A (not minimal) bounding sphere of points: the centre of their box, and the farthest point.
pub fn bounding_sphere(points: &[Vec3]) -> (Vec3, f32) {
    if points.is_empty() {
        return (Vec3::ZERO, 0.0);
    }
    let (lo, hi) = points.iter().fold(
        (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY)),
        |(l, h), p| (l.min(*p), h.max(*p)),
    );
    let c = (lo + hi) * 0.5;
    let r = points.iter().map(|p| (*p - c).length()).fold(0.0, f32::max);
    (c, r)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The aimed mixture's inverse density weighs origins by the area they stand for: over
    /// a stratified grid of draws, `sum(area) / n` over the origins in a square of the
    /// emission plane is the square's area, for a square inside the aimed disc, one across
    /// its rim and one outside it (where only a quarter of the draws go); without an aim,
    /// every origin stands for `pi R^2`.
    #[test]
    fn aimed_origins_weigh_to_the_area_they_cover() {
        let lights = Lights::new(&[], &[], (Vec3::splat(-10.0), Vec3::splat(10.0)));
        let (center, radius) = lights.scene_sphere();
        let dir = Vec3::new(0.3, -1.0, 0.2).normalize();
        let frame = Frame::from_normal(dir);
        let base = center - dir * (2.0 * radius);
        let aim = Aim {
            center: Vec3::new(3.0, 1.0, -2.0),
            radius: 2.0,
            share: 0.75,
        };
        let off = aim.center - center;
        let a = Vec2::new(off.dot(frame.s), off.dot(frame.t));
        // (lower corner, side) in the plane's (s, t) coordinates.
        let squares = [
            (a - Vec2::splat(0.5), 1.0),
            (a + Vec2::new(1.5, -0.5), 1.0),
            (Vec2::new(-12.0, -12.0), 4.0),
        ];
        let n = 512;
        let mut sums = [0.0f64; 3];
        for j in 0..n {
            for i in 0..n {
                let u = Vec2::new((i as f32 + 0.5) / n as f32, (j as f32 + 0.5) / n as f32);
                let (p, area) = lights.disc_origin(dir, u, Some(&aim)).expect("a density");
                let q = Vec2::new((p - base).dot(frame.s), (p - base).dot(frame.t));
                for (k, &(lo, side)) in squares.iter().enumerate() {
                    let r = q - lo;
                    if r.x >= 0.0 && r.y >= 0.0 && r.x < side && r.y < side {
                        sums[k] += area as f64 / (n * n) as f64;
                    }
                }
            }
        }
        for (k, &(_, side)) in squares.iter().enumerate() {
            let want = (side * side) as f64;
            assert!(
                (sums[k] / want - 1.0).abs() < 0.03,
                "square {k}: {} for area {want}",
                sums[k]
            );
        }
        let (_, area) = lights.disc_origin(dir, Vec2::new(0.3, 0.7), None).unwrap();
        assert!((area - PI * radius * radius).abs() < 1e-3 * area);
    }
}
