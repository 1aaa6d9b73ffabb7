//! The linear-spring model, eq. 10 (eq. 16 when tuned): every phase in closed form.
//!
//! Stance: chi'' = eta1 (chi_0 - chi) - gamma chi' - g outside the thrust, and
//! chi'' = tau - gamma chi' - g during it (t in [t_b, t_b + delta)). Flight: chi'' = -g.
//! Touchdown and liftoff at chi_l. With y = chi - chi_eq, chi_eq = chi_0 - g / eta1 (the
//! loaded rest position), the stance is the damped oscillator of eq. 1,
//! y'' + 2 omega beta y' + omega^2 (1 + beta^2) y = 0, with gamma = 2 omega beta and
//! eta1 = omega^2 (1 + beta^2); the model requires it underdamped (gamma^2 < 4 eta1).
//!
//! **Compression and decompression** (eq. 23 in the paper's normal coordinates): with
//! sigma = gamma/2 and omega = sqrt(eta1 - sigma^2),
//!
//! y(t)  = e^{-sigma t} [ y0 cos(omega t) + (v0 + sigma y0)/omega sin(omega t) ],
//! y'(t) = e^{-sigma t} [ v0 cos(omega t) - (eta1 y0 + sigma v0)/omega sin(omega t) ].
//!
//! The bottom (y' = 0) is at the closed-form time t = ((phi + pi/2) mod pi)/omega with
//! phi = atan2(-(eta1 y0 + sigma v0)/omega, v0). The liftoff is the root of the closed-form
//! y(t) = chi_l - chi_eq on the rising stretch between two velocity zeros (closed-form bracket
//! ends, y monotone there), found by bisection to adjacent floats; if y at the top of that
//! stretch stays below it, the hopper does not lift off ([`super::RunEnd::NoLiftoff`]).
//!
//! **Thrust** (eq. 24 re-derived, gravity included): with a = tau - g and
//! phi1(t) = (1 - e^{-gamma t})/gamma, chi'(t) = v_b e^{-gamma t} + a phi1(t),
//! chi(t) = chi_b + v_b phi1(t) + a (t - phi1(t))/gamma (t^2/2 series for small gamma t).
//! From rest this is (chi_t, chi'_t) = (a/gamma^2 (gamma delta - 1 + e^{-gamma delta}),
//! a/gamma (1 - e^{-gamma delta})). The paper's eq. 24 prints 1/(2 omega^2 beta^2) and
//! e^{-2 beta delta} in chi_t; direct integration gives 1/gamma^2 = 1/(4 omega^2 beta^2) and
//! e^{-2 omega beta delta} (and chi_t / chi'_t -> delta/2, consistent with Lemma 6's bound).
//! If chi reaches chi_l during the thrust, the leg is extended: liftoff there (flagged
//! [`super::Cycle::early_liftoff`], outside the valid regime of sec. 3.3).
//!
//! The energy coordinate is eq. 17's normalized energy at the bottom, E = eta1 (x - chi_eq)^2
//! (m^2/s^2; = omega^2 (1 + beta^2) chi_b^2 in the tuned coordinates of eq. 16).

use super::{Entry, HopEvent, HopperError, RunEnd, Sampler, StanceResult};
use dexter_core::hop::{RaibertThrust, StancePhase};
use dexter_core::params::{finite, non_negative, positive};

/// Bisection iterations for a liftoff root (converges to adjacent floats long before).
pub const ROOT_ITERATIONS: u32 = 200;

/// The linear-spring model of eq. 10.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LinearSpring {
    liftoff_m: f64,
    eta1: f64,
    gamma: f64,
    rest_m: f64,
    leg_mass_ratio: f64,
    gravity_mps2: f64,
}

