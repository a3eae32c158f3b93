//! Small geometric helpers on top of `glam`: rays, orthonormal frames and the robust
//! ray-origin offset (pbrt-style error bounds) that keeps secondary and shadow rays from
//! re-hitting their own surface at any scene scale.
pub use glam::{Mat3, Mat4, Vec2, Vec3};

/// A ray `o + t d` for `t` in `[tmin, tmax]`. `d` need not be normalised.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Ray {
    pub o: Vec3,
    pub d: Vec3,
    pub tmin: f32,
    pub tmax: f32,
}

impl Ray {
    /// A ray from `o` along `d` with the whole positive half-line.
    pub fn new(o: Vec3, d: Vec3) -> Self {
        Ray {
            o,
            d,
            tmin: 0.0,
            tmax: f32::INFINITY,
        }
    }

    /// A segment ray from `o` along `d` up to `tmax` (in units of `d`).
    pub fn segment(o: Vec3, d: Vec3, tmax: f32) -> Self {
        Ray {
            o,
            d,
            tmin: 0.0,
            tmax,
        }
    }

    pub fn at(&self, t: f32) -> Vec3 {
        self.o + self.d * t
    }
}

/// An orthonormal frame around a unit normal; local z is the normal.
#[derive(Clone, Copy, Debug)]
pub struct Frame {
    pub s: Vec3,
    pub t: Vec3,
    pub n: Vec3,
}

impl Frame {
    /// Builds a frame from a unit normal (Duff et al. 2017, branchless ONB).
    pub fn from_normal(n: Vec3) -> Self {
        let sign = 1.0f32.copysign(n.z);
        let a = -1.0 / (sign + n.z);
        let b = n.x * n.y * a;
        let s = Vec3::new(1.0 + sign * n.x * n.x * a, sign * b, -sign * n.x);
        let t = Vec3::new(b, sign + n.y * n.y * a, -n.y);
        Frame { s, t, n }
    }

    pub fn to_local(&self, v: Vec3) -> Vec3 {
        Vec3::new(v.dot(self.s), v.dot(self.t), v.dot(self.n))
    }

    pub fn to_world(&self, v: Vec3) -> Vec3 {
        self.s * v.x + self.t * v.y + self.n * v.z
    }
}

/// `gamma(n) = n eps / (1 - n eps)` with `eps = 2^-24`: the relative error bound of `n`
/// floating-point operations (pbrt's notation).
pub fn gamma(n: i32) -> f32 {
    let e = n as f32 * f32::EPSILON * 0.5;
    e / (1.0 - e)
}

/// Spawns a ray origin from a surface point `p` whose components are known to within `err`
/// (e.g. [`crate::scene::Mesh::point_error`]): moves it along `n` (the side the new ray leaves
/// towards) past the error box, with a margin for the intersector's own arithmetic, then one
/// more ulp away in each component (pbrt-v4's `OffsetRayOrigin`). The offset scales with the
/// geometry's own magnitude, so it is right at any scene scale, large or tiny.
pub fn spawn_origin(p: Vec3, err: Vec3, n: Vec3) -> Vec3 {
    const MARGIN: f32 = 4.0;
    // A floor keeps the offset a normal float when the point is exact (a surface lying in a
    // coordinate plane through 0 has err = 0 there): one ulp of 0 is a subnormal, which
    // flush-to-zero reads as 0, leaving the origin on the surface.
    const MIN_OFFSET: f32 = 1e-30;
    let d = (MARGIN * n.abs().dot(err)).max(MIN_OFFSET);
    let offset = n * d;
    let mut o = p + offset;
    for c in 0..3 {
        if offset[c] > 0.0 {
            o[c] = o[c].next_up();
        } else if offset[c] < 0.0 {
            o[c] = o[c].next_down();
        }
    }
    o
}

/// Largest component of a colour triple.
pub fn max_component(c: Vec3) -> f32 {
    c.x.max(c.y).max(c.z)
}

/// Rec. 709 luminance of a linear RGB triple.
pub fn luminance(c: Vec3) -> f32 {
    0.2126 * c.x + 0.7152 * c.y + 0.0722 * c.z
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn frame_is_orthonormal() {
        for n in [
            Vec3::Z,
            -Vec3::Z,
            Vec3::X,
            Vec3::new(0.3, -0.4, 0.866).normalize(),
        ] {
            let f = Frame::from_normal(n);
            assert!(f.s.dot(f.t).abs() < 1e-6 && f.s.dot(f.n).abs() < 1e-6);
            assert!((f.s.length() - 1.0).abs() < 1e-6 && (f.t.length() - 1.0).abs() < 1e-6);
            let v = Vec3::new(0.1, 0.7, -0.2);
            assert!((f.to_world(f.to_local(v)) - v).length() < 1e-6);
        }
    }

    #[test]
    fn spawned_origin_leaves_to_the_normal_side() {
        for scale in [1e-4f32, 1.0, 1e4] {
            let p = Vec3::new(0.3, -0.7, 0.5) * scale;
            let err = p.abs() * gamma(7);
            for n in [Vec3::Z, -Vec3::Z] {
                let q = spawn_origin(p, err, n);
                assert!(
                    (q.z - p.z) * n.z > 0.0,
                    "scale {scale}: {q:?} not past {p:?}"
                );
                assert!(
                    (q - p).length() < 1e-5 * scale,
                    "scale {scale}: moved {}",
                    (q - p).length()
                );
            }
        }
        // An exact point on a coordinate plane still leaves it by a normal float.
        let q = spawn_origin(Vec3::new(1.0, 0.0, 2.0), Vec3::ZERO, Vec3::Y);
        assert!(q.y >= 1e-30 && q.y.is_normal());
    }
}
