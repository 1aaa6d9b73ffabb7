//! The arm system's run in one call: plan, verify, check the friction margin, optionally
//! track on the core, and return a serializable summary with what the plots need.
//!
//! JSON keys (`docs/arm.md`): `task`, `phases`, `mu_required`, `planner_iterations`,
//! `planner_wall_time_s`, `goal_error`, `executed` (`"ok"`, `"slipped"`,
//! `"lost_contact"`, `"missed"`), `mu_margin_check` (the run at 0.95 mu), plus
//! `trajectory` (its knots), `events`, `tracked` (the closed loop on the core). What only
//! the plots need (trajectory samples, friction over time, filmstrip frames, the arm's
//! outline) is kept in the summary but left out of its JSON.

use crate::controller::StepController;
use crate::model::arm::closed_loop::{sil_controller, track, TrackedMotion, TrackingReport};
use crate::model::arm::contact::Joint;
use crate::model::arm::geometry::V2;
use crate::model::arm::impact::{ImpactLaw, Outcome};
use crate::model::arm::motion::ArmMotion;
use crate::model::arm::planner::evaluate::PlanSample;
use crate::model::arm::planner::{plan, PhaseSpan, Plan};
use crate::model::arm::simulate::{
    execute_observed, execute_with, Event, Executed, Execution, Frame, FrictionSample, GoalError,
    ImpactRecord, Sample, SimOptions,
};
use crate::model::arm::{ArmError, ArmScene, Solver};
use dexter_core::arm_control::ArmController;
use serde::Serialize;

/// Factor of the margin check: the plan must still hold with mu 5 % below the value it
/// was planned with.
pub const MARGIN_FACTOR: f64 = 0.95;
/// Interval of trajectory samples in the summary, s.
pub const TRAJECTORY_DT_S: f64 = 0.005;

/// What the run at reduced friction did.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct MarginCheck {
    /// The friction coefficient used: 0.95 `mu_required`.
    pub mu: f64,
    /// Its verdict (anything but `ok` confirms the plan needs its mu).
    pub executed: Executed,
    /// Why.
    pub reason: String,
}

/// A knot (control point) placed on the time axis at its Greville abscissa.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Knot {
    /// Time, s.
    pub t_s: f64,
    /// Control point, rad.
    pub angle_rad: f64,
}

/// The joint trajectory for plots.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct TrajectoryData {
    /// Segment duration, s.
    pub segment_s: f64,
    /// The control points on the time axis.
    pub knots: Vec<Knot>,
    /// Samples every 5 ms through the spline and the release brake (plots; not in the
    /// JSON: `--trace` has the motion).
    #[serde(skip_serializing)]
    pub samples: Vec<(f64, Joint)>,
}

/// Everything a run of an arm scene found.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct ArmSummary {
    /// `snatch`, `throw`, `roll` or `rolling_throw`.
    pub task: &'static str,
    /// The phase letters, e.g. `grg`.
    pub phases: String,
    /// The friction coefficient the plan needs.
    pub mu_required: f64,
    /// The planner's mu variable (what its samples need, with the 1 % margin);
    /// `mu_required` is this or the verifier's dense peak, whichever is higher.
    pub mu_sampled: f64,
    /// The solver used.
    pub planner_solver: Solver,
    /// Solver iterations (summed over starts).
    pub planner_iterations: usize,
    /// Program evaluations (summed over starts, finite differences included).
    pub planner_evaluations: usize,
    /// Wall time of planning, s.
    pub planner_wall_time_s: f64,
    /// The winning start and the solver's status for it.
    pub planner_start: usize,
    /// See `planner_start`.
    pub planner_status: String,
    /// Distance from the goal at the end of the verified run.
    pub goal_error: Option<GoalError>,
    /// The verdict of the planned trajectory at `mu_required`.
    pub executed: Executed,
    /// The phase letters the verified run went through (`ok` only if they are `phases`).
    pub executed_phases: String,
    /// Why.
    pub reason: String,
    /// The same trajectory at 0.95 `mu_required`.
    pub mu_margin_check: MarginCheck,
    /// Roll landing speed, m/s (plan's value).
    pub impact_speed_mps: f64,
    /// The phases and their times.
    pub phase_times: Vec<PhaseSpan>,
    /// Joint trajectory with knots.
    pub trajectory: TrajectoryData,
    /// Friction needed over time in the verified run (plots only).
    #[serde(skip_serializing)]
    pub friction: Vec<FrictionSample>,
    /// Friction needed at the plan's own samples (plots only).
    #[serde(skip_serializing)]
    pub friction_planned: Vec<PlanSample>,
    /// Filmstrip frames of the verified run (plots only).
    #[serde(skip_serializing)]
    pub frames: Vec<Frame>,
    /// The arm's outline in its own frame (link and palm), m: rotate by a frame's angle
    /// (plots only).
    #[serde(skip_serializing)]
    pub arm_outline: Vec<V2>,
    /// Events of the verified run.
    pub events: Vec<Event>,
    /// The impact law the verifier applied (`object.impact_law`).
    pub impact_law: ImpactLaw,
    /// Impacts of the verified run whose impulse pulled (the no-rebound law only; 0 under
    /// the one-sided law, whose impulses only push).
    pub pulling_impacts: usize,
    /// Every impact of the verified run (an edge on the surface): the one-sided law's
    /// outcome (`grasp` or a `rock`), its impulse, the impulse's centre of pressure with its
    /// margin to the edge's ends, and the friction it needs.
    pub impacts: Vec<ImpactSummary>,
    /// A throw and catch's catch: its impact, how far from flat the edge came down, and
    /// whether it was feasible (stopped outright on the edge, the impulse inside the
    /// friction cone of `mu_required`, the grasp after it held to the end).
    pub catch: Option<CatchSummary>,
    /// The plan tracked by the core's controller (SIL), if asked for.
    pub tracked: Option<TrackingReport>,
}

