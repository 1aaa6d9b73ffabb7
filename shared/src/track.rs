//! Paddle tracking: PD plus acceleration feed-forward, kept within position, velocity and
//! acceleration limits.
//!
//! The paddle is driven by an acceleration command held for one control period `dt`
//! (zero-order hold). The command is
//!
//! ```text
//! u = r''_ref + kp (r_ref - r) + kd (r'_ref - r')
//! ```
//!
//! then limited so that after one period the velocity stays within `±velocity_max` and
//! within the speed from which the paddle can still stop before its travel limits at
//! `accel_max` (`sqrt(2 a_max d)`), and finally clamped to `±accel_max`.

use crate::math::Real;
use crate::mirror::PaddleReference;
use crate::params::{finite, positive, ParamError};
use crate::state::PaddleState;
use serde::{Deserialize, Serialize};

/// Limits of the paddle actuator, SI units.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct PaddleLimits {
    /// Lowest paddle height, m.
    pub min_height_m: f32,
    /// Highest paddle height, m (> min).
    pub max_height_m: f32,
    /// Largest paddle speed, m/s (> 0).
    pub velocity_max_mps: f32,
    /// Largest paddle acceleration magnitude, m/s^2 (> 0).
    pub accel_max_mps2: f32,
}

impl Default for PaddleLimits {
    fn default() -> Self {
        Self {
            min_height_m: -0.3,
            max_height_m: 0.1,
            velocity_max_mps: 3.0,
            accel_max_mps2: 200.0,
        }
    }
}

impl PaddleLimits {
    /// Check every field; the error names the first bad one.
    pub fn validate(&self) -> Result<(), ParamError> {
        finite("limits.min_height_m", self.min_height_m)?;
        finite("limits.max_height_m", self.max_height_m)?;
        if self.max_height_m <= self.min_height_m {
            return Err(ParamError::OutOfRange("limits.max_height_m"));
        }
        positive("limits.velocity_max_mps", self.velocity_max_mps)?;
        positive("limits.accel_max_mps2", self.accel_max_mps2)?;
        Ok(())
    }
}

/// PD-plus-feed-forward paddle tracker with limits.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Tracker {
    kp_per_s2: f32,
    kd_per_s: f32,
    limits: PaddleLimits,
    dt_s: f32,
    /// 1/dt, 1/s, computed once: the step multiplies instead of dividing (a `vdiv.f32` is
    /// 14 cycles on a Cortex-M4, a `vmul.f32` 1); within 1 ulp of dividing by dt.
    inv_dt_per_s: f32,
    /// `-velocity_max`, `-accel_max` and `2 accel_max`, computed once (the same values the
    /// step computed; a negation or doubling and its constant were ~6 instructions a step).
    neg_velocity_max_mps: f32,
    neg_accel_max_mps2: f32,
    two_accel_max_mps2: f32,
}

impl Tracker {
    /// A tracker with stiffness `kp_per_s2` (1/s^2, >= 0), damping `kd_per_s` (1/s, >= 0),
    /// `limits`, and control period `dt_s` (s, > 0).
    pub fn new(
        kp_per_s2: f32,
        kd_per_s: f32,
        limits: PaddleLimits,
        dt_s: f32,
    ) -> Result<Self, ParamError> {
        crate::params::non_negative("tracking.kp_per_s2", kp_per_s2)?;
        crate::params::non_negative("tracking.kd_per_s", kd_per_s)?;
        limits.validate()?;
        positive("dt_s", dt_s)?;
        Ok(Self {
            kp_per_s2,
            kd_per_s,
            limits,
            dt_s,
            inv_dt_per_s: 1.0 / dt_s,
            neg_velocity_max_mps: -limits.velocity_max_mps,
            neg_accel_max_mps2: -limits.accel_max_mps2,
            two_accel_max_mps2: 2.0 * limits.accel_max_mps2,
        })
    }

    /// The limits this tracker enforces.
    pub fn limits(&self) -> &PaddleLimits {
        &self.limits
    }

