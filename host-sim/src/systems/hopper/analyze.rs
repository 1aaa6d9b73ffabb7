//! `dexter analyze` on a hopper scene: the fixed point of the simulated cycle map and its
//! slope by finite differences, beside the closed forms.

use super::closed_forms::{none_reason, ClosedForm, ALPHA_DOUBLING};
use super::summary::{period_of, TAIL_CYCLES};
use super::{end_name, model_equation, model_name, HopperConfig};
use crate::model::hopper::params::ModelKind;
use crate::model::hopper::{Cycle, HopperError, RunEnd, RunOptions, Start};
use crate::stream::Tail;
use crate::system::{Failure, Report};
use serde_json::json;

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
        })
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
}

/// `dexter analyze` on a hopper scene.
pub fn analyze(sc: &HopperConfig) -> Result<Analysis<'_>, Failure> {
    let coord = Coord::of(sc);
    let (u0, cycles, late_period) = scene_run(sc, coord)?;
    let fp = CycleMap { sc, coord }.fixed_point(u0)?;
    let cf = ClosedForm::of(sc);
    Ok(Analysis {
        sc,
        coord,
        fp,
        closed: cf.and_then(|c| Some((c, c.fixed_energy()?, c.fixed_slope()?))),
        alpha: cf.and_then(|c| c.alpha()),
        cycles,
        late_period,
    })
}
