//! `dexter analyze` on a hopper scene: the fixed point of the simulated cycle map and its
//! slope by finite differences, beside the closed forms; for the simplified nonlinear model
//! with fixed thrust, the Singer–Guckenheimer certificate of eq. 15 through eq. 18 (Lemma 2,
//! Theorem 1) and eq. 19's first period doublings (docs/stability.md).

use super::closed_forms::{none_reason, ClosedForm, ALPHA_DOUBLING};
use super::summary::{period_of, TAIL_CYCLES};
use super::{end_name, model_equation, model_name, HopperConfig};
use crate::engine::unimodal::cascade::{ratios, Doubling};
use crate::engine::unimodal::{num, pictures, Certificate};
use crate::model::hopper::analysis::{
    self as map_analysis, Eq15, Eq15InEnergy, Eq17Conjugate, Eq19Family, EQ19_SCHWARZIAN,
};
use crate::model::hopper::params::ModelKind;
use crate::model::hopper::{Cycle, HopperError, RunEnd, RunOptions, Start};
use crate::stream::Tail;
use crate::system::{Failure, Report};
use serde_json::json;
use std::path::{Path, PathBuf};

/// Relative finite-difference step for the closed-form models (4th-order central stencil:
/// truncation ~h^4, rounding ~1e-16/h; both ~1e-12 here).
pub const FD_STEP_CLOSED: f64 = 1e-3;
/// Relative step for the integrated full model (its map carries the integrator's error,
/// ~tolerance, which a step divides: a larger step keeps it below ~1e-8).
pub const FD_STEP_INTEGRATED: f64 = 1e-2;
/// Newton iterations at most.
pub const MAX_NEWTON: usize = 60;

const MAP_ONLY: RunOptions = RunOptions {
    times: false,
    samples_per_phase: 0,
};

/// The coordinate the cycle map is taken in.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Coord {
    /// E = ln(chi_l / x) of the bottom (nonlinear models, fixed thrust).
    Energy,
    /// The bottom height x, m (linear model, fixed thrust).
    Bottom,
    /// The touchdown speed, m/s (energy servo: the thrust depends on it).
    TouchdownSpeed,
}

impl Coord {
    fn name(self) -> &'static str {
        match self {
            Coord::Energy => "bottom energy E = ln(chi_l / x)",
            Coord::Bottom => "bottom height x (m)",
            Coord::TouchdownSpeed => "touchdown speed (m/s)",
        }
    }
}

struct CycleMap<'a> {
    sc: &'a HopperConfig,
    coord: Coord,
}

impl CycleMap<'_> {
    /// The first cycle from the state with coordinate `u`, and the coordinate one hop later.
    fn step(&self, u: f64) -> Result<(Cycle, f64), Failure> {
        let chi_l = self.sc.params.liftoff_height_m;
        let (start, n) = match self.coord {
            Coord::Energy => (
                Start::Bottom {
                    height_m: chi_l * (-u).exp(),
                },
                2,
            ),
            Coord::Bottom => (Start::Bottom { height_m: u }, 2),
            Coord::TouchdownSpeed => (
                Start::Flight {
                    height_m: chi_l,
                    velocity_mps: -u.abs(),
                },
                1,
            ),
        };
        let run = self
            .sc
            .hopper
            .simulate(start, n, &MAP_ONLY)
            .map_err(|e| self.outside(u, &e))?;
        if run.end != RunEnd::Completed {
            return Err(Failure::run(format!(
                "cycle map at {} = {u}: the run ended with {}",
                self.coord.name(),
                end_name(run.end)
            )));
        }
        let c = run.cycles[n - 1];
        let next = match self.coord {
            Coord::Energy => c.energy,
            Coord::Bottom => c.bottom_height_m,
            Coord::TouchdownSpeed => -c.next_touchdown.velocity_mps,
        };
        Ok((run.cycles[0], next))
    }
    /// Why the map cannot be evaluated at `u`, a state the analysis probes (not the
    /// scene's start): a start error there names the settings that drove the orbit out.
    fn outside(&self, u: f64, e: &HopperError) -> Failure {
        let at = format!("cycle map at {} = {u:.6e}", self.coord.name());
        match e {
            HopperError::Relation {
                param: "hopper.initial_heights_m",
                requirement,
            } => Failure::run(format!(
                "{at}: the orbit left the model's domain ({requirement}, a state the analysis reached, not hopper.initial_heights_m): with this thrust and friction (hopper.thrust_tau_mps2, hopper.thrust_delta_s, hopper.friction_gamma_per_s) there is no orbit to analyze"
            )),
            e => Failure::run(format!("{at}: {e}")),
        }
    }
    fn p(&self, u: f64) -> Result<f64, Failure> {
        Ok(self.step(u)?.1)
    }
    /// P'(u), 4th-order central difference with step h.
    fn slope(&self, u: f64, h: f64) -> Result<f64, Failure> {
        let d1 = self.p(u + h)? - self.p(u - h)?;
        let d2 = self.p(u + 2.0 * h)? - self.p(u - 2.0 * h)?;
        Ok((8.0 * d1 - d2) / (12.0 * h))
    }
}

