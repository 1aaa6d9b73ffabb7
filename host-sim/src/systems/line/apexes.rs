//! The apex sequence of a run: convergence to the target apex and the settled period, on
//! the whole sequence or in constant memory as the run goes ([`ApexStats`]).

use super::scene::{ControlMode, Scene};
use crate::stream::Tail;

/// Fewest trailing in-band apexes for a run to count as converged.
pub const MIN_CONVERGED_TAIL: usize = 5;

/// The apex sequence of a run in constant memory: the last apex, the count, the length of
/// the trailing run of apexes within the convergence band, and the last
/// [`crate::period::values_needed`]`(analysis.max_period)` apexes. [`converged_after`] and
/// [`detect_period`] on these give the same answers as on the whole sequence.
#[derive(Clone, Debug, PartialEq)]
pub struct ApexStats {
    target: Option<f64>,
    band_m: f64,
    in_band_tail: u64,
    tail: Tail<f64>,
    max_period: u32,
    period_tolerance: f64,
}

impl ApexStats {
    /// For a run of `scene` (its target, if it has one, and its `[analysis]` table).
    pub fn for_scene(scene: &Scene) -> Self {
        let target = (scene.control.mode != ControlMode::None)
            .then_some(scene.control.target_apex_m)
            .flatten();
        let an = &scene.analysis;
        Self {
            target,
            band_m: target.map_or(0.0, |t| an.converge_tolerance * t.abs()),
            in_band_tail: 0,
            tail: Tail::new(crate::period::values_needed(an.max_period as usize)),
            max_period: an.max_period,
            period_tolerance: an.period_tolerance,
        }
    }

    /// The apex after one more impact, m.
    #[inline]
    pub fn push(&mut self, apex_m: f64) {
        match self.target {
            Some(t) if (apex_m - t).abs() <= self.band_m => self.in_band_tail += 1,
            _ => self.in_band_tail = 0,
        }
        self.tail.push(apex_m);
    }

    /// Apexes seen.
    pub fn count(&self) -> u64 {
        self.tail.seen()
    }

    /// The last apex, m.
    pub fn last(&self) -> Option<f64> {
        self.tail.last().copied()
    }

    /// As [`converged_after`] on every apex of the run.
    pub fn converged_after(&self) -> Option<u64> {
        self.target?;
        (self.in_band_tail >= MIN_CONVERGED_TAIL as u64)
            .then(|| self.count() - self.in_band_tail + 1)
    }

    /// As [`detect_period`] on every apex of the run.
    pub fn period(&self) -> Option<u32> {
        let tail = self.tail.to_vec();
        detect_period(&tail, self.max_period, self.period_tolerance)
    }
}

/// Impacts after which all apexes stay within `tol` (relative) of `target`; None if the
/// in-band tail is shorter than [`MIN_CONVERGED_TAIL`].
pub fn converged_after(apexes: &[f64], target: f64, tol: f64) -> Option<u64> {
    let band = tol * target.abs();
    let tail = apexes
        .iter()
        .rev()
        .take_while(|a| (*a - target).abs() <= band)
        .count();
    if tail >= MIN_CONVERGED_TAIL {
        Some((apexes.len() - tail) as u64 + 1)
    } else {
        None
    }
}

/// The smallest period p <= `max_period` the apex sequence has provably settled to, with
/// apexes one period apart equal within `tol` (relative): [`crate::period::settled_period`]
/// (the values can no longer move by more than `tol`, and the orbit is not still converging
/// to a shorter period); `None` if it has not settled.
pub fn detect_period(apexes: &[f64], max_period: u32, tol: f64) -> Option<u32> {
    let tol = crate::period::Tolerance::Relative(tol);
    crate::period::settled_period(apexes, max_period as usize, tol).map(|p| p as u32)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn convergence_counts_impacts_before_the_final_band() {
        let a = [0.5, 0.8, 0.95, 1.005, 0.998, 1.0, 1.001, 0.999];
        assert_eq!(converged_after(&a, 1.0, 0.01), Some(4));
        assert_eq!(converged_after(&a[..6], 1.0, 0.01), None); // tail of 3 only
        assert_eq!(converged_after(&[0.5; 20], 1.0, 0.01), None);
    }

    /// ApexStats over a stream gives what the functions give on the whole sequence.
    #[test]
    fn streaming_statistics_equal_the_whole_sequence() {
        let mut scene = Scene::default();
        scene.control.mode = ControlMode::IdealMirror;
        scene.control.target_apex_m = Some(1.0);
        scene.analysis.max_period = 3;
        // settling, a period-3 stretch, a period-2 stretch, noise, convergence
        let mut seq = Vec::new();
        let mut x = 0.37_f64;
        for i in 0..400 {
            x = 3.9 * x * (1.0 - x);
            seq.push(match i {
                0..=99 => 1.0 + 0.5 * (-(i as f64) / 20.0).exp(),
                100..=199 => [0.8, 1.1, 1.3][i % 3],
                200..=299 => [0.9, 1.2][i % 2],
                _ => 1.0 + 0.02 * (x - 0.5),
            });
        }
        for n in [0, 3, 14, 15, 99, 150, 160, 250, 399, 400] {
            let mut stats = ApexStats::for_scene(&scene);
            for &a in &seq[..n] {
                stats.push(a);
            }
            let whole = &seq[..n];
            assert_eq!(
                stats.converged_after(),
                converged_after(whole, 1.0, 0.01),
                "{n}"
            );
            assert_eq!(stats.period(), detect_period(whole, 3, 1e-3), "{n}");
            assert_eq!(stats.last(), whole.last().copied(), "{n}");
        }
    }

    #[test]
    fn period_two_is_found_and_period_one_preferred() {
        let p2: Vec<f64> = (0..20)
            .map(|i| if i % 2 == 0 { 1.2 } else { 0.7 })
            .collect();
        assert_eq!(detect_period(&p2, 8, 1e-6), Some(2));
        assert_eq!(detect_period(&[1.0; 20], 8, 1e-6), Some(1));
        let chaos: Vec<f64> = (0..50).map(|i| (i as f64 * 1.7).sin()).collect();
        assert_eq!(detect_period(&chaos, 8, 1e-6), None);
    }
}
