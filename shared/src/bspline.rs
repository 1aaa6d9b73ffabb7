//! Uniform cubic B-spline joint trajectories (Akella, Huang, Lynch & Mason, sec. 2.1).
//!
//! The paper plans each joint's position history as a cubic B-spline whose "knot points"
//! are evenly spaced in time; the trajectory is C^2 and piecewise cubic, its velocity C^1
//! and piecewise quadratic, its acceleration C^0 and piecewise linear. We store the
//! spline's control (de Boor) points `P_0 .. P_{n-1}`, rad, and the duration `h` of one
//! segment, s. With `n` points there are `n - 3` segments and the spline spans
//! `[0, T]`, `T = (n - 3) h`. On segment `j` (`t = (j + s) h`, `s` in `[0, 1]`):
//!
//! ```text
//! theta(t)   = [ (1-s)^3 P_j + (3s^3 - 6s^2 + 4) P_j+1 + (-3s^3 + 3s^2 + 3s + 1) P_j+2 + s^3 P_j+3 ] / 6
//! theta'(t)  = [ -(1-s)^2 P_j + (3s^2 - 4s) P_j+1 + (-3s^2 + 2s + 1) P_j+2 + s^2 P_j+3 ] / (2h)
//! theta''(t) = [ (1-s) P_j + (3s - 2) P_j+1 + (1 - 3s) P_j+2 + s P_j+3 ] / h^2
//! ```
//!
//! Two properties the planner and the controller rely on:
//! - at `t = 0`, `theta = (P_0 + 4 P_1 + P_2)/6`, `theta' = (P_2 - P_0)/(2h)`,
//!   `theta'' = (P_0 - 2 P_1 + P_2)/h^2`: three equal first points start the joint at rest
//!   with zero acceleration (and likewise at `t = T` with the last three);
//! - convex hull: `theta(t)` lies within `[min P, max P]` and `theta'(t)` within the range
//!   of the differences `(P_i+1 - P_i)/h`, so bounds on points bound the whole curve.
//!
//! Evaluation is O(1): one segment index and four points, no loop, for any `n`.

use crate::math::Real;
use crate::params::{positive, ParamError};
use serde::{Deserialize, Serialize};

/// The most control points a [`Knots`] buffer holds (the capacity on the wire).
pub const MAX_KNOTS: usize = 16;
/// The fewest control points of a cubic B-spline (one segment).
pub const MIN_KNOTS: usize = 4;

/// Position, velocity and acceleration of the spline at one instant, SI units.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct SplineSample<R> {
    /// Joint angle theta, rad.
    pub angle_rad: R,
    /// Joint velocity theta', rad/s.
    pub velocity_radps: R,
    /// Joint acceleration theta'', rad/s^2.
    pub accel_radps2: R,
}

/// Evaluate the uniform cubic B-spline with control points `points_rad` (rad) and segment
/// duration `segment_s` (s, > 0) at time `t_s` (s). Times outside `[0, T]` are clamped to
/// the nearest end (the end's position, velocity and acceleration). `None` if there are
/// fewer than [`MIN_KNOTS`] points, `segment_s` is not > 0, or `t_s` is NaN.
pub fn sample<R: SegmentIndex>(points_rad: &[R], segment_s: R, t_s: R) -> Option<SplineSample<R>> {
    let segments = points_rad.len().checked_sub(3).filter(|&s| s >= 1)?;
    // written so that NaN fails: `segment_s > 0` and `t_s` comparable
    let valid = segment_s > R::ZERO && t_s.partial_cmp(&t_s).is_some();
    if !valid {
        return None;
    }
    let u = (t_s / segment_s).clamp_r(R::ZERO, R::of_index(segments));
    // u >= 0 and finite here, so the cast truncates toward zero: floor(u)
    let j = u.floor_index().min(segments - 1);
    let s = u - R::of_index(j);
    let p = points_rad.get(j..j + 4)?;
    let (p0, p1, p2, p3) = (p[0], p[1], p[2], p[3]);
    Some(basis(s, [p0, p1, p2, p3], segment_s))
}

/// The conversions between a spline parameter and a segment index, done in the scalar's
/// own precision: on the target an `f32` converts to and from an index with one FPU
/// instruction (`vcvt`), where a detour through `f64` would pull in software
/// double-precision routines (about 0.5 KB of flash on a Cortex-M4F, and their cycles).
pub trait SegmentIndex: Real {
    /// `floor(self)` as an index, for finite `self >= 0` (saturating; NaN gives 0).
    fn floor_index(self) -> usize;
    /// The index as a scalar (exact below 2^24 for `f32`; segments are at most 13).
    fn of_index(index: usize) -> Self;
}

