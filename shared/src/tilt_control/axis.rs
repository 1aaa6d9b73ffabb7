//! One table axis (tilt or stroke): its reference and its tracking law.
//!
//! The law is [`crate::track::Tracker`]'s (the paddle's), to the bit: PD plus feed-forward
//! `u = a_ff + kp (r - p) + kd (r' - p')`, the velocity after one period limited to the
//! speed limit and to the speed from which the axis can still stop before the end of its
//! travel at its acceleration limit, `sqrt(2 a_max room)`, then the acceleration limit. It is
//! computed here with the stopping-distance limit on the side the velocity moves to only
//! (one `sqrt` instead of two: the other side's bound never binds), with the limit's
//! activity reported, because the tilt controller's step budget counts every instruction.
//! The test `same_law_as_the_paddle_tracker` checks the equality bit for bit.

use super::plan::AxisLimits;
use crate::math::Real;
use crate::state::PaddleState;

/// One axis: limits, gains, home and the reference (position, velocity) now, in the axis's
/// unit u (rad or m).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Axis {
    /// The axis's limits.
    pub limits: AxisLimits,
    kp: f32,
    kd: f32,
    /// 2 a_max, u/s^2.
    two_a: f32,
    /// 1 / dt, 1/s (the tracker's law multiplies by it, as [`crate::track::Tracker`]).
    inv_dt: f32,
    /// Position held while there is no valid estimate, u.
    pub home: f32,
    /// Reference position now, u.
    pub p: f32,
    /// Reference velocity now, u/s.
    pub v: f32,
}

impl Axis {
    /// An axis at rest at `home` with stiffness `kp` (1/s^2) and damping `kd` (1/s),
    /// stepped every `dt` s; the caller has validated every value.
    pub fn new(limits: AxisLimits, kp: f32, kd: f32, home: f32, dt: f32) -> Self {
        Self {
            limits,
            kp,
            kd,
            two_a: 2.0 * limits.accel_max,
            inv_dt: 1.0 / dt,
            home,
            p: home,
            v: 0.0,
        }
    }

    /// The command (u/s^2) that tracks the reference with feed-forward `a_ff` from the
    /// measured state, within the limits, and whether a limit changed it (NaN counts).
    #[inline]
    pub fn command(&self, a_ff: f32, m: &PaddleState<f32>, dt: f32) -> (f32, bool) {
        let l = &self.limits;
        let u = a_ff + self.kp * (self.p - m.height_m) + self.kd * (self.v - m.velocity_mps);
        let v_raw = m.velocity_mps + u * dt;
        // the clamp of v_raw into [-v_down, v_up] (0 lies inside): only the side v_raw is
        // on can bind (NaN: the lower side, as `clamp_r` maps it)
        let up = v_raw > 0.0;
        let room = if up {
            l.max - m.height_m
        } else {
            m.height_m - l.min
        };
        let v_lim = l
            .velocity_max
            .min_r(Real::sqrt(self.two_a * room.max_r(0.0)));
        let v_next = if up {
            if v_raw > v_lim {
                v_lim
            } else {
                v_raw
            }
        } else if v_raw >= -v_lim {
            v_raw
        } else {
            -v_lim
        };
        let u_v = (v_next - m.velocity_mps) * self.inv_dt;
        let limited = u_v.clamp_r(-l.accel_max, l.accel_max);
        (limited, v_next != v_raw || limited != u_v)
    }

    /// Advance the reference one period under the held acceleration `a_ff` (exact).
    #[inline]
    pub fn advance(&mut self, a_ff: f32, dt: f32) {
        (self.p, self.v) = self.advanced(a_ff, dt);
    }

    /// The reference (position, velocity) one period on under the held acceleration
    /// `a_ff` (exact), without moving it.
    #[inline]
    pub fn advanced(&self, a_ff: f32, dt: f32) -> (f32, f32) {
        (self.p + (self.v + 0.5 * a_ff * dt) * dt, self.v + a_ff * dt)
    }

    /// The feed-forward that brings the reference velocity to rest within the limit.
    #[inline]
    pub fn brake_reference(&self) -> f32 {
        (-self.v * self.inv_dt).clamp_r(-self.limits.accel_max, self.limits.accel_max)
    }

    /// The acceleration that stops `m` in one period if it can, else the largest braking
    /// acceleration (the safe state; [`crate::track::Tracker::brake`]'s law).
    #[inline]
    pub fn brake(&self, m: &PaddleState<f32>) -> f32 {
        (-m.velocity_mps * self.inv_dt).clamp_r(-self.limits.accel_max, self.limits.accel_max)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mirror::PaddleReference;
    use crate::track::{PaddleLimits, Tracker};

    #[test]
    fn same_law_as_the_paddle_tracker() {
        let limits = AxisLimits {
            min: -0.1,
            max: 0.1,
            velocity_max: 2.0,
            accel_max: 60.0,
        };
        let dt = 0.002f32;
        let tracker = Tracker::new(
            2500.0,
            100.0,
            PaddleLimits {
                min_height_m: -0.1,
                max_height_m: 0.1,
                velocity_max_mps: 2.0,
                accel_max_mps2: 60.0,
            },
            dt,
        )
        .unwrap();
        let mut axis = Axis::new(limits, 2500.0, 100.0, 0.0, dt);
        let mut saturated = 0;
        let values = [-0.15f32, -0.1, -0.099, -0.03, 0.0, 0.02, 0.0999, 0.1, 0.12];
        let speeds = [-3.0f32, -2.0, -0.5, 0.0, 0.3, 1.9, 2.5, f32::NAN];
        for &p in &values {
            for &v in &speeds {
                for &r in &values {
                    for &rv in &speeds[..7] {
                        for &ff in &[-100.0f32, 0.0, 7.0, 1e6] {
                            axis.p = r;
                            axis.v = rv;
                            let m = PaddleState::new(p, v);
                            let (u, sat) = axis.command(ff, &m, dt);
                            let reference = PaddleReference {
                                height_m: r,
                                velocity_mps: rv,
                                accel_mps2: ff,
                            };
                            let expect = tracker.command(&reference, &m);
                            assert_eq!(
                                u.to_bits(),
                                expect.to_bits(),
                                "p {p} v {v} r {r} rv {rv} ff {ff}"
                            );
                            saturated += usize::from(sat);
                        }
                    }
                }
            }
        }
        assert!(saturated > 100);
        // the flag: a small correction is not limited, a huge one is
        axis.p = 0.0;
        axis.v = 0.0;
        assert!(!axis.command(1.0, &PaddleState::new(0.0, 0.0), dt).1);
        assert!(axis.command(1e4, &PaddleState::new(0.0, 0.0), dt).1);
        assert_eq!(
            axis.brake(&PaddleState::new(0.0, 0.2)),
            tracker.brake(&PaddleState::new(0.0, 0.2))
        );
    }
}
