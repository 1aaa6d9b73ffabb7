//! `dexter run` on a hopper scene.

use super::closed::{ClosedForm, ALPHA_DOUBLING};
use super::{
    end_name, load_table, model_equation, model_name, set_key, start_height, start_text, Loaded,
    MAX_RUN_CYCLES, PERIOD_TOL,
};
use crate::apps::{AppError, AppRun};
use crate::model::hopper::analysis::{bottom_heights, detect_period, energies, MAX_PERIOD};
use crate::model::hopper::params::ModelKind;
use crate::model::hopper::{Run, Start, MAX_SAMPLES};
use crate::plot::{self, Series, Style};
use serde_json::{json, Value};
use std::io::Write;
use std::path::Path;
use std::time::Instant;

/// Late values reported per trajectory.
pub const LATE: usize = 8;

/// One simulated trajectory.
struct Trajectory {
    start: Start,
    run: Run,
    period: Option<usize>,
}

impl Trajectory {
    fn late<T: Copy>(v: &[T]) -> Vec<T> {
        v[v.len().saturating_sub(LATE)..].to_vec()
    }
    fn x(&self) -> Vec<f64> {
        bottom_heights(&self.run.cycles)
    }
    fn e(&self) -> Vec<f64> {
        energies(&self.run.cycles)
    }
    fn sim_time_s(&self) -> f64 {
        self.run
            .cycles
            .last()
            .map_or(0.0, |c| c.next_touchdown.time_s)
    }
    fn apex_m(&self) -> f64 {
        self.run.cycles.last().map_or(f64::NAN, |c| c.apex.height_m)
    }
    fn json(&self, i: usize) -> Value {
        json!({
            "trajectory": i + 1,
            "initial_height_m": start_height(&self.start),
            "start": start_text(&self.start),
            "cycles": self.run.cycles.len(),
            "end": end_name(self.run.end),
            "period": self.period,
            "late_bottom_heights_m": Self::late(&self.x()),
            "late_energies": Self::late(&self.e()),
            "apex_height_m": self.apex_m(),
            "sim_time_s": self.sim_time_s(),
            "integrator_steps": self.run.steps,
            "early_liftoffs": self.run.cycles.iter().filter(|c| c.early_liftoff).count(),
        })
    }
}

/// Largest relative change of a period-p orbit's spread (max - min over p values) across
/// the last [`SETTLE_WINDOW`] values for the orbit to count as settled.
pub const SETTLE_REL: f64 = 1e-6;
/// Values over which a period >= 2 must hold its spread.
pub const SETTLE_WINDOW: usize = 64;

/// The period of a sequence of energies: `detect_period` (tolerance [`PERIOD_TOL`]); a
/// period p >= 2 must also hold its spread (near a doubling a slowly decaying
/// alternation passes the period-2 test), else `None` (not settled).
pub(crate) fn period_of(e: &[f64]) -> Option<usize> {
    let p = detect_period(e, MAX_PERIOD.min(e.len() / 3).max(1), PERIOD_TOL)?;
    if p == 1 {
        return Some(1);
    }
    let n = e.len();
    let w = SETTLE_WINDOW.max(2 * p).min(n);
    let spread = |a: usize| {
        let s = &e[a..a + p];
        s.iter().copied().fold(f64::NEG_INFINITY, f64::max)
            - s.iter().copied().fold(f64::INFINITY, f64::min)
    };
    let (first, last) = (spread(n - w), spread(n - p));
    ((last - first).abs() <= SETTLE_REL * last.abs()).then_some(p)
}

