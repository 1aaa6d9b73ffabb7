//! Numerical integration with event location, for the full model's stance phases only
//! (eq. 8: pneumatic spring with friction and gravity has no closed form).
//!
//! The state is (chi, chi') with chi'' = a(chi, chi'). The method is chosen per scene:
//! [`Integrator::Rk4`] (classical Runge-Kutta, fixed step) or [`Integrator::Rk45`]
//! (Dormand-Prince 5(4), adaptive), so accuracy can be traded for time; the run reports its
//! step count. (The simulator's `engine::integrate` hard-codes the drag force in its
//! `Method` trait, so the hopper has its own small generic stepper.)
//!
//! An event is a function of the state that is negative before it and crosses to >= 0 at
//! it. After a step that crosses, the event is located by bisection on the length of that
//! step, re-integrating from its start with one step of the method ([`EVENT_BISECTIONS`]
//! halvings: to 2^-60 of a step, i.e. to the method's own accuracy). Every loop is capped.

use dexter_core::params::{positive, ParamError};

/// Most integrator steps in one stance phase; the run ends with
/// [`super::RunEnd::StepCap`] beyond.
pub const MAX_STEPS_PER_PHASE: u64 = 10_000_000;
/// Bisection halvings that locate an event within a step.
pub const EVENT_BISECTIONS: u32 = 60;
/// Most step rejections in a row (adaptive method) before the step is forced.
pub const MAX_REJECTIONS: u32 = 60;
/// Smallest adaptive step, s.
pub const MIN_STEP_S: f64 = 1e-14;

/// The integration method for the full model's stance phases.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Integrator {
    /// Classical RK4 with a fixed step `step_s` (s); global error O(step^4).
    Rk4 {
        /// Step, s (> 0).
        step_s: f64,
    },
    /// Dormand-Prince 5(4) with local error tolerance `tolerance_m` (m, on chi and on
    /// chi' times the step) and first step `initial_step_s` (s).
    Rk45 {
        /// Local error tolerance, m (> 0).
        tolerance_m: f64,
        /// First trial step, s (> 0).
        initial_step_s: f64,
    },
}

impl Integrator {
    /// A validated RK4 integrator (`hopper.step_s` must be > 0).
    pub fn rk4(step_s: f64) -> Result<Self, ParamError> {
        Ok(Integrator::Rk4 {
            step_s: positive("hopper.step_s", step_s)?,
        })
    }
    /// A validated RK45 integrator.
    pub fn rk45(tolerance_m: f64, initial_step_s: f64) -> Result<Self, ParamError> {
        Ok(Integrator::Rk45 {
            tolerance_m: positive("hopper.tolerance_m", tolerance_m)?,
            initial_step_s: positive("hopper.step_s", initial_step_s)?,
        })
    }
}

/// (chi, chi').
pub type State = (f64, f64);

impl Integrator {
    /// The first step size, s, and the error tolerance, m (0 for fixed steps).
    fn first_step_and_tolerance(self) -> (f64, f64) {
        match self {
            Integrator::Rk4 { step_s } => (step_s, 0.0),
            Integrator::Rk45 {
                tolerance_m,
                initial_step_s,
            } => (initial_step_s, tolerance_m),
        }
    }
}

/// One step of size `h`: Dormand-Prince 5(4) with its error estimate if `adaptive`, else
/// RK4 with error 0.
fn one_step(adaptive: bool, a: &impl Fn(State) -> f64, y: State, h: f64) -> (State, f64) {
    if adaptive {
        dp45_step(a, y, h)
    } else {
        (rk4_step(a, y, h), 0.0)
    }
}

fn rk4_step(a: &impl Fn(State) -> f64, y: State, h: f64) -> State {
    let k1 = (y.1, a(y));
    let y2 = (y.0 + 0.5 * h * k1.0, y.1 + 0.5 * h * k1.1);
    let k2 = (y2.1, a(y2));
    let y3 = (y.0 + 0.5 * h * k2.0, y.1 + 0.5 * h * k2.1);
    let k3 = (y3.1, a(y3));
    let y4 = (y.0 + h * k3.0, y.1 + h * k3.1);
    let k4 = (y4.1, a(y4));
    (
        y.0 + h / 6.0 * (k1.0 + 2.0 * k2.0 + 2.0 * k3.0 + k4.0),
        y.1 + h / 6.0 * (k1.1 + 2.0 * k2.1 + 2.0 * k3.1 + k4.1),
    )
}

/// One Dormand-Prince 5(4) step: the 5th-order state and the local error estimate (m).
fn dp45_step(a: &impl Fn(State) -> f64, y: State, h: f64) -> (State, f64) {
    const C: [[f64; 6]; 6] = [
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
    const E: [f64; 7] = [
        71.0 / 57600.0,
        0.0,
        -71.0 / 16695.0,
        71.0 / 1920.0,
        -17253.0 / 339200.0,
        22.0 / 525.0,
        -1.0 / 40.0,
    ];
    let mut k = [(0.0, 0.0); 7];
    k[0] = (y.1, a(y));
    for s in 0..6 {
        let mut yi = y;
        for (j, kj) in k.iter().enumerate().take(s + 1) {
            yi.0 += h * C[s][j] * kj.0;
            yi.1 += h * C[s][j] * kj.1;
        }
        k[s + 1] = (yi.1, a(yi));
    }
    // k[6] is f at the 5th-order solution (row 5 of C are the b weights: FSAL)
    let mut y5 = y;
    for (j, kj) in k.iter().enumerate().take(6) {
        y5.0 += h * C[5][j] * kj.0;
        y5.1 += h * C[5][j] * kj.1;
    }
    let (mut e0, mut e1) = (0.0, 0.0);
    for (j, kj) in k.iter().enumerate() {
        e0 += h * E[j] * kj.0;
        e1 += h * E[j] * kj.1;
    }
    (y5, e0.abs().max((e1 * h).abs()))
}

/// How [`integrate_to_event`] ended.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Outcome {
    /// The event `index` (into the event list) fired after `dt_s` s, at this state.
    Event {
        /// Which event.
        index: usize,
        /// Time from the phase start, s.
        dt_s: f64,
        /// The state at the event.
        state: State,
    },
    /// [`MAX_STEPS_PER_PHASE`] steps without an event.
    StepCap,
}

