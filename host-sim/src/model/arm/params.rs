//! The arm scene's tables: `[arm]`, `[object]`, `[task]`, `[planner]`, `[tracking]`.
//!
//! Every table rejects unknown keys; [`ArmConfig::validate`] checks values and relations
//! and names the dotted key at fault (`task.goal_x_m`, `object.position_m`, ...). Units
//! are SI; the defaults describe an NSK-like arm (the paper gives the link's size and
//! the palm's angle; its inertia, torque and speed limits are our estimates for a hollow
//! aluminium beam on a direct-drive motor) and a 10 cm wooden square.

use super::contact::{ArmInertia, Placement, Rig};
use super::geometry::{Polygon, Surface, V2};
use super::task::{Goal, Task, TaskKind};
use super::{ArmError, ArmScene, JointBounds, PlannerSettings, Solver, TrackingSettings};
use dexter_core::bspline::MAX_KNOTS;
use dexter_core::params::{finite, non_negative, positive, within, ParamError};

/// Longest phase a plan may have, s (`planner.phase_time_max_s`): with the hold and the
/// brake it bounds a run's simulated time, hence its work and memory.
pub const MAX_PHASE_TIME_S: f64 = 10.0;
/// Longest hold after the motion, s (`task.hold_s`).
pub const MAX_HOLD_S: f64 = 10.0;
/// Gentlest release brake, rad/s^2 (`arm.brake_accel_radps2`): from the joint's speed
/// limit it stops within `velocity_max / 1` s.
pub const MIN_BRAKE_ACCEL_RADPS2: f64 = 1.0;
/// Control period range, s (`tracking.dt_s`): at most 10^5 periods per 10 s of motion.
pub const MIN_DT_S: f64 = 1e-4;
/// See [`MIN_DT_S`].
pub const MAX_DT_S: f64 = 0.1;
use serde::{Deserialize, Serialize};
use std::f64::consts::TAU;

/// A whole arm scene.
#[derive(Clone, Debug, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct ArmConfig {
    /// `[arm]`: the robot.
    #[serde(default)]
    pub arm: ArmTable,
    /// `[object]`: the polygon and where it lies.
    #[serde(default)]
    pub object: ObjectTable,
    /// `[task]`: what to do.
    pub task: TaskTable,
    /// `[planner]`: the optimization.
    #[serde(default)]
    pub planner: PlannerTable,
    /// `[tracking]`: the closed loop with the core's controller.
    #[serde(default)]
    pub tracking: TrackingTable,
}

/// `[arm]`: geometry, dynamics and limits of the one-joint arm.
#[derive(Clone, Debug, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields, default)]
pub struct ArmTable {
    /// `link_length_m`: link length, m (1.22, the paper's).
    pub link_length_m: f64,
    /// `half_thickness_m`: height of the link's top surface above its axis, m (0.05).
    pub half_thickness_m: f64,
    /// `palm_angle_rad`: palm direction above the link, rad (pi/4, the paper's).
    pub palm_angle_rad: f64,
    /// `palm_length_m`: usable palm length from the link's tip, m (0.3).
    pub palm_length_m: f64,
    /// `inertia_kgm2`: arm inertia about the joint, kg m^2 (2.2).
    pub inertia_kgm2: f64,
    /// `gravity_torque_nm`: arm gravity torque with the link level, N m (25).
    pub gravity_torque_nm: f64,
    /// `gravity_mps2`: gravity, m/s^2 (9.81).
    pub gravity_mps2: f64,
    /// `torque_max_nm`: joint torque limit, N m (100).
    pub torque_max_nm: f64,
    /// `torque_rate_max_nmps`: torque-rate limit, N m/s (3000).
    pub torque_rate_max_nmps: f64,
    /// `velocity_max_radps`: joint speed limit, rad/s (8).
    pub velocity_max_radps: f64,
    /// `min_angle_rad`, `max_angle_rad`: joint limits, rad, within +-2 pi (-1.5, 1.5).
    pub min_angle_rad: f64,
    /// See `min_angle_rad`.
    pub max_angle_rad: f64,
    /// `brake_accel_radps2`: deceleration after a throw's release, rad/s^2, >= 1 (30).
    pub brake_accel_radps2: f64,
}

