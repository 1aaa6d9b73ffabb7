//! Zeno sequences: infinitely many bounces in finite time, summed in closed form.
//!
//! Against a surface with constant acceleration `a` (m/s^2, `g + a > 0`), a ball leaving
//! with relative speed `u` (m/s) returns after `2 u / (g + a)` and leaves again with `e u`,
//! so the remaining flights form a geometric series: `sum = 2 u / ((g + a)(1 - e))`, s.

/// When a bounce counts as the start of a Zeno sequence.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ZenoPolicy {
    /// Absolute take-off speed threshold relative to the paddle, m/s.
    pub velocity_threshold_mps: f64,
    /// Threshold relative to the paddle speed at impact, dimensionless.
    pub relative_threshold: f64,
    /// Cap on impacts within one control step (driven paddles) before resting contact is
    /// forced; fixed surfaces need no cap: their Zeno detection is exact.
    pub max_impacts_per_segment: u32,
}

impl ZenoPolicy {
    /// True if a take-off at relative speed `relative_mps` (m/s) with the paddle moving at
    /// `paddle_velocity_mps` (m/s) starts a Zeno sequence.
    #[inline]
    pub fn is_zeno(&self, relative_mps: f64, paddle_velocity_mps: f64) -> bool {
        relative_mps
            <= self
                .velocity_threshold_mps
                .max(self.relative_threshold * paddle_velocity_mps.abs())
    }
}

/// Total time of the remaining bounces, s: `2 u / ((g + a)(1 - e))` for take-off relative
/// speed `u` >= 0, effective gravity `g + a` > 0 and restitution `e` < 1; `None` if the
/// series does not converge (e >= 1 or g + a <= 0).
pub fn remaining_time_s(relative_mps: f64, g_eff_mps2: f64, e: f64) -> Option<f64> {
    if e < 1.0 && g_eff_mps2 > 0.0 && relative_mps >= 0.0 {
        Some(2.0 * relative_mps / (g_eff_mps2 * (1.0 - e)))
    } else {
        None
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn geometric_series_equals_explicit_sum() {
        let (u, g, e) = (0.3, 9.81, 0.7f64);
        let explicit: f64 = (0..2000).map(|n| 2.0 * u * e.powi(n) / g).sum();
        let closed = remaining_time_s(u, g, e).unwrap();
        assert!((closed - explicit).abs() < 1e-14 * explicit);
        assert_eq!(remaining_time_s(u, g, 1.0), None);
        assert_eq!(remaining_time_s(u, -1.0, 0.5), None);
    }

    #[test]
    fn threshold_scales_with_paddle_speed() {
        let p = ZenoPolicy {
            velocity_threshold_mps: 1e-6,
            relative_threshold: 1e-3,
            max_impacts_per_segment: 10,
        };
        assert!(p.is_zeno(5e-7, 0.0));
        assert!(!p.is_zeno(5e-6, 0.0));
        assert!(p.is_zeno(5e-4, 1.0));
    }
}
