//! The stored photon: a compact 20-byte record.
//!
//! | bytes | field | encoding |
//! |-------|-------|----------|
//! | 0..12 | position | 3 x `f32` |
//! | 12..17 | power (RGB) | shared exponent "rgb11e7": three 11-bit mantissas, one 7-bit exponent |
//! | 17..19 | incoming direction | octahedral map, 8 + 8 bits, nearest of the 4 neighbouring codes |
//! | 19 | flags | bits 0-3: [`Photon::CAUSTIC`], ...; bits 4-7: the bounce ([`Photon::bounce`]) |
//!
//! The kd-tree keeps its split axes in its own array, so the record needs no axis field.
//!
//! Power accuracy: every channel is within `2^-11` (0.05%) of the largest channel, for largest
//! channels between about `1e-19` and `9.2e18`; larger values saturate, smaller ones degrade
//! gracefully to zero, NaN and negative channels store as zero. Direction accuracy: at most
//! [`MAX_DIR_ERROR_DEG`] degrees (measured by `dir_round_trip_error` over a dense sphere grid).
use crate::math::Vec3;

/// Bits per mantissa of the shared-exponent power.
const MANT_BITS: u32 = 11;
const MANT_MAX: u32 = (1 << MANT_BITS) - 1;
/// Exponent bias: a stored exponent `E` in `0..=127` means the scale `2^(E - BIAS - 11)`.
const EXP_BIAS: i32 = 64;
const EXP_MIN: i32 = -EXP_BIAS;
const EXP_MAX: i32 = 127 - EXP_BIAS;

/// Largest angle (degrees) between a unit direction and its decoded octahedral code.
pub const MAX_DIR_ERROR_DEG: f32 = 0.65;

/// A photon as stored in the map. See the module docs for the layout.
#[derive(Clone, Copy, Debug, PartialEq)]
#[repr(C)]
pub struct Photon {
    pos: [f32; 3],
    power: [u8; 5],
    dir: [u8; 2],
    flags: u8,
}

impl Photon {
    /// Flag bit: the photon reached this surface through specular bounces only (caustic map).
    pub const CAUSTIC: u8 = 1;
    /// Flag bit: the photon was stored directly from a light (no bounce); useful for debugging.
    pub const DIRECT: u8 = 2;
    /// Flag bit: the photon reached this surface through surfaces without a diffuse lobe only,
    /// at least one of them glossy (a glossy caustic: L (S|G)* G (S|G)* D).
    pub const GLOSSY: u8 = 4;
    /// Flag bit: a caustic photon stored on a rough glossy surface (not a diffuse one).
    pub const ON_GLOSSY: u8 = 8;

    /// A photon at `pos` carrying RGB `power`, travelling along the unit vector `dir`
    /// (direction of travel, i.e. pointing into the surface it hit), with free-form `flags`.
    pub fn new(pos: Vec3, power: Vec3, dir: Vec3, flags: u8) -> Self {
        Photon {
            pos: pos.to_array(),
            power: encode_power(power),
            dir: encode_dir(dir),
            flags,
        }
    }

    /// Position where the photon was stored.
    #[inline]
    pub fn pos(&self) -> Vec3 {
        Vec3::from_array(self.pos)
    }

    /// Decoded RGB power.
    #[inline]
    pub fn power(&self) -> Vec3 {
        decode_power(self.power)
    }

    /// Decoded unit direction of travel.
    #[inline]
    pub fn dir(&self) -> Vec3 {
        decode_dir(self.dir)
    }

    /// True when the photon travels against `n` (`dot(dir, n) < 0`): it arrived on the side
    /// `n` points to. Cheaper than `dir().dot(n) < 0.0` (no normalisation).
    #[inline]
    pub fn arrives_against(&self, n: Vec3) -> bool {
        decode_dir_unnormalized(self.dir).dot(n) < 0.0
    }

