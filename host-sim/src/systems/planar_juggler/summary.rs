//! The planar juggler run's summary beside the closed form, as text or one JSON object.

use super::{end_name, JugglerConfig, Law};
use crate::model::planar::juggler::{Bat, JuggleRun, JugglerParams};
use crate::output::{json_text, JsonStyle};
use crate::system::Outcome;
use serde::Serialize;

/// Relative band around the fixed point's energy and b_x* that counts as converged.
pub const CONVERGE_TOLERANCE: f64 = 0.01;
/// Fewest trailing in-band bats for a run to count as converged.
pub const MIN_CONVERGED_TAIL: usize = 5;

/// The fixed point of the vertical motion on the line b_x = b_x* (eq. 8): the impact
/// speed maps as f(v) = (alpha + (1 + alpha)(kappa0 + kappa1 (eta* - v^2/2))) v.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct ClosedForm {
    /// eta* = gamma h*, J/kg.
    pub target_energy_jpkg: f64,
    /// The fixed point's energy, eta* - (1 - alpha - (1 + alpha) kappa0)/((1 + alpha)
    /// kappa1), J/kg (eta* when kappa0 is matched); `None` without an isolated positive one.
    pub fixed_point_energy_jpkg: Option<f64>,
    /// Its apex height, eta_fp / gamma, m.
    pub fixed_point_apex_m: Option<f64>,
    /// f'(v*) = 1 - (1 + alpha) kappa1 v*^2, v*^2 = 2 eta_fp: stable for |slope| < 1.
    pub energy_slope: Option<f64>,
}

impl ClosedForm {
    /// The closed form of a juggler with `p`.
    pub fn of(p: &JugglerParams) -> Self {
        let a = p.restitution;
        let eta_star = p.gravity_mps2 * p.target_apex_m;
        let eta = (p.kappa1_s2pm2 > 0.0)
            .then(|| eta_star - (1.0 - a - (1.0 + a) * p.kappa0) / ((1.0 + a) * p.kappa1_s2pm2))
            .filter(|e| e.is_finite() && *e > 0.0);
        Self {
            target_energy_jpkg: eta_star,
            fixed_point_energy_jpkg: eta,
            fixed_point_apex_m: eta.map(|e| e / p.gravity_mps2),
            energy_slope: eta.map(|e| 1.0 - (1.0 + a) * p.kappa1_s2pm2 * 2.0 * e),
        }
    }
}

/// The summary of one run (the `--json` object).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct JugglerSummary {
    /// Scene name.
    pub scene: String,
    /// `mirror` or `modified`.
    pub law: Law,
    /// `eq. 12` or `eq. 15`.
    pub equation: &'static str,
    /// alpha.
    pub restitution: f64,
    /// gamma, m/s^2.
    pub gravity_mps2: f64,
    /// kappa0 in use.
    pub kappa0: f64,
    /// kappa1 in use, s^2/m^2.
    pub kappa1_s2pm2: f64,
    /// kappa10.
    pub kappa10: f64,
    /// kappa11.
    pub kappa11: f64,
    /// h*, m.
    pub target_apex_m: f64,
    /// b_x*, m.
    pub target_x_m: f64,
    /// The closed form.
    #[serde(flatten)]
    pub closed_form: ClosedForm,
    /// Bats asked for.
    pub impacts_requested: usize,
    /// Bats simulated.
    pub impacts: usize,
    /// Why the run ended (`completed`, `no_contact`, `bad_contact`, `left_half_plane`,
    /// `non_finite`).
    pub end: &'static str,
    /// Apex (b_x, b_z) after the first bat, m.
    pub first_apex_m: Option<[f64; 2]>,
    /// Apex (b_x, b_z) after the last bat, m.
    pub final_apex_m: Option<[f64; 2]>,
    /// Energy after the last bat, J/kg.
    pub final_energy_jpkg: Option<f64>,
    /// b_x' after the last bat, m/s.
    pub final_x_dot_mps: Option<f64>,
    /// Final apex b_x - b_x*, m.
    pub apex_x_error_m: Option<f64>,
    /// Final energy - the fixed point's, J/kg.
    pub energy_error_jpkg: Option<f64>,
    /// Bats after which every bat stayed within [`CONVERGE_TOLERANCE`] of the fixed
    /// point's energy and of b_x* (null if never, or for fewer than 5 bats).
    pub converged_after_impacts: Option<usize>,
    /// Simulated time, s.
    pub sim_time_s: f64,
    /// Wall-clock time, s.
    pub wall_time_s: f64,
}

/// A planar juggler run's result.
#[derive(Clone, Debug)]
pub struct JugglerOutcome {
    /// The summary.
    pub summary: JugglerSummary,
}

