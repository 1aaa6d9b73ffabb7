//! The hopper driven by a thrust valve that a fixed-rate controller switches: the thrust acts
//! exactly while the commanded valve is open (zero-order hold between control steps), for
//! the linear model (eq. 10 / 16) and the full model (eq. 8).
//!
//! The continuous state is advanced piece by piece; each piece keeps the contact and the
//! valve constant and ends at the requested time or at a contact change (touchdown,
//! liftoff), which the caller sees as a [`TrueEvent`] with its exact time. Bottoms (chi'
//! crossing 0 upward in stance) and flight apexes are reported on the way.
//!
//! | piece | dynamics (per unit body mass) | how |
//! | --- | --- | --- |
//! | flight | chi'' = -g | closed form; touchdown at chi = chi_l, apex at chi' = 0 |
//! | stance, valve open (thrust) | chi'' = tau - gamma chi' - g | closed form ([`super::linear::thrust_motion`], eq. 24 re-derived); the velocity has at most one zero (bottom or turn); liftoff by bisection on a rising stretch |
//! | stance, valve closed, linear | chi'' = eta1 (chi_0 - chi) - gamma chi' - g | closed form ([`LinearSpring::free_motion`]); velocity zeros in closed form every pi/omega; liftoff by bisection on a rising stretch |
//! | stance, valve closed, full | chi'' = eta/chi - gamma chi' - g | **integrated** ([`crate::engine::ode`]), events (liftoff, bottom, turn) located by bisection |
//!
//! **The valve in the full model.** The leg is a pneumatic cylinder (sec. 3.1): in flight it
//! is connected to the touchdown pressure, so a stance starts with the sealed-gas constant
//! eta = eta1 = p_td A chi_td; with the valve open the force is the thrust tau = p_th A; when
//! the valve closes at height chi_c the gas is sealed at the thrust pressure, eta = tau chi_c
//! (eq. 8's eta2 = tau chi_et, here at whatever time the controller closes it). The linear
//! model's spring is the same before and after the thrust (eq. 10: eta2 = eta1).
//!
//! **Flight and liftoff.** The valve has no effect in flight (the leg is at its stop).
//! Liftoff is the leg reaching full extension, chi = chi_l, rising, in any stance piece (with
//! the valve still open this is the early liftoff that Corollary 8 excludes; it is flagged);
//! the leg pickup of eq. 7 scales the velocity by 1 / (1 + mu').

use super::linear::{bisect_rising, thrust_motion};
use super::MAX_STEPS_PER_PHASE;
use super::{FullNonlinear, LinearSpring};
use crate::engine::ode::{End, State};

/// Most pieces (contact changes, bottoms, turns) within one call of
/// [`ValvePlant::advance_to`]; more means the control period spans many oscillations.
pub const MAX_PIECES: usize = 256;

/// The two models whose thrust has a duration.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum ValveModel {
    /// Eq. 10 / 16: linear spring, every piece in closed form.
    Linear(LinearSpring),
    /// Eq. 8: pneumatic spring; its closed-valve stance is integrated.
    Full(FullNonlinear),
}

impl ValveModel {
    /// chi_l, m.
    pub fn liftoff_m(&self) -> f64 {
        match self {
            ValveModel::Linear(m) => m.liftoff_m(),
            ValveModel::Full(m) => m.liftoff_m(),
        }
    }
    /// g, m/s^2.
    pub fn gravity_mps2(&self) -> f64 {
        match self {
            ValveModel::Linear(m) => m.gravity_mps2(),
            ValveModel::Full(m) => m.gravity_mps2(),
        }
    }
    /// gamma, 1/s.
    pub fn friction_gamma_per_s(&self) -> f64 {
        match self {
            ValveModel::Linear(m) => m.friction_gamma_per_s(),
            ValveModel::Full(m) => m.friction_gamma_per_s(),
        }
    }
    /// mu'.
    pub fn leg_mass_ratio(&self) -> f64 {
        match self {
            ValveModel::Linear(m) => m.leg_mass_ratio(),
            ValveModel::Full(m) => m.leg_mass_ratio(),
        }
    }
}

