//! The hopper run's summary: per start its cycles, end, period and late values beside the
//! closed forms (eq. 15/19, eq. 17), as text or one JSON object. Each trajectory keeps
//! its last [`TAIL_CYCLES`] cycles: enough for the period and the late values, whatever the
//! run's length.

use super::closed_forms::{none_reason, ClosedForm, ALPHA_DOUBLING};
use super::{
    end_name, model_equation, model_name, start_height, start_text, HopperConfig, PERIOD_TOL,
};
use crate::model::hopper::analysis::MAX_PERIOD;
use crate::model::hopper::params::ModelKind;
use crate::model::hopper::{Cycle, RunEnd, Sample, Start};
use crate::period::Tolerance;
use crate::stream::Tail;
use crate::system::Outcome;
use serde_json::{json, Value};

/// Late values reported per trajectory.
pub const LATE: usize = 8;

/// Cycles each trajectory keeps: what [`period_of`] looks at for periods up to
/// [`MAX_PERIOD`].
pub const TAIL_CYCLES: usize = crate::period::values_needed(MAX_PERIOD);

/// The period the energies whose last values are `e` (of `total` in all) have provably
/// settled to: [`crate::period::settled_period`] with the tolerance [`PERIOD_TOL`]
/// (`|a - b| <= tol (1 + |a|)`), periods up to [`MAX_PERIOD`] (and `total / 3`); `None`
/// (not settled) if the orbit is still converging (near a doubling a slowly decaying
/// alternation repeats with twice the period long before it settles), aperiodic or too
/// short.
pub fn period_of(e: &[f64], total: usize) -> Option<usize> {
    let max = MAX_PERIOD.min(total / 3).max(1);
    crate::period::settled_period(e, max, Tolerance::Mixed(PERIOD_TOL))
}

/// One simulated start, kept in bounded memory.
#[derive(Clone, Debug)]
pub struct Trajectory {
    /// Where it started.
    pub start: Start,
    /// Cycles simulated.
    pub cycles: usize,
    /// Why it ended.
    pub end: RunEnd,
    /// Integrator steps (full model).
    pub steps: u64,
    /// Cycles whose leg extended during the thrust.
    pub early_liftoffs: usize,
    /// The late orbit's period ([`period_of`]).
    pub period: Option<usize>,
    /// Dense samples for the phase portrait (at most `MAX_SAMPLES`).
    pub samples: Vec<Sample>,
    tail: Tail<Cycle>,
}

impl Trajectory {
    /// Before its first cycle.
    pub fn new(start: Start) -> Self {
        Self {
            start,
            cycles: 0,
            end: RunEnd::Completed,
            steps: 0,
            early_liftoffs: 0,
            period: None,
            samples: Vec::new(),
            tail: Tail::new(TAIL_CYCLES),
        }
    }

    /// One more cycle.
    pub fn push(&mut self, c: &Cycle) {
        self.cycles += 1;
        self.early_liftoffs += usize::from(c.early_liftoff);
        self.tail.push(*c);
    }

    /// The run ended.
    pub fn finish(&mut self, end: RunEnd, steps: u64, samples: Vec<Sample>) {
        self.end = end;
        self.steps = steps;
        self.samples = samples;
        self.period = period_of(&self.late_e(TAIL_CYCLES), self.cycles);
    }

    /// The last `k` bottom heights x_n, m.
    pub fn late_x(&self, k: usize) -> Vec<f64> {
        self.late(k, |c| c.bottom_height_m)
    }

    /// The last `k` energies E_n.
    pub fn late_e(&self, k: usize) -> Vec<f64> {
        self.late(k, |c| c.energy)
    }

    fn late(&self, k: usize, f: fn(&Cycle) -> f64) -> Vec<f64> {
        let n = self.tail.len();
        self.tail.iter().skip(n.saturating_sub(k)).map(f).collect()
    }

    fn sim_time_s(&self) -> f64 {
        self.tail.last().map_or(0.0, |c| c.next_touchdown.time_s)
    }

    fn apex_m(&self) -> f64 {
        self.tail.last().map_or(f64::NAN, |c| c.apex.height_m)
    }

    fn json(&self, i: usize) -> Value {
        json!({
            "trajectory": i + 1,
            "initial_height_m": start_height(&self.start),
            "start": start_text(&self.start),
            "cycles": self.cycles,
            "end": end_name(self.end),
            "period": self.period,
            "late_bottom_heights_m": self.late_x(LATE),
            "late_energies": self.late_e(LATE),
            "apex_height_m": self.apex_m(),
            "sim_time_s": self.sim_time_s(),
            "integrator_steps": self.steps,
            "early_liftoffs": self.early_liftoffs,
        })
    }
}