impl Default for ArmTable {
    fn default() -> Self {
        Self {
            link_length_m: 1.22,
            half_thickness_m: 0.05,
            palm_angle_rad: std::f64::consts::FRAC_PI_4,
            palm_length_m: 0.3,
            inertia_kgm2: 2.2,
            gravity_torque_nm: 25.0,
            gravity_mps2: 9.81,
            torque_max_nm: 100.0,
            torque_rate_max_nmps: 3000.0,
            velocity_max_radps: 8.0,
            min_angle_rad: -1.5,
            max_angle_rad: 1.5,
            brake_accel_radps2: 30.0,
        }
    }
}

/// Which surface carries the object (`object.surface`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Deserialize, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum SurfaceKind {
    /// `"link"`: the link's top surface, from the joint axis outward.
    #[default]
    Link,
    /// `"palm"`: the palm at the link's tip.
    Palm,
}

/// `[object]`: the polygon and its starting place.
#[derive(Clone, Debug, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields, default)]
pub struct ObjectTable {
    /// `side_m`: side of a square, m (0.1); ignored if `vertices_m` is given.
    pub side_m: f64,
    /// `vertices_m`: a convex polygon's vertices, counterclockwise, m (any origin).
    pub vertices_m: Option<Vec<[f64; 2]>>,
    /// `mass_kg`: object mass, kg (0.1).
    pub mass_kg: f64,
    /// `radius_of_gyration_m`: about the centre of mass, m (default: a uniform plate).
    pub radius_of_gyration_m: Option<f64>,
    /// `surface`: `"link"` or `"palm"`.
    pub surface: SurfaceKind,
    /// `edge`: index of the edge on the surface at the start (vertex k to k + 1).
    pub edge: usize,
    /// `position_m`: surface coordinate of that edge's midpoint, m (0.9).
    pub position_m: f64,
    /// `impact_law`: `"one_sided"` (impulses only push) or `"no_rebound"` (the paper's:
    /// every impact stops the object outright, pulls flagged).
    pub impact_law: super::impact::ImpactLaw,
}

impl Default for ObjectTable {
    fn default() -> Self {
        Self {
            side_m: 0.1,
            vertices_m: None,
            mass_kg: 0.1,
            radius_of_gyration_m: None,
            surface: SurfaceKind::Link,
            edge: 0,
            position_m: 0.9,
            impact_law: super::impact::ImpactLaw::OneSided,
        }
    }
}

/// Roll direction (`task.roll_direction`), seen with the joint axis toward the viewer.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Deserialize, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum RollDirection {
    /// `"ccw"`: the object turns counterclockwise relative to the surface (on the link:
    /// over its vertex nearer the joint).
    #[default]
    Ccw,
    /// `"cw"`: clockwise (on the link: over the vertex toward the tip).
    Cw,
}

