//! The spatial juggler run's summary beside the closed form, as text or one JSON object.

use super::SpatialConfig;
use crate::controller::{HilReport, SafeSteps};
use crate::model::spatial::sil::SilReport;
use crate::model::spatial::{Law, SpatialBat, SpatialParams};
use crate::output::{json_text, JsonStyle};
use crate::system::Outcome;
use dexter_core::mirror::MirrorLaw;
use serde::Serialize;

/// Relative band (of rho* horizontally, of the fixed point's apex vertically) that counts as
/// converged.
pub const CONVERGE_TOLERANCE: f64 = 0.01;
/// Fewest trailing in-band bats for a run to count as converged.
pub const MIN_CONVERGED_TAIL: usize = 5;

/// The fixed point of the vertical motion over the set point (eq. 8, the line juggler's).
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct ClosedForm {
    /// Its impact speed v*, m/s; `None` without a positive period-1 orbit.
    pub fixed_point_speed_mps: Option<f64>,
    /// Its apex, v*^2 / (2 gamma), m.
    pub fixed_point_apex_m: Option<f64>,
    /// eq. 8's slope there, 1 - (1 + alpha) kappa1 v*^2: stable for |slope| < 1.
    pub energy_slope: Option<f64>,
}

impl ClosedForm {
    /// The closed form for `p` (the core's line-juggler law, independent of the spatial one).
    pub fn of(p: &SpatialParams) -> Self {
        let l = &p.law;
        let law = MirrorLaw::new(l.kappa0, l.kappa1_s2pm2, l.target_apex_m, l.gravity_mps2).ok();
        let v = law.and_then(|m| m.fixed_point_speed_mps(p.restitution));
        Self {
            fixed_point_speed_mps: v,
            fixed_point_apex_m: v.map(|v| v * v / (2.0 * l.gravity_mps2)),
            energy_slope: law.and_then(|m| m.fixed_point_slope(p.restitution)),
        }
    }
}

/// The summary of one run (the `--json` object).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct SpatialSummary {
    /// Scene name.
    pub scene: String,
    /// `mirror` or `modified`.
    pub law: Law,
    /// alpha.
    pub restitution: f64,
    /// gamma, m/s^2.
    pub gravity_mps2: f64,
    /// kappa0 in use.
    pub kappa0: f64,
    /// kappa1 in use, s^2/m^2.
    pub kappa1_s2pm2: f64,
    /// kappa10 in use.
    pub kappa10: f64,
    /// kappa11 in use.
    pub kappa11: f64,
    /// kappa20 in use, rad/m.
    pub kappa20_radpm: f64,
    /// kappa21 in use, rad s/m.
    pub kappa21_radspm: f64,
    /// The set point (rho* cos phi*, rho* sin phi*, h*), m.
    pub target_m: [f64; 3],
    /// The closed form.
    #[serde(flatten)]
    pub closed_form: ClosedForm,
    /// Bats asked for.
    pub impacts_requested: usize,
    /// Bats simulated.
    pub impacts: usize,
    /// Why the run ended.
    pub end: &'static str,
    /// Apex after the first bat, m.
    pub first_apex_m: Option<[f64; 3]>,
    /// Apex after the last bat, m.
    pub final_apex_m: Option<[f64; 3]>,
    /// Its horizontal distance from the set point, m.
    pub horizontal_apex_error_m: Option<f64>,
    /// Its height relative to the fixed point's apex, (z - h_fp)/h_fp.
    pub apex_height_rel_error: Option<f64>,
    /// Bats after which every bat's apex stayed within [`CONVERGE_TOLERANCE`] of the set
    /// point horizontally (of rho*) and of h_fp (null if never, or for fewer than 5 bats).
    pub converged_after_impacts: Option<usize>,
    /// Simulated time, s.
    pub sim_time_s: f64,
    /// Wall-clock time, s.
    pub wall_time_s: f64,
    /// The fixed-rate controller's figures (`[spatial_juggler.sil]` scenes only).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub controller: Option<ControllerFigures>,
}

