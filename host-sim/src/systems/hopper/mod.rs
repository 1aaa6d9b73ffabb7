//! Koditschek & Bühler's vertical hopper (`[hopper]` scenes): `run`, `sweep` and `analyze`
//! (physics in [`crate::model::hopper`]; commands and output in `docs/hopper.md`,
//! "Command line").
//!
//! - `run`: every start of the scene, streamed cycle by cycle (the trace, the plots' points
//!   and the late values in constant memory), a summary beside the closed forms.
//! - `sweep` ([`sweep`]): a bifurcation diagram over any `[hopper]` key; over the thrust of
//!   eq. 9 it also locates the first period doubling (alpha = e^2).
//! - `analyze` ([`analyze`]): the fixed point of the simulated cycle map and its slope by
//!   finite differences, beside the closed forms (eq. 15/19, eq. 17).
//!
//! A `[hopper]` scene with a `[hopper.control]` table is the sampled hopper instead
//! ([`sampled`]): the thrust valve switched by the core's fixed-rate controller, in SIL or
//! on the MCU (`--hil`).

pub mod analyze;
pub mod closed_forms;
pub mod plots;
pub mod sampled;
pub mod scene;
pub mod summary;
pub mod sweep;
pub mod trace;

use self::summary::{HopperOutcome, Trajectory};
use self::trace::HopperRow;
use crate::controller::StepController;
use crate::model::hopper::params::ModelKind;
use crate::model::hopper::{Hopper, HopperParams, RunEnd, Start, MAX_SAMPLES};
use crate::progress::Progress;
use crate::scene::{deserialize, SceneError, SceneFile};
use crate::system::{Analyzes, Failure, NoController, Report, RunLength, Setup, System};
use serde::Deserialize;
use std::time::Instant;

/// Most cycles one `run` simulates per start (a bound on its time; its memory does not
/// grow with the cycles).
pub const MAX_RUN_CYCLES: u64 = 10_000_000;

/// Tolerance of the period detection on E_n (relative, see `detect_period`).
pub const PERIOD_TOL: f64 = 1e-8;

/// A scene file for the hopper, read from a table (unknown keys are errors).
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct SceneFileTable {
    hopper: HopperParams,
}

/// The hopper system.
#[derive(Clone, Copy, Debug, Default)]
pub struct HopperSystem;

/// A parsed, validated hopper scene.
#[derive(Clone, Debug, PartialEq)]
pub struct HopperConfig {
    /// The scene's name (the file stem).
    pub name: String,
    /// The `[hopper]` table.
    pub params: HopperParams,
    /// The validated hopper.
    pub hopper: Hopper,
    /// One start per `initial_heights_m` entry (at least one).
    pub starts: Vec<Start>,
}

impl HopperConfig {
    /// Deserialize and validate; errors name the key (`hopper.spring_eta1 must be > 0`).
    pub fn from_table(name: &str, table: toml::Table) -> Result<Self, SceneError> {
        sampled_tables_in_file(&table)?;
        let params = deserialize::<SceneFileTable>(table)?.hopper;
        let hopper = params.build().map_err(SceneError::whole)?;
        let starts = params.starts().map_err(SceneError::whole)?;
        if starts.is_empty() {
            return Err(SceneError::whole(
                "hopper.initial_heights_m must hold at least one height",
            ));
        }
        Ok(Self {
            name: name.to_string(),
            params,
            hopper,
            starts,
        })
    }

    /// True for eq. 9 with Raibert's fixed thrust (where alpha and eq. 15/19 apply).
    pub fn is_eq9_fixed(&self) -> bool {
        self.params.model == ModelKind::SimplifiedNonlinear && self.params.servo.is_none()
    }
}

/// The scene key of a model.
pub fn model_name(m: ModelKind) -> &'static str {
    match m {
        ModelKind::SimplifiedNonlinear => "simplified_nonlinear",
        ModelKind::Linear => "linear",
        ModelKind::Full => "full",
    }
}

/// The paper's equation of a model.
pub fn model_equation(m: ModelKind) -> &'static str {
    match m {
        ModelKind::SimplifiedNonlinear => "eq. 9",
        ModelKind::Linear => "eq. 10/16",
        ModelKind::Full => "eq. 8",
    }
}

/// Why a run ended, snake_case.
pub fn end_name(e: RunEnd) -> &'static str {
    match e {
        RunEnd::Completed => "completed",
        RunEnd::NoLiftoff => "no_liftoff",
        RunEnd::WeakThrust => "weak_thrust",
        RunEnd::StepCap => "step_cap",
        RunEnd::NonFinite => "non_finite",
    }
}

