//! The closed forms a scene is compared with: eq. 15/19 (simplified nonlinear model, fixed
//! thrust) and eq. 17 (linear model, exact when tuned: chi_l = chi_eq, eq. 16).

use super::HopperConfig;
use crate::model::hopper::HopperModel;
use dexter_core::hop::{
    energy_fixed_point, energy_fixed_point_slope, energy_return_map, leg_mass_factor,
    nonlinear_alpha, nonlinear_return_map,
};
use std::f64::consts::PI;

/// alpha = e^2: eq. 19's first period doubling (slope -1).
pub const ALPHA_DOUBLING: f64 = std::f64::consts::E * std::f64::consts::E;

/// Eq. 17, E_{n+1} = f(E_n), in eq. 16's normalized energy E = eta1 (x - chi_eq)^2
/// (m^2/s^2), with the normalized thrust vector (psi_t, psi_t') of eq. 25.
#[derive(Clone, Copy, Debug)]
pub struct Eq17 {
    beta: f64,
    psi: f64,
    psi_dot: f64,
}

impl Eq17 {
    /// From omega (rad/s), beta, delta (s) and eq. 16's net thrust tau16 = tau - g (m/s^2).
    pub fn new(omega: f64, beta: f64, delta: f64, tau16: f64) -> Self {
        let gamma = 2.0 * omega * beta;
        let gd = gamma * delta;
        // thrust from rest (eq. 24 re-derived, docs/hopper.md); series for small gamma delta
        let (chi_t, chi_dot_t) = if gd < 1e-6 {
            (
                tau16 * delta * delta / 2.0 * (1.0 - gd / 3.0),
                tau16 * delta * (1.0 - gd / 2.0),
            )
        } else {
            (
                tau16 / (gamma * gamma) * (gd - 1.0 + (-gd).exp()),
                tau16 / gamma * (1.0 - (-gd).exp()),
            )
        };
        let s = (1.0 + beta * beta).sqrt();
        Self {
            beta,
            psi: omega * s * chi_t + beta / s * chi_dot_t,
            psi_dot: chi_dot_t / s,
        }
    }

    /// (β, ψ_t, ψ̇_t): the damping parameter and eq. 25's normalized thrust vector (m/s).
    pub fn thrust_vector(&self) -> (f64, f64, f64) {
        (self.beta, self.psi, self.psi_dot)
    }

    /// The smallest E where eq. 17 applies (the thrust ends in stance: sqrt(E) > psi_t).
    pub fn domain_start(&self) -> f64 {
        self.psi * self.psi
    }

    /// f(E), m^2/s^2 (NaN outside its domain).
    pub fn f(&self, e: f64) -> f64 {
        let r = e.sqrt();
        if r <= self.psi {
            return f64::NAN;
        }
        ((self.psi - r).powi(2) + self.psi_dot.powi(2))
            * (-2.0 * self.beta * (PI - (self.psi_dot / (r - self.psi)).atan())).exp()
    }

    /// f'(E), by differentiating eq. 17: B(r) (r - psi - beta psi') / r, r = sqrt(E),
    /// B the exponential factor.
    pub fn slope(&self, e: f64) -> f64 {
        let r = e.sqrt();
        let b = (-2.0 * self.beta * (PI - (self.psi_dot / (r - self.psi)).atan())).exp();
        b * (r - self.psi - self.beta * self.psi_dot) / r
    }

