//! The one ODE engine: second-order scalar equations `x'' = a(t, x, x')` integrated by a
//! fixed-step or an adaptive method, with events declared as witness functions and located
//! by the engine.
//!
//! Every integrated phase in the simulator is of this form: the line juggler's ball under
//! quadratic drag ([`super::drag`]), the hopper's pneumatic stance (eq. 8 of Koditschek &
//! Bühler, `crate::model::hopper`), the arm's joint under a held torque and the object's
//! roll about a vertex (`crate::model::arm`). A model hands the engine its acceleration and
//! its events; it writes no stepping or bisection loop of its own.
//!
//! - **Methods** ([`Method`]): [`Rk4`], classical Runge–Kutta with a fixed step (global
//!   error O(h^4)), and [`Rk45`], Dormand–Prince 5(4) with its embedded error estimate
//!   (local error on x, and on x' times the step, both in the unit of x). The method is a
//!   type parameter chosen once when a plant is assembled, or [`Integrator`] at run time.
//! - **Step control** (adaptive methods): a step whose error estimate exceeds the tolerance
//!   is retried shorter (factor `0.9 (tol/err)^(1/5)`, clamped to [0.1, 0.9]), at most
//!   [`MAX_REJECTIONS`] times in a row and never below [`MIN_STEP_S`]; an accepted step sets
//!   the next (the same factor, clamped to [0.2, 5]).
//! - **Events** (in the manner of Drake's witness functions): each is a function `w(t, y)`
//!   of the time since the start of the integration and the state, negative before its event
//!   and `>= 0` at it. They are checked at the end of every accepted step (never at the
//!   start); the first in declaration order that fired is the event. It is then located by
//!   bisection on the length of that step, re-integrating from the step's start with one
//!   step of the method, [`EVENT_BISECTIONS`] halvings (to 2^-60 of a step: to the method's
//!   own accuracy). The state returned is the one just past the event (its witness `>= 0`).
//! - **Caps**: every loop is bounded; a run of [`Ode::integrate`] ends with
//!   [`End::StepCap`] after `max_steps` method steps (rejected and bisection steps count).
//!
//! Limitation: an event whose witness becomes non-negative and negative again within one
//! step (a near-graze) is not seen. Choose the step (or the tolerance) small against the
//! phase; closed-form flights have no such limitation (see [`super::roots`]).

use super::locate::bisect;
use dexter_core::params::{positive, ParamError};

/// The state (x, x'), in the unit of x and that unit per second.
pub type State = (f64, f64);

/// Bisection halvings that locate an event within a step.
pub const EVENT_BISECTIONS: u32 = 60;
/// Most step rejections in a row (adaptive methods) before the step is accepted anyway.
pub const MAX_REJECTIONS: u32 = 60;
/// Smallest adaptive step, s.
pub const MIN_STEP_S: f64 = 1e-14;

/// One step of an ODE method for `x'' = a(t, x, x')`.
pub trait Method: Copy {
    /// True for methods that adapt their step (and return an error estimate).
    const ADAPTIVE: bool;
    /// Advance `y` at time `t` (s) by `h` (s): the new state and the local error estimate
    /// (in the unit of x; 0 for fixed-step methods).
    fn step(self, a: &impl Fn(f64, State) -> f64, t: f64, y: State, h: f64) -> (State, f64);
}

/// Classical Runge–Kutta 4, fixed step.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Rk4;

impl Method for Rk4 {
    const ADAPTIVE: bool = false;

    #[inline]
    fn step(self, a: &impl Fn(f64, State) -> f64, t: f64, y: State, h: f64) -> (State, f64) {
        let k1 = (y.1, a(t, y));
        let y2 = (y.0 + 0.5 * h * k1.0, y.1 + 0.5 * h * k1.1);
        let k2 = (y2.1, a(t + 0.5 * h, y2));
        let y3 = (y.0 + 0.5 * h * k2.0, y.1 + 0.5 * h * k2.1);
        let k3 = (y3.1, a(t + 0.5 * h, y3));
        let y4 = (y.0 + h * k3.0, y.1 + h * k3.1);
        let k4 = (y4.1, a(t + h, y4));
        (
            (
                y.0 + h / 6.0 * (k1.0 + 2.0 * k2.0 + 2.0 * k3.0 + k4.0),
                y.1 + h / 6.0 * (k1.1 + 2.0 * k2.1 + 2.0 * k3.1 + k4.1),
            ),
            0.0,
        )
    }
}

/// Dormand–Prince 5(4), adaptive: the 5th-order solution, and the difference to the
/// embedded 4th-order one as the error estimate.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Rk45;