impl Coord {
    /// The coordinate of a scene's cycle map.
    fn of(sc: &HopperConfig) -> Self {
        if sc.params.servo.is_some() {
            Coord::TouchdownSpeed
        } else if sc.params.model == ModelKind::Linear {
            Coord::Bottom
        } else {
            Coord::Energy
        }
    }

    /// The coordinate of a cycle (its next hop's, for the touchdown speed).
    fn value(self, c: &Cycle) -> f64 {
        match self {
            Coord::Energy => c.energy,
            Coord::Bottom => c.bottom_height_m,
            Coord::TouchdownSpeed => -c.next_touchdown.velocity_mps,
        }
    }
}

/// The fixed point of the cycle map and the map's slope there.
struct FixedPoint {
    /// The coordinate u*.
    u: f64,
    /// The first cycle from u*.
    cycle: Cycle,
    iterations: usize,
    /// P(u*) - u*.
    residual: f64,
    /// P'(u*).
    slope: f64,
    /// The finite-difference step.
    h: f64,
}

impl CycleMap<'_> {
    /// The scale of the coordinate near `u` (finite-difference steps are relative to it).
    fn scale(&self, u: f64) -> f64 {
        match self.coord {
            Coord::Bottom => (self.sc.params.liftoff_height_m - u).abs().max(1e-6),
            _ => u.abs().max(1e-6),
        }
    }

    /// Newton's method on P(u) - u from `u`, then the slope there.
    fn fixed_point(&self, mut u: f64) -> Result<FixedPoint, Failure> {
        let rel = if self.sc.params.model == ModelKind::Full {
            FD_STEP_INTEGRATED
        } else {
            FD_STEP_CLOSED
        };
        let mut iterations = 0;
        let mut residual = f64::NAN;
        for _ in 0..MAX_NEWTON {
            iterations += 1;
            let f = self.p(u)? - u;
            residual = f;
            let du = f / (self.slope(u, rel * self.scale(u))? - 1.0);
            if !du.is_finite() {
                break;
            }
            let mut next = u - du;
            if self.coord != Coord::Bottom && next <= 0.0 {
                next = 0.5 * u;
            }
            u = next;
            if du.abs() <= 1e-15 * self.scale(u) {
                break;
            }
        }
        let (cycle, pu) = self.step(u)?;
        if (pu - u).is_finite() {
            residual = pu - u;
        }
        let h = rel * self.scale(u);
        Ok(FixedPoint {
            u,
            cycle,
            iterations,
            residual,
            slope: self.slope(u, h)?,
            h,
        })
    }
}

/// The scene's own run (first start, `hopper.cycles` hops): the mean of its last two
/// coordinates (Newton's first guess), its cycles and its late period.
fn scene_run(sc: &HopperConfig, coord: Coord) -> Result<(f64, usize, Option<usize>), Failure> {
    let mut tail = Tail::new(TAIL_CYCLES);
    let (end, _) = sc
        .hopper
        .run(sc.starts[0], sc.params.cycles, &MAP_ONLY, &mut |c| {
            tail.push(*c)
        })
        .map_err(Failure::scene)?;
    let cycles = tail.seen() as usize;
    if cycles < 2 {
        return Err(Failure::run(format!(
            "the scene's run ended after {cycles} cycles ({}): no orbit to analyze",
            end_name(end)
        )));
    }
    let e: Vec<f64> = tail.iter().map(|c| c.energy).collect();
    let last: Vec<f64> = tail.iter().rev().take(2).map(|c| coord.value(c)).collect();
    Ok((0.5 * (last[0] + last[1]), cycles, period_of(&e, cycles)))
}