/// `dexter run` on a hopper scene.
pub fn run(args: &AppRun) -> Result<(), AppError> {
    let mut table = load_table(&args.scene, &args.sets)?;
    if let Some(n) = args.impacts {
        if n == 0 || n > MAX_RUN_CYCLES {
            return Err(AppError::Scene(format!(
                "--impacts (hopper.cycles) must be in 1..={MAX_RUN_CYCLES}, got {n}"
            )));
        }
        set_key(&mut table, "hopper.cycles", toml::Value::Integer(n as i64))?;
    }
    let sc = Loaded::from_table(table, &args.scene)?;
    if sc.params.cycles as u64 > MAX_RUN_CYCLES {
        return Err(AppError::Scene(format!(
            "hopper.cycles must be <= {MAX_RUN_CYCLES} for run"
        )));
    }
    let mut opts = sc.params.run_options();
    if args.plot.is_some() && opts.samples_per_phase == 0 {
        // dense samples for the phase portrait, within the global cap
        opts.samples_per_phase = (MAX_SAMPLES / (5 * sc.params.cycles + 5)).clamp(2, 64);
    }
    let wall = Instant::now();
    let mut trajs = Vec::new();
    for &start in &sc.starts {
        let run = sc
            .hopper
            .simulate(start, sc.params.cycles, &opts)
            .map_err(|e| AppError::Scene(e.to_string()))?;
        let period = period_of(&energies(&run.cycles));
        trajs.push(Trajectory { start, run, period });
    }
    let wall_s = wall.elapsed().as_secs_f64();
    let closed = ClosedForm::of(&sc);
    if let Some(path) = &args.trace {
        write_trace(path, &trajs)?;
    }
    let mut written = Vec::new();
    if let Some(dir) = &args.plot {
        written = write_plots(&sc, closed.as_ref(), &trajs, dir)?;
    }
    if args.json {
        println!("{}", summary_json(&sc, closed.as_ref(), &trajs, wall_s));
    } else {
        print!("{}", summary_text(&sc, closed.as_ref(), &trajs, wall_s));
    }
    for p in written {
        eprintln!("wrote {}", p.display());
    }
    if let Some(path) = &args.trace {
        eprintln!("wrote {}", path.display());
    }
    Ok(())
}

fn closed_json(sc: &Loaded, cf: Option<&ClosedForm>) -> Value {
    let Some(cf) = cf else {
        return Value::Null;
    };
    let Some(e) = cf.fixed_energy() else {
        return Value::Null;
    };
    let slope = cf.fixed_slope().unwrap_or(f64::NAN);
    let mut v = json!({
        "equation": cf.equation(),
        "exact": cf.exact(),
        "energy": e,
        "bottom_height_m": cf.bottom_of(e),
        "slope": slope,
        "stable": slope.abs() < 1.0,
    });
    if let (Some((p, q)), Some(o)) = (cf.two_cycle(), v.as_object_mut()) {
        o.insert(
            "two_cycle".into(),
            json!({
                "energies": [p, q],
                "bottom_heights_m": [cf.bottom_of(p), cf.bottom_of(q)],
            }),
        );
    }
    if let (super::closed::ClosedForm::Eq17 { detuning_m, .. }, Some(o)) = (cf, v.as_object_mut()) {
        o.insert("detuning_m".into(), json!(detuning_m));
    }
    let _ = sc;
    v
}

fn energy_unit(m: ModelKind) -> &'static str {
    match m {
        ModelKind::Linear => "m^2/s^2 (eq. 17: eta1 (x - chi_eq)^2)",
        _ => "1 (eq. 18: ln(chi_l / x))",
    }
}

fn summary_json(sc: &Loaded, cf: Option<&ClosedForm>, trajs: &[Trajectory], wall_s: f64) -> Value {
    let t0 = &trajs[0];
    let alpha = cf.and_then(|c| c.alpha());
    json!({
        "scene": sc.name,
        "model": model_name(sc.params.model),
        "equation": model_equation(sc.params.model),
        "thrust_tau_mps2": sc.params.thrust_tau_mps2,
        "thrust_delta_s": sc.params.thrust_delta_s,
        "energy_servo": sc.params.servo.is_some(),
        "liftoff_height_m": sc.params.liftoff_height_m,
        "alpha": alpha,
        "alpha_doubling": alpha.map(|_| ALPHA_DOUBLING),
        "fixed_point_closed_form": closed_json(sc, cf),
        "energy_unit": energy_unit(sc.params.model),
        "cycles": t0.run.cycles.len(),
        "period": t0.period,
        "late_bottom_heights_m": Trajectory::late(&t0.x()),
        "late_energies": Trajectory::late(&t0.e()),
        "apex_height_m": t0.apex_m(),
        "sim_time_s": t0.sim_time_s(),
        "wall_time_s": wall_s,
        "end": end_name(t0.run.end),
        "trajectories": trajs.iter().enumerate().map(|(i, t)| t.json(i)).collect::<Vec<_>>(),
    })
}

