//! The arm's move to rest after its planned trajectory: the time-optimal bang-bang motion
//! of a joint under `|theta''| <= a` and `|theta'| <= v_max` (Akella, Huang, Lynch & Mason,
//! sec. 2.5: "the arm is maximally decelerated at the release point ... if the arm is also
//! to catch the object, it follows a bang-bang trajectory to reach the catching
//! configuration").
//!
//! ## The move
//! From `(theta_0, w_0)` the joint either brakes to rest wherever that stops it
//! ([`BangBang::brake`], a throw's release), or reaches rest at a given angle `theta_c`
//! ([`BangBang::to_rest_at`], the catch). The second is the classical minimum-time control
//! of a double integrator: full acceleration `sigma a` then full deceleration `-sigma a`,
//! with a coast at `sigma v_max` between them if the peak speed would pass the limit. With
//! `d = theta_c - theta_0` and the braking distance `d_b = w_0 |w_0| / (2 a)`, the switch
//! sign is
//!
//! ```text
//! sigma = +1 if d >= d_b (the brake alone would stop short), else -1
//! ```
//!
//! and the peak speed `w_1` solves `(w_1^2 - w_0^2) / (2 sigma a) + w_1^2 / (2 sigma a) = d`:
//!
//! ```text
//! w_1 = sigma sqrt(sigma a d + w_0^2 / 2)     (the root is real: sigma (d - d_b) >= 0)
//! ```
//!
//! clamped to `|w_1| <= v_max`, when the coast takes `(d - (2 w_1^2 - w_0^2)/(2 sigma a)) / w_1`.
//! The arcs last `(w_1 - w_0) / (sigma a)`, the coast, and `|w_1| / a`. With `d = d_b`
//! the first arc and the coast have zero length and the move is the brake itself.
//!
//! The joint's extreme angles over the move are `theta_0`, the braking stop
//! `theta_0 + d_b` (passed only when `sigma` opposes `w_0`) and `theta_c`: a caller that
//! checks those three within the joint's range has the whole move there.
//!
//! Every function is loop-free apart from the three arcs (a fixed count), allocates
//! nothing and never panics. Evaluation ([`BangBang::sample`]) costs a few multiplies; the
//! square root is paid once, when the move is built.

use crate::bspline::SplineSample;
use crate::math::Real;

/// One arc of constant acceleration: its start state and duration.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
struct Arc<R> {
    /// Duration, s (>= 0).
    duration_s: R,
    /// Angle at the arc's start, rad.
    angle_rad: R,
    /// Velocity at the arc's start, rad/s.
    velocity_radps: R,
    /// Constant acceleration, rad/s^2.
    accel_radps2: R,
}

impl<R: Real> Arc<R> {
    /// The arc at `s` seconds from its start (`0 <= s <= duration_s`).
    fn at(&self, s: R) -> SplineSample<R> {
        let a = self.accel_radps2;
        SplineSample {
            angle_rad: self.angle_rad + self.velocity_radps * s + R::HALF * a * s * s,
            velocity_radps: self.velocity_radps + a * s,
            accel_radps2: a,
        }
    }

    /// The arc that follows this one, with `accel_radps2` for `duration_s`.
    fn then(&self, duration_s: R, accel_radps2: R) -> Self {
        let end = self.at(self.duration_s);
        Self {
            duration_s,
            angle_rad: end.angle_rad,
            velocity_radps: end.velocity_radps,
            accel_radps2,
        }
    }
}

/// A bang-bang move to rest: up to three arcs (full acceleration, coast, full
/// deceleration), then rest at [`end_angle_rad`](Self::end_angle_rad) (module docs).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct BangBang<R> {
    arcs: [Arc<R>; 3],
    /// Angle at rest after the move, rad.
    end_angle_rad: R,
    /// Duration of the whole move, s.
    duration_s: R,
}

impl<R: Real> BangBang<R> {
    /// Brake from `(angle_rad, velocity_radps)` (rad, rad/s) at `accel_radps2` (rad/s^2,
    /// > 0) to rest where that stops the joint: one arc, `|w_0| / a` long.
    pub fn brake(angle_rad: R, velocity_radps: R, accel_radps2: R) -> Self {
        let dir = if velocity_radps < R::ZERO {
            -R::ONE
        } else {
            R::ONE
        };
        let first = Arc {
            duration_s: velocity_radps.abs() / accel_radps2,
            angle_rad,
            velocity_radps,
            accel_radps2: -dir * accel_radps2,
        };
        Self::of_arcs(first, first.then(R::ZERO, R::ZERO))
    }

