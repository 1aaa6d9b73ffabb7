//! The arm run's summary: the plan, its verification at mu and at 0.95 mu, the tracked
//! run (SIL or the target) and, with `--hil`, the target's figures and the tracked
//! trajectory compared with SIL's bit for bit; as text or one JSON object (keys in
//! `docs/arm.md`, "Output").

use super::execute::ArmSummary;
use super::trace::phase_name;
use super::ArmRunConfig;
use crate::controller::HilReport;
use crate::model::arm::closed_loop::TrackedMotion;
use crate::model::arm::juggle::Chain;
use crate::model::arm::simulate::{Executed, GoalError};
use crate::model::arm::Solver;
use crate::output::{json_text, JsonStyle};
use crate::stream::Decimator;
use crate::system::Outcome;
use dexter_core::arm_control::ArmController;
use dexter_core::fixed_rate::FixedRate;
use serde::Serialize;

/// Events listed in the text summary (the JSON has them all).
const EVENTS_SHOWN: usize = 8;

/// The tracked trajectory on the target against the same loop closed in SIL.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
pub struct TrajectoryComparison {
    /// Control steps compared.
    pub steps: usize,
    /// Steps whose joint state (angle, velocity) or held torque differ in any bit.
    pub mismatches: usize,
    /// Time of the first differing step, s.
    pub first_mismatch_s: Option<f64>,
}

/// Compare two closed-loop runs step by step, bit for bit (a different length counts
/// every missing step).
pub fn compare_trajectories(a: &TrackedMotion, b: &TrackedMotion) -> TrajectoryComparison {
    let bits = |m: &TrackedMotion, k: usize| {
        let (x, v) = m.states.get(k).copied().unwrap_or((f64::NAN, f64::NAN));
        let tau = m.torques_nm.get(k).copied().unwrap_or(f64::NAN);
        (x.to_bits(), v.to_bits(), tau.to_bits())
    };
    let steps = a.states.len().max(b.states.len());
    let differ: Vec<usize> = (0..steps).filter(|&k| bits(a, k) != bits(b, k)).collect();
    TrajectoryComparison {
        steps,
        mismatches: differ.len(),
        first_mismatch_s: differ.first().map(|&k| k as f64 * a.dt_s),
    }
}

/// The HIL part of the JSON.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct HilSummary {
    /// The target's figures (`step_instructions_min/_mean/_max`, `sil_mismatches`,
    /// `link_errors`, ...).
    #[serde(flatten)]
    pub report: HilReport,
    /// `ArmController`'s instruction budget per step.
    pub step_instruction_budget: u32,
    /// The tracked trajectory against SIL's.
    pub sil_trajectory: TrajectoryComparison,
}

/// A juggle's cycles (`task.cycles > 1`): the exact chain and the tracked one.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct JuggleSummary {
    /// Cycles asked for.
    pub cycles: usize,
    /// The planned motions verified, each catch the next cycle's start.
    pub exact: Chain,
    /// The plans tracked by the controller (SIL or the target), each verified catch the
    /// next cycle's start.
    pub tracked: Chain,
}

/// The `--json` object.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct ArmJson {
    /// Scene name.
    pub scene: String,
    /// B-spline control points of the plan.
    pub knots: usize,
    /// The plan, its verification and the tracked run.
    #[serde(flatten)]
    pub summary: ArmSummary,
    /// `"sil"` (the core linked in) or `"hil"` (the firmware on a target).
    pub controller: &'static str,
    /// The target's figures (`--hil`), else null.
    pub hil: Option<HilSummary>,
    /// A juggle's cycles, else null.
    pub juggle: Option<JuggleSummary>,
}

/// An arm run's result.
#[derive(Clone, Debug)]
pub struct ArmOutcome {
    /// The summary.
    pub json: ArmJson,
    /// Tracked joint angle over time, (s, rad), decimated (plots).
    pub tracked_angle: Vec<(f64, f64)>,
    /// Torque the controller commanded over time, (s, N m), decimated (plots).
    pub tracked_torque: Vec<(f64, f64)>,
    /// The tracked trajectory against SIL's (`--hil` only), until the report is attached.
    against_sil: Option<TrajectoryComparison>,
    /// Control period, s.
    pub dt_s: f64,
}

