//! `dexter`: run scenes, sweep parameters, analyze, write traces and plots.
//!
//! The scene file is read once; the system that claims its top-level tables
//! (`dexter_sim::cli::registry::claim`) runs the verb. Nothing here knows a system by name.

use clap::{Args, Parser, Subcommand, ValueEnum};
use dexter_sim::cli::registry::{claim, Entry};
use dexter_sim::hil::LinkKind;
use dexter_sim::scene::SceneFile;
use dexter_sim::system::{Failure, HilRequest};
use dexter_sim::verbs::{AnalyzeRequest, RunRequest, SweepRequest};
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
    Run(RunArgs),
    /// Run a scene over a range of one key (or a map over two) and collect late values.
    Sweep(SweepArgs),
    /// Linearize a scene's return map at its fixed point: eigenvalues or slope, verdict.
    Analyze(AnalyzeArgs),
}

#[derive(Args)]
struct AnalyzeArgs {
    /// The scene file (TOML).
    scene: PathBuf,
    /// Override a scene key: key.path=value (repeatable).
    #[arg(long = "set", value_name = "KEY=VALUE")]
    set: Vec<String>,
    /// Print one JSON object instead of the human report.
    #[arg(long)]
    json: bool,
}

#[derive(Clone, Copy, Debug, ValueEnum)]
enum Link {
    Semihosting,
    Uart,
}

#[derive(Args)]
struct RunArgs {
    /// The scene file (TOML).
    scene: PathBuf,
    /// Events to simulate: impacts, hops or bats (line scenes: overrides stop.impacts; the
    /// duration limit becomes N x 60 s, a cap for runs whose ball stops bouncing).
    #[arg(long, conflicts_with = "duration")]
    impacts: Option<u64>,
    /// Simulated seconds (line scenes: overrides stop.duration_s; the impact limit is lifted).
    #[arg(long)]
    duration: Option<f64>,
    /// Override a scene key: key.path=value (repeatable).
    #[arg(long = "set", value_name = "KEY=VALUE")]
    set: Vec<String>,
    /// Write the trace as CSV, one row per event (a missing directory is created).
    #[arg(long, value_name = "FILE.csv")]
    trace: Option<PathBuf>,
    /// Write plots (SVG + PNG) into this directory.
    #[arg(long, value_name = "DIR")]
    plot: Option<PathBuf>,
    /// Print the summary as one JSON object.
    #[arg(long)]
    json: bool,
    /// Hardware in the loop: the firmware in QEMU is the controller.
    #[arg(long)]
    hil: bool,
    /// Firmware ELF for --hil (default: the release build in target/).
    #[arg(long, value_name = "PATH", requires = "hil")]
    firmware: Option<PathBuf>,
    /// Plant link for --hil.
    #[arg(long, value_enum, requires = "hil")]
    link: Option<Link>,
    /// Instruction budget per control step for --hil (0 = no budget).
    #[arg(long, value_name = "N", requires = "hil")]
    budget: Option<u32>,
    /// Fraction of host-to-device bytes corrupted for --hil, in [0, 1].
    #[arg(long, value_name = "F", requires = "hil")]
    corrupt_rate: Option<f64>,
    /// HIL against a real board on this serial port (e.g. /dev/ttyACM0) instead of QEMU.
    #[arg(long, value_name = "PATH", requires = "hil", conflicts_with_all = ["firmware", "link"])]
    port: Option<PathBuf>,
}

#[derive(Args)]
struct SweepArgs {
    /// The scene file (TOML).
    scene: PathBuf,
    /// The swept key and its values: key.path=FROM:TO:N.
    #[arg(long, value_name = "KEY=FROM:TO:N")]
    range: String,
    /// A second swept key for a two-dimensional map (planar scenes): key.path=FROM:TO:N.
    #[arg(long, value_name = "KEY=FROM:TO:N")]
    range2: Option<String>,
    /// Override a scene key: key.path=value (repeatable).
    #[arg(long = "set", value_name = "KEY=VALUE")]
    set: Vec<String>,
    /// Late values kept from the end of each run.
    #[arg(long, default_value_t = 64)]
    keep: usize,
    /// Write the points as CSV (a missing directory is created; else on stdout).
    #[arg(long, value_name = "FILE.csv")]
    csv: Option<PathBuf>,
    /// Write the sweep's plot into this directory.
    #[arg(long, value_name = "DIR")]
    plot: Option<PathBuf>,
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

impl RunArgs {
    /// The default command: the realistic line juggler, plots into `out/`.
    fn default_run() -> Self {
        let root = workspace_root();
        Self {
            scene: root.join("scenes").join("line-juggler.toml"),
            impacts: None,
            duration: None,
            set: Vec::new(),
            trace: None,
            plot: Some(root.join("out")),
            json: false,
            hil: false,
            firmware: None,
            link: None,
            budget: None,
            corrupt_rate: None,
            port: None,
        }
    }

    fn request(self) -> RunRequest {
        let hil = self.hil.then(|| HilRequest {
            firmware: self.firmware,
            link: self.link.map(|l| match l {
                Link::Semihosting => LinkKind::Semihosting,
                Link::Uart => LinkKind::Uart,
            }),
            budget: self.budget,
            corrupt_rate: self.corrupt_rate,
            port: self.port,
        });
        RunRequest {
            sets: self.set,
            impacts: self.impacts,
            duration: self.duration,
            trace: self.trace,
            plot: self.plot,
            json: self.json,
            hil,
        }
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

fn main() -> ExitCode {
    let cli = Cli::parse();
    let result = match cli.command {
        Some(Command::Run(args)) => run(args),
        None => run(RunArgs::default_run()),
        Some(Command::Sweep(a)) => with_scene(&a.scene.clone(), |s, f| {
            let req = SweepRequest {
                sets: a.set,
                range: a.range,
                range2: a.range2,
                keep: a.keep,
                csv: a.csv,
                plot: a.plot,
            };
            (s.sweep)(f, &req)
        }),
        Some(Command::Analyze(a)) => with_scene(&a.scene.clone(), |s, f| {
            let req = AnalyzeRequest {
                sets: a.set,
                json: a.json,
            };
            (s.analyze)(f, &req)
        }),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(f) => {
            eprintln!("error: {}", f.message);
            ExitCode::from(f.code)
        }
    }
}

fn run(args: RunArgs) -> Result<(), Failure> {
    let path = args.scene.clone();
    with_scene(&path, |s, f| (s.run)(f, &args.request()))
}