/// Something that happened in the plant, at its exact time.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum TrueEvent {
    /// The leg touched down at chi_l.
    Touchdown {
        /// Time, s.
        time_s: f64,
        /// Body velocity, m/s (<= 0).
        velocity_mps: f64,
    },
    /// Maximal compression: chi' crosses 0 upward in stance.
    Bottom {
        /// Time, s.
        time_s: f64,
        /// Body height x_n, m.
        height_m: f64,
    },
    /// The leg reached full extension: the body leaves the ground.
    Liftoff {
        /// Time, s.
        time_s: f64,
        /// Body velocity just before the pickup of eq. 7, m/s.
        velocity_before_mps: f64,
        /// Body velocity after it, m/s.
        velocity_mps: f64,
        /// True if the valve was open (an early liftoff, during the thrust).
        during_thrust: bool,
    },
    /// The top of a flight.
    Apex {
        /// Time, s.
        time_s: f64,
        /// Body height, m.
        height_m: f64,
    },
}

/// Why the plant could not be advanced.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PlantError {
    /// The state became non-finite, or the full model's body reached chi <= 0.
    NonFinite,
    /// The full model's integrator took [`super::MAX_STEPS_PER_PHASE`] steps in
    /// one piece.
    StepCap,
    /// More than [`MAX_PIECES`] pieces in one call.
    PieceCap,
}

impl core::fmt::Display for PlantError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.write_str(match self {
            PlantError::NonFinite => "the hopper's state became non-finite (or chi <= 0)",
            PlantError::StepCap => "the integrator hit its step cap within one control period",
            PlantError::PieceCap => "too many events within one control period",
        })
    }
}

/// The continuous state of the valve-driven hopper.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ValveState {
    /// Time, s.
    pub time_s: f64,
    /// Body height chi, m.
    pub height_m: f64,
    /// Body velocity chi', m/s.
    pub velocity_mps: f64,
    /// Foot on the ground.
    pub contact: bool,
    /// Valve open (thrust on while in stance).
    pub valve_open: bool,
    /// Thrust tau while the valve is open, m/s^2.
    pub thrust_mps2: f64,
    /// Full model: the sealed-gas constant eta of the closed leg, m^2/s^2 (see the module
    /// doc); unused by the linear model.
    pub gas_eta: f64,
}

/// The hopper with a commanded thrust valve.
#[derive(Clone, Debug)]
pub struct ValvePlant {
    model: ValveModel,
    state: ValveState,
    steps: u64,
}

type Events<'a> = &'a mut dyn FnMut(TrueEvent);

impl ValvePlant {
    /// A hopper in flight at `height_m` (>= chi_l) with velocity `velocity_mps`, valve
    /// closed, at time 0.
    pub fn new(model: ValveModel, height_m: f64, velocity_mps: f64) -> Self {
        let eta1 = match model {
            ValveModel::Full(m) => m.spring_eta1(),
            ValveModel::Linear(_) => 0.0,
        };
        Self {
            model,
            state: ValveState {
                time_s: 0.0,
                height_m,
                velocity_mps,
                contact: false,
                valve_open: false,
                thrust_mps2: 0.0,
                gas_eta: eta1,
            },
            steps: 0,
        }
    }

    /// A hopper in stance at `height_m` (< chi_l) with velocity `velocity_mps`, valve
    /// closed, at time 0 (the full model's gas sealed at touchdown, eta1).
    pub fn in_stance(model: ValveModel, height_m: f64, velocity_mps: f64) -> Self {
        let mut p = Self::new(model, height_m, velocity_mps);
        p.state.contact = true;
        p
    }

    /// The model.
    pub fn model(&self) -> &ValveModel {
        &self.model
    }

    /// The state now.
    pub fn state(&self) -> &ValveState {
        &self.state
    }

    /// Integrator steps taken so far (full model; 0 for the linear model).
    pub fn integrator_steps(&self) -> u64 {
        self.steps
    }

    /// Leg compression chi_l - chi in stance, 0 in flight, m.
    pub fn compression_m(&self) -> f64 {
        if self.state.contact {
            self.model.liftoff_m() - self.state.height_m
        } else {
            0.0
        }
    }

    /// Set the valve from now on (the thrust `thrust_mps2`, m/s^2, acts while it is open and
    /// the foot is down). Closing it in stance seals the full model's gas at the thrust
    /// pressure: eta = tau chi.
    pub fn set_valve(&mut self, open: bool, thrust_mps2: f64) {
        let s = &mut self.state;
        if s.valve_open && !open && s.contact {
            s.gas_eta = s.thrust_mps2 * s.height_m;
        }
        s.valve_open = open;
        s.thrust_mps2 = if open { thrust_mps2 } else { 0.0 };
    }

