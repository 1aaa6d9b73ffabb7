//! Summaries of a sampled run in constant memory: timing statistics of the detected phase
//! transitions against the true ones, and the settled period of the apex sequence.

use serde::Serialize;

/// Count, mean, min and max of a timing error, s.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Timing {
    /// Values seen.
    pub count: u64,
    /// Mean, s (NaN if none; `null` in JSON).
    pub mean_s: f64,
    /// Smallest, s.
    pub min_s: f64,
    /// Largest, s.
    pub max_s: f64,
    #[serde(skip)]
    sum_s: f64,
}

impl Default for Timing {
    fn default() -> Self {
        Self {
            count: 0,
            mean_s: f64::NAN,
            min_s: f64::NAN,
            max_s: f64::NAN,
            sum_s: 0.0,
        }
    }
}

impl Timing {
    /// Add one value (non-finite values are ignored).
    pub fn push(&mut self, value_s: f64) {
        if !value_s.is_finite() {
            return;
        }
        self.count += 1;
        self.sum_s += value_s;
        self.mean_s = self.sum_s / self.count as f64;
        self.min_s = if self.count == 1 {
            value_s
        } else {
            self.min_s.min(value_s)
        };
        self.max_s = if self.count == 1 {
            value_s
        } else {
            self.max_s.max(value_s)
        };
    }
}

/// How one kind of detected transition compares with the true event.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
pub struct EventErrors {
    /// True events (one per completed cycle that has one).
    pub events: u64,
    /// True events with no detection in their cycle.
    pub missed: u64,
    /// Detections beyond the first in a cycle (chatter), and detections in a cycle without
    /// the true event.
    pub spurious: u64,
    /// Detection time minus true time, s, of the first detection in each cycle.
    pub lag: Timing,
}

impl EventErrors {
    /// One cycle: whether it has the true event at `true_s`, and its `detections`, the
    /// first at `detected_s`.
    pub fn cycle(&mut self, true_s: Option<f64>, detections: u32, detected_s: f64) {
        match true_s {
            Some(t) => {
                self.events += 1;
                if detections == 0 {
                    self.missed += 1;
                } else {
                    self.spurious += u64::from(detections - 1);
                    self.lag.push(detected_s - t);
                }
            }
            None => self.spurious += u64::from(detections),
        }
    }
}

/// `phase_detection_errors`: the controller's detected phase transitions against the
/// plant's true events, per completed cycle (touchdown to touchdown).
///
/// - `touchdown`, `liftoff`: detection of the contact changes (`Flight` -> `Compression`,
///   any stance phase -> `Flight`); lag = detection step time - true event time.
/// - `bottom`: the end of `Compression` (the bottom decision); lag = decision time - true
///   bottom time (chi' = 0).
/// - `thrust_start_s`: valve opening - true bottom (the exact law opens at the bottom);
///   `thrust_end_s`: valve closing - (true bottom + delta) (the exact law closes then).
/// - `phase_mismatch_steps`: control steps whose detected contact (stance or flight)
///   differs from the true contact at the step.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
pub struct PhaseDetectionErrors {
    /// Touchdown detection.
    pub touchdown: EventErrors,
    /// Bottom detection.
    pub bottom: EventErrors,
    /// Liftoff detection.
    pub liftoff: EventErrors,
    /// Valve opening - true bottom, s.
    pub thrust_start_s: Timing,
    /// Valve closing - (true bottom + delta), s.
    pub thrust_end_s: Timing,
    /// Steps whose detected contact differs from the truth.
    pub phase_mismatch_steps: u64,
    /// Steps compared.
    pub steps: u64,
}

/// Hops per window of [`settled_period`].
pub const SETTLE_WINDOW: usize = 32;

/// Longest period [`settled_period`] looks for.
pub const MAX_SETTLE_PERIOD: usize = 8;

/// Why a period was or was not reported.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Settle {
    /// The settled period, if any.
    pub period: Option<usize>,
    /// The tolerance used, relative to the mean value.
    pub tolerance: f64,
    /// For the reported period (or period 1 if none): the largest spread of one phase of the
    /// orbit over the last 2 windows, relative to the mean.
    pub spread: f64,
    /// For the reported period (or period 1): the change of the orbit's amplitude (largest
    /// minus smallest phase mean) from the older window to the newer, relative to the mean.
    pub amplitude_change: f64,
}