/// A start in words.
pub fn start_text(s: &Start) -> String {
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
pub fn start_height(s: &Start) -> f64 {
    match s {
        Start::Flight { height_m, .. } | Start::Bottom { height_m } => *height_m,
    }
}

impl System for HopperSystem {
    const NAME: &'static str = "hopper";
    const LENGTH: RunLength = RunLength::Events {
        key: "hopper.cycles",
        max: MAX_RUN_CYCLES,
    };
    type Config = HopperConfig;
    type Controller = NoController;
    type Row = HopperRow;
    type Outcome = HopperOutcome;
    type Plots = plots::HopperPlots;

    /// A `[hopper]` table (the sampled hopper, asked first, takes those with
    /// `[hopper.control]`).
    fn claims(table: &toml::Table) -> bool {
        table.contains_key("hopper")
    }

    fn parse(file: &SceneFile, table: toml::Table) -> Result<HopperConfig, SceneError> {
        HopperConfig::from_table(&file.stem, table)
    }

    /// The exact hopper has no controller: `--hil` names the table that would add one.
    fn controller_params(_: &HopperConfig) -> Result<Option<()>, SceneError> {
        Err(SceneError::new(
            "hopper.control",
            "is absent: the exact hopper times its thrust exactly and has no controller to put on the target (--hil needs a [hopper.control] table: the sampled hopper, docs/hopper.md)",
        ))
    }

    fn run(
        cfg: &HopperConfig,
        _: Option<&mut dyn StepController<NoController>>,
        setup: &Setup,
        rows: &mut dyn FnMut(&HopperRow),
    ) -> Result<HopperOutcome, Failure> {
        if cfg.params.cycles as u64 > MAX_RUN_CYCLES {
            return Err(Failure::scene(format!(
                "hopper.cycles must be <= {MAX_RUN_CYCLES} for run"
            )));
        }
        let mut opts = cfg.params.run_options();
        if setup.plot && opts.samples_per_phase == 0 {
            // dense samples for the phase portrait, within the global cap
            opts.samples_per_phase = (MAX_SAMPLES / (5 * cfg.params.cycles + 5)).clamp(2, 64);
        }
        let wall = Instant::now();
        let mut trajectories = Vec::with_capacity(cfg.starts.len());
        let total = (cfg.params.cycles * cfg.starts.len()) as f64;
        let mut bar = Progress::new([(total, "cycles")], setup.progress);
        for (i, &start) in cfg.starts.iter().enumerate() {
            let mut t = Trajectory::new(start);
            let mut samples = Vec::new();
            let done_before = (i * cfg.params.cycles) as f64;
            let (end, steps) = cfg
                .hopper
                .run_with_samples(start, cfg.params.cycles, &opts, &mut samples, &mut |c| {
                    t.push(c);
                    rows(&HopperRow {
                        trajectory: i + 1,
                        cycle: *c,
                    });
                    if c.index % 4096 == 0 {
                        bar.update([done_before + c.index as f64]);
                    }
                })
                .map_err(Failure::scene)?;
            t.finish(end, steps, samples);
            trajectories.push(t);
        }
        bar.finish();
        Ok(HopperOutcome::new(
            cfg,
            trajectories,
            wall.elapsed().as_secs_f64(),
        ))
    }
}

impl Analyzes for HopperSystem {
    fn analyze<'a>(
        file: &'a SceneFile,
        cfg: &'a HopperConfig,
    ) -> Result<Box<dyn Report + 'a>, Failure> {
        let _ = file;
        Ok(Box::new(analyze::analyze(cfg)?))
    }
}

/// The sampled hopper's tables, `[hopper.control]` and `[hopper.sensor]`, given to the exact
/// hopper: the system is chosen by the scene file's own tables, so they came from `--set`
/// (or a sweep), which cannot switch a scene to the sampled hopper.
fn sampled_tables_in_file(table: &toml::Table) -> Result<(), SceneError> {
    let hopper = table.get("hopper").and_then(toml::Value::as_table);
    for key in ["control", "sensor"] {
        if hopper.is_some_and(|h| h.contains_key(key)) {
            return Err(SceneError::new(
                format!("hopper.{key}"),
                "belongs to the sampled hopper, which runs only a scene file with its own [hopper.control] table (e.g. scenes/hopper-raibert-sil.toml; docs/hopper.md, \"The hopper on the MCU\"): --set cannot turn this exact-hopper scene into one",
            ));
        }
    }
    Ok(())
}
