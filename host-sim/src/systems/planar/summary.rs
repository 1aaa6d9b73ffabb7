//! The planar run's summary: outcome, energy against eta*, tilt amplitude and the
//! stability class, as text or one JSON object (`docs/planar.md`, "Command line").

use crate::controller::{HilReport, SafeSteps};
use crate::model::planar::analysis;
use crate::model::planar::stats::{CellClass, RunStats};
use crate::model::planar::table_run::PlanSteps;
use crate::model::planar::{Body, ContactLaw, PlanarModel, PlanarParams, RunEnd, Streamed};
use dexter_core::tilt::kappa_crit;
use serde::Serialize;
use std::fmt::Write as _;

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
    /// Impacts in the late window (the last quarter; of a run that ended early, at most
    /// the last 65536 impacts).
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
    /// The stability-map class of this run (`stats::classify`).
    pub class: CellClass,
    /// `ideal` (the paper's table) or `real` (`[real_table]`).
    pub table: &'static str,
    /// The run ended because |theta| reached the tip angle.
    pub tipped_over: bool,
    /// (late mean eta - eta*)/eta*, as `late_mean_energy_rel_error` (the same key for both
    /// tables, `docs/planar.md`).
    pub late_energy_error: f64,
    /// max |theta| at impacts over the late window, rad, as `late_max_abs_theta_rad`.
    pub late_theta_max_rad: f64,
    /// The real table's figures (absent for the ideal table).
    #[serde(flatten, skip_serializing_if = "Option::is_none")]
    pub real: Option<RealFigures>,
    /// Gap evaluations of all contact searches.
    pub gap_evaluations: usize,
    /// Simulated time, s (= end_time_s).
    pub sim_time_s: f64,
    /// Wall-clock time of the simulation, s.
    pub wall_time_s: f64,
}

/// eq. 16's kappa_crit at the model's target energy (NaN for a point mass / no flight).
pub(super) fn kappa_crit_of(model: &PlanarModel) -> f64 {
    match (model.body, analysis::fixed_point_velocity_mps(model)) {
        (Body::Rigid { rho_m, l_m }, Ok(y)) => kappa_crit(model.gravity_mps2, rho_m, l_m, y, 1.0),
        _ => f64::NAN,
    }
}

/// The summary of a run of `model` (scene `p`, `requested` impacts) whose impacts went
/// through `stats` and which ended for `end` after `gap_evaluations` gap evaluations.
pub(super) fn summarize(
    name: &str,
    p: &PlanarParams,
    model: &PlanarModel,
    stats: &RunStats,
    done: &Streamed,
    wall_s: f64,
) -> RunSummary {
    let eta_star = model.feedback.target_energy_jpkg();
    let late = stats.late();
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
        impacts_requested: p.impacts,
        impacts: stats.impacts,
        end: done.end,
        stayed_up: done.end == RunEnd::Completed,
        end_time_s: stats.end_time_s,
        target_energy_jpkg: eta_star,
        first_energy_jpkg: stats.first_energy_jpkg,
        late_window_impacts: late.impacts,
        late_mean_energy_jpkg: late.mean_energy_jpkg,
        late_mean_energy_rel_error: (late.mean_energy_jpkg - eta_star) / eta_star,
        max_abs_theta_rad: stats.max_abs_law_rad,
        late_max_abs_theta_rad: late.max_abs_law_rad,
        mean_theta_rad: stats.mean_law_rad(),
        class: stats.class(done.end),
        table: "ideal",
        tipped_over: done.end == RunEnd::TippedOver,
        late_energy_error: (late.mean_energy_jpkg - eta_star) / eta_star,
        late_theta_max_rad: late.max_abs_law_rad,
        real: None,
        gap_evaluations: done.gap_evaluations,
        sim_time_s: stats.end_time_s,
        wall_time_s: wall_s,
    }
}