    /// Advance to `t_end_s` (no-op if not later than now), reporting events in time order.
    pub fn advance_to(&mut self, t_end_s: f64, on_event: Events<'_>) -> Result<(), PlantError> {
        for _ in 0..MAX_PIECES {
            if self.state.time_s >= t_end_s {
                return Ok(());
            }
            let span = t_end_s - self.state.time_s;
            let before = self.state.time_s;
            if !self.state.contact {
                self.flight(span, on_event);
            } else if self.state.valve_open {
                self.thrust(span, on_event);
            } else {
                match self.model {
                    ValveModel::Linear(m) => self.linear_stance(&m, span, on_event)?,
                    ValveModel::Full(m) => self.full_stance(&m, span, on_event)?,
                }
            }
            let s = &self.state;
            if !(s.height_m.is_finite() && s.velocity_mps.is_finite()) {
                return Err(PlantError::NonFinite);
            }
            // a piece that ends at t_end lands on it exactly
            if self.state.time_s >= before + span {
                self.state.time_s = t_end_s;
            }
        }
        if self.state.time_s >= t_end_s {
            Ok(())
        } else {
            Err(PlantError::PieceCap)
        }
    }

    fn flight(&mut self, span: f64, on_event: Events<'_>) {
        let g = self.model.gravity_mps2();
        let chi_l = self.model.liftoff_m();
        let s = self.state;
        let h = s.height_m - chi_l;
        let v = s.velocity_mps;
        let v_td = (v * v + 2.0 * g * h).max(0.0).sqrt();
        let t_td = (v + v_td) / g;
        if v > 0.0 && v / g <= span.min(t_td) {
            on_event(TrueEvent::Apex {
                time_s: s.time_s + v / g,
                height_m: s.height_m + v * v / (2.0 * g),
            });
        }
        if t_td <= span {
            self.state.time_s = s.time_s + t_td;
            self.state.height_m = chi_l;
            self.state.velocity_mps = -v_td;
            self.state.contact = true;
            if let ValveModel::Full(m) = self.model {
                self.state.gas_eta = m.spring_eta1();
            }
            on_event(TrueEvent::Touchdown {
                time_s: self.state.time_s,
                velocity_mps: -v_td,
            });
        } else {
            self.state.time_s = s.time_s + span;
            self.state.height_m = s.height_m + v * span - 0.5 * g * span * span;
            self.state.velocity_mps = v - g * span;
        }
    }

    /// The liftoff at `t` (from the piece start) with velocity `v` (before eq. 7).
    fn lift_off(&mut self, t0: f64, t: f64, v: f64, on_event: Events<'_>) {
        let pickup = 1.0 / (1.0 + self.model.leg_mass_ratio());
        let v = v.max(0.0);
        self.state.time_s = t0 + t;
        self.state.height_m = self.model.liftoff_m();
        self.state.velocity_mps = v * pickup;
        self.state.contact = false;
        on_event(TrueEvent::Liftoff {
            time_s: t0 + t,
            velocity_before_mps: v,
            velocity_mps: v * pickup,
            during_thrust: self.state.valve_open,
        });
    }

    fn thrust(&mut self, span: f64, on_event: Events<'_>) {
        let s = self.state;
        let a = s.thrust_mps2 - self.model.gravity_mps2();
        let gamma = self.model.friction_gamma_per_s();
        let chi_l = self.model.liftoff_m();
        let at = |t: f64| thrust_motion(s.height_m, s.velocity_mps, a, gamma, t);
        // the velocity a/gamma + (v0 - a/gamma) e^{-gamma t} is monotone: at most one zero
        let v0 = s.velocity_mps;
        let t_zero = if v0 * a < 0.0 {
            if gamma == 0.0 {
                -v0 / a
            } else {
                (-gamma * v0 / a).ln_1p() / gamma
            }
        } else {
            f64::INFINITY
        };
        if v0 < 0.0 && t_zero <= span {
            on_event(TrueEvent::Bottom {
                time_s: s.time_s + t_zero,
                height_m: at(t_zero).0,
            });
        }
        // the rising stretch within the span: from 0 to the turn, or from the bottom on
        let (lo, hi) = if v0 > 0.0 || (v0 == 0.0 && a > 0.0) {
            (0.0, t_zero.min(span))
        } else if v0 < 0.0 && a > 0.0 {
            (t_zero, span)
        } else {
            (span, span)
        };
        if lo < hi && at(hi).0 >= chi_l {
            let t = if at(lo).0 >= chi_l {
                lo
            } else {
                bisect_rising(&|t| at(t).0 - chi_l, lo, hi)
            };
            let v = at(t).1;
            self.lift_off(s.time_s, t, v, on_event);
            return;
        }
        let (x, v) = at(span);
        self.state.time_s = s.time_s + span;
        self.state.height_m = x;
        self.state.velocity_mps = v;
    }

