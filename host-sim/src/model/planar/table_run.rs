//! What a run of the planar body on a table produced, the same for the paper's ideal table
//! and for the real one ([`super::real_table`]), so the two compare key for key.
//!
//! The figures a balancing run is judged by: `impacts`, `tipped_over`, `late_theta_max_rad`,
//! `late_energy_error` (relative to eta*), the impact-time prediction error and the safe
//! steps by fault. The **late window** is the last quarter of the impacts (as
//! [`super::stats::classify`] uses).

use super::{PlanarModel, PlanarRun, PlanarState, RunEnd};
use crate::controller::SafeSteps;
use serde::Serialize;

/// Which table a run used.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum TableKind {
    /// The paper's table: perfect sensing and control (sec. 2), optional timing noise (sec. 2.3).
    Ideal,
    /// Tilt and stroke drives with limits, a camera, the core's [`TiltController`] in the loop.
    ///
    /// [`TiltController`]: dexter_core::tilt_control::TiltController
    Real,
}

/// One impact.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct TableImpact {
    /// Impact n (0 = the first).
    pub index: usize,
    /// Time since the start, s.
    pub time_s: f64,
    /// State just before.
    pub before: PlanarState,
    /// State just after.
    pub after: PlanarState,
    /// Table angle alpha, rad.
    pub table_angle_rad: f64,
    /// Velocity of the table surface at the contact point, m/s.
    pub table_velocity_mps: [f64; 2],
    /// The same just after the impact, m/s: on the real table the pivot follows the body's
    /// new x' (sliding the line along itself), so only the tangential part changes.
    pub table_velocity_after_mps: [f64; 2],
    /// Tilt rate alpha' at the impact, rad/s (0 for the ideal table).
    pub table_rate_radps: f64,
    /// Height of the contact point, m.
    pub contact_height_m: f64,
    /// eta = G l cos theta + y'^2/2 before the impact, J/kg (eq. 25).
    pub energy_jpkg: f64,
    /// The controller's last prediction of this impact's time, s (real table only).
    pub predicted_time_s: Option<f64>,
    /// The contact was grazing.
    pub grazing: bool,
}

/// Control steps by the plan status the controller reported.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize)]
pub struct PlanSteps {
    /// No plan (hold, safe, right after an impact).
    pub idle: u64,
    /// Planned within limits.
    pub planned: u64,
    /// Committed within limits.
    pub committed: u64,
    /// The plan exceeded an axis's limits (or the tracker saturated).
    pub limited: u64,
    /// No contact ahead.
    pub unreachable: u64,
    /// The predicted contact was not provably the first.
    pub ambiguous: u64,
}

/// The run's figures (JSON keys are the field names).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct TableSummary {
    /// Ideal or real table.
    pub table: TableKind,
    /// Impacts that happened.
    pub impacts: usize,
    /// Why the run ended.
    pub end: RunEnd,
    /// True if the run ended by tipping over.
    pub tipped_over: bool,
    /// True if all requested impacts happened.
    pub stayed_up: bool,
    /// eta*, J/kg.
    pub target_energy_jpkg: f64,
    /// Impacts in the late window (the last quarter, at least one).
    pub late_window_impacts: usize,
    /// Mean eta over the late window, J/kg.
    pub late_mean_energy_jpkg: f64,
    /// (late mean eta - eta*) / eta*, dimensionless.
    pub late_energy_error: f64,
    /// Largest |theta| at an impact in the late window, rad.
    pub late_theta_max_rad: f64,
    /// Largest |theta| at any impact, rad.
    pub max_abs_theta_rad: f64,
    /// Largest |x| of the centre of mass at an impact, m (how far the body wanders: the x'
    /// eigenvalue is 1).
    pub max_abs_x_m: f64,
    /// Impacts with a prediction from the controller.
    pub predicted_impacts: usize,
    /// Root mean square of (actual - predicted) impact time, s (None without predictions).
    pub impact_time_error_rms_s: Option<f64>,
    /// Largest |actual - predicted| impact time, s.
    pub impact_time_error_max_s: Option<f64>,
    /// Control steps taken (0 for the ideal table).
    pub control_steps: u64,
    /// Steps answered in the safe state, by fault.
    pub safe: SafeSteps,
    /// Steps by plan status.
    pub plan_steps: PlanSteps,
    /// Simulated time at the end, s.
    pub sim_time_s: f64,
}

/// One sample of the body and the table at a control step (for filmstrip plots).
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct StepSample {
    /// Time, s.
    pub time_s: f64,
    /// Body pose (x m, y m, theta rad).
    pub body: [f64; 3],
    /// Table angle, rad.
    pub table_angle_rad: f64,
    /// Pivot height (the table line's height under the centre of mass), m.
    pub table_height_m: f64,
}

/// A finished run.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct TableRun {
    /// The figures.
    pub summary: TableSummary,
    /// Every impact.
    pub impacts: Vec<TableImpact>,
    /// Step samples inside the requested recording windows.
    pub samples: Vec<StepSample>,
}

/// Counters the run loop keeps besides the impacts.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct RunCounters {
    /// Control steps.
    pub control_steps: u64,
    /// Steps answered in the safe state, by fault.
    pub safe: SafeSteps,
    /// Steps by plan status.
    pub plan_steps: PlanSteps,
    /// Simulated time, s.
    pub sim_time_s: f64,
}

/// Most impacts in a late window: a run of more than four times this many impacts takes
/// its late figures over its last `MAX_LATE_WINDOW` impacts (bounded memory however long).
pub const MAX_LATE_WINDOW: usize = 1 << 18;