pub(super) fn end_words(end: RunEnd) -> &'static str {
    match end {
        RunEnd::Completed => "completed",
        RunEnd::TippedOver => "tipped over (|theta| reached the tip angle)",
        RunEnd::NoSeparation => "no separation (the body no longer flies off the table)",
        RunEnd::NoContact => "no contact found (the body does not come back to the table)",
        RunEnd::SearchCap => "the contact search hit its iteration cap (an internal limit)",
        RunEnd::Jam => "Painleve jam in a frictional impact",
        RunEnd::NonFinite => "a state became non-finite",
        RunEnd::TimeLimit => "the time limit (real_table.max_duration_s) passed",
        RunEnd::OutOfTravel => {
            "out of travel (the body left the table's x range, real_table.stage)"
        }
    }
}

pub(super) fn class_name(c: CellClass) -> &'static str {
    match c {
        CellClass::Converges => "converges",
        CellClass::Drifts => "drifts",
        CellClass::TipsOver => "tips_over",
        CellClass::Diverges => "diverges",
    }
}

pub(super) fn class_words(c: CellClass) -> &'static str {
    match c {
        CellClass::Converges => "stays up and converges",
        CellClass::Drifts => "stays up, drifts",
        CellClass::TipsOver => "tips over",
        CellClass::Diverges => "diverges / lost",
    }
}

/// The scene's lines of the summary: model, control, contact.
fn scene_text(s: &RunSummary) -> String {
    let mut o = format!("planar scene {}\n", s.scene);
    let _ = match s.body {
        "rigid" => writeln!(
            o,
            "  model:        rigid body, rho {} m, l {} m, G {} m/s^2, {}",
            s.rho_m, s.l_m, s.gravity_mps2, s.contact
        ),
        _ => writeln!(
            o,
            "  model:        point mass, G {} m/s^2, {}",
            s.gravity_mps2, s.contact
        ),
    };
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
    o
}

pub(super) fn summary_text(s: &RunSummary) -> String {
    let mut o = scene_text(s);
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
        "  energy:       eta* {:.5} J/kg; first impact {}; late mean (last {} impacts) {}",
        s.target_energy_jpkg,
        or_none(s.first_energy_jpkg, |v| format!("{v:.5} J/kg")),
        s.late_window_impacts,
        or_none(s.late_mean_energy_jpkg, |v| format!(
            "{v:.5} J/kg ({:+.2} % of eta*)",
            100.0 * s.late_mean_energy_rel_error
        )),
    );
    let _ = writeln!(
        o,
        "  theta:        max |theta| {:.4} rad (late {:.4} rad), mean {}",
        s.max_abs_theta_rad,
        s.late_max_abs_theta_rad,
        or_none(s.mean_theta_rad, |v| format!("{v:+.4} rad"))
    );
    let _ = writeln!(o, "  class:        {}", class_words(s.class));
    if let Some(r) = &s.real {
        o += &r.text();
    }
    let _ = writeln!(
        o,
        "  time:         simulated {:.3} s, wall {:.3} ms ({} gap evaluations)",
        s.sim_time_s,
        1e3 * s.wall_time_s,
        s.gap_evaluations
    );
    o
}

/// `v` written by `f`, or "none" for a statistic with no samples (NaN: no impacts).
fn or_none(v: f64, f: impl Fn(f64) -> String) -> String {
    if v.is_finite() {
        f(v)
    } else {
        "none".to_string()
    }
}

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
    /// kappa_x of the horizontal regulation, rad/m.
    pub kappa_x_pm: f64,
    /// kappa_x' of the horizontal regulation, s/m.
    pub kappa_xdot_spm: f64,
    /// The x range the table can be under the centre of mass (`real_table.stage`), m.
    pub x_range_m: [f64; 2],
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
    /// Largest |x| of the centre of mass at an impact, m (the paper's law does not hold x;
    /// the horizontal regulation does).
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
            "  real table:   tilt controller at {} Hz, kappa_w {} s, kappa_x {} /m, kappa_x' {} s/m, {} Newton steps; {}; drives {}; x range {} .. {} m",
            self.control_rate_hz,
            self.kappa_rate_s,
            self.kappa_x_pm,
            self.kappa_xdot_spm,
            self.contact_iterations,
            camera,
            if self.drives_limited { "limited" } else { "ideal" },
            self.x_range_m[0],
            self.x_range_m[1]
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
