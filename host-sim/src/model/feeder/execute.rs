//! Simulated execution of a plan, its summary (the feeder's JSON keys, `docs/feeder.md`)
//! and the sweep over random arrival poses.

use super::geometry::{Pose, Vec2};
use super::planner::goal::goal_edge;
use super::planner::{plan, Feeder, Plan, PlanOptions};
use super::primitives::Primitive;
use super::quasistatic::{Fence, Mode};
use super::sim::{flush_edge, run, Failure};
use super::FeederError;
use rand::rngs::StdRng;
use rand::{Rng, SeedableRng};
use rand_distr::{Distribution, Normal};
use rayon::prelude::*;
use serde::Serialize;

/// A feed succeeds when the part ends on the goal edge within this distance of the goal
/// radius, m (1 mm: a part is fed when it ends on the goal edge to 1 mm).
pub const FEED_TOL_M: f64 = 1e-3;

/// Perturbations of an execution (the plan is made with the nominal values); each is a
/// standard deviation of a normal perturbation, drawn from `seed`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
pub struct Noise {
    /// Seed of the draws.
    pub seed: u64,
    /// Belt speed, relative (0.02 = 2 %).
    pub belt_speed_rel: f64,
    /// Fence friction mu, relative.
    pub fence_mu_rel: f64,
    /// Arrival position, each axis, m.
    pub arrival_xy_m: f64,
    /// Arrival angle, rad.
    pub arrival_angle_rad: f64,
}

/// What the execution actually used.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Actual {
    /// Belt speed, m/s.
    pub belt_speed_mps: f64,
    /// Fence friction.
    pub fence_mu: f64,
    /// Arrival pose.
    pub arrival: Pose,
}

/// One picture of the filmstrip: the fence, and the part, at a knot of the schedule.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Frame {
    /// Time, s.
    pub t_s: f64,
    /// Index into the plan's steps of the primitive running at `t_s`.
    pub step: usize,
    /// Fence angle, rad.
    pub fence_angle_rad: f64,
    /// Fence tip, world, m (the pivot is the origin).
    pub fence_tip_m: Vec2,
    /// Part pose.
    pub pose: Pose,
    /// Part polygon, world, m.
    pub part_m: Vec<Vec2>,
}

/// The outcome of simulating a plan.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Execution {
    /// Part on the goal edge within [`FEED_TOL_M`] of the goal radius, with no failure.
    pub reached_goal: bool,
    /// Hull edge flush on the fence at the end, if any.
    pub final_edge: Option<usize>,
    /// Contact radius at the end, m (the COM's fence coordinate).
    pub final_contact_radius_m: f64,
    /// Final minus goal radius, m.
    pub radius_error_m: f64,
    /// Why the part left the belt or the fence, if it did.
    pub failure: Option<Failure>,
    /// The values the run used.
    pub actual: Actual,
    /// Simulation steps taken.
    pub steps: usize,
    /// Pictures at every fence-schedule knot.
    pub frames: Vec<Frame>,
}

/// Draws the perturbed belt speed, mu and arrival pose.
pub fn perturb(f: &Feeder, arrival: Pose, noise: Option<&Noise>) -> Actual {
    let nominal = Actual {
        belt_speed_mps: f.setup.medium.belt_speed_mps,
        fence_mu: f.setup.medium.fence_mu,
        arrival,
    };
    let Some(n) = noise else { return nominal };
    let mut rng = StdRng::seed_from_u64(n.seed);
    let mut g = |sd: f64| {
        if sd > 0.0 {
            Normal::new(0.0, sd).map_or(0.0, |d| d.sample(&mut rng))
        } else {
            0.0
        }
    };
    let (dv, dmu, dx, dy, da) = (
        g(n.belt_speed_rel),
        g(n.fence_mu_rel),
        g(n.arrival_xy_m),
        g(n.arrival_xy_m),
        g(n.arrival_angle_rad),
    );
    Actual {
        belt_speed_mps: nominal.belt_speed_mps * (1.0 + dv).max(0.05),
        fence_mu: (nominal.fence_mu * (1.0 + dmu)).max(0.0),
        arrival: Pose {
            com_m: arrival.com_m + Vec2::new(dx, dy),
            angle_rad: arrival.angle_rad + da,
        },
    }
}