impl LinearSpring {
    /// - `liftoff_m`: chi_l = chi_td, touchdown/liftoff height, m (any finite value; eq. 16
    ///   puts it at 0).
    /// - `spring_eta1`: eta1, spring stiffness per unit mass, 1/s^2 (> 0).
    /// - `friction_gamma_per_s`: gamma, viscous friction per unit mass, 1/s (>= 0,
    ///   gamma^2 < 4 eta1).
    /// - `spring_rest_m`: chi_0, the spring's relaxed position, m.
    /// - `leg_mass_ratio`: mu' (>= 0; the paper's linear model has 0, eq. 10).
    /// - `gravity_mps2`: g, m/s^2 (> 0), in stance and flight.
    pub fn new(
        liftoff_m: f64,
        spring_eta1: f64,
        friction_gamma_per_s: f64,
        spring_rest_m: f64,
        leg_mass_ratio: f64,
        gravity_mps2: f64,
    ) -> Result<Self, HopperError> {
        let eta1 = positive("hopper.spring_eta1", spring_eta1)?;
        let gamma = non_negative("hopper.friction_gamma_per_s", friction_gamma_per_s)?;
        if gamma * gamma >= 4.0 * eta1 {
            return Err(HopperError::Relation {
                param: "hopper.friction_gamma_per_s",
                requirement: "gamma^2 < 4 eta1 (underdamped stance, eq. 1)",
            });
        }
        Ok(Self {
            liftoff_m: finite("hopper.liftoff_height_m", liftoff_m)?,
            eta1,
            gamma,
            rest_m: finite("hopper.spring_rest_m", spring_rest_m)?,
            leg_mass_ratio: non_negative("hopper.leg_mass_ratio", leg_mass_ratio)?,
            gravity_mps2: positive("hopper.gravity_mps2", gravity_mps2)?,
        })
    }

    /// The tuned model of eq. 16 from the paper's parameters: `omega` (rad/s, > 0), `beta`
    /// (> 0), touchdown at chi = 0, chi_0 = g / eta1 so gravity cancels in stance. Eq. 16's
    /// thrust tau16 (m/s^2) is the net thrust, so the [`RaibertThrust`] to use is
    /// tau16 + g ([`Self::eq16_thrust`]).
    pub fn from_eq16(omega: f64, beta: f64, gravity_mps2: f64) -> Result<Self, HopperError> {
        let omega = positive("hopper.omega", omega)?;
        let beta = positive("hopper.beta", beta)?;
        let g = positive("hopper.gravity_mps2", gravity_mps2)?;
        let eta1 = omega * omega * (1.0 + beta * beta);
        Self::new(0.0, eta1, 2.0 * omega * beta, g / eta1, 0.0, g)
    }

    /// The eq. 10 thrust (m/s^2) for eq. 16's net thrust `tau16`: tau16 + g.
    pub fn eq16_thrust(&self, tau16: f64) -> f64 {
        tau16 + self.gravity_mps2
    }

    /// chi_l, m.
    pub fn liftoff_m(&self) -> f64 {
        self.liftoff_m
    }
    /// eta1, 1/s^2.
    pub fn spring_eta1(&self) -> f64 {
        self.eta1
    }
    /// gamma, 1/s.
    pub fn friction_gamma_per_s(&self) -> f64 {
        self.gamma
    }
    /// mu'.
    pub fn leg_mass_ratio(&self) -> f64 {
        self.leg_mass_ratio
    }
    /// g, m/s^2.
    pub fn gravity_mps2(&self) -> f64 {
        self.gravity_mps2
    }
    /// chi_eq = chi_0 - g / eta1, the loaded rest position, m.
    pub fn equilibrium_m(&self) -> f64 {
        self.rest_m - self.gravity_mps2 / self.eta1
    }
    /// omega = sqrt(eta1 - gamma^2/4), rad/s.
    pub fn omega(&self) -> f64 {
        (self.eta1 - 0.25 * self.gamma * self.gamma).sqrt()
    }
    /// beta = gamma / (2 omega).
    pub fn beta(&self) -> f64 {
        0.5 * self.gamma / self.omega()
    }
    /// Normalized energy of a bottom at `x_m` (eq. 17 coordinate), m^2/s^2.
    pub fn bottom_energy(&self, x_m: f64) -> f64 {
        let y = x_m - self.equilibrium_m();
        self.eta1 * y * y
    }
    /// Spring force per unit mass at `x_m`, eta1 (chi_0 - x), m/s^2.
    pub fn spring_force_mps2(&self, x_m: f64) -> f64 {
        self.eta1 * (self.rest_m - x_m)
    }

    /// Free stance motion from (y0, v0) after `t` s: (y, y').
    fn free(&self, y0: f64, v0: f64, t: f64) -> (f64, f64) {
        let s = 0.5 * self.gamma;
        let w = self.omega();
        let (sn, cs) = (w * t).sin_cos();
        let e = (-s * t).exp();
        (
            e * (y0 * cs + (v0 + s * y0) / w * sn),
            e * (v0 * cs - (self.eta1 * y0 + s * v0) / w * sn),
        )
    }

