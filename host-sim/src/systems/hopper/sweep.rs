//! `dexter sweep` on a hopper scene: a bifurcation diagram over any `[hopper]` key. Each
//! value runs the first start for `hopper.cycles` hops of transient, then keeps `--keep`
//! more (map-only runs). CSV: `KEY,alpha,period,end,cycle,bottom_height_m,energy`, one row
//! per kept cycle. Over the thrust of eq. 9 the first period doubling is located
//! ([`locate_first_doubling`]) and printed beside the closed form alpha = e^2.

use super::closed_forms::{ClosedForm, ALPHA_DOUBLING};
use super::summary::period_of;
use super::{end_name, HopperConfig, HopperSystem};
use crate::model::hopper::analysis::locate_first_doubling;
use crate::model::hopper::{HopperModel, RunEnd, RunOptions};
use crate::output::Sig17;
use crate::plot::{key_label, Chart};
use crate::stream::Decimator;
use crate::system::{Failure, SweepBase, SweepReport, Sweeps};
use std::fmt::Write as _;
use std::io::Write;
use std::path::{Path, PathBuf};

/// Hops per bisection probe of the doubling search (at least; `hopper.cycles` if larger).
pub const PROBE_CYCLES: usize = 100_000;
/// Bisection steps at most.
pub const MAX_BISECTIONS: u32 = 40;
/// Resolution of the doubling search, in alpha.
pub const ALPHA_RESOLUTION: f64 = 1e-6;

/// Keys whose values are integers.
const INTEGER_KEYS: [&str; 2] = ["hopper.cycles", "hopper.samples_per_phase"];

/// The TOML value for `key` = `v`.
fn value_for(key: &str, v: f64) -> Result<toml::Value, Failure> {
    if INTEGER_KEYS.contains(&key) {
        if v.fract() != 0.0 || v < 0.0 {
            return Err(Failure::scene(format!(
                "{key} must be a non-negative integer, the range gives {v}"
            )));
        }
        return Ok(toml::Value::Integer(v as i64));
    }
    if key == "hopper.initial_heights_m" {
        return Ok(toml::Value::Array(vec![toml::Value::Float(v)]));
    }
    Ok(toml::Value::Float(v))
}

/// Every run end, for reading a name back.
const RUN_ENDS: [RunEnd; 5] = [
    RunEnd::Completed,
    RunEnd::NoLiftoff,
    RunEnd::WeakThrust,
    RunEnd::StepCap,
    RunEnd::NonFinite,
];

/// One swept value.
pub struct HopperPoint {
    alpha: Option<f64>,
    period: Option<usize>,
    end: RunEnd,
    /// Cycles dropped before the kept ones (`hopper.cycles` at this value).
    transient: usize,
    /// (bottom height, energy) of the kept cycles.
    kept: Vec<(f64, f64)>,
}

/// The run of one value.
fn late_cycles(base: &SweepBase<HopperSystem>, v: f64) -> Result<HopperPoint, Failure> {
    let key = &base.grid.x.key;
    let sc = HopperConfig::from_table(&base.config.name, base.table_with(key, value_for(key, v)?)?)
        .map_err(|e| Failure::scene(e).at(format!("at {key} = {v}")))?;
    let transient = sc.params.cycles;
    let opts = RunOptions {
        times: false,
        samples_per_phase: 0,
    };
    let mut kept = Vec::with_capacity(base.keep);
    let (end, _) = sc
        .hopper
        .run(sc.starts[0], transient + base.keep, &opts, &mut |c| {
            if c.index >= transient {
                kept.push((c.bottom_height_m, c.energy));
            }
        })
        .map_err(|e| Failure::scene(e).at(format!("at {key} = {v}")))?;
    let e: Vec<f64> = kept.iter().map(|p| p.1).collect();
    Ok(HopperPoint {
        alpha: ClosedForm::of(&sc).and_then(|c| c.alpha()),
        period: (kept.len() == base.keep)
            .then(|| period_of(&e, e.len()))
            .flatten(),
        end,
        transient,
        kept,
    })
}

/// What the summary and the bifurcation plot keep.
pub struct HopperSweepReport {
    base: HopperConfig,
    key: String,
    from: f64,
    to: f64,
    keep: usize,
    /// (value, alpha, period, end) per point, in order.
    points: Vec<(f64, Option<f64>, Option<usize>, RunEnd)>,
    dots: Decimator<(f64, f64)>,
}

