//! One-motor dynamic manipulation (Akella, Huang, Lynch & Mason, "From Robotic Juggling to
//! Robotic Parts Feeding", sec. 2): a one-joint arm in the vertical plane, like the
//! paper's NSK arm (a 1.22 m link of 10 cm square section with a palm at 45 degrees), moves
//! a polygonal object that it does not grasp: dynamic grasp, roll about a vertex, free
//! flight. Plans are cubic B-spline joint trajectories found by sequential quadratic
//! programming that minimizes the friction coefficient they need (sec. 2.1-2.4).
//!
//! | module | what it holds |
//! | --- | --- |
//! | [`geometry`] | plane vectors, the convex polygon, the arm's surfaces |
//! | [`contact`] | grasp and roll forces, phase conditions, flight, the arm's torque (derived) |
//! | [`impact`] | one-sided plastic impacts: an edge landing stops or rocks onto its striking vertex |
//! | [`task`] | the tasks as phase sequences (g, gf, grg, grf, gf + catch) and their goals |
//! | [`juggle`] | throw and catch again and again, each catch the next throw's start |
//! | [`params`] | the scene's tables, validation naming the dotted key |
//! | [`motion`] | joint motions: the planned spline with its move to rest (the release brake, or the bang-bang to a catch) |
//! | [`planner`] | design vector, sec. 2.2 constraints, shooting seeds, SLSQP / ALM |
//! | [`simulate`] | the event-driven verifier and its verdicts |
//! | [`closed_loop`] | the plan tracked by the core's `ArmController` (SIL), then verified |
//!
//! # For a system module
//!
//! Plan, verify, margin check and tracking in one call, with the JSON summary, are the
//! system's (`crate::systems::arm::execute`):
//!
//! ```no_run
//! use dexter_sim::model::arm::params::ArmConfig;
//! use dexter_sim::systems::arm::execute::{run, RunOptions};
//! let text = dexter_sim::systems::arm::examples::THROW;
//! let sys = ArmConfig::from_toml_str(text)?.validate()?; // errors name the dotted key
//! let summary = run(&sys, RunOptions { track: true })?;    // plan, verify, 0.95 mu, SIL
//! println!("{}", serde_json::to_string(&summary).unwrap()); // task, mu_required, executed, ...
//! # Ok::<(), dexter_sim::model::arm::ArmError>(())
//! ```
//!
//! # What the paper leaves open, and what we chose
//!
//! - Only the link's length and section and the palm's angle are given; the arm's
//!   inertia (2.2 kg m^2), gravity torque (25 N m), torque limit (100 N m), torque-rate
//!   limit (3000 N m/s) and speed limit (8 rad/s) are estimates for a hollow aluminium
//!   beam on a direct-drive motor (`[arm]`, all overridable).
//! - "Knot points" are taken as the B-spline's control points; the initial state holds
//!   by construction (three equal first points), as does rest at the end.
//! - The snatch is `g` from a table flush with the arm's surface; the `rg` snatch (first
//!   contact at a vertex, with the table still touching) needs a two-contact phase that
//!   is not modelled.
//! - The roll's end is a one-sided plastic impact ([`impact`]): the paper's "no rebound"
//!   (stop outright) only where its impulse's centre of pressure lies on the edge, else a
//!   rock onto the striking vertex, simulated until it settles; the impulse must lie in
//!   its friction cone.
//! - The planner does not keep a thrown object clear of the arm during flight; the
//!   verifier checks it and calls a strike `missed`.

pub mod closed_loop;
pub mod contact;
pub mod geometry;
pub mod impact;
pub mod juggle;
pub mod motion;
pub mod params;
pub mod planner;
pub mod simulate;
pub mod task;

use contact::{ArmInertia, Placement, Rig};
use dexter_core::arm_control::{ArmParams, JointLimits};
use dexter_core::bspline::Knots;
use dexter_core::params::ParamError;
use motion::RestMove;
use serde::{Deserialize, Serialize};
use task::Task;

