//! CLI front end of the planar scenes (`[planar]` table): run, sweep, analyze
//! (Zumel & Erdmann's bouncing body, `crate::model::planar`; commands and output in
//! `docs/planar.md`, "Command line").
//!
//! Loading: file text -> `toml::Table` -> `--set` overrides -> [`PlanarParams`] (unknown keys
//! and wrong types are errors naming the dotted key) -> [`PlanarParams::build`] (range errors
//! name the key). Every bad value is an [`AppError::Scene`] (exit status 2), never a panic.

use super::{AppAnalyze, AppError, AppRun, AppSweep};
use crate::model::planar::analysis::{self, AnalysisReport, CellClass};
use crate::model::planar::{
    Body, ContactLaw, ImpactRecord, PlanarError, PlanarModel, PlanarParams, PlanarRun, RunEnd,
};
use crate::plot::{self, Series, Style};
use crate::scene::{apply_set, parse_set};
use crate::sweep::Range;
use dexter_core::tilt::kappa_crit;
use serde::{Deserialize, Serialize};
use std::fmt::Write as _;
use std::path::Path;
use std::time::Instant;

/// Relative tolerance of the late mean energy around eta* that `docs/planar.md` states for
/// the triangle scene without noise (the test `triangle_stays_upright_...`).
pub const ENERGY_TOL_NOISE_FREE: f64 = 0.01;
/// The same with 10 ms timing noise.
pub const ENERGY_TOL_NOISE: f64 = 0.03;

/// A planar scene file: only a `[planar]` table.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct PlanarFile {
    planar: PlanarParams,
}

fn scene_err(m: impl std::fmt::Display) -> AppError {
    AppError::Scene(m.to_string())
}

fn planar_err(e: PlanarError) -> AppError {
    match e {
        PlanarError::Analysis(m) => AppError::Run(format!("planar analysis: {m}")),
        other => AppError::Scene(other.to_string()),
    }
}

/// The scene file as a table with the `--set` overrides applied.
fn load_table(path: &Path, sets: &[String]) -> Result<toml::Table, AppError> {
    let text = std::fs::read_to_string(path)
        .map_err(|e| scene_err(format!("cannot read {}: {e}", path.display())))?;
    let mut table: toml::Table = text
        .parse()
        .map_err(|e: toml::de::Error| scene_err(format!("not valid TOML: {}", e.message())))?;
    for s in sets {
        let (key, value) = parse_set(s).map_err(scene_err)?;
        apply_set(&mut table, &key, value).map_err(scene_err)?;
    }
    Ok(table)
}

/// Deserialize a table into [`PlanarParams`] (errors name the dotted key) and validate it
/// with [`PlanarParams::build`] (errors name the key).
fn params_of(table: &toml::Table) -> Result<(PlanarParams, PlanarModel), AppError> {
    let value = toml::Value::Table(table.clone());
    let file: PlanarFile = serde_path_to_error::deserialize(value).map_err(|e| {
        let path = e.path().to_string();
        let msg = e.into_inner().message().to_string();
        if path == "." || path.is_empty() {
            scene_err(msg)
        } else {
            scene_err(format!("`{path}`: {msg}"))
        }
    })?;
    let model = file.planar.build().map_err(planar_err)?;
    Ok((file.planar, model))
}

fn scene_name(path: &Path) -> String {
    path.file_stem()
        .and_then(|s| s.to_str())
        .unwrap_or("planar")
        .to_string()
}

fn io_err(path: &Path, e: impl std::fmt::Display) -> AppError {
    AppError::Run(format!("cannot write {}: {e}", path.display()))
}

fn plot_err(e: plot::PlotError) -> AppError {
    AppError::Run(format!("plot: {e}"))
}

// -------------------------------------------------------------------------------- run

