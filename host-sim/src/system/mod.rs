//! What every simulated system is to the CLI's verbs: the [`System`] trait, what a run
//! produced ([`Outcome`]) and drew ([`Plots`]), what a run records besides its summary
//! ([`Setup`]), its run length ([`RunLength`]), its failures and their exit statuses
//! ([`Failure`]), and the verbs a system opts into ([`Sweeps`], [`Analyzes`]). Its
//! controller on a target (`--hil`) is [`target`]'s.
//!
//! The systems (`crate::systems`) implement these; the verbs (`crate::verbs`) and the
//! registry (`crate::cli`) use them. Nothing here names a system.

mod analyze;
pub mod basin;
mod failure;
mod length;
mod sweep;
pub mod target;

pub use analyze::{Analyzes, Report};
pub use failure::{Failure, EXIT_BROKEN_PIPE, EXIT_RUN, EXIT_SCENE};
pub use length::RunLength;
pub use sweep::{SweepBase, SweepReport, Sweeps};
pub use target::{HilRequest, OnTarget, Target};

use crate::controller::{HilReport, SafeSteps, StepController};
use crate::output::TraceRow;
use crate::scene::{SceneError, SceneFile};
use dexter_core::fixed_rate::FixedRate;
use std::path::{Path, PathBuf};

/// What a run records besides its summary.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Setup {
    /// The plots are drawn: record what only they need (e.g. phase-portrait samples).
    pub plot: bool,
    /// Show a progress bar on a terminal.
    pub progress: bool,
}

/// A simulated system: what the CLI's verbs need of it. Systems are unit structs; every
/// method is an associated function of the type.
///
/// The data flow of `dexter run` (`crate::verbs::run`): the scene table (with `--set`
/// and the run length, [`System::LENGTH`], applied) is parsed and validated into a [`System::Config`]
/// ([`System::parse`]); [`System::run`] assembles the plant with only the enabled effects,
/// closes its loop through a [`StepController`] of kind [`System::Controller`] if it has
/// one (the core linked in, or the firmware in QEMU with `--hil`), and streams one
/// [`System::Row`] per event to the trace and the plots while it keeps its summary in
/// constant memory; the [`System::Outcome`] is printed as text or JSON.
pub trait System: Sync + Sized + 'static {
    /// The system's name in messages and docs (`line`, `planar`, `hopper`, ...).
    const NAME: &'static str;
    /// The parsed, validated scene.
    type Config: Sync;
    /// The controller kind the plant closes its loop through ([`NoController`] if none).
    type Controller: OnTarget;
    /// One row of the `--trace` CSV (one per event: impact, hop, bat).
    type Row: TraceRow;
    /// What a run produced: its summary as text and JSON.
    type Outcome: Outcome;
    /// What the `--plot` pictures keep of the rows (bounded) and how they are drawn.
    type Plots: Plots<Self>;

    /// True if this system runs a scene with these top-level tables (e.g. it has a
    /// `[planar]` table). The registry asks the systems in its order.
    fn claims(table: &toml::Table) -> bool;

    /// What `--impacts` and `--duration` set in this system's scenes.
    const LENGTH: RunLength;

    /// Parse and validate the scene (`--set` and the run length applied): unknown keys
    /// are denied and every error names its key.
    fn parse(file: &SceneFile, table: toml::Table) -> Result<Self::Config, SceneError>;

    /// The parameters of the controller this scene runs on a target (`--hil`), or `None`
    /// if the system has no such controller. A scene that cannot close its loop through
    /// one (e.g. a passive scene) is a [`SceneError`] naming the key.
    fn controller_params(
        cfg: &Self::Config,
    ) -> Result<Option<<Self::Controller as FixedRate>::Params>, SceneError> {
        let _ = cfg;
        Ok(None)
    }

    /// Simulate: `ctrl` is the external controller (`--hil`) or `None` (the system's own:
    /// the core linked in, SIL); every event's row goes to `rows` as it happens.
    fn run(
        cfg: &Self::Config,
        ctrl: Option<&mut dyn StepController<Self::Controller>>,
        setup: &Setup,
        rows: &mut dyn FnMut(&Self::Row),
    ) -> Result<Self::Outcome, Failure>;
}

/// A refusal of `what` (a verb or an option) for system `S` (exit status 2).
pub fn unsupported<S: System>(what: &str) -> Failure {
    refusal(S::NAME, what)
}

/// A refusal of `what` for the system called `system` (exit status 2).
fn refusal(system: &str, what: &str) -> Failure {
    Failure::usage(format!("{what} is not available for {system} scenes"))
}

/// A run's result as the CLI prints it.
pub trait Outcome {
    /// The human summary.
    fn text(&self) -> String;
    /// One JSON object.
    fn json(&self) -> Result<String, String>;
    /// The HIL figures of a run whose controller ran on the target.
    fn attach_hil(&mut self, report: HilReport) {
        let _ = report;
    }
    /// The controller's safe-state steps, for a system that closes its loop through one
    /// (counted by [`crate::closed_loop::drive`]): `run` warns on the terminal when
    /// there are any, and exits with status 1 when they are more than half of the steps.
    fn safe_steps(&self) -> Option<&SafeSteps> {
        None
    }
    /// Why the run stopped before doing what was asked for a reason other than the
    /// system's physics (an internal cap, a non-finite state), as the summary names it:
    /// `run` prints the summary, then this as the error, and exits with status 1.
    fn shortfall(&self) -> Option<String> {
        None
    }
}

/// The `--plot` pictures of a run of `S`: what they keep of the rows (bounded: decimated
/// past [`crate::stream::PLOT_MAX_POINTS`] points per series) and how they are drawn.
pub trait Plots<S: System>: Sized {
    /// Ready to collect for a run of `cfg`.
    fn new(cfg: &S::Config) -> Self;
    /// One event's row.
    fn push(&mut self, row: &S::Row);
    /// Draw every plot into `dir` (SVG + PNG each); the files written.
    fn write(
        self,
        cfg: &S::Config,
        outcome: &S::Outcome,
        dir: &Path,
    ) -> Result<Vec<PathBuf>, Failure>;
}

/// The controller kind of a system that has none on a target (no `--hil`): it cannot be
/// built, so no value of it exists.
#[derive(Clone, Copy, Debug)]
pub enum NoController {}

impl FixedRate for NoController {
    type Params = ();
    type Frame = ();
    type Command = dexter_core::protocol::ActuatorCommand;
    /// Never stepped.
    const STEP_INSTRUCTION_BUDGET: u32 = 0;

    fn new(_: ()) -> Result<Self, dexter_core::params::ParamError> {
        Err(dexter_core::params::ParamError::OutOfRange("controller"))
    }
    fn params(&self) -> &() {
        match *self {}
    }
    fn step(&mut self, _: &()) -> Self::Command {
        match *self {}
    }
    fn safe(&mut self, _: u32, _: dexter_core::fixed_rate::Fault) -> Self::Command {
        match *self {}
    }
    fn telemetry(&self) -> dexter_core::fixed_rate::Telemetry {
        match *self {}
    }
}
