//! `dexter sweep` on a feeder scene: one planned and simulated feed per value of any numeric
//! `[feeder]` key, in parallel, reported in serial order with the **fraction fed**. Over
//! `feeder.arrival.seed` (`--range feeder.arrival.seed=1:200:200`) every point is a random
//! arrival pose (x uniform in `feeder.arrival.x_range_m`, the angle uniform), so the
//! fraction is the fraction of random arrivals fed; with `[feeder.noise]` each arrival also
//! gets its own perturbation. A point whose plan does not exist counts as not fed (its
//! outcome is `no_plan`; the first reasons are printed); a bad value stops the sweep naming
//! the key.
//!
//! CSV: `KEY,arrival_x_m,arrival_y_m,arrival_angle_deg,start_edge,goal_edge,outcome,
//! final_edge,final_contact_radius_m,radius_error_m,plan_time_s,primitives,convergent_turns`
//! (`outcome`: `fed`, `missed` (ended on the wrong edge or outside the radius tolerance),
//! a simulation failure (`off_belt`, `past_pivot`, `off_fence_tip`, `too_long`) or
//! `no_plan`; empty cells where a value does not exist).

use super::{FeederConfig, FeederSystem};
use crate::model::feeder::execute::{plan_and_execute, Summary, FEED_TOL_M};
use crate::model::feeder::geometry::Pose;
use crate::model::feeder::sim::Failure as SimFailure;
use crate::model::feeder::FeederError;
use crate::output::Sig17;
use crate::plot::{key_label, Chart};
use crate::scene::SceneError;
use crate::stream::Decimator;
use crate::system::{Failure, SweepBase, SweepReport, Sweeps};
use std::fmt::Write as _;
use std::io::Write;
use std::path::{Path, PathBuf};

/// Keys whose values are integers.
const INTEGER_KEYS: [&str; 2] = ["feeder.arrival.seed", "feeder.noise.seed"];

/// Planner messages the summary prints at most.
const MAX_REASONS: usize = 5;

/// The TOML value for `key` = `v`.
fn value_for(key: &str, v: f64) -> Result<toml::Value, Failure> {
    if INTEGER_KEYS.contains(&key) {
        if v.fract() != 0.0 || v < 0.0 {
            return Err(Failure::scene(format!(
                "`{key}`: must be a non-negative integer, the range gives {v}"
            )));
        }
        return Ok(toml::Value::Integer(v as i64));
    }
    Ok(toml::Value::Float(v))
}

/// One swept value's feed.
pub struct FeederPoint {
    /// The arrival pose used (noise not applied).
    pub arrival: Pose,
    /// The plan and its execution, or why no plan exists.
    pub result: Result<Summary, String>,
}

impl FeederPoint {
    /// `fed`, `missed`, a simulation failure or `no_plan`.
    pub fn outcome(&self) -> &'static str {
        match &self.result {
            Err(_) => "no_plan",
            Ok(s) => match s.failure {
                Some(SimFailure::OffBelt { .. }) => "off_belt",
                Some(SimFailure::PastPivot { .. }) => "past_pivot",
                Some(SimFailure::OffFenceTip { .. }) => "off_fence_tip",
                Some(SimFailure::TooLong { .. }) => "too_long",
                None if s.reached_goal => "fed",
                None => "missed",
            },
        }
    }
}

fn point(base: &SweepBase<FeederSystem>, v: f64) -> Result<FeederPoint, Failure> {
    let key = &base.grid.x.key;
    let at = || format!("at {key} = {v}");
    let cfg =
        FeederConfig::from_table(&base.config.name, base.table_with(key, value_for(key, v)?)?)
            .map_err(|e| Failure::scene(e).at(at()))?;
    let b = &cfg.built;
    let result = match plan_and_execute(&b.feeder, b.arrival, &b.options, b.noise.as_ref()) {
        Ok(s) => Ok(s),
        Err(e @ FeederError::Infeasible(_)) => Err(e.to_string()),
        Err(e) => return Err(Failure::scene(e).at(at())),
    };
    Ok(FeederPoint {
        arrival: b.arrival,
        result,
    })
}

/// What the summary and the plot keep of the points.
pub struct FeederSweepReport {
    name: String,
    key: String,
    from: f64,
    to: f64,
    points: usize,
    fed: usize,
    on_goal_edge: usize,
    no_plan: usize,
    failures: usize,
    worst_fed_error_m: f64,
    reasons: Vec<String>,
    /// (arrival angle or swept value, arrival x) of fed and unfed points.
    fed_dots: Decimator<(f64, f64)>,
    unfed_dots: Decimator<(f64, f64)>,
}

impl Sweeps for FeederSystem {
    type Point = FeederPoint;
    type Report = FeederSweepReport;
    const KEEPS: bool = false;

    fn check_key(key: &str) -> Result<(), SceneError> {
        match key.starts_with("feeder.") {
            true => Ok(()),
            false => Err(SceneError::new(
                key,
                "a feeder sweep sweeps a key of the [feeder] table",
            )),
        }
    }

    fn point(base: &SweepBase<Self>, x: f64, _: Option<f64>) -> Result<FeederPoint, Failure> {
        point(base, x)
    }

