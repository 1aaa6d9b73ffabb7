//! The planar run on the real table: the plant of
//! [`crate::model::planar::real_table`] closed through the tilt controller (the core linked
//! in, or the firmware with `--hil`), streamed impact by impact into the same rows and run
//! statistics as the ideal table, plus the real table's own figures
//! ([`super::summary::RealFigures`]).

use super::film::FilmKeeper;
use super::summary::{summarize, HilFields, RealFigures};
use super::trace::PlanarRow;
use super::{PlanarConfig, PlanarOutcome};
use crate::controller::{Paced, SafeSteps, Sil, StepController};
use crate::model::planar::impact::FrictionMode;
use crate::model::planar::real_table::{stream_real_table, RealTable, TableRunConfig, TableSink};
use crate::model::planar::stats::RunStats;
use crate::model::planar::table_run::{PlanSteps, StepSample, TableImpact};
use crate::model::planar::{ContactLaw, ImpactRecord, Streamed, TableCommand};
use crate::progress::Progress;
use crate::system::{Failure, Setup};
use dexter_core::tilt_control::TiltController;
use std::cell::Cell;
use std::time::Instant;

/// Where the streamed run's impacts and steps go: the run statistics, the rows (trace and
/// plots), the filmstrip, the impacts so far (for the progress bar).
struct Streams<'a> {
    stats: RunStats,
    rows: &'a mut dyn FnMut(&PlanarRow),
    film: Option<FilmKeeper>,
    l_m: f64,
    mode: FrictionMode,
    impacts: &'a Cell<u64>,
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
        self.impacts.set(r.index as u64 + 1);
    }

    fn step(&mut self, s: &StepSample) {
        if let Some(f) = self.film.as_mut() {
            f.step(s);
        }
    }
}

/// An f32 parameter as the scene's decimal value (the f32's shortest form), not its widened
/// binary.
fn decimal(v: f32) -> f64 {
    v.to_string().parse().unwrap_or(f64::NAN)
}

/// The scene's real-table figures before the run's counts are in.
fn figures(table: &RealTable) -> RealFigures {
    let c = &table.controller;
    RealFigures {
        control_rate_hz: (1.0 / f64::from(c.dt_s) * 1e3).round() / 1e3,
        kappa_rate_s: decimal(c.kappa_rate_s),
        kappa_x_pm: decimal(c.kappa_x_pm),
        kappa_xdot_spm: decimal(c.kappa_xdot_spm),
        x_range_m: table.x_range_m,
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
    // the bar moves with simulated time too: a body that rests makes no impacts
    let limits = [
        (p.impacts as f64, "impacts"),
        (table.max_duration_s, "s simulated"),
    ];
    let impacts = Cell::new(0);
    let bar = Progress::new(limits, setup.progress);
    let dt_s = f64::from(table.controller.dt_s);
    let mut paced = Paced::new(inner, bar, &impacts, dt_s);
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
        impacts: &impacts,
    };
    let run = stream_real_table(&run_cfg, table, &mut paced, &mut streams)
        .map_err(|e| Failure::run(e.to_string()))?;
    paced.finish();
    let t = &run.summary;
    let done = Streamed {
        end: t.end,
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
