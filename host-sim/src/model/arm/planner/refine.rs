//! Refinement of the constraint samples. The program checks the grasp at fixed samples;
//! an optimum tends to push friction peaks between them. After each solve the verifier
//! steps the plan densely with unlimited friction; every stretch where the friction
//! ratio exceeds the plan's mu adds a sample at its peak (as a fraction of its grasp
//! phase, so it moves with the phase times), and the solve is repeated from there, at
//! most [`ROUNDS`] times.

use super::super::simulate::{execute, Execution};
use super::super::task::Phase;
use super::evaluate::Problem;

/// Solves after the first, per start.
pub const ROUNDS: usize = 3;

/// Peaks of the friction ratio above `mu`: the time of the highest sample of each
/// stretch above it.
fn peaks_above(e: &Execution, mu: f64) -> Vec<f64> {
    let mut out = Vec::new();
    let mut best: Option<(f64, f64)> = None;
    for f in &e.friction {
        if f.ratio > mu && f.phase == Phase::Grasp {
            if best.is_none_or(|b| f.ratio > b.1) {
                best = Some((f.t_s, f.ratio));
            }
        } else if let Some((t, _)) = best.take() {
            out.push(t);
        }
    }
    out.extend(best.map(|b| b.0));
    out
}

/// Add samples where the dense run of design `x` needs more friction than its mu;
/// returns how many were added.
pub fn add_peaks(problem: &mut Problem, x: &[f64]) -> usize {
    let d = problem.layout.decode(x);
    let e = execute(problem.sys, &problem.motion(&d), f64::INFINITY);
    let mut added = 0;
    for t in peaks_above(&e, d.mu * (1.0 + 1e-3)) {
        let mut t0 = 0.0;
        for (i, (&phase, &dur)) in problem.layout.phases.iter().zip(&d.times_s).enumerate() {
            if phase == Phase::Grasp && t >= t0 && t < t0 + dur {
                let f = (t - t0) / dur;
                if !problem.extra[i].iter().any(|g| (g - f).abs() < 1e-6) {
                    problem.extra[i].push(f);
                    added += 1;
                }
            }
            if phase != Phase::Flight {
                t0 += dur;
            }
        }
    }
    added
}