    /// The flag byte given to [`Photon::new`] (with the bounce in its high bits, see
    /// [`Photon::with_bounce`]).
    #[inline]
    pub fn flags(&self) -> u8 {
        self.flags
    }

    /// Largest bounce stored: [`Photon::bounce`] `MAX_BOUNCE` means this many or more.
    pub const MAX_BOUNCE: u8 = 15;

    /// The photon with its bounce recorded: stored at its `b`-th surface hit, 0 straight
    /// from the light (at most [`Photon::MAX_BOUNCE`], which stands for it and any more).
    /// Kept in the flag byte's high four bits, which the flags leave free.
    pub fn with_bounce(mut self, b: u32) -> Self {
        let b = b.min(Self::MAX_BOUNCE as u32) as u8;
        self.flags = (self.flags & 0x0f) | (b << 4);
        self
    }

    /// The bounce given to [`Photon::with_bounce`] (0 when none was).
    #[inline]
    pub fn bounce(&self) -> u8 {
        self.flags >> 4
    }

    /// True when every bit of `flag` is set.
    #[inline]
    pub fn has(&self, flag: u8) -> bool {
        self.flags & flag == flag
    }
}

/// `2^e` as an `f32`, for `e` in the normal range `-126..=127`.
#[inline]
fn exp2i(e: i32) -> f32 {
    f32::from_bits(((e + 127) as u32) << 23)
}

/// Packs an RGB power into three 11-bit mantissas and a shared 7-bit exponent (40 bits,
/// little endian: r in bits 0..11, g in 11..22, b in 22..33, exponent in 33..40).
fn encode_power(c: Vec3) -> [u8; 5] {
    // Largest representable channel value: 2047 * 2^(EXP_MAX - 11).
    let max_value = MANT_MAX as f32 * exp2i(EXP_MAX - MANT_BITS as i32);
    let clean = |x: f32| if x > 0.0 { x.min(max_value) } else { 0.0 };
    let c = [clean(c.x), clean(c.y), clean(c.z)];
    let max = c[0].max(c[1]).max(c[2]);
    if max < exp2i(EXP_MIN - MANT_BITS as i32 - 1) {
        return [0; 5];
    }
    // e such that max < 2^e (max is a normal f32 here): floor(log2 max) + 1.
    let mut e = (((max.to_bits() >> 23) & 0xff) as i32 - 127 + 1).max(EXP_MIN);
    let quantise = |e: i32| c.map(|x| (x * exp2i(MANT_BITS as i32 - e)).round() as u32);
    let mut m = quantise(e);
    if m.iter().any(|&v| v > MANT_MAX) {
        // Rounding carried into bit 11: one exponent up (max_value keeps e within range).
        e = (e + 1).min(EXP_MAX);
        m = quantise(e).map(|v| v.min(MANT_MAX));
    }
    let stored = (e - EXP_MIN) as u64;
    let bits = m[0] as u64 | (m[1] as u64) << 11 | (m[2] as u64) << 22 | stored << 33;
    let b = bits.to_le_bytes();
    [b[0], b[1], b[2], b[3], b[4]]
}

/// Inverse of [`encode_power`].
#[inline]
fn decode_power(p: [u8; 5]) -> Vec3 {
    let bits = u64::from_le_bytes([p[0], p[1], p[2], p[3], p[4], 0, 0, 0]);
    let e = (bits >> 33) as i32 + EXP_MIN;
    let scale = exp2i(e - MANT_BITS as i32);
    let mask = MANT_MAX as u64;
    Vec3::new(
        (bits & mask) as f32,
        ((bits >> 11) & mask) as f32,
        ((bits >> 22) & mask) as f32,
    ) * scale
}

/// `±1` with the sign of `x`, `+1` for zero.
#[inline]
fn sign_not_zero(x: f32) -> f32 {
    if x >= 0.0 {
        1.0
    } else {
        -1.0
    }
}

