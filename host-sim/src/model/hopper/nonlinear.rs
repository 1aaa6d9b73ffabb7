//! The simplified nonlinear-spring model, eq. 9: every phase in closed form.
//!
//! Stance neglects gravity and friction, the thrust is instantaneous (delta = 0): at bottom
//! the spring constant jumps from eta1 to eta2 = tau x_b (sec. 3.1). Gravity g acts in
//! flight only (Table 1's "0/10", figs. 11 and 13).
//!
//! - **Compression** (touchdown at chi_l with chi'_td < 0 to bottom), eq. 13:
//!   x_b = chi_l exp(-E_b), E_b = chi'_td^2 / (2 eta1), computed in the energy coordinate
//!   E_b (eq. 18) so that a deep bottom underflows gracefully instead of giving NaN.
//! - **Decompression** (bottom to liftoff), eq. 12 with eta2 = tau x_b:
//!   chi'_l-^2 = 2 tau x_b ln(chi_l / x_b) = 2 tau x_b E_b; eq. 7 then scales it by
//!   1/(1 + mu'), which is eq. 14.
//! - **Flight**: ballistic and symmetric (closed form in [`super::Hopper`]).
//!
//! Bottom to bottom this is exactly eq. 15, g(x) = chi_l exp{-(tau mu / eta1) x ln(chi_l/x)},
//! or eq. 19 in E.
//!
//! **Times** (only when asked for): with eq. 12 from the bottom, chi'^2 = 2 eta ln(chi/x_b),
//! the substitution chi = x_b exp(s^2) turns t = int dchi / |chi'| into
//! t(chi) = chi sqrt(2/eta) D(sqrt(ln(chi/x_b))), with Dawson's integral
//! D(a) = exp(-a^2) int_0^a exp(s^2) ds. Compression lasts chi_l sqrt(2/eta1) D(sqrt(E_b)),
//! decompression chi_l sqrt(2/eta2) D(sqrt(E_b)). D is evaluated by Gauss-Legendre quadrature
//! of its smooth, bounded integrand ([`dawson`]), to ~1e-15 relative.

use super::{Entry, HopEvent, HopperError, RunEnd, RunOptions, Sampler, Stance, StanceResult};
use dexter_core::hop::{leg_mass_factor, RaibertThrust, StancePhase};
use dexter_core::params::{non_negative, positive};

/// The simplified nonlinear spring model of eq. 9.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SimplifiedNonlinear {
    liftoff_m: f64,
    eta1: f64,
    leg_mass_ratio: f64,
    gravity_mps2: f64,
}

impl SimplifiedNonlinear {
    /// - `liftoff_m`: chi_l = chi_td, the body height with the leg fully extended, m (> 0).
    /// - `spring_eta1`: eta1 = p_td A chi_td per unit body mass, m^2/s^2 (> 0): the
    ///   compression spring force is eta1 / chi (m/s^2).
    /// - `leg_mass_ratio`: mu', leg mass / body mass (>= 0); eq. 7 / 14.
    /// - `gravity_mps2`: g in flight, m/s^2 (> 0).
    ///
    /// Errors name the `[hopper]` key, e.g. `hopper.spring_eta1 must be > 0`.
    pub fn new(
        liftoff_m: f64,
        spring_eta1: f64,
        leg_mass_ratio: f64,
        gravity_mps2: f64,
    ) -> Result<Self, HopperError> {
        Ok(Self {
            liftoff_m: positive("hopper.liftoff_height_m", liftoff_m)?,
            eta1: positive("hopper.spring_eta1", spring_eta1)?,
            leg_mass_ratio: non_negative("hopper.leg_mass_ratio", leg_mass_ratio)?,
            gravity_mps2: positive("hopper.gravity_mps2", gravity_mps2)?,
        })
    }

    /// chi_l, m.
    pub fn liftoff_m(&self) -> f64 {
        self.liftoff_m
    }
    /// eta1, m^2/s^2.
    pub fn spring_eta1(&self) -> f64 {
        self.eta1
    }
    /// mu'.
    pub fn leg_mass_ratio(&self) -> f64 {
        self.leg_mass_ratio
    }
    /// g (flight), m/s^2.
    pub fn gravity_mps2(&self) -> f64 {
        self.gravity_mps2
    }
    /// mu = (1/(1 + mu'))^2 (eq. 14).
    pub fn mu(&self) -> f64 {
        leg_mass_factor(self.leg_mass_ratio)
    }
    /// alpha = tau chi_l mu / eta1 of eq. 19 for thrust `tau_mps2`.
    pub fn alpha(&self, tau_mps2: f64) -> f64 {
        dexter_core::hop::nonlinear_alpha(tau_mps2, self.mu(), self.eta1, self.liftoff_m)
    }
    /// The thrust that gives `alpha` (inverse of [`Self::alpha`]), m/s^2.
    pub fn thrust_for_alpha(&self, alpha: f64) -> f64 {
        alpha * self.eta1 / (self.liftoff_m * self.mu())
    }