/// A hopper run's result.
#[derive(Clone, Debug)]
pub struct HopperOutcome {
    /// The scene.
    pub cfg: HopperConfig,
    /// Its closed form, if it has one.
    pub closed: Option<ClosedForm>,
    /// One per start.
    pub trajectories: Vec<Trajectory>,
    /// Wall-clock time of the simulation, s.
    pub wall_s: f64,
}

impl HopperOutcome {
    /// The outcome of `trajectories` (at least one) of `cfg`.
    pub fn new(cfg: &HopperConfig, trajectories: Vec<Trajectory>, wall_s: f64) -> Self {
        Self {
            closed: ClosedForm::of(cfg),
            cfg: cfg.clone(),
            trajectories,
            wall_s,
        }
    }
}

impl Outcome for HopperOutcome {
    fn text(&self) -> String {
        let mut s = header_text(&self.cfg);
        s += &closed_text(&self.cfg, self.closed.as_ref());
        for (i, t) in self.trajectories.iter().enumerate() {
            s += &trajectory_text(i, t, self.closed.as_ref());
        }
        s += &format!("  wall time {:.3} ms\n", self.wall_s * 1e3);
        s
    }

    fn json(&self) -> Result<String, String> {
        Ok(summary_json(self).to_string())
    }

    /// An integrator at its step cap, or a non-finite state, is not the hopper's physics.
    fn shortfall(&self) -> Option<String> {
        let (i, t) = self
            .trajectories
            .iter()
            .enumerate()
            .find(|(_, t)| matches!(t.end, RunEnd::StepCap | RunEnd::NonFinite))?;
        Some(format!(
            "trajectory {} ended after {} of {} cycles: {}",
            i + 1,
            t.cycles,
            self.cfg.params.cycles,
            end_name(t.end)
        ))
    }
}

fn closed_json(cf: Option<&ClosedForm>) -> Value {
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
    if let (ClosedForm::Eq17 { detuning_m, .. }, Some(o)) = (cf, v.as_object_mut()) {
        o.insert("detuning_m".into(), json!(detuning_m));
    }
    v
}

fn energy_unit(m: ModelKind) -> &'static str {
    match m {
        ModelKind::Linear => "m^2/s^2 (eq. 17: eta1 (x - chi_eq)^2)",
        _ => "1 (eq. 18: ln(chi_l / x))",
    }
}

fn summary_json(o: &HopperOutcome) -> Value {
    let (p, cf) = (&o.cfg.params, o.closed.as_ref());
    let t0 = &o.trajectories[0];
    let alpha = cf.and_then(|c| c.alpha());
    json!({
        "scene": o.cfg.name,
        "model": model_name(p.model),
        "equation": model_equation(p.model),
        "thrust_tau_mps2": p.thrust_tau_mps2,
        "thrust_delta_s": p.thrust_delta_s,
        "energy_servo": p.servo.is_some(),
        "liftoff_height_m": p.liftoff_height_m,
        "alpha": alpha,
        "alpha_doubling": alpha.map(|_| ALPHA_DOUBLING),
        "fixed_point_closed_form": closed_json(cf),
        "energy_unit": energy_unit(p.model),
        "cycles": t0.cycles,
        "period": t0.period,
        "late_bottom_heights_m": t0.late_x(LATE),
        "late_energies": t0.late_e(LATE),
        "apex_height_m": t0.apex_m(),
        "sim_time_s": t0.sim_time_s(),
        "wall_time_s": o.wall_s,
        "end": end_name(t0.end),
        "trajectories": o.trajectories.iter().enumerate().map(|(i, t)| t.json(i)).collect::<Vec<_>>(),
    })
}

/// Ten decimals.
fn g(v: f64) -> String {
    format!("{v:.10}")
}

fn header_text(cfg: &HopperConfig) -> String {
    let p = &cfg.params;
    format!(
        "hopper scene {}: {} model ({})\n  thrust tau = {} m/s^2 for delta = {} s{}\n",
        cfg.name,
        model_name(p.model),
        model_equation(p.model),
        p.thrust_tau_mps2,
        p.thrust_delta_s,
        if p.servo.is_some() {
            " (energy servo: tau is the nominal thrust)"
        } else {
            ""
        }
    )
}

