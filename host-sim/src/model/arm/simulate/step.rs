//! One step of each phase, with its events located inside the step.
//!
//! Grasp: no state of its own (the object moves with the arm); each condition is a
//! function of time, and a sign change inside a step is located by the engine's bisection
//! ([`crate::engine::locate`]). Roll: the state (psi, psi') is integrated by the engine's
//! RK4 ([`crate::engine::ode`]); an event inside a step is located by the same bisection on
//! the time, re-integrating from the step's start. Flight is closed form.

use super::super::contact::{BodyState, Joint, Pivot, Placement, Rig};
use super::super::motion::ArmMotion;
use crate::engine::locate::bisect;
use crate::engine::ode::{Method, Rk4, State};

/// Bisection iterations for an event inside a step (2^-40 of the step).
const BISECTIONS: u32 = 40;

/// What ended a grasp step.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum GraspEvent {
    /// The contact force would have to pull: the object leaves the surface.
    Separates,
    /// The force left the friction cone: the object slips.
    Slips,
    /// The centre of pressure reached a vertex: a roll starts (+1 ccw over vertex k,
    /// -1 cw over vertex k + 1).
    Tips(f64),
}

/// The first grasp condition to fail in `(t0, t1]`, with its time; `None` if all hold.
pub fn grasp_step(
    rig: &Rig,
    place: &Placement,
    arm: &dyn ArmMotion,
    mu: f64,
    t0: f64,
    t1: f64,
) -> Option<(f64, GraspEvent)> {
    let fail = |t: f64| -> Option<GraspEvent> {
        let g = rig.grasp(place, &arm.joint(t));
        if g.force.normal <= 0.0 {
            Some(GraspEvent::Separates)
        } else if g.force.tangential.abs() > mu * g.force.normal {
            Some(GraspEvent::Slips)
        } else if g.cop_m < 0.0 {
            Some(GraspEvent::Tips(1.0))
        } else if g.cop_m > g.edge_length_m {
            Some(GraspEvent::Tips(-1.0))
        } else {
            None
        }
    };
    let at_end = fail(t1)?;
    Some(bisect((t0, t1), at_end, BISECTIONS, fail))
}

/// What ended a roll step.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum RollEvent {
    /// The pivot's contact force would have to pull: the object flies.
    Separates,
    /// The pivot slips.
    Slips,
    /// The next edge struck the surface (|psi| = gamma).
    Lands,
    /// The object fell back onto its old edge (psi = 0).
    FallsBack,
}

/// Roll state (psi, psi').
pub type RollState = (f64, f64);

fn roll_advance(
    rig: &Rig,
    pv: &Pivot,
    arm: &dyn ArmMotion,
    t0: f64,
    s: RollState,
    h: f64,
) -> RollState {
    let acc = |t: f64, y: State| rig.roll(pv, y.0, y.1, &arm.joint(t)).psi_accel_radps2;
    Rk4.step(&acc, t0, s, h).0
}

fn roll_fail(rig: &Rig, pv: &Pivot, j: &Joint, s: RollState, mu: f64) -> Option<RollEvent> {
    let r = rig.roll(pv, s.0, s.1, j);
    let a = pv.dir * s.0;
    if a >= pv.gamma_rad {
        Some(RollEvent::Lands)
    } else if a <= 0.0 {
        Some(RollEvent::FallsBack)
    } else if r.force.normal <= 0.0 {
        Some(RollEvent::Separates)
    } else if r.force.tangential.abs() > mu * r.force.normal {
        Some(RollEvent::Slips)
    } else {
        None
    }
}

/// Advance the roll over `(t0, t1]`; the state at `t1`, or at the first event and the
/// event.
pub fn roll_step(
    rig: &Rig,
    pv: &Pivot,
    arm: &dyn ArmMotion,
    mu: f64,
    t0: f64,
    t1: f64,
    s: RollState,
) -> (f64, RollState, Option<RollEvent>) {
    let at = |t: f64| {
        let s1 = roll_advance(rig, pv, arm, t0, s, t - t0);
        (s1, roll_fail(rig, pv, &arm.joint(t), s1, mu))
    };
    let (s1, e) = at(t1);
    let Some(e) = e else {
        return (t1, s1, None);
    };
    let first = |t: f64| match at(t) {
        (s, Some(e)) => Some((s, e)),
        (_, None) => None,
    };
    let (hi, (s_hi, e_hi)) = bisect((t0, t1), (s1, e), BISECTIONS, first);
    (hi, s_hi, Some(e_hi))
}

/// Lowest height of the object's vertices above the arm's surface, over the surface's
/// extent, m (positive: clear; `+inf` if no vertex is over the surface).
pub fn clearance_m(rig: &Rig, body: &BodyState, j: &Joint) -> f64 {
    rig.body
        .vertices
        .iter()
        .map(|&v| body.point(v).rotate(-j.angle_rad))
        .filter(|p| (0.0..=rig.surface.length_m).contains(&rig.surface.sigma_m(*p)))
        .map(|p| rig.surface.height_m(p))
        .fold(f64::INFINITY, f64::min)
}
