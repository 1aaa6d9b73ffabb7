//! One-motor dynamic manipulation (Akella, Huang, Lynch & Mason, sec. 2) as a system:
//! `dexter run scenes/arm-throw.toml` plans a cubic B-spline joint trajectory that
//! minimizes the friction the task needs (snatch, throw, roll, rolling throw), verifies it
//! event by event at the planned mu and at 0.95 mu, and tracks it with the core's
//! [`ArmController`] (SIL, or the firmware in QEMU with `--hil`) to show how tracking
//! error changes the outcome. Physics and planner in [`crate::model::arm`]; keys, output,
//! trace columns and plots in `docs/arm.md`.
//!
//! An arm scene has the tables `[arm]`, `[object]`, `[task]`, `[planner]`, `[tracking]`
//! (only `[task]` is required); the system claims a scene with `[arm]` or `[task]`, and
//! any other top-level table is an error naming it.

pub mod examples;
pub mod execute;
pub mod plots;
pub mod scene;
pub mod summary;
pub mod trace;

use self::execute::run_with;
use self::summary::{compare_trajectories, ArmOutcome, JuggleSummary, TrajectoryComparison};
use self::trace::ArmRow;
use crate::controller::StepController;
use crate::model::arm::closed_loop::{sil_controller, track_sil};
use crate::model::arm::juggle::juggle;
use crate::model::arm::params::ArmConfig;
use crate::model::arm::planner::{plan, Plan};
use crate::model::arm::{ArmError, ArmScene};
use crate::scene::{deserialize, SceneError, SceneFile};
use crate::system::{Failure, RunLength, Setup, System};
use dexter_core::arm_control::{ArmController, ArmParams};
use dexter_core::params::ParamError;
use std::sync::OnceLock;

/// The one-joint arm system.
#[derive(Clone, Copy, Debug, Default)]
pub struct ArmSystem;

/// A parsed, validated arm scene, and its plan once made (planned at most once per run:
/// `--hil` needs the trajectory before the run starts, to configure the target).
#[derive(Debug)]
pub struct ArmRunConfig {
    /// The scene's name (the file stem).
    pub name: String,
    /// The tables as given (defaults filled in).
    pub tables: ArmConfig,
    /// The validated scene.
    pub scene: ArmScene,
    plan: OnceLock<Result<Plan, String>>,
}

impl ArmRunConfig {
    /// The plan (made on first use); a failure to plan is a failed run (exit 1).
    pub fn plan(&self) -> Result<&Plan, Failure> {
        self.plan
            .get_or_init(|| plan(&self.scene).map_err(|e| e.to_string()))
            .as_ref()
            .map_err(Failure::run)
    }
}

/// The dotted key and the reason of a model error, for the CLI.
pub fn scene_error(e: ArmError) -> SceneError {
    match e {
        ArmError::Param(p) => param_error(p),
        ArmError::Relation { param, requirement } => {
            SceneError::new(param, format!("must satisfy {requirement}"))
        }
        other => SceneError::whole(other),
    }
}

/// A parameter error with its key; a core controller's own name (e.g. `limits.*`) is not
/// a scene key, so it is reported as is.
fn param_error(e: ParamError) -> SceneError {
    let (key, reason) = match e {
        ParamError::NotFinite(k) => (k, "must be a finite number"),
        ParamError::NotPositive(k) => (k, "must be > 0"),
        ParamError::Negative(k) => (k, "must be >= 0"),
        ParamError::OutOfRange(k) => (k, "is out of its allowed range (docs/arm.md)"),
        other => return SceneError::whole(other),
    };
    let tables = ["arm.", "object.", "task.", "planner.", "tracking."];
    if tables.iter().any(|t| key.starts_with(t)) {
        return SceneError::new(key, reason);
    }
    match core_key(key) {
        // the core holds each value as an f32: a finite f64 may still be too large
        Some((key, note)) => SceneError::new(
            key,
            match e {
                ParamError::NotFinite(_) => format!(
                    "{reason} below 3.4e38 in size (the controller holds it as an f32){note}"
                ),
                _ => format!("{reason}{note}"),
            },
        ),
        None => SceneError::whole(format!("the core's arm controller rejects {e}")),
    }
}

/// The scene key of a field of the core's `ArmParams`, and what else feeds it.
fn core_key(field: &str) -> Option<(&'static str, &'static str)> {
    Some(match field {
        "dt_s" => ("tracking.dt_s", ""),
        "kp_per_s2" => ("tracking.kp_per_s2", ""),
        "kd_per_s" => ("tracking.kd_per_s", ""),
        "max_tracking_error_rad" => ("tracking.max_tracking_error_rad", ""),
        "limits.accel_max_radps2" => ("tracking.accel_max_radps2", ""),
        "limits.min_angle_rad" => ("arm.min_angle_rad", ""),
        "limits.max_angle_rad" => ("arm.max_angle_rad", ""),
        "limits.velocity_max_radps" => ("arm.velocity_max_radps", ""),
        "limits.torque_max_nm" => ("arm.torque_max_nm", ""),
        "brake_accel_radps2" => ("arm.brake_accel_radps2", ""),
        "inertia_kgm2" => (
            "arm.inertia_kgm2",
            " (with the payload's, from object.mass_kg and object.side_m)",
        ),
        "gravity_torque_nm" => (
            "arm.gravity_torque_nm",
            " (with the payload's, from object.mass_kg and arm.gravity_mps2)",
        ),
        _ => return None,
    })
}