    /// The first time > 0 (or 0 if `v0 == 0`) at which the free velocity vanishes.
    fn first_velocity_zero(&self, y0: f64, v0: f64) -> f64 {
        let s = 0.5 * self.gamma;
        let w = self.omega();
        let b = -(self.eta1 * y0 + s * v0) / w;
        if v0 == 0.0 {
            return if b == 0.0 {
                0.0
            } else {
                core::f64::consts::PI / w
            };
        }
        // v = R cos(w t - phi), phi = atan2(b, v0); zeros at w t = phi + pi/2 + k pi
        let phi = b.atan2(v0);
        let mut t = (phi + core::f64::consts::FRAC_PI_2).rem_euclid(core::f64::consts::PI) / w;
        if t <= 0.0 {
            t += core::f64::consts::PI / w;
        }
        t
    }

    /// The free stance motion (valve closed) in closed form, for plants that step it in
    /// pieces (the sampled plant, [`super::valve`]): (y, y') after `t_s` s from (y0, v0),
    /// y = chi - chi_eq in m, y' in m/s (the module's damped-oscillator formula).
    pub fn free_motion(&self, y0_m: f64, v0_mps: f64, t_s: f64) -> (f64, f64) {
        self.free(y0_m, v0_mps, t_s)
    }

    /// The first time > 0 at which the free stance velocity from (y0, v0) vanishes, s
    /// (0 at rest at chi_eq); later zeros follow every pi / omega.
    pub fn first_velocity_zero_s(&self, y0_m: f64, v0_mps: f64) -> f64 {
        self.first_velocity_zero(y0_m, v0_mps)
    }

    pub(crate) fn stance(
        &self,
        entry: Entry,
        thrust: RaibertThrust<f64>,
        s: &mut Sampler<'_>,
    ) -> StanceResult {
        let ceq = self.equilibrium_m();
        let chi_l = self.liftoff_m;
        let bottom = match entry {
            Entry::Bottom(b) => b,
            Entry::Touchdown(td) => {
                let y0 = td.height_m - ceq;
                let v0 = td.velocity_mps;
                let t = if v0 < 0.0 {
                    self.first_velocity_zero(y0, v0)
                } else {
                    0.0
                };
                let (y, _) = self.free(y0, v0, t);
                if s.on() {
                    let n = s.per_phase.max(1);
                    for i in 0..=n {
                        let ti = t * i as f64 / n as f64;
                        let (yi, vi) = self.free(y0, v0, ti);
                        s.push(StancePhase::Compression, ev(td.time_s + ti, yi + ceq, vi));
                    }
                }
                ev(td.time_s + t, y + ceq, 0.0)
            }
        };
        // thrust, closed form
        let (et, early) = thrust_phase(bottom, thrust, self.gamma, self.gravity_mps2, chi_l, s);
        if early {
            return Ok(super::Stance {
                bottom,
                end_of_thrust: et,
                liftoff: et,
                early_liftoff: true,
                steps: 0,
                energy: self.bottom_energy(bottom.height_m),
            });
        }
        // decompression: rising stretch, then the root of y(t) = chi_l - chi_eq
        let y0 = et.height_m - ceq;
        let v0 = et.velocity_mps;
        let c = chi_l - ceq;
        let w = self.omega();
        let (t_lo, t_hi) = if v0 > 0.0 || (v0 == 0.0 && y0 < 0.0) {
            (0.0, self.first_velocity_zero(y0, v0))
        } else {
            let t1 = self.first_velocity_zero(y0, v0);
            (t1, t1 + core::f64::consts::PI / w)
        };
        let y_top = self.free(y0, v0, t_hi).0;
        if y_top < c || !y_top.is_finite() {
            return Err(RunEnd::NoLiftoff);
        }
        let f = |t: f64| self.free(y0, v0, t).0 - c;
        let t_l = if f(t_lo) >= 0.0 {
            t_lo
        } else {
            bisect_rising(&f, t_lo, t_hi)
        };
        let vl = self.free(y0, v0, t_l).1;
        if s.on() {
            let n = s.per_phase.max(1);
            for i in 0..=n {
                let ti = t_l * i as f64 / n as f64;
                let (yi, vi) = self.free(y0, v0, ti);
                s.push(StancePhase::Decompression, ev(et.time_s + ti, yi + ceq, vi));
            }
        }
        Ok(super::Stance {
            bottom,
            end_of_thrust: et,
            liftoff: ev(et.time_s + t_l, chi_l, vl),
            early_liftoff: false,
            steps: 0,
            energy: self.bottom_energy(bottom.height_m),
        })
    }
}

