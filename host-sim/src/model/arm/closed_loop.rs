//! The plan run on the core: the arm's joint closed through a [`StepController`] of the
//! core's [`ArmController`] (SIL: [`Sil`], the same code the firmware runs), then the
//! object verified against the joint motion that really happened.
//!
//! The plant is the joint as a second-order system with the motor's torque limit:
//! `J theta'' = sat(tau) - tau_g cos(theta + phi_g)`, with `J`, `tau_g`, `phi_g` the arm
//! with the object as a rigid payload at its starting place (the controller's model too;
//! the object's reaction torque as it rolls or flies is left out, a 0.1 kg object against a
//! 2.2 kg m^2 arm). Between control instants the torque is held (zero-order hold) and
//! the joint is integrated by RK4 with eight substeps. The tracking error therefore comes
//! from the hold, the controller's f32 arithmetic and polynomial cosine, its feedback
//! gains and its limits.

use super::contact::Joint;
use super::motion::{ArmMotion, PlannedMotion};
use super::planner::Plan;
use super::simulate::{execute, Executed, GoalError};
use super::{ArmError, ArmScene};
use crate::closed_loop::{drive, SampledPlant};
use crate::controller::{ControllerError, Sil, StepController};
use crate::engine::ode::{fixed_steps, Rk4, State};
use dexter_core::arm_control::{ArmCommand, ArmController, ArmFrame};
use dexter_core::fixed_rate::{Fault, Mode};
use serde::Serialize;
use std::ops::ControlFlow;

/// RK4 substeps per control period.
const SUBSTEPS: usize = 8;

/// The joint plant: inertia, gravity torque and the torque limit.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct JointPlant {
    /// Inertia, kg m^2.
    pub inertia_kgm2: f64,
    /// Gravity torque amplitude, N m.
    pub gravity_torque_nm: f64,
    /// Gravity torque phase, rad.
    pub gravity_phase_rad: f64,
    /// Torque limit, N m.
    pub torque_max_nm: f64,
}

impl JointPlant {
    fn accel(&self, angle: f64, tau: f64) -> f64 {
        let tau = tau.clamp(-self.torque_max_nm, self.torque_max_nm);
        (tau - self.gravity_torque_nm * (angle + self.gravity_phase_rad).cos()) / self.inertia_kgm2
    }

    /// The joint after `h` seconds under constant torque `tau`, by RK4 in `n` steps.
    fn advance(&self, angle: f64, vel: f64, tau: f64, h: f64, n: usize) -> (f64, f64) {
        let accel = |_: f64, y: State| self.accel(y.0, tau);
        fixed_steps(Rk4, &accel, 0.0, (angle, vel), h, n)
    }
}

/// The joint motion a closed loop produced: the state at each control instant and the
/// torque held after it.
#[derive(Clone, Debug, PartialEq)]
pub struct TrackedMotion {
    /// The plant.
    pub plant: JointPlant,
    /// Control period, s.
    pub dt_s: f64,
    /// (angle rad, velocity rad/s) at each control instant.
    pub states: Vec<(f64, f64)>,
    /// Torque held over each period, N m.
    pub torques_nm: Vec<f64>,
    /// End of the planned spline (the release brake's start), s.
    pub release_s: f64,
    /// When the planned motion is at rest, s (the run goes on past it for the hold).
    pub settled_s: f64,
}

impl ArmMotion for TrackedMotion {
    fn joint(&self, t_s: f64) -> Joint {
        let last = self.states.len().saturating_sub(1);
        let k = ((t_s / self.dt_s).floor().max(0.0) as usize).min(last);
        let (x0, v0) = self.states[k];
        let tau = self.torques_nm.get(k).copied().unwrap_or(0.0);
        let s = (t_s - k as f64 * self.dt_s).clamp(0.0, self.dt_s);
        let n = ((s / self.dt_s * SUBSTEPS as f64).ceil() as usize).max(1);
        let (x, v) = self.plant.advance(x0, v0, tau, s, n);
        Joint {
            angle_rad: x,
            velocity_radps: v,
            accel_radps2: self.plant.accel(x, tau),
        }
    }

    fn settled_s(&self) -> f64 {
        self.settled_s
    }

    fn release_s(&self) -> f64 {
        self.release_s
    }

    fn breaks_s(&self) -> Vec<f64> {
        (0..=self.torques_nm.len())
            .map(|k| k as f64 * self.dt_s)
            .collect()
    }
}

/// How the tracked run went.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct TrackingReport {
    /// The verdict of the object against the tracked motion, at the plan's mu.
    pub executed: Executed,
    /// Why.
    pub reason: String,
    /// Distance from the goal at the end.
    pub goal_error: Option<GoalError>,
    /// The friction the tracked motion needs (peak ratio with unlimited friction).
    pub mu_needed: f64,
    /// The verdict with friction `mu_needed`: does the tracked motion reach the goal
    /// when friction suffices?
    pub executed_at_mu_needed: Executed,
    /// Why.
    pub reason_at_mu_needed: String,
    /// Distance from the goal at the end of that run.
    pub goal_error_at_mu_needed: Option<GoalError>,
    /// Largest |reference - angle| over the run, rad.
    pub max_tracking_error_rad: f64,
    /// RMS tracking error over the run, rad.
    pub rms_tracking_error_rad: f64,
    /// Largest commanded torque magnitude, N m.
    pub max_torque_nm: f64,
    /// The controller's fault, if it went to its safe state.
    pub fault: Option<String>,
    /// Control steps run.
    pub steps: usize,
}