impl Sweeps for HopperSystem {
    type Point = HopperPoint;
    type Report = HopperSweepReport;

    fn point(base: &SweepBase<Self>, x: f64, _: Option<f64>) -> Result<HopperPoint, Failure> {
        late_cycles(base, x)
    }

    const SHARDS: bool = true;

    fn cost(key: &str, value: f64) -> f64 {
        match key {
            "hopper.cycles" => value,
            _ => 1.0,
        }
    }

    /// The rows `KEY,alpha,period,end,cycle,bottom_height_m,energy` of one value (one row
    /// with empty cycle cells if it kept none).
    fn read_point(_: f64, _: Option<f64>, rows: &[String]) -> Result<HopperPoint, String> {
        let num = |s: &str| s.parse::<f64>().map_err(|_| format!("bad number `{s}`"));
        let mut p = HopperPoint {
            alpha: None,
            period: None,
            end: RunEnd::Completed,
            transient: 0,
            kept: Vec::with_capacity(rows.len()),
        };
        for (i, row) in rows.iter().enumerate() {
            let cells: Vec<&str> = row.split(',').collect();
            let [_, alpha, period, end, cycle, x, e] = cells[..] else {
                return Err(format!("`{row}` has not the hopper sweep's 7 columns"));
            };
            p.alpha = (!alpha.is_empty()).then(|| num(alpha)).transpose()?;
            p.period = match period {
                "" => None,
                q => Some(q.parse().map_err(|_| format!("bad period `{q}`"))?),
            };
            p.end = *RUN_ENDS
                .iter()
                .find(|r| end_name(**r) == end)
                .ok_or_else(|| format!("unknown end `{end}`"))?;
            if cycle.is_empty() {
                continue;
            }
            let c: usize = cycle.parse().map_err(|_| format!("bad cycle `{cycle}`"))?;
            if i == 0 {
                p.transient = c;
            }
            p.kept.push((num(x)?, num(e)?));
        }
        Ok(p)
    }

    fn report(base: &SweepBase<Self>) -> HopperSweepReport {
        HopperSweepReport {
            base: base.config.clone(),
            key: base.grid.x.key.clone(),
            from: base.grid.x.from,
            to: base.grid.x.to,
            keep: base.keep,
            points: Vec::new(),
            dots: Decimator::default(),
        }
    }
}

impl SweepReport<HopperSystem> for HopperSweepReport {
    fn csv_header(&self) -> String {
        format!("{},alpha,period,end,cycle,bottom_height_m,energy", self.key)
    }

    fn write_csv(
        &self,
        v: f64,
        _: Option<f64>,
        p: &HopperPoint,
        w: &mut dyn Write,
    ) -> std::io::Result<()> {
        let alpha = p.alpha.map_or(String::new(), |a| Sig17(a).to_string());
        let period = p.period.map_or(String::new(), |q| q.to_string());
        let end = end_name(p.end);
        if p.kept.is_empty() {
            writeln!(w, "{},{alpha},{period},{end},,,", Sig17(v))?;
        }
        for (i, (x, e)) in p.kept.iter().enumerate() {
            let cycle = p.transient + i;
            writeln!(
                w,
                "{},{alpha},{period},{end},{cycle},{},{}",
                Sig17(v),
                Sig17(*x),
                Sig17(*e)
            )?;
        }
        Ok(())
    }

    fn add(&mut self, v: f64, _: Option<f64>, p: HopperPoint) {
        self.points.push((v, p.alpha, p.period, p.end));
        for k in &p.kept {
            self.dots.push((v, k.0));
        }
    }

    fn summary(&self, csv: Option<&Path>) -> Result<String, Failure> {
        let mut s = format!(
            "hopper sweep of {} over {} = {} .. {} ({} values, {} hops transient, {} kept from the first start)\n",
            self.base.name,
            self.key,
            self.from,
            self.to,
            self.points.len(),
            if self.key == "hopper.cycles" {
                "(the swept value)".to_string()
            } else {
                self.base.params.cycles.to_string()
            },
            self.keep
        );
        for &(v, alpha, period, end) in &self.points {
            let _ = writeln!(
                s,
                "  {} = {:<12} {}period {}{}",
                self.key,
                format!("{v:.6}"),
                alpha.map_or(String::new(), |a| format!("alpha = {a:.6}  ")),
                period.map_or("not settled".into(), |q| q.to_string()),
                if end == RunEnd::Completed {
                    String::new()
                } else {
                    format!(" (run ended: {})", end_name(end))
                }
            );
        }
        if self.over_eq9_thrust() {
            s += &self.locate();
        }
        if let Some(path) = csv {
            s += &format!("wrote {}\n", path.display());
        }
        Ok(s)
    }

