//! The planar run on the real table: the plant of
//! [`crate::model::planar::real_table`] closed through the tilt controller (the core linked
//! in, or the firmware with `--hil`), streamed impact by impact into the same rows and run
//! statistics as the ideal table, plus the real table's own figures ([`RealFigures`]).

use super::film::FilmKeeper;
use super::summary::summarize;
use super::trace::PlanarRow;
use super::{PlanarConfig, PlanarOutcome};
use crate::controller::{HilReport, SafeSteps, Sil, StepController};
use crate::model::planar::impact::FrictionMode;
use crate::model::planar::real_table::{stream_real_table, RealTable, TableRunConfig, TableSink};
use crate::model::planar::stats::RunStats;
use crate::model::planar::table_run::{PlanSteps, StepSample, TableImpact};
use crate::model::planar::{ContactLaw, ImpactRecord, Streamed, TableCommand};
use crate::progress::Progress;
use crate::verbs::{Failure, Setup};
use dexter_core::tilt_control::TiltController;
use serde::Serialize;
use std::fmt::Write as _;
use std::time::Instant;

/// The HIL figures of a run (every key null in SIL, where nothing ran on a target).
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
pub struct HilFields {
    /// Fewest instructions of one control step on the target.
    pub step_instructions_min: Option<u32>,
    /// Mean instructions per control step on the target.
    pub step_instructions_mean: Option<f64>,
    /// Most instructions of one control step on the target.
    pub step_instructions_max: Option<u32>,
    /// Steps whose firmware command differed from the SIL core's, bit for bit.
    pub sil_mismatches: Option<u64>,
    /// Frames rejected on the link, both directions.
    pub link_errors: Option<u64>,
    /// Steps over the instruction budget.
    pub over_budget_steps: Option<u64>,
    /// Steps answered in the safe state for a link timeout.
    pub link_timeouts: Option<u64>,
    /// Control steps per wall-clock second over the link.
    pub steps_per_wall_second: Option<f64>,
}

impl From<HilReport> for HilFields {
    fn from(h: HilReport) -> Self {
        Self {
            step_instructions_min: Some(h.step_instructions_min),
            step_instructions_mean: Some(h.step_instructions_mean),
            step_instructions_max: Some(h.step_instructions_max),
            sil_mismatches: Some(h.sil_mismatches),
            link_errors: Some(h.link_errors),
            over_budget_steps: Some(h.over_budget_steps),
            link_timeouts: Some(h.link_timeouts),
            steps_per_wall_second: Some(h.steps_per_wall_second),
        }
    }
}

/// The real table's figures in the planar summary (JSON keys flattened into it).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct RealFigures {
    /// The controller's rate, Hz.
    pub control_rate_hz: f64,
    /// kappa_w of the tilt-rate term, s.
    pub kappa_rate_s: f64,
    /// Newton steps per period for the contact time.
    pub contact_iterations: u8,
    /// The camera's noise on x and y (null: no camera, the true pose), m.
    pub camera_noise_m: Option<f64>,
    /// The camera's angle noise (null: no camera), rad.
    pub camera_noise_rad: Option<f64>,
    /// The drives obey their limits.
    pub drives_limited: bool,
    /// Impacts the controller had predicted (after it could have seen the previous one).
    pub predicted_impacts: usize,
    /// RMS of (actual - predicted) impact time, s (null without predictions).
    pub impact_time_error_rms_s: Option<f64>,
    /// Largest |actual - predicted| impact time, s.
    pub impact_time_error_max_s: Option<f64>,
    /// Largest |x| of the centre of mass at an impact, m (the body wanders: the law does
    /// not hold x).
    pub max_abs_x_m: f64,
    /// Control steps taken.
    pub control_steps: u64,
    /// Steps by the controller's plan status.
    pub plan_steps: PlanSteps,
    /// Safe-state steps (`safe_steps`) and by fault (`faults`).
    #[serde(flatten)]
    pub safe: SafeSteps,
    /// HIL figures (null in SIL).
    #[serde(flatten)]
    pub hil: HilFields,
}

impl RealFigures {
    /// The summary's lines for the real table.
    pub fn text(&self) -> String {
        let mut o = String::new();
        let camera = match (self.camera_noise_m, self.camera_noise_rad) {
            (Some(m), Some(r)) => format!("camera noise {m} m, {r} rad"),
            _ => "true pose (no camera)".to_string(),
        };
        let _ = writeln!(
            o,
            "  real table:   tilt controller at {} Hz, kappa_w {} s, {} Newton steps; {}; drives {}",
            self.control_rate_hz,
            self.kappa_rate_s,
            self.contact_iterations,
            camera,
            if self.drives_limited { "limited" } else { "ideal" }
        );
        let ms = |v: Option<f64>| v.map_or("-".to_string(), |s| format!("{:.3}", 1e3 * s));
        let _ = writeln!(
            o,
            "  prediction:   {} impacts predicted, impact-time error rms {} ms, max {} ms; max |x| {:.3} m",
            self.predicted_impacts,
            ms(self.impact_time_error_rms_s),
            ms(self.impact_time_error_max_s),
            self.max_abs_x_m
        );
        let _ = writeln!(o, "  steps:        {} control steps", self.control_steps);
        o += &self.safe.text();
        if let (Some(lo), Some(mean), Some(hi)) = (
            self.hil.step_instructions_min,
            self.hil.step_instructions_mean,
            self.hil.step_instructions_max,
        ) {
            let _ = writeln!(
                o,
                "  HIL:          {} mismatches, {} link errors, instructions per step min/mean/max {lo}/{mean:.1}/{hi}, steps/s {:.0}",
                self.hil.sil_mismatches.unwrap_or(0),
                self.hil.link_errors.unwrap_or(0),
                self.hil.steps_per_wall_second.unwrap_or(0.0)
            );
        }
        o
    }
}