/// Summary of one planar run (the `--json` object; snake_case keys with units).
#[derive(Clone, Debug, Serialize)]
pub struct RunSummary {
    /// Scene name (file stem).
    pub scene: String,
    /// `rigid` or `point_mass`.
    pub body: &'static str,
    /// `frictionless` or `coulomb`.
    pub contact: &'static str,
    /// rho, m (0 for a point mass).
    pub rho_m: f64,
    /// l, m (0 for a point mass).
    pub l_m: f64,
    /// G, m/s^2.
    pub gravity_mps2: f64,
    /// kappa.
    pub kappa: f64,
    /// kappa_E, s^2/m^2.
    pub kappa_e_s2pm2: f64,
    /// e.
    pub restitution: f64,
    /// mu.
    pub friction_mu: f64,
    /// sigma of the timing noise, s.
    pub timing_noise_s: f64,
    /// Noise seed.
    pub seed: u64,
    /// eq. 16's kappa_crit at the target energy (null for a point mass or no flight).
    pub kappa_crit_eq16: f64,
    /// Impacts asked for.
    pub impacts_requested: usize,
    /// Impacts simulated.
    pub impacts: usize,
    /// Why the run ended (`completed`, `tipped_over`, `no_separation`, ...).
    pub end: RunEnd,
    /// All impacts done without tipping over or losing the body.
    pub stayed_up: bool,
    /// Time of the last recorded impact, s.
    pub end_time_s: f64,
    /// eta*, J/kg.
    pub target_energy_jpkg: f64,
    /// eta at the first impact, J/kg.
    pub first_energy_jpkg: f64,
    /// Impacts in the late window (the last quarter).
    pub late_window_impacts: usize,
    /// Mean eta over the late window, J/kg.
    pub late_mean_energy_jpkg: f64,
    /// (late mean - eta*)/eta*.
    pub late_mean_energy_rel_error: f64,
    /// max |theta| at impacts over the run, rad (point mass: the incoming velocity's angle).
    pub max_abs_theta_rad: f64,
    /// max |theta| at impacts over the late window, rad.
    pub late_max_abs_theta_rad: f64,
    /// mean theta at impacts, rad.
    pub mean_theta_rad: f64,
    /// The stability-map class of this run (`analysis::classify`).
    pub class: CellClass,
    /// Gap evaluations of all contact searches.
    pub gap_evaluations: usize,
    /// Simulated time, s (= end_time_s).
    pub sim_time_s: f64,
    /// Wall-clock time of the simulation, s.
    pub wall_time_s: f64,
}

fn law_angle(model: &PlanarModel, r: &ImpactRecord) -> f64 {
    model.body.law_angle_rad(&r.before)
}

fn max_abs_theta(model: &PlanarModel, rs: &[ImpactRecord]) -> f64 {
    rs.iter()
        .fold(0.0f64, |m, r| m.max(law_angle(model, r).abs()))
}

/// eq. 16's kappa_crit at the model's target energy (NaN for a point mass / no flight).
fn kappa_crit_of(model: &PlanarModel) -> f64 {
    match (model.body, analysis::fixed_point_velocity_mps(model)) {
        (Body::Rigid { rho_m, l_m }, Ok(y)) => kappa_crit(model.gravity_mps2, rho_m, l_m, y, 1.0),
        _ => f64::NAN,
    }
}

fn summarize(
    name: &str,
    p: &PlanarParams,
    model: &PlanarModel,
    run: &PlanarRun,
    requested: usize,
    wall_s: f64,
) -> RunSummary {
    let n = run.impacts.len();
    let late = &run.impacts[n - (n / 4).max(1).min(n)..];
    let eta_star = model.feedback.target_energy_jpkg();
    let late_mean = if late.is_empty() {
        f64::NAN
    } else {
        late.iter().map(|r| r.energy_jpkg).sum::<f64>() / late.len() as f64
    };
    let end_time = run.impacts.last().map_or(0.0, |r| r.time_s);
    RunSummary {
        scene: name.to_string(),
        body: match model.body {
            Body::PointMass => "point_mass",
            Body::Rigid { .. } => "rigid",
        },
        contact: match model.contact {
            ContactLaw::Frictionless => "frictionless",
            ContactLaw::Coulomb { .. } => "coulomb",
        },
        rho_m: model.rho_m(),
        l_m: model.l_m(),
        gravity_mps2: model.gravity_mps2,
        kappa: model.tilt.kappa(),
        kappa_e_s2pm2: model.feedback.kappa_e_s2pm2(),
        restitution: model.feedback.e(),
        friction_mu: p.friction_mu,
        timing_noise_s: model.timing_noise_s,
        seed: p.seed,
        kappa_crit_eq16: kappa_crit_of(model),
        impacts_requested: requested,
        impacts: n,
        end: run.end,
        stayed_up: run.end == RunEnd::Completed,
        end_time_s: end_time,
        target_energy_jpkg: eta_star,
        first_energy_jpkg: run.impacts.first().map_or(f64::NAN, |r| r.energy_jpkg),
        late_window_impacts: late.len(),
        late_mean_energy_jpkg: late_mean,
        late_mean_energy_rel_error: (late_mean - eta_star) / eta_star,
        max_abs_theta_rad: max_abs_theta(model, &run.impacts),
        late_max_abs_theta_rad: max_abs_theta(model, late),
        mean_theta_rad: if n == 0 {
            f64::NAN
        } else {
            run.impacts.iter().map(|r| law_angle(model, r)).sum::<f64>() / n as f64
        },
        class: analysis::classify(model, run),
        gap_evaluations: run.gap_evaluations,
        sim_time_s: end_time,
        wall_time_s: wall_s,
    }
}

fn end_words(end: RunEnd) -> &'static str {
    match end {
        RunEnd::Completed => "completed",
        RunEnd::TippedOver => "tipped over (|theta| reached the tip angle)",
        RunEnd::NoSeparation => "no separation (the body no longer flies off the table)",
        RunEnd::NoContact => "no contact found",
        RunEnd::Jam => "Painleve jam in a frictional impact",
        RunEnd::NonFinite => "a state became non-finite",
    }
}

