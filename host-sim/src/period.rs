//! The period of a late orbit, reported only when the orbit has provably settled to it.
//!
//! A sequence `v` (apex heights, hop energies, ...) has *settled to period p* when its
//! values can no longer move by more than the tolerance: not merely when the last values
//! repeat every p within the tolerance. Near a period doubling the orbit converges slowly
//! (its multiplier is close to -1), and a slowly decaying alternation around a period-p
//! orbit repeats every 2p within any tolerance long before it repeats every p: a test of
//! the last values alone reports the next period ("period 4 just below the second
//! doubling"). So [`settled_period`] asks three things of a candidate p:
//!
//! 1. **Within the tolerance**: the last `m = max(4p, 12)` differences
//!    `d_k = v_k - v_{k-p}` are within the tolerance.
//! 2. **Settled**: the differences either sit at the rounding floor ([`FLOOR_REL`]), or
//!    decay geometrically: with the multiplier estimated by least squares,
//!    `mu = sum d_k d_{k+p} / sum d_k^2` over the window, |mu| < 1, and the most the values
//!    can still move, `max |d| / (1 - |mu|)` (the sum of the geometric tail of the last
//!    differences), is within the tolerance. A multiplier near 1 in modulus (slow
//!    convergence near a doubling) makes that bound large: not settled.
//! 3. **Not still converging to a shorter period**: for every divisor q = p / r (r a prime
//!    factor of p), the lag-q differences are not decaying (their largest magnitude over the
//!    last p differences is not below that over the first p of the window). A genuine
//!    period-p orbit has lag-q differences that repeat exactly; an orbit still converging to
//!    period q has them shrink.
//!
//! The smallest p that passes is the period; `None` means "not settled" (still converging,
//! aperiodic, or too short a sequence). A stationary noise (SIL runs with a noisy sensor)
//! has a multiplier estimate near -1/2: it passes as long as it stays within the tolerance.

/// Differences at or below this fraction of the values' magnitude count as rounding:
/// a period whose differences all sit there has settled whatever their trend.
pub const FLOOR_REL: f64 = 1e-12;

/// Least relative decay of a divisor's differences across the window that counts as
/// "still converging to the shorter period" (rule 3).
pub const DIVISOR_DECAY: f64 = 1e-6;

/// How close two values must be to count as one value of a periodic orbit.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Tolerance {
    /// `|a - b| <= t max(|a|, |b|)`.
    Relative(f64),
    /// `|a - b| <= t (1 + |a|)`.
    Mixed(f64),
}

impl Tolerance {
    /// The allowed difference between `a` and `b`.
    fn allowed(self, a: f64, b: f64) -> f64 {
        match self {
            Tolerance::Relative(t) => t * a.abs().max(b.abs()).max(f64::MIN_POSITIVE),
            Tolerance::Mixed(t) => t * (1.0 + a.abs()),
        }
    }
}

/// Differences a period-p candidate is judged over: `max(4p, 12)`.
pub const fn window(p: usize) -> usize {
    if 4 * p > 12 {
        4 * p
    } else {
        12
    }
}

/// Values [`settled_period`] needs to judge periods up to `max_period`.
pub const fn values_needed(max_period: usize) -> usize {
    window(max_period) + max_period
}

/// The smallest period p <= `max_period` the sequence has settled to (module docs), or
/// `None` (not settled).
pub fn settled_period(v: &[f64], max_period: usize, tol: Tolerance) -> Option<usize> {
    (1..=max_period)
        .find(|&p| settled(v, p, tol))
        .filter(|&p| !converging_to_divisor(v, p))
}

/// Rules 1 and 2 for period `p`.
fn settled(v: &[f64], p: usize, tol: Tolerance) -> bool {
    let n = v.len();
    let m = window(p);
    if p == 0 || n < m + p {
        return false;
    }
    let d = |j: usize| v[n - m + j] - v[n - m + j - p];
    let mut scale = 0.0f64;
    for j in 0..m {
        let (a, b) = (v[n - m + j], v[n - m + j - p]);
        if !(a.is_finite() && b.is_finite()) || (a - b).abs() > tol.allowed(a, b) {
            return false;
        }
        scale = scale.max(a.abs());
    }
    let last = (m - p..m).map(|j| d(j).abs()).fold(0.0, f64::max);
    if (0..m).all(|j| d(j).abs() <= FLOOR_REL * scale) {
        return true;
    }
    let (mut ss, mut sc) = (0.0, 0.0);
    for j in 0..m - p {
        ss += d(j) * d(j);
        sc += d(j) * d(j + p);
    }
    let mu = sc / ss;
    if mu.is_nan() || mu.abs() >= 1.0 {
        return false; // the differences do not decay: not converging to period p
    }
    let a = v[n - 1];
    last / (1.0 - mu.abs()) <= tol.allowed(a, a)
}