/// `[task]`: what to do.
#[derive(Clone, Debug, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct TaskTable {
    /// `kind`: `"snatch"`, `"throw"`, `"roll"`, `"rolling_throw"` or `"throw_catch"`.
    pub kind: TaskKind,
    /// `initial_angle_rad`: joint angle at the start, at rest, rad (0).
    #[serde(default)]
    pub initial_angle_rad: f64,
    /// `final_angle_rad`: joint angle at rest at the end (snatch: required), rad.
    pub final_angle_rad: Option<f64>,
    /// `final_angle_min_rad`, `final_angle_max_rad`: bounds on the end angle (roll), rad.
    pub final_angle_min_rad: Option<f64>,
    /// See `final_angle_min_rad`.
    pub final_angle_max_rad: Option<f64>,
    /// `roll_direction`: `"ccw"` or `"cw"` (roll, rolling throw).
    #[serde(default)]
    pub roll_direction: RollDirection,
    /// `goal_x_m`, `goal_y_m`, `goal_angle_rad`: a throw's goal (required for throws).
    pub goal_x_m: Option<f64>,
    /// See `goal_x_m`.
    pub goal_y_m: Option<f64>,
    /// See `goal_x_m`.
    pub goal_angle_rad: Option<f64>,
    /// `goal_tolerance_m`: accepted landing distance, m (0.01).
    #[serde(default = "default_goal_tol")]
    pub goal_tolerance_m: f64,
    /// `goal_angle_tolerance_rad`: accepted landing angle error, rad (0.05).
    #[serde(default = "default_angle_tol")]
    pub goal_angle_tolerance_rad: f64,
    /// `impact_weight_s2pm2`: weight of the squared roll-end impact speed in the
    /// objective mu + w v^2, (m/s)^-2 (0: minimize mu only).
    #[serde(default)]
    pub impact_weight_s2pm2: f64,
    /// `catch_angle_rad`, `catch_edge`, `catch_position_m`: a throw and catch's nominal
    /// catching joint angle (rad; the bang-bang move after the release comes to rest
    /// there), the edge it lands on and that
    /// edge's midpoint along the surface (m) (required for `throw_catch`).
    pub catch_angle_rad: Option<f64>,
    /// See `catch_angle_rad`.
    pub catch_edge: Option<usize>,
    /// See `catch_angle_rad`.
    pub catch_position_m: Option<f64>,
    /// `catch_turns`: whole turns the object makes in flight beyond the least (0).
    #[serde(default)]
    pub catch_turns: i32,
    /// `hold_s`: time the verifier keeps the arm at rest after the motion, s, 0 ..= 10 (0.3).
    #[serde(default = "default_hold")]
    pub hold_s: f64,
    /// `cycles`: throw-catch cycles in a row, 1 ..= 50 (1); more than one only for a
    /// `throw_catch`, whose every catch is the next throw's start (the juggle).
    #[serde(default = "default_cycles")]
    pub cycles: usize,
    /// `mu`: the contact's Coulomb friction coefficient, at which a juggle's cycles are
    /// verified (> 0; each cycle's plan must need at most it). Without it each cycle is
    /// verified at its own plan's `mu_required`.
    pub mu: Option<f64>,
}

fn default_cycles() -> usize {
    1
}

/// Most throw-catch cycles a juggle runs (`task.cycles`): each is planned and verified,
/// so this bounds a run's work.
pub const MAX_CYCLES: usize = 50;

fn default_goal_tol() -> f64 {
    0.01
}
fn default_angle_tol() -> f64 {
    0.05
}
fn default_hold() -> f64 {
    0.3
}

/// `[planner]`: the nonlinear program and its solver.
#[derive(Clone, Debug, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields, default)]
pub struct PlannerTable {
    /// `knots`: B-spline control points, 7 ..= 16 for tasks ending at rest, 5 ..= 16 for
    /// throws (16: the core's buffer) (9, as fig. 2).
    pub knots: usize,
    /// `samples_per_phase`: constraint samples in each grasp phase (32).
    pub samples_per_phase: usize,
    /// `roll_steps`: RK4 steps of the roll (also its constraint samples) (48).
    pub roll_steps: usize,
    /// `max_evaluations`: solver budget of objective evaluations (1000).
    pub max_evaluations: usize,
    /// `solver`: `"slsqp"` or `"alm"` (augmented Lagrangian with PANOC).
    pub solver: Solver,
    /// `phase_time_min_s`, `phase_time_max_s`: bounds on each phase's duration, s
    /// (0.02, 1.5; the maximum at most 10).
    pub phase_time_min_s: f64,
    /// See `phase_time_min_s`.
    pub phase_time_max_s: f64,
    /// `mu_max`: largest friction coefficient the planner may ask for (3).
    pub mu_max: f64,
    /// `friction_margin`: the plan keeps `|f_t| (1 + margin) <= mu f_n` at its samples,
    /// so that the friction peak between samples stays below mu (0.01).
    pub friction_margin: f64,
    /// `normal_force_min_mps2`: smallest contact force per unit mass, N/kg (0.5).
    pub normal_force_min_mps2: f64,
    /// `starts`: initial guesses tried (1 ..= 8); the best feasible plan wins (3).
    pub starts: usize,
    /// `accel_margin`: fraction of the tracker's acceleration limit
    /// (`tracking.accel_max_radps2`) the plan leaves to the tracker's feedback: the
    /// planned joint acceleration stays within `(1 - accel_margin) accel_max`, so the
    /// controller can follow it without saturating (0.1; 0 ..= 0.9).
    pub accel_margin: f64,
    /// `cop_margin`: the grasp's centre of pressure stays this fraction of the edge's
    /// length inside the edge at every sample of a grasp (its end before a roll
    /// excepted, where it must reach the vertex), so that the executed contact modes are
    /// the planned ones: no early tip that falls back between samples (0.02; 0 ..= 0.4).
    pub cop_margin: f64,
}

