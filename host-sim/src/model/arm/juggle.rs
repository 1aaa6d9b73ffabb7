//! The one-motor juggle: throw and catch again and again, each catch leaving the state
//! the next throw starts from (Akella, Huang, Lynch & Mason, sec. 2 and 2.5).
//!
//! A juggle is a `throw_catch` scene with `task.cycles > 1`. Cycle k is the scene with the
//! object where cycle k - 1 left it (its edge on the arm and that edge's midpoint) and the
//! arm at rest where it stopped; the catch goes to the scene's catching angle and
//! position, on the edge as many edges on as the scene's catch is from its start (a square
//! turned a quarter each time). Every cycle is planned anew from that state, so a landing
//! error does not accumulate: it is closed out by the next plan, as a juggler's next throw
//! corrects the last catch.
//!
//! Two chains are run: the planned motion verified event by event (exact), and the plan
//! tracked by the core's [`ArmController`] on the joint plant (SIL, or the firmware with
//! `--hil`), whose verified end is the next cycle's start. A tracked cycle starts at rest
//! at the angle the last one ended at; the joint's residual speed after the hold is
//! dropped and reported (`end_velocity_radps`). The chain stops at the first cycle that is
//! not `ok`, saying why.

use super::closed_loop::{track, TrackedMotion};
use super::contact::Joint;
use super::motion::ArmMotion;
use super::params::ArmConfig;
use super::planner::plan;
use super::simulate::{execute, Executed, Execution};
use super::{ArmError, ArmScene};
use crate::controller::StepController;
use dexter_core::arm_control::ArmController;
use serde::Serialize;
use std::f64::consts::TAU;

/// One throw-catch cycle of a juggle.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Cycle {
    /// 0-based.
    pub cycle: usize,
    /// The verdict of the cycle's throw and catch.
    pub executed: Executed,
    /// Why.
    pub reason: String,
    /// The edge on the arm at the throw's start.
    pub start_edge: usize,
    /// That edge's midpoint along the surface at the start, m.
    pub start_position_m: f64,
    /// The joint angle at the start, rad.
    pub start_angle_rad: f64,
    /// The plan's `mu_required`.
    pub mu_required: f64,
    /// The friction coefficient the cycle was verified at.
    pub mu: f64,
    /// The caught edge's midpoint along the surface, m (null if not caught).
    pub catch_position_m: Option<f64>,
    /// Caught position less the scene's catch position, m: the landing error.
    pub landing_error_m: Option<f64>,
    /// Angle between the caught edge and the surface when it came down, rad.
    pub flat_error_rad: Option<f64>,
    /// The catch impulse's |Pi_t| / Pi_n.
    pub catch_friction_ratio: Option<f64>,
    /// The catch impulse's centre of pressure from the nearer end of the edge, m.
    pub catch_cop_margin_m: Option<f64>,
    /// Joint speed at the cycle's end, rad/s (dropped: the next cycle starts at rest).
    pub end_velocity_radps: f64,
}

/// A chain of cycles.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct Chain {
    /// Cycles that ended `ok`, in a row from the first.
    pub completed: usize,
    /// Largest |landing error| over the completed cycles, m.
    pub max_landing_error_m: f64,
    /// Every cycle run (the last one is the first that failed, if any).
    pub cycles: Vec<Cycle>,
}

/// Where a cycle starts: the object's edge and its midpoint, and the joint angle.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Start {
    edge: usize,
    position_m: f64,
    angle_rad: f64,
}

/// How far the object turns in flight from its start to the goal, rad.
fn turn_rad(sys: &ArmScene) -> f64 {
    let at = Joint {
        angle_rad: sys.task.initial_angle_rad,
        ..Default::default()
    };
    let start = sys.rig.grasped_state(&sys.start, &at).angle_rad;
    sys.task.goal.map_or(0.0, |g| g.angle_rad - start)
}

/// The scene of a cycle starting at `s`, from the juggle's tables `cfg` (an object of
/// `sides` edges): the same catch as the first cycle's, relative to the start (as many
/// edges on, the same turn in flight).
fn cycle_scene(cfg: &ArmConfig, first: &ArmScene, s: Start) -> Result<ArmScene, ArmError> {
    let sides = first.rig.body.len();
    let mut c = cfg.clone();
    let step = cfg.task.catch_edge.unwrap_or(0) + sides - cfg.object.edge % sides;
    c.object.edge = s.edge;
    c.object.position_m = s.position_m;
    c.task.initial_angle_rad = s.angle_rad;
    c.task.catch_edge = Some((s.edge + step) % sides);
    c.task.cycles = 1;
    // the edge labels wrap; the turn in flight must not
    let off = (turn_rad(first) - turn_rad(&c.validate()?)) / TAU;
    c.task.catch_turns += off.round() as i32;
    c.validate()
}

