//! Fresnel reflectance and the two specular direction maps (mirror reflection and Snell
//! refraction), following pbrt-v4's conventions:
//!
//! - `eta` is the relative index of refraction, interior over exterior (the side the normal
//!   points to is the exterior);
//! - a negative `cos_theta_i` means the ray arrives from the interior, and the functions flip
//!   `eta` themselves.
use crate::math::Vec3;
use crate::spectrum::Spectrum;

/// Exact unpolarised Fresnel reflectance of a smooth dielectric interface.
///
/// - `cos_theta_i`: cosine between the incident direction and the normal; negative when the
///   direction lies on the interior side (then the relative index is `1 / eta`);
/// - `eta`: interior / exterior index of refraction (> 0).
///
/// Returns 1 under total internal reflection and 0 when `eta == 1` (no interface).
pub fn fr_dielectric(cos_theta_i: f32, eta: f32) -> f32 {
    if eta == 1.0 {
        return 0.0;
    }
    let cos_i = cos_theta_i.clamp(-1.0, 1.0);
    let inside = cos_i < 0.0;
    let cos_i = cos_i.abs();
    let Some(cos_t) = cos_transmitted(cos_i, eta, inside) else {
        return 1.0;
    };
    // With the relative index e (eta outside, 1/eta inside):
    // r_parl = (e cos_i - cos_t) / (e cos_i + cos_t), r_perp = (cos_i - e cos_t) / (cos_i + e cos_t).
    // Inside, both are multiplied through by eta so that 1/eta is never rounded.
    let (r_parl, r_perp) = if inside {
        (
            (cos_i - eta * cos_t) / (cos_i + eta * cos_t),
            (eta * cos_i - cos_t) / (eta * cos_i + cos_t),
        )
    } else {
        (
            (eta * cos_i - cos_t) / (eta * cos_i + cos_t),
            (cos_i - eta * cos_t) / (cos_i + eta * cos_t),
        )
    };
    0.5 * (r_parl * r_parl + r_perp * r_perp)
}

/// Cosine of the refracted angle, or `None` under total internal reflection.
///
/// - `cos_i`: incident cosine, non-negative;
/// - `eta`: interior / exterior index;
/// - `inside`: the incident direction is on the interior side (relative index `1 / eta`).
///
/// Evaluates pbrt's `1 - sin^2(theta_i) / e^2` as `(cos_i^2 + (eta - 1)(eta + 1)) / eta^2`
/// outside and `cos_i^2 eta^2 - (eta - 1)(eta + 1)` inside: the same quantity, but exact for
/// `eta == 1` at grazing angles (where `1 - cos_i^2` rounds to 1 and would report a spurious
/// total internal reflection) and free of the cancellation of `eta^2 - 1` near the critical
/// angle when `eta` is close to 1.
fn cos_transmitted(cos_i: f32, eta: f32, inside: bool) -> Option<f32> {
    let d = (eta - 1.0) * (eta + 1.0);
    let cos2_t = if inside {
        cos_i * cos_i * (eta * eta) - d
    } else {
        (cos_i * cos_i + d) / (eta * eta)
    };
    if cos2_t <= 0.0 {
        None
    } else {
        Some(cos2_t.min(1.0).sqrt())
    }
}

/// Exact unpolarised Fresnel reflectance of a conductor with complex index `eta + i k`, per
/// RGB channel (pbrt-v4's `FrComplex`), in the real closed form of pbrt-v3's `FrConductor`
/// (two square roots per channel instead of complex divisions and `hypot`: the estimate of
/// caustic photons on rough metal evaluates it once per photon). Checked against the complex
/// form in the tests.
///
/// - `cos_theta_i`: incident cosine, clamped to `[0, 1]` (conductors are opaque: the ray is
///   always on the exterior side);
/// - `eta`, `k`: real and imaginary parts of the relative index, per channel.
pub fn fr_complex(cos_theta_i: f32, eta: Spectrum, k: Spectrum) -> Spectrum {
    let cos = cos_theta_i.clamp(0.0, 1.0);
    let cos2 = cos * cos;
    let sin2 = 1.0 - cos2;
    let (eta2, k2) = (eta * eta, k * k);
    let t0 = eta2 - k2 - Spectrum::splat(sin2);
    // a^2 + b^2 = |(eta + i k)^2 - sin^2|, a = Re sqrt((eta + i k)^2 - sin^2).
    let a2b2 = (t0 * t0 + 4.0 * eta2 * k2).max(Spectrum::ZERO).sqrt();
    let a = (0.5 * (a2b2 + t0)).max(Spectrum::ZERO).sqrt();
    let t1 = a2b2 + Spectrum::splat(cos2);
    let t2 = 2.0 * cos * a;
    let rs = (t1 - t2) / (t1 + t2);
    let t3 = cos2 * a2b2 + Spectrum::splat(sin2 * sin2);
    let t4 = t2 * sin2;
    let rp = rs * (t3 - t4) / (t3 + t4);
    let r = 0.5 * (rp + rs);
    // 0/0 only for cos = 0 with a = 0 (eta = 1, k = 0 at grazing): total reflection.
    r.map(|x| if x.is_nan() { 1.0 } else { x })
}

