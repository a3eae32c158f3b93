//! Which light a shadow ray goes to, by what each light can send to the receiving point:
//! pbrt-v4's `LightBounds::Importance`, evaluated for every light with a position as its
//! `ExhaustiveLightSampler` does (pbrt-v4's default, the BVH light sampler, approximates the
//! same importance over a tree).
//!
//! A light's bounds are its box, its power `phi`, a cone of emitting normals (axis `w`,
//! half-angle `theta_o`) and the angle `theta_e` beyond the normals that light leaves at
//! (90 degrees for a diffuse emitter). Seen from `p` with normal `n`, the importance is
//! `phi cos(theta') cos(theta'_i) / d^2`: `theta'` the smallest angle between an emitting
//! normal and the direction to `p`, `theta'_i` the smallest angle between `n` and a direction
//! into the box, each widened by the angle the box subtends from `p`. It is zero only where
//! the light cannot reach `p`'s plane or cannot face `p`, so picking by it wastes no shadow
//! ray on a light behind the receiver or facing away from it, and favours near lights over
//! far ones. Measured (path, 32 spp, variance between two seeds): staircase2 (13 lights)
//! and bedroom 13% lower than by power, kitchen 3%, coffee, spaceship, lamp and living-room-2
//! unchanged.
//!
//! Lights without a position (distant, infinite) keep their share of the power, split among
//! them by power; the rest goes to the positioned lights by importance. With more than
//! [`EXHAUSTIVE_MAX`] positioned lights every light is picked by power (pbrt-v4's BVH is not
//! built). The bidirectional integrators' light subpaths pick by power; their light samples
//! pick by importance, and their partial sums take that density once the receiving point is
//! known (`integrator/vcm.rs`).
use crate::math::Vec3;
use crate::sampling::alias::AliasTable;
use crate::sampling::ONE_MINUS_EPSILON;

/// Positioned lights beyond which selection falls back to power alone.
pub const EXHAUSTIVE_MAX: usize = 64;

/// Where a light is picked for: the receiving point and the unit normal there (the shading
/// normal on a surface; zero in a medium, where every direction counts), and whether uniform
/// skies are left to the BSDF there.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Receiver {
    pub p: Vec3,
    pub n: Vec3,
    /// Whether uniform infinite lights ([`super::EnvMap::is_uniform`]) get no shadow rays here:
    /// see [`Receiver::sky_by_bsdf`].
    pub bsdf_sky: bool,
}

impl Receiver {
    pub fn new(p: Vec3, n: Vec3) -> Receiver {
        Receiver {
            p,
            n,
            bsdf_sky: false,
        }
    }

    /// A point in a medium.
    pub fn in_medium(p: Vec3) -> Receiver {
        Receiver::new(p, Vec3::ZERO)
    }

    /// This receiver for a tracer whose every non-delta vertex also continues by sampling its
    /// BSDF or phase function (the path tracer): uniform infinite lights are then never picked
    /// for shadow rays (their density in [`super::Lights::pmf_at`] is 0, so a sampled ray that
    /// leaves the scene sees them with full weight) and the other lights share all the picks.
    /// pbrt-v4's path tracers do the same (`UniformInfiniteLight::SampleLi` with
    /// `allowIncompletePDF`): for a uniform sky a cosine-weighted or glossy BSDF sample beats
    /// a uniform sphere sample, half of which lands behind the surface. Measured on spaceship
    /// (path, variance between two seeds at 640 spp): see BENCHMARKS.md.
    pub fn sky_by_bsdf(self) -> Receiver {
        Receiver {
            bsdf_sky: true,
            ..self
        }
    }
}

/// How a light's selection probability is counted (for MIS weights): by importance at the
/// receiver, as next-event estimation picks, or by power, as photons and light subpaths
/// pick.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Pick {
    At(Receiver),
    Power,
}