    fn plot(&self, dir: &Path) -> Result<Vec<PathBuf>, Failure> {
        let points = self.dots.values().to_vec();
        let mut xs = points.iter().map(|p| p.1).filter(|v| v.is_finite());
        let first = xs.next();
        let range = first.map(|f| xs.fold((f, f), |(a, b), v| (a.min(v), b.max(v))));
        let title = format!("{}: bifurcation diagram over {}", self.base.name, self.key);
        let mut chart = Chart::new(title, key_label(&self.key), "late bottom height x_n (m)").dots(
            format!("late bottom heights x_n ({} per value)", self.keep),
            points,
        );
        if let (true, HopperModel::SimplifiedNonlinear(m), Some((lo, hi))) =
            (self.over_eq9_thrust(), self.base.hopper.model, range)
        {
            // the closed-form first doubling, alpha = e^2, as a vertical line
            let tau = m.thrust_for_alpha(ALPHA_DOUBLING);
            let label = format!("closed form alpha = e^2: tau = {tau:.4} m/s^2");
            chart = chart.line(label, vec![(tau, lo), (tau, hi)]);
        }
        Ok(chart.draw(dir, &format!("{}-bifurcation", self.base.name))?)
    }
}

impl HopperSweepReport {
    /// True if the sweep is over the thrust of eq. 9 with fixed thrust.
    fn over_eq9_thrust(&self) -> bool {
        self.key == "hopper.thrust_tau_mps2" && self.base.is_eq9_fixed()
    }

    /// Locate the first period doubling of eq. 9 between the sweep's last period-1 value
    /// and the next value of period >= 2 (ascending thrust).
    fn locate(&self) -> String {
        let mut sorted: Vec<(f64, Option<usize>)> =
            self.points.iter().map(|p| (p.0, p.2)).collect();
        sorted.sort_by(|a, b| a.0.total_cmp(&b.0));
        // the last period-1 value below the first period >= 2 value; if the bisection
        // rejects the upper end (a slowly settling alternation just above e^2 can pass the
        // sweep's period test), the next period >= 2 values above it are tried in turn;
        // values between them whose orbit has not settled (no period) are skipped
        let doubled = |p: &(f64, Option<usize>)| p.1.is_some_and(|q| q >= 2);
        let first_doubled = sorted.iter().position(doubled);
        let Some(i) = first_doubled.and_then(|j| sorted[..j].iter().rposition(|p| p.1 == Some(1)))
        else {
            return format!(
                "  first period doubling: not bracketed in the range (no period-1 value below a period >= 2 value; closed form alpha = e^2 = {ALPHA_DOUBLING:.9})\n"
            );
        };
        let HopperModel::SimplifiedNonlinear(m) = self.base.hopper.model else {
            return String::new();
        };
        let below = sorted[i].0;
        let cycles = self.base.params.cycles.max(PROBE_CYCLES);
        let mut last_err = String::new();
        for &(above, _) in sorted[i + 1..].iter().filter(|p| doubled(p)).take(8) {
            match locate_first_doubling(
                &self.base.hopper,
                self.base.starts[0],
                below,
                above,
                MAX_BISECTIONS,
                cycles,
                1e-10,
                m.thrust_for_alpha(ALPHA_RESOLUTION),
            ) {
                Ok(d) => {
                    let tau = d.estimate_mps2();
                    let alpha = m.alpha(tau);
                    return format!(
                        "  first period doubling located: thrust = {tau:.9} m/s^2, alpha = {alpha:.9} (closed form alpha = e^2 = {ALPHA_DOUBLING:.9}, difference {:.3e}; thrust e^2 eta1 / (chi_l mu) = {:.9} m/s^2)\n  bracket alpha in [{:.9}, {:.9}] after {} bisection steps of {cycles} hops each\n",
                        alpha - ALPHA_DOUBLING,
                        m.thrust_for_alpha(ALPHA_DOUBLING),
                        m.alpha(d.below_mps2),
                        m.alpha(d.above_mps2),
                        d.steps
                    );
                }
                Err(e) => last_err = e.to_string(),
            }
        }
        format!(
            "  first period doubling: could not be located from the bracket above {below} ({last_err}); closed form alpha = e^2 = {ALPHA_DOUBLING:.9}\n"
        )
    }
}
