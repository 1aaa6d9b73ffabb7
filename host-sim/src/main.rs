//! `dexter`: run scenes, sweep parameters, write traces and plots.

use clap::{Args, Parser, Subcommand, ValueEnum};
use dexter_sim::apps::{self, AppAnalyze, AppError, AppRun, AppSweep, Kind};
use dexter_sim::controller::StepController;
use dexter_sim::report::Summary;
use dexter_sim::run::{run_scene, RunOptions, RunOutcome};
use dexter_sim::scene::{parse_set, Scene, SceneError};
use dexter_sim::sweep::{sweep, Range};
use dexter_sim::trace::{write_csv, ImpactRow};
use dexter_sim::{hil, plot};
use std::path::{Path, PathBuf};
use std::process::ExitCode;

/// Exit status for a bad scene or bad arguments.
const EXIT_SCENE: u8 = 2;
/// Exit status for a failed run (controller, I/O).
const EXIT_RUN: u8 = 1;

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
    /// Run a scene over a range of one key and collect late apexes (bifurcation diagram).
    Sweep(SweepArgs),
    /// Linearize a scene's impact-to-impact map at its fixed point: eigenvalues, verdict.
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
    /// Impacts to simulate (overrides stop.impacts; the duration limit becomes N x 60 s, a
    /// cap for runs whose ball stops bouncing).
    #[arg(long, conflicts_with = "duration")]
    impacts: Option<u64>,
    /// Simulated seconds (overrides stop.duration_s; the impact limit is lifted).
    #[arg(long)]
    duration: Option<f64>,
    /// Override a scene key: key.path=value (repeatable).
    #[arg(long = "set", value_name = "KEY=VALUE")]
    set: Vec<String>,
    /// Write the impact trace as CSV.
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
    /// --hil on a real board on this serial port (e.g. /dev/ttyACM0) instead of QEMU.
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
    /// Apexes kept from the end of each run.
    #[arg(long, default_value_t = 64)]
    keep: usize,
    /// Write the (value, apex) points as CSV.
    #[arg(long, value_name = "FILE.csv")]
    csv: Option<PathBuf>,
    /// Write the bifurcation plot into this directory.
    #[arg(long, value_name = "DIR")]
    plot: Option<PathBuf>,
}

/// A failure with its exit status.
struct Failure {
    code: u8,
    message: String,
}

impl From<SceneError> for Failure {
    fn from(e: SceneError) -> Self {
        Failure {
            code: EXIT_SCENE,
            message: format!("bad scene: {e}"),
        }
    }
}

fn run_failure(message: impl std::fmt::Display) -> Failure {
    Failure {
        code: EXIT_RUN,
        message: message.to_string(),
    }
}

/// The workspace root: this crate's parent, else the current directory.
fn workspace_root() -> PathBuf {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    if root.join("scenes").is_dir() {
        root.canonicalize().unwrap_or(root)
    } else {
        PathBuf::from(".")
    }
}

fn load_table(path: &Path, sets: &[String]) -> Result<toml::Table, Failure> {
    let overrides = sets
        .iter()
        .map(|s| parse_set(s))
        .collect::<Result<Vec<_>, _>>()?;
    let mut table = dexter_sim::scene::load_table(path, &overrides)?;
    // a scene without a name takes its file stem
    let stem = path
        .file_stem()
        .and_then(|s| s.to_str())
        .unwrap_or("scene")
        .to_string();
    if let Some(toml::Value::Table(meta)) = table.get_mut("scene") {
        meta.entry("name").or_insert(toml::Value::String(stem));
    } else if !table.contains_key("scene") {
        let mut meta = toml::Table::new();
        meta.insert("name".into(), toml::Value::String(stem));
        table.insert("scene".into(), toml::Value::Table(meta));
    }
    Ok(table)
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    let result = match cli.command {
        Some(Command::Run(args)) => cmd_run(args),
        Some(Command::Sweep(args)) => cmd_sweep(args),
        Some(Command::Analyze(args)) => cmd_analyze(args),
        None => {
            let root = workspace_root();
            cmd_run(RunArgs {
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
            })
        }
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(f) => {
            eprintln!("error: {}", f.message);
            ExitCode::from(f.code)
        }
    }
}

fn app_failure(e: AppError) -> Failure {
    match e {
        AppError::Scene(m) => Failure {
            code: EXIT_SCENE,
            message: format!("bad scene: {m}"),
        },
        AppError::Run(m) => run_failure(m),
    }
}

