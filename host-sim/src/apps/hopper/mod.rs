//! CLI front end of the hopper scenes (`[hopper]` table): `run`, `sweep`, `analyze`
//! (documented in `docs/hopper.md`, "Command line").
//!
//! - [`run`]: simulate every start of the scene, print a summary (or one JSON object), write
//!   a per-cycle CSV trace and the return-map, energy-map and phase-portrait plots.
//! - [`sweep`]: a bifurcation diagram over any `[hopper]` key; over the thrust of eq. 9 it
//!   also locates the first period doubling (alpha = e^2).
//! - [`analyze`]: the fixed point of the simulated cycle map and its slope by finite
//!   differences, beside the closed forms (eq. 15/19, eq. 17).

mod analyze;
mod closed;
mod run;
mod sweep;

pub use analyze::analyze;
pub use run::run;
pub use sweep::sweep;

use super::AppError;
use crate::model::hopper::params::ModelKind;
use crate::model::hopper::{Hopper, HopperParams, RunEnd, Start};
use serde::Deserialize;
use std::path::Path;

/// Most cycles one `run` simulates (every cycle is stored).
pub const MAX_RUN_CYCLES: u64 = 10_000_000;

/// A scene file for the hopper, read from a table (unknown keys are errors).
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct SceneFile {
    hopper: HopperParams,
}

/// A loaded, validated hopper scene.
pub(crate) struct Loaded {
    /// The scene's name (the file stem).
    pub name: String,
    /// The `[hopper]` table.
    pub params: HopperParams,
    /// The validated hopper.
    pub hopper: Hopper,
    /// One start per `initial_heights_m` entry.
    pub starts: Vec<Start>,
}

fn scene_error(e: crate::scene::SceneError) -> AppError {
    AppError::Scene(e.to_string())
}

/// The scene file as a TOML table with the `--set` overrides applied.
pub(crate) fn load_table(path: &Path, sets: &[String]) -> Result<toml::Table, AppError> {
    let overrides = sets
        .iter()
        .map(|s| crate::scene::parse_set(s))
        .collect::<Result<Vec<_>, _>>()
        .map_err(scene_error)?;
    crate::scene::load_table(path, &overrides).map_err(scene_error)
}

/// Set `key` to `value` in `table` (sets and sweeps).
pub(crate) fn set_key(
    table: &mut toml::Table,
    key: &str,
    value: toml::Value,
) -> Result<(), AppError> {
    crate::scene::apply_set(table, key, value).map_err(scene_error)
}

impl Loaded {
    /// Deserialize and validate; errors name the key (`hopper.spring_eta1 must be > 0`).
    pub fn from_table(table: toml::Table, path: &Path) -> Result<Self, AppError> {
        let file: SceneFile =
            serde_path_to_error::deserialize(toml::Value::Table(table)).map_err(|e| {
                let key = e.path().to_string();
                let msg = e.into_inner().message().to_string();
                AppError::Scene(if key == "." {
                    msg
                } else {
                    format!("{key}: {msg}")
                })
            })?;
        let params = file.hopper;
        let hopper = params.build().map_err(|e| AppError::Scene(e.to_string()))?;
        let starts = params
            .starts()
            .map_err(|e| AppError::Scene(e.to_string()))?;
        if starts.is_empty() {
            return Err(AppError::Scene(
                "hopper.initial_heights_m must hold at least one height".into(),
            ));
        }
        let name = path
            .file_stem()
            .and_then(|s| s.to_str())
            .unwrap_or("hopper")
            .to_string();
        Ok(Self {
            name,
            params,
            hopper,
            starts,
        })
    }

    /// Read the scene at `path` with `sets` applied.
    pub fn load(path: &Path, sets: &[String]) -> Result<Self, AppError> {
        Self::from_table(load_table(path, sets)?, path)
    }

    /// True for eq. 9 with Raibert's fixed thrust (where alpha and eq. 15/19 apply).
    pub fn is_eq9_fixed(&self) -> bool {
        self.params.model == ModelKind::SimplifiedNonlinear && self.params.servo.is_none()
    }
}

/// The scene key of a model.
pub(crate) fn model_name(m: ModelKind) -> &'static str {
    match m {
        ModelKind::SimplifiedNonlinear => "simplified_nonlinear",
        ModelKind::Linear => "linear",
        ModelKind::Full => "full",
    }
}

/// The paper's equation of a model.
pub(crate) fn model_equation(m: ModelKind) -> &'static str {
    match m {
        ModelKind::SimplifiedNonlinear => "eq. 9",
        ModelKind::Linear => "eq. 10/16",
        ModelKind::Full => "eq. 8",
    }
}

/// Why a run ended, snake_case.
pub(crate) fn end_name(e: RunEnd) -> &'static str {
    match e {
        RunEnd::Completed => "completed",
        RunEnd::NoLiftoff => "no_liftoff",
        RunEnd::WeakThrust => "weak_thrust",
        RunEnd::StepCap => "step_cap",
        RunEnd::NonFinite => "non_finite",
    }
}

/// A start in words.
pub(crate) fn start_text(s: &Start) -> String {
    match s {
        Start::Flight {
            height_m,
            velocity_mps,
        } if *velocity_mps == 0.0 => format!("apex {height_m} m"),
        Start::Flight {
            height_m,
            velocity_mps,
        } => format!("flight at {height_m} m, {velocity_mps} m/s"),
        Start::Bottom { height_m } => format!("bottom {height_m} m (at rest)"),
    }
}

/// The initial height of a start, m.
pub(crate) fn start_height(s: &Start) -> f64 {
    match s {
        Start::Flight { height_m, .. } | Start::Bottom { height_m } => *height_m,
    }
}

/// Tolerance of the period detection on E_n (relative, see `detect_period`).
pub const PERIOD_TOL: f64 = 1e-8;

/// Create the directory a file is to be written in.
pub(crate) fn create_parent(path: &Path) -> Result<(), AppError> {
    match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => std::fs::create_dir_all(d)
            .map_err(|e| AppError::Run(format!("cannot create {}: {e}", d.display()))),
        _ => Ok(()),
    }
}