/// Schlick's approximation `r0 + (1 - r0) (1 - cos)^5` of the Fresnel reflectance.
///
/// - `r0`: reflectance at normal incidence;
/// - `cos_theta`: incident cosine in `[0, 1]` (clamped).
pub fn schlick(r0: f32, cos_theta: f32) -> f32 {
    let m = (1.0 - cos_theta.clamp(0.0, 1.0)).powi(5);
    r0 + (1.0 - r0) * m
}

/// Mirror reflection of `wo` about the normal `n` (both unit; `wo` points away from the
/// surface and so does the result).
pub fn reflect(wo: Vec3, n: Vec3) -> Vec3 {
    -wo + 2.0 * wo.dot(n) * n
}

/// Snell refraction of `wi` (unit, pointing away from the surface) through the interface with
/// unit normal `n` and relative index `eta` (interior / exterior; `n` points to the exterior).
///
/// Returns the unit transmitted direction (pointing away from the surface on the other side)
/// and the relative index actually crossed (`eta`, or `1 / eta` when `wi` is on the interior
/// side), or `None` under total internal reflection.
pub fn refract(wi: Vec3, n: Vec3, eta: f32) -> Option<(Vec3, f32)> {
    let cos_i = n.dot(wi);
    let inside = cos_i < 0.0;
    let cos_t = cos_transmitted(cos_i.abs().min(1.0), eta, inside)?;
    // wt = -wi / e + (cos_i / e - cos_t) n with e the relative index and n facing wi.
    Some(if inside {
        let wt = -wi * eta + (-cos_i * eta - cos_t) * -n;
        (wt, 1.0 / eta)
    } else {
        let wt = -wi / eta + (cos_i / eta - cos_t) * n;
        (wt, eta)
    })
}

#[cfg(test)]
mod tests {
    // The complex form (pbrt-v4's FrComplex) in f64, as an independent check of fr_complex.
    /// A minimal complex number for the conductor Fresnel equations.
    #[derive(Clone, Copy, Debug, PartialEq)]
    pub(super) struct Complex {
        re: f64,
        im: f64,
    }

    impl Complex {
        fn new(re: f64, im: f64) -> Self {
            Complex { re, im }
        }

        fn real(re: f64) -> Self {
            Complex { re, im: 0.0 }
        }

        fn add(self, o: Complex) -> Complex {
            Complex::new(self.re + o.re, self.im + o.im)
        }

        fn sub(self, o: Complex) -> Complex {
            Complex::new(self.re - o.re, self.im - o.im)
        }

        fn mul(self, o: Complex) -> Complex {
            Complex::new(
                self.re * o.re - self.im * o.im,
                self.re * o.im + self.im * o.re,
            )
        }

        fn div(self, o: Complex) -> Complex {
            let scale = 1.0 / (o.re * o.re + o.im * o.im);
            Complex::new(
                scale * (self.re * o.re + self.im * o.im),
                scale * (self.im * o.re - self.re * o.im),
            )
        }

        /// Squared magnitude `|z|^2`.
        fn norm(self) -> f64 {
            self.re * self.re + self.im * self.im
        }

        /// Principal square root (non-negative real part).
        fn sqrt(self) -> Complex {
            let n = self.re.hypot(self.im);
            if n == 0.0 {
                return Complex::real(0.0);
            }
            let t1 = (0.5 * (n + self.re.abs())).sqrt();
            let t2 = 0.5 * self.im / t1;
            if self.re >= 0.0 {
                Complex::new(t1, t2)
            } else {
                Complex::new(t2.abs(), t1.copysign(self.im))
            }
        }
    }