/// Bats after which every bat is within the band (module constants).
fn converged_after(bats: &[Bat], cf: &ClosedForm, x_star: f64) -> Option<usize> {
    let eta = cf.fixed_point_energy_jpkg?;
    let in_band = |b: &Bat| {
        (b.energy_jpkg - eta).abs() <= CONVERGE_TOLERANCE * eta
            && (b.apex[0] - x_star).abs() <= CONVERGE_TOLERANCE * x_star
    };
    let tail = bats.iter().rev().take_while(|b| in_band(b)).count();
    (tail >= MIN_CONVERGED_TAIL).then(|| bats.len() - tail + 1)
}

impl JugglerOutcome {
    /// The outcome of `run`, a run of `cfg`.
    pub fn new(cfg: &JugglerConfig, cf: ClosedForm, run: &JuggleRun, wall_s: f64) -> Self {
        let p = &cfg.params;
        let last = run.bats.last();
        let summary = JugglerSummary {
            scene: cfg.name.clone(),
            law: cfg.table.law,
            equation: cfg.table.law.equation(),
            restitution: p.restitution,
            gravity_mps2: p.gravity_mps2,
            kappa0: p.kappa0,
            kappa1_s2pm2: p.kappa1_s2pm2,
            kappa10: p.kappa10,
            kappa11: p.kappa11,
            target_apex_m: p.target_apex_m,
            target_x_m: p.target_x_m,
            closed_form: cf,
            impacts_requested: cfg.table.impacts,
            impacts: run.bats.len(),
            end: end_name(run.end),
            first_apex_m: run.bats.first().map(|b| b.apex),
            final_apex_m: last.map(|b| b.apex),
            final_energy_jpkg: last.map(|b| b.energy_jpkg),
            final_x_dot_mps: last.map(|b| b.after[2]),
            apex_x_error_m: last.map(|b| b.apex[0] - p.target_x_m),
            energy_error_jpkg: last
                .zip(cf.fixed_point_energy_jpkg)
                .map(|(b, e)| b.energy_jpkg - e),
            converged_after_impacts: converged_after(&run.bats, &cf, p.target_x_m),
            sim_time_s: last.map_or(0.0, |b| b.time_s),
            wall_time_s: wall_s,
        };
        Self { summary }
    }
}

impl Outcome for JugglerOutcome {
    fn text(&self) -> String {
        let s = &self.summary;
        let cf = &s.closed_form;
        let mut o = format!(
            "planar juggler scene {}: {} law ({})\n  gains:        kappa0 {}, kappa1 {} s^2/m^2, kappa10 {}, kappa11 {}; alpha {}, gamma {} m/s^2\n",
            s.scene, s.law.name(), s.equation,
            s.kappa0, s.kappa1_s2pm2, s.kappa10, s.kappa11, s.restitution, s.gravity_mps2
        );
        o += &format!(
            "  target:       apex ({} m, {} m), eta* {:.6} J/kg\n",
            s.target_x_m, s.target_apex_m, cf.target_energy_jpkg
        );
        o += &match (cf.fixed_point_energy_jpkg, cf.energy_slope) {
            (Some(e), Some(sl)) => format!(
                "  closed form:  on b_x = b_x* the vertical motion is eq. 8: fixed point eta {e:.6} J/kg (apex {:.6} m), slope 1 - (1+alpha) kappa1 v*^2 = {sl:.6} ({})\n",
                e / s.gravity_mps2,
                if sl.abs() < 1.0 { "stable" } else { "unstable" }
            ),
            _ => "  closed form:  eq. 8 has no isolated positive fixed point for these gains\n".to_string(),
        };
        o += &format!(
            "  outcome:      {} of {} bats, {}\n",
            s.impacts, s.impacts_requested, s.end
        );
        if let (Some(a), Some(e)) = (s.final_apex_m, s.final_energy_jpkg) {
            o += &format!(
                "  late apex:    ({:.6} m, {:.6} m), energy {e:.6} J/kg; apex x - b_x* = {:.3e} m, eta - eta_fp = {}\n",
                a[0],
                a[1],
                a[0] - s.target_x_m,
                s.energy_error_jpkg.map_or("-".into(), |d| format!("{d:.3e} J/kg"))
            );
        }
        o += &format!(
            "  converged:    {}\n",
            s.converged_after_impacts.map_or(
                "never (1 % of the fixed point's energy and of b_x*)".into(),
                |n| format!("after {n} bats (within 1 % of the fixed point's energy and of b_x*)")
            )
        );
        o += &format!(
            "  time:         simulated {:.3} s, wall {:.3} ms\n",
            s.sim_time_s,
            1e3 * s.wall_time_s
        );
        o
    }

    fn json(&self) -> Result<String, String> {
        json_text(&self.summary, JsonStyle::Compact)
    }

    /// A contact search at its cap, or a non-finite value, is not the juggler's physics.
    fn shortfall(&self) -> Option<String> {
        let s = &self.summary;
        matches!(s.end, "search_cap" | "non_finite").then(|| {
            format!(
                "after {} of {} bats: {}",
                s.impacts, s.impacts_requested, s.end
            )
        })
    }
}
