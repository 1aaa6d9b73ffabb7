//! Return maps, periods and bifurcations extracted from simulated hops (sec. 2.3, 4).
//!
//! - [`bottom_heights`] / [`energies`]: the sequences x_n (eq. 15's coordinate) and E_n
//!   (eq. 18/19, or eq. 17's normalized energy for the linear model).
//! - [`return_map`]: the pairs (v_n, v_{n+1}) to plot against the closed forms.
//! - [`detect_period`]: the smallest period of the late orbit within a tolerance.
//! - [`sweep_thrust`]: bifurcation-diagram points (tau, late E_n values) over the thrust.
//! - [`locate_first_doubling`]: the first period doubling, by bisection on the detected
//!   period with a bounded number of steps.

use super::{Cycle, Hopper, HopperError, RunEnd, RunOptions, Start};

/// Most periods [`detect_period`] is asked to look for in a sweep.
pub const MAX_PERIOD: usize = 64;

/// x_n of each cycle, m.
pub fn bottom_heights(cycles: &[Cycle]) -> Vec<f64> {
    cycles.iter().map(|c| c.bottom_height_m).collect()
}

/// E_n of each cycle (see [`Cycle::energy`]).
pub fn energies(cycles: &[Cycle]) -> Vec<f64> {
    cycles.iter().map(|c| c.energy).collect()
}

/// The return-map pairs (v_n, v_{n+1}).
pub fn return_map(values: &[f64]) -> Vec<(f64, f64)> {
    values.windows(2).map(|w| (w[0], w[1])).collect()
}

/// The smallest p in 1..=`max_period` such that every value of the last `2 p` (at least
/// 8) satisfies |v_i - v_{i-p}| <= `tol` (1 + |v_i|); `None` if none does (aperiodic,
/// chaotic, or not yet settled) or the sequence is too short.
pub fn detect_period(values: &[f64], max_period: usize, tol: f64) -> Option<usize> {
    (1..=max_period).find(|&p| {
        let window = (2 * p).max(8);
        if values.len() < window + p {
            return false;
        }
        let n = values.len();
        (n - window..n).all(|i| {
            let (a, b) = (values[i], values[i - p]);
            a.is_finite() && (a - b).abs() <= tol * (1.0 + a.abs())
        })
    })
}

/// One point of a bifurcation diagram.
#[derive(Clone, Debug, PartialEq)]
pub struct SweepPoint {
    /// The thrust tau, m/s^2.
    pub thrust_mps2: f64,
    /// The late-orbit energies E_n (the last `keep` cycles).
    pub values: Vec<f64>,
    /// Their detected period ([`detect_period`] with the sweep's tolerance).
    pub period: Option<usize>,
    /// How the run ended.
    pub end: RunEnd,
}

/// Late-orbit energies of `hopper` with fixed thrust `tau` from `start`: `transient` cycles
/// dropped, then `keep` kept (map-only run: no eq. 9 times).
pub fn late_orbit(
    hopper: &Hopper,
    tau: f64,
    start: Start,
    transient: usize,
    keep: usize,
) -> Result<(Vec<f64>, RunEnd, Option<f64>), HopperError> {
    let h = hopper.with_thrust(tau)?;
    let mut vals = Vec::with_capacity(keep);
    let mut last_x = None;
    let opts = RunOptions {
        times: false,
        samples_per_phase: 0,
    };
    let (end, _) = h.run(start, transient + keep, &opts, &mut |c| {
        if c.index >= transient {
            vals.push(c.energy);
        }
        last_x = Some(c.bottom_height_m);
    })?;
    Ok((vals, end, last_x))
}

/// Bifurcation diagram over the thrust: for each tau in `thrusts` (m/s^2), the late orbit
/// of [`late_orbit`] and its period (tolerance `tol`).
pub fn sweep_thrust(
    hopper: &Hopper,
    start: Start,
    thrusts: &[f64],
    transient: usize,
    keep: usize,
    tol: f64,
) -> Result<Vec<SweepPoint>, HopperError> {
    thrusts
        .iter()
        .map(|&tau| {
            let (values, end, _) = late_orbit(hopper, tau, start, transient, keep)?;
            let period = detect_period(&values, MAX_PERIOD.min(keep / 3).max(1), tol);
            Ok(SweepPoint {
                thrust_mps2: tau,
                values,
                period,
                end,
            })
        })
        .collect()
}

/// The bracket found by [`locate_first_doubling`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Doubling {
    /// Largest thrust classified period 1, m/s^2.
    pub below_mps2: f64,
    /// Smallest thrust classified period >= 2, m/s^2.
    pub above_mps2: f64,
    /// Bisection steps used.
    pub steps: u32,
}