/// The bounds of one light with a position (pbrt-v4's `LightBounds`).
#[derive(Clone, Copy, Debug)]
pub struct Bounds {
    pub lo: Vec3,
    pub hi: Vec3,
    /// Emitted power (the same scalar as the power selection's).
    pub phi: f32,
    /// Axis of the cone of emitting normals.
    pub w: Vec3,
    /// Cosine of the cone's half-angle (-1: every direction).
    pub cos_o: f32,
    /// Cosine of the angle beyond the normals that light leaves at (0 for a diffuse emitter).
    pub cos_e: f32,
    pub two_sided: bool,
}

/// `cos(max(0, a - b))` from the sines and cosines of `a` and `b`.
fn cos_sub_clamped(sin_a: f32, cos_a: f32, sin_b: f32, cos_b: f32) -> f32 {
    if cos_a > cos_b {
        1.0
    } else {
        cos_a * cos_b + sin_a * sin_b
    }
}

/// `sin(max(0, a - b))` from the sines and cosines of `a` and `b`.
fn sin_sub_clamped(sin_a: f32, cos_a: f32, sin_b: f32, cos_b: f32) -> f32 {
    if cos_a > cos_b {
        0.0
    } else {
        sin_a * cos_b - cos_a * sin_b
    }
}

fn safe_sqrt(x: f32) -> f32 {
    x.max(0.0).sqrt()
}

impl Bounds {
    /// pbrt-v4's `LightBounds::Importance` at `r` (never negative; zero only where the light
    /// sends nothing to `r`'s point within the cosine bound of its normal).
    pub fn importance(&self, r: Receiver) -> f32 {
        let pc = (self.lo + self.hi) * 0.5;
        let diag = (self.hi - self.lo).length();
        let d2 = r.p.distance_squared(pc).max(diag / 2.0);
        let to = r.p - pc;
        let len = to.length();
        // From inside the box's sphere every direction is possible.
        let r2 = (diag / 2.0) * (diag / 2.0);
        let cos_b = if len * len < r2 || len == 0.0 {
            -1.0
        } else {
            safe_sqrt(1.0 - r2 / (len * len))
        };
        let sin_b = safe_sqrt(1.0 - cos_b * cos_b);
        let wi = if len > 0.0 { to / len } else { Vec3::Z };
        let mut cos_w = self.w.dot(wi);
        if self.two_sided {
            cos_w = cos_w.abs();
        }
        let sin_w = safe_sqrt(1.0 - cos_w * cos_w);
        let sin_o = safe_sqrt(1.0 - self.cos_o * self.cos_o);
        let cos_x = cos_sub_clamped(sin_w, cos_w, sin_o, self.cos_o);
        let sin_x = sin_sub_clamped(sin_w, cos_w, sin_o, self.cos_o);
        let cos_p = cos_sub_clamped(sin_x, cos_x, sin_b, cos_b);
        if cos_p <= self.cos_e {
            return 0.0;
        }
        let mut importance = self.phi * cos_p / d2;
        if r.n != Vec3::ZERO {
            let cos_i = wi.dot(r.n).abs();
            let sin_i = safe_sqrt(1.0 - cos_i * cos_i);
            importance *= cos_sub_clamped(sin_i, cos_i, sin_b, cos_b);
        }
        if importance.is_finite() {
            importance.max(0.0)
        } else {
            0.0
        }
    }
}

/// The cone of unit normals `ns` (weighted by `weights`): its axis and the cosine of its
/// half-angle (-1 when the normals point every way).
pub fn normal_cone(ns: &[Vec3], weights: &[f32]) -> (Vec3, f32) {
    let sum = ns
        .iter()
        .zip(weights)
        .fold(Vec3::ZERO, |acc, (n, w)| acc + *n * *w);
    let Some(w) = sum.try_normalize() else {
        return (Vec3::Z, -1.0);
    };
    let cos = ns.iter().fold(1.0f32, |c, n| c.min(n.dot(w)));
    // Rounding must not exclude a normal of the set.
    let cos = (cos - 1e-4).max(-1.0);
    (w, cos)
}

