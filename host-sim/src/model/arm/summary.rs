//! One call for a system module: plan, verify, check the friction margin, optionally
//! track on the core, and return a serializable summary with what the plots need.
//!
//! JSON keys (issue 15): `task`, `phases`, `mu_required`, `planner_iterations`,
//! `planner_wall_time_s`, `goal_error`, `executed` (`"ok"`, `"slipped"`,
//! `"lost_contact"`, `"missed"`), `mu_margin_check` (the run at 0.95 mu), plus
//! `trajectory` (samples and knots), `friction` (executed and planned), `frames`
//! (filmstrip), `arm_outline`, `events`, `tracked` (the closed loop on the core).

use super::closed_loop::{track_sil, TrackingReport};
use super::contact::Joint;
use super::geometry::V2;
use super::motion::ArmMotion;
use super::planner::evaluate::PlanSample;
use super::planner::{plan, PhaseSpan, Plan};
use super::simulate::{execute, Event, Executed, Execution, Frame, FrictionSample, GoalError};
use super::{ArmError, ArmScene, Solver};
use serde::Serialize;

/// Factor of the margin check (issue 15: "mu 5 % below the plan's value").
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
    /// Samples every 5 ms through the spline and the release brake.
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
    /// Friction needed over time in the verified run.
    pub friction: Vec<FrictionSample>,
    /// Friction needed at the plan's own samples.
    pub friction_planned: Vec<PlanSample>,
    /// Filmstrip frames of the verified run.
    pub frames: Vec<Frame>,
    /// The arm's outline in its own frame (link and palm), m: rotate by a frame's angle.
    pub arm_outline: Vec<V2>,
    /// Events of the verified run.
    pub events: Vec<Event>,
    /// The plan tracked by the core's controller (SIL), if asked for.
    pub tracked: Option<TrackingReport>,
}

/// What to run besides planning and verifying.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct RunOptions {
    /// Close the loop with the core's controller (SIL) and verify the tracked motion.
    pub track: bool,
}

/// Plan, verify at mu and at 0.95 mu, optionally track; the summary.
pub fn run(sys: &ArmScene, opt: RunOptions) -> Result<ArmSummary, ArmError> {
    let p = plan(sys)?;
    let motion = p.motion(sys.bounds.brake_accel_radps2);
    let ok = execute(sys, &motion, p.mu);
    let low = execute(sys, &motion, MARGIN_FACTOR * p.mu);
    let tracked = if opt.track {
        Some(track_sil(sys, &p)?.1)
    } else {
        None
    };
    Ok(summarize(sys, &p, &motion, ok, low, tracked))
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

impl ArmSummary {
    /// A few lines for a terminal.
    pub fn text(&self) -> String {
        let mut s = format!(
            "task {} ({}): mu_required {:.4}, planner {:?} {} iterations {:.2} s ({})\n",
            self.task,
            self.phases,
            self.mu_required,
            self.planner_solver,
            self.planner_iterations,
            self.planner_wall_time_s,
            self.planner_status
        );
        s += &format!("executed: {:?} ({})\n", self.executed, self.reason);
        if let Some(e) = self.goal_error {
            s += &format!(
                "goal error: {:.4} m, {:.4} rad\n",
                e.position_m, e.angle_rad
            );
        }
        let m = &self.mu_margin_check;
        s += &format!(
            "at mu {:.4} (0.95x): {:?} ({})\n",
            m.mu, m.executed, m.reason
        );
        if let Some(t) = &self.tracked {
            s += &format!(
                "tracked on the core: {:?}, max error {:.2e} rad, needs mu {:.4} ({:?} with it)\n",
                t.executed, t.max_tracking_error_rad, t.mu_needed, t.executed_at_mu_needed
            );
        }
        s
    }
}
