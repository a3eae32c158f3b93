//! [`Spectrum`]: the value a path carries (throughput, a BSDF's `f`, emitted radiance), four
//! lanes wide.
//!
//! In a spectral render the lanes are radiance at the camera sample's four wavelengths
//! ([`super::Lambda`]). In an RGB render the lanes are red, green, blue and green again: every
//! lane-wise operation keeps the fourth lane equal to the second, so no lane divides zero by
//! zero, and [`Spectrum::max_element`], [`Spectrum::min_element`] and `is_finite` mean what they
//! mean for RGB. Only [`super::Lambda`] turns RGB into a spectrum and back ([`Spectrum::rgb`]
//! and [`Spectrum::from_rgb`] are for code that renders in RGB only).
use crate::math::Vec3;
use glam::Vec4;
use std::ops::{Add, AddAssign, Div, DivAssign, Mul, MulAssign, Neg, Sub, SubAssign};

/// Four lanes of radiance (or of a factor of it); see the module docs.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Spectrum(pub Vec4);

impl Spectrum {
    pub const ZERO: Spectrum = Spectrum(Vec4::ZERO);
    pub const ONE: Spectrum = Spectrum(Vec4::ONE);

    /// Every lane `v`.
    #[inline]
    pub const fn splat(v: f32) -> Spectrum {
        Spectrum(Vec4::splat(v))
    }

    /// Lane by lane.
    #[inline]
    pub fn from_array(a: [f32; 4]) -> Spectrum {
        Spectrum(Vec4::from_array(a))
    }

    #[inline]
    pub fn to_array(self) -> [f32; 4] {
        self.0.to_array()
    }

    /// An RGB value as an RGB render carries it (red, green, blue, green).
    #[inline]
    pub fn from_rgb(c: Vec3) -> Spectrum {
        Spectrum(Vec4::new(c.x, c.y, c.z, c.y))
    }

    /// The RGB an RGB render's value holds (its first three lanes).
    #[inline]
    pub fn rgb(self) -> Vec3 {
        self.0.truncate()
    }

    /// `f` of each lane.
    #[inline]
    pub fn map(self, f: impl Fn(f32) -> f32) -> Spectrum {
        Spectrum(self.0.map(f))
    }

    #[inline]
    pub fn max_element(self) -> f32 {
        self.0.max_element()
    }

    #[inline]
    pub fn min_element(self) -> f32 {
        self.0.min_element()
    }

    #[inline]
    pub fn is_finite(self) -> bool {
        self.0.is_finite()
    }

    #[inline]
    pub fn is_nan(self) -> bool {
        self.0.is_nan()
    }

    /// Every lane zero.
    #[inline]
    pub fn is_black(self) -> bool {
        self.0 == Vec4::ZERO
    }

    #[inline]
    pub fn max(self, o: Spectrum) -> Spectrum {
        Spectrum(self.0.max(o.0))
    }

    #[inline]
    pub fn abs(self) -> Spectrum {
        Spectrum(self.0.abs())
    }

    #[inline]
    pub fn exp(self) -> Spectrum {
        Spectrum(self.0.exp())
    }

    #[inline]
    pub fn sqrt(self) -> Spectrum {
        self.map(f32::sqrt)
    }
}

impl std::ops::Index<usize> for Spectrum {
    type Output = f32;
    /// Lane `i` (0-3).
    fn index(&self, i: usize) -> &f32 {
        &self.0[i]
    }
}

impl std::fmt::Display for Spectrum {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}", self.0)
    }
}

impl Add for Spectrum {
    type Output = Spectrum;
    #[inline]
    fn add(self, o: Spectrum) -> Spectrum {
        Spectrum(self.0 + o.0)
    }
}

impl Sub for Spectrum {
    type Output = Spectrum;
    #[inline]
    fn sub(self, o: Spectrum) -> Spectrum {
        Spectrum(self.0 - o.0)
    }
}

impl Mul for Spectrum {
    type Output = Spectrum;
    #[inline]
    fn mul(self, o: Spectrum) -> Spectrum {
        Spectrum(self.0 * o.0)
    }
}

impl Mul<f32> for Spectrum {
    type Output = Spectrum;
    #[inline]
    fn mul(self, s: f32) -> Spectrum {
        Spectrum(self.0 * s)
    }
}

impl Mul<Spectrum> for f32 {
    type Output = Spectrum;
    #[inline]
    fn mul(self, s: Spectrum) -> Spectrum {
        Spectrum(s.0 * self)
    }
}

impl Div for Spectrum {
    type Output = Spectrum;
    #[inline]
    fn div(self, o: Spectrum) -> Spectrum {
        Spectrum(self.0 / o.0)
    }
}

impl Div<f32> for Spectrum {
    type Output = Spectrum;
    #[inline]
    fn div(self, s: f32) -> Spectrum {
        Spectrum(self.0 / s)
    }
}

impl Neg for Spectrum {
    type Output = Spectrum;
    #[inline]
    fn neg(self) -> Spectrum {
        Spectrum(-self.0)
    }
}

impl AddAssign for Spectrum {
    #[inline]
    fn add_assign(&mut self, o: Spectrum) {
        self.0 += o.0;
    }
}

impl SubAssign for Spectrum {
    #[inline]
    fn sub_assign(&mut self, o: Spectrum) {
        self.0 -= o.0;
    }
}

impl MulAssign for Spectrum {
    #[inline]
    fn mul_assign(&mut self, o: Spectrum) {
        self.0 *= o.0;
    }
}

impl MulAssign<f32> for Spectrum {
    #[inline]
    fn mul_assign(&mut self, s: f32) {
        self.0 *= s;
    }
}

impl DivAssign<f32> for Spectrum {
    #[inline]
    fn div_assign(&mut self, s: f32) {
        self.0 /= s;
    }
}

impl std::iter::Sum for Spectrum {
    fn sum<I: Iterator<Item = Spectrum>>(it: I) -> Spectrum {
        it.fold(Spectrum::ZERO, |a, b| a + b)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// An RGB value's fourth lane stays its green through every lane-wise operation, so the
    /// reductions mean what they mean for RGB.
    #[test]
    fn rgb_lanes_stay_rgb() {
        let a = Spectrum::from_rgb(Vec3::new(0.2, 0.5, 0.9));
        let b = Spectrum::from_rgb(Vec3::new(0.0, 2.0, 0.1));
        let c = (a * b + a / 2.0 - b.exp()) / (a + Spectrum::ONE);
        assert_eq!(c[3], c[1]);
        assert_eq!(c.rgb(), Vec3::from_array([0, 1, 2].map(|i| c[i])));
        assert_eq!(a.max_element(), 0.9);
        assert_eq!(b.min_element(), 0.0);
        assert!((b / b).is_nan());
        assert!(!(a / a).is_nan());
    }
}