/// The closed loop's figures: the controller, where it ran, its safe steps, its tracking.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct ControllerFigures {
    /// `"sil"` (the core linked in) or `"hil"` (the firmware on a target).
    pub runs_on: &'static str,
    /// Control (and camera) rate, Hz.
    pub control_rate_hz: f64,
    /// Camera noise per coordinate, m.
    pub camera_sigma_m: f64,
    /// Camera latency, s.
    pub camera_latency_s: f64,
    /// Control steps and those answered in the safe state, by fault.
    pub safe: SafeSteps,
    /// Largest |reference - joint angle| at an impact, rad.
    pub max_tracking_error_at_impact_rad: f64,
    /// The controller's instruction budget per step on the target.
    pub step_instruction_budget: u32,
    /// The target's figures (`--hil`), else null.
    pub hil: Option<HilReport>,
}

impl ControllerFigures {
    /// The figures of `report`, a closed-loop run of `cfg`.
    pub fn new(cfg: &SpatialConfig, report: SilReport, on_target: bool) -> Self {
        let plant = cfg.sil.map(|(_, p)| p);
        Self {
            runs_on: if on_target { "hil" } else { "sil" },
            control_rate_hz: plant.map_or(0.0, |p| 1.0 / p.dt_s),
            camera_sigma_m: plant.map_or(0.0, |p| p.camera.sigma_m),
            camera_latency_s: plant.map_or(0.0, |p| p.camera.latency_s),
            safe: report.safe,
            max_tracking_error_at_impact_rad: report.max_tracking_error_at_impact_rad,
            step_instruction_budget: super::sil::STEP_BUDGET,
            hil: None,
        }
    }

    fn text(&self) -> String {
        let mut o = format!(
            "  controller:   {} at {} Hz, camera noise {} m, latency {} s; tracking error at impacts up to {:.3e} rad; {} of {} steps in the safe state\n",
            self.runs_on.to_uppercase(),
            self.control_rate_hz,
            self.camera_sigma_m,
            self.camera_latency_s,
            self.max_tracking_error_at_impact_rad,
            self.safe.safe_steps,
            self.safe.steps
        );
        let safe = self.safe.text();
        if !safe.is_empty() {
            o += &format!("  {safe}");
        }
        if let Some(h) = &self.hil {
            o += &format!("  {}", h.text());
        }
        o
    }
}

/// A spatial juggler run's result.
#[derive(Clone, Debug)]
pub struct SpatialOutcome {
    /// The summary.
    pub summary: SpatialSummary,
}

/// The horizontal distance of `apex` from the set point, m.
fn horizontal_error(apex: &[f64; 3], target: &[f64; 3]) -> f64 {
    (apex[0] - target[0]).hypot(apex[1] - target[1])
}

/// Bats after which every apex is within the band.
fn converged_after(
    bats: &[SpatialBat],
    target: &[f64; 3],
    rho: f64,
    h: Option<f64>,
) -> Option<usize> {
    let h = h?;
    let in_band = |b: &SpatialBat| {
        horizontal_error(&b.apex_m, target) <= CONVERGE_TOLERANCE * rho
            && (b.apex_m[2] - h).abs() <= CONVERGE_TOLERANCE * h
    };
    let tail = bats.iter().rev().take_while(|b| in_band(b)).count();
    (tail >= MIN_CONVERGED_TAIL).then(|| bats.len() - tail + 1)
}

