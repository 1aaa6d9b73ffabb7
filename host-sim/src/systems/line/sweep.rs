//! `dexter sweep` on a line scene: the scene run at every value of one key, keeping the
//! last `--keep` apexes of each run: a bifurcation diagram (e.g. over
//! `control.kappa1_s2pm2`). CSV: `KEY,period,end,apex_height_m`, one row per kept apex:
//! the period the run's apexes settled to (empty if not settled: still converging near a
//! doubling, or aperiodic; see the summary's `period`) and which limit ended the run
//! (`impacts`, `duration`: the time limit cut it short, `resting`, `diverged`: one row with
//! no apex, since a diverged run's apexes are not finite).

use super::run::{run_streaming, End, RunError, RunOptions};
use super::scene::Scene;
use super::summary::Summary;
use super::LineSystem;
use crate::output::Sig17;
use crate::plot;
use crate::stream::{Decimator, Tail};
use crate::system::{Failure, SweepBase, SweepReport, Sweeps};
use std::io::Write;
use std::path::{Path, PathBuf};

/// The line scene's integer keys: a sweep gives them integers, as the other systems do.
const INTEGER_KEYS: [&str; 8] = [
    "stop.impacts",
    "control.stale_limit_steps",
    "control.estimator.reinit_after",
    "control.estimator.settle_samples",
    "sensor.seed",
    "jitter.seed",
    "zeno.max_impacts_per_segment",
    "analysis.max_period",
];

/// The TOML value of a swept number: an integer key keeps a whole value an integer (a
/// fractional or huge one stays a float, and the scene then names the key's type).
fn swept_value(key: &str, v: f64) -> toml::Value {
    if INTEGER_KEYS.contains(&key) && v.fract() == 0.0 && v.abs() < 9.0e15 {
        toml::Value::Integer(v as i64)
    } else {
        toml::Value::Float(v)
    }
}

/// One run of a sweep: its late apexes (m), settled period and end.
pub struct LatePoint {
    apexes: Vec<f64>,
    period: Option<u32>,
    end: End,
}

/// Run the scene `table` with `key` = `value`: its last `keep` apexes, its period and
/// what ended it.
fn late_point(
    table: &toml::Table,
    key: &str,
    value: f64,
    keep: usize,
) -> Result<LatePoint, RunError> {
    let mut t = table.clone();
    crate::scene::apply_set(&mut t, key, swept_value(key, value))?;
    let scene = Scene::from_table(t)?;
    let mut tail = Tail::new(keep);
    let out = run_streaming(&scene, &RunOptions::default(), None, &mut |r| {
        tail.push(r.apex_height_m)
    })?;
    Ok(LatePoint {
        apexes: tail.iter().copied().collect(),
        period: Summary::new(&scene, &out).period,
        end: out.end,
    })
}

/// Every end, for reading a name back.
const ENDS: [End; 4] = [End::Impacts, End::Duration, End::Resting, End::Diverged];

/// The estimated cost of a run with `key` = `value` (for the shards of a sweep or a basin
/// map): the run's length where the key sets it, else 1.
pub fn run_cost(key: &str, value: f64) -> f64 {
    match key {
        "stop.impacts" | "stop.duration_s" => value,
        _ => 1.0,
    }
}

/// The end's name in the CSV.
fn end_name(e: End) -> &'static str {
    match e {
        End::Impacts => "impacts",
        End::Duration => "duration",
        End::Resting => "resting",
        End::Diverged => "diverged",
    }
}

/// [`late_point`]'s apexes.
fn late_apexes(
    table: &toml::Table,
    key: &str,
    value: f64,
    keep: usize,
) -> Result<Vec<f64>, RunError> {
    Ok(late_point(table, key, value, keep)?.apexes)
}