    /// Exact Fresnel reflectance of one channel for a complex relative index `eta + i k`.
    fn fr_complex_channel(cos_i: f64, eta: Complex) -> f64 {
        let sin2_i = (1.0 - cos_i * cos_i).max(0.0);
        let sin2_t = Complex::real(sin2_i).div(eta.mul(eta));
        let cos_t = Complex::real(1.0).sub(sin2_t).sqrt();
        let ci = Complex::real(cos_i);
        let r_parl = eta.mul(ci).sub(cos_t).div(eta.mul(ci).add(cos_t));
        let r_perp = ci.sub(eta.mul(cos_t)).div(ci.add(eta.mul(cos_t)));
        0.5 * (r_parl.norm() + r_perp.norm())
    }

    fn fr_complex_reference(cos: f32, eta: f32, k: f32) -> f32 {
        let c = (cos as f64).clamp(0.0, 1.0);
        fr_complex_channel(c, Complex::new(eta as f64, k as f64)) as f32
    }

    #[test]
    fn closed_form_matches_the_complex_form() {
        let mut worst = 0.0f32;
        for &(eta, k) in &[
            (0.2f32, 3.9f32),
            (1.66, 9.22),
            (2.87, 3.03),
            (0.05, 0.0),
            (1.0, 0.0),
            (1.5, 0.0),
            (0.7, 0.0),
            (1.0, 1e-4),
            (4.0, 40.0),
        ] {
            for i in 0..=1000 {
                let c = i as f32 / 1000.0;
                let got = fr_complex(c, Spectrum::splat(eta), Spectrum::splat(k))[0];
                let want = fr_complex_reference(c, eta, k);
                if k == 0.0 && eta < 1.0 && (c * c - (1.0 - eta * eta)).abs() < 1e-3 {
                    continue; // the critical angle's infinite slope
                }
                if want.is_nan() {
                    // eta = 1, k = 0 at grazing: 0/0 in the complex form, 1 in ours.
                    assert_eq!(got, 1.0);
                    continue;
                }
                worst = worst.max((got - want).abs());
                assert!(
                    (got - want).abs() < 2e-5,
                    "eta {eta} k {k} cos {c}: {got} vs {want}"
                );
            }
        }
        println!("worst difference {worst:e}");
    }

    use super::*;
    use crate::bsdf::testutil::Rng;

    /// Independent Fresnel transmittance from the amplitude transmission coefficients
    /// (Hecht): T = (n2 cos_t)/(n1 cos_i) * (t_s^2 + t_p^2) / 2, in f64.
    fn transmittance_from_amplitudes(cos_i: f64, n1: f64, n2: f64) -> f64 {
        let sin_t = n1 / n2 * (1.0 - cos_i * cos_i).sqrt();
        if sin_t >= 1.0 {
            return 0.0;
        }
        let cos_t = (1.0 - sin_t * sin_t).sqrt();
        let ts = 2.0 * n1 * cos_i / (n1 * cos_i + n2 * cos_t);
        let tp = 2.0 * n1 * cos_i / (n2 * cos_i + n1 * cos_t);
        (n2 * cos_t) / (n1 * cos_i) * 0.5 * (ts * ts + tp * tp)
    }

    const ETAS: [f32; 6] = [1.0001, 1.2, 1.33, 1.5, 2.4, 3.5];

    #[test]
    fn dielectric_r_plus_t_is_one_both_sides() {
        let mut worst = (0.0f64, 0.0f32, 0.0f32);
        for &eta in &ETAS {
            for i in 0..=200 {
                let c = (i as f32 / 200.0).max(1e-3);
                // Outside: n1 = 1, n2 = eta.
                let r = fr_dielectric(c, eta) as f64;
                let t = transmittance_from_amplitudes(c as f64, 1.0, eta as f64);
                let d = (r + t - 1.0).abs();
                if d > worst.0 {
                    worst = (d, c, eta);
                }
                // Inside: n1 = eta, n2 = 1 (TIR gives t = 0).
                let r = fr_dielectric(-c, eta) as f64;
                let t = transmittance_from_amplitudes(c as f64, eta as f64, 1.0);
                let d = (r + t - 1.0).abs();
                if d > worst.0 {
                    worst = (d, -c, eta);
                }
            }
        }
        println!("max |R + T - 1| over the sweep: {worst:?}");
        assert!(worst.0 < 2e-5, "R + T deviates by {worst:?}");
    }

    #[test]
    fn dielectric_normal_incidence() {
        for &eta in &ETAS {
            let want = ((eta - 1.0) / (eta + 1.0)).powi(2);
            for c in [1.0f32, -1.0] {
                let r = fr_dielectric(c, eta);
                assert!((r - want).abs() < 1e-6, "eta {eta} cos {c}: {r} vs {want}");
            }
        }
        assert!((fr_dielectric(1.0, 1.5) - 0.04).abs() < 1e-6);
    }