/// Run `cfg.task.cycles` cycles: exact (no `tracker`) or tracked through `tracker`,
/// whose tracked motions are returned too (for comparing HIL with SIL).
pub fn juggle(
    cfg: &ArmConfig,
    mut tracker: Option<&mut dyn StepController<ArmController>>,
) -> Result<(Chain, Vec<TrackedMotion>), ArmError> {
    let mut s = Start {
        edge: cfg.object.edge,
        position_m: cfg.object.position_m,
        angle_rad: cfg.task.initial_angle_rad,
    };
    let first = cfg.validate()?;
    let mut chain = Chain::default();
    let mut motions = Vec::new();
    for k in 0..cfg.task.cycles {
        let sys = cycle_scene(cfg, &first, s)?;
        let p = match plan(&sys) {
            Ok(p) => p,
            Err(e) => {
                chain.cycles.push(unplanned(k, s, e));
                break;
            }
        };
        let mu = sys.task.mu.unwrap_or(p.mu);
        let (run, end) = match tracker.as_deref_mut() {
            None => {
                let m = p.motion(&sys.rest_move());
                let end = m.joint(m.settled_s() + sys.task.hold_s);
                (execute(&sys, &m, mu), (end.angle_rad, end.velocity_radps))
            }
            Some(c) => {
                c.reconfigure(sys.controller_params(&p.points_rad, p.segment_s)?)
                    .map_err(|e| ArmError::NoPlan(format!("controller: {e}")))?;
                let (m, _) = track(&sys, c, &p)?;
                let end = m.states.last().copied().unwrap_or_default();
                let run = execute(&sys, &m, mu);
                motions.push(m);
                (run, end)
            }
        };
        let cycle = report(k, &sys, s, p.mu, mu, &run, end.1);
        let ok = cycle.executed == Executed::Ok;
        if ok {
            chain.completed += 1;
            let e = cycle.landing_error_m.unwrap_or(f64::NAN).abs();
            chain.max_landing_error_m = chain.max_landing_error_m.max(e);
        }
        chain.cycles.push(cycle);
        match (ok, run.rest) {
            (true, Some(r)) => {
                let l = sys.rig.body.edge_length_m(r.edge);
                s = Start {
                    edge: r.edge,
                    position_m: r.sigma_m + 0.5 * l,
                    angle_rad: end.0,
                };
            }
            _ => break,
        }
    }
    Ok((chain, motions))
}

/// A cycle that found no plan from where the last catch left the object.
fn unplanned(k: usize, s: Start, e: ArmError) -> Cycle {
    Cycle {
        cycle: k,
        executed: Executed::Missed,
        reason: format!("no plan from where the last catch left it: {e}"),
        start_edge: s.edge,
        start_position_m: s.position_m,
        start_angle_rad: s.angle_rad,
        mu_required: f64::NAN,
        mu: f64::NAN,
        catch_position_m: None,
        landing_error_m: None,
        flat_error_rad: None,
        catch_friction_ratio: None,
        catch_cop_margin_m: None,
        end_velocity_radps: 0.0,
    }
}

/// The cycle's figures from its verified run.
fn report(
    k: usize,
    sys: &ArmScene,
    s: Start,
    mu_required: f64,
    mu: f64,
    run: &Execution,
    end_velocity_radps: f64,
) -> Cycle {
    let caught = run.rest.filter(|_| run.executed == Executed::Ok);
    let position = caught.map(|r| r.sigma_m + 0.5 * sys.rig.body.edge_length_m(r.edge));
    let target = sys
        .task
        .catch
        .map(|c| c.place.sigma_m + 0.5 * sys.rig.body.edge_length_m(c.place.edge));
    let catch = run.catch_index.and_then(|i| run.impacts.get(i));
    Cycle {
        cycle: k,
        executed: run.executed,
        reason: run.reason.clone(),
        start_edge: s.edge,
        start_position_m: s.position_m,
        start_angle_rad: s.angle_rad,
        mu_required,
        mu,
        catch_position_m: position,
        landing_error_m: position.zip(target).map(|(p, t)| p - t),
        flat_error_rad: run.catch_flat_error_rad,
        catch_friction_ratio: catch.map(|c| c.impact.friction_ratio()),
        catch_cop_margin_m: catch.map(|c| c.impact.cop_margin_m()),
        end_velocity_radps,
    }
}