fn g(v: f64) -> String {
    format!("{v:.10}")
}

fn summary_text(sc: &Loaded, cf: Option<&ClosedForm>, trajs: &[Trajectory], wall_s: f64) -> String {
    let p = &sc.params;
    let mut s = format!(
        "hopper scene {}: {} model ({})\n  thrust tau = {} m/s^2 for delta = {} s{}\n",
        sc.name,
        model_name(p.model),
        model_equation(p.model),
        p.thrust_tau_mps2,
        p.thrust_delta_s,
        if p.servo.is_some() {
            " (energy servo: tau is the nominal thrust)"
        } else {
            ""
        }
    );
    match cf {
        Some(c @ ClosedForm::Eq19 { alpha, .. }) => {
            s += &format!(
                "  alpha = tau chi_l mu / eta1 = {alpha:.6} ({} e^2 = {ALPHA_DOUBLING:.6}, the first period doubling)\n",
                if *alpha < ALPHA_DOUBLING { "<" } else { ">=" }
            );
            match c.fixed_energy() {
                Some(e) => {
                    let sl = c.fixed_slope().unwrap_or(f64::NAN);
                    s += &format!(
                        "  closed form (eq. 15/19): x* = chi_l / alpha = {} m, E* = ln alpha = {}, slope 1 - ln alpha = {sl:.6} ({})\n",
                        g(c.bottom_of(e)),
                        g(e),
                        if sl.abs() < 1.0 { "stable" } else { "unstable" }
                    );
                }
                None => {
                    s += "  closed form: alpha <= 1, no hopping fixed point (the hopper stops)\n"
                }
            }
            if let Some((a, b)) = c.two_cycle() {
                s += &format!(
                    "  closed-form 2-cycle: E = {} / {} (sum 2 ln alpha = {}), x = {} / {} m\n",
                    g(a),
                    g(b),
                    g(a + b),
                    g(c.bottom_of(a)),
                    g(c.bottom_of(b))
                );
            }
        }
        Some(c @ ClosedForm::Eq17 { detuning_m, .. }) => {
            let tuned = if c.exact() {
                "tuned, exact".to_string()
            } else {
                format!("untuned by chi_l - chi_eq = {detuning_m:.6} m, so only approximate")
            };
            match c.fixed_energy() {
                Some(e) => {
                    s += &format!(
                        "  closed form (eq. 17, {tuned}): E* = {} m^2/s^2, x* = {} m, slope f'(E*) = {:.6}\n",
                        g(e),
                        g(c.bottom_of(e)),
                        c.fixed_slope().unwrap_or(f64::NAN)
                    );
                }
                None => s += &format!("  closed form (eq. 17, {tuned}): no interior fixed point\n"),
            }
        }
        None => s += &format!("  closed form: {}\n", super::closed::none_reason(sc)),
    }
    for (i, t) in trajs.iter().enumerate() {
        let x = t.x();
        let e = t.e();
        s += &format!(
            "  trajectory {} from {}: {} cycles, end {}\n",
            i + 1,
            start_text(&t.start),
            t.run.cycles.len(),
            end_name(t.run.end)
        );
        if x.is_empty() {
            continue;
        }
        let period = t
            .period
            .map_or("none detected (not settled or aperiodic)".into(), |p| {
                p.to_string()
            });
        s += &format!("    period {period}\n");
        let k = t.period.unwrap_or(1).min(x.len());
        let late_x: Vec<String> = x[x.len() - k..].iter().map(|v| g(*v)).collect();
        let late_e: Vec<String> = e[e.len() - k..].iter().map(|v| g(*v)).collect();
        s += &format!(
            "    late bottoms x_n = {} m, energies E_n = {}\n",
            late_x.join(" / "),
            late_e.join(" / ")
        );
        if let (Some(c), Some(1)) = (cf, t.period) {
            if let Some(es) = c.fixed_energy() {
                s += &format!(
                    "    vs closed form: x_n - x* = {:.3e} m, E_n - E* = {:.3e}\n",
                    x[x.len() - 1] - c.bottom_of(es),
                    e[e.len() - 1] - es
                );
            }
        }
        if let (Some(c), Some(2)) = (cf, t.period) {
            if let Some(a) = c.alpha() {
                s += &format!(
                    "    vs closed form: E_n + E_n-1 - 2 ln alpha = {:.3e}\n",
                    e[e.len() - 1] + e[e.len() - 2] - 2.0 * a.ln()
                );
            }
        }
        s += &format!(
            "    apex {} m, sim time {:.6} s{}\n",
            g(t.apex_m()),
            t.sim_time_s(),
            if t.run.steps > 0 {
                format!(", {} integrator steps", t.run.steps)
            } else {
                String::new()
            }
        );
    }
    s += &format!("  wall time {:.3} ms\n", wall_s * 1e3);
    s
}