fn cmd_analyze(args: AnalyzeArgs) -> Result<(), Failure> {
    let app = AppAnalyze {
        scene: args.scene.clone(),
        sets: args.set.clone(),
        json: args.json,
    };
    match apps::kind_of(&args.scene).map_err(app_failure)? {
        Kind::Hopper => apps::hopper::analyze(&app).map_err(app_failure),
        Kind::Planar => apps::planar::analyze(&app).map_err(app_failure),
        Kind::Line => Err(Failure {
            code: EXIT_SCENE,
            message: "analyze takes a planar or hopper scene (a [planar] or [hopper] table)".into(),
        }),
    }
}

fn cmd_run(args: RunArgs) -> Result<(), Failure> {
    let kind = apps::kind_of(&args.scene).map_err(app_failure)?;
    if kind != Kind::Line {
        if args.hil || args.duration.is_some() {
            return Err(Failure {
                code: EXIT_SCENE,
                message: "--hil and --duration apply to line scenes only".into(),
            });
        }
        let app = AppRun {
            scene: args.scene.clone(),
            sets: args.set.clone(),
            impacts: args.impacts,
            json: args.json,
            plot: args.plot.clone(),
            trace: args.trace.clone(),
        };
        return match kind {
            Kind::Hopper => apps::hopper::run(&app),
            _ => apps::planar::run(&app),
        }
        .map_err(app_failure);
    }
    let mut sets = args.set.clone();
    if let Some(n) = args.impacts {
        sets.push(format!("stop.impacts={n}"));
        sets.push(format!("stop.duration_s={:e}", (n.max(1) as f64) * 60.0));
    }
    if let Some(d) = args.duration {
        sets.push(format!("stop.duration_s={d:e}"));
        sets.push(format!("stop.impacts={}", u64::MAX >> 1));
    }
    let table = load_table(&args.scene, &sets)?;
    let scene = Scene::from_table(table)?;
    let options = RunOptions {
        record_rows: true,
        record_phase: args.plot.is_some(),
        progress: !args.json,
    };
    let out = if args.hil {
        run_hil(&scene, &options, &args)?
    } else {
        run_scene(&scene, &options, None).map_err(run_failure)?
    };
    let summary = Summary::new(&scene, &out);
    if let Some(path) = &args.trace {
        let file = std::fs::File::create(path)
            .map_err(|e| run_failure(format!("cannot write {}: {e}", path.display())))?;
        write_csv(&out.rows, std::io::BufWriter::new(file))
            .map_err(|e| run_failure(format!("cannot write {}: {e}", path.display())))?;
    }
    if let Some(dir) = &args.plot {
        write_plots(&scene, &out, dir)?;
    }
    if args.json {
        println!("{}", summary.to_json());
    } else {
        print!("{}", summary.to_text());
    }
    Ok(())
}

/// `--hil`: the firmware in QEMU (crate::hil::LockStep) closes the loop.
fn run_hil(scene: &Scene, options: &RunOptions, args: &RunArgs) -> Result<RunOutcome, Failure> {
    let params = scene.controller_params()?;
    let mut opts = hil::HilOptions::default();
    if let Some(p) = &args.firmware {
        opts.firmware_elf = p.clone();
    }
    if let Some(l) = args.link {
        opts.link = match l {
            Link::Semihosting => hil::LinkKind::Semihosting,
            Link::Uart => hil::LinkKind::Uart,
        };
    }
    opts.serial = args.port.clone().map(hil::SerialPortOptions::new);
    if let Some(b) = args.budget {
        opts.instruction_budget = (b > 0).then_some(b).into();
    }
    if let Some(r) = args.corrupt_rate {
        if !(0.0..=1.0).contains(&r) {
            return Err(Failure {
                code: EXIT_SCENE,
                message: format!("--corrupt-rate must be in [0, 1], got {r}"),
            });
        }
        opts.corrupt_rate = r;
    }
    let mut lock = hil::LockStep::start(params, opts).map_err(run_failure)?;
    let mut out = run_scene(scene, options, Some(&mut lock as &mut dyn StepController))
        .map_err(run_failure)?;
    out.hil = Some(lock.finish().map_err(run_failure)?);
    Ok(out)
}

