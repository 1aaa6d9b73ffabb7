//! The line juggler (Rizzi & Koditschek 1994, sec. 2) and the passive bounce: a ball and a
//! paddle (or a fixed table) on a vertical line, with the switchable effects of
//! [`crate::effects`] (sensor, actuator, jitter), drag and Zeno. Its controller is the
//! core's [`Controller`] (`control.mode = "sil"`), in SIL or on the target (`--hil`).
//!
//! | module | what it holds |
//! | --- | --- |
//! | [`scene`], [`validate`] | the scene schema (`docs/scenes.md`) and its checks |
//! | [`assemble`] | the plant from the scene, only the enabled effects |
//! | [`loops`] | the event-driven run loop and the plant sampled at the control rate |
//! | [`run`] | the run API: streaming every impact |
//! | [`outcome`] | what a run records: options, errors, ends, outcome |
//! | [`apexes`] | convergence and period of the apex sequence, in constant memory |
//! | [`summary`] | convergence, period, resting contact; text and JSON |
//! | [`trace`] | one CSV row per impact |
//! | [`plots`] | apex per impact, return map, phase portrait |
//! | [`sweep`] | late apexes over one key (bifurcation diagram) |
//!
//! It runs every scene that no other system claims (the registry asks it last).

pub mod analyze;
pub mod apexes;
pub mod assemble;
pub mod basin;
pub mod loops;
pub mod outcome;
pub mod plots;
pub mod run;
pub mod scene;
pub mod summary;
pub mod sweep;
pub mod trace;
pub mod validate;

use self::run::{run_streaming, End, RunOptions};
use self::scene::{ControlMode, Scene};
use self::summary::Summary;
use self::trace::ImpactRow;
use crate::controller::{HilReport, SafeSteps, StepController};
use crate::output::{json_text, JsonStyle};
use crate::scene::{SceneError, SceneFile};
use crate::system::{Analyzes, Failure, Outcome, Report, RunLength, Setup, System};
use dexter_core::control::{Controller, ControllerParams};

/// The line system.
#[derive(Clone, Copy, Debug, Default)]
pub struct LineSystem;

/// A line run's result: its summary, and the phase samples the plots draw.
#[derive(Clone, Debug)]
pub struct LineOutcome {
    /// The summary (`--json`).
    pub summary: Summary,
    /// (b, b') once per control step (SIL runs with `--plot`).
    pub phase: Vec<(f64, f64)>,
    /// Gravity, m/s^2 (for the phase portrait of a run without a controller).
    pub gravity_mps2: f64,
}

impl Outcome for LineOutcome {
    fn text(&self) -> String {
        self.summary.to_text()
    }
    fn json(&self) -> Result<String, String> {
        json_text(&self.summary, JsonStyle::Pretty)
    }
    fn attach_hil(&mut self, report: HilReport) {
        self.summary.hil = Some(report);
    }
    fn safe_steps(&self) -> Option<&SafeSteps> {
        (self.summary.control_steps > 0).then_some(&self.summary.safe)
    }
    fn shortfall(&self) -> Option<String> {
        (self.summary.end == End::Diverged).then(|| {
            "diverged: the apex or the ball's state is not finite (a command overflowed)"
                .to_string()
        })
    }
}

/// The error of closing a loop through an external controller (`--hil`) on a scene
/// without one: it names the mode (exit 2, before anything starts).
fn needs_sil(scene: &Scene) -> SceneError {
    let (mode, what) = match scene.control.mode {
        ControlMode::None => ("none", "a passive scene"),
        ControlMode::IdealMirror => ("ideal_mirror", "the ideal-mirror scene"),
        ControlMode::Sil => ("sil", "this scene"),
    };
    SceneError::new(
        "control.mode",
        format!(
            "is \"{mode}\": {what} has no controller to put on the target (--hil needs control.mode = \"sil\")"
        ),
    )
}

impl System for LineSystem {
    const NAME: &'static str = "line";
    /// `--impacts N` sets `stop.impacts` and caps the time at N x 60 s (for runs whose
    /// ball stops bouncing); `--duration S` sets `stop.duration_s` and lifts the impacts.
    const LENGTH: RunLength = RunLength::EventsOrTime {
        events: "stop.impacts",
        time: "stop.duration_s",
        cap_s: 60.0,
    };
    type Config = Scene;
    type Controller = Controller;
    type Row = ImpactRow;
    type Outcome = LineOutcome;
    type Plots = plots::LinePlots;

    /// Every scene (it has no table of its own: `[physics]`, `[control]`, ...,
    /// `docs/scenes.md`): the registry asks the line system last, so it runs the scenes no
    /// other system claims.
    fn claims(_: &toml::Table) -> bool {
        true
    }

    fn parse(file: &SceneFile, mut table: toml::Table) -> Result<Scene, SceneError> {
        scene::name_after(&mut table, &file.stem)?;
        Scene::from_table(table)
    }

    fn controller_params(cfg: &Scene) -> Result<Option<ControllerParams>, SceneError> {
        if cfg.control.mode != ControlMode::Sil {
            return Err(needs_sil(cfg));
        }
        cfg.controller_params().map(Some)
    }

    fn run(
        cfg: &Scene,
        ctrl: Option<&mut dyn StepController<Controller>>,
        setup: &Setup,
        rows: &mut dyn FnMut(&ImpactRow),
    ) -> Result<LineOutcome, Failure> {
        let options = RunOptions {
            record_rows: false,
            record_phase: setup.plot,
            progress: setup.progress,
        };
        let out = run_streaming(cfg, &options, ctrl, rows).map_err(|e| match e {
            run::RunError::Scene(s) => Failure::scene(s),
            other => Failure::run(other),
        })?;
        Ok(LineOutcome {
            summary: Summary::new(cfg, &out),
            phase: out.phase,
            gravity_mps2: cfg.physics.gravity_mps2,
        })
    }
}

impl Analyzes for LineSystem {
    fn analyze<'a>(file: &'a SceneFile, cfg: &'a Scene) -> Result<Box<dyn Report + 'a>, Failure> {
        let _ = file;
        Ok(Box::new(analyze::analyze(cfg)?))
    }
}
