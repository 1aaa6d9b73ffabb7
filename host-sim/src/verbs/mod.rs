//! The CLI's verbs, written once for every system: `run` ([`run()`]: `--impacts`,
//! `--duration`, `--set`, `--json`, `--trace`, `--plot`, `--hil`) and `sweep` ([`sweep()`]:
//! `--range`, `--range2`, `--keep`, `--csv`, `--plot`); `analyze` is a system's own. A
//! system opts into each verb and option (see [`crate::systems::System`]); one it does not
//! support is refused with exit status 2 and a message naming the option.
//!
//! Exit statuses: 2 for a bad scene or bad arguments ([`Failure::scene`],
//! [`Failure::usage`]), 1 for a run that failed (controller, I/O; [`Failure::run`]).

mod run;
mod sweep;

pub use run::{run, RunLength, Setup};
pub use sweep::{sweep, SweepBase, SweepReport, Sweeps};

use crate::external::HilRequest;
use crate::output::OutputError;
use crate::plot::PlotError;
use crate::scene::SceneError;
use std::fmt;
use std::path::PathBuf;

/// Exit status for a bad scene or bad arguments.
pub const EXIT_SCENE: u8 = 2;
/// Exit status for a failed run (controller, I/O).
pub const EXIT_RUN: u8 = 1;

/// A failed command: its exit status and what to tell the user.
#[derive(Clone, Debug, PartialEq)]
pub struct Failure {
    /// [`EXIT_SCENE`] or [`EXIT_RUN`].
    pub code: u8,
    /// The message (printed after `error: `).
    pub message: String,
}

impl Failure {
    /// A bad scene (exit 2): `bad scene: ...`.
    pub fn scene(e: impl fmt::Display) -> Self {
        Self {
            code: EXIT_SCENE,
            message: format!("bad scene: {e}"),
        }
    }

    /// Bad arguments (exit 2).
    pub fn usage(m: impl fmt::Display) -> Self {
        Self {
            code: EXIT_SCENE,
            message: m.to_string(),
        }
    }

    /// A failed run (exit 1).
    pub fn run(m: impl fmt::Display) -> Self {
        Self {
            code: EXIT_RUN,
            message: m.to_string(),
        }
    }

    /// The same failure with `context` after its message (e.g. the swept value).
    pub fn at(mut self, context: impl fmt::Display) -> Self {
        self.message = format!("{} ({context})", self.message);
        self
    }
}

impl fmt::Display for Failure {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.message)
    }
}

impl From<SceneError> for Failure {
    fn from(e: SceneError) -> Self {
        Failure::scene(e)
    }
}

impl From<OutputError> for Failure {
    fn from(e: OutputError) -> Self {
        Failure::run(e)
    }
}

impl From<PlotError> for Failure {
    fn from(e: PlotError) -> Self {
        Failure::run(format!("plot: {e}"))
    }
}

/// `dexter run SCENE ...` as parsed from the command line.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct RunRequest {
    /// `--set key.path=value`, unparsed, in order.
    pub sets: Vec<String>,
    /// `--impacts N`: the run's length in the system's events (impacts, hops, bats).
    pub impacts: Option<u64>,
    /// `--duration S`: simulated seconds (systems with a time limit).
    pub duration: Option<f64>,
    /// `--trace FILE.csv`: one row per event.
    pub trace: Option<PathBuf>,
    /// `--plot DIR`: SVG + PNG plots.
    pub plot: Option<PathBuf>,
    /// `--json`: one JSON object instead of the human summary.
    pub json: bool,
    /// `--hil ...`: the controller runs as firmware in QEMU.
    pub hil: Option<HilRequest>,
}

/// `dexter sweep SCENE ...` as parsed from the command line.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct SweepRequest {
    /// `--set key.path=value`, unparsed, in order.
    pub sets: Vec<String>,
    /// `--range key.path=FROM:TO:N`, unparsed.
    pub range: String,
    /// `--range2 key.path=FROM:TO:M`, unparsed: a second axis (systems that map two).
    pub range2: Option<String>,
    /// `--keep K`: late values kept per point (systems that keep values).
    pub keep: usize,
    /// `--csv FILE`: the points as CSV (else on stdout).
    pub csv: Option<PathBuf>,
    /// `--plot DIR`: the sweep's plot.
    pub plot: Option<PathBuf>,
}

/// `dexter analyze SCENE ...` as parsed from the command line.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct AnalyzeRequest {
    /// `--set key.path=value`, unparsed, in order.
    pub sets: Vec<String>,
    /// `--json`: one JSON object instead of the human report.
    pub json: bool,
}

/// Print a run's or an analysis' result: `text`, or `json` when asked.
pub fn print_result(
    json: bool,
    text: impl FnOnce() -> String,
    json_text: impl FnOnce() -> Result<String, String>,
) -> Result<(), Failure> {
    if json {
        println!("{}", json_text().map_err(Failure::run)?);
    } else {
        print!("{}", text());
    }
    Ok(())
}
