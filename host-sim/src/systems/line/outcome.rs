//! What a line run produces and records as it goes: its options, its errors, which limit
//! ended it, its outcome (apex statistics in constant memory, rows only when asked for).

use super::apexes::ApexStats;
use super::scene::Scene;
use super::trace::ImpactRow;
use crate::controller::{ControllerError, SafeSteps};
use crate::model::line::RestEvent;
use crate::scene::SceneError;
use dexter_core::state::BallState;

/// Most (b, b') samples kept for a phase portrait.
pub const MAX_PHASE_SAMPLES: usize = 200_000;

/// What to record and show during a run.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct RunOptions {
    /// Keep every impact row and apex height in the outcome (tests; memory grows with the
    /// run). The CLI streams rows instead ([`super::run::run_streaming`]).
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
    /// An impact left the ball slower than the paddle (the jitter made the restitution
    /// law's command unphysical): the run cannot go on.
    Unphysical(String),
}

impl std::fmt::Display for RunError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            RunError::Scene(e) => write!(f, "scene error: {e}"),
            RunError::Controller(e) => write!(f, "{e}"),
            RunError::Stalled(e) => write!(f, "the simulation stalled: {e}"),
            RunError::Unphysical(e) => write!(f, "unphysical impact: {e}"),
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
    /// The run diverged: the last apex or the ball's state is not finite (a law's command
    /// overflowed); the run fails (exit 1) after its summary.
    Diverged,
}

impl RunOutcome {
    /// End the run as [`End::Diverged`] if its last apex or the ball's final state is not
    /// finite. Checked once, at the end: a ball past 1e154 m/s never comes back within a
    /// run's time limit, so the per-impact path pays nothing for it.
    pub(super) fn check_finite(&mut self) {
        let ball = [self.final_ball.height_m, self.final_ball.velocity_mps];
        let apex = self.apexes.last().unwrap_or(0.0);
        if !(apex.is_finite() && ball.iter().all(|v| v.is_finite())) {
            self.end = End::Diverged;
        }
    }
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

impl<'a> Recorder<'a> {
    /// An empty outcome for a run of `scene`, keeping rows if `keep_rows`, every impact
    /// passed on to `sink`.
    pub(super) fn new(scene: &Scene, keep_rows: bool, sink: &'a mut dyn FnMut(&ImpactRow)) -> Self {
        Self {
            out: RunOutcome::new(scene),
            keep_rows,
            sink,
        }
    }

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