impl Default for PlannerTable {
    fn default() -> Self {
        Self {
            knots: 9,
            samples_per_phase: 32,
            roll_steps: 48,
            max_evaluations: 1000,
            solver: Solver::Slsqp,
            phase_time_min_s: 0.02,
            phase_time_max_s: 1.5,
            mu_max: 3.0,
            friction_margin: 0.01,
            normal_force_min_mps2: 0.5,
            starts: 3,
            accel_margin: 0.1,
            cop_margin: 0.02,
        }
    }
}

/// `[tracking]`: the core's controller closing the loop around the joint.
#[derive(Clone, Debug, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields, default)]
pub struct TrackingTable {
    /// `dt_s`: control period, s, 1e-4 ..= 0.1 (0.001).
    pub dt_s: f64,
    /// `kp_per_s2`, `kd_per_s`: tracking gains (2500, 100).
    pub kp_per_s2: f64,
    /// See `kp_per_s2`.
    pub kd_per_s: f64,
    /// `accel_max_radps2`: the controller's acceleration limit, rad/s^2 (30).
    pub accel_max_radps2: f64,
    /// `max_tracking_error_rad`: error that faults the controller, rad (0.2).
    pub max_tracking_error_rad: f64,
}

impl Default for TrackingTable {
    fn default() -> Self {
        Self {
            dt_s: 0.001,
            kp_per_s2: 2500.0,
            kd_per_s: 100.0,
            accel_max_radps2: 30.0,
            max_tracking_error_rad: 0.2,
        }
    }
}

impl TaskTable {
    /// `task.cycles`, checked: 1 ..= [`MAX_CYCLES`], and more than one only for a catch.
    fn cycles(&self) -> Result<usize, ArmError> {
        if !(1..=MAX_CYCLES).contains(&self.cycles) {
            return Err(relation("task.cycles", "1 ..= 50"));
        }
        if self.cycles > 1 && self.kind != TaskKind::ThrowCatch {
            return Err(relation("task.cycles", "1 unless task.kind is throw_catch"));
        }
        Ok(self.cycles)
    }
}

fn relation(param: &'static str, requirement: &'static str) -> ArmError {
    ArmError::Relation { param, requirement }
}

impl ArmConfig {
    /// The validated system; errors name the key at fault.
    pub fn validate(&self) -> Result<ArmScene, ArmError> {
        let (arm, bounds, g) = self.arm.validate()?;
        let (rig, start) = self.object.validate(&self.arm, g)?;
        let mut task = self.task.validate(&bounds)?;
        if task.kind.catches() {
            self.task.catch(&rig, &bounds, &mut task)?;
        }
        let mut planner = self.planner.validate(task.kind)?;
        let tracking = self.tracking.validate(&bounds)?;
        let margin = within("planner.accel_margin", self.planner.accel_margin, 0.0, 0.9)?;
        planner.accel_max_radps2 = (1.0 - margin) * tracking.accel_max_radps2;
        if start.sigma_m < 0.0
            || start.sigma_m + rig.body.edge_length_m(start.edge) > rig.surface.length_m
        {
            return Err(relation(
                "object.position_m",
                "the contact edge lies on the surface",
            ));
        }
        let system = ArmScene {
            rig,
            arm,
            mass_kg: self.object.mass_kg,
            bounds,
            start,
            impact_law: self.object.impact_law,
            task,
            planner,
            tracking,
        };
        // the core's controller must accept these limits (payload included)
        system.controller_params(&[task.initial_angle_rad; 4], 0.1)?;
        Ok(system)
    }
}