impl System for ArmSystem {
    const NAME: &'static str = "arm";
    /// A run is the planned motion, settled and held: neither `--impacts` nor
    /// `--duration` applies.
    const LENGTH: RunLength = RunLength::Fixed;
    type Config = ArmRunConfig;
    type Controller = ArmController;
    type Row = ArmRow;
    type Outcome = ArmOutcome;
    type Plots = plots::ArmPlots;

    fn claims(table: &toml::Table) -> bool {
        table.contains_key("arm") || table.contains_key("task")
    }

    fn parse(file: &SceneFile, table: toml::Table) -> Result<ArmRunConfig, SceneError> {
        let tables: ArmConfig = deserialize(table)?;
        let scene = tables.validate().map_err(scene_error)?;
        Ok(ArmRunConfig {
            name: file.stem.clone(),
            tables,
            scene,
            plan: OnceLock::new(),
        })
    }

    /// The controller tracking the plan (so `--hil` plans first). Without a plan the
    /// controller holds the start and the run then fails saying why (exit 1).
    fn controller_params(cfg: &ArmRunConfig) -> Result<Option<ArmParams>, SceneError> {
        let held = [cfg.scene.task.initial_angle_rad; 4];
        let (points, segment_s) = match cfg.plan() {
            Ok(p) => (&p.points_rad[..], p.segment_s),
            Err(_) => (&held[..], 0.1),
        };
        let params = cfg.scene.controller_params(points, segment_s);
        params.map(Some).map_err(scene_error)
    }

    fn run(
        cfg: &ArmRunConfig,
        ctrl: Option<&mut dyn StepController<ArmController>>,
        _: &Setup,
        rows: &mut dyn FnMut(&ArmRow),
    ) -> Result<ArmOutcome, Failure> {
        let plan = cfg.plan()?;
        let on_target = ctrl.is_some();
        let mut sil;
        let tracker: &mut dyn StepController<ArmController> = match ctrl {
            Some(c) => c,
            None => {
                sil = sil_controller(&cfg.scene, plan).map_err(Failure::run)?;
                &mut sil
            }
        };
        let mut observe = |s: &_| rows(&ArmRow(*s));
        let (summary, tracked) =
            run_with(&cfg.scene, plan, Some(tracker), &mut observe).map_err(Failure::run)?;
        let tracked = tracked.ok_or_else(|| Failure::run("the closed loop did not run"))?;
        let mut against_sil = match on_target {
            true => {
                let (sil_motion, _) = track_sil(&cfg.scene, plan).map_err(Failure::run)?;
                Some(compare_trajectories(&tracked, &sil_motion))
            }
            false => None,
        };
        let juggle = match cfg.scene.task.cycles {
            1 => None,
            _ => Some(run_juggle(cfg, tracker, against_sil.as_mut())?),
        };
        let mut outcome = ArmOutcome::new(cfg, summary, &tracked, against_sil);
        outcome.json.juggle = juggle;
        Ok(outcome)
    }
}

/// A juggle's two chains (exact, and tracked through `tracker`); on a target, its tracked
/// motions compared with SIL's, cycle by cycle, into `against_sil`.
fn run_juggle(
    cfg: &ArmRunConfig,
    tracker: &mut dyn StepController<ArmController>,
    against_sil: Option<&mut TrajectoryComparison>,
) -> Result<JuggleSummary, Failure> {
    let (exact, _) = juggle(&cfg.tables, None).map_err(Failure::run)?;
    let (tracked, motions) = juggle(&cfg.tables, Some(tracker)).map_err(Failure::run)?;
    if let Some(total) = against_sil {
        let mut sil = sil_controller(&cfg.scene, cfg.plan()?).map_err(Failure::run)?;
        let (_, sil_motions) = juggle(&cfg.tables, Some(&mut sil)).map_err(Failure::run)?;
        let t0 = total.steps as f64 * cfg.scene.tracking.dt_s;
        for (a, b) in motions.iter().zip(&sil_motions) {
            let c = compare_trajectories(a, b);
            if total.first_mismatch_s.is_none() {
                total.first_mismatch_s = c.first_mismatch_s.map(|t| t + t0);
            }
            total.steps += c.steps;
            total.mismatches += c.mismatches;
        }
        total.mismatches += motions.len().abs_diff(sil_motions.len());
    }
    Ok(JuggleSummary {
        cycles: cfg.scene.task.cycles,
        exact,
        tracked,
    })
}