/// Integrate chi'' = `a`(chi, chi') from `y0` until one of `events` fires (each is
/// negative before its event and non-negative at it); `on_step(dt, state)` sees every
/// accepted step. Returns the outcome and the steps taken.
pub fn integrate_to_event(
    method: Integrator,
    a: &impl Fn(State) -> f64,
    y0: State,
    events: &[&dyn Fn(State) -> f64],
    on_step: &mut impl FnMut(f64, State),
) -> (Outcome, u64) {
    let fired = |y: State| events.iter().position(|e| e(y) >= 0.0);
    let mut y = y0;
    let mut t = 0.0;
    let mut steps = 0u64;
    let (mut h, tol) = method.first_step_and_tolerance();
    let adaptive = matches!(method, Integrator::Rk45 { .. });
    let step = |y: State, h: f64| one_step(adaptive, a, y, h);
    while steps < MAX_STEPS_PER_PHASE {
        let mut hs = h;
        let mut y1;
        let mut rejections = 0;
        loop {
            let (yn, err) = step(y, hs);
            y1 = yn;
            steps += 1;
            if !adaptive {
                break;
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
            h = (hs * factor.clamp(0.2, 5.0)).max(MIN_STEP_S);
            break;
        }
        if let Some(first) = fired(y1) {
            // locate within (0, hs]: bisect on the step length
            let (mut lo, mut hi) = (0.0, hs);
            let mut y_hi = y1;
            let mut idx = first;
            for _ in 0..EVENT_BISECTIONS {
                let mid = 0.5 * (lo + hi);
                if mid <= lo || mid >= hi {
                    break;
                }
                let (ym, _) = step(y, mid);
                steps += 1;
                match fired(ym) {
                    Some(i) => {
                        hi = mid;
                        y_hi = ym;
                        idx = i;
                    }
                    None => lo = mid,
                }
            }
            on_step(t + hi, y_hi);
            return (
                Outcome::Event {
                    index: idx,
                    dt_s: t + hi,
                    state: y_hi,
                },
                steps,
            );
        }
        y = y1;
        t += hs;
        on_step(t, y);
    }
    (Outcome::StepCap, steps)
}

/// How [`integrate_span`] ended.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum SpanOutcome {
    /// The event `index` fired after `dt_s` s (< the span), at this state.
    Event {
        /// Which event.
        index: usize,
        /// Time from the span start, s.
        dt_s: f64,
        /// The state at the event.
        state: State,
    },
    /// The span ended without an event, at this state.
    End(State),
    /// [`MAX_STEPS_PER_PHASE`] steps without reaching the span's end.
    StepCap,
}

/// Integrate chi'' = `a`(chi, chi') from `y0` for `span_s` s, or until one of `events` fires
/// (each negative before its event and non-negative at it; checked after each step, never
/// at the start), as [`integrate_to_event`] does, with the last step shortened to end on the
/// span. For plants stepped at a fixed rate (the sampled hopper's full model between two
/// control steps). Returns the outcome and the steps taken.
pub fn integrate_span(
    method: Integrator,
    a: &impl Fn(State) -> f64,
    y0: State,
    span_s: f64,
    events: &[&dyn Fn(State) -> f64],
) -> (SpanOutcome, u64) {
    let fired = |y: State| events.iter().position(|e| e(y) >= 0.0);
    let (mut h, tol) = method.first_step_and_tolerance();
    let adaptive = matches!(method, Integrator::Rk45 { .. });
    let step = |y: State, h: f64| one_step(adaptive, a, y, h);
    let (mut y, mut t, mut steps) = (y0, 0.0, 0u64);
    while t < span_s {
        if steps >= MAX_STEPS_PER_PHASE {
            return (SpanOutcome::StepCap, steps);
        }
        let last = h >= span_s - t;
        let mut hs = if last { span_s - t } else { h };
        let mut rejections = 0;
        let y1 = loop {
            let (yn, err) = step(y, hs);
            steps += 1;
            if !adaptive {
                break yn;
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
            h = (hs * factor.clamp(0.2, 5.0)).max(MIN_STEP_S);
            break yn;
        };
        if let Some(first) = fired(y1) {
            let (mut lo, mut hi, mut y_hi, mut idx) = (0.0, hs, y1, first);
            for _ in 0..EVENT_BISECTIONS {
                let mid = 0.5 * (lo + hi);
                if mid <= lo || mid >= hi {
                    break;
                }
                let (ym, _) = step(y, mid);
                steps += 1;
                match fired(ym) {
                    Some(i) => (hi, y_hi, idx) = (mid, ym, i),
                    None => lo = mid,
                }
            }
            let dt_s = t + hi;
            return (
                SpanOutcome::Event {
                    index: idx,
                    dt_s,
                    state: y_hi,
                },
                steps,
            );
        }
        y = y1;
        t = if hs >= span_s - t { span_s } else { t + hs };
    }
    (SpanOutcome::End(y), steps)
}
