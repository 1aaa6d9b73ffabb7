//! Running a line scene: the plant is assembled once from the scene (only the enabled
//! effects, as concrete types: [`super::assemble`]), then either jumps from impact to
//! impact (no controller) or steps a [`StepController`] at its fixed rate with the
//! firmware's `SensorFrame`/`ActuatorCommand` ([`super::loops`]).
//!
//! Every impact is passed on as it happens ([`run_streaming`]); the outcome keeps its
//! apex statistics in constant memory ([`ApexStats`]), and keeps every row only when asked
//! ([`RunOptions::record_rows`], for tests).

use super::scene::{ControlMode, Scene};
use super::summary::ApexStats;
use super::trace::ImpactRow;
use crate::controller::{ControllerError, HilReport, SafeSteps, StepController};
use crate::model::line::RestEvent;
use crate::scene::SceneError;
use dexter_core::state::BallState;

/// Most (b, b') samples kept for a phase portrait.
pub const MAX_PHASE_SAMPLES: usize = 200_000;

/// What to record and show during a run.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct RunOptions {
    /// Keep every impact row and apex height in the outcome (tests; memory grows with the
    /// run). The CLI streams rows instead ([`run_streaming`]).
    pub record_rows: bool,
    /// Keep (b, b') samples once per control step (SIL) for a phase portrait, at most
    /// [`MAX_PHASE_SAMPLES`].
    pub record_phase: bool,
    /// Show a progress bar (only on a terminal, and for runs of more than 10 000 impacts).
    pub progress: bool,
}

/// Why a run failed.
#[derive(Debug)]
pub enum RunError {
    /// The scene cannot be run as asked.
    Scene(SceneError),
    /// The controller failed.
    Controller(ControllerError),
    /// The plant stopped advancing before the run's end (an internal cap was hit: the run
    /// fails rather than end early).
    Stalled(String),
}

impl std::fmt::Display for RunError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            RunError::Scene(e) => write!(f, "scene error: {e}"),
            RunError::Controller(e) => write!(f, "{e}"),
            RunError::Stalled(e) => write!(f, "the simulation stalled: {e}"),
        }
    }
}

/// Which of its limits ended a run.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum End {
    /// The requested impacts (`stop.impacts`, `--impacts`) were simulated.
    Impacts,
    /// The time limit (`stop.duration_s`, `--duration`) was reached.
    #[default]
    Duration,
    /// The ball came to rest on a fixed table: no impact will follow.
    Resting,
}

impl std::error::Error for RunError {}

impl From<SceneError> for RunError {
    fn from(e: SceneError) -> Self {
        RunError::Scene(e)
    }
}

impl From<ControllerError> for RunError {
    fn from(e: ControllerError) -> Self {
        RunError::Controller(e)
    }
}

/// Everything a run produced.
#[derive(Clone, Debug)]
pub struct RunOutcome {
    /// Impact rows (empty unless [`RunOptions::record_rows`]).
    pub rows: Vec<ImpactRow>,
    /// Apex height after every impact, m (empty unless [`RunOptions::record_rows`]).
    pub apexes_m: Vec<f64>,
    /// Convergence, period and the last apex, in constant memory.
    pub apexes: ApexStats,
    /// The last impact, if any.
    pub last_row: Option<ImpactRow>,
    /// Impacts simulated.
    pub impacts: u64,
    /// Simulated time at the end, s.
    pub sim_time_s: f64,
    /// Wall-clock time of the run, s.
    pub wall_time_s: f64,
    /// Control steps taken (0 without a controller).
    pub control_steps: u64,
    /// Resting-contact episodes (first 64).
    pub rests: Vec<RestEvent>,
    /// Resting-contact episodes in total.
    pub rest_count: u64,
    /// True if the ball rests on the paddle at the end.
    pub resting_at_end: bool,
    /// Grazing contacts.
    pub grazing_contacts: u64,
    /// (b, b') samples, m and m/s.
    pub phase: Vec<(f64, f64)>,
    /// Ball state at the end.
    pub final_ball: BallState<f64>,
    /// HIL timing and link figures, if the controller ran on a target.
    pub hil: Option<HilReport>,
    /// Which limit ended the run.
    pub end: End,
    /// The controller's safe-state steps (none without a controller).
    pub safe: SafeSteps,
}

impl RunOutcome {
    /// An empty outcome for a run of `scene`.
    pub(super) fn new(scene: &Scene) -> Self {
        Self {
            rows: Vec::new(),
            apexes_m: Vec::new(),
            apexes: ApexStats::for_scene(scene),
            last_row: None,
            impacts: 0,
            sim_time_s: 0.0,
            wall_time_s: 0.0,
            control_steps: 0,
            rests: Vec::new(),
            rest_count: 0,
            resting_at_end: false,
            grazing_contacts: 0,
            phase: Vec::new(),
            final_ball: BallState::default(),
            hil: None,
            end: End::Duration,
            safe: SafeSteps::default(),
        }
    }
}

/// Collects impacts into the outcome and passes them on.
pub(super) struct Recorder<'a> {
    pub(super) out: RunOutcome,
    keep_rows: bool,
    sink: &'a mut dyn FnMut(&ImpactRow),
}

impl Recorder<'_> {
    #[inline(always)]
    pub(super) fn push(&mut self, row: &ImpactRow) {
        self.out.apexes.push(row.apex_height_m);
        if self.keep_rows {
            self.out.rows.push(*row);
            self.out.apexes_m.push(row.apex_height_m);
        }
        (self.sink)(row);
    }
}

/// Run `scene` with `options`, passing every impact to `on_impact` as it happens. For
/// `control.mode = "sil"` the controller is `controller` if given (e.g. the firmware in
/// QEMU), else the core linked in ([`crate::controller::Sil`]).
pub fn run_streaming(
    scene: &Scene,
    options: &RunOptions,
    controller: Option<&mut dyn StepController>,
    on_impact: &mut dyn FnMut(&ImpactRow),
) -> Result<RunOutcome, RunError> {
    if controller.is_some() && scene.control.mode != ControlMode::Sil {
        return Err(super::needs_sil(scene).into());
    }
    let mut rec = Recorder {
        out: RunOutcome::new(scene),
        keep_rows: options.record_rows,
        sink: on_impact,
    };
    super::assemble::run(scene, options, controller, &mut rec)?;
    Ok(rec.out)
}

/// Run `scene` with `options` (as [`run_streaming`], keeping rows only if
/// [`RunOptions::record_rows`]).
pub fn run_scene(
    scene: &Scene,
    options: &RunOptions,
    controller: Option<&mut dyn StepController>,
) -> Result<RunOutcome, RunError> {
    run_streaming(scene, options, controller, &mut |_| {})
}