/// Octahedral projection of a unit vector to `[-1, 1]^2`.
fn oct_project(d: Vec3) -> [f32; 2] {
    let l1 = d.x.abs() + d.y.abs() + d.z.abs();
    if !(l1 > 0.0 && l1.is_finite()) {
        return [0.0, 0.0]; // degenerate input: store +z
    }
    let (x, y) = (d.x / l1, d.y / l1);
    if d.z >= 0.0 {
        [x, y]
    } else {
        [
            (1.0 - y.abs()) * sign_not_zero(x),
            (1.0 - x.abs()) * sign_not_zero(y),
        ]
    }
}

/// Encodes a unit direction into two bytes: of the 4 codes around its octahedral projection,
/// the one whose decoded direction is closest (largest dot product).
fn encode_dir(d: Vec3) -> [u8; 2] {
    let [u, v] = oct_project(d);
    let to_grid = |x: f32| ((x.clamp(-1.0, 1.0) * 0.5 + 0.5) * 255.0).floor();
    let (gu, gv) = (to_grid(u), to_grid(v));
    let mut best = [0u8; 2];
    let mut best_dot = f32::NEG_INFINITY;
    for (du, dv) in [(0.0, 0.0), (1.0, 0.0), (0.0, 1.0), (1.0, 1.0)] {
        let code = [(gu + du).min(255.0) as u8, (gv + dv).min(255.0) as u8];
        let dot = decode_dir(code).dot(d);
        if dot > best_dot {
            best_dot = dot;
            best = code;
        }
    }
    best
}

/// Inverse of [`encode_dir`]: a unit vector.
#[inline]
fn decode_dir(code: [u8; 2]) -> Vec3 {
    decode_dir_unnormalized(code).normalize()
}