/// One way of picking lights for shadow rays: by power alone, or (at most [`EXHAUSTIVE_MAX`]
/// positioned lights) the positioned ones by importance and the others by power within their
/// share. [`super::Lights`] keeps one over every light and one without the uniform skies
/// ([`Receiver::sky_by_bsdf`]).
#[derive(Clone, Debug, Default)]
pub(super) struct Selection {
    /// Every light by power (what is picked when `bounded` is empty).
    power: AliasTable,
    /// The positioned lights (empty: pick by power).
    bounded: Vec<usize>,
    /// The lights without a position by power among them, and their share of the power.
    unbounded: AliasTable,
    p_unbounded: f32,
}

impl Selection {
    /// Picks light `i` with power `powers[i]` (0: never), `bounds[i]` its bounds when it has a
    /// position.
    pub(super) fn new(powers: &[f32], bounds: &[Option<Bounds>]) -> Selection {
        let mut out = Selection {
            power: AliasTable::new(powers),
            ..Selection::default()
        };
        let bounded: Vec<usize> = (0..powers.len())
            .filter(|&i| powers[i] > 0.0 && bounds[i].is_some_and(|b| b.phi > 0.0))
            .collect();
        if bounded.len() > EXHAUSTIVE_MAX {
            return out;
        }
        let unbounded: Vec<f32> = (0..powers.len())
            .map(|i| if bounds[i].is_none() { powers[i] } else { 0.0 })
            .collect();
        if unbounded.iter().any(|&w| w > 0.0) {
            out.unbounded = AliasTable::new(&unbounded);
            out.p_unbounded = (0..powers.len())
                .filter(|&i| bounds[i].is_none())
                .map(|i| out.power.pmf(i))
                .sum::<f32>()
                .min(1.0);
        }
        out.bounded = bounded;
        out
    }

    /// Every light of the selection by power alone (the photons' and the bidirectional
    /// integrators' choice, [`super::Lights::pick`]).
    pub(super) fn by_power(&self) -> &AliasTable {
        &self.power
    }

    /// The importance of each positioned light at `r` into `imp` (in the order of
    /// `self.bounded`), and their sum.
    fn importances(&self, bounds: &[Option<Bounds>], r: Receiver, imp: &mut [f32]) -> f32 {
        let mut sum = 0.0;
        for (k, &i) in self.bounded.iter().enumerate() {
            imp[k] = bounds[i].map_or(0.0, |b| b.importance(r));
            sum += imp[k];
        }
        sum
    }

    /// The share of the lights without a position when the positioned ones' importances at
    /// the receiver sum to `sum`: their share of the power, or everything where no positioned
    /// light can reach the receiver.
    fn unbounded_share(&self, sum: f32) -> f32 {
        if sum > 0.0 && sum.is_finite() {
            self.p_unbounded
        } else if self.unbounded.is_empty() {
            0.0
        } else {
            1.0
        }
    }

    /// Picks a light for a shadow ray from `r` (`u` in `[0, 1)`): its index and probability;
    /// `None` when no light can reach `r`.
    pub(super) fn pick(
        &self,
        bounds: &[Option<Bounds>],
        r: Receiver,
        u: f32,
    ) -> Option<(usize, f32)> {
        if self.bounded.is_empty() {
            return self.power.sample(u);
        }
        let mut imp = [0.0; EXHAUSTIVE_MAX];
        let sum = self.importances(bounds, r, &mut imp);
        let share = self.unbounded_share(sum);
        if u < share {
            let (i, pmf) = self.unbounded.sample((u / share).min(ONE_MINUS_EPSILON))?;
            return Some((i, pmf * share));
        }
        if !(sum > 0.0 && sum.is_finite()) {
            return None;
        }
        let target = ((u - share) / (1.0 - share)).min(ONE_MINUS_EPSILON) * sum;
        let mut acc = 0.0;
        let mut last = None;
        for (k, &i) in self.bounded.iter().enumerate() {
            if imp[k] <= 0.0 {
                continue;
            }
            last = Some((i, imp[k]));
            acc += imp[k];
            if target < acc {
                break;
            }
        }
        let (i, w) = last?;
        Some((i, (1.0 - share) * w / sum))
    }

