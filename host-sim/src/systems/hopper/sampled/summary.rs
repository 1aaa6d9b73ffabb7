//! The sampled hopper's summary: its documented keys (`cycles`, `period`,
//! `late_apex_heights_m`, `fixed_point_error`, `phase_detection_errors`), the exact-thrust
//! orbit they are measured against, the run's health, and with `--hil` the target's
//! figures; as text or one JSON object. Everything is a fixed-size summary of the run
//! ([`SampledRun`] keeps the last hops only).

use super::super::{model_equation, model_name};
use super::scene::SampledHopperConfig;
use crate::controller::{HilReport, SafeSteps};
use crate::model::hopper::sampled::{
    EventErrors, SampledEnd, SampledRun, SampledSummary, Timing, LATE_APEXES,
};
use crate::model::hopper::ThrustLaw;
use crate::output::{json_text, JsonStyle};
use crate::system::Outcome;
use serde::Serialize;

/// What a sampled run produced.
#[derive(Clone, Debug)]
pub struct SampledOutcome {
    /// The scene's name.
    pub name: String,
    /// `linear` or `full`.
    pub model: &'static str,
    /// The model's equation.
    pub equation: &'static str,
    /// `raibert` or `energy_servo`.
    pub thrust_law: &'static str,
    /// The thrust law in words.
    pub thrust_text: String,
    /// Control rate, Hz.
    pub control_rate_hz: f64,
    /// The servo's target hop height E*/g, m (servo scenes).
    pub target_hop_height_m: Option<f64>,
    /// The run.
    pub run: SampledRun,
    /// Wall-clock time of the run, s.
    pub wall_time_s: f64,
    /// The target's figures (`--hil`).
    pub hil: Option<HilReport>,
}

/// The JSON object.
#[derive(Serialize)]
struct Json<'a> {
    scene: &'a str,
    model: &'static str,
    equation: &'static str,
    thrust_law: &'static str,
    control_rate_hz: f64,
    #[serde(flatten)]
    run: SampledSummary<'a>,
    target_hop_height_m: Option<f64>,
    target_hop_error: Option<f64>,
    wall_time_s: f64,
    #[serde(flatten, skip_serializing_if = "Option::is_none")]
    hil: Option<&'a HilReport>,
}

impl SampledOutcome {
    /// The outcome of `run` for the scene `cfg`.
    pub fn new(cfg: &SampledHopperConfig, run: SampledRun, wall_s: f64) -> Self {
        let p = &cfg.hopper.params;
        let (thrust_law, thrust_text, target) = match &cfg.hopper.hopper.law {
            ThrustLaw::Raibert(r) => (
                "raibert",
                format!(
                    "Raibert, tau {} m/s^2 for {} s from the bottom",
                    r.thrust_mps2(),
                    r.duration_s()
                ),
                None,
            ),
            ThrustLaw::EnergyServo(s) => (
                "energy_servo",
                format!(
                    "energy servo, tau0 {} m/s^2 + {} 1/m x (E* {} J/kg - E), at most {} m/s^2, for {} s",
                    s.nominal_thrust_mps2(),
                    s.gain_per_m(),
                    s.target_energy_jpkg(),
                    s.max_thrust_mps2(),
                    p.thrust_delta_s
                ),
                Some(s.target_energy_jpkg() / p.gravity_mps2),
            ),
        };
        Self {
            name: cfg.name().to_string(),
            model: model_name(p.model),
            equation: model_equation(p.model),
            thrust_law,
            thrust_text,
            control_rate_hz: cfg.control.rate_hz,
            target_hop_height_m: target,
            run,
            wall_time_s: wall_s,
            hil: None,
        }
    }

    /// The mean hop height (apex - chi_l) of the last [`LATE_APEXES`] hops, m.
    pub fn late_hop_height_m(&self) -> Option<f64> {
        let r = &self.run.recent_hop_heights_m;
        let tail = &r[r.len().saturating_sub(LATE_APEXES)..];
        (!tail.is_empty()).then(|| tail.iter().sum::<f64>() / tail.len() as f64)
    }

    /// |late hop height - target| / target (servo scenes).
    pub fn target_hop_error(&self) -> Option<f64> {
        let t = self.target_hop_height_m?;
        Some((self.late_hop_height_m()? - t).abs() / t)
    }

    fn period_text(&self) -> String {
        let s = &self.run.settle;
        match s.period {
            Some(p) => format!(
                "{p} (hop heights within {:.1e} over the last hops)",
                s.spread
            ),
            None if !s.spread.is_finite() => "not settled (too few hops to tell)".to_string(),
            None => format!(
                "not settled (largest spread of a phase {:.3e}, relative)",
                s.spread
            ),
        }
    }

