//! Zumel & Erdmann's planar bouncing body on the kappa-tilt table (`[planar]` scenes):
//! `run`, `sweep` (the stability map) and `analyze` (the linearized impact map); physics in
//! [`crate::model::planar`], commands and output in `docs/planar.md`, "Command line".
//!
//! Loading: `[planar]` table (`--set` applied) -> [`PlanarParams`] (unknown keys and wrong
//! types name the dotted key) -> [`PlanarParams::build`] and [`PlanarParams::start`] (range
//! errors name the key). A run streams its impacts (to the trace and the plots) and keeps
//! its summary and stability class in constant memory
//! ([`crate::model::planar::stats::RunStats`]); `planar.impacts` is at most
//! [`crate::model::planar::MAX_IMPACTS`] (a bound on its time).

pub mod analyze;
pub mod closed_loop;
pub mod film;
pub mod plots;
pub mod real;
pub mod scene;
pub mod summary;
pub mod sweep;
pub mod trace;

use self::film::FilmKeeper;
use self::real::RealTableScene;
use self::summary::{summarize, summary_text, RunSummary};
use self::trace::PlanarRow;
use crate::controller::{HilReport, SafeSteps, StepController};
use crate::model::planar::real_table::RealTable;
use crate::model::planar::stats::RunStats;
use crate::model::planar::{
    PlanarError, PlanarModel, PlanarParams, PlanarState, RunEnd, MAX_IMPACTS,
};
use crate::output::{json_text, JsonStyle};
use crate::progress::Progress;
use crate::scene::{deserialize, SceneError, SceneFile};
use crate::system::{Analyzes, Failure, Outcome, Report, RunLength, Setup, System};
use dexter_core::tilt_control::{TiltController, TiltParams};
use serde::Deserialize;
use std::time::Instant;

/// Relative tolerance of the late mean energy around eta* that `docs/planar.md` states for
/// the triangle scene without noise (the test `triangle_stays_upright_...`).
pub const ENERGY_TOL_NOISE_FREE: f64 = 0.01;
/// The same with 10 ms timing noise.
pub const ENERGY_TOL_NOISE: f64 = 0.03;

/// A planar scene file: a `[planar]` table, and a `[real_table]` for the real table
/// (without it, the paper's ideal table).
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct PlanarFile {
    planar: PlanarParams,
    real_table: Option<RealTableScene>,
}

/// The planar body system.
#[derive(Clone, Copy, Debug, Default)]
pub struct PlanarSystem;

/// A parsed, validated planar scene.
#[derive(Clone, Debug, PartialEq)]
pub struct PlanarConfig {
    /// The scene's name (the file stem).
    pub name: String,
    /// The `[planar]` table.
    pub params: PlanarParams,
    /// The validated model.
    pub model: PlanarModel,
    /// The initial state.
    pub start: PlanarState,
    /// The real table (`[real_table]`), closed through the tilt controller; `None`: the
    /// paper's ideal table.
    pub real: Option<RealTable>,
}

/// A planar run's result.
#[derive(Clone, Debug)]
pub struct PlanarOutcome {
    /// The summary (`--json`).
    pub summary: RunSummary,
    /// What the real table's filmstrip keeps (with `--plot`).
    pub film: Option<FilmKeeper>,
}

impl Outcome for PlanarOutcome {
    fn text(&self) -> String {
        summary_text(&self.summary)
    }
    fn json(&self) -> Result<String, String> {
        json_text(&self.summary, JsonStyle::Compact)
    }
    fn attach_hil(&mut self, report: HilReport) {
        if let Some(r) = self.summary.real.as_mut() {
            r.hil = report.into();
        }
    }
    fn safe_steps(&self) -> Option<&SafeSteps> {
        self.summary.real.as_ref().map(|r| &r.safe)
    }
    /// A contact search at its cap, a non-finite state, or the real table's time limit, is
    /// not the body's physics.
    fn shortfall(&self) -> Option<String> {
        let s = &self.summary;
        let cut = matches!(
            s.end,
            RunEnd::SearchCap | RunEnd::NonFinite | RunEnd::TimeLimit
        );
        cut.then(|| {
            format!(
                "after {} of {} impacts: {}",
                s.impacts,
                s.impacts_requested,
                summary::end_words(s.end)
            )
        })
    }
}

/// A model error as a failure: analysis failures are run failures, the rest bad scenes.
fn planar_failure(e: PlanarError) -> Failure {
    match e {
        PlanarError::Analysis(m) => Failure::run(format!("planar analysis: {m}")),
        other => Failure::scene(other),
    }
}

/// Deserialize and validate a `[planar]` scene table (and its `[real_table]`).
fn config_of(name: &str, table: toml::Table) -> Result<PlanarConfig, SceneError> {
    let file = deserialize::<PlanarFile>(table)?;
    let params = file.planar;
    let model = params.build().map_err(SceneError::whole)?;
    let start = params.start().map_err(SceneError::whole)?;
    let real = match &file.real_table {
        Some(r) => Some(r.table(&params, &model)?),
        None => None,
    };
    Ok(PlanarConfig {
        name: name.to_string(),
        params,
        model,
        start,
        real,
    })
}

impl System for PlanarSystem {
    const NAME: &'static str = "planar";
    const LENGTH: RunLength = RunLength::Events {
        key: "planar.impacts",
        max: MAX_IMPACTS as u64,
    };
    type Config = PlanarConfig;
    type Controller = TiltController;
    type Row = PlanarRow;
    type Outcome = PlanarOutcome;
    type Plots = plots::PlanarPlots;

    fn claims(table: &toml::Table) -> bool {
        table.contains_key("planar")
    }

    fn parse(file: &SceneFile, table: toml::Table) -> Result<PlanarConfig, SceneError> {
        config_of(&file.stem, table)
    }

    /// The real table's controller; an ideal-table scene has none on a target.
    fn controller_params(cfg: &PlanarConfig) -> Result<Option<TiltParams>, SceneError> {
        match &cfg.real {
            Some(t) => Ok(Some(t.controller)),
            None => Err(SceneError::new(
                "real_table",
                "--hil needs a [real_table] (the ideal table has no controller to run on a target)",
            )),
        }
    }

    fn run(
        cfg: &PlanarConfig,
        ctrl: Option<&mut dyn StepController<TiltController>>,
        setup: &Setup,
        rows: &mut dyn FnMut(&PlanarRow),
    ) -> Result<PlanarOutcome, Failure> {
        if let Some(table) = &cfg.real {
            return closed_loop::run_real(cfg, table, ctrl, setup, rows);
        }
        let p = &cfg.params;
        let t0 = Instant::now();
        let l_m = cfg.model.l_m();
        let mut stats = RunStats::new(&cfg.model, p.impacts);
        let mut bar = Progress::new([(p.impacts as f64, "impacts")], setup.progress);
        let done = cfg
            .model
            .run_streaming(cfg.start, p.impacts, p.seed, &mut |r| {
                stats.push(r);
                rows(&PlanarRow { record: *r, l_m });
                if r.index % 4096 == 0 {
                    bar.update([r.index as f64]);
                }
            });
        bar.finish();
        let wall_s = t0.elapsed().as_secs_f64();
        Ok(PlanarOutcome {
            summary: summarize(&cfg.name, p, &cfg.model, &stats, &done, wall_s),
            film: None,
        })
    }
}

impl Analyzes for PlanarSystem {
    fn analyze<'a>(
        file: &'a SceneFile,
        cfg: &'a PlanarConfig,
    ) -> Result<Box<dyn Report + 'a>, Failure> {
        Ok(Box::new(analyze::analyze(file, cfg)?))
    }
}