/// Impacts between progress updates.
const PROGRESS_EVERY: usize = 64;

/// Where the streamed run's impacts and steps go: the run statistics, the rows (trace and
/// plots), the filmstrip, the progress bar.
struct Streams<'a> {
    stats: RunStats,
    rows: &'a mut dyn FnMut(&PlanarRow),
    film: Option<FilmKeeper>,
    l_m: f64,
    mode: FrictionMode,
    bar: Progress,
}

impl TableSink for Streams<'_> {
    fn impact(&mut self, r: &TableImpact) {
        let record = ImpactRecord {
            index: r.index,
            time_s: r.time_s,
            before: r.before,
            after: r.after,
            table: TableCommand {
                alpha_rad: r.table_angle_rad,
                velocity_mps: r.table_velocity_mps,
            },
            energy_jpkg: r.energy_jpkg,
            grazing: r.grazing,
            mode: self.mode,
        };
        self.stats.push(&record);
        (self.rows)(&PlanarRow {
            record,
            l_m: self.l_m,
        });
        if let Some(f) = self.film.as_mut() {
            f.impact(r);
        }
        if r.index.is_multiple_of(PROGRESS_EVERY) {
            self.bar.update([r.index as f64]);
        }
    }

    fn step(&mut self, s: &StepSample) {
        if let Some(f) = self.film.as_mut() {
            f.step(s);
        }
    }
}

/// The scene's real-table figures before the run's counts are in.
fn figures(table: &RealTable) -> RealFigures {
    let c = &table.controller;
    RealFigures {
        control_rate_hz: (1.0 / f64::from(c.dt_s) * 1e3).round() / 1e3,
        // the scene's decimal value (the f32's shortest form), not its widened binary
        kappa_rate_s: c.kappa_rate_s.to_string().parse().unwrap_or(f64::NAN),
        contact_iterations: c.contact_iterations,
        camera_noise_m: table.camera.map(|k| k.noise_m),
        camera_noise_rad: table.camera.map(|k| k.noise_rad),
        drives_limited: table.tilt.is_some(),
        predicted_impacts: 0,
        impact_time_error_rms_s: None,
        impact_time_error_max_s: None,
        max_abs_x_m: 0.0,
        control_steps: 0,
        plan_steps: PlanSteps::default(),
        safe: SafeSteps::default(),
        hil: HilFields::default(),
    }
}

/// Run `cfg` on its real `table`, the controller `ctrl` (`--hil`) or the core linked in.
pub(super) fn run_real(
    cfg: &PlanarConfig,
    table: &RealTable,
    ctrl: Option<&mut dyn StepController<TiltController>>,
    setup: &Setup,
    rows: &mut dyn FnMut(&PlanarRow),
) -> Result<PlanarOutcome, Failure> {
    let p = &cfg.params;
    let t0 = Instant::now();
    let mut sil;
    let inner: &mut dyn StepController<TiltController> = match ctrl {
        Some(c) => c,
        None => {
            sil = Sil::<TiltController>::new(table.controller)
                .map_err(|e| Failure::run(e.to_string()))?;
            &mut sil
        }
    };
    let run_cfg = TableRunConfig {
        model: cfg.model,
        start: cfg.start,
        impacts: p.impacts,
        record: Vec::new(),
    };
    let mut streams = Streams {
        stats: RunStats::new(&cfg.model, p.impacts),
        rows,
        film: setup.plot.then(FilmKeeper::default),
        l_m: cfg.model.l_m(),
        mode: match cfg.model.contact {
            ContactLaw::Frictionless => FrictionMode::Frictionless,
            ContactLaw::Coulomb { .. } => FrictionMode::Sliding,
        },
        bar: Progress::new([(p.impacts as f64, "impacts")], setup.progress),
    };
    let run = stream_real_table(&run_cfg, table, inner, &mut streams)
        .map_err(|e| Failure::run(e.to_string()))?;
    streams.bar.finish();
    let t = &run.summary;
    let done = Streamed {
        end: t.end.into(),
        impacts: t.impacts,
        gap_evaluations: 0,
    };
    let mut summary = summarize(&cfg.name, p, &cfg.model, &streams.stats, &done, 0.0);
    summary.wall_time_s = t0.elapsed().as_secs_f64();
    summary.table = "real";
    summary.real = Some(RealFigures {
        predicted_impacts: t.predicted_impacts,
        impact_time_error_rms_s: t.impact_time_error_rms_s,
        impact_time_error_max_s: t.impact_time_error_max_s,
        max_abs_x_m: t.max_abs_x_m,
        control_steps: t.control_steps,
        plan_steps: t.plan_steps,
        safe: t.safe.clone(),
        ..figures(table)
    });
    Ok(PlanarOutcome {
        summary,
        film: streams.film,
    })
}