    fn report(base: &SweepBase<Self>) -> FeederSweepReport {
        FeederSweepReport {
            name: base.config.name.clone(),
            key: base.grid.x.key.clone(),
            from: base.grid.x.from,
            to: base.grid.x.to,
            points: 0,
            fed: 0,
            on_goal_edge: 0,
            no_plan: 0,
            failures: 0,
            worst_fed_error_m: 0.0,
            reasons: Vec::new(),
            fed_dots: Decimator::default(),
            unfed_dots: Decimator::default(),
        }
    }
}

/// A CSV cell: the value, or empty.
fn cell(v: Option<f64>) -> String {
    v.map_or(String::new(), |x| Sig17(x).to_string())
}

impl SweepReport<FeederSystem> for FeederSweepReport {
    fn csv_header(&self) -> String {
        format!(
            "{},arrival_x_m,arrival_y_m,arrival_angle_deg,start_edge,goal_edge,outcome,final_edge,final_contact_radius_m,radius_error_m,plan_time_s,primitives,convergent_turns",
            self.key
        )
    }

    fn write_csv(
        &self,
        v: f64,
        _: Option<f64>,
        p: &FeederPoint,
        w: &mut dyn Write,
    ) -> std::io::Result<()> {
        let a = &p.arrival;
        let value = match INTEGER_KEYS.contains(&self.key.as_str()) {
            true => format!("{v}"),
            false => Sig17(v).to_string(),
        };
        write!(
            w,
            "{value},{},{},{},",
            Sig17(a.com_m.x),
            Sig17(a.com_m.y),
            Sig17(a.angle_rad.to_degrees())
        )?;
        let s = p.result.as_ref().ok();
        let int = |v: Option<usize>| v.map_or(String::new(), |e| e.to_string());
        writeln!(
            w,
            "{},{},{},{},{},{},{},{},{}",
            int(s.map(|s| s.start_edge)),
            int(s.map(|s| s.goal_edge)),
            p.outcome(),
            int(s.and_then(|s| s.final_edge)),
            cell(s.map(|s| s.final_contact_radius_m)),
            cell(s.map(|s| s.radius_error_m)),
            cell(s.map(|s| s.plan_time_s)),
            int(s.map(|s| s.plan.len())),
            int(s.map(|s| s.convergent_turns)),
        )
    }

    fn add(&mut self, v: f64, _: Option<f64>, p: FeederPoint) {
        self.points += 1;
        let outcome = p.outcome();
        let dot = match self.key.starts_with("feeder.arrival.") {
            true => (p.arrival.angle_rad.to_degrees(), p.arrival.com_m.x),
            false => (v, p.arrival.com_m.x),
        };
        match &p.result {
            Err(why) => {
                self.no_plan += 1;
                if self.reasons.len() < MAX_REASONS {
                    self.reasons.push(format!("{} = {v}: {why}", self.key));
                }
            }
            Ok(s) => {
                if s.failure.is_some() {
                    self.failures += 1;
                } else if s.final_edge == Some(s.goal_edge) {
                    self.on_goal_edge += 1;
                }
                if s.reached_goal {
                    self.fed += 1;
                    self.worst_fed_error_m = self.worst_fed_error_m.max(s.radius_error_m.abs());
                }
            }
        }
        match outcome {
            "fed" => self.fed_dots.push(dot),
            _ => self.unfed_dots.push(dot),
        }
    }

    fn summary(&self, csv: Option<&Path>) -> Result<String, Failure> {
        let n = self.points.max(1) as f64;
        let mut s = format!(
            "feeder sweep of {} over {} = {} .. {} ({} feeds)\n",
            self.name, self.key, self.from, self.to, self.points
        );
        let _ = writeln!(
            s,
            "  fraction fed: {}/{} = {:.4} (on the goal edge within {FEED_TOL_M} m of the goal radius)",
            self.fed,
            self.points,
            self.fed as f64 / n
        );
        let _ = writeln!(
            s,
            "  on the goal edge: {}; no plan: {}; left the belt or the fence: {}; worst |radius error| of the fed: {:.3e} m",
            self.on_goal_edge, self.no_plan, self.failures, self.worst_fed_error_m
        );
        for r in &self.reasons {
            let _ = writeln!(s, "  no plan at {r}");
        }
        if let Some(path) = csv {
            let _ = writeln!(s, "wrote {}", path.display());
        }
        Ok(s)
    }

    fn plot(&self, dir: &Path) -> Result<Vec<PathBuf>, Failure> {
        let arrival = self.key.starts_with("feeder.arrival.");
        let (x, y) = match arrival {
            true => ("arrival angle (deg)".to_string(), "arrival x (m)"),
            false => (key_label(&self.key), "arrival x (m)"),
        };
        let title = format!(
            "{}: fed {} of {} over {}",
            self.name, self.fed, self.points, self.key
        );
        let chart = Chart::new(title, x, y)
            .dots("fed", self.fed_dots.values().to_vec())
            .dots("not fed", self.unfed_dots.values().to_vec());
        Ok(chart.draw(dir, &format!("{}-sweep", self.name))?)
    }
}