    #[test]
    fn eta_one_is_invisible() {
        let cosines = [1.0f32, 0.9, 0.5, 0.1, 1e-3, 1e-5, 1e-7];
        for &c in &cosines {
            for s in [c, -c] {
                assert_eq!(fr_dielectric(s, 1.0), 0.0, "cos {s}");
                // Also through the general code path with eta a hair away from 1 (only away
                // from grazing: at grazing even a tiny contrast reflects strongly).
                if s.abs() >= 0.1 {
                    assert!(fr_dielectric(s, 1.0 + 1e-6) < 1e-7, "cos {s}");
                }
                let sin = (1.0 - s * s).max(0.0).sqrt();
                let wo = Vec3::new(sin, 0.0, s).normalize();
                let (wt, etap) = refract(wo, Vec3::Z, 1.0).expect("no TIR at eta 1");
                assert!((wt + wo).length() < 1e-6, "cos {s}: {wt:?} vs {:?}", -wo);
                assert_eq!(etap, 1.0);
            }
        }
    }

    #[test]
    fn total_internal_reflection_past_critical_angle() {
        for &eta in &[1.2f32, 1.33, 1.5, 2.4] {
            let crit = (1.0 / eta as f64).asin();
            for (scale, tir) in [(1.0 - 1e-4, false), (1.0 + 1e-4, true), (0.5, false)] {
                let theta = crit * scale;
                let cos = theta.cos() as f32;
                let w = Vec3::new(theta.sin() as f32, 0.0, -cos);
                let r = fr_dielectric(-cos, eta);
                let refr = refract(w, Vec3::Z, eta);
                if tir {
                    assert_eq!(r, 1.0, "eta {eta} theta {theta}");
                    assert!(refr.is_none());
                } else {
                    assert!(r < 1.0, "eta {eta} theta {theta}: R = {r}");
                    assert!(refr.is_some());
                }
            }
            // Beyond the critical angle everything reflects, also at grazing.
            assert_eq!(fr_dielectric(-1e-6, eta), 1.0);
        }
    }

    #[test]
    fn grazing_from_outside_reflects_everything() {
        for &eta in &[1.33f32, 1.5, 2.4] {
            let mut prev = 0.0;
            for c in [0.5f32, 0.1, 1e-2, 1e-3, 1e-4] {
                let r = fr_dielectric(c, eta);
                assert!(r > prev, "R must grow towards grazing");
                prev = r;
            }
            assert!(prev > 0.999, "eta {eta}: R(1e-4) = {prev}");
            assert_eq!(fr_dielectric(0.0, eta), 1.0);
        }
    }

    #[test]
    fn schlick_error_bound_for_glass() {
        let eta = 1.5f32;
        let r0 = ((eta - 1.0) / (eta + 1.0)).powi(2);
        let mut worst = (0.0f32, 0.0f32);
        for i in 0..=10000 {
            let c = i as f32 / 10000.0;
            let d = (schlick(r0, c) - fr_dielectric(c, eta)).abs();
            if d > worst.0 {
                worst = (d, c);
            }
        }
        println!(
            "Schlick vs exact, eta 1.5: max |diff| = {:.5} at cos = {:.4}",
            worst.0, worst.1
        );
        assert!(worst.0 < 0.04, "Schlick error {:?}", worst);
        assert_eq!(schlick(r0, 1.0), r0);
        assert_eq!(schlick(r0, 0.0), 1.0);
    }

    /// pbrt-v3's closed-form conductor Fresnel (a^2 + b^2 formulation), in f64: an independent
    /// algebraic route to the same quantity as `fr_complex`.
    fn fr_conductor_v3(cos_i: f64, eta: f64, k: f64) -> f64 {
        let cos2 = cos_i * cos_i;
        let sin2 = 1.0 - cos2;
        let (eta2, k2) = (eta * eta, k * k);
        let t0 = eta2 - k2 - sin2;
        let a2b2 = (t0 * t0 + 4.0 * eta2 * k2).sqrt();
        let t1 = a2b2 + cos2;
        let a = (0.5 * (a2b2 + t0)).max(0.0).sqrt();
        let t2 = 2.0 * cos_i * a;
        let rs = (t1 - t2) / (t1 + t2);
        let t3 = cos2 * a2b2 + sin2 * sin2;
        let t4 = t2 * sin2;
        let rp = rs * (t3 - t4) / (t3 + t4);
        0.5 * (rp + rs)
    }