/// The settled period of the last `2 SETTLE_WINDOW` values, honest about convergence
/// (a period is reported only once the orbit provably settled to it): the smallest
/// p <= [`MAX_SETTLE_PERIOD`] such that
///
/// 1. every phase of the orbit (the values i = j mod p, over both windows) stays within
///    `tol` of the mean value (max - min <= tol |mean|), so nothing drifted by more than the
///    tolerance over 2 windows; and
/// 2. the orbit's amplitude (the spread of its p phase means) changed by at most tol/2
///    between the older and the newer window: a p-cycle still growing or decaying (a
///    convergence to a lower period near a doubling) is not settled.
///
/// A contraction slower than about tol / (2 SETTLE_WINDOW) per hop of the mean cannot be
/// resolved in the window and passes. `None` if no p passes or there are fewer than
/// 2 windows of values (not settled).
pub fn settled_period(values: &[f64], tol: f64) -> Settle {
    let n = 2 * SETTLE_WINDOW;
    let mut out = Settle {
        period: None,
        tolerance: tol,
        spread: f64::NAN,
        amplitude_change: f64::NAN,
    };
    if values.len() < n || values[values.len() - n..].iter().any(|v| !v.is_finite()) {
        return out;
    }
    let tail = &values[values.len() - n..];
    let scale = tail.iter().map(|v| v.abs()).sum::<f64>() / n as f64;
    if scale <= 0.0 {
        return out;
    }
    for p in 1..=MAX_SETTLE_PERIOD {
        let (spread, change) = orbit_spread(tail, p);
        let (spread, change) = (spread / scale, change / scale);
        let settled = spread <= tol && change <= 0.5 * tol;
        if p == 1 || settled {
            out.spread = spread;
            out.amplitude_change = change;
        }
        if settled {
            out.period = Some(p);
            return out;
        }
    }
    out
}

/// For period p: (the largest max - min over the p phases of the orbit, the change of the
/// orbit's amplitude, max - min of the phase means, from the first half to the second).
fn orbit_spread(tail: &[f64], p: usize) -> (f64, f64) {
    let half = tail.len() / 2;
    let mut spread = 0.0f64;
    let mut old_means = [0.0f64; MAX_SETTLE_PERIOD];
    let mut new_means = [0.0f64; MAX_SETTLE_PERIOD];
    for j in 0..p {
        let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
        let (mut sum_old, mut n_old, mut sum_new, mut n_new) = (0.0, 0.0, 0.0, 0.0);
        for (i, &v) in tail.iter().enumerate().skip(j).step_by(p) {
            lo = lo.min(v);
            hi = hi.max(v);
            if i < half {
                (sum_old, n_old) = (sum_old + v, n_old + 1.0);
            } else {
                (sum_new, n_new) = (sum_new + v, n_new + 1.0);
            }
        }
        spread = spread.max(hi - lo);
        old_means[j] = sum_old / f64::max(n_old, 1.0);
        new_means[j] = sum_new / f64::max(n_new, 1.0);
    }
    let amplitude = |m: &[f64]| {
        let lo = m.iter().copied().fold(f64::INFINITY, f64::min);
        let hi = m.iter().copied().fold(f64::NEG_INFINITY, f64::max);
        hi - lo
    };
    let change = (amplitude(&new_means[..p]) - amplitude(&old_means[..p])).abs();
    (spread, change)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fixed_point_and_two_cycle_are_found() {
        let ones = vec![2.0; 100];
        assert_eq!(settled_period(&ones, 1e-6).period, Some(1));
        let two: Vec<f64> = (0..100)
            .map(|i| if i % 2 == 0 { 1.0 } else { 3.0 })
            .collect();
        assert_eq!(settled_period(&two, 1e-6).period, Some(2));
        let four: Vec<f64> = (0..100).map(|i| [1.0, 3.0, 1.5, 2.5][i % 4]).collect();
        assert_eq!(settled_period(&four, 1e-6).period, Some(4));
        assert_eq!(settled_period(&ones[..60], 1e-6).period, None, "too short");
    }

    #[test]
    fn a_slowly_decaying_alternation_is_not_a_two_cycle() {
        // multiplier -0.99 near a doubling: x_n = 2 + 0.5 (-0.99)^n. Over the last 64 values
        // each phase moves by 0.5 (0.99^36 - 0.99^100) ~ 0.165: neither period 1 nor 2 at 1e-3
        let decaying: Vec<f64> = (0..100).map(|i| 2.0 + 0.5 * (-0.99f64).powi(i)).collect();
        let s = settled_period(&decaying, 1e-3);
        assert_eq!(s.period, None, "{s:?}");
        // a growing alternation (leaving an unstable fixed point) is not settled either
        let growing: Vec<f64> = (0..100).map(|i| 2.0 + 1e-3 * (-1.01f64).powi(i)).collect();
        assert_eq!(settled_period(&growing, 1e-4).period, None);
    }

    #[test]
    fn jitter_within_the_tolerance_is_settled() {
        // a period-1 orbit with +-3e-4 relative jitter settles at 1e-3
        let jit: Vec<f64> = (0..100)
            .map(|i| 1.0 + 3e-4 * ((i * 7919) % 13) as f64 / 13.0)
            .collect();
        let s = settled_period(&jit, 1e-3);
        assert_eq!(s.period, Some(1));
        assert!(s.spread < 1e-3);
    }

    #[test]
    fn timing_and_event_errors() {
        let mut e = EventErrors::default();
        e.cycle(Some(1.0), 1, 1.002);
        e.cycle(Some(2.0), 3, 2.001);
        e.cycle(Some(3.0), 0, f64::NAN);
        e.cycle(None, 2, 4.0);
        assert_eq!((e.events, e.missed, e.spurious), (3, 1, 4));
        assert_eq!(e.lag.count, 2);
        assert!((e.lag.mean_s - 0.0015).abs() < 1e-12);
        assert!((e.lag.min_s - 0.001).abs() < 1e-12 && (e.lag.max_s - 0.002).abs() < 1e-12);
    }
}