impl SegmentIndex for f32 {
    #[inline]
    fn floor_index(self) -> usize {
        self as usize
    }
    #[inline]
    fn of_index(index: usize) -> Self {
        index as f32
    }
}

impl SegmentIndex for f64 {
    #[inline]
    fn floor_index(self) -> usize {
        self as usize
    }
    #[inline]
    fn of_index(index: usize) -> Self {
        index as f64
    }
}

/// The segment polynomials above at local parameter `s` in `[0, 1]`.
#[inline]
fn basis<R: Real>(s: R, p: [R; 4], h: R) -> SplineSample<R> {
    let one = R::ONE;
    let three = R::of(3.0);
    let six = R::of(6.0);
    let u = one - s;
    let s2 = s * s;
    let s3 = s2 * s;
    let angle = (u * u * u * p[0]
        + (three * s3 - six * s2 + R::of(4.0)) * p[1]
        + (-three * s3 + three * s2 + three * s + one) * p[2]
        + s3 * p[3])
        / six;
    let velocity = (-(u * u) * p[0]
        + (three * s2 - R::of(4.0) * s) * p[1]
        + (-three * s2 + R::TWO * s + one) * p[2]
        + s2 * p[3])
        / (R::TWO * h);
    let accel =
        (u * p[0] + (three * s - R::TWO) * p[1] + (one - three * s) * p[2] + s * p[3]) / (h * h);
    SplineSample {
        angle_rad: angle,
        velocity_radps: velocity,
        accel_radps2: accel,
    }
}

/// A cubic B-spline joint trajectory of at most [`MAX_KNOTS`] control points, f32, as the
/// controller receives it (postcard: 1 + 4 + 64 bytes).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Knots {
    /// Number of control points in use, in `[MIN_KNOTS, MAX_KNOTS]`.
    pub count: u8,
    /// Duration of one spline segment, s (> 0); the spline spans `(count - 3)` segments.
    pub segment_s: f32,
    /// Control points, rad; entries at and after `count` are ignored.
    pub points_rad: [f32; MAX_KNOTS],
}

impl Default for Knots {
    /// A one-segment spline at rest at 0 rad lasting 0.1 s.
    fn default() -> Self {
        Self {
            count: MIN_KNOTS as u8,
            segment_s: 0.1,
            points_rad: [0.0; MAX_KNOTS],
        }
    }
}

impl Knots {
    /// Control points from a slice (rad) and a segment duration (s); the error names
    /// `trajectory.count` if there are too few or too many points.
    pub fn from_slice(points_rad: &[f32], segment_s: f32) -> Result<Self, ParamError> {
        if !(MIN_KNOTS..=MAX_KNOTS).contains(&points_rad.len()) {
            return Err(ParamError::OutOfRange("trajectory.count"));
        }
        let mut k = Self {
            count: points_rad.len() as u8,
            segment_s,
            ..Self::default()
        };
        for (dst, src) in k.points_rad.iter_mut().zip(points_rad) {
            *dst = *src;
        }
        k.validate()?;
        Ok(k)
    }

    /// Check count, segment duration and that every used point is finite.
    pub fn validate(&self) -> Result<(), ParamError> {
        if !(MIN_KNOTS..=MAX_KNOTS).contains(&(self.count as usize)) {
            return Err(ParamError::OutOfRange("trajectory.count"));
        }
        positive("trajectory.segment_s", self.segment_s)?;
        if self.points().iter().any(|p| !p.is_finite()) {
            return Err(ParamError::NotFinite("trajectory.points_rad"));
        }
        Ok(())
    }

    /// The control points in use, rad.
    pub fn points(&self) -> &[f32] {
        let n = (self.count as usize).min(MAX_KNOTS);
        self.points_rad.get(..n).unwrap_or(&[])
    }

    /// Total duration `T = (count - 3) segment_s`, s.
    pub fn duration_s(&self) -> f32 {
        (self.count as f32 - 3.0).max(0.0) * self.segment_s
    }