impl ArmOutcome {
    /// The outcome of a run of `cfg`.
    pub fn new(
        cfg: &ArmRunConfig,
        summary: ArmSummary,
        tracked: &TrackedMotion,
        against_sil: Option<TrajectoryComparison>,
    ) -> Self {
        let mut d = Decimator::default();
        for (k, (x, _)) in tracked.states.iter().enumerate() {
            d.push((k as f64 * tracked.dt_s, *x));
        }
        let mut tau = Decimator::default();
        for (k, t) in tracked.torques_nm.iter().enumerate() {
            tau.push((k as f64 * tracked.dt_s, *t));
        }
        Self {
            json: ArmJson {
                scene: cfg.name.clone(),
                knots: summary.trajectory.knots.len(),
                summary,
                controller: "sil",
                hil: None,
                juggle: None,
            },
            tracked_angle: d.into_values(),
            tracked_torque: tau.into_values(),
            against_sil,
            dt_s: tracked.dt_s,
        }
    }
}

/// The solver's name, as in the scene.
fn solver_name(s: Solver) -> &'static str {
    match s {
        Solver::Slsqp => "slsqp",
        Solver::Alm => "alm",
    }
}

/// The verdict's name, as in the JSON.
pub fn verdict(e: Executed) -> &'static str {
    match e {
        Executed::Ok => "ok",
        Executed::Slipped => "slipped",
        Executed::LostContact => "lost_contact",
        Executed::Missed => "missed",
    }
}

fn goal(e: Option<GoalError>) -> String {
    e.map_or(String::new(), |g| {
        format!("; goal error {:.4} m, {:.4} rad", g.position_m, g.angle_rad)
    })
}

impl ArmOutcome {
    fn plan_lines(&self) -> String {
        let s = &self.json.summary;
        let mut o = format!(
            "arm scene {}: {} ({}), {} knots, segment {:.4} s\n",
            self.json.scene, s.task, s.phases, self.json.knots, s.trajectory.segment_s
        );
        o += &format!(
            "  plan:        mu_required {:.6} (the program's samples need {:.6}); {}: {} iterations, {} evaluations, start {} ({}), wall time {:.3} s\n",
            s.mu_required,
            s.mu_sampled,
            solver_name(s.planner_solver),
            s.planner_iterations,
            s.planner_evaluations,
            s.planner_start,
            s.planner_status,
            s.planner_wall_time_s
        );
        let phases: Vec<String> = s
            .phase_times
            .iter()
            .map(|p| {
                format!(
                    "{} {:.4} s + {:.4} s",
                    phase_name(p.phase),
                    p.start_s,
                    p.duration_s
                )
            })
            .collect();
        o += &format!("  phases:      {}\n", phases.join(", "));
        let mut events: Vec<String> = s
            .events
            .iter()
            .take(EVENTS_SHOWN)
            .map(|e| format!("{} {:.4} s", e.kind, e.t_s))
            .collect();
        if s.events.len() > EVENTS_SHOWN {
            events.push(format!("... ({} in all)", s.events.len()));
        }
        if events.is_empty() {
            events.push("none (no phase change)".into());
        }
        o += &format!("  events:      {}\n", events.join(", "));
        o += &impact_line(&s.impacts);
        if s.pulling_impacts > 0 {
            o += &format!(
                "  pulls:       {} impact(s) stopped the object outright only by pulling (object.impact_law = \"no_rebound\", the paper's assumption)\n",
                s.pulling_impacts
            );
        }
        o
    }

    fn verify_lines(&self) -> String {
        let s = &self.json.summary;
        let m = &s.mu_margin_check;
        let mut o = format!(
            "  executed:    {} at mu {:.6}: {}{}\n",
            verdict(s.executed),
            s.mu_required,
            s.reason,
            goal(s.goal_error)
        );
        o += &format!(
            "  at 0.95 mu:  {} at mu {:.6}: {} ({})\n",
            verdict(m.executed),
            m.mu,
            m.reason,
            match m.executed {
                Executed::Ok => "the plan does not need all of its mu",
                _ => "the plan needs its mu",
            }
        );
        o
    }