fn closed_text(cfg: &HopperConfig, cf: Option<&ClosedForm>) -> String {
    match cf {
        Some(c @ ClosedForm::Eq19 { alpha, .. }) => eq19_text(c, *alpha),
        Some(c @ ClosedForm::Eq17 { detuning_m, .. }) => {
            let tuned = if c.exact() {
                "tuned, exact".to_string()
            } else {
                format!("untuned by chi_l - chi_eq = {detuning_m:.6} m, so only approximate")
            };
            match c.fixed_energy() {
                Some(e) => format!(
                    "  closed form (eq. 17, {tuned}): E* = {} m^2/s^2, x* = {} m, slope f'(E*) = {:.6}\n",
                    g(e),
                    g(c.bottom_of(e)),
                    c.fixed_slope().unwrap_or(f64::NAN)
                ),
                None => format!("  closed form (eq. 17, {tuned}): no interior fixed point\n"),
            }
        }
        None => format!("  closed form: {}\n", none_reason(cfg)),
    }
}

fn eq19_text(c: &ClosedForm, alpha: f64) -> String {
    let mut s = format!(
        "  alpha = tau chi_l mu / eta1 = {alpha:.6} ({} e^2 = {ALPHA_DOUBLING:.6}, the first period doubling)\n",
        if alpha < ALPHA_DOUBLING { "<" } else { ">=" }
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
        None => s += "  closed form: alpha <= 1, no hopping fixed point (the hopper stops)\n",
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
    s
}

fn trajectory_text(i: usize, t: &Trajectory, cf: Option<&ClosedForm>) -> String {
    let mut s = format!(
        "  trajectory {} from {}: {} cycles, end {}\n",
        i + 1,
        start_text(&t.start),
        t.cycles,
        end_name(t.end)
    );
    if t.cycles == 0 {
        return s;
    }
    let period = t
        .period
        .map_or("not settled (still converging, or aperiodic)".into(), |p| {
            p.to_string()
        });
    s += &format!("    period {period}\n");
    let k = t.period.unwrap_or(1).min(t.cycles);
    let late_x: Vec<String> = t.late_x(k).into_iter().map(g).collect();
    let late_e: Vec<String> = t.late_e(k).into_iter().map(g).collect();
    s += &format!(
        "    late bottoms x_n = {} m, energies E_n = {}\n",
        late_x.join(" / "),
        late_e.join(" / ")
    );
    s += &vs_closed_text(t, cf);
    s += &format!(
        "    apex {} m, sim time {:.6} s{}\n",
        g(t.apex_m()),
        t.sim_time_s(),
        if t.steps > 0 {
            format!(", {} integrator steps", t.steps)
        } else {
            String::new()
        }
    );
    s
}

/// The late orbit against the closed-form fixed point (period 1) or 2-cycle (period 2).
fn vs_closed_text(t: &Trajectory, cf: Option<&ClosedForm>) -> String {
    let (x, e) = (t.late_x(2), t.late_e(2));
    let last = |v: &[f64]| v[v.len() - 1];
    match (cf, t.period) {
        (Some(c), Some(1)) => c.fixed_energy().map_or(String::new(), |es| {
            format!(
                "    vs closed form: x_n - x* = {:.3e} m, E_n - E* = {:.3e}\n",
                last(&x) - c.bottom_of(es),
                last(&e) - es
            )
        }),
        (Some(c), Some(2)) => c.alpha().map_or(String::new(), |a| {
            format!(
                "    vs closed form: E_n + E_n-1 - 2 ln alpha = {:.3e}\n",
                e[e.len() - 1] + e[e.len() - 2] - 2.0 * a.ln()
            )
        }),
        _ => String::new(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The period of the last [`TAIL_CYCLES`] values equals the period of all of them.
    #[test]
    fn the_tail_gives_the_period_of_the_whole_sequence() {
        let seqs: [Box<dyn Fn(usize) -> f64>; 5] = [
            Box::new(|i| 1.0 + 0.3 * (-(i as f64) / 50.0).exp()),
            Box::new(|i| [1.0, 2.0][i % 2]),
            Box::new(|i| {
                [1.0, 2.0][i % 2] + 0.4 * (-(i as f64) / 300.0).exp() * [1.0, -1.0][i % 2]
            }),
            Box::new(|i| [1.0, 2.0, 1.5, 3.0][i % 4]),
            Box::new(|i| ((i as f64) * 1.7).sin()),
        ];
        for (k, f) in seqs.iter().enumerate() {
            for n in [10, 100, 191, 192, 256, 257, 1000] {
                let all: Vec<f64> = (0..n).map(f).collect();
                let tail = &all[n.saturating_sub(TAIL_CYCLES)..];
                assert_eq!(
                    period_of(tail, n),
                    period_of(&all, n),
                    "sequence {k}, n {n}"
                );
            }
        }
        assert_eq!(period_of(&[[1.0, 2.0][0]; 100], 100), Some(1));
    }
}