    /// The spline at `t_s` (clamped to `[0, T]`); `None` only for an invalid buffer or NaN.
    pub fn sample(&self, t_s: f32) -> Option<SplineSample<f32>> {
        sample(self.points(), self.segment_s, t_s)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Independent reference: de Boor's recursion on the uniform knot vector
    /// `t_k = (k - 3) h`, k = 0 .. n + 3, for the position.
    fn de_boor(p: &[f64], h: f64, t: f64) -> f64 {
        let n = p.len();
        let knot = |k: usize| (k as f64 - 3.0) * h;
        let j = ((t / h).floor() as usize).min(n - 4) + 3; // t in [knot(j), knot(j+1))
        let mut d: Vec<f64> = (0..4).map(|r| p[j - 3 + r]).collect();
        for r in 1..=3 {
            for i in (r..=3).rev() {
                let k = i + j - 3;
                let a = (t - knot(k)) / (knot(k + 4 - r) - knot(k));
                d[i] = (1.0 - a) * d[i - 1] + a * d[i];
            }
        }
        d[3]
    }

    const P: [f64; 9] = [0.0, 0.1, -0.3, 0.5, 0.9, 0.2, -0.1, 0.4, 0.4];

    #[test]
    fn matches_de_boor_and_finite_differences() {
        let h = 0.07;
        for i in 0..=120 {
            let t = i as f64 * 6.0 * h / 120.0;
            let s = sample(&P, h, t).unwrap();
            assert!((s.angle_rad - de_boor(&P, h, t)).abs() < 1e-12, "t = {t}");
            let e = 1e-6;
            if t > e && t < 6.0 * h - e {
                let fd_v = (de_boor(&P, h, t + e) - de_boor(&P, h, t - e)) / (2.0 * e);
                assert!((s.velocity_radps - fd_v).abs() < 1e-5, "velocity at {t}");
                let v = |t| sample(&P, h, t).unwrap().velocity_radps;
                let fd_a = (v(t + e) - v(t - e)) / (2.0 * e);
                // the jerk jumps at knots: central differences err by ~e * jump there
                assert!((s.accel_radps2 - fd_a).abs() < 1e-2, "accel at {t}");
            }
        }
    }

    #[test]
    fn three_equal_points_start_at_rest_and_curve_stays_in_hull() {
        let p = [0.2, 0.2, 0.2, 1.0, -0.5, 0.3];
        let s = sample(&p, 0.1, 0.0).unwrap();
        assert!((s.angle_rad - 0.2).abs() < 1e-15);
        assert!(s.velocity_radps.abs() < 1e-12 && s.accel_radps2.abs() < 1e-12);
        for i in 0..=300 {
            let s = sample(&p, 0.1, i as f64 * 0.001).unwrap();
            assert!((-0.5..=1.0).contains(&s.angle_rad));
            assert!(
                s.velocity_radps.abs() <= 15.0 + 1e-9,
                "|dP|/h bounds velocity"
            );
        }
    }

    #[test]
    fn clamps_outside_and_rejects_bad_input() {
        let end = sample(&P, 0.1, 0.6).unwrap();
        let after = sample(&P, 0.1, 5.0).unwrap();
        assert!((after.angle_rad - end.angle_rad).abs() < 1e-12);
        assert!((after.accel_radps2 - end.accel_radps2).abs() < 1e-9);
        assert_eq!(sample(&P, 0.1, -1.0), sample(&P, 0.1, 0.0));
        assert_eq!(sample(&P[..3], 0.1, 0.0), None);
        assert_eq!(sample(&P, 0.0, 0.0), None);
        assert_eq!(sample(&P, 0.1, f64::NAN), None);
        assert!(sample(&P, 0.1, f64::INFINITY).is_some());
    }

    #[test]
    fn knots_buffer_validates_and_matches_f64() {
        let pts: Vec<f32> = P.iter().map(|&p| p as f32).collect();
        let k = Knots::from_slice(&pts, 0.05).unwrap();
        assert!((k.duration_s() - 0.3).abs() < 1e-7);
        let a = k.sample(0.123).unwrap().angle_rad as f64;
        assert!((a - sample(&P, 0.05, 0.123).unwrap().angle_rad).abs() < 1e-6);
        assert_eq!(
            Knots::from_slice(&pts[..3], 0.05),
            Err(ParamError::OutOfRange("trajectory.count"))
        );
        let mut bad = k;
        bad.points_rad[2] = f32::NAN;
        assert_eq!(
            bad.validate(),
            Err(ParamError::NotFinite("trajectory.points_rad"))
        );
        bad.count = 40;
        assert_eq!(
            bad.validate(),
            Err(ParamError::OutOfRange("trajectory.count"))
        );
        let _ = bad.sample(0.0); // never panics, whatever the count
        let bytes = postcard::to_allocvec(&k).unwrap();
        assert!(bytes.len() <= 69, "{} bytes", bytes.len());
    }
}
