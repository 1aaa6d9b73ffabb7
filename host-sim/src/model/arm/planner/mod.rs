//! Planning as constrained optimization (sec. 2.1-2.4): the design variables are the
//! B-spline control points, the phase durations and mu; the constraints are sec. 2.2's
//! ([`evaluate`]); the objective is mu (plus, optionally, the squared impact speed at a
//! roll's end, fig. 2). Several initial guesses are tried ([`layout::Layout::guess`]);
//! the feasible plan with the lowest objective wins.

pub mod evaluate;
pub mod layout;
pub mod refine;
pub mod seed;
pub mod solve;

use super::motion::{PlannedMotion, RestMove};
use super::task::Phase;
use super::{ArmError, ArmScene, Solver};
use crate::progress::Progress;
use evaluate::{Kind, PlanSample, Problem};
use serde::Serialize;
use std::cell::{Cell, RefCell};
use std::time::Instant;

/// Largest scaled constraint value a plan may keep and still count as feasible (a
/// ten-thousandth of each constraint's scale: of g for forces, of the limit for torques
/// and speeds, of a tenth of the tolerance for the goal). Friction rows are not left
/// violated: mu is raised to what the samples need (`repair_mu`).
pub const FEASIBILITY_TOL: f64 = 1e-4;

/// SQP stops a hair outside the friction cone; mu is a free variable, so raise it to
/// what the samples need: the friction rows then hold exactly.
fn repair_mu(problem: &Problem, x: &mut [f64]) {
    let e = problem.evaluate(x, false);
    if let Some(mu) = x.last_mut() {
        *mu = mu.max(e.mu_needed);
    }
}

/// A phase of the plan and its timing.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct PhaseSpan {
    /// Which phase.
    pub phase: Phase,
    /// Start, s.
    pub start_s: f64,
    /// Duration, s.
    pub duration_s: f64,
}

/// A plan: the trajectory, its phases, the mu it needs, and what it cost to find.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Plan {
    /// B-spline control points, rad.
    pub points_rad: Vec<f64>,
    /// Segment duration, s.
    pub segment_s: f64,
    /// The phases in order (a flight starts at the release).
    pub phases: Vec<PhaseSpan>,
    /// The friction coefficient the plan needs: the design variable at the optimum, or
    /// the peak friction ratio the verifier finds along the whole trajectory if that is
    /// higher (the program samples the phases; the verifier steps every 0.1 ms).
    pub mu: f64,
    /// The design variable mu at the optimum (what the sampled program needs).
    pub mu_sampled: f64,
    /// Objective value.
    pub objective: f64,
    /// Normal speed of the roll-end impact, m/s (0 without one).
    pub impact_speed_mps: f64,
    /// Solver iterations, summed over the starts.
    pub iterations: usize,
    /// Program evaluations, summed over the starts.
    pub evaluations: usize,
    /// Wall time of the whole planning, s (noisy on a loaded machine).
    pub wall_time_s: f64,
    /// Which start won (0-based) and the solver's status for it.
    pub start: usize,
    /// The solver's status word for the winning start.
    pub status: String,
    /// The plan's own samples (friction ratio and torque over time).
    pub samples: Vec<PlanSample>,
}

impl Plan {
    /// The planned joint motion (spline, then the move to rest, then rest).
    pub fn motion(&self, rest: &RestMove) -> PlannedMotion {
        PlannedMotion::new(self.points_rad.clone(), self.segment_s, rest)
    }

    /// Times of the control points' Greville abscissae, s: where each point "sits" on
    /// the time axis of a plot of the trajectory with its knots.
    pub fn knot_times_s(&self) -> Vec<f64> {
        let n = self.points_rad.len();
        (0..n)
            .map(|i| {
                ((i as f64 - 1.0) * self.segment_s).clamp(0.0, (n - 3) as f64 * self.segment_s)
            })
            .collect()
    }
}