/// One impact of the verified run, for the JSON.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct ImpactSummary {
    /// When, s.
    pub t_s: f64,
    /// The edge that struck.
    pub edge: usize,
    /// `grasp` (stopped on the edge) or `rock` (onto the striking vertex).
    pub outcome: &'static str,
    /// Normal speed of the striking end, m/s.
    pub speed_mps: f64,
    /// Impulse per unit mass along the normal, m/s.
    pub impulse_normal_mps: f64,
    /// Impulse per unit mass along the tangent, m/s.
    pub impulse_tangential_mps: f64,
    /// The impulse's centre of pressure from the edge's first vertex, m.
    pub cop_m: f64,
    /// Its distance from the nearer end of the edge, m (>= 0: on the edge).
    pub cop_margin_m: f64,
    /// Where a stop outright would need it, m (off the edge: it would have to pull).
    pub stop_cop_m: f64,
    /// The edge's length, m.
    pub edge_length_m: f64,
    /// The impulse's resultant is off the edge: it pulled (only under the no-rebound law).
    pub pulls: bool,
    /// |Pi_t| / Pi_n.
    pub friction_ratio: f64,
    /// Relative rate before and after, rad/s.
    pub rate_before_radps: f64,
    /// See `rate_before_radps`.
    pub rate_after_radps: f64,
}

/// The catch of a throw and catch, for the JSON.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct CatchSummary {
    /// Stopped outright on the edge, inside the cone, and held (`executed` is `ok`).
    pub feasible: bool,
    /// Angle between the caught edge and the surface when it came down, rad.
    pub flat_error_rad: f64,
    /// The catch's impact.
    #[serde(flatten)]
    pub impact: ImpactSummary,
}

impl From<&ImpactRecord> for ImpactSummary {
    fn from(r: &ImpactRecord) -> Self {
        let i = &r.impact;
        Self {
            t_s: r.t_s,
            edge: r.edge,
            outcome: match i.outcome {
                Outcome::Grasp => "grasp",
                Outcome::Rock { .. } => "rock",
            },
            speed_mps: i.speed_mps,
            impulse_normal_mps: i.impulse_normal_mps,
            impulse_tangential_mps: i.impulse_tangential_mps,
            cop_m: i.cop_m,
            cop_margin_m: i.cop_margin_m(),
            stop_cop_m: i.stop_cop_m,
            edge_length_m: i.edge_length_m,
            pulls: i.pulls(),
            friction_ratio: i.friction_ratio(),
            rate_before_radps: i.rate_before_radps,
            rate_after_radps: i.rate_after_radps,
        }
    }
}

/// What to run besides planning and verifying.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct RunOptions {
    /// Close the loop with the core's controller (SIL) and verify the tracked motion.
    pub track: bool,
}

/// Plan, verify at mu and at 0.95 mu, optionally track (SIL); the summary.
pub fn run(sys: &ArmScene, opt: RunOptions) -> Result<ArmSummary, ArmError> {
    let p = plan(sys)?;
    let mut sil = match opt.track {
        true => Some(sil_controller(sys, &p)?),
        false => None,
    };
    let tracker = sil
        .as_mut()
        .map(|c| c as &mut dyn StepController<ArmController>);
    Ok(run_with(sys, &p, tracker, &mut |_| {})?.0)
}