/// A run's figures built impact by impact in bounded memory: the late window's energies and
/// angles in a ring of at most [`MAX_LATE_WINDOW`], the rest as running maxima and sums.
/// [`SummaryBuilder::finish`] gives the same figures, bit for bit, as summing over all the
/// impacts would (the late sums are taken in the same order).
#[derive(Clone, Debug)]
pub struct SummaryBuilder {
    late_cap: usize,
    /// (energy J/kg, theta rad) of the newest impacts.
    late: std::collections::VecDeque<(f64, f64)>,
    impacts: usize,
    max_abs_theta_rad: f64,
    max_abs_x_m: f64,
    predicted: usize,
    error_sq_sum: f64,
    error_max_s: f64,
}

impl SummaryBuilder {
    /// Ready for a run of at most `requested` impacts (its late window is the last quarter
    /// of the impacts that happen, so it never needs more than `requested / 4` of them).
    pub fn new(requested: usize) -> Self {
        Self {
            late_cap: (requested / 4).clamp(1, MAX_LATE_WINDOW),
            late: std::collections::VecDeque::new(),
            impacts: 0,
            max_abs_theta_rad: 0.0,
            max_abs_x_m: 0.0,
            predicted: 0,
            error_sq_sum: 0.0,
            error_max_s: 0.0,
        }
    }

    /// One impact.
    pub fn push(&mut self, r: &TableImpact) {
        if self.late.len() == self.late_cap {
            self.late.pop_front();
        }
        self.late.push_back((r.energy_jpkg, r.before.theta_rad));
        self.impacts += 1;
        self.max_abs_theta_rad = self.max_abs_theta_rad.max(r.before.theta_rad.abs());
        self.max_abs_x_m = self.max_abs_x_m.max(r.before.x_m.abs());
        if let Some(p) = r.predicted_time_s {
            let e = r.time_s - p;
            self.predicted += 1;
            self.error_sq_sum += e * e;
            self.error_max_s = self.error_max_s.max(e.abs());
        }
    }

    /// Impacts pushed so far.
    pub fn impacts(&self) -> usize {
        self.impacts
    }

    /// The figures (eta* from `model`).
    pub fn finish(
        &self,
        table: TableKind,
        model: &PlanarModel,
        end: RunEnd,
        counters: &RunCounters,
    ) -> TableSummary {
        let eta_star = model.feedback.target_energy_jpkg();
        let n = self.impacts;
        let late = (n / 4).max(1).min(self.late.len());
        let window = self.late.iter().skip(self.late.len() - late);
        let late_mean = if late > 0 {
            window.clone().map(|r| r.0).sum::<f64>() / late as f64
        } else {
            f64::NAN
        };
        let late_theta = window.map(|r| r.1.abs()).fold(0.0, f64::max);
        let k = self.predicted;
        TableSummary {
            table,
            impacts: n,
            end,
            tipped_over: end == RunEnd::TippedOver,
            stayed_up: end == RunEnd::Completed,
            target_energy_jpkg: eta_star,
            late_window_impacts: late,
            late_mean_energy_jpkg: late_mean,
            late_energy_error: (late_mean - eta_star) / eta_star,
            late_theta_max_rad: late_theta,
            max_abs_theta_rad: self.max_abs_theta_rad,
            max_abs_x_m: self.max_abs_x_m,
            predicted_impacts: k,
            impact_time_error_rms_s: (k > 0).then(|| (self.error_sq_sum / k as f64).sqrt()),
            impact_time_error_max_s: (k > 0).then_some(self.error_max_s),
            control_steps: counters.control_steps,
            safe: counters.safe.clone(),
            plan_steps: counters.plan_steps,
            sim_time_s: counters.sim_time_s,
        }
    }
}

/// The summary of `impacts` (eta* from `model`).
pub fn summarize(
    table: TableKind,
    model: &PlanarModel,
    impacts: &[TableImpact],
    end: RunEnd,
    counters: &RunCounters,
) -> TableSummary {
    let mut b = SummaryBuilder::new(impacts.len());
    for r in impacts {
        b.push(r);
    }
    b.finish(table, model, end, counters)
}

/// The paper's ideal table ([`PlanarModel::run`]) as a [`TableRun`]: `impacts` impacts from
/// `start`, timing noise from `seed` when the model has some.
pub fn run_ideal_table(
    model: &PlanarModel,
    start: PlanarState,
    impacts: usize,
    seed: u64,
) -> TableRun {
    let run: PlanarRun = model.run(start, impacts, seed);
    let l = model.l_m();
    let records: Vec<TableImpact> = run
        .impacts
        .iter()
        .map(|r| TableImpact {
            index: r.index,
            time_s: r.time_s,
            before: r.before,
            after: r.after,
            table_angle_rad: r.table.alpha_rad,
            table_velocity_mps: r.table.velocity_mps,
            table_velocity_after_mps: r.table.velocity_mps,
            table_rate_radps: 0.0,
            contact_height_m: r.before.contact_point(l)[1],
            energy_jpkg: r.energy_jpkg,
            predicted_time_s: None,
            grazing: r.grazing,
        })
        .collect();
    let counters = RunCounters {
        sim_time_s: records.last().map_or(0.0, |r| r.time_s),
        ..RunCounters::default()
    };
    let summary = summarize(TableKind::Ideal, model, &records, run.end, &counters);
    TableRun {
        summary,
        impacts: records,
        samples: Vec::new(),
    }
}