/// One simulation step of an execution (what `--trace` streams).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct StepRecord {
    /// Time after the step, s.
    pub t_s: f64,
    /// Index into the plan's steps of the primitive running at `t_s`.
    pub step: usize,
    /// The fence at `t_s` (its angle, and the rate of the schedule segment).
    pub fence: Fence,
    /// The part's pose after the step.
    pub pose: Pose,
    /// The contact mode that held during the step.
    pub mode: Mode,
}

/// Simulates `plan` for a part arriving at `arrival`, with optional `noise`.
pub fn execute(f: &Feeder, plan: &Plan, arrival: Pose, noise: Option<&Noise>) -> Execution {
    execute_observed(f, plan, arrival, noise, &mut |_| {})
}

/// Start time of each of the plan's steps, s.
fn step_starts(plan: &Plan) -> Vec<f64> {
    plan.steps
        .iter()
        .scan(0.0, |t, s| {
            let t0 = *t;
            *t += s.duration_s();
            Some(t0)
        })
        .collect()
}

/// [`execute`], handing every simulation step to `observe` as it happens.
pub fn execute_observed(
    f: &Feeder,
    plan: &Plan,
    arrival: Pose,
    noise: Option<&Noise>,
    observe: &mut dyn FnMut(&StepRecord),
) -> Execution {
    let actual = perturb(f, arrival, noise);
    let mut setup = f.setup;
    setup.medium.belt_speed_mps = actual.belt_speed_mps;
    setup.medium.fence_mu = actual.fence_mu;
    let sched = &plan.schedule;
    let starts = step_starts(plan);
    let step_at = |t: f64| starts.iter().rposition(|&s| s <= t + 1e-9).unwrap_or(0);
    let mut frames = Vec::with_capacity(sched.knots.len());
    let (mut t, mut pose) = (0.0, actual.arrival);
    let (mut failure, mut steps) = (None, 0);
    for &(tk, _) in &sched.knots {
        if tk > t {
            let out = run(&f.part, &setup, sched, pose, t, tk, |ts, p, m| {
                observe(&StepRecord {
                    t_s: ts,
                    step: step_at(ts),
                    fence: sched.at(ts),
                    pose: *p,
                    mode: m.mode,
                })
            });
            (t, pose, failure) = (out.t_s, out.pose, out.failure);
            steps += out.steps;
        }
        frames.push(frame(f, plan, &starts, t, pose));
        if failure.is_some() {
            break;
        }
    }
    let fence = sched.at(t);
    let final_edge = if failure.is_none() {
        flush_edge(&f.part, &pose, &fence, f.setup.fence_length_m)
    } else {
        None
    };
    let r = fence.tangent().dot(pose.com_m);
    let err = r - plan.goal_radius_m;
    Execution {
        reached_goal: failure.is_none()
            && final_edge == Some(plan.goal_edge)
            && err.abs() <= FEED_TOL_M,
        final_edge,
        final_contact_radius_m: r,
        radius_error_m: err,
        failure,
        actual,
        steps,
        frames,
    }
}

fn frame(f: &Feeder, plan: &Plan, starts: &[f64], t: f64, pose: Pose) -> Frame {
    let fence = plan.schedule.at(t);
    Frame {
        t_s: t,
        step: starts.iter().rposition(|&s| s <= t + 1e-9).unwrap_or(0),
        fence_angle_rad: fence.angle_rad,
        fence_tip_m: fence.tangent().scale(f.setup.fence_length_m),
        pose,
        part_m: f.part.vertices.iter().map(|&v| pose.to_world(v)).collect(),
    }
}