fn io_err(path: &Path, e: std::io::Error) -> AppError {
    AppError::Run(format!("cannot write {}: {e}", path.display()))
}

/// The per-cycle CSV (columns in docs/hopper.md).
fn write_trace(path: &Path, trajs: &[Trajectory]) -> Result<(), AppError> {
    super::create_parent(path)?;
    let file = std::fs::File::create(path).map_err(|e| io_err(path, e))?;
    let mut w = std::io::BufWriter::new(file);
    let f = |v: f64| format!("{v:.16e}");
    let mut out = String::from(
        "trajectory,cycle,thrust_mps2,touchdown_time_s,touchdown_velocity_mps,touchdown_energy_jpkg,\
bottom_time_s,bottom_height_m,energy,end_of_thrust_time_s,end_of_thrust_height_m,\
end_of_thrust_velocity_mps,liftoff_time_s,liftoff_velocity_before_mps,liftoff_velocity_mps,\
apex_time_s,apex_height_m,next_touchdown_time_s,early_liftoff,dissipating\n",
    );
    for (i, t) in trajs.iter().enumerate() {
        for c in &t.run.cycles {
            let (tt, tv) = c.touchdown.map_or((String::new(), String::new()), |td| {
                (f(td.time_s), f(td.velocity_mps))
            });
            out += &format!(
                "{},{},{},{tt},{tv},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{}\n",
                i + 1,
                c.index,
                f(c.thrust_mps2),
                f(c.touchdown_energy_jpkg),
                f(c.bottom.time_s),
                f(c.bottom_height_m),
                f(c.energy),
                f(c.end_of_thrust.time_s),
                f(c.end_of_thrust.height_m),
                f(c.end_of_thrust.velocity_mps),
                f(c.liftoff.time_s),
                f(c.liftoff_velocity_before_mps),
                f(c.liftoff.velocity_mps),
                f(c.apex.time_s),
                f(c.apex.height_m),
                f(c.next_touchdown.time_s),
                c.early_liftoff,
                c.dissipating
            );
        }
        w.write_all(out.as_bytes()).map_err(|e| io_err(path, e))?;
        out.clear();
    }
    w.write_all(out.as_bytes()).map_err(|e| io_err(path, e))?;
    w.flush().map_err(|e| io_err(path, e))
}

/// Palette slots (plot::series colours series by index): simulated dots take the first
/// (red, green), the closed form the fourth (blue), the identity the fifth (orange).
const CURVE_SLOT: usize = 3;
const IDENTITY_SLOT: usize = 4;