/// (b, b') along the ballistic flights between recorded impacts (for runs without a
/// controller, whose plant is not sampled per step).
fn phase_from_rows(rows: &[ImpactRow], g: f64) -> Vec<(f64, f64)> {
    const PER_FLIGHT: usize = 24;
    let mut pts = Vec::new();
    for w in rows.windows(2).take(4000) {
        let (a, b) = (&w[0], &w[1]);
        let dt = b.time_s - a.time_s;
        for i in 0..=PER_FLIGHT {
            let t = dt * i as f64 / PER_FLIGHT as f64;
            pts.push((
                a.ball_height_m + a.ball_velocity_after_mps * t - 0.5 * g * t * t,
                a.ball_velocity_after_mps - g * t,
            ));
        }
    }
    pts
}

fn write_plots(scene: &Scene, out: &RunOutcome, dir: &Path) -> Result<(), Failure> {
    std::fs::create_dir_all(dir)
        .map_err(|e| run_failure(format!("cannot create {}: {e}", dir.display())))?;
    let stem = scene.name();
    let target = scene.control.target_apex_m.unwrap_or(f64::NAN);
    let mut written = Vec::new();
    let plot_err = |e: plot::PlotError| run_failure(format!("plot: {e}"));
    if !out.rows.is_empty() {
        written.extend(
            plot::apex_per_impact(&out.rows, target, dir, &format!("{stem}-apex"))
                .map_err(plot_err)?,
        );
        let speeds: Vec<f64> = out
            .rows
            .iter()
            .map(|r| -r.ball_velocity_before_mps)
            .collect();
        if speeds.len() >= 2 {
            written.extend(
                plot::return_map(&speeds, dir, &format!("{stem}-return-map")).map_err(plot_err)?,
            );
        }
    }
    let phase = if out.phase.is_empty() {
        phase_from_rows(&out.rows, scene.physics.gravity_mps2)
    } else {
        out.phase.clone()
    };
    if !phase.is_empty() {
        written
            .extend(plot::phase_portrait(&phase, dir, &format!("{stem}-phase")).map_err(plot_err)?);
    }
    for p in written {
        eprintln!("wrote {}", p.display());
    }
    Ok(())
}

/// An axis label for a scene key: the key with the unit its suffix names.
fn param_label(key: &str) -> String {
    let units = [
        ("_s2pm2", "s^2/m^2"),
        ("_mps2", "m/s^2"),
        ("_mps", "m/s"),
        ("_hz", "Hz"),
        ("_per_s2", "1/s^2"),
        ("_per_s", "1/s"),
        ("_per_m", "1/m"),
        ("_m", "m"),
        ("_s", "s"),
    ];
    match units.iter().find(|(suffix, _)| key.ends_with(suffix)) {
        Some((_, unit)) => format!("{key} ({unit})"),
        None => key.to_string(),
    }
}

fn cmd_sweep(args: SweepArgs) -> Result<(), Failure> {
    let kind = apps::kind_of(&args.scene).map_err(app_failure)?;
    if kind != Kind::Line {
        let app = AppSweep {
            scene: args.scene.clone(),
            sets: args.set.clone(),
            range: args.range.clone(),
            range2: args.range2.clone(),
            keep: args.keep,
            csv: args.csv.clone(),
            plot: args.plot.clone(),
        };
        return match kind {
            Kind::Hopper => apps::hopper::sweep(&app),
            _ => apps::planar::sweep(&app),
        }
        .map_err(app_failure);
    }
    let range = Range::parse(&args.range)?;
    let table = load_table(&args.scene, &args.set)?;
    // validate the base scene once so a bad file fails before the sweep starts
    let base = Scene::from_table(table.clone())?;
    let points = sweep(&table, &range, args.keep).map_err(|e| match e {
        dexter_sim::run::RunError::Scene(s) => Failure::from(s),
        other => run_failure(other),
    })?;
    let mut csv = format!("{},apex_height_m\n", range.key);
    for (v, a) in &points {
        csv += &format!("{v:.16e},{a:.16e}\n");
    }
    match &args.csv {
        Some(path) => std::fs::write(path, &csv)
            .map_err(|e| run_failure(format!("cannot write {}: {e}", path.display())))?,
        None => print!("{csv}"),
    }
    if let Some(dir) = &args.plot {
        std::fs::create_dir_all(dir)
            .map_err(|e| run_failure(format!("cannot create {}: {e}", dir.display())))?;
        let stem = format!("{}-bifurcation", base.name());
        for p in plot::bifurcation(&points, &param_label(&range.key), dir, &stem)
            .map_err(|e| run_failure(format!("plot: {e}")))?
        {
            eprintln!("wrote {}", p.display());
        }
    }
    Ok(())
}