/// Geometry a filmstrip needs besides the frames.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Stage {
    /// Fence length, m.
    pub fence_length_m: f64,
    /// Belt's right edge, x, m (the pivot is on the belt's center line).
    pub belt_edge_m: f64,
    /// Belt speed, m/s (the belt moves in -y).
    pub belt_speed_mps: f64,
}

/// The JSON summary of one planned and simulated feed (the keys `docs/feeder.md` documents
/// first).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Summary {
    /// Goal edge (index into the part's convex hull, counter-clockwise).
    pub goal_edge: usize,
    /// The primitives with their parameters.
    pub plan: Vec<Primitive>,
    /// The plan's time: how long the planned feed takes from the arrival pose, s (the
    /// quantity the planner minimizes, sec. 3.3).
    pub plan_time_s: f64,
    /// Whether the simulated execution reached the goal edge within [`FEED_TOL_M`] of the
    /// goal radius.
    pub reached_goal: bool,
    /// Edge flush on the fence at the end.
    pub final_edge: Option<usize>,
    /// Contact radius at the end, m.
    pub final_contact_radius_m: f64,
    /// Final minus goal radius, m.
    pub radius_error_m: f64,
    /// Goal contact radius, m.
    pub goal_radius_m: f64,
    /// The contact radius the plan predicts (its own simulation, nominal values), m.
    pub planned_radius_m: f64,
    /// Edge the part settled on at arrival.
    pub start_edge: usize,
    /// The part's stable hull edges.
    pub stable_edges: Vec<usize>,
    /// Convergent turns in the plan.
    pub convergent_turns: usize,
    /// Failure of the execution, if any.
    pub failure: Option<Failure>,
    /// Values the execution used (noise applied).
    pub actual: Actual,
    /// Simulation steps of the execution.
    pub sim_steps: usize,
    /// The planner's wall-clock time, s.
    pub wall_time_s: f64,
    /// Fence and belt for the filmstrip.
    pub stage: Stage,
    /// The filmstrip's frames: part and fence at every schedule knot (not in the JSON).
    #[serde(skip)]
    pub frames: Vec<Frame>,
}

/// Plans (timing the planner) and executes; the summary.
pub fn plan_and_execute(
    f: &Feeder,
    arrival: Pose,
    opts: &PlanOptions,
    noise: Option<&Noise>,
) -> Result<Summary, FeederError> {
    plan_and_execute_observed(f, arrival, opts, noise, &mut |_| {})
}

/// [`plan_and_execute`], handing every simulation step of the execution to `observe`.
pub fn plan_and_execute_observed(
    f: &Feeder,
    arrival: Pose,
    opts: &PlanOptions,
    noise: Option<&Noise>,
    observe: &mut dyn FnMut(&StepRecord),
) -> Result<Summary, FeederError> {
    let t0 = std::time::Instant::now();
    let p = plan(f, arrival, opts)?;
    let wall_time_s = t0.elapsed().as_secs_f64();
    let ex = execute_observed(f, &p, arrival, noise, observe);
    Ok(summarize(f, p, ex, wall_time_s))
}

/// The summary of `plan`, planned in `wall_time_s`, and its execution `ex`.
pub fn summarize(f: &Feeder, p: Plan, ex: Execution, wall_time_s: f64) -> Summary {
    let convergent_turns = p
        .steps
        .iter()
        .filter(|s| matches!(s, Primitive::ConvergentTurn { .. }))
        .count();
    Summary {
        goal_edge: p.goal_edge,
        plan_time_s: p.duration_s,
        reached_goal: ex.reached_goal,
        final_edge: ex.final_edge,
        final_contact_radius_m: ex.final_contact_radius_m,
        radius_error_m: ex.radius_error_m,
        goal_radius_m: p.goal_radius_m,
        planned_radius_m: p.predicted_radius_m,
        start_edge: p.start_edge,
        stable_edges: f.part.stable_edges(),
        convergent_turns,
        failure: ex.failure,
        actual: ex.actual,
        sim_steps: ex.steps,
        wall_time_s,
        stage: Stage {
            fence_length_m: f.setup.fence_length_m,
            belt_edge_m: f.setup.belt_edge_m,
            belt_speed_mps: f.setup.medium.belt_speed_mps,
        },
        frames: ex.frames,
        plan: p.steps,
    }
}

