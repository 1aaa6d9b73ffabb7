//! The closed-form return map of the tuned linear model, eq. 17 (Koditschek & Bühler 1991,
//! sec. 3.3, appendix A.1), in eq. 16's normalized energy at the bottom,
//! E = eta1 (x - chi_eq)^2 (m^2/s^2):
//!
//! f(E) = ([sqrt(E) - psi_t]^2 + psi_t'^2) exp{-2 beta [pi - arctan(psi_t' / (sqrt(E) - psi_t))]}
//!
//! with the normalized thrust vector (psi_t, psi_t') = W (chi_t, chi_t') of eq. 25 and the
//! thrust displacement from rest of eq. 24, re-derived (`docs/hopper.md`: the paper prints
//! 1/(2 omega^2 beta^2) and e^{-2 beta delta}; direct integration gives 1/gamma^2 and
//! e^{-gamma delta}, gamma = 2 omega beta). It is exact for the tuned model
//! (chi_l = chi_eq = chi_0 - g/eta1) with thrust that starts exactly at the bottom.
//!
//! The sampled plant's fixed-point error is measured against it (`sampled`); the CLI's
//! comparison (`apps::hopper::closed`) has its own copy.

use std::f64::consts::PI;

/// Eq. 17 for one parameter set.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Eq17 {
    beta: f64,
    psi: f64,
    psi_dot: f64,
}

impl Eq17 {
    /// From omega (rad/s, > 0), beta (>= 0), delta (s) and eq. 16's net thrust
    /// tau16 = tau - g (m/s^2).
    pub fn new(omega: f64, beta: f64, delta_s: f64, net_thrust_mps2: f64) -> Self {
        let gamma = 2.0 * omega * beta;
        let gd = gamma * delta_s;
        let a = net_thrust_mps2;
        // eq. 24 re-derived: from rest, chi'' = a - gamma chi' for delta
        let (chi_t, chi_dot_t) = if gd < 1e-6 {
            (
                a * delta_s * delta_s / 2.0 * (1.0 - gd / 3.0),
                a * delta_s * (1.0 - gd / 2.0),
            )
        } else {
            (
                a / (gamma * gamma) * (gd + (-gd).exp_m1()),
                -a / gamma * (-gd).exp_m1(),
            )
        };
        // eq. 25: W (chi_t, chi_t')
        let s = (1.0 + beta * beta).sqrt();
        Self {
            beta,
            psi: omega * s * chi_t + beta / s * chi_dot_t,
            psi_dot: chi_dot_t / s,
        }
    }

    /// f(E), m^2/s^2; NaN where the thrust would not end in stance (sqrt(E) <= psi_t).
    pub fn f(&self, energy: f64) -> f64 {
        let r = energy.sqrt();
        if r <= self.psi {
            return f64::NAN;
        }
        let angle = (self.psi_dot / (r - self.psi)).atan();
        ((r - self.psi).powi(2) + self.psi_dot.powi(2)) * (-2.0 * self.beta * (PI - angle)).exp()
    }

    /// The interior fixed point E* (unique, Lemma 5), by bracketing f(E) - E from the
    /// domain's start upward and bisecting to adjacent floats; `None` if there is none.
    pub fn fixed_point(&self) -> Option<f64> {
        let above = |e: f64| self.f(e) > e;
        let mut lo = (self.psi * self.psi * (1.0 + 1e-12)).max(f64::MIN_POSITIVE);
        if !above(lo) {
            return None;
        }
        let mut hi = lo;
        for _ in 0..4000 {
            hi *= 1.5;
            if !above(hi) {
                break;
            }
            lo = hi;
        }
        if above(hi) {
            return None;
        }
        for _ in 0..2000 {
            let mid = 0.5 * (lo + hi);
            if mid <= lo || mid >= hi {
                break;
            }
            if above(mid) {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        Some(0.5 * (lo + hi))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fig2_parameters_have_a_stable_interior_fixed_point() {
        // fig. 2: omega = 20, beta = 0.2, delta = 0.01, tau = 1
        let m = Eq17::new(20.0, 0.2, 0.01, 1.0);
        let e = m.fixed_point().unwrap();
        assert!((m.f(e) - e).abs() <= 1e-12 * e);
        // slope by central difference: |f'| < 1 (Theorem 2)
        let h = 1e-6 * e;
        let slope = (m.f(e + h) - m.f(e - h)) / (2.0 * h);
        assert!(slope.abs() < 1.0, "{slope}");
    }

    #[test]
    fn without_friction_thrust_from_rest_is_by_hand() {
        // beta = 0: chi_t = a delta^2 / 2, chi_t' = a delta; psi = omega chi_t, psi' = chi_t'
        let m = Eq17::new(10.0, 0.0, 0.1, 2.0);
        assert!((m.psi - 10.0 * 0.01).abs() < 1e-15);
        assert!((m.psi_dot - 0.2).abs() < 1e-15);
        // lossless: f(E) = (r - psi)^2 + psi'^2 = E at r* = (psi^2 + psi'^2) / (2 psi) = 0.25
        let e = m.fixed_point().unwrap();
        assert!((e - 0.0625).abs() < 1e-12, "{e}");
    }
}