    #[test]
    fn fr_complex_matches_dielectric_when_k_is_zero() {
        for &eta in &[0.5f32, 0.8, 1.33, 1.5, 2.4] {
            for i in 0..=100 {
                let c = i as f32 / 100.0;
                // At the critical angle (eta < 1) R has an infinite slope: f32 rounding of the
                // inputs alone moves it by ~1e-3, so skip its neighbourhood.
                if (c * c - (1.0 - eta * eta)).abs() < 1e-3 {
                    continue;
                }
                let want = fr_dielectric(c, eta);
                let got = fr_complex(c, Spectrum::splat(eta), Spectrum::ZERO);
                assert!(
                    (got - Spectrum::splat(want)).abs().max_element() < 1e-5,
                    "eta {eta} cos {c}: {got:?} vs {want}"
                );
            }
        }
    }

    #[test]
    fn fr_complex_normal_incidence_and_closed_form() {
        // Gold-ish, copper-ish and silver-ish indices per channel.
        let eta = Vec3::new(0.143, 0.374, 1.442);
        let k = Vec3::new(3.983, 2.385, 1.603);
        let got = fr_complex(1.0, Spectrum::from_rgb(eta), Spectrum::from_rgb(k));
        let want = ((eta - 1.0) * (eta - 1.0) + k * k) / ((eta + 1.0) * (eta + 1.0) + k * k);
        assert!(
            (got - Spectrum::from_rgb(want)).abs().max_element() < 1e-5,
            "{got:?} vs {want:?}"
        );
        let mut worst = 0.0f64;
        for i in 1..=100 {
            let c = i as f32 / 100.0;
            let f = fr_complex(c, Spectrum::from_rgb(eta), Spectrum::from_rgb(k));
            for ch in 0..3 {
                let w = fr_conductor_v3(c as f64, eta[ch] as f64, k[ch] as f64);
                worst = worst.max((f[ch] as f64 - w).abs());
            }
        }
        println!("fr_complex vs closed-form conductor Fresnel: max |diff| = {worst:.3e}");
        assert!(worst < 1e-5);
    }

    #[test]
    fn snell_law_and_reversibility() {
        let mut rng = Rng::new(7);
        for _ in 0..10000 {
            let w = rng.sphere();
            if w.z.abs() < 1e-3 {
                continue;
            }
            let eta = 1.0 + 2.0 * rng.f32();
            let Some((wt, etap)) = refract(w, Vec3::Z, eta) else {
                // Only possible from inside past the critical angle.
                assert!(w.z < 0.0 && (1.0 - w.z * w.z).sqrt() * eta >= 0.999);
                continue;
            };
            assert!((wt.length() - 1.0).abs() < 1e-5);
            assert!(wt.z * w.z < 0.0, "transmitted to the same side");
            let want_etap = if w.z > 0.0 { eta } else { 1.0 / eta };
            assert!((etap - want_etap).abs() < 1e-6);
            let sin_i = w.truncate().length();
            let sin_t = wt.truncate().length();
            assert!(
                (sin_t * etap - sin_i).abs() < 2e-5,
                "{sin_t} * {etap} vs {sin_i}"
            );
            // The tangential parts are antiparallel (plane of incidence kept).
            assert!(w.truncate().perp_dot(wt.truncate()).abs() < 1e-5);
            assert!(w.truncate().dot(wt.truncate()) <= 1e-6);
            // Back through the interface. Returning to a near-grazing direction from near the
            // critical angle is ill-conditioned in f32, so only check well-posed round trips.
            let (back, back_eta) = refract(wt, Vec3::Z, eta).expect("reverse path exists");
            assert!((back_eta * etap - 1.0).abs() < 1e-6);
            if w.z.abs() > 0.02 {
                assert!((back - w).length() < 1e-4, "{back:?} vs {w:?}");
            }
        }
    }

    #[test]
    fn reflect_is_mirror() {
        let n = Vec3::new(0.3, -0.2, 0.9).normalize();
        let wo = Vec3::new(-0.5, 0.1, 0.6).normalize();
        let r = reflect(wo, n);
        assert!((r.dot(n) - wo.dot(n)).abs() < 1e-6);
        assert!(((r + wo).cross(n)).length() < 1e-6);
        assert!((r.length() - 1.0).abs() < 1e-6);
    }
}