/// Why an arm scene could not be set up, planned or run.
#[derive(Clone, Debug, PartialEq)]
pub enum ArmError {
    /// A single value is invalid; the name is its dotted key (`object.mass_kg must be > 0`).
    Param(ParamError),
    /// A value violates a relation with others.
    Relation {
        /// The dotted key at fault.
        param: &'static str,
        /// What it must satisfy, in words.
        requirement: &'static str,
    },
    /// The scene text is not valid TOML or does not fit the schema (with the key path).
    Toml(String),
    /// The planner found no plan that meets every constraint (the message says which).
    NoPlan(String),
}

impl std::fmt::Display for ArmError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            ArmError::Param(e) => write!(f, "{e}"),
            ArmError::Relation { param, requirement } => {
                write!(f, "{param} must satisfy {requirement}")
            }
            ArmError::Toml(m) => write!(f, "arm scene: {m}"),
            ArmError::NoPlan(m) => write!(f, "arm planner: {m}"),
        }
    }
}

impl std::error::Error for ArmError {}

impl From<ParamError> for ArmError {
    fn from(e: ParamError) -> Self {
        ArmError::Param(e)
    }
}

/// The joint's limits (sec. 2.2, manipulator constraints 1-4) and the release brake.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct JointBounds {
    /// Lowest joint angle, rad.
    pub min_angle_rad: f64,
    /// Highest joint angle, rad.
    pub max_angle_rad: f64,
    /// Largest joint speed, rad/s.
    pub velocity_max_radps: f64,
    /// Largest joint torque, N m.
    pub torque_max_nm: f64,
    /// Largest torque rate, N m/s.
    pub torque_rate_max_nmps: f64,
    /// Deceleration after the trajectory ends (a throw's release), rad/s^2.
    pub brake_accel_radps2: f64,
}

/// Which optimizer solves the nonlinear program (`planner.solver`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Deserialize, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Solver {
    /// `"slsqp"`: Kraft's sequential least-squares QP (the `slsqp` crate).
    #[default]
    Slsqp,
    /// `"alm"`: augmented Lagrangian with PANOC inner solves (`optimization_engine`).
    Alm,
}

/// Validated planner settings (see [`params::PlannerTable`]).
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct PlannerSettings {
    /// B-spline control points.
    pub knots: usize,
    /// Constraint samples per grasp phase.
    pub samples_per_phase: usize,
    /// RK4 steps of the roll.
    pub roll_steps: usize,
    /// Objective evaluations the solver may spend per start.
    pub max_evaluations: usize,
    /// The optimizer.
    pub solver: Solver,
    /// Bounds on each phase's duration, s.
    pub phase_time_s: (f64, f64),
    /// Largest mu the plan may need.
    pub mu_max: f64,
    /// Relative friction margin at samples.
    pub friction_margin: f64,
    /// Smallest contact force per unit mass, N/kg.
    pub normal_force_min_mps2: f64,
    /// Initial guesses tried.
    pub starts: usize,
    /// Centre-of-pressure margin inside a grasped edge, as a fraction of its length.
    pub cop_margin: f64,
    /// Largest joint acceleration the plan may ask for, rad/s^2: the tracker's limit
    /// `tracking.accel_max_radps2` less the `planner.accel_margin` left to its feedback.
    pub accel_max_radps2: f64,
}

/// Validated closed-loop settings (see [`params::TrackingTable`]).
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct TrackingSettings {
    /// Control period, s.
    pub dt_s: f64,
    /// Stiffness, 1/s^2.
    pub kp_per_s2: f64,
    /// Damping, 1/s.
    pub kd_per_s: f64,
    /// The controller's acceleration limit, rad/s^2.
    pub accel_max_radps2: f64,
    /// Tracking error that faults the controller, rad.
    pub max_tracking_error_rad: f64,
}