fn class_name(c: CellClass) -> &'static str {
    match c {
        CellClass::Converges => "converges",
        CellClass::Drifts => "drifts",
        CellClass::TipsOver => "tips_over",
        CellClass::Diverges => "diverges",
    }
}

fn class_words(c: CellClass) -> &'static str {
    match c {
        CellClass::Converges => "stays up and converges",
        CellClass::Drifts => "stays up, drifts",
        CellClass::TipsOver => "tips over",
        CellClass::Diverges => "diverges / lost",
    }
}

fn summary_text(s: &RunSummary) -> String {
    let mut o = String::new();
    let _ = writeln!(o, "planar scene {}", s.scene);
    match s.body {
        "rigid" => {
            let _ = writeln!(
                o,
                "  model:        rigid body, rho {} m, l {} m, G {} m/s^2, {}",
                s.rho_m, s.l_m, s.gravity_mps2, s.contact
            );
        }
        _ => {
            let _ = writeln!(
                o,
                "  model:        point mass, G {} m/s^2, {}",
                s.gravity_mps2, s.contact
            );
        }
    }
    let _ = writeln!(
        o,
        "  control:      kappa {}, kappa_E {} s^2/m^2 ({})",
        s.kappa,
        s.kappa_e_s2pm2,
        if s.kappa_crit_eq16.is_nan() {
            "point mass: the angle converges for 0 < kappa < 1, eq. 4".to_string()
        } else {
            format!("kappa_crit eq. 16: {:.4}", s.kappa_crit_eq16)
        }
    );
    let _ = writeln!(
        o,
        "  contact:      e {}, mu {}, timing noise sigma {} s (seed {})",
        s.restitution, s.friction_mu, s.timing_noise_s, s.seed
    );
    if s.stayed_up {
        let _ = writeln!(
            o,
            "  outcome:      {} of {} impacts, stayed up{}",
            s.impacts,
            s.impacts_requested,
            if s.body == "rigid" { " (upright)" } else { "" }
        );
    } else {
        let _ = writeln!(
            o,
            "  outcome:      ended after {} of {} impacts at t = {:.4} s: {}",
            s.impacts,
            s.impacts_requested,
            s.end_time_s,
            end_words(s.end)
        );
    }
    let _ = writeln!(
        o,
        "  energy:       eta* {:.5} J/kg; first impact {:.5} J/kg; late mean (last {} impacts) {:.5} J/kg ({:+.2} % of eta*)",
        s.target_energy_jpkg,
        s.first_energy_jpkg,
        s.late_window_impacts,
        s.late_mean_energy_jpkg,
        100.0 * s.late_mean_energy_rel_error
    );
    let _ = writeln!(
        o,
        "  theta:        max |theta| {:.4} rad (late {:.4} rad), mean {:+.4} rad",
        s.max_abs_theta_rad, s.late_max_abs_theta_rad, s.mean_theta_rad
    );
    let _ = writeln!(o, "  class:        {}", class_words(s.class));
    let _ = writeln!(
        o,
        "  time:         simulated {:.3} s, wall {:.3} ms ({} gap evaluations)",
        s.sim_time_s,
        1e3 * s.wall_time_s,
        s.gap_evaluations
    );
    o
}

/// The `--trace` CSV header (documented in `docs/planar.md`).
pub const TRACE_HEADER: &str = "index,time_s,x_m,y_m,theta_rad,x_dot_mps,y_dot_mps,theta_dot_radps,x_dot_after_mps,y_dot_after_mps,theta_dot_after_radps,contact_y_m,table_angle_rad,table_vx_mps,table_vy_mps,energy_jpkg,grazing,mode";

fn trace_csv(model: &PlanarModel, run: &PlanarRun) -> String {
    let mut o = String::with_capacity(run.impacts.len() * 320 + 256);
    o.push_str(TRACE_HEADER);
    o.push('\n');
    let l = model.l_m();
    for r in &run.impacts {
        let b = &r.before;
        let a = &r.after;
        let nums = [
            r.time_s,
            b.x_m,
            b.y_m,
            b.theta_rad,
            b.x_dot_mps,
            b.y_dot_mps,
            b.theta_dot_radps,
            a.x_dot_mps,
            a.y_dot_mps,
            a.theta_dot_radps,
            b.contact_point(l)[1],
            r.table.alpha_rad,
            r.table.velocity_mps[0],
            r.table.velocity_mps[1],
            r.energy_jpkg,
        ];
        let _ = write!(o, "{}", r.index);
        for v in nums {
            let _ = write!(o, ",{v:.16e}");
        }
        let mode = serde_json::to_value(r.mode)
            .ok()
            .and_then(|v| v.as_str().map(str::to_string))
            .unwrap_or_default();
        let _ = writeln!(o, ",{},{mode}", u8::from(r.grazing));
    }
    o
}