impl SpatialOutcome {
    /// The outcome of a run of `cfg` that made `bats` and ended for `end`.
    pub fn new(cfg: &SpatialConfig, bats: &[SpatialBat], end: &'static str, wall_s: f64) -> Self {
        let p = &cfg.params;
        let l = &p.law;
        let cf = ClosedForm::of(p);
        let (s, c) = l.target_azimuth_rad.sin_cos();
        let target = [
            l.target_radius_m * c,
            l.target_radius_m * s,
            l.target_apex_m,
        ];
        let last = bats.last();
        let summary = SpatialSummary {
            scene: cfg.name.clone(),
            law: cfg.table.law,
            restitution: p.restitution,
            gravity_mps2: l.gravity_mps2,
            kappa0: l.kappa0,
            kappa1_s2pm2: l.kappa1_s2pm2,
            kappa10: l.kappa10,
            kappa11: l.kappa11,
            kappa20_radpm: l.kappa20_radpm,
            kappa21_radspm: l.kappa21_radspm,
            target_m: target,
            closed_form: cf,
            impacts_requested: cfg.table.impacts,
            impacts: bats.len(),
            end,
            first_apex_m: bats.first().map(|b| b.apex_m),
            final_apex_m: last.map(|b| b.apex_m),
            horizontal_apex_error_m: last.map(|b| horizontal_error(&b.apex_m, &target)),
            apex_height_rel_error: last
                .zip(cf.fixed_point_apex_m)
                .map(|(b, h)| (b.apex_m[2] - h) / h),
            converged_after_impacts: converged_after(
                bats,
                &target,
                l.target_radius_m,
                cf.fixed_point_apex_m,
            ),
            sim_time_s: last.map_or(0.0, |b| b.time_s),
            wall_time_s: wall_s,
            controller: None,
        };
        Self { summary }
    }
}

impl Outcome for SpatialOutcome {
    fn text(&self) -> String {
        let s = &self.summary;
        let cf = &s.closed_form;
        let [tx, ty, th] = s.target_m;
        let mut o = format!(
            "spatial juggler scene {}: {} law ({})\n  gains:        kappa0 {}, kappa1 {} s^2/m^2, kappa10 {}, kappa11 {}, kappa20 {} rad/m, kappa21 {} rad s/m; alpha {}, gamma {} m/s^2\n",
            s.scene,
            s.law.name(),
            match s.law {
                Law::Mirror => "eq. 13",
                Law::Modified => "solvable flight time, docs/spatial.md",
            },
            s.kappa0, s.kappa1_s2pm2, s.kappa10, s.kappa11, s.kappa20_radpm, s.kappa21_radspm,
            s.restitution, s.gravity_mps2
        );
        o += &format!("  target:       apex ({tx} m, {ty} m, {th} m)\n");
        o += &match (cf.fixed_point_apex_m, cf.energy_slope) {
            (Some(h), Some(sl)) => format!(
                "  closed form:  over the set point the vertical motion is eq. 8: fixed-point apex {h:.6} m, slope {sl:.6} ({})\n",
                if sl.abs() < 1.0 { "stable" } else { "unstable" }
            ),
            _ => "  closed form:  eq. 8 has no positive period-1 orbit for these gains\n".into(),
        };
        o += &format!(
            "  outcome:      {} of {} bats, {}\n",
            s.impacts, s.impacts_requested, s.end
        );
        if let (Some([x, y, z]), Some(e)) = (s.final_apex_m, s.horizontal_apex_error_m) {
            o += &format!(
                "  late apex:    ({x:.6} m, {y:.6} m, {z:.6} m): {e:.3e} m from the set point horizontally, height {} of the fixed point's\n",
                s.apex_height_rel_error
                    .map_or("-".into(), |r| format!("{:+.3e}", r))
            );
        }
        o += &format!(
            "  converged:    {}\n",
            s.converged_after_impacts.map_or(
                "never (1 % of rho* horizontally and of the fixed point's apex)".into(),
                |n| format!(
                    "after {n} bats (within 1 % of rho* horizontally and of the fixed point's apex)"
                )
            )
        );
        if let Some(c) = &s.controller {
            o += &c.text();
        }
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

    fn attach_hil(&mut self, report: HilReport) {
        if let Some(c) = self.summary.controller.as_mut() {
            c.hil = Some(report);
        }
    }

    fn safe_steps(&self) -> Option<&SafeSteps> {
        self.summary.controller.as_ref().map(|c| &c.safe)
    }

    /// A contact search at its cap, a non-finite value, or the closed loop's step cap, is
    /// not the juggler's physics.
    fn shortfall(&self) -> Option<String> {
        let s = &self.summary;
        matches!(s.end, "search_cap" | "non_finite" | "step_cap").then(|| {
            format!(
                "after {} of {} bats: {}",
                s.impacts, s.impacts_requested, s.end
            )
        })
    }
}