/// Rule 3: the orbit's lag-q differences still shrink for some divisor q of `p`.
fn converging_to_divisor(v: &[f64], p: usize) -> bool {
    let n = v.len();
    let m = window(p);
    prime_factors(p).any(|r| {
        let q = p / r;
        let mag = |from: usize| {
            (from..from + p)
                .map(|j| (v[n - m + j] - v[n - m + j - q]).abs())
                .fold(0.0, f64::max)
        };
        let (first, last) = (mag(0), mag(m - p));
        last < first * (1.0 - DIVISOR_DECAY)
    })
}

/// The distinct prime factors of `p`.
fn prime_factors(mut p: usize) -> impl Iterator<Item = usize> {
    let mut out = Vec::new();
    let mut f = 2;
    while f * f <= p {
        if p.is_multiple_of(f) {
            out.push(f);
            while p.is_multiple_of(f) {
                p /= f;
            }
        }
        f += 1;
    }
    if p > 1 {
        out.push(p);
    }
    out.into_iter()
}

#[cfg(test)]
mod tests {
    use super::*;

    const TOL: Tolerance = Tolerance::Relative(1e-3);

    #[test]
    fn exact_and_fast_converging_orbits_have_their_period() {
        assert_eq!(settled_period(&[1.0; 20], 8, TOL), Some(1));
        let p2: Vec<f64> = (0..40).map(|i| [1.2, 0.7][i % 2]).collect();
        assert_eq!(settled_period(&p2, 8, TOL), Some(2));
        let p3: Vec<f64> = (0..60).map(|i| [1.2, 0.7, 0.9][i % 3]).collect();
        assert_eq!(settled_period(&p3, 8, TOL), Some(3));
        let fast: Vec<f64> = (0..60).map(|k| 1.0 + 0.5 * (-0.3f64).powi(k)).collect();
        assert_eq!(settled_period(&fast, 8, TOL), Some(1));
    }

    /// A period-1 orbit whose alternation decays slowly (multiplier -0.99) repeats every 2
    /// within the tolerance long before it repeats every 1: not settled, never "period 2".
    #[test]
    fn a_slowly_converging_orbit_is_not_settled() {
        let x: Vec<f64> = (0..400).map(|k| 1.0 + 0.01 * (-0.99f64).powi(k)).collect();
        let tail = &x[x.len() - 40..];
        assert!(tail
            .iter()
            .zip(&tail[2..])
            .all(|(a, b)| (a - b).abs() < 1e-3));
        assert_eq!(settled_period(&x, 8, TOL), None);
        // the same, converged further: period 1
        let x: Vec<f64> = (0..4000).map(|k| 1.0 + 0.01 * (-0.99f64).powi(k)).collect();
        assert_eq!(settled_period(&x, 8, TOL), Some(1));
    }

    /// A period-2 orbit whose two values differ by less than the tolerance is period 2, not
    /// 1: its lag-1 differences do not decay.
    #[test]
    fn a_narrow_period_two_orbit_is_not_period_one() {
        let x: Vec<f64> = (0..100).map(|k| [1.0, 1.0002][k % 2]).collect();
        assert_eq!(settled_period(&x, 8, TOL), Some(2));
    }

    #[test]
    fn noise_within_the_tolerance_is_period_one_and_chaos_has_none() {
        let mut s = 0.37f64;
        let noisy: Vec<f64> = (0..100)
            .map(|_| {
                s = 3.99 * s * (1.0 - s);
                1.0 + 1e-5 * (s - 0.5)
            })
            .collect();
        assert_eq!(settled_period(&noisy, 8, TOL), Some(1));
        let chaos: Vec<f64> = (0..100)
            .map(|_| {
                s = 3.99 * s * (1.0 - s);
                s
            })
            .collect();
        assert_eq!(settled_period(&chaos, 8, TOL), None);
        assert_eq!(settled_period(&[1.0; 5], 8, TOL), None, "too short");
    }

    #[test]
    fn prime_factors_are_distinct() {
        let f = |p| prime_factors(p).collect::<Vec<_>>();
        assert_eq!(f(1), Vec::<usize>::new());
        assert_eq!(f(8), [2]);
        assert_eq!(f(12), [2, 3]);
        assert_eq!(f(7), [7]);
    }
}
