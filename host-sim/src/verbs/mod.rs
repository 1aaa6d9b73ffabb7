//! The CLI's verbs, written once for every system: `run` ([`run()`]: `--impacts`,
//! `--duration`, `--set`, `--json`, `--trace`, `--plot`, `--hil`), `sweep` ([`sweep()`]:
//! `--range`, `--range2`, `--keep`, `--csv`, `--plot`) and `analyze` ([`analyze()`]:
//! `--set`, `--json`; the analysis is the system's own); `sweep` and `basin` also run one
//! shard of their grid (`--shard K/N`, [`crate::shard`]) and `merge` ([`merge`]) joins the
//! shards. A system opts into each verb and
//! option (see [`crate::system::System`]); one it does not support is refused with exit
//! status 2 and a message naming the option ([`crate::system::Failure`]).

mod analyze;
pub mod basin;
pub mod board;
pub mod merge;
mod run;
mod shard;
mod sweep;

pub use analyze::analyze;
pub use run::run;
pub use sweep::{sweep, MAX_KEEP};

use crate::output::print_stdout;
use crate::system::{Failure, HilRequest};
use clap::Args;
use std::path::PathBuf;

/// `dexter run SCENE ...` as parsed from the command line (the doc comment of each field
/// is its `--help` line).
#[derive(Args, Clone, Debug, Default, PartialEq)]
pub struct RunRequest {
    /// The scene file (TOML).
    pub scene: PathBuf,
    /// Events to simulate: impacts, hops or bats (line scenes: overrides stop.impacts; the
    /// duration limit becomes N x 60 s, a cap for runs whose ball stops bouncing).
    #[arg(long, conflicts_with = "duration")]
    pub impacts: Option<u64>,
    /// Simulated seconds (line scenes: overrides stop.duration_s; the impact limit is lifted).
    #[arg(long)]
    pub duration: Option<f64>,
    /// Override a scene key: key.path=value (repeatable).
    #[arg(long = "set", value_name = "KEY=VALUE")]
    pub sets: Vec<String>,
    /// Write the trace as CSV, one row per event (a missing directory is created).
    #[arg(long, value_name = "FILE.csv")]
    pub trace: Option<PathBuf>,
    /// Write plots (SVG + PNG) into this directory.
    #[arg(long, value_name = "DIR")]
    pub plot: Option<PathBuf>,
    /// Print the summary as one JSON object.
    #[arg(long)]
    pub json: bool,
    /// Hardware in the loop: the firmware in QEMU is the controller.
    #[arg(long)]
    pub hil: bool,
    /// The `--hil` options (each requires `--hil`).
    #[command(flatten)]
    pub target: HilRequest,
}

impl RunRequest {
    /// The `--hil` options, if `--hil` was given.
    pub fn on_target(&self) -> Option<&HilRequest> {
        self.hil.then_some(&self.target)
    }
}

/// `dexter sweep SCENE ...` as parsed from the command line.
#[derive(Args, Clone, Debug, Default, PartialEq)]
pub struct SweepRequest {
    /// The scene file (TOML).
    pub scene: PathBuf,
    /// The swept key and its values: key.path=FROM:TO:N.
    #[arg(long, value_name = "KEY=FROM:TO:N")]
    pub range: String,
    /// A second swept key for a two-dimensional map (planar scenes): key.path=FROM:TO:N.
    #[arg(long, value_name = "KEY=FROM:TO:N")]
    pub range2: Option<String>,
    /// Override a scene key: key.path=value (repeatable).
    #[arg(long = "set", value_name = "KEY=VALUE")]
    pub sets: Vec<String>,
    /// Late values kept from the end of each run.
    #[arg(long, default_value_t = 64)]
    pub keep: usize,
    /// Write the points as CSV (a missing directory is created; else on stdout).
    #[arg(long, value_name = "FILE.csv")]
    pub csv: Option<PathBuf>,
    /// Write the sweep's plot into this directory.
    #[arg(long, value_name = "DIR")]
    pub plot: Option<PathBuf>,
    /// Run only the K-th of N shards of the grid (1 <= K <= N) into --csv FILE, for
    /// `dexter merge`; a complete shard already there is kept.
    #[arg(long, value_name = "K/N")]
    pub shard: Option<String>,
}

/// `dexter analyze SCENE ...` as parsed from the command line.
#[derive(Args, Clone, Debug, Default, PartialEq)]
pub struct AnalyzeRequest {
    /// The scene file (TOML).
    pub scene: PathBuf,
    /// Override a scene key: key.path=value (repeatable).
    #[arg(long = "set", value_name = "KEY=VALUE")]
    pub sets: Vec<String>,
    /// Print one JSON object instead of the human report.
    #[arg(long)]
    pub json: bool,
    /// Write the analysis' pictures into this directory (where the system draws them).
    #[arg(long, value_name = "DIR")]
    pub plot: Option<PathBuf>,
}

/// Print a run's or an analysis' result on stdout: `text`, or `json` when asked. A write
/// error is returned (a closed pipe: [`crate::system::EXIT_BROKEN_PIPE`], silently; a full
/// disk: exit 1), never a panic.
pub fn print_result(
    json: bool,
    text: impl FnOnce() -> String,
    json_text: impl FnOnce() -> Result<String, String>,
) -> Result<(), Failure> {
    let out = match json {
        true => json_text().map_err(Failure::run)? + "\n",
        false => text(),
    };
    Ok(print_stdout(&out)?)
}