/// Dormand–Prince stage times, as fractions of the step.
const DP_C: [f64; 6] = [1.0 / 5.0, 3.0 / 10.0, 4.0 / 5.0, 8.0 / 9.0, 1.0, 1.0];
/// Dormand–Prince stage weights; row 5 is the 5th-order solution's (first same as last).
const DP_A: [[f64; 6]; 6] = [
    [1.0 / 5.0, 0.0, 0.0, 0.0, 0.0, 0.0],
    [3.0 / 40.0, 9.0 / 40.0, 0.0, 0.0, 0.0, 0.0],
    [44.0 / 45.0, -56.0 / 15.0, 32.0 / 9.0, 0.0, 0.0, 0.0],
    [
        19372.0 / 6561.0,
        -25360.0 / 2187.0,
        64448.0 / 6561.0,
        -212.0 / 729.0,
        0.0,
        0.0,
    ],
    [
        9017.0 / 3168.0,
        -355.0 / 33.0,
        46732.0 / 5247.0,
        49.0 / 176.0,
        -5103.0 / 18656.0,
        0.0,
    ],
    [
        35.0 / 384.0,
        0.0,
        500.0 / 1113.0,
        125.0 / 192.0,
        -2187.0 / 6784.0,
        11.0 / 84.0,
    ],
];
/// 5th- minus 4th-order weights.
const DP_E: [f64; 7] = [
    71.0 / 57600.0,
    0.0,
    -71.0 / 16695.0,
    71.0 / 1920.0,
    -17253.0 / 339200.0,
    22.0 / 525.0,
    -1.0 / 40.0,
];

impl Method for Rk45 {
    const ADAPTIVE: bool = true;

    fn step(self, a: &impl Fn(f64, State) -> f64, t: f64, y: State, h: f64) -> (State, f64) {
        let mut k = [(0.0, 0.0); 7];
        k[0] = (y.1, a(t, y));
        for s in 0..6 {
            let mut yi = y;
            for (j, kj) in k.iter().enumerate().take(s + 1) {
                yi.0 += h * DP_A[s][j] * kj.0;
                yi.1 += h * DP_A[s][j] * kj.1;
            }
            k[s + 1] = (yi.1, a(t + DP_C[s] * h, yi));
        }
        // k[6] is f at the 5th-order solution (row 5 of DP_A are its weights)
        let mut y5 = y;
        for (j, kj) in k.iter().enumerate().take(6) {
            y5.0 += h * DP_A[5][j] * kj.0;
            y5.1 += h * DP_A[5][j] * kj.1;
        }
        let (mut e0, mut e1) = (0.0, 0.0);
        for (j, kj) in k.iter().enumerate() {
            e0 += h * DP_E[j] * kj.0;
            e1 += h * DP_E[j] * kj.1;
        }
        (y5, e0.abs().max((e1 * h).abs()))
    }
}

/// `n` steps of `h / n` of the method from `y` at `t` (fixed steps, no step control, no
/// events): the state at `t + h`.
#[inline]
pub fn fixed_steps<M: Method>(
    method: M,
    a: &impl Fn(f64, State) -> f64,
    t: f64,
    y: State,
    h: f64,
    n: usize,
) -> State {
    let dt = h / n as f64;
    let mut y = y;
    for i in 0..n {
        y = method.step(a, t + i as f64 * dt, y, dt).0;
    }
    y
}

/// The events of an integration: their witness functions (module docs, "Events").
pub trait Witnesses {
    /// The first event, in declaration order, whose witness is `>= 0` at `(t, y)`.
    fn fired(&self, t: f64, y: State) -> Option<usize>;
}

/// Any number of events, each a witness `w(t, y)` (event index = position).
impl Witnesses for [&dyn Fn(f64, State) -> f64] {
    #[inline]
    fn fired(&self, t: f64, y: State) -> Option<usize> {
        self.iter().position(|w| w(t, y) >= 0.0)
    }
}

/// One event, its witness a closure (event index 0; called directly, not through `dyn`).
#[derive(Clone, Copy, Debug)]
pub struct Witness<F>(pub F);

impl<F: Fn(f64, State) -> f64> Witnesses for Witness<F> {
    #[inline]
    fn fired(&self, t: f64, y: State) -> Option<usize> {
        (self.0(t, y) >= 0.0).then_some(0)
    }
}