    fn linear_stance(
        &mut self,
        m: &LinearSpring,
        span: f64,
        on_event: Events<'_>,
    ) -> Result<(), PlantError> {
        let s = self.state;
        let ceq = m.equilibrium_m();
        let (y0, v0) = (s.height_m - ceq, s.velocity_mps);
        let c = self.model.liftoff_m() - ceq;
        let half = core::f64::consts::PI / m.omega();
        let at = |t: f64| m.free_motion(y0, v0, t);
        // monotone stretches between velocity zeros t1, t1 + pi/w, ...
        let mut lo = 0.0;
        let mut zero = m.first_velocity_zero_s(y0, v0);
        if zero <= 0.0 {
            // at rest at chi_eq: no motion
            self.state.time_s = s.time_s + span;
            return Ok(());
        }
        for _ in 0..MAX_PIECES {
            let hi = zero.min(span);
            let y_lo = at(lo).0;
            // a stretch rises if it starts rising, or starts at a velocity zero below chi_eq
            let rising = if lo == 0.0 {
                v0 > 0.0 || (v0 == 0.0 && y0 < 0.0)
            } else {
                y_lo < 0.0
            };
            if rising && at(hi).0 >= c {
                let t = if y_lo >= c {
                    lo
                } else {
                    bisect_rising(&|t| at(t).0 - c, lo, hi)
                };
                let v = at(t).1;
                self.lift_off(s.time_s, t, v, on_event);
                return Ok(());
            }
            if zero > span {
                let (y, v) = at(span);
                self.state.time_s = s.time_s + span;
                self.state.height_m = y + ceq;
                self.state.velocity_mps = v;
                return Ok(());
            }
            let y_zero = at(zero).0;
            if y_zero < 0.0 {
                on_event(TrueEvent::Bottom {
                    time_s: s.time_s + zero,
                    height_m: y_zero + ceq,
                });
            }
            lo = zero;
            zero += half;
        }
        Err(PlantError::PieceCap)
    }

    fn full_stance(
        &mut self,
        m: &FullNonlinear,
        span: f64,
        on_event: Events<'_>,
    ) -> Result<(), PlantError> {
        let s = self.state;
        let (eta, gamma, g, chi_l) = (
            s.gas_eta,
            m.friction_gamma_per_s(),
            m.gravity_mps2(),
            m.liftoff_m(),
        );
        let acc = |_: f64, y: State| eta / y.0 - gamma * y.1 - g;
        let lift = |_: f64, y: State| y.0 - chi_l;
        let bottom = |_: f64, y: State| y.1;
        let turn = |_: f64, y: State| -y.1;
        let falling = s.velocity_mps < 0.0;
        let second: &dyn Fn(f64, State) -> f64 = if falling { &bottom } else { &turn };
        let y0 = (s.height_m, s.velocity_mps);
        let events = [&lift as &dyn Fn(f64, State) -> f64, second];
        let (out, n) = m.integrator().integrate(
            MAX_STEPS_PER_PHASE,
            &acc,
            y0,
            span,
            &events[..],
            &mut |_, _| {},
        );
        self.steps += n;
        match out {
            End::StepCap { .. } => Err(PlantError::StepCap),
            End::Span(y) => {
                self.state.time_s = s.time_s + span;
                (self.state.height_m, self.state.velocity_mps) = y;
                self.check_full()
            }
            End::Event {
                index: 0,
                dt_s,
                state,
            } => {
                self.lift_off(s.time_s, dt_s, state.1, on_event);
                Ok(())
            }
            End::Event { dt_s, state, .. } => {
                if falling {
                    on_event(TrueEvent::Bottom {
                        time_s: s.time_s + dt_s,
                        height_m: state.0,
                    });
                }
                self.state.time_s = s.time_s + dt_s;
                (self.state.height_m, self.state.velocity_mps) = state;
                self.check_full()
            }
        }
    }

    fn check_full(&self) -> Result<(), PlantError> {
        if self.state.height_m > 0.0 && self.state.height_m.is_finite() {
            Ok(())
        } else {
            Err(PlantError::NonFinite)
        }
    }
}