    /// The probability that [`Self::pick`] picks light `i` for `r`.
    pub(super) fn pmf(&self, bounds: &[Option<Bounds>], r: Receiver, i: usize) -> f32 {
        if self.bounded.is_empty() {
            return self.power.pmf(i);
        }
        let mut imp = [0.0; EXHAUSTIVE_MAX];
        let sum = self.importances(bounds, r, &mut imp);
        let share = self.unbounded_share(sum);
        if bounds.get(i).is_some_and(|b| b.is_none()) {
            return share * self.unbounded.pmf(i);
        }
        match self.bounded.iter().position(|&j| j == i) {
            Some(k) if sum > 0.0 && sum.is_finite() => (1.0 - share) * imp[k] / sum,
            _ => 0.0,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn quad(n: Vec3, two_sided: bool) -> Bounds {
        Bounds {
            lo: Vec3::new(-0.5, -0.5, 0.0),
            hi: Vec3::new(0.5, 0.5, 0.0),
            phi: 1.0,
            w: n,
            cos_o: 1.0,
            cos_e: 0.0,
            two_sided,
        }
    }

    /// A one-sided quad at z = 0 facing +z sends nothing below its plane (beyond the box's
    /// angular extent) and something everywhere above; two-sided, both.
    #[test]
    fn importance_is_zero_only_behind_a_one_sided_light() {
        let up = Receiver::in_medium(Vec3::new(0.3, -0.2, 2.0));
        let down = Receiver::in_medium(Vec3::new(0.3, -0.2, -2.0));
        let grazing = Receiver::in_medium(Vec3::new(3.0, 0.0, 0.05));
        let b = quad(Vec3::Z, false);
        assert!(b.importance(up) > 0.0);
        assert_eq!(b.importance(down), 0.0);
        assert!(
            b.importance(grazing) > 0.0,
            "a point beside the plane sees its edge"
        );
        let b2 = quad(Vec3::Z, true);
        assert!(b2.importance(down) > 0.0);
        assert!((b2.importance(down) - b2.importance(up)).abs() < 1e-6);
    }

    /// A receiver whose normal is perpendicular to the direction of the light's centre still
    /// counts the light (the box subtends an angle), less than one facing it; far away the
    /// value falls with the distance squared.
    #[test]
    fn receiver_normal_and_distance() {
        let b = quad(Vec3::Z, false);
        let p = Vec3::new(0.0, 0.0, 5.0);
        let facing = b.importance(Receiver::new(p, -Vec3::Z));
        let side = b.importance(Receiver::new(p, Vec3::X));
        assert!(side > 0.0 && side < 0.2 * facing, "{side} vs {facing}");
        let far = b.importance(Receiver::new(p * 2.0, -Vec3::Z));
        assert!((facing / far - 4.0).abs() < 0.2, "{facing} / {far}");
    }

    #[test]
    fn cone_of_normals() {
        let (w, c) = normal_cone(&[Vec3::Z, Vec3::X], &[1.0, 1.0]);
        assert!((w - Vec3::new(1.0, 0.0, 1.0).normalize()).length() < 1e-5);
        assert!((c - std::f32::consts::FRAC_1_SQRT_2).abs() < 1e-3);
        let (_, c) = normal_cone(&[Vec3::Z, -Vec3::Z], &[1.0, 1.0]);
        assert_eq!(c, -1.0);
    }
}