impl ArmTable {
    fn validate(&self) -> Result<(ArmInertia, JointBounds, f64), ArmError> {
        positive("arm.link_length_m", self.link_length_m)?;
        non_negative("arm.half_thickness_m", self.half_thickness_m)?;
        finite("arm.palm_angle_rad", self.palm_angle_rad)?;
        positive("arm.palm_length_m", self.palm_length_m)?;
        let g = positive("arm.gravity_mps2", self.gravity_mps2)?;
        let arm = ArmInertia {
            inertia_kgm2: positive("arm.inertia_kgm2", self.inertia_kgm2)?,
            gravity_torque_nm: non_negative("arm.gravity_torque_nm", self.gravity_torque_nm)?,
            gravity_phase_rad: 0.0,
        };
        let bounds = JointBounds {
            min_angle_rad: within("arm.min_angle_rad", self.min_angle_rad, -TAU, TAU)?,
            max_angle_rad: within("arm.max_angle_rad", self.max_angle_rad, -TAU, TAU)?,
            velocity_max_radps: positive("arm.velocity_max_radps", self.velocity_max_radps)?,
            torque_max_nm: positive("arm.torque_max_nm", self.torque_max_nm)?,
            torque_rate_max_nmps: positive("arm.torque_rate_max_nmps", self.torque_rate_max_nmps)?,
            brake_accel_radps2: within(
                "arm.brake_accel_radps2",
                self.brake_accel_radps2,
                MIN_BRAKE_ACCEL_RADPS2,
                f64::MAX,
            )?,
        };
        if bounds.max_angle_rad <= bounds.min_angle_rad {
            return Err(relation(
                "arm.max_angle_rad",
                "max_angle_rad > min_angle_rad",
            ));
        }
        if arm.gravity_torque_nm >= bounds.torque_max_nm {
            return Err(relation(
                "arm.torque_max_nm",
                "torque_max_nm > gravity_torque_nm (the arm can hold itself)",
            ));
        }
        Ok((arm, bounds, g))
    }
}

impl ObjectTable {
    fn validate(&self, arm: &ArmTable, g: f64) -> Result<(Rig, Placement), ArmError> {
        positive("object.mass_kg", self.mass_kg)?;
        let rho = match self.radius_of_gyration_m {
            Some(r) => Some(positive("object.radius_of_gyration_m", r)?),
            None => None,
        };
        let body = match &self.vertices_m {
            Some(v) => {
                let pts: Vec<V2> = v.iter().map(|p| V2::new(p[0], p[1])).collect();
                if pts.iter().any(|p| !p.x.is_finite() || !p.y.is_finite()) {
                    return Err(ParamError::NotFinite("object.vertices_m").into());
                }
                Polygon::new(&pts, rho).map_err(|r| relation("object.vertices_m", r))?
            }
            None => Polygon::square(positive("object.side_m", self.side_m)?, rho)
                .map_err(|r| relation("object.side_m", r))?,
        };
        if self.edge >= body.len() {
            return Err(ParamError::OutOfRange("object.edge").into());
        }
        let h = arm.half_thickness_m;
        let surface = match self.surface {
            SurfaceKind::Link => Surface {
                origin: V2::new(0.0, h),
                beta_rad: 0.0,
                length_m: arm.link_length_m,
            },
            SurfaceKind::Palm => Surface {
                origin: V2::new(arm.link_length_m, h),
                beta_rad: arm.palm_angle_rad,
                length_m: arm.palm_length_m,
            },
        };
        let sigma =
            finite("object.position_m", self.position_m)? - 0.5 * body.edge_length_m(self.edge);
        let rig = Rig {
            body,
            surface,
            gravity_mps2: g,
        };
        Ok((
            rig,
            Placement {
                edge: self.edge,
                sigma_m: sigma,
            },
        ))
    }
}