    fn orbit_lines(&self) -> String {
        let mut s = String::new();
        if let Some(ex) = &self.run.exact {
            let hops: Vec<String> = ex.hop_heights_m.iter().map(|h| format!("{h:.6}")).collect();
            s += &format!(
                "exact thrust     hop heights {} m ({}, period {})\n",
                hops.join(", "),
                ex.source,
                ex.period()
            );
        } else {
            s += "exact thrust     not settled (no fixed point to compare with)\n";
        }
        s += &match self.run.fixed_point_error {
            Some(e) => format!("fixed-point err  {:.4} % (of the hop height)\n", 100.0 * e),
            None => "fixed-point err  none (an orbit did not settle)\n".to_string(),
        };
        if let (Some(t), Some(h)) = (self.target_hop_height_m, self.late_hop_height_m()) {
            s += &format!(
                "target hop       {t:.6} m, late hops {h:.6} m ({:.4} % off)\n",
                100.0 * (h - t).abs() / t
            );
        }
        s
    }

    fn detection_lines(&self) -> String {
        let e = &self.run.phase_detection_errors;
        let ev = |name: &str, x: &EventErrors| {
            format!(
                "  {name:<10} {} events, {} missed, {} spurious, lag {}\n",
                x.events,
                x.missed,
                x.spurious,
                timing(&x.lag)
            )
        };
        let mut s = "phase detection\n".to_string();
        s += &ev("touchdown", &e.touchdown);
        s += &ev("bottom", &e.bottom);
        s += &ev("liftoff", &e.liftoff);
        s += &format!(
            "  valve open  - true bottom:         {}\n",
            timing(&e.thrust_start_s)
        );
        s += &format!(
            "  valve close - (true bottom+delta): {}\n",
            timing(&e.thrust_end_s)
        );
        s += &format!(
            "  contact wrong at {} of {} steps\n",
            e.phase_mismatch_steps, e.steps
        );
        s
    }

    fn end_text(&self) -> String {
        match self.run.end {
            SampledEnd::Completed => "at the requested cycles".to_string(),
            _ => self
                .shortfall()
                .unwrap_or_else(|| format!("{:?}", self.run.end)),
        }
    }
}

/// A timing in ms: mean [min, max].
fn timing(t: &Timing) -> String {
    if t.count == 0 {
        return "none".to_string();
    }
    format!(
        "mean {:+.3} ms [{:+.3}, {:+.3}]",
        1e3 * t.mean_s,
        1e3 * t.min_s,
        1e3 * t.max_s
    )
}

impl Outcome for SampledOutcome {
    fn text(&self) -> String {
        let r = &self.run;
        let apexes: Vec<String> = r
            .late_apex_heights_m
            .iter()
            .map(|a| format!("{a:.6}"))
            .collect();
        let mut s = format!("scene            {}\n", self.name);
        s += &format!("model            {} ({})\n", self.model, self.equation);
        s += &format!("thrust           {}\n", self.thrust_text);
        s += &format!("controller       {} Hz\n", self.control_rate_hz);
        s += &format!("cycles           {}\n", r.cycles);
        s += &format!("period           {}\n", self.period_text());
        s += &format!("late apexes      {} m\n", apexes.join(", "));
        s += &self.orbit_lines();
        s += &self.detection_lines();
        s += &format!("ended            {}\n", self.end_text());
        s += &format!("control steps    {}\n", r.control_steps);
        s += &r.safe.text();
        if r.invalid_commands > 0 || r.early_liftoffs > 0 {
            s += &format!(
                "warnings         {} invalid commands, {} liftoffs with the valve open\n",
                r.invalid_commands, r.early_liftoffs
            );
        }
        s += &format!("sim time         {:.6} s\n", r.sim_time_s);
        s += &format!("wall time        {:.6} s\n", self.wall_time_s);
        if let Some(h) = &self.hil {
            s += &h.text();
        }
        s
    }

    fn json(&self) -> Result<String, String> {
        let j = Json {
            scene: &self.name,
            model: self.model,
            equation: self.equation,
            thrust_law: self.thrust_law,
            control_rate_hz: self.control_rate_hz,
            run: self.run.summary(),
            target_hop_height_m: self.target_hop_height_m,
            target_hop_error: self.target_hop_error(),
            wall_time_s: self.wall_time_s,
            hil: self.hil.as_ref(),
        };
        json_text(&j, JsonStyle::Pretty)
    }

    fn attach_hil(&mut self, report: HilReport) {
        self.hil = Some(report);
    }

    fn safe_steps(&self) -> Option<&SafeSteps> {
        Some(&self.run.safe)
    }

    fn shortfall(&self) -> Option<String> {
        let r = &self.run;
        match r.end {
            SampledEnd::Completed => None,
            SampledEnd::TimeLimit => Some(format!(
                "hopper.control.max_time_s passed at {:.3} s after {} of the requested cycles (the hopper stopped hopping)",
                r.sim_time_s, r.cycles
            )),
            SampledEnd::NonFinite => Some("the hopper's state became non-finite".to_string()),
            SampledEnd::StepCap => Some(
                "the full model's integrator reached its step cap within one piece (loosen hopper.tolerance_m)"
                    .to_string(),
            ),
            SampledEnd::PieceCap => Some(
                "more than 256 events within one control period (raise hopper.control.rate_hz)"
                    .to_string(),
            ),
        }
    }
}