pub(crate) fn ev(time_s: f64, height_m: f64, velocity_mps: f64) -> HopEvent {
    HopEvent {
        time_s,
        height_m,
        velocity_mps,
    }
}

/// The smallest t in [lo, hi] with f(t) >= 0, for f increasing with f(lo) < 0 <= f(hi).
pub(crate) fn bisect_rising(f: &impl Fn(f64) -> f64, mut lo: f64, mut hi: f64) -> f64 {
    for _ in 0..ROOT_ITERATIONS {
        let mid = 0.5 * (lo + hi);
        if mid <= lo || mid >= hi {
            break;
        }
        if f(mid) >= 0.0 {
            hi = mid;
        } else {
            lo = mid;
        }
    }
    hi
}

/// The thrust motion in closed form (eq. 8 / 10 with the valve open): (chi, chi') after
/// `t_s` s of chi'' = a - gamma chi' from (`x0_m`, `v0_mps`), with a = tau - g the net
/// thrust (m/s^2) and gamma (1/s) the friction: chi = x0 + v0 phi1(t) + a (t - phi1(t))/gamma,
/// chi' = v0 e^{-gamma t} + a phi1(t), phi1 = (1 - e^{-gamma t})/gamma.
pub fn thrust_motion(
    x0_m: f64,
    v0_mps: f64,
    net_accel_mps2: f64,
    gamma_per_s: f64,
    t_s: f64,
) -> (f64, f64) {
    (
        x0_m + v0_mps * phi1(gamma_per_s, t_s) + net_accel_mps2 * psi2(gamma_per_s, t_s),
        v0_mps * (-gamma_per_s * t_s).exp() + net_accel_mps2 * phi1(gamma_per_s, t_s),
    )
}

/// (1 - e^{-gamma t}) / gamma, s (t for gamma = 0).
fn phi1(gamma: f64, t: f64) -> f64 {
    if gamma == 0.0 {
        t
    } else {
        -(-gamma * t).exp_m1() / gamma
    }
}

/// (t - phi1) / gamma = (gamma t - 1 + e^{-gamma t}) / gamma^2, s^2 (t^2/2 for gamma = 0).
fn psi2(gamma: f64, t: f64) -> f64 {
    let x = gamma * t;
    if x.abs() < 1e-2 {
        t * t * (0.5 + x * (-1.0 / 6.0 + x * (1.0 / 24.0 + x * (-1.0 / 120.0 + x / 720.0))))
    } else {
        (x + (-x).exp_m1()) / (gamma * gamma)
    }
}

/// The thrust phase in closed form: chi'' = tau - gamma chi' - g for delta s from `bottom`
/// (eq. 8 / 10; eq. 24 from rest). Returns the end-of-thrust state and whether the leg
/// extended (chi reached `chi_l`) first, in which case the state is that liftoff.
pub(crate) fn thrust_phase(
    bottom: HopEvent,
    thrust: RaibertThrust<f64>,
    gamma: f64,
    g: f64,
    chi_l: f64,
    s: &mut Sampler<'_>,
) -> (HopEvent, bool) {
    let a = thrust.thrust_mps2() - g;
    let delta = thrust.duration_s();
    let (x0, v0) = (bottom.height_m, bottom.velocity_mps);
    let at = |t: f64| {
        (
            x0 + v0 * phi1(gamma, t) + a * psi2(gamma, t),
            v0 * (-gamma * t).exp() + a * phi1(gamma, t),
        )
    };
    let (xd, _) = at(delta);
    // chi is increasing on [0, delta] (v0 >= 0, a > 0): the leg extends at most once
    let (t_end, early) = if delta > 0.0 && xd >= chi_l {
        let t = if x0 >= chi_l {
            0.0
        } else {
            bisect_rising(&|t| at(t).0 - chi_l, 0.0, delta)
        };
        (t, true)
    } else {
        (delta, false)
    };
    if s.on() && t_end > 0.0 {
        let n = s.per_phase.max(1);
        for i in 0..=n {
            let ti = t_end * i as f64 / n as f64;
            let (xi, vi) = at(ti);
            s.push(StancePhase::Thrust, ev(bottom.time_s + ti, xi, vi));
        }
    }
    let (x, v) = at(t_end);
    let x = if early { chi_l } else { x };
    (ev(bottom.time_s + t_end, x, v), early)
}