    /// Clamp a reference into the travel range (zeroing its velocity and acceleration where
    /// the position is clamped).
    pub fn clamp_reference(&self, r: PaddleReference<f32>) -> PaddleReference<f32> {
        let l = &self.limits;
        if r.height_m > l.max_height_m || r.height_m < l.min_height_m {
            PaddleReference {
                height_m: r.height_m.clamp_r(l.min_height_m, l.max_height_m),
                velocity_mps: 0.0,
                accel_mps2: 0.0,
            }
        } else {
            PaddleReference {
                height_m: r.height_m,
                velocity_mps: r
                    .velocity_mps
                    .clamp_r(self.neg_velocity_max_mps, l.velocity_max_mps),
                accel_mps2: r.accel_mps2,
            }
        }
    }

    /// Acceleration command (m/s^2) that tracks `reference` from `paddle`, within limits.
    /// Finite inputs give a finite output in `[-accel_max, accel_max]`.
    pub fn command(&self, reference: &PaddleReference<f32>, paddle: &PaddleState<f32>) -> f32 {
        let u = reference.accel_mps2
            + self.kp_per_s2 * (reference.height_m - paddle.height_m)
            + self.kd_per_s * (reference.velocity_mps - paddle.velocity_mps);
        self.limit(u, paddle)
    }

    /// Deceleration to rest (the safe state): the acceleration that stops the paddle in one
    /// period if it can, else the largest braking acceleration.
    pub fn brake(&self, paddle: &PaddleState<f32>) -> f32 {
        let a = self.limits.accel_max_mps2;
        (-paddle.velocity_mps * self.inv_dt_per_s).clamp_r(self.neg_accel_max_mps2, a)
    }

    /// [`Self::brake`], with `paddle` dead-reckoned one period under it: where the safe
    /// state takes the paddle to be while its measurements are not trusted (every
    /// controller's safe command).
    #[inline]
    pub fn brake_and_coast(&self, paddle: &mut PaddleState<f32>) -> f32 {
        let u = self.brake(paddle);
        let (dt, j) = (self.dt_s, *paddle);
        *paddle = PaddleState::new(
            j.height_m + j.velocity_mps * dt + 0.5 * u * dt * dt,
            j.velocity_mps + u * dt,
        );
        u
    }

