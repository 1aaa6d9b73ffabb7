//! The CLI's verbs, written once for every system: `run` ([`run()`]: `--impacts`,
//! `--duration`, `--set`, `--json`, `--trace`, `--plot`, `--hil`), `sweep` ([`sweep()`]:
//! `--range`, `--range2`, `--keep`, `--csv`, `--plot`) and `analyze` ([`analyze()`]:
//! `--set`, `--json`; the analysis is the system's own). A system opts into each verb and
//! option (see [`crate::system::System`]); one it does not support is refused with exit
//! status 2 and a message naming the option ([`crate::system::Failure`]).

mod analyze;
mod run;
mod sweep;

pub use analyze::analyze;
pub use run::run;
pub use sweep::{sweep, MAX_KEEP};

use crate::system::{Failure, HilRequest};
use std::path::PathBuf;

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