    /// The minimum-time move from `(angle_rad, velocity_radps)` (rad, rad/s) to rest at
    /// `target_rad` (rad) under `|theta''| <= accel_radps2` (rad/s^2, > 0) and
    /// `|theta'| <= velocity_max_radps` (rad/s, > 0, at least `|velocity_radps|`).
    pub fn to_rest_at(
        angle_rad: R,
        velocity_radps: R,
        target_rad: R,
        accel_radps2: R,
        velocity_max_radps: R,
    ) -> Self {
        let (w0, a) = (velocity_radps, accel_radps2);
        let d = target_rad - angle_rad;
        let braking = w0 * w0.abs() / (R::TWO * a);
        let sigma = if d >= braking { R::ONE } else { -R::ONE };
        let peak2 = (sigma * a * d + R::HALF * w0 * w0).max_r(R::ZERO);
        let limited = peak2.sqrt() > velocity_max_radps;
        let w1 = sigma * peak2.sqrt().min_r(velocity_max_radps);
        // a coast only where the speed limit cut the peak (else rounding would leave a
        // sliver of one)
        let coast_s = if limited {
            let ramps = (R::TWO * w1 * w1 - w0 * w0) / (R::TWO * sigma * a);
            ((d - ramps) / w1).max_r(R::ZERO)
        } else {
            R::ZERO
        };
        let first = Arc {
            duration_s: ((w1 - w0) / (sigma * a)).max_r(R::ZERO),
            angle_rad,
            velocity_radps: w0,
            accel_radps2: sigma * a,
        };
        let coast = first.then(coast_s, R::ZERO);
        let last = coast.then(w1.abs() / a, -sigma * a);
        let mut m = Self::of_arcs(first, coast);
        m.arcs[2] = last;
        m.end_angle_rad = last.at(last.duration_s).angle_rad;
        m.duration_s = first.duration_s + coast_s + last.duration_s;
        m
    }

    /// A move of `first` then `second` (and an empty third arc).
    fn of_arcs(first: Arc<R>, second: Arc<R>) -> Self {
        let third = second.then(R::ZERO, R::ZERO);
        Self {
            arcs: [first, second, third],
            end_angle_rad: third.angle_rad,
            duration_s: first.duration_s + second.duration_s,
        }
    }

    /// The joint `s_s` seconds after the move's start (s; before 0 the start, after
    /// [`duration_s`](Self::duration_s) at rest at the end angle).
    pub fn sample(&self, s_s: R) -> SplineSample<R> {
        let mut s = s_s.max_r(R::ZERO);
        for arc in &self.arcs {
            if s < arc.duration_s {
                return arc.at(s);
            }
            s = s - arc.duration_s;
        }
        SplineSample {
            angle_rad: self.end_angle_rad,
            velocity_radps: R::ZERO,
            accel_radps2: R::ZERO,
        }
    }