    fn limit(&self, u: f32, paddle: &PaddleState<f32>) -> f32 {
        let l = &self.limits;
        let a = l.accel_max_mps2;
        // speed from which the paddle can still stop before each end of its travel
        let up_room = (l.max_height_m - paddle.height_m).max_r(0.0);
        let down_room = (paddle.height_m - l.min_height_m).max_r(0.0);
        let v_up = l
            .velocity_max_mps
            .min_r((self.two_accel_max_mps2 * up_room).sqrt());
        let v_down = l
            .velocity_max_mps
            .min_r((self.two_accel_max_mps2 * down_room).sqrt());
        let v_next = (paddle.velocity_mps + u * self.dt_s).clamp_r(-v_down, v_up);
        ((v_next - paddle.velocity_mps) * self.inv_dt_per_s).clamp_r(self.neg_accel_max_mps2, a)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn tracker() -> Tracker {
        Tracker::new(2500.0, 100.0, PaddleLimits::default(), 0.002).unwrap()
    }

    #[test]
    fn pd_plus_feedforward_within_limits() {
        let t = tracker();
        let r = PaddleReference {
            height_m: -0.05,
            velocity_mps: 0.2,
            accel_mps2: 1.0,
        };
        let p = PaddleState::new(-0.051, 0.19);
        let expected = 1.0 + 2500.0 * 0.001 + 100.0 * 0.01;
        assert!((t.command(&r, &p) - expected).abs() < 1e-4);
    }

    #[test]
    fn acceleration_and_travel_limits_hold() {
        let t = tracker();
        let far = PaddleReference {
            height_m: 10.0,
            velocity_mps: 50.0,
            accel_mps2: 1e6,
        };
        let u = t.command(&far, &PaddleState::new(0.0, 0.0));
        assert_eq!(u, 200.0);
        // at the top end moving up: must brake
        let u = t.command(&far, &PaddleState::new(0.1, 1.0));
        assert!(u < 0.0);
        // nan in the reference still gives a value within limits
        let nan = PaddleReference {
            height_m: f32::NAN,
            velocity_mps: 0.0,
            accel_mps2: 0.0,
        };
        let u = t.command(&nan, &PaddleState::new(0.0, 0.0));
        assert!(u.is_finite() && u.abs() <= 200.0);
    }

    /// Near a travel end the speed towards it is limited to the speed from which a_max can
    /// still stop the paddle: sqrt(2 a_max room). By hand, a_max = 200 m/s^2, room 2.5 mm:
    /// 1 m/s; from 1.2 m/s towards the end the command is (1 - 1.2)/dt = -100 m/s^2.
    #[test]
    fn stopping_speed_limit_near_each_travel_end_by_hand() {
        let t = tracker();
        let far_up = PaddleReference {
            height_m: 0.1,
            velocity_mps: 3.0,
            accel_mps2: 0.0,
        };
        let u = t.command(&far_up, &PaddleState::new(0.0975, 1.2));
        assert!((u + 100.0).abs() < 0.1, "{u}");
        let far_down = PaddleReference {
            height_m: -0.3,
            velocity_mps: -3.0,
            accel_mps2: 0.0,
        };
        let u = t.command(&far_down, &PaddleState::new(-0.2975, -1.2));
        assert!((u - 100.0).abs() < 0.1, "{u}");
        // beyond the end (no room): the speed limit is 0, the paddle is braked to rest
        let u = t.command(&far_up, &PaddleState::new(0.12, 0.1));
        assert!((u + 50.0).abs() < 1e-3, "{u}");
    }

    /// References are clamped into the travel range: beyond it the position is clamped and
    /// velocity and acceleration zeroed; exactly at an end or inside it nothing is changed
    /// except the velocity clamp to +-velocity_max.
    #[test]
    fn reference_clamp_by_hand() {
        let t = tracker();
        let r = |h: f32, v: f32| PaddleReference {
            height_m: h,
            velocity_mps: v,
            accel_mps2: 1.5,
        };
        let zero = |h: f32| PaddleReference {
            height_m: h,
            velocity_mps: 0.0,
            accel_mps2: 0.0,
        };
        assert_eq!(t.clamp_reference(r(0.2, 1.0)), zero(0.1));
        assert_eq!(t.clamp_reference(r(-0.5, 1.0)), zero(-0.3));
        assert_eq!(t.clamp_reference(r(0.1, 1.0)), r(0.1, 1.0));
        assert_eq!(t.clamp_reference(r(-0.3, 1.0)), r(-0.3, 1.0));
        assert_eq!(t.clamp_reference(r(0.0, 5.0)), r(0.0, 3.0));
        assert_eq!(t.clamp_reference(r(0.0, -5.0)), r(0.0, -3.0));
    }

    #[test]
    fn bad_limits_are_named() {
        let bad = |l: PaddleLimits| Tracker::new(1.0, 1.0, l, 0.002).unwrap_err();
        let d = PaddleLimits::default();
        assert_eq!(
            bad(PaddleLimits {
                min_height_m: f32::NAN,
                ..d
            }),
            ParamError::NotFinite("limits.min_height_m")
        );
        assert_eq!(
            bad(PaddleLimits {
                max_height_m: f32::INFINITY,
                ..d
            }),
            ParamError::NotFinite("limits.max_height_m")
        );
        assert_eq!(
            bad(PaddleLimits {
                max_height_m: -0.3,
                ..d
            }),
            ParamError::OutOfRange("limits.max_height_m")
        );
        assert_eq!(
            bad(PaddleLimits {
                velocity_max_mps: 0.0,
                ..d
            }),
            ParamError::NotPositive("limits.velocity_max_mps")
        );
        assert_eq!(
            bad(PaddleLimits {
                accel_max_mps2: -1.0,
                ..d
            }),
            ParamError::NotPositive("limits.accel_max_mps2")
        );
        assert_eq!(
            Tracker::new(-1.0, 1.0, d, 0.002).unwrap_err(),
            ParamError::Negative("tracking.kp_per_s2")
        );
        assert_eq!(
            Tracker::new(1.0, -1.0, d, 0.002).unwrap_err(),
            ParamError::Negative("tracking.kd_per_s")
        );
        assert_eq!(
            Tracker::new(1.0, 1.0, d, 0.0).unwrap_err(),
            ParamError::NotPositive("dt_s")
        );
        assert_eq!(tracker().limits(), &d);
    }

    #[test]
    fn brake_stops_in_one_step_when_it_can() {
        let t = tracker();
        assert!((t.brake(&PaddleState::new(0.0, 0.2)) + 100.0).abs() < 1e-3);
        assert_eq!(t.brake(&PaddleState::new(0.0, -3.0)), 200.0);
    }
}
