//! The orbit the sampled loop is measured against: the same model with exactly timed thrust
//! (the valve opens at the true bottom and closes delta later), from eq. 17 where it applies
//! and from the exact event-driven simulator ([`Hopper`]) otherwise.

use super::super::eq17::Eq17;
use super::super::valve::ValveModel;
use super::super::{Hopper, HopperError, HopperModel, RunOptions, Start, ThrustLaw};
use super::stats::{settled_period, SETTLE_WINDOW};
use serde::Serialize;
use std::collections::VecDeque;

/// Most hops the exact simulator runs to find a settled orbit.
pub const MAX_REFERENCE_CYCLES: usize = 20_000;
/// Relative tolerance for the exact simulator's orbit to count as settled.
pub const REFERENCE_TOLERANCE: f64 = 1e-9;
/// Relative detuning |chi_l - chi_eq| / max(1, |chi_eq|) under which eq. 17 applies.
pub const TUNED_TOLERANCE: f64 = 1e-9;

/// The exact-thrust orbit.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct ExactOrbit {
    /// Hop heights (apex - chi_l, m) of one period of the orbit, in the order the exact
    /// simulator visits them (one value for a fixed point).
    pub hop_heights_m: Vec<f64>,
    /// Where it comes from: `"eq. 17"` (closed form, tuned linear model with Raibert's
    /// thrust) or `"exact-thrust simulator"`.
    pub source: &'static str,
}

impl ExactOrbit {
    /// The period.
    pub fn period(&self) -> usize {
        self.hop_heights_m.len()
    }
}

/// The exact-thrust orbit of `model` with `law`, from a flight start at `start_height_m`
/// (used when there is no closed form); `None` if the exact simulator does not settle within
/// [`MAX_REFERENCE_CYCLES`] hops or its run ends early (no liftoff, weak thrust).
pub fn exact_orbit(
    model: &ValveModel,
    law: &ThrustLaw,
    start_height_m: f64,
) -> Result<Option<ExactOrbit>, HopperError> {
    let hopper_model = match model {
        ValveModel::Linear(m) => HopperModel::Linear(*m),
        ValveModel::Full(m) => HopperModel::Full(*m),
    };
    let hopper = Hopper::new(hopper_model, *law)?;
    if let (ValveModel::Linear(m), ThrustLaw::Raibert(r)) = (model, law) {
        let tuned = (m.liftoff_m() - m.equilibrium_m()).abs()
            <= TUNED_TOLERANCE * m.equilibrium_m().abs().max(1.0);
        if tuned {
            let eq = Eq17::new(
                m.omega(),
                m.beta(),
                r.duration_s(),
                r.thrust_mps2() - m.gravity_mps2(),
            );
            if let Some(e) = eq.fixed_point() {
                // eq. 17's bottom, then one exact cycle from it to its apex
                let x = m.equilibrium_m() - (e / m.spring_eta1()).sqrt();
                let run =
                    hopper.simulate(Start::Bottom { height_m: x }, 1, &RunOptions::default())?;
                if let Some(c) = run.cycles.first() {
                    return Ok(Some(ExactOrbit {
                        hop_heights_m: vec![c.apex.height_m - m.liftoff_m()],
                        source: "eq. 17",
                    }));
                }
            }
        }
    }
    simulated_orbit(&hopper, model.liftoff_m(), start_height_m)
}

/// The settled orbit of the exact simulator from a flight start, run in chunks of
/// [`SETTLE_WINDOW`] hops (each from the previous chunk's last apex, the same state).
fn simulated_orbit(
    hopper: &Hopper,
    chi_l: f64,
    start_height_m: f64,
) -> Result<Option<ExactOrbit>, HopperError> {
    let keep = 2 * SETTLE_WINDOW;
    let mut last: VecDeque<f64> = VecDeque::with_capacity(keep + SETTLE_WINDOW);
    let opts = RunOptions {
        times: true,
        samples_per_phase: 0,
    };
    let mut apex = start_height_m;
    for _ in 0..MAX_REFERENCE_CYCLES / SETTLE_WINDOW {
        let start = Start::Flight {
            height_m: apex,
            velocity_mps: 0.0,
        };
        let mut hops = 0;
        let (end, _) = hopper.run(start, SETTLE_WINDOW, &opts, &mut |c| {
            apex = c.apex.height_m;
            last.push_back(apex - chi_l);
            hops += 1;
        })?;
        if hops < SETTLE_WINDOW || end != super::super::RunEnd::Completed {
            return Ok(None);
        }
        while last.len() > keep {
            last.pop_front();
        }
        let v: Vec<f64> = last.iter().copied().collect();
        if let Some(p) = settled_period(&v, REFERENCE_TOLERANCE).period {
            return Ok(Some(ExactOrbit {
                hop_heights_m: v[v.len() - p..].to_vec(),
                source: "exact-thrust simulator",
            }));
        }
    }
    Ok(None)
}
