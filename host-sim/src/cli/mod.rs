//! The command line (`dexter`): clap parses straight into the verbs' request types
//! ([`RunRequest`], [`SweepRequest`], [`AnalyzeRequest`]); the scene file is read once and
//! the system that claims its top-level tables ([`registry::claim`]) runs the verb. Nothing
//! here knows a system by name.

mod interrupt;
pub mod registry;

use crate::scene::SceneFile;
use crate::system::Failure;
use crate::verbs::basin::BasinRequest;
use crate::verbs::board::BoardRequest;
use crate::verbs::merge::{MergeRequest, ShardSet};
use crate::verbs::{AnalyzeRequest, RunRequest, SweepRequest};
use clap::{Parser, Subcommand};
use registry::{claim, Entry};
use std::path::{Path, PathBuf};
use std::process::ExitCode;

#[derive(Parser)]
#[command(
    name = "dexter",
    version,
    about = "dexter simulator: scenes, SIL/HIL runs, traces and plots.\nWithout a subcommand: run scenes/line-juggler.toml and write its plots to out/."
)]
struct Cli {
    #[command(subcommand)]
    command: Option<Command>,
}

#[derive(Subcommand)]
enum Command {
    /// Run one scene and print its summary.
    Run(RunRequest),
    /// Run a scene over a range of one key (or a map over two) and collect late values.
    Sweep(SweepRequest),
    /// Linearize a scene's return map at its fixed point: eigenvalues or slope, verdict.
    Analyze(AnalyzeRequest),
    /// Run every point of a two-key grid to its end and classify it (basin map).
    Basin(BasinRequest),
    /// What the NUCLEO-F446RE's stand-alone loop needs of a line scene: camera rate and
    /// latency; `--write FILE`: the scene's Configure frame for the board's build.
    Board(BoardRequest),
    /// Merge the shards of a sweep or basin map (`--shard K/N`) into its CSV and plots.
    Merge(MergeRequest),
}

/// Where the default run finds `scenes/line-juggler.toml` and writes `out/`: the current
/// directory if it has that scene, else this crate's workspace, else the current directory.
fn workspace_root() -> PathBuf {
    let here = PathBuf::from(".");
    let built = Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    let root = if here.join("scenes").join("line-juggler.toml").is_file() {
        here
    } else if built.join("scenes").is_dir() {
        built
    } else {
        return here;
    };
    root.canonicalize().unwrap_or(root)
}

/// The default command: the realistic line juggler, plots into `out/`.
fn default_run() -> RunRequest {
    let root = workspace_root();
    RunRequest {
        scene: root.join("scenes").join("line-juggler.toml"),
        plot: Some(root.join("out")),
        ..RunRequest::default()
    }
}

/// Read the scene once and hand it to the system that claims it.
fn with_scene(
    path: &Path,
    verb: impl FnOnce(&Entry, &SceneFile) -> Result<(), Failure>,
) -> Result<(), Failure> {
    let file = SceneFile::read(path)?;
    verb(claim(&file.table), &file)
}

/// `dexter merge`: the shards checked, then merged by the system their scene belongs to.
fn merge(req: &MergeRequest) -> Result<(), Failure> {
    let set = ShardSet::open(req)?;
    let entry = claim(&set.file.table);
    match set.verb() {
        "basin" => (entry.merge_basin)(set, req),
        _ => (entry.merge_sweep)(set, req),
    }
}

/// `dexter` with the process's arguments: the exit status of the verb (0, or the
/// [`Failure`]'s code after printing `error: ` and its message on stderr).
pub fn main() -> ExitCode {
    let cli = Cli::parse();
    let command = cli.command.unwrap_or_else(|| Command::Run(default_run()));
    let (verb, scene) = match &command {
        Command::Run(r) => ("run", &r.scene),
        Command::Sweep(r) => ("sweep", &r.scene),
        Command::Analyze(r) => ("analyze", &r.scene),
        Command::Basin(r) => ("basin", &r.scene),
        Command::Board(r) => ("board", &r.scene),
        Command::Merge(r) => ("merge", &r.out),
    };
    interrupt::install(format!("{verb} {}", scene.display()));
    let result = match command {
        Command::Run(req) => with_scene(&req.scene, |s, f| (s.run)(f, &req)),
        Command::Sweep(req) => with_scene(&req.scene, |s, f| (s.sweep)(f, &req)),
        Command::Analyze(req) => with_scene(&req.scene, |s, f| (s.analyze)(f, &req)),
        Command::Basin(req) => with_scene(&req.scene, |s, f| (s.basin)(f, &req)),
        Command::Board(req) => with_scene(&req.scene, |s, f| {
            crate::verbs::board::board(s.name, f, &req)
        }),
        Command::Merge(req) => merge(&req),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(f) => {
            // a closed stdout ends quietly; a failure to write stderr changes nothing
            if !f.message.is_empty() {
                crate::output::note(format_args!("error: {}", f.message));
            }
            ExitCode::from(f.code)
        }
    }
}