impl TaskTable {
    fn validate(&self, b: &JointBounds) -> Result<Task, ArmError> {
        let kind = self.kind;
        let theta0 = finite("task.initial_angle_rad", self.initial_angle_rad)?;
        if !(b.min_angle_rad..=b.max_angle_rad).contains(&theta0) {
            return Err(ParamError::OutOfRange("task.initial_angle_rad").into());
        }
        let final_angle = match (kind, self.final_angle_rad) {
            (TaskKind::Snatch, None) => {
                return Err(relation("task.final_angle_rad", "given for a snatch"))
            }
            (_, Some(a)) => Some(finite("task.final_angle_rad", a)?),
            (_, None) => None,
        };
        let lo = finite(
            "task.final_angle_min_rad",
            self.final_angle_min_rad.unwrap_or(b.min_angle_rad),
        )?;
        let hi = finite(
            "task.final_angle_max_rad",
            self.final_angle_max_rad.unwrap_or(b.max_angle_rad),
        )?;
        if hi < lo {
            return Err(relation(
                "task.final_angle_max_rad",
                "final_angle_max_rad >= final_angle_min_rad",
            ));
        }
        if let Some(a) = final_angle {
            if a < lo.max(b.min_angle_rad) || a > hi.min(b.max_angle_rad) {
                return Err(ParamError::OutOfRange("task.final_angle_rad").into());
            }
        }
        let goal = if kind.throws() && !kind.catches() {
            Some(self.goal()?)
        } else {
            None
        };
        Ok(Task {
            kind,
            initial_angle_rad: theta0,
            roll_dir: match (kind.rolls(), self.roll_direction) {
                (false, _) => 0.0,
                (true, RollDirection::Ccw) => 1.0,
                (true, RollDirection::Cw) => -1.0,
            },
            final_angle_rad: final_angle,
            final_angle_range_rad: (lo, hi),
            goal,
            catch: None,
            impact_weight_s2pm2: non_negative(
                "task.impact_weight_s2pm2",
                self.impact_weight_s2pm2,
            )?,
            hold_s: within("task.hold_s", self.hold_s, 0.0, MAX_HOLD_S)?,
            cycles: self.cycles()?,
            mu: self.mu.map(|m| positive("task.mu", m)).transpose()?,
        })
    }

    fn goal(&self) -> Result<Goal, ArmError> {
        let need = |v: Option<f64>, key: &'static str| match v {
            Some(x) => Ok(finite(key, x)?),
            None => Err(relation(key, "given for a throw")),
        };
        Ok(Goal {
            x_m: need(self.goal_x_m, "task.goal_x_m")?,
            y_m: need(self.goal_y_m, "task.goal_y_m")?,
            angle_rad: need(self.goal_angle_rad, "task.goal_angle_rad")?,
            tolerance_m: positive("task.goal_tolerance_m", self.goal_tolerance_m)?,
            angle_tolerance_rad: positive(
                "task.goal_angle_tolerance_rad",
                self.goal_angle_tolerance_rad,
            )?,
        })
    }
}

impl TaskTable {
    /// The catch of a throw and catch, and the throw's goal: the caught pose.
    fn catch(&self, rig: &Rig, b: &JointBounds, task: &mut Task) -> Result<(), ArmError> {
        let need = |v: Option<f64>, key: &'static str| match v {
            Some(x) => Ok(finite(key, x)?),
            None => Err(relation(key, "given for a throw_catch")),
        };
        let angle = need(self.catch_angle_rad, "task.catch_angle_rad")?;
        if !(b.min_angle_rad + 0.02..=b.max_angle_rad - 0.02).contains(&angle) {
            return Err(relation(
                "task.catch_angle_rad",
                "within arm.min_angle_rad + 0.02 ..= arm.max_angle_rad - 0.02",
            ));
        }
        let edge = self
            .catch_edge
            .ok_or_else(|| relation("task.catch_edge", "given for a throw_catch"))?;
        if edge >= rig.body.len() {
            return Err(relation("task.catch_edge", "an edge index of the object"));
        }
        let l = rig.body.edge_length_m(edge);
        let sigma = need(self.catch_position_m, "task.catch_position_m")? - 0.5 * l;
        if sigma < 0.0 || sigma + l > rig.surface.length_m {
            return Err(relation(
                "task.catch_position_m",
                "the caught edge lies on the surface",
            ));
        }
        if self.catch_turns.abs() > 4 {
            return Err(relation("task.catch_turns", "-4 ..= 4"));
        }
        let place = Placement {
            edge,
            sigma_m: sigma,
        };
        let at = crate::model::arm::contact::Joint {
            angle_rad: angle,
            ..Default::default()
        };
        let pose = rig.grasped_state(&place, &at);
        task.catch = Some(crate::model::arm::task::Catch {
            angle_rad: angle,
            place,
        });
        task.goal = Some(Goal {
            x_m: pose.com.x,
            y_m: pose.com.y,
            angle_rad: pose.angle_rad + std::f64::consts::TAU * self.catch_turns as f64,
            tolerance_m: positive("task.goal_tolerance_m", self.goal_tolerance_m)?,
            angle_tolerance_rad: positive(
                "task.goal_angle_tolerance_rad",
                self.goal_angle_tolerance_rad,
            )?,
        });
        Ok(())
    }
}