/// How [`Ode::integrate`] ended.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum End {
    /// Event `index` (into the events) fired `dt_s` s after the start, at `state`.
    Event {
        /// Which event.
        index: usize,
        /// Time from the start, s.
        dt_s: f64,
        /// The state just past the event.
        state: State,
    },
    /// The span ended without an event, at this state.
    Span(State),
    /// The step cap was reached `t_s` s after the start, at `state`, before the span's end.
    StepCap {
        /// Time from the start, s.
        t_s: f64,
        /// The state then.
        state: State,
    },
}

/// An integration: the method, its tolerance and its step cap.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Ode<M> {
    /// The method.
    pub method: M,
    /// Local error tolerance (adaptive methods), in the unit of x.
    pub tolerance: f64,
    /// Most method steps (accepted, rejected and bisection steps) in one integration.
    pub max_steps: u64,
}

impl<M: Method> Ode<M> {
    /// Integrate `x'' = a(t, x, x')` from `y0` at t = 0 over `span_s` s (`f64::INFINITY`:
    /// until an event or the cap), or until one of `events` fires; the last step is
    /// shortened to end on the span. `step_s` is the first step (s) and, for adaptive
    /// methods, is left at the next step the controller chose (a caller that keeps it
    /// warm-starts its next integration). `on_step(t, y)` sees every accepted step's end and
    /// the located event. Returns how it ended and the method steps taken.
    #[allow(clippy::too_many_arguments)]
    pub fn integrate<W: Witnesses + ?Sized>(
        &self,
        step_s: &mut f64,
        a: &impl Fn(f64, State) -> f64,
        y0: State,
        span_s: f64,
        events: &W,
        on_step: &mut impl FnMut(f64, State),
    ) -> (End, u64) {
        let (mut y, mut t, mut steps) = (y0, 0.0, 0u64);
        while t < span_s {
            if steps >= self.max_steps {
                return (End::StepCap { t_s: t, state: y }, steps);
            }
            let first = if *step_s >= span_s - t {
                span_s - t
            } else {
                *step_s
            };
            let (hs, y1) = self.accepted_step(step_s, a, t, y, first, &mut steps);
            if let Some(index) = events.fired(t + hs, y1) {
                let (dt, state, index) =
                    self.locate(a, events, (t, y), (hs, y1, index), &mut steps);
                on_step(t + dt, state);
                let dt_s = t + dt;
                return (End::Event { index, dt_s, state }, steps);
            }
            y = y1;
            t = if hs >= span_s - t { span_s } else { t + hs };
            on_step(t, y);
        }
        (End::Span(y), steps)
    }

    /// One accepted step from `y` at `t`, trying `hs` first: its length and end state; for
    /// adaptive methods `step_s` is left at the next step.
    #[inline]
    fn accepted_step(
        &self,
        step_s: &mut f64,
        a: &impl Fn(f64, State) -> f64,
        t: f64,
        y: State,
        mut hs: f64,
        steps: &mut u64,
    ) -> (f64, State) {
        let tol = self.tolerance;
        let mut rejections = 0;
        loop {
            let (yn, err) = self.method.step(a, t, y, hs);
            *steps += 1;
            if !M::ADAPTIVE {
                return (hs, yn);
            }
            let factor = if err > 0.0 {
                0.9 * (tol / err).powf(0.2)
            } else {
                5.0
            };
            if err > tol && hs > MIN_STEP_S && rejections < MAX_REJECTIONS {
                hs = (hs * factor.clamp(0.1, 0.9)).max(MIN_STEP_S);
                rejections += 1;
                continue;
            }
            *step_s = (hs * factor.clamp(0.2, 5.0)).max(MIN_STEP_S);
            return (hs, yn);
        }
    }

    /// Locate the event that fired at the end of the step `(hs, y1)` from `(t, y)`, by
    /// bisection on the step's length: (time into the step, state, event).
    #[inline]
    fn locate<W: Witnesses + ?Sized>(
        &self,
        a: &impl Fn(f64, State) -> f64,
        events: &W,
        (t, y): (f64, State),
        (hs, y1, first): (f64, State, usize),
        steps: &mut u64,
    ) -> (f64, State, usize) {
        let step = |mid: f64| {
            let (ym, _) = self.method.step(a, t, y, mid);
            *steps += 1;
            events.fired(t + mid, ym).map(|i| (ym, i))
        };
        let (hi, (y_hi, idx)) = bisect((0.0, hs), (y1, first), EVENT_BISECTIONS, step);
        (hi, y_hi, idx)
    }
}

/// The method chosen at run time (e.g. by a scene key), with its step settings.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Integrator {
    /// [`Rk4`] with a fixed step `step_s` (s, > 0).
    Rk4 {
        /// Step, s (> 0).
        step_s: f64,
    },
    /// [`Rk45`] with local error tolerance `tolerance_m` (in the unit of x) and first
    /// trial step `initial_step_s` (s).
    Rk45 {
        /// Local error tolerance (> 0).
        tolerance_m: f64,
        /// First trial step, s (> 0).
        initial_step_s: f64,
    },
}

