//! Quadratic air drag, `b'' = -g - c |b'| b'`, integrated numerically with event location.
//!
//! The method is a type parameter ([`Rk4`] fixed step, [`Rk45`] adaptive Dormand-Prince
//! 5(4)), chosen once when the plant is assembled, so accuracy can be traded for time.
//! A contact is located by bisection on the length of the last step, re-integrating from
//! its start: the event time is found to 2^-60 of a step (to the method's own accuracy).
//! The apex of the following flight uses the exact closed form for rising flight with
//! quadratic drag, `b + ln(1 + c v^2 / g) / (2 c)`.
//!
//! Limitation: contacts are detected by the sign of the gap at step ends, so a contact in
//! which the gap dips below zero and recovers within one step (a near-graze) is not seen;
//! choose `step_s` (or `tolerance`) small against the flight. Closed-form flights have no
//! such limitation (see [`super::roots`]).

use super::flight::{Flight, FlightEnd, Poly};
use dexter_core::state::BallState;

/// Most integrator steps in one call to [`Flight::fly`]; the caller continues after.
pub const MAX_STEPS_PER_CALL: u32 = 1_000_000;
/// Bisection iterations that locate a contact within a step.
pub const EVENT_BISECTIONS: u32 = 60;

/// One step of an ODE method for the drag flight.
pub trait Method {
    /// Advance `y = (b, b')` by `h` s; returns the new state and, for adaptive methods, an
    /// error estimate (m), else 0.
    fn step(&self, y: (f64, f64), h: f64, g: f64, c: f64) -> ((f64, f64), f64);
    /// True for methods that adapt their step.
    const ADAPTIVE: bool;
}

#[inline]
fn f(y: (f64, f64), g: f64, c: f64) -> (f64, f64) {
    (y.1, -g - c * y.1.abs() * y.1)
}

/// Classical Runge-Kutta 4, fixed step.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Rk4;

impl Method for Rk4 {
    const ADAPTIVE: bool = false;
    #[inline]
    fn step(&self, y: (f64, f64), h: f64, g: f64, c: f64) -> ((f64, f64), f64) {
        let k1 = f(y, g, c);
        let k2 = f((y.0 + 0.5 * h * k1.0, y.1 + 0.5 * h * k1.1), g, c);
        let k3 = f((y.0 + 0.5 * h * k2.0, y.1 + 0.5 * h * k2.1), g, c);
        let k4 = f((y.0 + h * k3.0, y.1 + h * k3.1), g, c);
        (
            (
                y.0 + h / 6.0 * (k1.0 + 2.0 * k2.0 + 2.0 * k3.0 + k4.0),
                y.1 + h / 6.0 * (k1.1 + 2.0 * k2.1 + 2.0 * k3.1 + k4.1),
            ),
            0.0,
        )
    }
}

/// Dormand-Prince 5(4), adaptive (local error on the height, m).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Rk45;