/// Push `s` as series number `slot` (padding with empty, unlabelled series), or last if
/// the slot is taken.
fn push_at(series: &mut Vec<Series>, slot: usize, s: Series) {
    while series.len() < slot {
        series.push(Series {
            label: String::new(),
            points: Vec::new(),
            style: Style::Line,
        });
    }
    series.push(s);
}

/// `n` points evenly spaced over [a, b].
fn linspace(a: f64, b: f64, n: usize) -> Vec<f64> {
    (0..n)
        .map(|i| a + (b - a) * i as f64 / (n - 1) as f64)
        .collect()
}

fn finite_range(v: impl Iterator<Item = f64>) -> Option<(f64, f64)> {
    let (lo, hi) = v
        .filter(|x| x.is_finite())
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), x| {
            (a.min(x), b.max(x))
        });
    (lo <= hi).then_some((lo, hi))
}

fn plot_err(e: plot::PlotError) -> AppError {
    AppError::Run(format!("plot: {e}"))
}

/// Return map (x), energy map (E) and phase portrait.
/// One dotted series of successive pairs (v_n, v_{n+1}) per trajectory, and every
/// coordinate of them (for the axis range).
fn successive_pairs(
    trajs: &[Trajectory],
    values: fn(&Trajectory) -> Vec<f64>,
    label: &dyn Fn(&Trajectory) -> String,
) -> (Vec<Series>, Vec<f64>) {
    let mut series = Vec::new();
    let mut all = Vec::new();
    for t in trajs {
        let pts: Vec<(f64, f64)> = values(t).windows(2).map(|w| (w[0], w[1])).collect();
        all.extend(pts.iter().flat_map(|p| [p.0, p.1]));
        series.push(Series {
            label: label(t),
            points: pts,
            style: Style::Dots,
        });
    }
    (series, all)
}