/// Everything `analyze` reports.
pub struct Analysis<'a> {
    sc: &'a HopperConfig,
    coord: Coord,
    fp: FixedPoint,
    closed: Option<(ClosedForm, f64, f64)>,
    alpha: Option<f64>,
    cycles: usize,
    late_period: Option<usize>,
    global: Option<Global>,
    linear: Option<Linear>,
}

/// Doublings of eq. 19 located by `Global` (Theorem 1: at least six).
pub const DOUBLINGS: usize = 6;

/// Feigenbaum's constant δ = 4.669201609... (Feigenbaum 1978), for comparison.
pub const FEIGENBAUM_DELTA: f64 = 4.669_201_609_102_99;

/// The certificate of the tuned linear model through Lemma 4's conjugate (Theorem 2).
struct Linear {
    map: Eq17Conjugate,
    /// `None`: the model leaves its physical domain (ρ ḡ(c) ≥ 1).
    cert: Option<Certificate>,
    /// False for a slightly detuned scene compared with eq. 17 approximately.
    exact: bool,
}

/// Lemma 4's closed-form argument (the paper's, cited; the sign is proven here by interval
/// arithmetic on g itself).
const LEMMA4_SCHWARZIAN: &str = "Lemma 4: g = k o gbar with k = arctan o hbar^-1 (S(k) < 0: S(arctan) < 0 and hbar is projective) and S(gbar) = -v^T G v / (cos p - beta sin p)^2 < 0, G positive definite, so S(g) = S(k)(gbar) gbar'^2 + S(gbar) < 0; here proven by interval arithmetic on g";

impl Linear {
    fn of(cf: &ClosedForm) -> Option<Self> {
        let ClosedForm::Eq17 { map, .. } = cf else {
            return None;
        };
        let (beta, psi, psi_dot) = map.thrust_vector();
        let g = Eq17Conjugate {
            beta,
            rho: psi / psi_dot,
        };
        Some(Self {
            map: g,
            cert: map_analysis::certificate_eq17(&g),
            exact: cf.exact(),
        })
    }

    fn note(&self) -> &'static str {
        if self.exact {
            "Theorem 2: every physically valid instance has a single essentially globally asymptotically stable fixed point, so no bifurcation over the physical range"
        } else {
            "approximate: this scene is slightly detuned, and eq. 17 (hence the certificate) is exact only for the tuned model"
        }
    }

    fn json(&self) -> serde_json::Value {
        let mut cert = match &self.cert {
            Some(c) => c.json(),
            None => {
                json!({"verdict_code": null, "reason": "rho gbar(c) >= 1: the thrust does not end in stance for some bottoms (outside the model's physical domain, Lemma 7)"})
            }
        };
        cert["map"] = json!("eq. 17 conjugated by h^-1(E) = arctan(psi_t'/(sqrt E - psi_t)) (eq. 20): g(x) = arctan(gbar/(1 - rho gbar)), gbar = sin x e^(beta (pi - x)) (Lemma 4)");
        cert["coordinate"] = json!("x = arctan(psi_t' / (sqrt E - psi_t)), rad");
        cert["schwarzian_argument"] = json!(LEMMA4_SCHWARZIAN);
        json!({
            "certificate": cert,
            "beta": num(self.map.beta),
            "rho": num(self.map.rho),
            "exact": self.exact,
            "regime": self.note(),
        })
    }

    fn text(&self) -> String {
        let mut s = format!(
            "  Singer-Guckenheimer certificate of eq. 17 through Lemma 4's conjugate in x = arctan(psi_t'/(sqrt E - psi_t)), beta = {:.6}, rho = {:.6}:\n",
            self.map.beta, self.map.rho
        );
        s += &format!("  Schwarzian: {LEMMA4_SCHWARZIAN}\n");
        match &self.cert {
            Some(c) => s += &c.text(),
            None => {
                s += "  no certificate: rho gbar(c) >= 1 (outside the model's physical domain)\n"
            }
        }
        s += &format!("  {}\n", self.note());
        s
    }
}