/// Points per flight in the path plot.
const PATH_SAMPLES: usize = 24;
/// Flights drawn in the path plot (more is an unreadable tangle).
const PATH_FLIGHTS: usize = 12;

fn run_plots(
    name: &str,
    model: &PlanarModel,
    run: &PlanarRun,
    dir: &Path,
) -> Result<Vec<std::path::PathBuf>, AppError> {
    std::fs::create_dir_all(dir)
        .map_err(|e| AppError::Run(format!("cannot create {}: {e}", dir.display())))?;
    let mut written = Vec::new();
    if run.impacts.is_empty() {
        return Err(AppError::Run("plot: the run has no impacts".into()));
    }
    let g = model.gravity_mps2;
    let point_mass = matches!(model.body, Body::PointMass);
    let sub = |title: &str| {
        format!(
            "{name}: {title} (kappa {}, e {}, {} impacts)",
            model.tilt.kappa(),
            model.feedback.e(),
            run.impacts.len()
        )
    };
    // fig. 4-5, upper: the orbit in the theta - theta' plane at the impacts
    if !point_mass {
        let pts: Vec<(f64, f64)> = run
            .impacts
            .iter()
            .map(|r| (r.before.theta_rad, r.before.theta_dot_radps))
            .collect();
        let first = vec![pts[0]];
        written.extend(
            plot::series(
                &sub("theta-theta' at impacts"),
                "theta just before impact (rad)",
                "theta' just before impact (rad/s)",
                &[
                    Series {
                        label: "impacts".into(),
                        points: pts,
                        style: Style::Dots,
                    },
                    Series {
                        label: "first impact".into(),
                        points: first,
                        style: Style::Dots,
                    },
                ],
                dir,
                &format!("{name}-theta"),
            )
            .map_err(plot_err)?,
        );
    }
    // fig. 4-5, lower: the orbit in the x' - y' plane at the impacts (the paper's "xy"
    // projection: "y is bounded in the neighborhood of y0, the y-velocity at first impact")
    let vel: Vec<(f64, f64)> = run
        .impacts
        .iter()
        .map(|r| (r.before.x_dot_mps, r.before.y_dot_mps))
        .collect();
    let y_star = analysis::fixed_point_velocity_mps(model).unwrap_or(f64::NAN);
    let mut vel_series = vec![
        Series {
            label: "impacts".into(),
            points: vel.clone(),
            style: Style::Dots,
        },
        Series {
            label: "first impact".into(),
            points: vec![vel[0]],
            style: Style::Dots,
        },
    ];
    if y_star.is_finite() {
        vel_series.push(Series {
            label: "fixed point (0, y*)".into(),
            points: vec![(0.0, y_star)],
            style: Style::Dots,
        });
    }
    written.extend(
        plot::series(
            &sub("x'-y' at impacts"),
            "x' just before impact (m/s)",
            "y' just before impact (m/s)",
            &vel_series,
            dir,
            &format!("{name}-velocity"),
        )
        .map_err(plot_err)?,
    );
    // the centre of mass's path in the x - y plane (flights between impacts)
    let mut path = Vec::new();
    for w in run.impacts.windows(2).take(PATH_FLIGHTS) {
        let dt = w[1].time_s - w[0].time_s;
        for i in 0..=PATH_SAMPLES {
            let s = w[0].after.flown(dt * i as f64 / PATH_SAMPLES as f64, g);
            path.push((s.x_m, s.y_m));
        }
    }
    let impacts_xy: Vec<(f64, f64)> = run
        .impacts
        .iter()
        .take(PATH_FLIGHTS + 1)
        .map(|r| (r.before.x_m, r.before.y_m))
        .collect();
    let mut path_series = vec![Series {
        label: "impacts".into(),
        points: impacts_xy,
        style: Style::Dots,
    }];
    if !path.is_empty() {
        path_series.insert(
            0,
            Series {
                label: "centre of mass in flight".into(),
                points: path,
                style: Style::Line,
            },
        );
    }
    written.extend(
        plot::series(
            &format!(
                "{name}: centre-of-mass path, first {} flights",
                PATH_FLIGHTS.min(run.impacts.len().saturating_sub(1))
            ),
            "x (m)",
            "y (m)",
            &path_series,
            dir,
            &format!("{name}-path"),
        )
        .map_err(plot_err)?,
    );
    // energy per impact with eta*
    let eta: Vec<(f64, f64)> = run
        .impacts
        .iter()
        .map(|r| (r.index as f64, r.energy_jpkg))
        .collect();
    let eta_star = model.feedback.target_energy_jpkg();
    let last = run.impacts.last().map_or(1.0, |r| r.index as f64).max(1.0);
    let n = run.impacts.len();
    let late = &run.impacts[n - (n / 4).max(1).min(n)..];
    let late_from = late.first().map_or(0.0, |r| r.index as f64);
    let late_mean = late.iter().map(|r| r.energy_jpkg).sum::<f64>() / late.len().max(1) as f64;
    written.extend(
        plot::series(
            &sub("energy per impact"),
            "impact n",
            "eta = G l cos(theta) + y'^2/2 before impact (J/kg)",
            &[
                Series {
                    label: "eta".into(),
                    points: eta,
                    style: Style::Line,
                },
                Series {
                    label: "eta* (target)".into(),
                    points: vec![(0.0, eta_star), (last, eta_star)],
                    style: Style::Line,
                },
                Series {
                    label: format!("late mean eta (last {} impacts)", late.len()),
                    points: vec![(late_from, late_mean), (last, late_mean)],
                    style: Style::Line,
                },
            ],
            dir,
            &format!("{name}-energy"),
        )
        .map_err(plot_err)?,
    );
    Ok(written)
}