/// The largest constraint value and what it constrains.
fn worst(e: &evaluate::Eval) -> (f64, Option<Kind>) {
    e.constraints
        .iter()
        .zip(&e.kinds)
        .fold((f64::NEG_INFINITY, None), |(w, k), (&c, &kind)| {
            if c > w {
                (c, Some(kind))
            } else {
                (w, k)
            }
        })
}

/// The planning's progress on a terminal: the starts done of all
/// (each start's solves capped by `planner.max_evaluations` per refinement round), and the
/// program evaluations so far, which move while a start runs. Drawn only from the main
/// thread: a sweep plans on rayon's workers and shows its own bar over the points.
struct Meter {
    bar: RefCell<Progress>,
    starts: Cell<usize>,
    evaluations: Cell<usize>,
}

impl Meter {
    fn new(starts: usize) -> Self {
        let limits = [
            (starts as f64, "starts"),
            (f64::INFINITY, "program evaluations"),
        ];
        let wanted = rayon::current_thread_index().is_none();
        Self {
            bar: RefCell::new(Progress::new(limits, wanted)),
            starts: Cell::new(0),
            evaluations: Cell::new(0),
        }
    }

    /// One more program evaluation (the bar is redrawn every 32).
    fn evaluated(&self) {
        let n = self.evaluations.get() + 1;
        self.evaluations.set(n);
        if n.is_multiple_of(32) {
            self.show();
        }
    }

    fn start_done(&self) {
        self.starts.set(self.starts.get() + 1);
        self.show();
    }

    fn show(&self) {
        let values = [self.starts.get() as f64, self.evaluations.get() as f64];
        self.bar.borrow_mut().update(values);
    }
}

/// One start: solve, then refine the samples and solve again (at most
/// [`refine::ROUNDS`] times), every evaluation reported to `watch`. Returns the problem
/// with its extra samples and the result.
fn solve_start<'a>(
    sys: &'a ArmScene,
    x0: Vec<f64>,
    watch: &'a dyn Fn(),
) -> (Problem<'a>, solve::Solved) {
    let mut problem = Problem::new(sys);
    problem.watch = Some(watch);
    let bounds = problem.layout.bounds();
    let (mut x, mut it, mut ev) = (x0, 0, 0);
    let mut status = String::new();
    for round in 0..=refine::ROUNDS {
        let s = match sys.planner.solver {
            Solver::Slsqp => solve::slsqp(&problem, &x, &bounds, sys.planner.max_evaluations),
            Solver::Alm => solve::alm(&problem, &x, &bounds, sys.planner.max_evaluations),
        };
        (x, status) = (s.x, s.status);
        it += s.iterations;
        ev += s.evaluations;
        repair_mu(&problem, &mut x);
        if round == refine::ROUNDS || refine::add_peaks(&mut problem, &x) == 0 {
            break;
        }
    }
    let solved = solve::Solved {
        x,
        iterations: it,
        evaluations: ev,
        status,
    };
    (problem, solved)
}