    pub(crate) fn stance(
        &self,
        entry: Entry,
        thrust: RaibertThrust<f64>,
        opts: &RunOptions,
        s: &mut Sampler<'_>,
    ) -> StanceResult {
        let chi_l = self.liftoff_m;
        let tau = thrust.thrust_mps2();
        // bottom, in the energy coordinate E_b = ln(chi_l / x_b) (eq. 13 / 18)
        let (t_td, e_b) = match entry {
            Entry::Touchdown(td) => (
                td.time_s,
                td.velocity_mps * td.velocity_mps / (2.0 * self.eta1),
            ),
            Entry::Bottom(b) => (b.time_s, (chi_l / b.height_m).ln()),
        };
        let x_b = match entry {
            Entry::Bottom(b) => b.height_m,
            Entry::Touchdown(_) => chi_l * (-e_b).exp(),
        };
        let d = if opts.times || s.on() {
            dawson(e_b.sqrt())
        } else {
            f64::NAN
        };
        let t_comp = match entry {
            Entry::Touchdown(_) => chi_l * (2.0 / self.eta1).sqrt() * d,
            Entry::Bottom(_) => 0.0,
        };
        let t_b = t_td + t_comp;
        let eta2 = tau * x_b;
        // eq. 12 from the bottom: chi'_l-^2 = 2 eta2 ln(chi_l / x_b)
        let v_l = (2.0 * eta2 * e_b).sqrt();
        if tau == 0.0 && e_b > 0.0 {
            // no thrust: nothing drives the leg out of the bottom (eq. 9's spring is
            // exhausted there), the body stays down
            return Err(RunEnd::NoLiftoff);
        }
        let t_dec = if eta2 > 0.0 {
            chi_l * (2.0 / eta2).sqrt() * d
        } else if e_b == 0.0 {
            0.0
        } else {
            f64::INFINITY
        };
        if s.on() {
            if let Entry::Touchdown(_) = entry {
                stance_samples(
                    s,
                    StancePhase::Compression,
                    x_b,
                    self.eta1,
                    t_b,
                    -1.0,
                    chi_l,
                );
            }
            stance_samples(s, StancePhase::Decompression, x_b, eta2, t_b, 1.0, chi_l);
        }
        let bottom = HopEvent {
            time_s: t_b,
            height_m: x_b,
            velocity_mps: 0.0,
        };
        Ok(Stance {
            bottom,
            end_of_thrust: bottom,
            liftoff: HopEvent {
                time_s: t_b + t_dec,
                height_m: chi_l,
                velocity_mps: v_l,
            },
            early_liftoff: false,
            steps: 0,
            energy: e_b,
        })
    }
}

/// Samples of one stance phase along the exact eq. 12 curve, uniform in chi between the
/// bottom `x_b` and `chi_l`; `dir` = -1 for compression (time before the bottom), +1 after.
fn stance_samples(
    s: &mut Sampler<'_>,
    phase: StancePhase,
    x_b: f64,
    eta: f64,
    t_b: f64,
    dir: f64,
    chi_l: f64,
) {
    let n = s.per_phase.max(1);
    for i in 0..=n {
        let k = if dir < 0.0 { n - i } else { i };
        let chi = x_b + (chi_l - x_b) * k as f64 / n as f64;
        let u = (chi / x_b).ln().max(0.0);
        let v = dir * (2.0 * eta * u).sqrt();
        let t = t_b + dir * chi * (2.0 / eta).sqrt() * dawson(u.sqrt());
        s.push(
            phase,
            HopEvent {
                time_s: t,
                height_m: chi,
                velocity_mps: v,
            },
        );
    }
}

/// Gauss-Legendre nodes and weights on [-1, 1], 10 points (positive half).
const GL10_X: [f64; 5] = [
    0.148_874_338_981_631_2,
    0.433_395_394_129_247_2,
    0.679_409_568_299_024_4,
    0.865_063_366_688_984_5,
    0.973_906_528_517_171_7,
];
const GL10_W: [f64; 5] = [
    0.295_524_224_714_752_9,
    0.269_266_719_309_996_4,
    0.219_086_362_515_982_04,
    0.149_451_349_150_580_6,
    0.066_671_344_308_688_14,
];

/// Dawson's integral D(a) = exp(-a^2) int_0^a exp(s^2) ds = int_0^a exp(-u (2a - u)) du
/// (u = a - s), dimensionless, for a >= 0 (NaN for NaN).
///
/// The integrand is in (0, 1], decreasing in u, and below e^-40 for u > 40/a, so the
/// range is cut there and split into panels over which the exponent changes by at most 2,
/// each integrated by 10-point Gauss-Legendre (error far below f64 rounding). At most
/// 80 panels.
pub fn dawson(a: f64) -> f64 {
    if a.is_nan() {
        return f64::NAN;
    }
    if a <= 0.0 {
        return 0.0;
    }
    if a.is_infinite() {
        return 0.0;
    }
    let len = a.min(40.0 / a);
    let width = (1.0 / a).min(0.5);
    let panels = ((len / width).ceil() as usize).clamp(1, 80);
    let h = len / panels as f64;
    let mut sum = 0.0;
    for p in 0..panels {
        let mid = (p as f64 + 0.5) * h;
        let half = 0.5 * h;
        let mut ps = 0.0;
        for (x, w) in GL10_X.iter().zip(GL10_W.iter()) {
            for u in [mid - half * x, mid + half * x] {
                ps += w * (-u * (2.0 * a - u)).exp();
            }
        }
        sum += ps * half;
    }
    sum
}