/// The global analysis of eq. 15/19: the certificate and the cascade.
struct Global {
    map: Eq15InEnergy,
    cert: Certificate,
    /// α = τ χ_l μ / η₁.
    alpha: f64,
    /// τ per unit α: η₁ / (χ_l μ), m/s².
    thrust_per_alpha: f64,
    cascade: Result<Vec<Doubling>, String>,
}

impl Global {
    fn of(cf: &ClosedForm) -> Option<Self> {
        let ClosedForm::Eq19 {
            alpha,
            tau,
            mu,
            eta1,
            chi_l,
        } = *cf
        else {
            return None;
        };
        let map = Eq15InEnergy(Eq15 {
            k_per_m: tau * mu / eta1,
            chi_l_m: chi_l,
        });
        Some(Self {
            map,
            cert: map_analysis::certificate(&map),
            alpha,
            thrust_per_alpha: eta1 / (chi_l * mu),
            cascade: map_analysis::cascade(DOUBLINGS).map_err(|e| e.0),
        })
    }

    /// Where the scene's α lies in the cascade.
    fn regime(&self) -> String {
        let a = self.alpha;
        if a <= 1.0 {
            return "alpha <= 1: no hop (Lemma 1: 0 is the only fixed point)".into();
        }
        let Ok(d) = &self.cascade else {
            return "unknown (the cascade was not located)".into();
        };
        match d.iter().position(|x| a < x.parameter) {
            Some(0) => "1 < alpha < alpha_1 = e^2: period 1 (Theorem 1)".into(),
            Some(n) => format!(
                "alpha_{n} < alpha < alpha_{}: period {}",
                n + 1,
                1usize << n
            ),
            None => format!("alpha > alpha_{}: period >= {}", d.len(), 1usize << d.len()),
        }
    }

    fn json(&self) -> serde_json::Value {
        let mut cert = self.cert.json();
        cert["map"] =
            json!("eq. 15 conjugated by eq. 18, h(x) = ln(chi_l/x): f(E) = alpha E e^-E (eq. 19)");
        cert["coordinate"] = json!("E = ln(chi_l / x) at bottom");
        cert["schwarzian_argument"] = json!(EQ19_SCHWARZIAN);
        let (doublings, ratios_v, error) = match &self.cascade {
            Ok(d) => (
                d.iter()
                    .enumerate()
                    .map(|(i, x)| {
                        json!({
                            "n": i + 1,
                            "period_losing_stability": x.period,
                            "alpha": num(x.parameter),
                            "thrust_tau_mps2": num(x.parameter * self.thrust_per_alpha),
                            "cycle_point_energy": num(x.x),
                            "multiplier_residual": num(x.multiplier_residual),
                            "cycle_residual": num(x.residual),
                        })
                    })
                    .collect::<Vec<_>>(),
                ratios(d).into_iter().map(num).collect::<Vec<_>>(),
                serde_json::Value::Null,
            ),
            Err(e) => (vec![], vec![], json!(e)),
        };
        json!({
            "certificate": cert,
            "doublings": doublings,
            "doublings_error": error,
            "feigenbaum_ratios": ratios_v,
            "feigenbaum_delta": FEIGENBAUM_DELTA,
            "regime": self.regime(),
        })
    }

    fn text(&self) -> String {
        let mut s = "  Singer-Guckenheimer certificate of eq. 15 in E = ln(chi_l/x) (eq. 18), f(E) = alpha E e^-E (eq. 19):\n".to_string();
        s += &format!("  Schwarzian in closed form: {EQ19_SCHWARZIAN}\n");
        s += &self.cert.text();
        match &self.cascade {
            Ok(d) => {
                s += "  period doublings of eq. 19 (continuation of each 2^n-cycle to multiplier -1):\n";
                for (i, x) in d.iter().enumerate() {
                    s += &format!(
                        "    alpha_{} = {:.12} (tau = {:.9} m/s^2): period {} -> {}\n",
                        i + 1,
                        x.parameter,
                        x.parameter * self.thrust_per_alpha,
                        x.period,
                        2 * x.period
                    );
                }
                let r: Vec<String> = ratios(d).iter().map(|r| format!("{r:.6}")).collect();
                s += &format!(
                    "  interval ratios (a_n - a_n-1)/(a_n+1 - a_n): {} (Feigenbaum delta = {FEIGENBAUM_DELTA:.6})\n",
                    r.join(", ")
                );
            }
            Err(e) => s += &format!("  period doublings not located: {e}\n"),
        }
        s += &format!("  this scene: {}\n", self.regime());
        s
    }
}