/// A validated arm scene: robot, object, task and settings.
#[derive(Clone, Debug, PartialEq)]
pub struct ArmScene {
    /// The object on its surface, and gravity.
    pub rig: Rig,
    /// The arm's own dynamics.
    pub arm: ArmInertia,
    /// Object mass, kg.
    pub mass_kg: f64,
    /// Joint limits.
    pub bounds: JointBounds,
    /// Where the object lies at the start.
    pub start: Placement,
    /// The impact law the verifier applies.
    pub impact_law: impact::ImpactLaw,
    /// The task.
    pub task: Task,
    /// Planner settings.
    pub planner: PlannerSettings,
    /// Closed-loop settings.
    pub tracking: TrackingSettings,
}

impl ArmScene {
    /// Inertia (kg m^2) and gravity torque amplitude (N m) and phase (rad) of the arm with
    /// the object as a rigid payload at its starting place: what the controller's
    /// inverse dynamics assumes.
    pub fn payload_model(&self) -> (f64, f64, f64) {
        let r = self.rig.com_arm(&self.start);
        let m = self.mass_kg;
        let inertia = self.arm.inertia_kgm2 + m * (r.norm2() + self.rig.body.rho_m.powi(2));
        let g = self.rig.gravity_mps2;
        // G_a cos(theta) + m g |r| cos(theta + atan2(r_y, r_x)) = A cos(theta + phase)
        let c = self.arm.gravity_torque_nm + m * g * r.x;
        let s = m * g * r.y;
        (inertia, c.hypot(s), s.atan2(c))
    }

    /// How the arm comes to rest after its spline: braking, or to the catch's angle.
    pub fn rest_move(&self) -> RestMove {
        RestMove {
            accel_radps2: self.bounds.brake_accel_radps2,
            velocity_max_radps: self.bounds.velocity_max_radps,
            catch_angle_rad: self.task.catch.map(|c| c.angle_rad),
        }
    }

    /// The core controller's parameters for a trajectory (control points in rad, segment
    /// duration in s); errors name the `[tracking]` or `[arm]` key at fault.
    pub fn controller_params(
        &self,
        points_rad: &[f64],
        segment_s: f64,
    ) -> Result<ArmParams, ArmError> {
        let (inertia, g_torque, phase) = self.payload_model();
        let t = &self.tracking;
        let b = &self.bounds;
        let pts: Vec<f32> = points_rad.iter().map(|&p| p as f32).collect();
        let params = ArmParams {
            dt_s: t.dt_s as f32,
            kp_per_s2: t.kp_per_s2 as f32,
            kd_per_s: t.kd_per_s as f32,
            limits: JointLimits {
                min_angle_rad: b.min_angle_rad as f32,
                max_angle_rad: b.max_angle_rad as f32,
                velocity_max_radps: b.velocity_max_radps as f32,
                accel_max_radps2: t.accel_max_radps2 as f32,
                torque_max_nm: b.torque_max_nm as f32,
            },
            inertia_kgm2: inertia as f32,
            gravity_torque_nm: g_torque as f32,
            gravity_phase_rad: phase as f32,
            brake_accel_radps2: b.brake_accel_radps2 as f32,
            catches: self.task.catch.is_some(),
            catch_angle_rad: self.task.catch.map_or(0.0, |c| c.angle_rad as f32),
            max_tracking_error_rad: t.max_tracking_error_rad as f32,
            stale_limit_steps: 5,
            trajectory: Knots::from_slice(&pts, segment_s as f32)?,
        };
        params.validate().map_err(|e| match e {
            ParamError::OutOfRange("limits.accel_max_radps2") => ArmError::Relation {
                param: "tracking.accel_max_radps2",
                requirement: "(arm + payload inertia) * accel_max_radps2 + gravity torque <= arm.torque_max_nm",
            },
            other => ArmError::Param(other),
        })?;
        Ok(params)
    }
}
