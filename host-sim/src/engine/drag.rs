//! Quadratic air drag, `b'' = -g - c |b'| b'`, integrated by the ODE engine
//! ([`super::ode`]) with the contact as its event.
//!
//! The method is a type parameter ([`Rk4`] fixed step, [`Rk45`] adaptive Dormand–Prince
//! 5(4)), chosen once when the plant is assembled, so accuracy can be traded for time. The
//! contact's witness is the paddle's height less the ball's, `p(t) - b` (`>= 0` at contact),
//! located by the engine to 2^-60 of a step (the method's own accuracy). The adaptive step is
//! kept from one flight to the next (warm start). The apex of the following flight uses the
//! exact closed form for rising flight with quadratic drag, `b + ln(1 + c v^2 / g) / (2 c)`.
//!
//! Limitation: contacts are detected by the sign of the witness at step ends, so a contact
//! in which the gap dips below zero and recovers within one step (a near-graze) is not seen;
//! choose `step_s` (or `tolerance`) small against the flight. Closed-form flights have no
//! such limitation (see [`super::roots`]).

use super::flight::{Flight, FlightEnd, Poly};
use super::ode::{End, Method, Ode, State, Witness};
pub use super::ode::{Rk4, Rk45};
use dexter_core::state::BallState;

/// Most integrator steps in one call to [`Flight::fly`]; the caller continues after.
pub const MAX_STEPS_PER_CALL: u64 = 1_000_000;

/// Flight with quadratic drag, integrated by `M`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DragFlight<M> {
    /// Drag coefficient c, 1/m.
    pub coefficient_per_m: f64,
    /// Step (RK4) or current step (RK45), s.
    pub step_s: f64,
    /// Local error tolerance (RK45), m.
    pub tolerance_m: f64,
    /// Steps taken so far (for reports and benchmarks).
    pub steps: u64,
    method: M,
}

impl<M: Method> DragFlight<M> {
    /// Drag flight with coefficient `coefficient_per_m` (1/m), step `step_s` (s) and
    /// tolerance `tolerance_m` (m, adaptive methods only).
    pub fn new(method: M, coefficient_per_m: f64, step_s: f64, tolerance_m: f64) -> Self {
        Self {
            coefficient_per_m,
            step_s,
            tolerance_m,
            steps: 0,
            method,
        }
    }
}

impl<M: Method> Flight for DragFlight<M> {
    fn fly(&mut self, ball: &mut BallState<f64>, paddle: &Poly, h_s: f64, g: f64) -> FlightEnd {
        let c = self.coefficient_per_m;
        let y = (ball.height_m, ball.velocity_mps);
        if y.0 - paddle.height_at(0.0) <= 0.0 && y.1 < paddle.velocity_mps {
            return FlightEnd::Contact {
                dt_s: 0.0,
                grazing: false,
            };
        }
        let ode = Ode {
            method: self.method,
            tolerance: self.tolerance_m,
            max_steps: MAX_STEPS_PER_CALL,
        };
        let drag = |_: f64, y: State| -g - c * y.1.abs() * y.1;
        let contact = Witness(|t: f64, y: State| paddle.height_at(t) - y.0);
        let (end, n) = ode.integrate(&mut self.step_s, &drag, y, h_s, &contact, &mut |_, _| {});
        self.steps += n;
        let (state, end) = match end {
            End::Event { dt_s, state, .. } => (
                state,
                FlightEnd::Contact {
                    dt_s,
                    grazing: false,
                },
            ),
            End::Span(state) => (state, FlightEnd::Reached(h_s)),
            End::StepCap { t_s, state } => (state, FlightEnd::Reached(t_s)),
        };
        *ball = BallState::new(state.0, state.1);
        end
    }

    fn apex_m(&self, ball: &BallState<f64>, g: f64) -> f64 {
        let v = ball.velocity_mps;
        let c = self.coefficient_per_m;
        if v <= 0.0 {
            ball.height_m
        } else if c == 0.0 {
            ball.height_m + v * v / (2.0 * g)
        } else {
            ball.height_m + (c * v * v / g).ln_1p() / (2.0 * c)
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Closed form for rising flight with quadratic drag: v(t) = vt tan(atan(v0/vt) - g t / vt),
    /// with terminal speed vt = sqrt(g / c).
    fn rising_velocity(v0: f64, g: f64, c: f64, t: f64) -> f64 {
        let vt = (g / c).sqrt();
        vt * ((v0 / vt).atan() - g * t / vt).tan()
    }

    #[test]
    fn rk4_and_rk45_match_the_closed_form_rising_flight() {
        let (g, c, v0) = (9.81, 0.1, 5.0);
        let table = Poly {
            height_m: -100.0,
            ..Poly::default()
        };
        let t_end = 0.3; // still rising: atan(5/9.9)*9.9/9.81 = 0.47 s
        for (name, err) in [
            ("rk4", {
                let mut fl = DragFlight::new(Rk4, c, 1e-3, 0.0);
                let mut b = BallState::new(0.0, v0);
                fl.fly(&mut b, &table, t_end, g);
                (b.velocity_mps - rising_velocity(v0, g, c, t_end)).abs()
            }),
            ("rk45", {
                let mut fl = DragFlight::new(Rk45, c, 1e-3, 1e-12);
                let mut b = BallState::new(0.0, v0);
                fl.fly(&mut b, &table, t_end, g);
                (b.velocity_mps - rising_velocity(v0, g, c, t_end)).abs()
            }),
        ] {
            assert!(err < 1e-9, "{name}: velocity error {err}");
        }
    }

    #[test]
    fn apex_closed_form_matches_integration() {
        let (g, c, v0) = (9.81, 0.1, 5.0);
        let fl = DragFlight::new(Rk4, c, 1e-4, 0.0);
        let apex = fl.apex_m(&BallState::new(0.0, v0), g);
        // integrate to the time the closed-form velocity reaches zero
        let vt = (g / c).sqrt();
        let t_apex = (v0 / vt).atan() * vt / g;
        let mut fl2 = DragFlight::new(Rk4, c, 1e-4, 0.0);
        let mut b = BallState::new(0.0, v0);
        let floor = Poly {
            height_m: -100.0,
            ..Poly::default()
        };
        fl2.fly(&mut b, &floor, t_apex, g);
        assert!(b.velocity_mps.abs() < 1e-10, "{}", b.velocity_mps);
        assert!(
            (b.height_m - apex).abs() < 1e-10,
            "{} vs {apex}",
            b.height_m
        );
    }

    #[test]
    fn contact_is_located_within_the_step() {
        // with c = 0 the drag flight is ballistic: contact at sqrt(2 h / g)
        let g = 9.81;
        let mut fl = DragFlight::new(Rk4, 0.0, 1e-2, 0.0);
        let mut b = BallState::new(1.0, 0.0);
        let end = fl.fly(&mut b, &Poly::default(), 10.0, g);
        let FlightEnd::Contact { dt_s, .. } = end else {
            panic!("no contact: {end:?}")
        };
        assert!((dt_s - (2.0f64 / g).sqrt()).abs() < 1e-12, "{dt_s}");
    }
}