impl Analysis<'_> {
    fn stable(&self) -> bool {
        self.fp.slope.abs() < 1.0
    }

    fn verdict(&self) -> String {
        let slope = self.fp.slope;
        if self.stable() {
            let oscillating = if slope < 0.0 {
                " (oscillating approach)"
            } else {
                ""
            };
            format!(
                "stable period-1 hopping: |slope| = {:.6} < 1{oscillating}",
                slope.abs()
            )
        } else if slope < -1.0 {
            "unstable through a flip: the slope has passed -1, where the fixed point period-doubles (the late orbit is a period-2 or longer cycle)".to_string()
        } else {
            "unstable: slope > 1".to_string()
        }
    }

    fn doubling(&self) -> Option<String> {
        self.alpha.map(|a| {
            format!(
                "period doubling at slope -1, alpha = e^2 = {ALPHA_DOUBLING:.9}; this scene has alpha = {a:.9} ({} e^2)",
                if a < ALPHA_DOUBLING { "<" } else { ">" }
            )
        })
    }

    fn json_value(&self) -> serde_json::Value {
        let (sc, fp) = (self.sc, &self.fp);
        json!({
            "scene": sc.name,
            "model": model_name(sc.params.model),
            "equation": model_equation(sc.params.model),
            "coordinate": self.coord.name(),
            "alpha": self.alpha,
            "alpha_doubling": self.alpha.map(|_| ALPHA_DOUBLING),
            "fixed_point": {
                "coordinate": fp.u,
                "bottom_height_m": fp.cycle.bottom_height_m,
                "energy": fp.cycle.energy,
                "residual": fp.residual,
                "newton_iterations": fp.iterations,
            },
            "slope_numerical": fp.slope,
            "finite_difference_step": fp.h,
            "closed_form": self.closed.map(|(c, e, s)| json!({
                "equation": c.equation(),
                "exact": c.exact(),
                "energy": e,
                "bottom_height_m": c.bottom_of(e),
                "slope": s,
                "slope_difference": fp.slope - s,
            })),
            "stable": self.stable(),
            "verdict": self.verdict(),
            "period_doubling": self.doubling(),
            "late_period": self.late_period,
            "global": match (&self.global, &self.linear) {
                (Some(g), _) => g.json(),
                (None, Some(l)) => l.json(),
                _ => json!({"certificate": null, "reason": self.global_reason()}),
            },
        })
    }

    /// Why a scene has no certificate.
    fn global_reason(&self) -> String {
        let why = if self.sc.params.servo.is_some() {
            "the energy servo changes the thrust from hop to hop (no one-parameter map of eq. 15/19)"
        } else {
            match self.sc.params.model {
                ModelKind::Linear => {
                    "eq. 17 (Theorem 2, Lemma 4) is exact only for the tuned linear model, and this scene is detuned too far to compare with it"
                }
                ModelKind::Full => "the full model (eq. 8) has no closed-form return map",
                _ => "no closed form applies",
            }
        };
        format!(
            "no Singer-Guckenheimer certificate: it is given for the simplified nonlinear model with fixed thrust (eq. 15/19) and the tuned linear model (eq. 17); here {why}"
        )
    }

    fn human(&self) -> String {
        let (sc, fp) = (self.sc, &self.fp);
        let mut s = format!(
            "hopper scene {}: {} model ({})\n  cycle map in the {} ({}, Newton {} iterations, residual {:.1e})\n",
            sc.name,
            model_name(sc.params.model),
            model_equation(sc.params.model),
            self.coord.name(),
            "simulated hop by hop",
            fp.iterations,
            fp.residual
        );
        let speed = match self.coord {
            Coord::TouchdownSpeed => format!(", touchdown speed {:.12} m/s", fp.u),
            _ => String::new(),
        };
        s += &format!(
            "  fixed point: x* = {:.12} m, E* = {:.12}{speed}\n",
            fp.cycle.bottom_height_m, fp.cycle.energy
        );
        s += &format!(
            "  slope of the return map there: {:.12} (4th-order central differences, step {:.3e})\n",
            fp.slope, fp.h
        );
        s += &self.closed_text();
        s += &format!("  verdict: {}\n", self.verdict());
        if let Some(d) = self.doubling() {
            s += &format!("  {d}\n");
        }
        s += &format!(
            "  the scene's own run ({} cycles): late period {}\n",
            self.cycles,
            self.late_period
                .map_or("not settled".into(), |p| p.to_string())
        );
        match (&self.global, &self.linear) {
            (Some(g), _) => s += &g.text(),
            (None, Some(l)) => s += &l.text(),
            _ => s += &format!("  {}\n", self.global_reason()),
        }
        s
    }

    fn closed_text(&self) -> String {
        let Some((c, e, cs)) = self.closed else {
            return format!("  closed form: {}\n", none_reason(self.sc));
        };
        format!(
            "  closed form ({}{}): E* = {e:.12}, x* = {:.12} m, slope {cs:.12}{}; slope difference {:.3e}\n",
            c.equation(),
            if c.exact() { "" } else { ", untuned scene: approximate" },
            c.bottom_of(e),
            if matches!(c, ClosedForm::Eq19 { .. }) {
                " = 1 - ln alpha"
            } else {
                ""
            },
            self.fp.slope - cs
        )
    }
}

