//! Joint motions the object is played against: the planned spline (f64) with the
//! controller's braking tail, or a tracked motion from the closed loop.

use super::contact::Joint;
use dexter_core::bang_bang::BangBang;
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

/// How the arm comes to rest after its spline: the core's bang-bang move
/// ([`dexter_core::bang_bang`]), braking wherever it stops, or reaching a catch angle.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RestMove {
    /// Acceleration bound of the move, rad/s^2 (`arm.brake_accel_radps2`).
    pub accel_radps2: f64,
    /// Speed bound of the move, rad/s (`arm.velocity_max_radps`).
    pub velocity_max_radps: f64,
    /// Where it comes to rest, rad: `None` where the brake stops (a throw), `Some` at the
    /// catching configuration (a throw and catch).
    pub catch_angle_rad: Option<f64>,
}

/// The planned trajectory: the B-spline on `[0, T]`, then the move to rest, then holding
/// (as the core's `ArmController::reference`, in f64).
#[derive(Clone, Debug, PartialEq)]
pub struct PlannedMotion {
    /// Control points, rad.
    pub points_rad: Vec<f64>,
    /// Segment duration, s.
    pub segment_s: f64,
    /// The move to rest after `T`.
    tail: BangBang<f64>,
}

impl PlannedMotion {
    /// The spline of `points_rad` (rad) with segments of `segment_s` (s), then `rest`.
    pub fn new(points_rad: Vec<f64>, segment_s: f64, rest: &RestMove) -> Self {
        let mut m = Self {
            points_rad,
            segment_s,
            tail: BangBang::default(),
        };
        let e = m.spline(m.duration_s());
        let (x, w, a) = (e.angle_rad, e.velocity_radps, rest.accel_radps2);
        m.tail = match rest.catch_angle_rad {
            None => BangBang::brake(x, w, a),
            Some(c) => BangBang::to_rest_at(x, w, c, a, rest.velocity_max_radps),
        };
        m
    }

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
}

impl ArmMotion for PlannedMotion {
    fn joint(&self, t_s: f64) -> Joint {
        let end = self.duration_s();
        if t_s <= end {
            return self.spline(t_s);
        }
        let s = self.tail.sample(t_s - end);
        Joint {
            angle_rad: s.angle_rad,
            velocity_radps: s.velocity_radps,
            accel_radps2: s.accel_radps2,
        }
    }

    fn settled_s(&self) -> f64 {
        self.duration_s() + self.tail.duration_s()
    }

    fn release_s(&self) -> f64 {
        self.duration_s()
    }

    fn breaks_s(&self) -> Vec<f64> {
        let n = self.points_rad.len().saturating_sub(3);
        let mut b: Vec<f64> = (0..=n).map(|k| k as f64 * self.segment_s).collect();
        b.extend(self.tail.switches_s().map(|s| self.duration_s() + s));
        b.dedup();
        b
    }
}
