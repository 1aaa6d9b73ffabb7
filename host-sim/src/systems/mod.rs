//! The simulated systems, all of one shape ([`System`]), and the registry the CLI
//! dispatches on ([`SYSTEMS`], [`claim`]).
//!
//! | system | scene table | what |
//! | --- | --- | --- |
//! | [`arm`] | `[arm]` or `[task]` | Akella, Huang, Lynch & Mason's one-joint arm: snatch, throw, roll, rolling throw, planned and tracked |
//! | [`feeder`] | `[feeder]` | Akella, Huang, Lynch & Mason's 1JOC parts feeder: plan, simulated feed, fraction fed |
//! | [`hopper::sampled`] | `[hopper]` with `[hopper.control]` | the hopper's thrust valve switched by the core's fixed-rate controller (SIL, `--hil`) |
//! | [`hopper`] | `[hopper]` | Koditschek & Bühler's vertical hopper: return maps, period doubling |
//! | [`planar_juggler`] | `[planar_juggler]` | Rizzi & Koditschek's planar juggler, mirror law eq. 12 or the modified law eq. 15 |
//! | [`planar`] | `[planar]` | Zumel & Erdmann's bouncing body on the kappa-tilt table |
//! | [`line`](mod@line) | any other (`[physics]`, `[control]`, ...) | the line juggler and the passive bounce |
//!
//! How to add one: `docs/adding-a-system.md`.

pub mod arm;
pub mod feeder;
pub mod hopper;
pub mod line;
pub mod planar;
pub mod planar_juggler;

use crate::controller::{HilReport, SafeSteps, StepController};
use crate::external::OnTarget;
use crate::output::TraceRow;
use crate::scene::{SceneError, SceneFile};
use crate::verbs::{AnalyzeRequest, Failure, RunLength, RunRequest, Setup, SweepRequest};
use dexter_core::fixed_rate::FixedRate;
use std::path::{Path, PathBuf};

/// A simulated system: what the CLI's verbs need of it. Systems are unit structs; every
/// method is an associated function of the type.
///
/// The data flow of `dexter run` ([`crate::verbs::run`]): the scene table (with `--set`
/// and the run length applied) is parsed and validated into a [`System::Config`]
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

    /// The top-level scene table that selects this system (`planar`, `hopper`, ...).
    const TABLE: &'static str;

    /// True if this system runs a scene with these top-level tables: by default, if it has
    /// [`System::TABLE`].
    fn claims(table: &toml::Table) -> bool {
        table.contains_key(Self::TABLE)
    }

    /// The scene key `--impacts N` sets (e.g. `planar.impacts`, `hopper.cycles`).
    const IMPACTS_KEY: &'static str;
    /// The largest `--impacts` the system runs.
    const MAX_IMPACTS: u64 = i64::MAX as u64;

    /// Apply `--impacts` / `--duration` to the scene table, or refuse the option. By
    /// default `--impacts N` sets [`System::IMPACTS_KEY`] (1 ..= [`System::MAX_IMPACTS`])
    /// and `--duration` is refused.
    fn set_length(table: &mut toml::Table, length: &RunLength) -> Result<(), Failure> {
        length.no_duration::<Self>()?;
        if let Some(n) = length.impacts {
            if n == 0 || n > Self::MAX_IMPACTS {
                return Err(Failure::scene(format!(
                    "--impacts ({}) must be in 1..={}, got {n}",
                    Self::IMPACTS_KEY,
                    Self::MAX_IMPACTS
                )));
            }
            let value = toml::Value::Integer(n as i64);
            crate::scene::apply_set(table, Self::IMPACTS_KEY, value)?;
        }
        Ok(())
    }

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

    /// `dexter sweep` (systems that sweep implement [`crate::verbs::Sweeps`] and call
    /// [`crate::verbs::sweep`] here).
    fn sweep(file: &SceneFile, req: &SweepRequest) -> Result<(), Failure> {
        let _ = (file, req);
        Err(unsupported::<Self>("sweep"))
    }

    /// `dexter analyze`: the system's own analysis (linearization, closed forms).
    fn analyze(file: &SceneFile, req: &AnalyzeRequest) -> Result<(), Failure> {
        let _ = (file, req);
        Err(unsupported::<Self>("analyze"))
    }
}

/// A refusal of `what` (a verb or an option) for system `S` (exit status 2).
pub fn unsupported<S: System>(what: &str) -> Failure {
    Failure::usage(format!("{what} is not available for {} scenes", S::NAME))
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
    fn safe(&mut self, _: u32, _: dexter_core::protocol::Fault) -> Self::Command {
        match *self {}
    }
    fn telemetry(&self) -> dexter_core::protocol::Telemetry {
        match *self {}
    }
}

/// A system behind a reference: what the CLI's dispatch sees ([`System`] is not object
/// safe; every system gets this through the blanket impl).
pub trait Dispatch: Sync {
    /// [`System::NAME`].
    fn name(&self) -> &'static str;
    /// [`System::claims`].
    fn claims(&self, table: &toml::Table) -> bool;
    /// `dexter run`.
    fn run(&self, file: &SceneFile, req: &RunRequest) -> Result<(), Failure>;
    /// `dexter sweep`.
    fn sweep(&self, file: &SceneFile, req: &SweepRequest) -> Result<(), Failure>;
    /// `dexter analyze`.
    fn analyze(&self, file: &SceneFile, req: &AnalyzeRequest) -> Result<(), Failure>;
}

impl<S: System> Dispatch for S {
    fn name(&self) -> &'static str {
        S::NAME
    }
    fn claims(&self, table: &toml::Table) -> bool {
        S::claims(table)
    }
    fn run(&self, file: &SceneFile, req: &RunRequest) -> Result<(), Failure> {
        crate::verbs::run::<S>(file, req)
    }
    fn sweep(&self, file: &SceneFile, req: &SweepRequest) -> Result<(), Failure> {
        S::sweep(file, req)
    }
    fn analyze(&self, file: &SceneFile, req: &AnalyzeRequest) -> Result<(), Failure> {
        S::analyze(file, req)
    }
}

/// Every system, in the order they are asked to claim a scene: the line system last (it
/// claims every scene, so it runs those no other system claims).
pub static SYSTEMS: [&dyn Dispatch; 7] = [
    &arm::ArmSystem,
    &hopper::sampled::SampledHopperSystem,
    &feeder::FeederSystem,
    &hopper::HopperSystem,
    &planar_juggler::PlanarJugglerSystem,
    &planar::PlanarSystem,
    &line::LineSystem,
];

/// The system that runs a scene with these top-level tables.
pub fn claim(table: &toml::Table) -> &'static dyn Dispatch {
    SYSTEMS
        .iter()
        .copied()
        .find(|s| s.claims(table))
        .unwrap_or(&line::LineSystem)
}