/// Verify `plan` at its mu (handing `observe` every [`Sample`] of that run) and at 0.95
/// mu, and, with a `tracker` (the core linked in, or the firmware in QEMU), close the
/// joint's loop through it and verify the tracked motion; the summary and the tracked
/// motion.
pub fn run_with(
    sys: &ArmScene,
    plan: &Plan,
    tracker: Option<&mut dyn StepController<ArmController>>,
    observe: &mut dyn FnMut(&Sample),
) -> Result<(ArmSummary, Option<TrackedMotion>), ArmError> {
    let motion = plan.motion(&sys.rest_move());
    let ok = execute_observed(sys, &motion, plan.mu, SimOptions::default(), observe);
    let quiet = SimOptions {
        record: false,
        ..SimOptions::default()
    };
    let low = execute_with(sys, &motion, MARGIN_FACTOR * plan.mu, quiet);
    let (tracked_motion, tracked) = match tracker {
        Some(c) => {
            let (m, r) = track(sys, c, plan)?;
            (Some(m), Some(r))
        }
        None => (None, None),
    };
    let summary = summarize(sys, plan, &motion, ok, low, tracked);
    Ok((summary, tracked_motion))
}

fn summarize(
    sys: &ArmScene,
    p: &Plan,
    motion: &dyn ArmMotion,
    ok: Execution,
    low: Execution,
    tracked: Option<TrackingReport>,
) -> ArmSummary {
    let end = motion.settled_s() + sys.task.hold_s;
    let samples = (0..=(end / TRAJECTORY_DT_S).ceil() as usize)
        .map(|k| {
            let t = k as f64 * TRAJECTORY_DT_S;
            (t, motion.joint(t))
        })
        .collect();
    let knots = p
        .knot_times_s()
        .into_iter()
        .zip(&p.points_rad)
        .map(|(t_s, &angle_rad)| Knot { t_s, angle_rad })
        .collect();
    ArmSummary {
        task: sys.task.kind.name(),
        phases: sys.task.kind.letters(),
        mu_required: p.mu,
        mu_sampled: p.mu_sampled,
        planner_solver: sys.planner.solver,
        planner_iterations: p.iterations,
        planner_evaluations: p.evaluations,
        planner_wall_time_s: p.wall_time_s,
        planner_start: p.start,
        planner_status: p.status.clone(),
        goal_error: ok.goal_error,
        executed: ok.executed,
        executed_phases: ok.phases.clone(),
        reason: ok.reason,
        mu_margin_check: MarginCheck {
            mu: low.mu,
            executed: low.executed,
            reason: low.reason,
        },
        impact_speed_mps: p.impact_speed_mps,
        phase_times: p.phases.clone(),
        trajectory: TrajectoryData {
            segment_s: p.segment_s,
            knots,
            samples,
        },
        friction: ok.friction,
        friction_planned: p.samples.clone(),
        frames: ok.frames,
        arm_outline: arm_outline(sys),
        events: ok.events,
        impact_law: sys.impact_law,
        pulling_impacts: ok.impacts.iter().filter(|r| r.impact.pulls()).count(),
        impacts: ok.impacts.iter().map(ImpactSummary::from).collect(),
        catch: ok
            .catch_index
            .and_then(|i| ok.impacts.get(i))
            .map(|r| CatchSummary {
                feasible: ok.executed == Executed::Ok && r.impact.outcome == Outcome::Grasp,
                flat_error_rad: ok.catch_flat_error_rad.unwrap_or(f64::NAN),
                impact: ImpactSummary::from(r),
            }),
        tracked,
    }
}

/// The link as a rectangle from the joint axis to its tip (top surface at the given
/// half thickness), and the palm as a segment from the tip, in the arm frame.
fn arm_outline(sys: &ArmScene) -> Vec<V2> {
    let s = &sys.rig.surface;
    let h = s.origin.y;
    let (l, palm) = if s.beta_rad == 0.0 {
        (s.length_m, None)
    } else {
        (s.origin.x, Some(s.point(s.length_m)))
    };
    let mut v = vec![V2::new(0.0, -h), V2::new(l, -h), V2::new(l, h)];
    if let Some(tip) = palm {
        v.push(tip);
        v.push(V2::new(l, h));
    }
    v.push(V2::new(0.0, h));
    v
}