impl PlannerTable {
    fn validate(&self, kind: TaskKind) -> Result<PlannerSettings, ArmError> {
        let min_knots = if kind.throws() { 5 } else { 7 };
        if self.knots < min_knots || self.knots > MAX_KNOTS {
            return Err(relation(
                "planner.knots",
                "7 ..= 16 for tasks ending at rest, 5 ..= 16 for throws (the core's buffer holds 16)",
            ));
        }
        let count = |v: usize, lo: usize, hi: usize, key: &'static str| {
            if (lo..=hi).contains(&v) {
                Ok(v)
            } else {
                Err(ArmError::from(ParamError::OutOfRange(key)))
            }
        };
        let t_min = positive("planner.phase_time_min_s", self.phase_time_min_s)?;
        let t_max = within(
            "planner.phase_time_max_s",
            self.phase_time_max_s,
            f64::MIN_POSITIVE,
            MAX_PHASE_TIME_S,
        )?;
        if t_max <= t_min {
            return Err(relation(
                "planner.phase_time_max_s",
                "phase_time_max_s > phase_time_min_s",
            ));
        }
        Ok(PlannerSettings {
            knots: self.knots,
            samples_per_phase: count(self.samples_per_phase, 4, 1000, "planner.samples_per_phase")?,
            roll_steps: count(self.roll_steps, 4, 2000, "planner.roll_steps")?,
            max_evaluations: count(self.max_evaluations, 1, 100_000, "planner.max_evaluations")?,
            solver: self.solver,
            phase_time_s: (t_min, t_max),
            mu_max: positive("planner.mu_max", self.mu_max)?,
            friction_margin: non_negative("planner.friction_margin", self.friction_margin)?,
            normal_force_min_mps2: non_negative(
                "planner.normal_force_min_mps2",
                self.normal_force_min_mps2,
            )?,
            starts: count(self.starts, 1, 8, "planner.starts")?,
            cop_margin: within("planner.cop_margin", self.cop_margin, 0.0, 0.4)?,
            // set from the tracker's limit once that is validated
            accel_max_radps2: f64::INFINITY,
        })
    }
}

impl TrackingTable {
    fn validate(&self, b: &JointBounds) -> Result<TrackingSettings, ArmError> {
        let t = TrackingSettings {
            dt_s: within("tracking.dt_s", self.dt_s, MIN_DT_S, MAX_DT_S)?,
            kp_per_s2: non_negative("tracking.kp_per_s2", self.kp_per_s2)?,
            kd_per_s: non_negative("tracking.kd_per_s", self.kd_per_s)?,
            accel_max_radps2: positive("tracking.accel_max_radps2", self.accel_max_radps2)?,
            max_tracking_error_rad: positive(
                "tracking.max_tracking_error_rad",
                self.max_tracking_error_rad,
            )?,
        };
        if b.brake_accel_radps2 > t.accel_max_radps2 {
            return Err(relation(
                "arm.brake_accel_radps2",
                "brake_accel_radps2 <= tracking.accel_max_radps2",
            ));
        }
        Ok(t)
    }
}