/// The joint sampled at the controller's rate, and the tracking figures as it goes.
struct Tracking<'a> {
    m: TrackedMotion,
    planned: &'a PlannedMotion,
    dt: f64,
    /// Largest |reference - angle| so far, rad.
    worst: f64,
    /// Sum of the squared tracking errors, rad^2.
    sq: f64,
    /// Largest |torque| commanded, N m.
    tau_max: f64,
    /// The first safe-state fault, and its step.
    fault: Option<String>,
}

impl SampledPlant<ArmController> for Tracking<'_> {
    type End = std::convert::Infallible;
    type Error = ControllerError;

    fn frame(&mut self, k: u64, _t_k: f64) -> ArmFrame {
        let (x, v) = self.m.states[k as usize];
        ArmFrame {
            seq: k as u32,
            angle_rad: x as f32,
            velocity_radps: v as f32,
        }
    }

    fn apply(&mut self, k: u64, t_k: f64, cmd: &ArmCommand) {
        if cmd.mode == Mode::Safe && self.fault.is_none() && cmd.fault != Fault::None {
            self.fault = Some(format!("{:?} at step {k}", cmd.fault));
        }
        let x = self.m.states[k as usize].0;
        let err = self.planned.joint(t_k).angle_rad - x;
        self.worst = self.worst.max(err.abs());
        self.sq += err * err;
        let tau = cmd.torque_nm as f64;
        self.tau_max = self.tau_max.max(tau.abs());
        self.m.torques_nm.push(tau);
    }

    fn advance(&mut self, k: u64, _t_next: f64) -> Result<ControlFlow<Self::End>, ControllerError> {
        let (x, v) = self.m.states[k as usize];
        let tau = self.m.torques_nm[k as usize];
        let next = self.m.plant.advance(x, v, tau, self.dt, SUBSTEPS);
        self.m.states.push(next);
        Ok(ControlFlow::Continue(()))
    }
}

/// Close the loop: the controller `ctl` (SIL or HIL) tracks the plan on the joint plant
/// for the whole motion and `hold_s` after.
pub fn track(
    sys: &ArmScene,
    ctl: &mut dyn StepController<ArmController>,
    plan: &Plan,
) -> Result<(TrackedMotion, TrackingReport), ArmError> {
    let (inertia, g_torque, phase) = sys.payload_model();
    let plant = JointPlant {
        inertia_kgm2: inertia,
        gravity_torque_nm: g_torque,
        gravity_phase_rad: phase,
        torque_max_nm: sys.bounds.torque_max_nm,
    };
    let dt = sys.tracking.dt_s;
    let planned = plan.motion(&sys.rest_move());
    // past the verifier's end (settled + hold, or a catch + hold) by a few periods
    let caught_s = match sys.task.kind.catches() {
        true => plan.phases.last().map_or(0.0, |p| p.start_s + p.duration_s),
        false => 0.0,
    };
    let end_s = planned.settled_s().max(caught_s) + sys.task.hold_s;
    let steps = (end_s / dt).ceil() as usize + 5;
    let m = TrackedMotion {
        plant,
        dt_s: dt,
        states: vec![(sys.task.initial_angle_rad, 0.0)],
        torques_nm: Vec::with_capacity(steps),
        release_s: planned.duration_s(),
        settled_s: planned.settled_s(),
    };
    let mut joint = Tracking {
        m,
        planned: &planned,
        dt,
        worst: 0.0,
        sq: 0.0,
        tau_max: 0.0,
        fault: None,
    };
    drive(ctl, &mut joint, dt, steps as u64)
        .map_err(|e| ArmError::NoPlan(format!("controller: {e}")))?;
    let Tracking {
        m,
        worst,
        sq,
        tau_max,
        fault,
        ..
    } = joint;
    let run = execute(sys, &m, plan.mu);
    let free = super::simulate::execute_with(
        sys,
        &m,
        f64::INFINITY,
        super::simulate::SimOptions {
            record: false,
            ..Default::default()
        },
    );
    let enough = execute(sys, &m, free.peak_friction_ratio * (1.0 + 1e-9));
    let report = TrackingReport {
        executed: run.executed,
        reason: run.reason,
        goal_error: run.goal_error,
        mu_needed: free.peak_friction_ratio,
        executed_at_mu_needed: enough.executed,
        reason_at_mu_needed: enough.reason.clone(),
        goal_error_at_mu_needed: enough.goal_error,
        max_tracking_error_rad: worst,
        rms_tracking_error_rad: (sq / steps.max(1) as f64).sqrt(),
        max_torque_nm: tau_max,
        fault,
        steps,
    };
    Ok((m, report))
}

/// The core's controller linked in (SIL), configured for `plan`.
pub fn sil_controller(sys: &ArmScene, plan: &Plan) -> Result<Sil<ArmController>, ArmError> {
    let params = sys.controller_params(&plan.points_rad, plan.segment_s)?;
    Sil::<ArmController>::new(params).map_err(|e| ArmError::NoPlan(format!("controller: {e}")))
}

/// [`track`] with the core linked in (SIL).
pub fn track_sil(sys: &ArmScene, plan: &Plan) -> Result<(TrackedMotion, TrackingReport), ArmError> {
    let mut sil = sil_controller(sys, plan)?;
    track(sys, &mut sil, plan)
}