impl Method for Rk45 {
    const ADAPTIVE: bool = true;
    fn step(&self, y: (f64, f64), h: f64, g: f64, c: f64) -> ((f64, f64), f64) {
        const A21: f64 = 1.0 / 5.0;
        const A31: f64 = 3.0 / 40.0;
        const A32: f64 = 9.0 / 40.0;
        const A41: f64 = 44.0 / 45.0;
        const A42: f64 = -56.0 / 15.0;
        const A43: f64 = 32.0 / 9.0;
        const A51: f64 = 19372.0 / 6561.0;
        const A52: f64 = -25360.0 / 2187.0;
        const A53: f64 = 64448.0 / 6561.0;
        const A54: f64 = -212.0 / 729.0;
        const A61: f64 = 9017.0 / 3168.0;
        const A62: f64 = -355.0 / 33.0;
        const A63: f64 = 46732.0 / 5247.0;
        const A64: f64 = 49.0 / 176.0;
        const A65: f64 = -5103.0 / 18656.0;
        const B1: f64 = 35.0 / 384.0;
        const B3: f64 = 500.0 / 1113.0;
        const B4: f64 = 125.0 / 192.0;
        const B5: f64 = -2187.0 / 6784.0;
        const B6: f64 = 11.0 / 84.0;
        // error coefficients b - b* (5th minus 4th order)
        const E1: f64 = 71.0 / 57600.0;
        const E3: f64 = -71.0 / 16695.0;
        const E4: f64 = 71.0 / 1920.0;
        const E5: f64 = -17253.0 / 339200.0;
        const E6: f64 = 22.0 / 525.0;
        const E7: f64 = -1.0 / 40.0;
        let k1 = f(y, g, c);
        let k2 = f((y.0 + h * A21 * k1.0, y.1 + h * A21 * k1.1), g, c);
        let k3 = f(
            (
                y.0 + h * (A31 * k1.0 + A32 * k2.0),
                y.1 + h * (A31 * k1.1 + A32 * k2.1),
            ),
            g,
            c,
        );
        let k4 = f(
            (
                y.0 + h * (A41 * k1.0 + A42 * k2.0 + A43 * k3.0),
                y.1 + h * (A41 * k1.1 + A42 * k2.1 + A43 * k3.1),
            ),
            g,
            c,
        );
        let k5 = f(
            (
                y.0 + h * (A51 * k1.0 + A52 * k2.0 + A53 * k3.0 + A54 * k4.0),
                y.1 + h * (A51 * k1.1 + A52 * k2.1 + A53 * k3.1 + A54 * k4.1),
            ),
            g,
            c,
        );
        let k6 = f(
            (
                y.0 + h * (A61 * k1.0 + A62 * k2.0 + A63 * k3.0 + A64 * k4.0 + A65 * k5.0),
                y.1 + h * (A61 * k1.1 + A62 * k2.1 + A63 * k3.1 + A64 * k4.1 + A65 * k5.1),
            ),
            g,
            c,
        );
        let y5 = (
            y.0 + h * (B1 * k1.0 + B3 * k3.0 + B4 * k4.0 + B5 * k5.0 + B6 * k6.0),
            y.1 + h * (B1 * k1.1 + B3 * k3.1 + B4 * k4.1 + B5 * k5.1 + B6 * k6.1),
        );
        let k7 = f(y5, g, c);
        let err_b = h * (E1 * k1.0 + E3 * k3.0 + E4 * k4.0 + E5 * k5.0 + E6 * k6.0 + E7 * k7.0);
        let err_v = h * (E1 * k1.1 + E3 * k3.1 + E4 * k4.1 + E5 * k5.1 + E6 * k6.1 + E7 * k7.1);
        // velocity error weighted by the step so both are in metres
        (y5, err_b.abs().max((err_v * h).abs()))
    }
}

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
        let gap = |y: (f64, f64), t: f64| y.0 - paddle.height_at(t);
        let mut y = (ball.height_m, ball.velocity_mps);
        let g0 = gap(y, 0.0);
        if g0 <= 0.0 && y.1 < paddle.velocity_mps {
            return FlightEnd::Contact {
                dt_s: 0.0,
                grazing: false,
            };
        }
        let mut t = 0.0;
        let mut h = self.step_s;
        for _ in 0..MAX_STEPS_PER_CALL {
            if t >= h_s {
                break;
            }
            let hs = h.min(h_s - t);
            let (y1, err) = self.method.step(y, hs, g, c);
            self.steps += 1;
            if M::ADAPTIVE {
                let tol = self.tolerance_m;
                let factor = if err > 0.0 {
                    0.9 * (tol / err).powf(0.2)
                } else {
                    5.0
                };
                if err > tol && hs > 1e-12 {
                    h = hs * factor.clamp(0.1, 0.9);
                    continue;
                }
                h = (hs * factor.clamp(0.2, 5.0)).max(1e-12);
                self.step_s = h;
            }
            let t1 = t + hs;
            if gap(y1, t1) < 0.0 {
                // locate the contact in (t, t1]: bisect on the length of this step
                let (mut lo, mut hi) = (0.0, hs);
                let mut y_hi = y1;
                for _ in 0..EVENT_BISECTIONS {
                    let mid = 0.5 * (lo + hi);
                    if mid <= lo || mid >= hi {
                        break;
                    }
                    let (ym, _) = self.method.step(y, mid, g, c);
                    if gap(ym, t + mid) < 0.0 {
                        hi = mid;
                        y_hi = ym;
                    } else {
                        lo = mid;
                    }
                }
                *ball = BallState::new(y_hi.0, y_hi.1);
                return FlightEnd::Contact {
                    dt_s: t + hi,
                    grazing: false,
                };
            }
            y = y1;
            t = if hs == h_s - t { h_s } else { t1 };
        }
        *ball = BallState::new(y.0, y.1);
        FlightEnd::Reached(t)
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
