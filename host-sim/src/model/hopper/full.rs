//! The full model, eq. 8: pneumatic spring, thrust over delta, viscous friction, gravity in
//! stance, and the leg mass with the inelastic liftoff of eq. 7.
//!
//! | phase | dynamics (per unit body mass) | how |
//! | --- | --- | --- |
//! | compression | chi'' = eta1/chi - gamma chi' - g | **integrated** ([`super::Integrator`]) until chi' >= 0 (bottom), event located |
//! | thrust | chi'' = tau - gamma chi' - g | closed form ([`super::linear`]'s thrust phase, eq. 24 with gravity) |
//! | decompression | chi'' = tau chi_et/chi - gamma chi' - g | **integrated** until chi >= chi_l (liftoff), event located; chi' <= 0 first = no liftoff |
//! | flight | chi'' = -g | closed form |
//!
//! With gamma = 0 the stance has the energy integral chi'^2/2 - eta ln chi + g chi = const,
//! but the bottom and liftoff heights are then roots of a transcendental equation and the
//! times need a quadrature with a singular end; with gamma > 0 there is no closed form at
//! all. The model therefore always integrates its two spring phases, and the tests check
//! the integration against that energy integral.

use super::linear::{ev, thrust_phase};
use super::{Entry, HopperError, RunEnd, Sampler, Stance, StanceResult};
use super::{Integrator, MAX_STEPS_PER_PHASE};
use crate::engine::ode::{End, State};
use dexter_core::hop::{RaibertThrust, StancePhase};
use dexter_core::params::{non_negative, positive};

/// The full nonlinear model of eq. 8.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FullNonlinear {
    liftoff_m: f64,
    eta1: f64,
    gamma: f64,
    leg_mass_ratio: f64,
    gravity_mps2: f64,
    integrator: Integrator,
}

impl FullNonlinear {
    /// - `liftoff_m`: chi_l = chi_td, m (> 0).
    /// - `spring_eta1`: eta1 = p_td A chi_td per unit mass, m^2/s^2 (> 0).
    /// - `friction_gamma_per_s`: gamma, 1/s (>= 0).
    /// - `leg_mass_ratio`: mu' (>= 0), eq. 7.
    /// - `gravity_mps2`: g, m/s^2 (> 0), in stance and flight.
    /// - `integrator`: the method for the two spring phases.
    pub fn new(
        liftoff_m: f64,
        spring_eta1: f64,
        friction_gamma_per_s: f64,
        leg_mass_ratio: f64,
        gravity_mps2: f64,
        integrator: Integrator,
    ) -> Result<Self, HopperError> {
        Ok(Self {
            liftoff_m: positive("hopper.liftoff_height_m", liftoff_m)?,
            eta1: positive("hopper.spring_eta1", spring_eta1)?,
            gamma: non_negative("hopper.friction_gamma_per_s", friction_gamma_per_s)?,
            leg_mass_ratio: non_negative("hopper.leg_mass_ratio", leg_mass_ratio)?,
            gravity_mps2: positive("hopper.gravity_mps2", gravity_mps2)?,
            integrator,
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
    /// The integrator of the spring phases.
    pub fn integrator(&self) -> Integrator {
        self.integrator
    }

    pub(crate) fn stance(
        &self,
        entry: Entry,
        thrust: RaibertThrust<f64>,
        s: &mut Sampler<'_>,
    ) -> StanceResult {
        let (eta1, gamma, g, chi_l) = (self.eta1, self.gamma, self.gravity_mps2, self.liftoff_m);
        let sampling = s.on();
        let mut buf: Vec<(f64, (f64, f64))> = Vec::new();
        let mut steps = 0;
        let bottom = match entry {
            Entry::Bottom(b) => b,
            Entry::Touchdown(td) => {
                let y0 = (td.height_m, td.velocity_mps);
                let a0 = eta1 / y0.0 - g;
                if y0.1 == 0.0 && a0 >= 0.0 {
                    ev(td.time_s, td.height_m, 0.0)
                } else {
                    let acc = |_: f64, y: State| eta1 / y.0 - gamma * y.1 - g;
                    buf.clear();
                    if sampling {
                        buf.push((0.0, y0));
                    }
                    let bottom = |_: f64, y: State| y.1;
                    let (out, n) = self.integrator.integrate(
                        MAX_STEPS_PER_PHASE,
                        &acc,
                        y0,
                        f64::INFINITY,
                        &[&bottom as &dyn Fn(f64, State) -> f64][..],
                        &mut |t, y| {
                            if sampling {
                                buf.push((t, y));
                            }
                        },
                    );
                    steps += n;
                    let End::Event { dt_s, state, .. } = out else {
                        return Err(RunEnd::StepCap);
                    };
                    emit(s, StancePhase::Compression, td.time_s, &buf);
                    ev(td.time_s + dt_s, state.0, 0.0)
                }
            }
        };
        let (et, early) = thrust_phase(bottom, thrust, gamma, g, chi_l, s);
        if early {
            return Ok(Stance {
                bottom,
                end_of_thrust: et,
                liftoff: et,
                early_liftoff: true,
                steps,
                energy: (chi_l / bottom.height_m).ln(),
            });
        }
        let eta2 = thrust.thrust_mps2() * et.height_m;
        let acc = |_: f64, y: State| eta2 / y.0 - gamma * y.1 - g;
        let y0 = (et.height_m, et.velocity_mps);
        buf.clear();
        if sampling {
            buf.push((0.0, y0));
        }
        let lift = |_: f64, y: State| y.0 - chi_l;
        let turned = |_: f64, y: State| -y.1;
        let (out, n) = self.integrator.integrate(
            MAX_STEPS_PER_PHASE,
            &acc,
            y0,
            f64::INFINITY,
            &[&lift as &dyn Fn(f64, State) -> f64, &turned][..],
            &mut |t, y| {
                if sampling {
                    buf.push((t, y));
                }
            },
        );
        steps += n;
        match out {
            End::Event {
                index: 0,
                dt_s,
                state,
            } => {
                emit(s, StancePhase::Decompression, et.time_s, &buf);
                Ok(Stance {
                    bottom,
                    end_of_thrust: et,
                    liftoff: ev(et.time_s + dt_s, chi_l, state.1),
                    early_liftoff: false,
                    steps,
                    energy: (chi_l / bottom.height_m).ln(),
                })
            }
            End::Event { .. } => Err(RunEnd::NoLiftoff),
            End::StepCap { .. } | End::Span(_) => Err(RunEnd::StepCap),
        }
    }
}

/// Thin the accepted steps of one phase to at most `per_phase + 1` samples.
fn emit(s: &mut Sampler<'_>, phase: StancePhase, t0: f64, buf: &[(f64, (f64, f64))]) {
    if !s.on() || buf.is_empty() {
        return;
    }
    let n = s.per_phase.max(1);
    let stride = buf.len().div_ceil(n).max(1);
    for (i, (t, y)) in buf.iter().enumerate() {
        if i % stride == 0 || i + 1 == buf.len() {
            s.push(phase, ev(t0 + t, y.0, y.1));
        }
    }
}
