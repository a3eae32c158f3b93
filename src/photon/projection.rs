//! Caustic projection maps (Jensen & Christensen 1995): per light, a grid over the 2D sample
//! domain of its emission (directions for area, point and spot lights; positions on the disc
//! for distant lights) in which a cell is marked when some photon it can emit may reach the
//! bounding sphere of a specular object. Caustic photons are emitted only into marked cells,
//! their power scaled by the marked fraction of the domain, so the estimate stays unbiased
//! while far fewer photons are wasted.
//!
//! The cell test is conservative: a cell's directions are bounded by a cone (axis through the
//! cell centre, half-angle reaching the corners and edge midpoints, plus a margin), the light's
//! origins by its bounding sphere; a cell is marked when that cone meets a target sphere grown
//! by the light's radius. Curved area lights (no common normal) get every cell marked.
use crate::light::{EmissionDomain, Lights};
use crate::math::{Vec2, Vec3};
use crate::scene::Scene;

/// Default cells per side of a projection map.
pub const DEFAULT_RESOLUTION: u32 = 64;

/// Extra angle (radians) added to every cell cone: covers directions between the probe
/// points.
const ANGLE_MARGIN: f32 = 0.02;

/// The marked cells of one light's emission domain.
#[derive(Clone, Debug)]
pub struct ProjectionMap {
    pub domain: EmissionDomain,
    res: u32,
    marked: Vec<u32>,
}

impl ProjectionMap {
    /// Marks the cells of light `i` whose photons may reach one of `targets` (centre, radius).
    pub fn build(
        scene: &Scene,
        lights: &Lights,
        i: usize,
        targets: &[(Vec3, f32)],
        res: u32,
    ) -> ProjectionMap {
        let domain = lights.emission_domain(i);
        let res = res.max(1);
        let all = !lights.fixed_direction_frame(i);
        let marked = (0..res * res)
            .filter(|&c| {
                all || cell_may_hit(scene, lights, i, domain, c % res, c / res, res, targets)
            })
            .collect();
        ProjectionMap {
            domain,
            res,
            marked,
        }
    }

    /// A map with every cell marked (projection maps disabled).
    pub fn full(domain: EmissionDomain) -> ProjectionMap {
        ProjectionMap {
            domain,
            res: 1,
            marked: vec![0],
        }
    }

    /// Fraction of the sample domain that is marked: the power scale of caustic photons.
    pub fn fraction(&self) -> f32 {
        self.marked.len() as f32 / (self.res * self.res) as f32
    }

    /// The emission samples `(u_pos, u_dir)` with the one of them this map's domain restricts
    /// moved into the marked cells ([`Self::sample`]); `None` when nothing is marked.
    pub fn restrict(&self, u_pos: Vec2, u_dir: Vec2) -> Option<(Vec2, Vec2)> {
        Some(match self.domain {
            EmissionDomain::Direction => (u_pos, self.sample(u_dir)?),
            EmissionDomain::Position => (self.sample(u_pos)?, u_dir),
        })
    }

    /// Maps a uniform `u` in [0,1)^2 to a uniform point of the marked cells (keeps `u`'s
    /// stratification: `u.x` picks the cell and is re-stretched inside it).
    pub fn sample(&self, u: Vec2) -> Option<Vec2> {
        if self.marked.is_empty() {
            return None;
        }
        let m = self.marked.len() as f32;
        let k = ((u.x * m) as usize).min(self.marked.len() - 1);
        let fx = (u.x * m - k as f32).clamp(0.0, 1.0);
        let c = self.marked[k];
        let (cx, cy) = ((c % self.res) as f32, (c / self.res) as f32);
        let r = self.res as f32;
        Some(Vec2::new(
            ((cx + fx) / r).min(crate::sampling::ONE_MINUS_EPSILON),
            ((cy + u.y) / r).min(crate::sampling::ONE_MINUS_EPSILON),
        ))
    }
}

/// Probe points of a cell: centre, corners, edge midpoints (inset from the domain border).
fn probes(cx: u32, cy: u32, res: u32) -> [Vec2; 9] {
    let r = res as f32;
    let at = |fx: f32, fy: f32| {
        Vec2::new(
            ((cx as f32 + fx) / r).clamp(1e-6, 1.0 - 1e-6),
            ((cy as f32 + fy) / r).clamp(1e-6, 1.0 - 1e-6),
        )
    };
    [
        at(0.5, 0.5),
        at(0.0, 0.0),
        at(1.0, 0.0),
        at(0.0, 1.0),
        at(1.0, 1.0),
        at(0.5, 0.0),
        at(0.5, 1.0),
        at(0.0, 0.5),
        at(1.0, 0.5),
    ]
}

#[allow(clippy::too_many_arguments)]
fn cell_may_hit(
    scene: &Scene,
    lights: &Lights,
    i: usize,
    domain: EmissionDomain,
    cx: u32,
    cy: u32,
    res: u32,
    targets: &[(Vec3, f32)],
) -> bool {
    let pts = probes(cx, cy, res);
    let centre = Vec2::splat(0.5);
    match domain {
        EmissionDomain::Direction => {
            let dirs: Vec<Vec3> = pts
                .iter()
                .filter_map(|&u| lights.emit(&scene.meshes, i, centre, u).map(|e| e.dir))
                .collect();
            let Some(&axis) = dirs.first() else {
                return false;
            };
            let half =
                dirs.iter().map(|d| angle(axis, *d)).fold(0.0, f32::max) * 1.1 + ANGLE_MARGIN;
            let (origin, lr) = lights.origin_bounds(&scene.meshes, i);
            targets.iter().any(|&(c, r)| {
                let v = c - origin;
                let dist = v.length();
                if dist <= r + lr {
                    return true;
                }
                let spread = ((r + lr) / dist).min(1.0).asin();
                angle(axis, v / dist) <= half + spread
            })
        }
        EmissionDomain::Position => {
            let rays: Vec<(Vec3, Vec3)> = pts
                .iter()
                .filter_map(|&u| {
                    lights
                        .emit(&scene.meshes, i, u, centre)
                        .map(|e| (e.p, e.dir))
                })
                .collect();
            let Some(&(pc, dir)) = rays.first() else {
                return false;
            };
            let reach = rays
                .iter()
                .map(|(p, _)| (*p - pc).length())
                .fold(0.0, f32::max)
                * 1.1;
            targets.iter().any(|&(c, r)| {
                let v = c - pc;
                let along = v.dot(dir);
                along > -r && (v - dir * along).length() <= r + reach
            })
        }
    }
}

fn angle(a: Vec3, b: Vec3) -> f32 {
    a.dot(b).clamp(-1.0, 1.0).acos()
}