/// `dexter run` on a planar scene.
pub fn run(args: &AppRun) -> Result<(), AppError> {
    let mut table = load_table(&args.scene, &args.sets)?;
    if let Some(n) = args.impacts {
        let n = i64::try_from(n).map_err(|_| {
            scene_err(format!(
                "--impacts {n}: planar.impacts is out of its allowed range"
            ))
        })?;
        apply_set(&mut table, "planar.impacts", toml::Value::Integer(n)).map_err(scene_err)?;
    }
    let (p, model) = params_of(&table)?;
    let start = p.start().map_err(planar_err)?;
    let name = scene_name(&args.scene);
    let t0 = Instant::now();
    let out = model.run(start, p.impacts, p.seed);
    let wall = t0.elapsed().as_secs_f64();
    let summary = summarize(&name, &p, &model, &out, p.impacts, wall);
    if let Some(path) = &args.trace {
        std::fs::write(path, trace_csv(&model, &out)).map_err(|e| io_err(path, e))?;
    }
    if let Some(dir) = &args.plot {
        for f in run_plots(&name, &model, &out, dir)? {
            eprintln!("wrote {}", f.display());
        }
    }
    if args.json {
        let text =
            serde_json::to_string(&summary).map_err(|e| AppError::Run(format!("json: {e}")))?;
        println!("{text}");
    } else {
        print!("{}", summary_text(&summary));
    }
    Ok(())
}

// ----------------------------------------------------------------------------- analyze

/// The label of each closed-form eigenvalue (same order as `ClosedForms::predicted`).
fn closed_form_labels(model: &PlanarModel) -> [&'static str; 4] {
    match model.body {
        Body::PointMass => [
            "eq. 3: 1 - 2 kappa",
            "energy: 1 - (1+e) kappa_E y*^2",
            "",
            "",
        ],
        Body::Rigid { .. } => [
            "x' (horizontal drift): 1",
            "energy: 1 - (1+e) kappa_E y*^2",
            "eq. 11",
            "eq. 11",
        ],
    }
}

/// For each numerical eigenvalue, the index of the closed form matched to it (greedy by
/// distance, one to one, as `analysis::analyze` does).
fn match_closed_forms(r: &AnalysisReport) -> Vec<Option<usize>> {
    let pred = &r.closed_form.predicted[..r.closed_form.count];
    let mut out = vec![None; r.eigenvalues.len()];
    for (i, p) in pred.iter().enumerate() {
        let best = r
            .eigenvalues
            .iter()
            .enumerate()
            .filter(|(k, _)| out[*k].is_none())
            .map(|(k, q)| (k, (q.re - p.0).hypot(q.im - p.1)))
            .min_by(|a, b| a.1.total_cmp(&b.1));
        if let Some((k, _)) = best {
            out[k] = Some(i);
        }
    }
    out
}

fn complex(re: f64, im: f64) -> String {
    format!(
        "{re:+.10} {} {:.10}i",
        if im < 0.0 { '-' } else { '+' },
        im.abs()
    )
}

fn regime(r: &AnalysisReport) -> String {
    let k = r.params.kappa;
    let kc = r.closed_form.kappa_crit_eq16;
    if kc.is_nan() {
        return if k > 0.0 && k < 1.0 {
            "0 < kappa < 1: the point-mass angle converges (eq. 4)".into()
        } else {
            "kappa outside (0, 1): the point-mass angle does not converge (eq. 4)".into()
        };
    }
    if k < 1.0 {
        "kappa < 1: real pair, one outside the unit circle (eq. 13)".into()
    } else if k == 1.0 {
        "kappa = 1: double eigenvalue 1".into()
    } else if k < kc {
        "1 < kappa < kappa_crit: complex pair on the unit circle (eq. 14)".into()
    } else if k == kc {
        "kappa = kappa_crit: double eigenvalue -1".into()
    } else {
        "kappa > kappa_crit: real pair, one below -1 (eq. 15)".into()
    }
}

