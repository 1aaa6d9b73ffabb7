//! Joint motions the object is played against: the planned spline (f64) with the
//! controller's braking tail, or a tracked motion from the closed loop.

use super::contact::Joint;
use dexter_core::bspline;

/// A joint motion known at every time.
pub trait ArmMotion {
    /// Joint state at `t_s` (s, >= 0).
    fn joint(&self, t_s: f64) -> Joint;
    /// Time after which the joint is at rest for good, s.
    fn settled_s(&self) -> f64;
    /// End of the planned trajectory, where a throw's release brake begins, s.
    fn release_s(&self) -> f64;
    /// Times where the acceleration may jump (knots, the release, sample instants), s:
    /// the verifier steps exactly onto them.
    fn breaks_s(&self) -> Vec<f64>;
}

/// The planned trajectory: the B-spline on `[0, T]`, then braking at `brake_accel` from
/// the end velocity to rest, then holding (as the core's `ArmController::reference`).
#[derive(Clone, Debug, PartialEq)]
pub struct PlannedMotion {
    /// Control points, rad.
    pub points_rad: Vec<f64>,
    /// Segment duration, s.
    pub segment_s: f64,
    /// Braking deceleration after `T`, rad/s^2.
    pub brake_accel_radps2: f64,
}

impl PlannedMotion {
    /// Spline duration T, s.
    pub fn duration_s(&self) -> f64 {
        (self.points_rad.len() as f64 - 3.0) * self.segment_s
    }

    fn spline(&self, t_s: f64) -> Joint {
        let s = bspline::sample(&self.points_rad, self.segment_s, t_s).unwrap_or_default();
        Joint {
            angle_rad: s.angle_rad,
            velocity_radps: s.velocity_radps,
            accel_radps2: s.accel_radps2,
        }
    }

    /// Time the brake needs after `T`, s.
    fn brake_s(&self) -> f64 {
        self.spline(self.duration_s()).velocity_radps.abs() / self.brake_accel_radps2
    }
}

impl ArmMotion for PlannedMotion {
    fn joint(&self, t_s: f64) -> Joint {
        let end = self.duration_s();
        if t_s <= end {
            return self.spline(t_s);
        }
        let e = self.spline(end);
        let a = self.brake_accel_radps2;
        let w = e.velocity_radps;
        let dir = if w < 0.0 { -1.0 } else { 1.0 };
        let stop = self.brake_s();
        let s = (t_s - end).min(stop);
        let moving = t_s - end < stop;
        Joint {
            angle_rad: e.angle_rad + w * s - 0.5 * dir * a * s * s,
            velocity_radps: if moving { w - dir * a * s } else { 0.0 },
            accel_radps2: if moving { -dir * a } else { 0.0 },
        }
    }

    fn settled_s(&self) -> f64 {
        self.duration_s() + self.brake_s()
    }

    fn release_s(&self) -> f64 {
        self.duration_s()
    }

    fn breaks_s(&self) -> Vec<f64> {
        let n = self.points_rad.len().saturating_sub(3);
        let mut b: Vec<f64> = (0..=n).map(|k| k as f64 * self.segment_s).collect();
        b.push(self.settled_s());
        b
    }
}