/// The decoded direction before normalisation (the point on the octahedron).
#[inline]
fn decode_dir_unnormalized(code: [u8; 2]) -> Vec3 {
    let x = code[0] as f32 * (2.0 / 255.0) - 1.0;
    let y = code[1] as f32 * (2.0 / 255.0) - 1.0;
    let z = 1.0 - x.abs() - y.abs();
    let (x, y) = if z < 0.0 {
        (
            (1.0 - y.abs()) * sign_not_zero(x),
            (1.0 - x.abs()) * sign_not_zero(y),
        )
    } else {
        (x, y)
    };
    Vec3::new(x, y, z)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// xorshift64* for reproducible test inputs.
    fn rng(state: &mut u64) -> f32 {
        *state ^= *state >> 12;
        *state ^= *state << 25;
        *state ^= *state >> 27;
        ((state.wrapping_mul(0x2545_f491_4f6c_dd1d) >> 40) as f32) / (1u64 << 24) as f32
    }

    #[test]
    fn bounce_rides_in_the_high_bits_and_saturates() {
        let p = Photon::new(
            Vec3::ONE,
            Vec3::ONE,
            Vec3::Z,
            Photon::CAUSTIC | Photon::ON_GLOSSY,
        );
        assert_eq!(p.bounce(), 0);
        for b in [0u32, 1, 7, 14, 15] {
            let q = p.with_bounce(b);
            assert_eq!(q.bounce() as u32, b);
            assert!(q.has(Photon::CAUSTIC | Photon::ON_GLOSSY) && !q.has(Photon::DIRECT));
            assert_eq!(q.flags() & 0x0f, Photon::CAUSTIC | Photon::ON_GLOSSY);
        }
        assert_eq!(p.with_bounce(16).bounce(), Photon::MAX_BOUNCE);
        assert_eq!(p.with_bounce(9).with_bounce(2).bounce(), 2);
    }

    #[test]
    fn record_is_at_most_20_bytes() {
        assert_eq!(std::mem::size_of::<Photon>(), 20);
        assert!(std::mem::size_of::<Photon>() <= 20);
    }

    #[test]
    fn power_round_trip_within_2_pow_minus_11_of_max_channel() {
        let mut s = 0x1234_5678_9abc_def1u64;
        let mut worst = 0.0f32;
        for i in 0..200_000 {
            // Magnitudes spread over 1e-18 .. 1e18, channels independent (some zero).
            let scale = 10f32.powf(rng(&mut s) * 36.0 - 18.0);
            let mut c = Vec3::new(rng(&mut s), rng(&mut s), rng(&mut s)) * scale;
            if i % 7 == 0 {
                c.y = 0.0;
            }
            let back = Photon::new(Vec3::ZERO, c, Vec3::Z, 0).power();
            let max = c.max_element();
            let err = (back - c).abs().max_element() / max;
            worst = worst.max(err);
            assert!(
                err <= 2f32.powi(-11) * 1.0001,
                "{c:?} -> {back:?} (rel {err})"
            );
        }
        println!(
            "worst power relative error {worst:e} (bound {:e})",
            2f32.powi(-11)
        );
        // Exact cases: zero, powers of two, small integers.
        for c in [Vec3::ZERO, Vec3::ONE, Vec3::new(1000.0, 3.0, 0.5)] {
            assert_eq!(Photon::new(Vec3::ZERO, c, Vec3::Z, 0).power(), c);
        }
    }

    #[test]
    fn power_handles_bad_and_extreme_input() {
        let p = |c: Vec3| Photon::new(Vec3::ZERO, c, Vec3::Z, 0).power();
        assert_eq!(p(Vec3::new(f32::NAN, -1.0, 0.0)), Vec3::ZERO);
        let inf = p(Vec3::new(f32::INFINITY, 1.0, 0.0));
        assert!(inf.is_finite() && inf.x > 9e18, "{inf:?}");
        assert_eq!(p(Vec3::splat(1e-30)), Vec3::ZERO);
        // Rounding that carries into the next exponent: 2047.9 rounds up to 2048.
        let c = Vec3::new(2047.9, 1.0, 0.0);
        assert!((p(c) - c).abs().max_element() <= 2048.0 * 2f32.powi(-11));
    }

    #[test]
    fn dir_round_trip_error() {
        let mut worst = 0.0f32;
        let n = 800;
        for i in 0..n {
            for j in 0..2 * n {
                let cos_t = 1.0 - 2.0 * (i as f32 + 0.5) / n as f32;
                let sin_t = (1.0 - cos_t * cos_t).max(0.0).sqrt();
                let phi = std::f32::consts::PI * (j as f32 + 0.37) / n as f32;
                let d = Vec3::new(sin_t * phi.cos(), sin_t * phi.sin(), cos_t).normalize();
                let back = Photon::new(Vec3::ZERO, Vec3::ONE, d, 0).dir();
                assert!((back.length() - 1.0).abs() < 1e-5);
                let ang = d.dot(back).clamp(-1.0, 1.0).acos().to_degrees();
                worst = worst.max(ang);
            }
        }
        // Axis directions and the octahedron's edges.
        for d in [Vec3::X, -Vec3::X, Vec3::Y, -Vec3::Y, Vec3::Z, -Vec3::Z] {
            let back = Photon::new(Vec3::ZERO, Vec3::ONE, d, 0).dir();
            worst = worst.max(d.dot(back).clamp(-1.0, 1.0).acos().to_degrees());
        }
        println!("worst direction error {worst} degrees");
        assert!(worst <= MAX_DIR_ERROR_DEG, "{worst} degrees");
    }

    #[test]
    fn position_and_flags_are_exact() {
        let pos = Vec3::new(1e-4, -3.25e4, 7.0);
        let p = Photon::new(pos, Vec3::ONE, -Vec3::Z, Photon::CAUSTIC);
        assert_eq!(p.pos(), pos);
        assert!(p.has(Photon::CAUSTIC) && !p.has(Photon::DIRECT));
        assert_eq!(p.flags(), 1);
        assert!(p.arrives_against(Vec3::Z) && !p.arrives_against(-Vec3::Z));
        // A degenerate direction does not produce NaN.
        let q = Photon::new(pos, Vec3::ONE, Vec3::ZERO, 0);
        assert!(q.dir().is_finite());
    }
}