impl Integrator {
    /// A validated [`Integrator::Rk4`] (`step_s` > 0 and finite; the error names `step_s`).
    pub fn rk4(step_s: f64) -> Result<Self, ParamError> {
        Ok(Integrator::Rk4 {
            step_s: positive("step_s", step_s)?,
        })
    }

    /// A validated [`Integrator::Rk45`] (both > 0 and finite; the error names the first
    /// invalid one, `tolerance_m` or `step_s`).
    pub fn rk45(tolerance_m: f64, initial_step_s: f64) -> Result<Self, ParamError> {
        Ok(Integrator::Rk45 {
            tolerance_m: positive("tolerance_m", tolerance_m)?,
            initial_step_s: positive("step_s", initial_step_s)?,
        })
    }

    /// [`Ode::integrate`] with this method, starting from its first step each call (no
    /// warm start), capped at `max_steps`.
    pub fn integrate<W: Witnesses + ?Sized>(
        self,
        max_steps: u64,
        a: &impl Fn(f64, State) -> f64,
        y0: State,
        span_s: f64,
        events: &W,
        on_step: &mut impl FnMut(f64, State),
    ) -> (End, u64) {
        match self {
            Integrator::Rk4 { step_s } => {
                let ode = Ode {
                    method: Rk4,
                    tolerance: 0.0,
                    max_steps,
                };
                ode.integrate(&mut { step_s }, a, y0, span_s, events, on_step)
            }
            Integrator::Rk45 {
                tolerance_m,
                initial_step_s,
            } => {
                let ode = Ode {
                    method: Rk45,
                    tolerance: tolerance_m,
                    max_steps,
                };
                ode.integrate(&mut { initial_step_s }, a, y0, span_s, events, on_step)
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// x'' = -x from (1, 0): x = cos t, x' = -sin t.
    fn oscillator(_: f64, y: State) -> f64 {
        -y.0
    }

    #[test]
    fn rk4_has_fourth_order_global_error() {
        let a = oscillator;
        let err = |n: usize| {
            let y = fixed_steps(Rk4, &a, 0.0, (1.0, 0.0), 1.0, n);
            (y.0 - 1f64.cos()).abs()
        };
        // halving the step divides the error by 2^4
        let ratio = err(20) / err(40);
        assert!((ratio - 16.0).abs() < 0.5, "ratio {ratio}");
    }

    #[test]
    fn rk45_keeps_its_tolerance_and_adapts_the_step() {
        let ode = Ode {
            method: Rk45,
            tolerance: 1e-10,
            max_steps: 100_000,
        };
        let mut h = 1e-3;
        let (end, steps) = ode.integrate(
            &mut h,
            &oscillator,
            (1.0, 0.0),
            2.0,
            &[][..],
            &mut |_, _| {},
        );
        let End::Span(y) = end else { panic!("{end:?}") };
        assert!((y.0 - 2f64.cos()).abs() < 1e-8, "{}", y.0 - 2f64.cos());
        assert!((y.1 + 2f64.sin()).abs() < 1e-8);
        // far fewer steps than a fixed 1 ms step would need, and the step grew
        assert!(steps < 200, "{steps}");
        assert!(h > 1e-3);
    }

    #[test]
    fn time_dependent_acceleration_is_integrated_at_the_stage_times() {
        // x'' = 6 t: x = t^3 from rest at 0; RK4 and DP45 are exact on cubics
        let a = |t: f64, _: State| 6.0 * t;
        let y = fixed_steps(Rk4, &a, 0.0, (0.0, 0.0), 1.5, 3);
        assert!((y.0 - 1.5f64.powi(3)).abs() < 1e-13, "{}", y.0);
        let (y5, _) = Rk45.step(&a, 0.5, (0.125, 0.75), 1.0);
        assert!((y5.0 - 1.5f64.powi(3)).abs() < 1e-13, "{}", y5.0);
        assert!((y5.1 - 3.0 * 1.5f64.powi(2)).abs() < 1e-13);
    }

    #[test]
    fn an_event_is_located_to_the_method_accuracy() {
        // x = cos t crosses 0 at pi/2: the witness -x fires there
        let ode = Ode {
            method: Rk4,
            tolerance: 0.0,
            max_steps: 100_000,
        };
        let w = |_: f64, y: State| -y.0;
        let mut seen = Vec::new();
        let (end, _) = ode.integrate(
            &mut 1e-3,
            &oscillator,
            (1.0, 0.0),
            f64::INFINITY,
            &Witness(w),
            &mut |t, _| seen.push(t),
        );
        let End::Event { index, dt_s, state } = end else {
            panic!("{end:?}")
        };
        assert_eq!(index, 0);
        assert!((dt_s - std::f64::consts::FRAC_PI_2).abs() < 1e-12, "{dt_s}");
        assert!(state.0 <= 0.0 && state.0 > -1e-12, "just past the event");
        assert_eq!(seen.last(), Some(&dt_s), "on_step sees the event");
    }

    #[test]
    fn the_first_declared_event_wins_and_time_reaches_the_witness() {
        // a witness of time alone (t - 0.25) and one of the state (x'' = -1: x' < -0.5 at 0.5)
        let ode = Ode {
            method: Rk4,
            tolerance: 0.0,
            max_steps: 1000,
        };
        let clock = |t: f64, _: State| t - 0.25;
        let slow = |_: f64, y: State| -0.5 - y.1;
        let events: [&dyn Fn(f64, State) -> f64; 2] = [&slow, &clock];
        let (end, _) = ode.integrate(
            &mut 0.1,
            &|_, _| -1.0,
            (0.0, 0.0),
            1.0,
            &events[..],
            &mut |_, _| {},
        );
        let End::Event { index, dt_s, .. } = end else {
            panic!("{end:?}")
        };
        assert_eq!(index, 1, "the clock fires first, at 0.25 s");
        assert!((dt_s - 0.25).abs() < 1e-15, "{dt_s}");
    }

    #[test]
    fn a_witness_that_reaches_zero_at_a_step_end_fires_there() {
        // witnesses fire at >= 0: t - 0.25 is exactly 0 at the end of the second 0.125 s
        // step, so the event is that step's end, with no bisection past it
        let ode = Ode {
            method: Rk4,
            tolerance: 0.0,
            max_steps: 1000,
        };
        let clock = |t: f64, _: State| t - 0.25;
        let one = |t: f64, _: State| t - 0.25;
        for end in [
            ode.integrate(
                &mut 0.125,
                &|_, _| 0.0,
                (0.0, 0.0),
                1.0,
                &[&clock as &dyn Fn(f64, State) -> f64][..],
                &mut |_, _| {},
            )
            .0,
            ode.integrate(
                &mut 0.125,
                &|_, _| 0.0,
                (0.0, 0.0),
                1.0,
                &Witness(one),
                &mut |_, _| {},
            )
            .0,
        ] {
            let End::Event { dt_s, .. } = end else {
                panic!("{end:?}")
            };
            assert_eq!(dt_s, 0.25);
        }
    }

    #[test]
    fn the_span_is_ended_exactly_and_the_cap_holds() {
        let ode = Ode {
            method: Rk4,
            tolerance: 0.0,
            max_steps: 1000,
        };
        let mut last = 0.0;
        let (end, steps) = ode.integrate(
            &mut 0.3,
            &oscillator,
            (1.0, 0.0),
            1.0,
            &[][..],
            &mut |t, _| last = t,
        );
        assert!(matches!(end, End::Span(_)));
        assert_eq!(
            (steps, last),
            (4, 1.0),
            "0.3, 0.3, 0.3 and the 0.1 that ends on the span"
        );
        let capped = Ode {
            max_steps: 3,
            ..ode
        };
        let (end, steps) = capped.integrate(
            &mut 0.3,
            &oscillator,
            (1.0, 0.0),
            1.0,
            &[][..],
            &mut |_, _| {},
        );
        assert_eq!(steps, 3);
        let End::StepCap { t_s, .. } = end else {
            panic!("{end:?}")
        };
        assert!((t_s - 0.9).abs() < 1e-15);
    }

    #[test]
    fn an_unmeetable_tolerance_ends_at_the_smallest_step_not_in_a_loop() {
        // tolerance 0: each rejection cuts the step tenfold until MIN_STEP_S, where every
        // step is accepted; the run ends at its cap
        let ode = Ode {
            method: Rk45,
            tolerance: 0.0,
            max_steps: 100,
        };
        let mut h = 1e-3;
        let (end, steps) = ode.integrate(
            &mut h,
            &oscillator,
            (1.0, 0.0),
            1.0,
            &[][..],
            &mut |_, _| {},
        );
        assert!(matches!(end, End::StepCap { .. }), "{end:?}");
        assert_eq!(steps, 100);
        assert_eq!(h, MIN_STEP_S);
    }
}