fn analyze_text(name: &str, r: &AnalysisReport, model: &PlanarModel) -> String {
    let p = &r.params;
    let c = &r.closed_form;
    let mut o = String::new();
    let _ = writeln!(
        o,
        "planar scene {name}: the impact-to-impact map linearized at its fixed point"
    );
    let _ = writeln!(
        o,
        "  parameters:   rho {} m, l {} m, G {} m/s^2, e {}, kappa {}, kappa_E {} s^2/m^2",
        p.rho_m, p.l_m, p.gravity_mps2, p.restitution, p.kappa, p.kappa_e_s2pm2
    );
    let coords = if r.fixed_point.len() == 2 {
        "(x', y')"
    } else {
        "(rho theta, x', y', rho theta')"
    };
    let fp: Vec<String> = r.fixed_point.iter().map(|v| format!("{v:.6}")).collect();
    let _ = writeln!(
        o,
        "  fixed point:  eta* {:.6} J/kg, impact velocity y* {:.6} m/s; z* = {coords} = ({}), residual {:.1e}",
        p.target_energy_jpkg,
        p.impact_velocity_mps,
        fp.join(", "),
        r.fixed_point_residual
    );
    let _ = writeln!(
        o,
        "  Jacobian:     central differences, Richardson x2; error estimate {:.1e}",
        r.jacobian_error
    );
    let _ = writeln!(
        o,
        "  eigenvalues   {:<36} {:>13}   {:<36} which",
        "numerical (re + im i)", "|lambda|", "closed form"
    );
    let labels = closed_form_labels(model);
    for (ev, m) in r.eigenvalues.iter().zip(match_closed_forms(r)) {
        let (cf, which) = match m {
            Some(i) => {
                let (re, im) = c.predicted[i];
                (complex(re, im), labels[i])
            }
            None => ("-".to_string(), ""),
        };
        let _ = writeln!(
            o,
            "                {:<36} {:>13.10}   {:<36} {which}",
            complex(ev.re, ev.im),
            ev.modulus,
            cf
        );
    }
    let _ = writeln!(
        o,
        "  max |closed form - numerical|: {:.1e}",
        r.closed_form_max_abs_diff
    );
    let verdict = match r.verdict {
        analysis::Verdict::Unstable => "unstable (some |lambda| > 1)",
        analysis::Verdict::Marginal => {
            "marginal (all |lambda| <= 1, some = 1: neutrally stable to first order)"
        }
        analysis::Verdict::AsymptoticallyStable => "asymptotically stable (all |lambda| < 1)",
    };
    let _ = writeln!(
        o,
        "  verdict:      {verdict}; tolerance on |lambda| = 1: {:.1e}",
        r.verdict_tolerance
    );
    let _ = writeln!(o, "  regime:       {}", regime(r));
    if !c.kappa_crit_eq16.is_nan() {
        let _ = writeln!(
            o,
            "  kappa_crit:   eq. 16 {:.6}; eq. 26 as printed (e = {}) {:.6}",
            c.kappa_crit_eq16, p.restitution, c.kappa_crit_eq26
        );
    }
    let _ = writeln!(
        o,
        "  energy:       eigenvalue 1 - (1+e) kappa_E y*^2 = {:.6}; kappa_Emax {:.6} s^2/m^2 re-derived, {:.6} as printed",
        c.energy_eigenvalue, c.kappa_e_max, c.kappa_e_max_as_printed
    );
    o
}

/// The `analyze --json` object: the serialized [`AnalysisReport`] with the eigenvalues as
/// `[re, im]` pairs (`eigenvalue_moduli` beside them) and the closed forms' eigenvalues
/// likewise.
fn analyze_json(name: &str, r: &AnalysisReport) -> Result<String, AppError> {
    let json_err = |e: serde_json::Error| AppError::Run(format!("json: {e}"));
    let mut v = serde_json::to_value(r).map_err(json_err)?;
    let obj = v
        .as_object_mut()
        .ok_or_else(|| AppError::Run("json: report is not an object".into()))?;
    obj.insert(
        "eigenvalues".into(),
        serde_json::json!(r
            .eigenvalues
            .iter()
            .map(|e| [e.re, e.im])
            .collect::<Vec<_>>()),
    );
    obj.insert(
        "eigenvalue_moduli".into(),
        serde_json::json!(r.eigenvalues.iter().map(|e| e.modulus).collect::<Vec<_>>()),
    );
    if let Some(cf) = obj.get_mut("closed_form").and_then(|c| c.as_object_mut()) {
        let pred = &r.closed_form.predicted[..r.closed_form.count];
        cf.insert(
            "predicted".into(),
            serde_json::json!(pred.iter().map(|p| [p.0, p.1]).collect::<Vec<_>>()),
        );
    }
    obj.insert("scene".into(), serde_json::json!(name));
    serde_json::to_string(&v).map_err(json_err)
}