impl Report for Analysis<'_> {
    fn text(&self) -> String {
        self.human()
    }
    fn json(&self) -> Result<String, String> {
        Ok(self.json_value().to_string())
    }
    /// `{scene}-return-map`, `{scene}-schwarzian` (eq. 19 in E) and `{scene}-bifurcation`
    /// (eq. 19 over alpha with the located doublings).
    fn plot(&self, dir: &Path) -> Result<Vec<PathBuf>, Failure> {
        if let (None, Some(l)) = (&self.global, &self.linear) {
            let Some(cert) = &l.cert else {
                return Err(Failure::usage(
                    "--plot: no certificate (outside the model's physical domain)",
                ));
            };
            let (stem, coord) = (
                self.sc.name.as_str(),
                "x = arctan(psi_t'/(sqrt E - psi_t)) (rad)",
            );
            let mut files = pictures::return_map(&l.map, cert, coord, dir, stem)?;
            files.extend(pictures::schwarzian_sign(&l.map, cert, coord, dir, stem)?);
            return Ok(files);
        }
        let Some(g) = &self.global else {
            return Err(Failure::usage(format!("--plot: {}", self.global_reason())));
        };
        let (stem, coord) = (self.sc.name.as_str(), "bottom energy E = ln(chi_l/x)");
        let mut files = pictures::return_map(&g.map, &g.cert, coord, dir, stem)?;
        files.extend(pictures::schwarzian_sign(
            &g.map, &g.cert, coord, dir, stem,
        )?);
        let alphas: Vec<f64> = (0..=600).map(|i| 1.5 + 14.0 * i as f64 / 600.0).collect();
        let located = g.cascade.as_deref().unwrap_or(&[]);
        files.extend(pictures::bifurcation(
            &Eq19Family,
            &alphas,
            located,
            ("alpha = tau chi_l mu / eta1", "late E_n"),
            dir,
            stem,
        )?);
        Ok(files)
    }
}

/// `dexter analyze` on a hopper scene.
pub fn analyze(sc: &HopperConfig) -> Result<Analysis<'_>, Failure> {
    let coord = Coord::of(sc);
    let (u0, cycles, late_period) = scene_run(sc, coord)?;
    let fp = CycleMap { sc, coord }.fixed_point(u0)?;
    let cf = ClosedForm::of(sc);
    let global = cf.as_ref().and_then(Global::of);
    let linear = cf.as_ref().and_then(Linear::of);
    Ok(Analysis {
        sc,
        coord,
        fp,
        closed: cf.and_then(|c| Some((c, c.fixed_energy()?, c.fixed_slope()?))),
        alpha: cf.and_then(|c| c.alpha()),
        cycles,
        late_period,
        global,
        linear,
    })
}
