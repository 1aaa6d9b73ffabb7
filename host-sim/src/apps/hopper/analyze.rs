//! `dexter analyze` on a hopper scene: the fixed point of the simulated cycle map and its
//! slope by finite differences, beside the closed forms.

use super::closed::{ClosedForm, ALPHA_DOUBLING};
use super::run::period_of;
use super::{model_equation, model_name, Loaded};
use crate::apps::{AppAnalyze, AppError};
use crate::model::hopper::analysis::energies;
use crate::model::hopper::params::ModelKind;
use crate::model::hopper::{Cycle, RunEnd, RunOptions, Start};
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
    sc: &'a Loaded,
    coord: Coord,
}

impl CycleMap<'_> {
    /// The first cycle from the state with coordinate `u`, and the coordinate one hop later.
    fn step(&self, u: f64) -> Result<(Cycle, f64), AppError> {
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
            .map_err(|e| AppError::Run(format!("cycle map at {u}: {e}")))?;
        if run.end != RunEnd::Completed {
            return Err(AppError::Run(format!(
                "cycle map at {} = {u}: the run ended with {}",
                self.coord.name(),
                super::end_name(run.end)
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
    fn p(&self, u: f64) -> Result<f64, AppError> {
        Ok(self.step(u)?.1)
    }
    /// P'(u), 4th-order central difference with step h.
    fn slope(&self, u: f64, h: f64) -> Result<f64, AppError> {
        let d1 = self.p(u + h)? - self.p(u - h)?;
        let d2 = self.p(u + 2.0 * h)? - self.p(u - 2.0 * h)?;
        Ok((8.0 * d1 - d2) / (12.0 * h))
    }
}

/// `dexter analyze` on a hopper scene.
pub fn analyze(args: &AppAnalyze) -> Result<(), AppError> {
    let sc = Loaded::load(&args.scene, &args.sets)?;
    let coord = if sc.params.servo.is_some() {
        Coord::TouchdownSpeed
    } else if sc.params.model == ModelKind::Linear {
        Coord::Bottom
    } else {
        Coord::Energy
    };
    let map = CycleMap { sc: &sc, coord };
    // the scene's own run: its late orbit is Newton's first guess
    let run = sc
        .hopper
        .simulate(sc.starts[0], sc.params.cycles, &MAP_ONLY)
        .map_err(|e| AppError::Scene(e.to_string()))?;
    let late_period = period_of(&energies(&run.cycles));
    let cs = &run.cycles;
    if cs.len() < 2 {
        return Err(AppError::Run(format!(
            "the scene's run ended after {} cycles ({}): no orbit to analyze",
            cs.len(),
            super::end_name(run.end)
        )));
    }
    let val = |c: &Cycle| match coord {
        Coord::Energy => c.energy,
        Coord::Bottom => c.bottom_height_m,
        Coord::TouchdownSpeed => -c.next_touchdown.velocity_mps,
    };
    let mut u = 0.5 * (val(&cs[cs.len() - 1]) + val(&cs[cs.len() - 2]));
    let rel = if sc.params.model == ModelKind::Full {
        FD_STEP_INTEGRATED
    } else {
        FD_STEP_CLOSED
    };
    let scale = |u: f64| match coord {
        Coord::Bottom => (sc.params.liftoff_height_m - u).abs().max(1e-6),
        _ => u.abs().max(1e-6),
    };
    // Newton on P(u) - u
    let mut iterations = 0;
    let mut residual = f64::NAN;
    for _ in 0..MAX_NEWTON {
        iterations += 1;
        let f = map.p(u)? - u;
        residual = f;
        let d = map.slope(u, rel * scale(u))? - 1.0;
        let du = f / d;
        if !du.is_finite() {
            break;
        }
        let mut next = u - du;
        if coord != Coord::Bottom && next <= 0.0 {
            next = 0.5 * u;
        }
        u = next;
        if du.abs() <= 1e-15 * scale(u) {
            break;
        }
    }
    let (fixed_cycle, pu) = map.step(u)?;
    residual = if (pu - u).is_finite() {
        pu - u
    } else {
        residual
    };
    let h = rel * scale(u);
    let slope = map.slope(u, h)?;
    let cf = ClosedForm::of(&sc);
    let closed = cf.and_then(|c| {
        let e = c.fixed_energy()?;
        Some((c, e, c.fixed_slope()?))
    });
    let stable = slope.abs() < 1.0;
    let alpha = cf.and_then(|c| c.alpha());
    let verdict = if stable {
        format!(
            "stable period-1 hopping: |slope| = {:.6} < 1{}",
            slope.abs(),
            if slope < 0.0 {
                " (oscillating approach)"
            } else {
                ""
            }
        )
    } else if slope < -1.0 {
        "unstable through a flip: the slope has passed -1, where the fixed point period-doubles (the late orbit is a period-2 or longer cycle)".to_string()
    } else {
        "unstable: slope > 1".to_string()
    };
    let doubling = alpha.map(|a| {
        format!(
            "period doubling at slope -1, alpha = e^2 = {ALPHA_DOUBLING:.9}; this scene has alpha = {a:.9} ({} e^2)",
            if a < ALPHA_DOUBLING { "<" } else { ">" }
        )
    });
    let x_star = fixed_cycle.bottom_height_m;
    let e_star = fixed_cycle.energy;
    if args.json {
        let v = json!({
            "scene": sc.name,
            "model": model_name(sc.params.model),
            "equation": model_equation(sc.params.model),
            "coordinate": coord.name(),
            "alpha": alpha,
            "alpha_doubling": alpha.map(|_| ALPHA_DOUBLING),
            "fixed_point": {
                "coordinate": u,
                "bottom_height_m": x_star,
                "energy": e_star,
                "residual": residual,
                "newton_iterations": iterations,
            },
            "slope_numerical": slope,
            "finite_difference_step": h,
            "closed_form": closed.map(|(c, e, s)| json!({
                "equation": c.equation(),
                "exact": c.exact(),
                "energy": e,
                "bottom_height_m": c.bottom_of(e),
                "slope": s,
                "slope_difference": slope - s,
            })),
            "stable": stable,
            "verdict": verdict,
            "period_doubling": doubling,
            "late_period": late_period,
        });
        println!("{v}");
        return Ok(());
    }
    let mut s = format!(
        "hopper scene {}: {} model ({})\n  cycle map in the {} ({}, Newton {} iterations, residual {:.1e})\n",
        sc.name,
        model_name(sc.params.model),
        model_equation(sc.params.model),
        coord.name(),
        "simulated hop by hop",
        iterations,
        residual
    );
    s += &format!(
        "  fixed point: x* = {x_star:.12} m, E* = {e_star:.12}{}\n",
        if coord == Coord::TouchdownSpeed {
            format!(", touchdown speed {u:.12} m/s")
        } else {
            String::new()
        }
    );
    s += &format!(
        "  slope of the return map there: {slope:.12} (4th-order central differences, step {h:.3e})\n"
    );
    match closed {
        Some((c, e, cs)) => {
            s += &format!(
                "  closed form ({}{}): E* = {e:.12}, x* = {:.12} m, slope {cs:.12}{}; slope difference {:.3e}\n",
                c.equation(),
                if c.exact() { "" } else { ", untuned scene: approximate" },
                c.bottom_of(e),
                if matches!(c, ClosedForm::Eq19 { .. }) {
                    " = 1 - ln alpha"
                } else {
                    ""
                },
                slope - cs
            );
        }
        None => s += &format!("  closed form: {}\n", super::closed::none_reason(&sc)),
    }
    s += &format!("  verdict: {verdict}\n");
    if let Some(d) = doubling {
        s += &format!("  {d}\n");
    }
    s += &format!(
        "  the scene's own run ({} cycles): late period {}\n",
        cs.len(),
        late_period.map_or("none detected".into(), |p| p.to_string())
    );
    print!("{s}");
    Ok(())
}
