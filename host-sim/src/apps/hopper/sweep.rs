//! `dexter sweep` on a hopper scene: a bifurcation diagram over any `[hopper]` key.

use super::closed::{ClosedForm, ALPHA_DOUBLING};
use super::run::period_of;
use super::{end_name, load_table, set_key, Loaded};
use crate::apps::{AppError, AppSweep};
use crate::model::hopper::analysis::locate_first_doubling;
use crate::model::hopper::{HopperModel, RunEnd, RunOptions};
use crate::plot::{self, Series, Style};
use crate::sweep::Range;
use std::fmt::Write as _;

/// Hops per bisection probe of the doubling search (at least; `hopper.cycles` if larger).
pub const PROBE_CYCLES: usize = 100_000;
/// Bisection steps at most.
pub const MAX_BISECTIONS: u32 = 40;
/// Resolution of the doubling search, in alpha.
pub const ALPHA_RESOLUTION: f64 = 1e-6;

/// Keys whose values are integers.
const INTEGER_KEYS: [&str; 2] = ["hopper.cycles", "hopper.samples_per_phase"];

/// The TOML value for `key` = `v`.
fn value_for(key: &str, v: f64) -> Result<toml::Value, AppError> {
    if INTEGER_KEYS.contains(&key) {
        if v.fract() != 0.0 || v < 0.0 {
            return Err(AppError::Scene(format!(
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

struct Point {
    value: f64,
    alpha: Option<f64>,
    period: Option<usize>,
    end: RunEnd,
    /// Cycles dropped before the kept ones (`hopper.cycles` at this value).
    transient: usize,
    /// (bottom height, energy) of the kept cycles.
    kept: Vec<(f64, f64)>,
}

/// `dexter sweep` on a hopper scene.
pub fn sweep(args: &AppSweep) -> Result<(), AppError> {
    let range = Range::parse(&args.range).map_err(|e| AppError::Scene(e.to_string()))?;
    if args.keep == 0 {
        return Err(AppError::Scene("--keep must be >= 1".into()));
    }
    let table = load_table(&args.scene, &args.sets)?;
    let base = Loaded::from_table(table.clone(), &args.scene)?;
    let key = range.key.clone();
    let mut points = Vec::new();
    for v in range.values() {
        let mut t = table.clone();
        set_key(&mut t, &key, value_for(&key, v)?)?;
        let sc = Loaded::from_table(t, &args.scene).map_err(|e| match e {
            AppError::Scene(m) => AppError::Scene(format!("{m} (at {key} = {v})")),
            other => other,
        })?;
        let transient = sc.params.cycles;
        let opts = RunOptions {
            times: false,
            samples_per_phase: 0,
        };
        let mut kept = Vec::with_capacity(args.keep);
        let (end, _) = sc
            .hopper
            .run(sc.starts[0], transient + args.keep, &opts, &mut |c| {
                if c.index >= transient {
                    kept.push((c.bottom_height_m, c.energy));
                }
            })
            .map_err(|e| AppError::Scene(format!("{e} (at {key} = {v})")))?;
        let e: Vec<f64> = kept.iter().map(|p| p.1).collect();
        let alpha = ClosedForm::of(&sc).and_then(|c| c.alpha());
        points.push(Point {
            value: v,
            alpha,
            period: if kept.len() == args.keep {
                period_of(&e)
            } else {
                None
            },
            end,
            transient,
            kept,
        });
    }
    // CSV: one row per kept cycle
    let mut csv = format!("{key},alpha,period,end,cycle,bottom_height_m,energy\n");
    for p in &points {
        let alpha = p.alpha.map_or(String::new(), |a| format!("{a:.16e}"));
        let period = p.period.map_or(String::new(), |q| q.to_string());
        if p.kept.is_empty() {
            let _ = writeln!(
                csv,
                "{:.16e},{alpha},{period},{},,,",
                p.value,
                end_name(p.end)
            );
        }
        for (i, (x, e)) in p.kept.iter().enumerate() {
            let _ = writeln!(
                csv,
                "{:.16e},{alpha},{period},{},{},{x:.16e},{e:.16e}",
                p.value,
                end_name(p.end),
                p.transient + i
            );
        }
    }
    // the summary: periods per value, and the located doubling
    let mut summary = format!(
        "hopper sweep of {} over {key} = {} .. {} ({} values, {} hops transient, {} kept from the first start)\n",
        base.name,
        range.from,
        range.to,
        points.len(),
        if key == "hopper.cycles" {
            "(the swept value)".to_string()
        } else {
            base.params.cycles.to_string()
        },
        args.keep
    );
    for p in &points {
        let _ = writeln!(
            summary,
            "  {key} = {:<12} {}period {}{}",
            format!("{:.6}", p.value),
            p.alpha
                .map_or(String::new(), |a| format!("alpha = {a:.6}  ")),
            p.period.map_or("none".into(), |q| q.to_string()),
            if p.end == RunEnd::Completed {
                String::new()
            } else {
                format!(" (run ended: {})", end_name(p.end))
            }
        );
    }
    if key == "hopper.thrust_tau_mps2" && base.is_eq9_fixed() {
        summary += &locate(&base, &points)?;
    }
    match &args.csv {
        Some(path) => {
            super::create_parent(path)?;
            std::fs::write(path, &csv)
                .map_err(|e| AppError::Run(format!("cannot write {}: {e}", path.display())))?;
            print!("{summary}");
            println!("wrote {}", path.display());
        }
        None => {
            print!("{csv}");
            eprint!("{summary}");
        }
    }
    if let Some(dir) = &args.plot {
        let mut series = Vec::new();
        let dots: Vec<(f64, f64)> = points
            .iter()
            .flat_map(|p| p.kept.iter().map(move |k| (p.value, k.0)))
            .collect();
        series.push(Series {
            label: format!("late bottom heights x_n ({} per value)", args.keep),
            points: dots,
            style: Style::Dots,
        });
        if let (true, HopperModel::SimplifiedNonlinear(m)) = (
            key == "hopper.thrust_tau_mps2" && base.is_eq9_fixed(),
            base.hopper.model,
        ) {
            // the closed-form first doubling, alpha = e^2, as a vertical line
            let tau = m.thrust_for_alpha(ALPHA_DOUBLING);
            let xs = series[0]
                .points
                .iter()
                .map(|p| p.1)
                .filter(|v| v.is_finite());
            let (lo, hi) = xs.fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), v| {
                (a.min(v), b.max(v))
            });
            if lo <= hi {
                series.push(Series {
                    label: format!("closed form alpha = e^2: tau = {tau:.4} m/s^2"),
                    points: vec![(tau, lo), (tau, hi)],
                    style: Style::Line,
                });
            }
        }
        let files = plot::series(
            &format!("{}: bifurcation diagram over {key}", base.name),
            &param_label(&key),
            "late bottom height x_n (m)",
            &series,
            dir,
            &format!("{}-bifurcation", base.name),
        )
        .map_err(|e| AppError::Run(format!("plot: {e}")))?;
        for f in files {
            eprintln!("wrote {}", f.display());
        }
    }
    Ok(())
}

/// The key with its unit.
fn param_label(key: &str) -> String {
    let units = [
        ("_mps2", "m/s^2"),
        ("_mps", "m/s"),
        ("_per_s", "1/s"),
        ("_jpkg", "J/kg"),
        ("_m", "m"),
        ("_s", "s"),
    ];
    match units.iter().find(|(s, _)| key.ends_with(s)) {
        Some((_, u)) => format!("{key} ({u})"),
        None => key.to_string(),
    }
}

/// Locate the first period doubling of eq. 9 between the sweep's last period-1 value and the
/// next value of period >= 2 (ascending thrust).
fn locate(base: &Loaded, points: &[Point]) -> Result<String, AppError> {
    let mut sorted: Vec<&Point> = points.iter().collect();
    sorted.sort_by(|a, b| a.value.total_cmp(&b.value));
    // the last period-1 value below the first period >= 2 value; if the bisection rejects
    // the upper end (a slowly settling alternation just above e^2 can pass the sweep's
    // period test), the next period >= 2 values above it are tried in turn
    // values between them whose orbit has not settled (no period) are skipped
    let first_doubled = sorted.iter().position(|p| p.period.is_some_and(|q| q >= 2));
    let Some(i) = first_doubled.and_then(|j| sorted[..j].iter().rposition(|p| p.period == Some(1)))
    else {
        return Ok(format!(
            "  first period doubling: not bracketed in the range (no period-1 value below a period >= 2 value; closed form alpha = e^2 = {ALPHA_DOUBLING:.9})\n"
        ));
    };
    let HopperModel::SimplifiedNonlinear(m) = base.hopper.model else {
        return Ok(String::new());
    };
    let below = sorted[i].value;
    let resolution = m.thrust_for_alpha(ALPHA_RESOLUTION);
    let cycles = base.params.cycles.max(PROBE_CYCLES);
    let mut last_err = String::new();
    let mut found = None;
    for p in sorted[i + 1..]
        .iter()
        .filter(|p| p.period.is_some_and(|q| q >= 2))
        .take(8)
    {
        match locate_first_doubling(
            &base.hopper,
            base.starts[0],
            below,
            p.value,
            MAX_BISECTIONS,
            cycles,
            1e-10,
            resolution,
        ) {
            Ok(d) => {
                found = Some(d);
                break;
            }
            Err(e) => last_err = e.to_string(),
        }
    }
    let Some(d) = found else {
        return Ok(format!(
            "  first period doubling: could not be located from the bracket above {key_v} ({last_err}); closed form alpha = e^2 = {ALPHA_DOUBLING:.9}\n",
            key_v = below
        ));
    };
    let tau = d.estimate_mps2();
    let alpha = m.alpha(tau);
    Ok(format!(
        "  first period doubling located: thrust = {tau:.9} m/s^2, alpha = {alpha:.9} (closed form alpha = e^2 = {ALPHA_DOUBLING:.9}, difference {:.3e}; thrust e^2 eta1 / (chi_l mu) = {:.9} m/s^2)\n  bracket alpha in [{:.9}, {:.9}] after {} bisection steps of {cycles} hops each\n",
        alpha - ALPHA_DOUBLING,
        m.thrust_for_alpha(ALPHA_DOUBLING),
        m.alpha(d.below_mps2),
        m.alpha(d.above_mps2),
        d.steps
    ))
}