fn write_plots(
    sc: &Loaded,
    cf: Option<&ClosedForm>,
    trajs: &[Trajectory],
    dir: &Path,
) -> Result<Vec<std::path::PathBuf>, AppError> {
    let mut written = Vec::new();
    let multi = trajs.len() > 1;
    let label = |t: &Trajectory| {
        if multi {
            format!("simulated, from {}", start_text(&t.start))
        } else {
            "simulated".to_string()
        }
    };
    let chi_l = sc.params.liftoff_height_m;
    // the bottom-height return map x_{n+1} vs x_n
    let (mut series, all) = successive_pairs(trajs, Trajectory::x, &label);
    if let Some((lo, hi)) = finite_range(all.iter().copied()) {
        let pad = 0.15 * (hi - lo).max(1e-3 * hi.abs().max(1e-3));
        let (mut a, mut b) = (lo - pad, hi + pad);
        let curve_label = match cf {
            Some(ClosedForm::Eq19 { .. }) => {
                // the unimodal map on its whole domain (0, chi_l)
                a = a.min(1e-4 * chi_l).max(1e-6 * chi_l);
                b = b.max(chi_l).min(chi_l);
                Some("eq. 15: g(x) = chi_l exp(-(tau mu / eta1) x ln(chi_l / x))".to_string())
            }
            Some(c @ ClosedForm::Eq17 { .. }) => Some(if c.exact() {
                "eq. 17 (tuned), in x = chi_eq - sqrt(E / eta1)".to_string()
            } else {
                "eq. 17 with this scene's omega, beta, delta, tau - g (scene untuned: approximate)"
                    .to_string()
            }),
            None => None,
        };
        let xs = linspace(a, b, 600);
        if let (Some(c), Some(l)) = (cf, curve_label) {
            push_at(
                &mut series,
                CURVE_SLOT,
                Series {
                    label: l,
                    points: xs.iter().map(|&x| (x, c.bottom_map(x))).collect(),
                    style: Style::Line,
                },
            );
        }
        push_at(
            &mut series,
            IDENTITY_SLOT,
            Series {
                label: "identity x(n+1) = x(n)".into(),
                points: vec![(a, a), (b, b)],
                style: Style::Line,
            },
        );
        written.extend(
            plot::series(
                &format!("{}: return map of bottom heights", sc.name),
                "x(n), bottom height (m)",
                "x(n+1) (m)",
                &series,
                dir,
                &format!("{}-return-map", sc.name),
            )
            .map_err(plot_err)?,
        );
    } else {
        eprintln!("warning: fewer than two cycles, no return map plotted");
    }
    // the energy map E_{n+1} vs E_n
    let (mut series, all) = successive_pairs(trajs, Trajectory::e, &label);
    if let Some((lo, hi)) = finite_range(all.iter().copied()) {
        let (unit, coord) = match sc.params.model {
            ModelKind::Linear => ("m^2/s^2", "eta1 (x - chi_eq)^2"),
            _ => ("dimensionless", "ln(chi_l / x)"),
        };
        let pad = 0.15 * (hi - lo).max(1e-3 * hi.abs().max(1e-3));
        let (mut a, b) = ((lo - pad).max(0.0), hi + pad);
        match cf {
            Some(c @ ClosedForm::Eq19 { .. }) => {
                a = 0.0;
                let es = linspace(a, b, 600);
                push_at(
                    &mut series,
                    CURVE_SLOT,
                    Series {
                        label: "eq. 19: f(E) = alpha E exp(-E)".into(),
                        points: es.iter().map(|&e| (e, c.energy_map(e))).collect(),
                        style: Style::Line,
                    },
                );
            }
            Some(c @ ClosedForm::Eq17 { map, .. }) => {
                a = a.max(map.domain_start() * (1.0 + 1e-6));
                let es = linspace(a, b.max(a * 1.01), 600);
                push_at(
                    &mut series,
                    CURVE_SLOT,
                    Series {
                        label: if c.exact() {
                            "eq. 17 (tuned)".into()
                        } else {
                            "eq. 17 (scene untuned: approximate)".into()
                        },
                        points: es.iter().map(|&e| (e, c.energy_map(e))).collect(),
                        style: Style::Line,
                    },
                );
            }
            None => {}
        }
        push_at(
            &mut series,
            IDENTITY_SLOT,
            Series {
                label: "identity E(n+1) = E(n)".into(),
                points: vec![(a, a), (b, b)],
                style: Style::Line,
            },
        );
        written.extend(
            plot::series(
                &format!("{}: energy return map, E = {coord}", sc.name),
                &format!("E(n) ({unit})"),
                &format!("E(n+1) ({unit})"),
                &series,
                dir,
                &format!("{}-energy-map", sc.name),
            )
            .map_err(plot_err)?,
        );
    }
    // the phase portrait (chi, chi'), figs. 7-13
    let mut series = Vec::new();
    for t in trajs {
        let pts: Vec<(f64, f64)> = t
            .run
            .samples
            .iter()
            .map(|s| (s.state.height_m, s.state.velocity_mps))
            .collect();
        if !pts.is_empty() {
            series.push(Series {
                label: label(t),
                points: pts,
                style: Style::Line,
            });
        }
    }
    let vr = finite_range(series.iter().flat_map(|s| s.points.iter().map(|p| p.1)));
    if let Some((vlo, vhi)) = vr {
        push_at(
            &mut series,
            CURVE_SLOT,
            Series {
                label: "chi_l: touchdown / liftoff height".into(),
                points: vec![(chi_l, vlo), (chi_l, vhi)],
                style: Style::Line,
            },
        );
        written.extend(
            plot::series(
                &format!(
                    "{}: phase portrait ({})",
                    sc.name,
                    model_equation(sc.params.model)
                ),
                "body height chi (m)",
                "body velocity chi' (m/s)",
                &series,
                dir,
                &format!("{}-phase", sc.name),
            )
            .map_err(plot_err)?,
        );
    }
    Ok(written)
}