    fn tracking_lines(&self) -> String {
        let Some(t) = &self.json.summary.tracked else {
            return String::new();
        };
        let who = match self.json.hil {
            Some(_) => "the firmware on the target",
            None => "the core linked in (SIL)",
        };
        let mut o = format!(
            "  tracked:     ArmController, {who}: {} steps of {:.4} s, max error {:.3e} rad (rms {:.3e}), max torque {:.3} N m, {}\n",
            t.steps,
            self.dt_s,
            t.max_tracking_error_rad,
            t.rms_tracking_error_rad,
            t.max_torque_nm,
            t.fault.as_deref().map_or("no fault".to_string(), |f| format!("fault {f}"))
        );
        let mu = self.json.summary.mu_required;
        o += &format!(
            "  tracked run: {} at mu {:.6}: {}{}; it needs mu {:.6} ({:+.2} %), with which: {}{}\n",
            verdict(t.executed),
            mu,
            t.reason,
            goal(t.goal_error),
            t.mu_needed,
            100.0 * (t.mu_needed / mu - 1.0),
            verdict(t.executed_at_mu_needed),
            goal(t.goal_error_at_mu_needed)
        );
        o
    }

    fn juggle_lines(&self) -> String {
        let Some(j) = &self.json.juggle else {
            return String::new();
        };
        let chain = |name: &str, c: &Chain| {
            let last = c.cycles.last().filter(|l| l.executed != Executed::Ok);
            format!(
                "  juggle {name}: {} of {} cycles caught in a row, largest landing error {:.4} m{}\n",
                c.completed,
                j.cycles,
                c.max_landing_error_m,
                last.map_or(String::new(), |l| format!(
                    "; cycle {} {}: {}",
                    l.cycle,
                    verdict(l.executed),
                    l.reason
                ))
            )
        };
        chain("exact  ", &j.exact) + &chain("tracked", &j.tracked)
    }

    fn hil_lines(&self) -> String {
        let Some(h) = &self.json.hil else {
            return String::new();
        };
        let r = &h.report;
        let c = &h.sil_trajectory;
        format!(
            "  HIL:         {} mismatches, {} link errors, {} timeouts, {} over budget, steps/s {:.0}, instr min/mean/max {}/{:.1}/{} (budget {})\n  vs SIL:      {} of {} control steps differ in joint state or torque (bit for bit)\n",
            r.sil_mismatches,
            r.link_errors,
            r.link_timeouts,
            r.over_budget_steps,
            r.steps_per_wall_second,
            r.step_instructions_min,
            r.step_instructions_mean,
            r.step_instructions_max,
            h.step_instruction_budget,
            c.mismatches,
            c.steps
        )
    }
}

impl Outcome for ArmOutcome {
    fn text(&self) -> String {
        self.plan_lines()
            + &self.verify_lines()
            + &self.tracking_lines()
            + &self.juggle_lines()
            + &self.hil_lines()
    }

    fn json(&self) -> Result<String, String> {
        json_text(&self.json, JsonStyle::Pretty)
    }

    fn attach_hil(&mut self, report: HilReport) {
        self.json.controller = "hil";
        self.json.hil = Some(HilSummary {
            report,
            step_instruction_budget: <ArmController as FixedRate>::STEP_INSTRUCTION_BUDGET,
            sil_trajectory: self.against_sil.unwrap_or_default(),
        });
    }
}

/// The verified run's impacts in one line: how many, how many rocked, the first one's
/// centre of pressure and friction.
fn impact_line(impacts: &[super::execute::ImpactSummary]) -> String {
    let Some(first) = impacts.first() else {
        return String::new();
    };
    let rocks = impacts.iter().filter(|i| i.outcome == "rock").count();
    format!(
        "  impacts:     {} ({rocks} rocked onto the striking vertex); first at {:.4} s: {} at {:.3} m/s, centre of pressure {:.4} m on the {:.3} m edge (margin {:.4} m; a stop would need {:.4} m), friction ratio {:.4}, rate {:.3} -> {:.3} rad/s\n",
        impacts.len(),
        first.t_s,
        first.outcome,
        first.speed_mps,
        first.cop_m,
        first.edge_length_m,
        first.cop_margin_m,
        first.stop_cop_m,
        first.friction_ratio,
        first.rate_before_radps,
        first.rate_after_radps
    )
}