/// `dexter analyze` on a planar scene.
pub fn analyze(args: &AppAnalyze) -> Result<(), AppError> {
    let table = load_table(&args.scene, &args.sets)?;
    let (_, model) = params_of(&table)?;
    let report = analysis::analyze(&model).map_err(planar_err)?;
    let name = scene_name(&args.scene);
    if args.json {
        println!("{}", analyze_json(&name, &report)?);
    } else {
        print!("{}", analyze_text(&name, &report, &model));
    }
    Ok(())
}

// ------------------------------------------------------------------------------- sweep

/// One cell of a planar sweep.
#[derive(Clone, Debug)]
struct SweepCell {
    x: f64,
    y: Option<f64>,
    class: CellClass,
    impacts: usize,
    end: RunEnd,
    max_abs_theta_rad: f64,
    late_mean_energy_jpkg: f64,
}

fn set_number(table: &mut toml::Table, key: &str, v: f64) -> Result<(), AppError> {
    // integer keys (impacts, seed) keep an integer value
    let integer = key == "planar.impacts" || key == "planar.seed";
    let value = if integer && v.fract() == 0.0 && v.abs() < 9.0e15 {
        toml::Value::Integer(v as i64)
    } else {
        toml::Value::Float(v)
    };
    apply_set(table, key, value).map_err(scene_err)
}

fn check_key(key: &str) -> Result<(), AppError> {
    // the key must exist in the [planar] table (checked again by deserialization)
    let probe = serde_json::to_value(PlanarParams::default()).ok();
    let known = key
        .strip_prefix("planar.")
        .is_some_and(|k| probe.as_ref().is_some_and(|p| p.get(k).is_some()));
    if known {
        Ok(())
    } else {
        Err(scene_err(format!(
            "`{key}`: unknown sweep key (use a [planar] key such as planar.kappa or planar.initial_theta_rad)"
        )))
    }
}

fn classify_cell(table: &toml::Table) -> Result<(CellClass, PlanarModel, PlanarRun), AppError> {
    let (p, model) = params_of(table)?;
    let start = p.start().map_err(planar_err)?;
    let run = model.run(start, p.impacts, p.seed);
    Ok((analysis::classify(&model, &run), model, run))
}

fn class_letter(c: CellClass) -> char {
    match c {
        CellClass::Converges => 'C',
        CellClass::Drifts => 'D',
        CellClass::TipsOver => 'T',
        CellClass::Diverges => 'X',
    }
}

fn short_key(key: &str) -> &str {
    key.strip_prefix("planar.").unwrap_or(key)
}

fn axis_label(key: &str) -> String {
    let k = short_key(key);
    let unit = [
        ("_s2pm2", "s^2/m^2"),
        ("_mps2", "m/s^2"),
        ("_radps", "rad/s"),
        ("_rad", "rad"),
        ("_mps", "m/s"),
        ("_m", "m"),
        ("_s", "s"),
    ]
    .iter()
    .find(|(s, _)| k.ends_with(s))
    .map(|(_, u)| *u);
    match unit {
        Some(u) => format!("{k} ({u})"),
        None => k.to_string(),
    }
}

const CLASSES: [CellClass; 4] = [
    CellClass::Converges,
    CellClass::Drifts,
    CellClass::TipsOver,
    CellClass::Diverges,
];