/// Plan the system's task. `Err(NoPlan)` names the constraint that no start satisfied.
pub fn plan(sys: &ArmScene) -> Result<Plan, ArmError> {
    let clock = Instant::now();
    let seeding = Problem::new(sys);
    // shot seeds first, then the plain guesses: SQP's local optima differ by start
    let mut starts = seed::seeds(&seeding, sys.planner.starts);
    let shot = starts.len();
    for k in 0..sys.planner.starts.saturating_sub(shot).max(2) {
        starts.push(seeding.layout.guess(sys.task.kind, k));
    }
    let (mut iterations, mut evaluations) = (0, 0);
    let meter = Meter::new(starts.len());
    let watch = || meter.evaluated();
    let mut best: Option<(usize, Problem, solve::Solved, f64)> = None;
    let mut least_bad: (f64, Option<Kind>, String) = (f64::INFINITY, None, String::new());
    for (k, x0) in starts.into_iter().enumerate() {
        let (problem, s) = solve_start(sys, x0, &watch);
        meter.start_done();
        iterations += s.iterations;
        evaluations += s.evaluations;
        let e = problem.evaluate(&s.x, false);
        let (w, kind) = worst(&e);
        if w > FEASIBILITY_TOL {
            if w < least_bad.0 {
                least_bad = (w, kind, s.status.clone());
            }
            continue;
        }
        if best.as_ref().is_none_or(|b| e.objective < b.3) {
            best = Some((k, problem, s, e.objective));
        }
    }
    meter.bar.borrow().finish();
    let Some((start, mut problem, s, _)) = best else {
        return Err(ArmError::NoPlan(no_plan_message(least_bad)));
    };
    problem.watch = None;
    let e = problem.evaluate(&s.x, true);
    let mut d = problem.layout.decode(&s.x);
    if sys.task.kind.catches() {
        on_grid(&mut d, problem.layout.phases, sys.tracking.dt_s);
    }
    let dense = super::simulate::execute_with(
        sys,
        &problem.motion(&d),
        f64::INFINITY,
        super::simulate::SimOptions {
            record: false,
            ..Default::default()
        },
    );
    let mut t0 = 0.0;
    let phases = problem
        .layout
        .phases
        .iter()
        .zip(&d.times_s)
        .map(|(&phase, &dur)| {
            let span = PhaseSpan {
                phase,
                start_s: t0,
                duration_s: dur,
            };
            if phase != Phase::Flight {
                t0 += dur;
            }
            span
        })
        .collect();
    Ok(Plan {
        points_rad: d.points_rad,
        segment_s: d.segment_s,
        phases,
        mu: d.mu.max(dense.peak_friction_ratio * (1.0 + 1e-9)),
        mu_sampled: d.mu,
        objective: e.objective,
        impact_speed_mps: e.impact_speed_mps,
        iterations,
        evaluations,
        wall_time_s: clock.elapsed().as_secs_f64(),
        start,
        status: s.status,
        samples: e.trace,
    })
}

/// A catch's plan: stretch the design's spline (by under half a control period in all) so
/// that it ends a
/// hundredth of a period before an instant of the control grid of period `dt_s`: the
/// fixed-rate controller then switches to the move after the trajectory at that instant,
/// where the plan does (its f32 time is past the end there whatever its rounding),
/// instead of up to a period late. A throw released a period late by an arm still
/// accelerating leaves faster, and a caught object comes down turned (docs/arm.md, "The
/// juggle"). The phase times before the release stretch with it; the verifier then judges
/// this design, and `mu_required` is what it needs. Only for a catch: the stretch moves a
/// throw's landing too (by 12 mm for the rolling throw planned without its
/// centre-of-pressure margin, past a throw's 10 mm tolerance), and a throw that is not
/// caught is not sensitive to the turn it lands with.
fn on_grid(d: &mut layout::Design, phases: &[Phase], dt_s: f64) {
    let segments = d.points_rad.len().saturating_sub(3).max(1) as f64;
    let t = segments * d.segment_s;
    let end = ((t / dt_s).round().max(1.0) - 0.01) * dt_s;
    let scale = end / t;
    d.segment_s = end / segments;
    for (p, time) in phases.iter().zip(&mut d.times_s) {
        if *p != Phase::Flight {
            *time *= scale;
        }
    }
}

/// Why no start gave a plan, in words: the constraint the closest start violated most, by
/// how much (scaled), and the solver's status, each only when known.
fn no_plan_message((by, kind, status): (f64, Option<Kind>, String)) -> String {
    let mut m = String::from("no start met every constraint");
    match kind {
        Some(kind) if by.is_finite() => {
            m += &format!("; the closest start violated {kind} by {by:.3e} (scaled)");
        }
        Some(kind) => m += &format!("; the closest start violated {kind}"),
        None if by.is_finite() => m += &format!("; the closest start was off by {by:.3e} (scaled)"),
        None => m += "; no start's constraints could be evaluated (not finite)",
    }
    if !status.is_empty() {
        m += &format!(" (solver status: {status})");
    }
    m
}