/// Random arrival poses of a sweep.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct SweepSpec {
    /// Arrivals.
    pub trials: usize,
    /// Seed of the arrival draws (the noise of trial i uses `noise.seed + i`).
    pub seed: u64,
    /// Arrival x range, m (uniform).
    pub x_range_m: (f64, f64),
    /// Arrival height of the COM above the pivot, m.
    pub y_m: f64,
}

/// The sweep's outcome.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct SweepResult {
    /// Arrivals tried.
    pub trials: usize,
    /// Arrivals fed to the goal edge and radius.
    pub fed: usize,
    /// fed / trials.
    pub fraction_fed: f64,
    /// Arrivals that ended on the goal edge (fed or not: the radius may miss).
    pub on_goal_edge: usize,
    /// Arrivals for which the planner found no plan, with its reason (first few).
    pub unplanned: usize,
    /// Up to 5 planner errors, for the report.
    pub errors: Vec<String>,
    /// Worst |radius error| among the fed, m.
    pub worst_radius_error_m: f64,
}

/// The arrival poses of a sweep (uniform x in range, uniform angle).
pub fn sweep_arrivals(spec: &SweepSpec) -> Vec<Pose> {
    let mut rng = StdRng::seed_from_u64(spec.seed);
    (0..spec.trials)
        .map(|_| Pose {
            com_m: Vec2::new(
                rng.random_range(spec.x_range_m.0..=spec.x_range_m.1),
                spec.y_m,
            ),
            angle_rad: rng.random_range(0.0..std::f64::consts::TAU),
        })
        .collect()
}

/// Plans and executes one feed per random arrival (in parallel); the fraction fed.
pub fn sweep(
    f: &Feeder,
    opts: &PlanOptions,
    spec: &SweepSpec,
    noise: Option<&Noise>,
) -> SweepResult {
    let arrivals = sweep_arrivals(spec);
    let outcomes: Vec<Result<Execution, FeederError>> = arrivals
        .par_iter()
        .enumerate()
        .map(|(i, &a)| {
            let n = noise.map(|n| Noise {
                seed: n.seed.wrapping_add(i as u64),
                ..*n
            });
            plan(f, a, opts).map(|p| execute(f, &p, a, n.as_ref()))
        })
        .collect();
    let fed = outcomes
        .iter()
        .filter(|o| o.as_ref().is_ok_and(|e| e.reached_goal))
        .count();
    let goal = goal_edge(&f.part);
    let on_goal_edge = outcomes
        .iter()
        .filter(|o| {
            o.as_ref().is_ok_and(|e| {
                e.failure.is_none() && e.final_edge.is_some() && e.final_edge == goal
            })
        })
        .count();
    let errors: Vec<String> = outcomes
        .iter()
        .filter_map(|o| o.as_ref().err().map(|e| e.to_string()))
        .collect();
    let worst = outcomes
        .iter()
        .filter_map(|o| {
            o.as_ref()
                .ok()
                .filter(|e| e.reached_goal)
                .map(|e| e.radius_error_m.abs())
        })
        .fold(0.0, f64::max);
    SweepResult {
        trials: spec.trials,
        fed,
        fraction_fed: if spec.trials > 0 {
            fed as f64 / spec.trials as f64
        } else {
            0.0
        },
        on_goal_edge,
        unplanned: errors.len(),
        errors: errors.into_iter().take(5).collect(),
        worst_radius_error_m: worst,
    }
}