/// `dexter sweep` on a planar scene.
pub fn sweep(args: &AppSweep) -> Result<(), AppError> {
    let base = load_table(&args.scene, &args.sets)?;
    // validate the base scene once so a bad file fails before the sweep starts
    let (base_params, base_model) = params_of(&base)?;
    let r1 = Range::parse(&args.range).map_err(scene_err)?;
    check_key(&r1.key)?;
    let r2 = match &args.range2 {
        Some(s) => {
            let r = Range::parse(s).map_err(scene_err)?;
            check_key(&r.key)?;
            if r.key == r1.key {
                return Err(scene_err(format!(
                    "`{}`: --range2 sweeps the same key as --range",
                    r.key
                )));
            }
            Some(r)
        }
        None => None,
    };
    let xs = r1.values();
    let ys: Vec<Option<f64>> = match &r2 {
        Some(r) => r.values().into_iter().map(Some).collect(),
        None => vec![None],
    };
    let mut cells = Vec::with_capacity(xs.len() * ys.len());
    for &y in &ys {
        for &x in &xs {
            let mut t = base.clone();
            set_number(&mut t, &r1.key, x)?;
            if let (Some(r), Some(y)) = (&r2, y) {
                set_number(&mut t, &r.key, y)?;
            }
            let (class, model, run) = classify_cell(&t)?;
            let n = run.impacts.len();
            let late = &run.impacts[n - (n / 4).max(1).min(n)..];
            cells.push(SweepCell {
                x,
                y,
                class,
                impacts: n,
                end: run.end,
                max_abs_theta_rad: max_abs_theta(&model, &run.impacts),
                late_mean_energy_jpkg: if late.is_empty() {
                    f64::NAN
                } else {
                    late.iter().map(|r| r.energy_jpkg).sum::<f64>() / late.len() as f64
                },
            });
        }
    }
    // CSV
    let mut csv = String::new();
    csv.push_str(&r1.key);
    if let Some(r) = &r2 {
        csv.push(',');
        csv.push_str(&r.key);
    }
    csv.push_str(",class,impacts,end,max_abs_theta_rad,late_mean_energy_jpkg\n");
    for c in &cells {
        let _ = write!(csv, "{:.16e}", c.x);
        if let Some(y) = c.y {
            let _ = write!(csv, ",{y:.16e}");
        }
        let end = serde_json::to_value(c.end)
            .ok()
            .and_then(|v| v.as_str().map(str::to_string))
            .unwrap_or_default();
        let _ = writeln!(
            csv,
            ",{},{},{end},{:.16e},{:.16e}",
            class_name(c.class),
            c.impacts,
            c.max_abs_theta_rad,
            c.late_mean_energy_jpkg
        );
    }
    // letter grid: rows = range2 values, columns = range values
    let mut grid = format!(
        "planar sweep of {}: {} (C converges, D drifts, T tips over, X diverges)\n",
        scene_name(&args.scene),
        match &r2 {
            Some(r) => format!("rows {}, columns {}", r.key, r1.key),
            None => format!("columns {}", r1.key),
        }
    );
    let _ = write!(grid, "{:>12} |", "");
    for x in &xs {
        let _ = write!(grid, " {x:>7.4}");
    }
    grid.push('\n');
    for (j, y) in ys.iter().enumerate() {
        match y {
            Some(y) => {
                let _ = write!(grid, "{y:>12.4} |");
            }
            None => {
                let _ = write!(grid, "{:>12} |", "");
            }
        }
        for c in &cells[j * xs.len()..(j + 1) * xs.len()] {
            let _ = write!(grid, " {:>7}", class_letter(c.class));
        }
        grid.push('\n');
    }
    match &args.csv {
        Some(path) => {
            std::fs::write(path, &csv).map_err(|e| io_err(path, e))?;
            print!("{grid}");
        }
        None => print!("{csv}"),
    }
    if let Some(dir) = &args.plot {
        std::fs::create_dir_all(dir)
            .map_err(|e| AppError::Run(format!("cannot create {}: {e}", dir.display())))?;
        let y_of = |c: &SweepCell| c.y.unwrap_or(c.max_abs_theta_rad);
        let mut series: Vec<Series> = CLASSES
            .iter()
            .map(|&k| Series {
                label: class_words(k).into(),
                points: cells
                    .iter()
                    .filter(|c| c.class == k)
                    .map(|c| (c.x, y_of(c)))
                    .collect(),
                style: Style::Dots,
            })
            .filter(|s| !s.points.is_empty())
            .collect();
        // kappa = 1 and kappa_crit (eq. 16) as lines across the other axis
        let kc = kappa_crit_of(&base_model);
        let finite_ys: Vec<f64> = cells.iter().map(y_of).filter(|v| v.is_finite()).collect();
        let (ylo, yhi) = finite_ys
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &v| {
                (a.min(v), b.max(v))
            });
        let (xlo, xhi) = (
            xs.iter().copied().fold(f64::INFINITY, f64::min),
            xs.iter().copied().fold(f64::NEG_INFINITY, f64::max),
        );
        let marks = [
            (1.0, "kappa = 1".to_string()),
            (kc, format!("kappa_crit = {kc:.4} (eq. 16)")),
        ];
        for (k, label) in marks {
            if !k.is_finite() {
                continue;
            }
            if r1.key == "planar.kappa" && ylo.is_finite() {
                series.push(Series {
                    label,
                    points: vec![(k, ylo), (k, yhi)],
                    style: Style::Line,
                });
            } else if r2.as_ref().is_some_and(|r| r.key == "planar.kappa") {
                series.push(Series {
                    label,
                    points: vec![(xlo, k), (xhi, k)],
                    style: Style::Line,
                });
            }
        }
        let y_label = match &r2 {
            Some(r) => axis_label(&r.key),
            None => "max |theta| at impacts (rad)".to_string(),
        };
        let title = format!(
            "{}: stability map, {} impacts per cell",
            scene_name(&args.scene),
            base_params.impacts
        );
        let stem = format!("{}-stability", scene_name(&args.scene));
        for f in plot::series(&title, &axis_label(&r1.key), &y_label, &series, dir, &stem)
            .map_err(plot_err)?
        {
            eprintln!("wrote {}", f.display());
        }
    }
    Ok(())
}
