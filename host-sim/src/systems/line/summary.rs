//! Run summaries: convergence to the target apex, the detected period, resting contact,
//! timing; as human-readable text or one JSON object. The apex statistics are kept in
//! constant memory as the run goes ([`super::apexes::ApexStats`]).

pub use super::apexes::{converged_after, detect_period};
use super::outcome::{End, RunOutcome};
use super::scene::{ControlMode, Scene};
use crate::controller::HilReport;
use crate::controller::SafeSteps;
use serde::Serialize;

/// The summary of one run (the `--json` object).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Summary {
    /// Scene name.
    pub scene: String,
    /// Impacts simulated.
    pub impacts: u64,
    /// Control steps taken (0 without a controller).
    pub control_steps: u64,
    /// Simulated time, s.
    pub sim_time_s: f64,
    /// Wall-clock time, s.
    pub wall_time_s: f64,
    /// Target apex h*, m (null for a passive scene).
    pub target_apex_m: Option<f64>,
    /// Apex after the last impact, m (null without impacts, or if it is not finite: the
    /// run diverged).
    pub final_apex_m: Option<f64>,
    /// Impacts after which every apex stayed within `analysis.converge_tolerance` of the
    /// target (null if it never settled there, or did for fewer than 5 impacts).
    pub converged_after_impacts: Option<u64>,
    /// Period the apex sequence has settled to at the end, impacts ([`detect_period`];
    /// null if it has not settled to one, or rests).
    pub period: Option<u32>,
    /// True if the ball came to resting contact (a Zeno sequence) at any time.
    pub resting_contact: bool,
    /// Time the first resting contact began, s (the Zeno limit for a fixed table).
    pub resting_since_s: Option<f64>,
    /// Impacts before the first resting contact.
    pub resting_after_impacts: Option<u64>,
    /// True if a resting contact was forced by the cap `zeno.max_impacts_per_segment`
    /// rather than detected (present only then).
    #[serde(skip_serializing_if = "std::ops::Not::not")]
    pub resting_forced: bool,
    /// Grazing contacts (zero relative speed).
    pub grazing_contacts: u64,
    /// Which limit ended the run: `impacts` (the requested impacts), `duration` (the time
    /// limit), `resting` (the ball rests on a fixed table) or `diverged` (not finite).
    pub end: End,
    /// Control steps answered in the controller's safe state (`safe_steps`), and by fault
    /// (`faults`: fault name to count).
    #[serde(flatten)]
    pub safe: SafeSteps,
    /// HIL figures (only with `--hil`: attached by the run verb when it stops the target).
    #[serde(flatten, skip_serializing_if = "Option::is_none")]
    pub hil: Option<HilReport>,
}

impl Summary {
    /// Summarise `out`, a run of `scene`.
    pub fn new(scene: &Scene, out: &RunOutcome) -> Self {
        let target = (scene.control.mode != ControlMode::None)
            .then_some(scene.control.target_apex_m)
            .flatten();
        let first_rest = out.rests.first();
        Self {
            scene: scene.name().to_string(),
            impacts: out.impacts,
            control_steps: out.control_steps,
            sim_time_s: out.sim_time_s,
            wall_time_s: out.wall_time_s,
            target_apex_m: target,
            final_apex_m: out.apexes.last().filter(|a| a.is_finite()),
            converged_after_impacts: out.apexes.converged_after(),
            period: if out.resting_at_end {
                None
            } else {
                out.apexes.period()
            },
            resting_contact: out.rest_count > 0,
            resting_since_s: first_rest.map(|r| r.time_s),
            resting_after_impacts: first_rest.map(|r| r.after_impacts),
            resting_forced: out.rests.iter().any(|r| r.forced),
            grazing_contacts: out.grazing_contacts,
            end: out.end,
            safe: out.safe.clone(),
            hil: None,
        }
    }

    /// Which limit ended the run, in words.
    fn end_text(&self) -> &'static str {
        match self.end {
            End::Impacts => "at the requested impacts",
            End::Duration => "at the time limit (stop.duration_s)",
            End::Resting => "resting on the table (no impact follows)",
            End::Diverged => "diverged: the apex or the ball's state is not finite",
        }
    }

    /// One JSON object (indented).
    pub fn to_json(&self) -> String {
        serde_json::to_string_pretty(self).unwrap_or_else(|e| format!("{{\"error\": \"{e}\"}}"))
    }

    /// Human-readable summary.
    pub fn to_text(&self) -> String {
        let mut s = String::new();
        let opt = |v: Option<f64>| v.map_or("-".to_string(), |x| format!("{x:.6} m"));
        s += &format!("scene            {}\n", self.scene);
        s += &format!("target apex      {}\n", opt(self.target_apex_m));
        s += &format!(
            "final apex       {}\n",
            match self.end {
                End::Diverged => "not finite (diverged)".to_string(),
                _ => opt(self.final_apex_m),
            }
        );
        s += &format!(
            "converged (1 %)  {}\n",
            match (self.target_apex_m, self.converged_after_impacts) {
                (None, _) => "- (no target)".to_string(),
                (_, Some(n)) => format!("after {n} impacts"),
                (_, None) => "never".to_string(),
            }
        );
        s += &format!(
            "period           {}\n",
            self.period
                .map_or("not settled".to_string(), |p| p.to_string())
        );
        s += &format!(
            "resting contact  {}\n",
            match (self.resting_since_s, self.resting_after_impacts) {
                (Some(t), Some(n)) => format!("yes, from t = {t:.9} s after {n} impacts (Zeno)"),
                _ => "no".to_string(),
            }
        );
        if self.resting_forced {
            s +=
                "                 (forced: zeno.max_impacts_per_segment impacts within one step)\n";
        }
        s += &format!("impacts          {}\n", self.impacts);
        s += &format!("ended            {}\n", self.end_text());
        if self.control_steps > 0 {
            s += &format!("control steps    {}\n", self.control_steps);
        }
        s += &self.safe.text();
        s += &format!("sim time         {:.6} s\n", self.sim_time_s);
        s += &format!("wall time        {:.6} s\n", self.wall_time_s);
        if let Some(h) = &self.hil {
            s += &h.text();
        }
        s
    }
}
