//! The feeder run's summary: the plan and its simulated execution, as text or one JSON
//! object (keys in `docs/feeder.md`, "JSON").

use super::FeederConfig;
use crate::model::feeder::execute::{Summary, FEED_TOL_M};
use crate::model::feeder::primitives::Primitive;
use crate::output::{json_text, JsonStyle};
use crate::system::Outcome;
use serde::Serialize;
use std::fmt::Write as _;

/// The scene around the summary (the `--json` object).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct FeederReport {
    /// Scene name.
    pub scene: String,
    /// The plan and its execution (the keys `docs/feeder.md` documents first).
    #[serde(flatten)]
    pub summary: Summary,
    /// The part's convex hull, body frame (origin at the center of mass), m; hull edge i
    /// runs from vertex i to vertex i + 1.
    pub hull_m: Vec<[f64; 2]>,
    /// The seed the arrival pose was drawn from, if it was.
    pub arrival_seed: Option<u64>,
    /// Whether the execution was perturbed (`[feeder.noise]`).
    pub noise: bool,
}

/// A feeder run's result.
#[derive(Clone, Debug)]
pub struct FeederOutcome {
    /// The report.
    pub report: FeederReport,
}

impl FeederOutcome {
    /// The outcome of a run of `cfg` summarized by `summary`.
    pub fn new(cfg: &FeederConfig, summary: Summary) -> Self {
        let b = &cfg.built;
        let report = FeederReport {
            scene: cfg.name.clone(),
            hull_m: b.feeder.part.hull.iter().map(|v| [v.x, v.y]).collect(),
            arrival_seed: b.arrival_seed,
            noise: b.noise.is_some(),
            summary,
        };
        Self { report }
    }
}

/// One primitive in words.
pub fn primitive_text(p: &Primitive) -> String {
    let deg = |r: f64| r.to_degrees();
    match p {
        Primitive::Catch {
            edge,
            contact_radius_m,
            duration_s,
        } => format!("catch     settles on edge {edge} at r = {contact_radius_m:.5} m ({duration_s:.3} s)"),
        Primitive::Jog {
            edge,
            tilt_rad,
            hold_s,
            from_radius_m,
            to_radius_m,
            duration_s,
        } => format!(
            "jog       edge {edge}: r {from_radius_m:.5} -> {to_radius_m:.5} m, fence tilt {:.2} deg held {hold_s:.3} s ({duration_s:.3} s)",
            deg(*tilt_rad)
        ),
        Primitive::DriftJog {
            edge,
            step_angles_rad,
            from_radius_m,
            to_radius_m,
            duration_s,
        } => {
            let widest = step_angles_rad.iter().fold(0.0f64, |m, a| m.max(a.abs()));
            format!(
                "drift jog edge {edge}: r {from_radius_m:.5} -> {to_radius_m:.5} m, {} push-and-drift steps of up to {:.2} deg ({duration_s:.3} s)",
                step_angles_rad.len(),
                deg(widest)
            )
        }
        Primitive::Turn {
            from_edge,
            to_edge,
            theta_plus_rad,
            theta_minus_rad,
            from_radius_m,
            to_radius_m,
            duration_s,
        } => format!(
            "turn      edge {from_edge} -> {to_edge}: theta+ {:.2} deg, theta- {:.2} deg, r {from_radius_m:.5} -> {to_radius_m:.5} m ({duration_s:.3} s)",
            deg(*theta_plus_rad),
            deg(*theta_minus_rad)
        ),
        Primitive::ConvergentTurn {
            from_edge,
            via_edge,
            to_edge,
            theta_plus_rad,
            theta_minus_rad,
            from_radius_m,
            to_radius_m,
            duration_s,
        } => format!(
            "converge  edge {from_edge} -> {to_edge} via unstable edge {via_edge}: theta+ {:.2} deg, theta- {:.2} deg, r {from_radius_m:.5} -> {to_radius_m:.5} m ({duration_s:.3} s)",
            deg(*theta_plus_rad),
            deg(*theta_minus_rad)
        ),
    }
}

impl Outcome for FeederOutcome {
    fn text(&self) -> String {
        let r = &self.report;
        let s = &r.summary;
        let a = &s.actual;
        let mut o = format!(
            "1JOC feeder scene {}: part with {} hull edges, stable edges {:?}, goal edge {} at r = {:.5} m\n",
            r.scene,
            r.hull_m.len(),
            s.stable_edges,
            s.goal_edge,
            s.goal_radius_m
        );
        let drawn = r
            .arrival_seed
            .map_or(String::new(), |k| format!(" (drawn from seed {k})"));
        let _ = writeln!(
            o,
            "  arrival:    COM ({:.5}, {:.5}) m, angle {:.3} deg{drawn}{}",
            a.arrival.com_m.x,
            a.arrival.com_m.y,
            a.arrival.angle_rad.to_degrees(),
            if r.noise {
                ", perturbed by [feeder.noise]"
            } else {
                ""
            }
        );
        let _ = writeln!(
            o,
            "  plan:       {} primitives, {:.3} s of feeding ({} convergent turns):",
            s.plan.len(),
            s.plan_time_s,
            s.convergent_turns
        );
        for (i, p) in s.plan.iter().enumerate() {
            let _ = writeln!(o, "    {i:>2}  {}", primitive_text(p));
        }
        o += &self.outcome_lines();
        o
    }

    fn json(&self) -> Result<String, String> {
        json_text(&self.report, JsonStyle::Compact)
    }
}

impl FeederOutcome {
    fn outcome_lines(&self) -> String {
        let s = &self.report.summary;
        let a = &s.actual;
        let mut o = String::new();
        let edge = s
            .final_edge
            .map_or("no edge".into(), |e| format!("edge {e}"));
        let verdict = if s.reached_goal {
            "fed: on the goal edge".to_string()
        } else {
            format!("NOT fed (goal: edge {})", s.goal_edge)
        };
        let _ = writeln!(
            o,
            "  execution:  {verdict}; ends on {edge} at r = {:.6} m, error {:.3e} m (tolerance {FEED_TOL_M} m; planned r = {:.6} m), {} steps",
            s.final_contact_radius_m, s.radius_error_m, s.planned_radius_m, s.sim_steps
        );
        if let Some(f) = &s.failure {
            let _ = writeln!(o, "  failure:    {f}");
        }
        if self.report.noise {
            let _ = writeln!(
                o,
                "  noise:      belt {:.6} m/s, fence mu {:.5} (the plan assumed the scene's values)",
                a.belt_speed_mps, a.fence_mu
            );
        }
        let _ = writeln!(o, "  planner:    wall {:.1} ms", 1e3 * s.wall_time_s);
        o
    }
}