    /// The interior fixed point (Lemma 5: unique), by a scan and bisection on f(E) - E.
    pub fn fixed_point(&self) -> Option<f64> {
        let mut lo = (self.domain_start() * (1.0 + 1e-9)).max(1e-300);
        let above = |e: f64| self.f(e) > e;
        if !above(lo) {
            return None;
        }
        let mut hi = lo;
        loop {
            hi *= 1.5;
            if hi > 1e300 {
                return None;
            }
            if !above(hi) {
                break;
            }
            lo = hi;
        }
        for _ in 0..300 {
            let mid = 0.5 * (lo + hi);
            if above(mid) {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        Some(0.5 * (lo + hi))
    }
}

/// The closed form that applies to a scene.
#[derive(Clone, Copy, Debug)]
pub enum ClosedForm {
    /// Eq. 15 in x, eq. 19 in E = ln(chi_l / x).
    Eq19 {
        /// alpha = tau chi_l mu / eta1.
        alpha: f64,
        /// tau, m/s^2.
        tau: f64,
        /// mu = (1/(1 + mu'))^2.
        mu: f64,
        /// eta1, m^2/s^2.
        eta1: f64,
        /// chi_l, m.
        chi_l: f64,
    },
    /// Eq. 17 in E = eta1 (x - chi_eq)^2.
    Eq17 {
        /// The map.
        map: Eq17,
        /// chi_eq, m.
        chi_eq: f64,
        /// eta1, 1/s^2.
        eta1: f64,
        /// chi_l - chi_eq, m (0 when tuned, eq. 16).
        detuning_m: f64,
    },
}

/// Largest detuning |chi_l - chi_eq|, as a fraction of eq. 17's compression depth
/// sqrt(E* / eta1), for which an untuned linear scene is still compared with eq. 17
/// (approximately; figs. 9 and 10: 0.02 and 1e-4; fig. 8: 1.7, not compared).
pub const MAX_DETUNING: f64 = 0.1;

/// Relative detuning |chi_l - chi_eq| below which a linear scene counts as tuned (eq. 16).
pub const TUNED_TOL: f64 = 1e-9;

impl ClosedForm {
    /// The closed form of a scene with Raibert's fixed thrust; `None` for the full model
    /// (no closed form), for the energy servo (the thrust changes from hop to hop) and for
    /// a linear scene detuned by more than [`MAX_DETUNING`].
    pub fn of(sc: &HopperConfig) -> Option<Self> {
        if sc.params.servo.is_some() {
            return None;
        }
        let tau = sc.params.thrust_tau_mps2;
        match sc.hopper.model {
            HopperModel::SimplifiedNonlinear(m) => {
                let mu = leg_mass_factor(m.leg_mass_ratio());
                Some(ClosedForm::Eq19 {
                    alpha: nonlinear_alpha(tau, mu, m.spring_eta1(), m.liftoff_m()),
                    tau,
                    mu,
                    eta1: m.spring_eta1(),
                    chi_l: m.liftoff_m(),
                })
            }
            HopperModel::Linear(m) => {
                let map = Eq17::new(
                    m.omega(),
                    m.beta(),
                    sc.params.thrust_delta_s,
                    tau - m.gravity_mps2(),
                );
                let cf = ClosedForm::Eq17 {
                    map,
                    chi_eq: m.equilibrium_m(),
                    eta1: m.spring_eta1(),
                    detuning_m: m.liftoff_m() - m.equilibrium_m(),
                };
                // an untuned scene is compared with eq. 17 only while its detuning is small
                // against the compression depth at eq. 17's fixed point
                let depth = cf
                    .fixed_energy()
                    .map_or(0.0, |e| (e / m.spring_eta1()).sqrt());
                let detuning = (m.liftoff_m() - m.equilibrium_m()).abs();
                (cf.exact() || detuning <= MAX_DETUNING * depth).then_some(cf)
            }
            _ => None,
        }
    }

    /// True if the closed form is exact for this scene (eq. 17 needs chi_l = chi_eq).
    pub fn exact(&self) -> bool {
        match self {
            ClosedForm::Eq19 { .. } => true,
            ClosedForm::Eq17 {
                detuning_m, chi_eq, ..
            } => detuning_m.abs() <= TUNED_TOL * chi_eq.abs().max(1.0),
        }
    }

    /// The equation's name.
    pub fn equation(&self) -> &'static str {
        match self {
            ClosedForm::Eq19 { .. } => "eq. 15/19",
            ClosedForm::Eq17 { .. } => "eq. 17",
        }
    }

    /// The energy map f(E).
    pub fn energy_map(&self, e: f64) -> f64 {
        match self {
            ClosedForm::Eq19 { alpha, .. } => energy_return_map(e, *alpha),
            ClosedForm::Eq17 { map, .. } => map.f(e),
        }
    }

    /// The bottom-height map g(x), m (eq. 15; eq. 17 through E = eta1 (x - chi_eq)^2 for
    /// bottoms below chi_eq).
    pub fn bottom_map(&self, x: f64) -> f64 {
        match self {
            ClosedForm::Eq19 {
                tau,
                mu,
                eta1,
                chi_l,
                ..
            } => nonlinear_return_map(x, *tau, *mu, *eta1, *chi_l),
            ClosedForm::Eq17 { .. } => self.bottom_of(self.energy_map(self.energy_of(x))),
        }
    }

    /// E of a bottom at `x`.
    pub fn energy_of(&self, x: f64) -> f64 {
        match self {
            ClosedForm::Eq19 { chi_l, .. } => (chi_l / x).ln(),
            ClosedForm::Eq17 { chi_eq, eta1, .. } => {
                if x < *chi_eq {
                    eta1 * (x - chi_eq).powi(2)
                } else {
                    f64::NAN
                }
            }
        }
    }

    /// The bottom of energy `e`, m.
    pub fn bottom_of(&self, e: f64) -> f64 {
        match self {
            ClosedForm::Eq19 { chi_l, .. } => chi_l * (-e).exp(),
            ClosedForm::Eq17 { chi_eq, eta1, .. } => chi_eq - (e / eta1).sqrt(),
        }
    }

    /// The interior fixed point E* (eq. 19: ln alpha for alpha > 1; eq. 17: Lemma 5).
    pub fn fixed_energy(&self) -> Option<f64> {
        match self {
            ClosedForm::Eq19 { alpha, .. } => energy_fixed_point(*alpha),
            ClosedForm::Eq17 { map, .. } => map.fixed_point(),
        }
    }

    /// f'(E*) (eq. 19: 1 - ln alpha).
    pub fn fixed_slope(&self) -> Option<f64> {
        let e = self.fixed_energy()?;
        Some(match self {
            ClosedForm::Eq19 { alpha, .. } => energy_fixed_point_slope(*alpha),
            ClosedForm::Eq17 { map, .. } => map.slope(e),
        })
    }

    /// Eq. 19's 2-cycle {p, q} (p < q, p + q = 2 ln alpha) for alpha > e^2.
    pub fn two_cycle(&self) -> Option<(f64, f64)> {
        let ClosedForm::Eq19 { alpha, .. } = *self else {
            return None;
        };
        if alpha <= ALPHA_DOUBLING {
            return None;
        }
        let l = alpha.ln();
        // p + f(p) = 2 ln alpha has the root p = L (the fixed point) and one in (0, L)
        let g = |p: f64| p + energy_return_map(p, alpha) - 2.0 * l;
        let (mut lo, mut hi) = (0.0, l * (1.0 - 1e-9));
        if g(hi) <= 0.0 {
            return None;
        }
        for _ in 0..300 {
            let mid = 0.5 * (lo + hi);
            if g(mid) > 0.0 {
                hi = mid;
            } else {
                lo = mid;
            }
        }
        let p = 0.5 * (lo + hi);
        Some((p, 2.0 * l - p))
    }

    /// alpha, for eq. 19.
    pub fn alpha(&self) -> Option<f64> {
        match self {
            ClosedForm::Eq19 { alpha, .. } => Some(*alpha),
            ClosedForm::Eq17 { .. } => None,
        }
    }
}

/// Why a scene has no closed form to compare with, in words.
pub fn none_reason(sc: &HopperConfig) -> String {
    if sc.params.servo.is_some() {
        return "none with the energy servo (the thrust changes from hop to hop)".into();
    }
    match sc.hopper.model {
        HopperModel::Linear(m) => format!(
            "none: eq. 17 needs the tuned linear model (chi_l = chi_eq = chi_0 - g/eta1, eq. 16); this scene is detuned by chi_l - chi_eq = {:.6} m",
            m.liftoff_m() - m.equilibrium_m()
        ),
        HopperModel::Full(_) => "none for the full model (eq. 8): simulated points only".into(),
        HopperModel::SimplifiedNonlinear(_) => "none".into(),
    }
}