impl Doubling {
    /// The estimate, the bracket's midpoint, m/s^2.
    pub fn estimate_mps2(&self) -> f64 {
        0.5 * (self.below_mps2 + self.above_mps2)
    }
}

/// Relative change of the alternation amplitude over the second half of a probe below which
/// a detected period >= 2 counts as settled.
pub const SETTLED_REL: f64 = 1e-6;

/// Classification of one probe (see [`locate_first_doubling`]): true if period >= 2; and
/// the continuation start for the next probe if period 1.
fn classify(
    hopper: &Hopper,
    tau: f64,
    start: Start,
    cycles: usize,
    tol: f64,
) -> Result<(bool, Option<Start>), HopperError> {
    let h = hopper.with_thrust(tau)?;
    let opts = RunOptions {
        times: false,
        samples_per_phase: 0,
    };
    let cycles = cycles.max(4 * MAX_PERIOD);
    let mut e = Vec::with_capacity(cycles);
    let mut last_x = [f64::NAN; 2];
    let (end, _) = h.run(start, cycles, &opts, &mut |c| {
        e.push(c.energy);
        last_x = [last_x[1], c.bottom_height_m];
    })?;
    if end != RunEnd::Completed {
        return Err(HopperError::Relation {
            param: "hopper.thrust_tau_mps2",
            requirement: "a bisection probe that completes its cycles (it stalled)",
        });
    }
    let n = e.len();
    let half = (n / 2) & !1;
    let amp = |i: usize| (e[i] - e[i - 1]).abs();
    let (a_end, a_mid) = (amp(n - 1), amp(n - 1 - half));
    let doubled = match detect_period(&e[n - 3 * MAX_PERIOD..], MAX_PERIOD, tol) {
        Some(1) => false,
        Some(_) if (a_end / a_mid - 1.0).abs() <= SETTLED_REL => true,
        _ => a_end >= a_mid,
    };
    let next_start = (!doubled).then(|| Start::Bottom {
        height_m: 0.5 * (last_x[0] + last_x[1]),
    });
    Ok((doubled, next_start))
}

/// Locate the first period doubling in thrust between `below_mps2` (period 1) and
/// `above_mps2` (period >= 2) by at most `max_steps` bisection steps; stops early once the
/// bracket is narrower than `resolution_mps2` (m/s^2). Errors if the ends are not
/// classified as claimed.
///
/// Each probe is a map-only run of `cycles` hops (at least 256), classified by its
/// detected period (tolerance `tol`) and, when unsettled, by the trend of its alternation
/// amplitude a = |E_n - E_n-1| between mid-run and the end:
/// - a detected period 1 is period 1;
/// - a detected period p >= 2 whose amplitude held over the second half
///   (|a / a_mid - 1| <= [`SETTLED_REL`]) is period p;
/// - otherwise the orbit has not settled (near the bifurcation the multiplier is close to
///   -1, and a slowly decaying alternation can even pass a period-2 test): a decaying
///   alternation is still converging to the fixed point (period 1), a growing one is being
///   attracted by a period-2 orbit.
///
/// The trend is decisive because probes after the first start near the fixed point: at the
/// midpoint of the last two bottoms of the latest period-1 probe (continuation), where the
/// alternation is smaller than the period-2 orbit that appears above the bifurcation.
#[allow(clippy::too_many_arguments)]
pub fn locate_first_doubling(
    hopper: &Hopper,
    start: Start,
    below_mps2: f64,
    above_mps2: f64,
    max_steps: u32,
    cycles: usize,
    tol: f64,
    resolution_mps2: f64,
) -> Result<Doubling, HopperError> {
    let (lo_doubled, lo_next) = classify(hopper, below_mps2, start, cycles, tol)?;
    if lo_doubled {
        return Err(HopperError::Relation {
            param: "below_mps2",
            requirement: "a period-1 thrust (the lower bracket end)",
        });
    }
    let (hi_doubled, _) = classify(hopper, above_mps2, start, cycles, tol)?;
    if !hi_doubled {
        return Err(HopperError::Relation {
            param: "above_mps2",
            requirement: "a period >= 2 thrust (the upper bracket end)",
        });
    }
    let (mut lo, mut hi) = (below_mps2, above_mps2);
    let mut from = lo_next.unwrap_or(start);
    let mut steps = 0;
    while steps < max_steps && hi - lo > resolution_mps2 {
        let mid = 0.5 * (lo + hi);
        let (doubled, next) = classify(hopper, mid, from, cycles, tol)?;
        if doubled {
            hi = mid;
        } else {
            lo = mid;
            from = next.unwrap_or(from);
        }
        steps += 1;
    }
    Ok(Doubling {
        below_mps2: lo,
        above_mps2: hi,
        steps,
    })
}