/// Run `base` (a scene table, overrides applied) at every value of `range`, keeping the
/// last `keep` apex heights of each run: (value, apex) points, in order (serially; the CLI
/// runs the points on every core).
pub fn sweep(
    base: &toml::Table,
    range: &crate::grid::Range,
    keep: usize,
) -> Result<Vec<(f64, f64)>, RunError> {
    let mut points = Vec::new();
    for v in range.values() {
        let late = late_apexes(base, &range.key, v, keep)?;
        points.extend(late.into_iter().map(|a| (v, a)));
    }
    Ok(points)
}

/// What the bifurcation plot keeps.
pub struct LineSweepReport {
    key: String,
    stem: String,
    points: Decimator<(f64, f64)>,
}

impl Sweeps for LineSystem {
    type Point = LatePoint;
    type Report = LineSweepReport;

    fn point(base: &SweepBase<Self>, x: f64, _: Option<f64>) -> Result<LatePoint, Failure> {
        let late = late_point(&base.table, &base.grid.x.key, x, base.keep);
        late.map_err(|e| match e {
            RunError::Scene(s) => Failure::scene(s),
            other => Failure::run(other),
        })
    }

    fn report(base: &SweepBase<Self>) -> LineSweepReport {
        LineSweepReport {
            key: base.grid.x.key.clone(),
            stem: format!("{}-bifurcation", base.config.name()),
            points: Decimator::default(),
        }
    }

    const SHARDS: bool = true;

    fn cost(key: &str, value: f64) -> f64 {
        run_cost(key, value)
    }

    /// The rows `KEY,period,end,apex_height_m` of one run (none if it kept no apex).
    fn read_point(_: f64, _: Option<f64>, rows: &[String]) -> Result<LatePoint, String> {
        let mut p = LatePoint {
            apexes: Vec::with_capacity(rows.len()),
            period: None,
            end: End::Impacts,
        };
        for row in rows {
            let cells: Vec<&str> = row.split(',').collect();
            let [_, period, end, apex] = cells[..] else {
                return Err(format!("`{row}` has not 4 columns"));
            };
            p.period = match period {
                "" => None,
                q => Some(q.parse().map_err(|_| format!("bad period `{q}`"))?),
            };
            p.end = *ENDS
                .iter()
                .find(|e| end_name(**e) == end)
                .ok_or_else(|| format!("unknown end `{end}`"))?;
            if p.end != End::Diverged {
                p.apexes
                    .push(apex.parse().map_err(|_| format!("bad apex `{apex}`"))?);
            }
        }
        Ok(p)
    }
}

impl SweepReport<LineSystem> for LineSweepReport {
    fn csv_header(&self) -> String {
        format!("{},period,end,apex_height_m", self.key)
    }

    fn write_csv(
        &self,
        x: f64,
        _: Option<f64>,
        p: &LatePoint,
        w: &mut dyn Write,
    ) -> std::io::Result<()> {
        let period = p.period.map_or(String::new(), |q| q.to_string());
        let end = end_name(p.end);
        if p.end == End::Diverged {
            // one row, no apexes: a diverged run's are not finite
            return writeln!(w, "{},{period},{end},", Sig17(x));
        }
        for &a in &p.apexes {
            writeln!(w, "{},{period},{end},{}", Sig17(x), Sig17(a))?;
        }
        Ok(())
    }

    fn add(&mut self, x: f64, _: Option<f64>, p: LatePoint) {
        // a diverged run is plotted as its CSV shows it: without apexes
        if p.end == End::Diverged {
            return;
        }
        for a in p.apexes.into_iter().filter(|a| a.is_finite()) {
            self.points.push((x, a));
        }
    }

    fn summary(&self, _: Option<&Path>) -> Result<String, Failure> {
        Ok(String::new())
    }

    fn plot(&self, dir: &Path) -> Result<Vec<PathBuf>, Failure> {
        let label = plot::key_label(&self.key);
        Ok(super::plots::bifurcation(
            self.points.values(),
            &label,
            dir,
            &self.stem,
        )?)
    }
}
