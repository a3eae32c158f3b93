//! Small geometric helpers on top of `glam`: rays, orthonormal frames and the robust
//! ray-origin offset that keeps secondary and shadow rays from re-hitting their own surface.
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

/// Offsets a ray origin off a surface along its geometric normal so that the new ray does not
/// hit the surface it starts on, at any scene scale (Wächter & Binder, "A Fast and Robust
/// Method for Avoiding Self-Intersection", Ray Tracing Gems ch. 6): a few ulps in integer
/// space far from the origin, a fixed tiny epsilon near it. `n` must point to the side the new
/// ray leaves towards (flip it for transmission).
pub fn offset_ray_origin(p: Vec3, n: Vec3) -> Vec3 {
    const ORIGIN: f32 = 1.0 / 32.0;
    const FLOAT_SCALE: f32 = 1.0 / 65536.0;
    const INT_SCALE: f32 = 256.0;
    let of_i = [
        (INT_SCALE * n.x) as i32,
        (INT_SCALE * n.y) as i32,
        (INT_SCALE * n.z) as i32,
    ];
    let bump = |pc: f32, oi: i32| -> f32 {
        let bits = pc.to_bits() as i32;
        f32::from_bits((bits + if pc < 0.0 { -oi } else { oi }) as u32)
    };
    let p_i = Vec3::new(bump(p.x, of_i[0]), bump(p.y, of_i[1]), bump(p.z, of_i[2]));
    Vec3::new(
        if p.x.abs() < ORIGIN {
            p.x + FLOAT_SCALE * n.x
        } else {
            p_i.x
        },
        if p.y.abs() < ORIGIN {
            p.y + FLOAT_SCALE * n.y
        } else {
            p_i.y
        },
        if p.z.abs() < ORIGIN {
            p.z + FLOAT_SCALE * n.z
        } else {
            p_i.z
        },
    )
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
    fn offset_moves_to_the_normal_side() {
        for scale in [1e-4f32, 1.0, 1e4] {
            let p = Vec3::new(0.3, -0.7, 0.5) * scale;
            let n = Vec3::new(0.0, 0.0, 1.0);
            let q = offset_ray_origin(p, n);
            assert!(q.z > p.z, "scale {scale}: {q:?} not above {p:?}");
            assert!((q - p).length() < 1e-3 * scale.max(1.0));
        }
    }
}