    /// Times from the move's start where its acceleration may jump: each arc's end, s.
    pub fn switches_s(&self) -> impl Iterator<Item = R> + '_ {
        let mut t = R::ZERO;
        self.arcs.iter().map(move |a| {
            t = t + a.duration_s;
            t
        })
    }

    /// Duration of the move, s.
    pub fn duration_s(&self) -> R {
        self.duration_s
    }

    /// Angle at rest after the move, rad.
    pub fn end_angle_rad(&self) -> R {
        self.end_angle_rad
    }

    /// The acceleration of the move's first arc of nonzero length, rad/s^2 (what the joint
    /// does just after the trajectory's end; 0 for a move of zero length).
    pub fn first_accel_radps2(&self) -> R {
        self.arcs
            .iter()
            .find(|a| a.duration_s > R::ZERO)
            .map_or(R::ZERO, |a| a.accel_radps2)
    }

    /// The farthest angle the joint reaches in the direction of `w_0` before turning (the
    /// braking stop), and the end angle: with the start, the move's extreme angles, rad.
    pub fn extremes_rad(&self) -> (R, R) {
        let first = self.arcs[0];
        let a = first.accel_radps2;
        let w0 = first.velocity_radps;
        let turns = a != R::ZERO && (w0 > R::ZERO) != (a > R::ZERO);
        // where the first arc's velocity crosses zero (for the brake, its end: the same
        // arithmetic as `sample` there)
        let stop = if turns {
            first.at(-w0 / a).angle_rad
        } else {
            first.angle_rad
        };
        (stop, self.end_angle_rad)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Integrate `m` by explicit small steps of its own acceleration samples (an
    /// independent check of the closed-form arcs' continuity and end).
    fn integrate(m: &BangBang<f64>, x0: f64, v0: f64) -> (f64, f64) {
        let n = 200_000;
        let h = m.duration_s() / n as f64;
        let (mut x, mut v) = (x0, v0);
        for k in 0..n {
            let a = m.sample((k as f64 + 0.5) * h).accel_radps2;
            x += v * h + 0.5 * a * h * h;
            v += a * h;
        }
        (x, v)
    }

    #[test]
    fn brake_stops_at_the_braking_distance() {
        let m = BangBang::brake(0.5_f64, 3.0, 30.0);
        assert!((m.duration_s() - 0.1).abs() < 1e-15);
        assert!((m.end_angle_rad() - (0.5 + 9.0 / 60.0)).abs() < 1e-15);
        assert_eq!(m.sample(0.2).velocity_radps, 0.0);
        assert_eq!(m.first_accel_radps2(), -30.0);
    }

    /// Hand case: from rest at 0 to rest at 1 rad under a = 4: accelerate 0.5 s to 2 rad/s,
    /// decelerate 0.5 s; the minimum time is 2 sqrt(d / a) = 1 s.
    #[test]
    fn rest_to_rest_takes_two_sqrt_d_over_a() {
        let m = BangBang::to_rest_at(0.0_f64, 0.0, 1.0, 4.0, 10.0);
        assert!((m.duration_s() - 1.0).abs() < 1e-12);
        let mid = m.sample(0.5);
        assert!((mid.angle_rad - 0.5).abs() < 1e-12 && (mid.velocity_radps - 2.0).abs() < 1e-12);
        assert!((m.end_angle_rad() - 1.0).abs() < 1e-12);
        assert_eq!(m.sample(0.25).accel_radps2, 4.0);
        assert_eq!(m.sample(0.75).accel_radps2, -4.0);
    }

    /// Hand case with the speed limit: 0 to 1 rad under a = 4, v_max = 1: ramps of
    /// 0.25 s (0.125 rad each) and a coast of 0.75 rad at 1 rad/s; 1.25 s in all.
    #[test]
    fn a_speed_limit_inserts_a_coast() {
        let m = BangBang::to_rest_at(0.0_f64, 0.0, 1.0, 4.0, 1.0);
        assert!((m.duration_s() - 1.25).abs() < 1e-12);
        assert!((m.sample(0.6).velocity_radps - 1.0).abs() < 1e-12);
        assert_eq!(m.sample(0.6).accel_radps2, 0.0);
        assert!((m.end_angle_rad() - 1.0).abs() < 1e-12);
    }

    /// Speed-limited moves from a moving start, both ways, against their distances by hand:
    /// the ramp from `w_0` to `w_1` covers `(w_1^2 - w_0^2) / (2 sigma a)`, the ramp down
    /// `w_1^2 / (2 sigma a)`, and the coast the rest at `w_1`.
    /// - forward: (0.5 rad, 1 rad/s) to 5 rad, a = 2, v_max = 3: sigma = +1, the peak
    ///   sqrt(2 * 4.5 + 0.5) = 3.08 is cut to 3; ramps 2 + 2.25 = 4.25 rad in 1 s and 1.5 s,
    ///   a coast of 0.25 rad in 1/12 s; the joint never turns, so its extremes are the
    ///   start and the target;
    /// - backward: (0, -0.5 rad/s) to -3 rad, a = 2, v_max = 1.5: sigma = -1, peak
    ///   sqrt(6.125) = 2.47 cut to 1.5; ramps -0.5 rad in 0.5 s and -0.5625 rad in 0.75 s, a
    ///   coast of -1.9375 rad in 1.9375 / 1.5 s.
    #[test]
    fn a_limited_move_from_a_moving_start_coasts_the_rest_of_the_way() {
        let m = BangBang::to_rest_at(0.5_f64, 1.0, 5.0, 2.0, 3.0);
        let (up, coast, down) = (1.0, 1.0 / 12.0, 1.5);
        assert!(
            (m.duration_s() - (up + coast + down)).abs() < 1e-12,
            "{}",
            m.duration_s()
        );
        let switches: Vec<f64> = m.switches_s().collect();
        for (got, want) in switches.iter().zip([up, up + coast, up + coast + down]) {
            assert!((got - want).abs() < 1e-12, "{switches:?}");
        }
        assert!((m.sample(up + 0.5 * coast).velocity_radps - 3.0).abs() < 1e-12);
        assert!((m.end_angle_rad() - 5.0).abs() < 1e-12);
        let (stop, end) = m.extremes_rad();
        assert_eq!(stop, 0.5, "no turn: the start is the near extreme");
        assert!((end - 5.0).abs() < 1e-12);

        let m = BangBang::to_rest_at(0.0_f64, -0.5, -3.0, 2.0, 1.5);
        let (up, coast, down) = (0.5, 1.9375 / 1.5, 0.75);
        assert!(
            (m.duration_s() - (up + coast + down)).abs() < 1e-12,
            "{}",
            m.duration_s()
        );
        assert!((m.sample(up + 0.5 * coast).velocity_radps + 1.5).abs() < 1e-12);
        assert!((m.end_angle_rad() + 3.0).abs() < 1e-12);
        assert_eq!(m.first_accel_radps2(), -2.0);
    }

    /// A throw's catch: moving forward at 3 rad/s, back to 0.2 rad behind the start under
    /// a = 30. The joint must first brake (sigma = -1), overshoot to the braking stop
    /// 0.15 rad ahead, come back. Time by hand: w_1 = -sqrt(30 * 0.2 + 4.5) = -sqrt(10.5),
    /// t = (3 + sqrt(10.5)) / 30 + sqrt(10.5) / 30.
    #[test]
    fn a_catch_behind_the_release_brakes_first_and_comes_back() {
        let m = BangBang::to_rest_at(0.0_f64, 3.0, -0.2, 30.0, 8.0);
        let w1 = 10.5_f64.sqrt();
        assert!((m.duration_s() - (3.0 + 2.0 * w1) / 30.0).abs() < 1e-12);
        assert_eq!(m.first_accel_radps2(), -30.0);
        let (stop, end) = m.extremes_rad();
        assert!((stop - 0.15).abs() < 1e-12);
        assert!((end + 0.2).abs() < 1e-12);
        // the step straddling the switch takes one acceleration: O(a h) in velocity
        let (x, v) = integrate(&m, 0.0, 3.0);
        assert!((x + 0.2).abs() < 1e-5 && v.abs() < 1e-4, "{x} {v}");
    }

    /// Exhaustive over a grid of starts and targets: the move ends at rest on target,
    /// never passes the speed limit, and is never slower than the brake plus the
    /// rest-to-rest time from the braking stop (a feasible, not optimal, alternative).
    #[test]
    fn every_move_ends_on_target_within_its_limits() {
        let (a, vmax) = (30.0_f64, 8.0);
        for i in -8..=8 {
            for j in -10..=10 {
                let (w0, target) = (i as f64, 0.1 * j as f64);
                let m = BangBang::to_rest_at(0.0, w0, target, a, vmax);
                assert!((m.end_angle_rad() - target).abs() < 1e-12, "{w0} {target}");
                let n = 400;
                for k in 0..=n {
                    let s = m.sample(m.duration_s() * k as f64 / n as f64);
                    assert!(s.velocity_radps.abs() <= vmax + 1e-12);
                }
                let b = BangBang::brake(0.0, w0, a);
                let rest = 2.0 * ((target - b.end_angle_rad()).abs() / a).sqrt();
                assert!(m.duration_s() <= b.duration_s() + rest + 1e-12);
            }
        }
    }

    #[test]
    fn the_target_at_the_braking_stop_is_the_brake() {
        let b = BangBang::brake(0.0_f64, 3.0, 30.0);
        let m = BangBang::to_rest_at(0.0_f64, 3.0, b.end_angle_rad(), 30.0, 8.0);
        assert!((m.duration_s() - b.duration_s()).abs() < 1e-12);
        assert_eq!(m.first_accel_radps2(), -30.0);
    }
}
