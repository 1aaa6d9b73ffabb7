//! Paddle actuation: how a commanded acceleration (m/s^2, held over a control period)
//! becomes paddle motion.

use dexter_core::state::PaddleState;

use crate::engine::roots::first_contact;

/// A paddle actuator. Within a regime the paddle moves with constant acceleration (a
/// quadratic in time); [`time_to_switch`](Actuator::time_to_switch) says when the regime
/// changes (a limit is reached), so the engine splits segments there.
pub trait Actuator {
    /// The acceleration the paddle actually gets for command `command_mps2` in `paddle`'s
    /// state, m/s^2.
    fn accel(&self, paddle: &PaddleState<f64>, command_mps2: f64) -> f64;
    /// Time until the regime with acceleration `accel_mps2` ends, s (infinite if never).
    fn time_to_switch(&self, paddle: &PaddleState<f64>, accel_mps2: f64) -> f64;
    /// As [`time_to_switch`](Actuator::time_to_switch) when that is shorter than
    /// `within_s`, else any value `>= within_s`: for a caller that only needs to know that
    /// the regime outlasts its segment (a model may then skip work).
    #[inline]
    fn time_to_switch_within(
        &self,
        paddle: &PaddleState<f64>,
        accel_mps2: f64,
        within_s: f64,
    ) -> f64 {
        let _ = within_s;
        self.time_to_switch(paddle, accel_mps2)
    }
    /// Snap the state onto the limit that was just reached (removes rounding).
    fn settle(&self, paddle: &mut PaddleState<f64>);
    /// The paddle states from which no limit ends a regime within `max_window_s` (s),
    /// whatever acceleration [`accel`](Actuator::accel) gave it: a cheap test for a loop
    /// whose segments mostly outlast nothing. [`QuietBox::NEVER`] by default.
    fn quiet_box(&self, max_window_s: f64) -> QuietBox {
        let _ = max_window_s;
        QuietBox::NEVER
    }
    /// The acceleration for `command_mps2` where no limit blocks it (a state in the
    /// [`QuietBox`]): [`accel`](Actuator::accel) there, in fewer tests.
    fn unblocked_accel(&self, command_mps2: f64) -> f64;
}

/// Relative margin of a [`QuietBox`] against the limits: a thousand times the margin of
/// [`SecondOrderActuator`]'s own out-of-reach tests, so that rounding in either cannot make
/// the box hold a state those tests would not clear.
const QUIET_MARGIN: f64 = 1e-6;

/// Paddle states (speed and height) from which an actuator's regime provably outlasts any
/// segment of at most `max_window_s` (s): where [`holds`](QuietBox::holds) is true,
/// [`Actuator::time_to_switch_within`] is at least the segment, and
/// [`Actuator::accel`] is [`Actuator::unblocked_accel`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct QuietBox {
    /// Largest speed, m/s.
    pub max_speed_mps: f64,
    /// Lowest height, m.
    pub min_height_m: f64,
    /// Highest height, m.
    pub max_height_m: f64,
    /// Longest segment, s.
    pub max_window_s: f64,
    /// Largest acceleration magnitude the actuator gives, m/s^2.
    pub max_accel_mps2: f64,
}

impl QuietBox {
    /// Holds no state (an actuator without a cheap bound).
    pub const NEVER: Self = Self {
        max_speed_mps: -1.0,
        min_height_m: f64::INFINITY,
        max_height_m: f64::NEG_INFINITY,
        max_window_s: -1.0,
        max_accel_mps2: f64::INFINITY,
    };
    /// Holds every finite state (an actuator without limits).
    pub const ALWAYS: Self = Self {
        max_speed_mps: f64::INFINITY,
        min_height_m: f64::NEG_INFINITY,
        max_height_m: f64::INFINITY,
        max_window_s: f64::INFINITY,
        max_accel_mps2: f64::INFINITY,
    };

    /// True if `p` is in the box: its regime outlasts any segment of at most
    /// `max_window_s`, and no limit blocks an acceleration there. Non-finite states are
    /// outside.
    #[inline(always)]
    pub fn holds(&self, p: &PaddleState<f64>) -> bool {
        p.velocity_mps.abs() <= self.max_speed_mps
            && p.height_m >= self.min_height_m
            && p.height_m <= self.max_height_m
    }
}

/// The paddle's acceleration is the command, without limits.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct IdealActuator;

impl Actuator for IdealActuator {
    #[inline]
    fn accel(&self, _: &PaddleState<f64>, command_mps2: f64) -> f64 {
        command_mps2
    }
    #[inline]
    fn time_to_switch(&self, _: &PaddleState<f64>, _: f64) -> f64 {
        f64::INFINITY
    }
    #[inline]
    fn settle(&self, _: &mut PaddleState<f64>) {}
    fn quiet_box(&self, _: f64) -> QuietBox {
        QuietBox::ALWAYS
    }
    #[inline]
    fn unblocked_accel(&self, command_mps2: f64) -> f64 {
        command_mps2
    }
}

/// A driven paddle mass (second order) with a force limit per unit mass, a speed limit
/// and hard, inelastic travel stops.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SecondOrderActuator {
    /// Largest force per unit mass, m/s^2.
    pub accel_max_mps2: f64,
    /// Largest speed, m/s.
    pub velocity_max_mps: f64,
    /// Lower stop, m.
    pub min_height_m: f64,
    /// Upper stop, m.
    pub max_height_m: f64,
}

/// How far, relative to the room to the nearer stop, the paddle's largest travel must
/// stay short of it for [`SecondOrderActuator::stops_out_of_reach`] to skip the stops'
/// roots (1e-9: millions of ulps, so the roots could not have found a stop earlier).
const STOP_CLEARANCE: f64 = 1e-9;

impl SecondOrderActuator {
    /// True if the paddle at `p` with acceleration `a` cannot reach either travel stop
    /// within `horizon_s` (s): its largest travel `|v| t + |a| t^2 / 2` is short of the
    /// room to the nearer stop by a margin ([`STOP_CLEARANCE`]). Then no stop ends the
    /// regime before the horizon, and the roots of the stops are not needed. False for a
    /// paddle at a stop, an infinite horizon or non-finite input (the roots decide).
    #[inline]
    fn stops_out_of_reach(&self, p: &PaddleState<f64>, a: f64, horizon_s: f64) -> bool {
        let travel_m = horizon_s * (p.velocity_mps.abs() + 0.5 * a.abs() * horizon_s);
        // the smaller room by one comparison: both are NaN or neither (`f64::min`'s NaN
        // handling cost 5 instructions a segment)
        let (up_m, down_m) = (
            self.max_height_m - p.height_m,
            p.height_m - self.min_height_m,
        );
        let room_m = if up_m < down_m { up_m } else { down_m };
        travel_m * (1.0 + STOP_CLEARANCE) < room_m * (1.0 - STOP_CLEARANCE)
    }

    /// True if the paddle at `p` with acceleration `a` cannot reach the speed limit within
    /// `horizon_s` (s): its largest speed `|v| + |a| t` stays short of the limit by the
    /// same margin as [`stops_out_of_reach`](Self::stops_out_of_reach). False for an
    /// infinite horizon or non-finite input (the division decides).
    #[inline]
    fn speed_limit_out_of_reach(&self, p: &PaddleState<f64>, a: f64, horizon_s: f64) -> bool {
        let top_mps = p.velocity_mps.abs() + a.abs() * horizon_s;
        top_mps * (1.0 + STOP_CLEARANCE) < self.velocity_max_mps * (1.0 - STOP_CLEARANCE)
    }

    /// Time until the speed limit ends acceleration `a` from `p`, s (infinite if never).
    #[inline]
    fn time_to_speed_limit(&self, p: &PaddleState<f64>, a: f64) -> f64 {
        if a > 0.0 && p.velocity_mps < self.velocity_max_mps {
            (self.velocity_max_mps - p.velocity_mps) / a
        } else if a < 0.0 && p.velocity_mps > -self.velocity_max_mps {
            (-self.velocity_max_mps - p.velocity_mps) / a
        } else {
            f64::INFINITY
        }
    }

    /// The earlier of `t_s` and the first time the room to a travel stop closes, s (the
    /// stops' roots, searched up to `t_s`).
    fn time_to_stop_or(&self, p: &PaddleState<f64>, a: f64, t_s: f64) -> f64 {
        let mut t = t_s;
        let up = first_contact(
            self.max_height_m - p.height_m,
            -p.velocity_mps,
            -0.5 * a,
            t.min(1e9),
        );
        let down = first_contact(
            p.height_m - self.min_height_m,
            p.velocity_mps,
            0.5 * a,
            t.min(1e9),
        );
        for c in [up, down].into_iter().flatten() {
            if c.time_s > 0.0 {
                t = t.min(c.time_s);
            }
        }
        t
    }
}

impl Actuator for SecondOrderActuator {
    /// The command clamped to the force limit (0 if not finite), or 0 where a stop or the
    /// speed limit blocks its direction. Spelled for the common case, a command within the
    /// limit (one comparison), and per direction (only its own limits are tested): the
    /// same values as `clamp` and the four-way test it replaces, ~10 instructions fewer
    /// per SIL step.
    #[inline]
    fn accel(&self, p: &PaddleState<f64>, command_mps2: f64) -> f64 {
        let a = self.unblocked_accel(command_mps2);
        let blocked = if a > 0.0 {
            (p.height_m >= self.max_height_m && p.velocity_mps >= 0.0)
                || p.velocity_mps >= self.velocity_max_mps
        } else if a < 0.0 {
            (p.height_m <= self.min_height_m && p.velocity_mps <= 0.0)
                || p.velocity_mps <= -self.velocity_max_mps
        } else {
            false
        };
        if blocked {
            0.0
        } else {
            a
        }
    }

    /// The command within the force limit (0 if not finite).
    #[inline]
    fn unblocked_accel(&self, command_mps2: f64) -> f64 {
        let a_max = self.accel_max_mps2;
        if command_mps2.abs() <= a_max {
            command_mps2
        } else if command_mps2.is_finite() {
            a_max.copysign(command_mps2)
        } else {
            0.0
        }
    }

    fn time_to_switch(&self, p: &PaddleState<f64>, a: f64) -> f64 {
        self.time_to_stop_or(p, a, self.time_to_speed_limit(p, a))
    }

    #[inline(always)]
    fn time_to_switch_within(&self, p: &PaddleState<f64>, a: f64, within_s: f64) -> f64 {
        if self.speed_limit_out_of_reach(p, a, within_s) && self.stops_out_of_reach(p, a, within_s)
        {
            // no limit within the segment: skip the division and the roots
            return f64::INFINITY;
        }
        let t = self.time_to_speed_limit(p, a);
        if self.stops_out_of_reach(p, a, t.min(within_s)) {
            // the speed limit (or nothing) ends the regime, or it outlasts the segment
            return t;
        }
        self.time_to_stop_or(p, a, t)
    }

    fn settle(&self, p: &mut PaddleState<f64>) {
        let v = self.velocity_max_mps;
        if (p.velocity_mps.abs() - v).abs() <= 1e-12 * v.max(1.0) {
            p.velocity_mps = p.velocity_mps.signum() * v;
        }
        let span = (self.max_height_m - self.min_height_m).abs().max(1.0);
        if p.height_m >= self.max_height_m - 1e-12 * span && p.velocity_mps > 0.0 {
            p.height_m = self.max_height_m;
            p.velocity_mps = 0.0;
        } else if p.height_m <= self.min_height_m + 1e-12 * span && p.velocity_mps < 0.0 {
            p.height_m = self.min_height_m;
            p.velocity_mps = 0.0;
        }
        p.height_m = p.height_m.clamp(self.min_height_m, self.max_height_m);
    }

    /// With the acceleration within the force limit `a` and a segment of at most `W`, a
    /// paddle at speed `|v| <= V = v_max (1 - m) - a W` stays below `v_max (1 - m)` and
    /// travels at most `D = W (V + a W / 2)`; with its height at least `D (1 + m)` from
    /// either stop neither limit is within reach, by `m` = 1e-6 relative where
    /// `speed_limit_out_of_reach` and
    /// `stops_out_of_reach` ask for 1e-9: so those tests
    /// clear every state in the box and the regime outlasts the segment. Empty
    /// ([`QuietBox::NEVER`]) when the limits leave no such state.
    fn quiet_box(&self, max_window_s: f64) -> QuietBox {
        let (a, w) = (self.accel_max_mps2, max_window_s);
        let v = self.velocity_max_mps * (1.0 - QUIET_MARGIN) - a * w;
        let d = w * (v + 0.5 * a * w) * (1.0 + QUIET_MARGIN);
        let (lo, hi) = (self.min_height_m + d, self.max_height_m - d);
        if v >= 0.0 && lo <= hi && w > 0.0 && d.is_finite() {
            QuietBox {
                max_speed_mps: v,
                min_height_m: lo,
                max_height_m: hi,
                max_window_s: w,
                max_accel_mps2: a,
            }
        } else {
            QuietBox::NEVER
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(4000))]
        /// The shortcut for a regime that outlasts the segment answers as the full
        /// computation does: the same time when that is shorter than the segment, else a
        /// time no shorter than the segment. States range over the travel, up to and past
        /// the speed limit, close to the stops (the shortcut's edge) and on them.
        #[test]
        fn switch_times_match_the_full_roots(
            h in -1.2f64..1.2,
            near_stop_exp in -14i32..0,
            v in -2.5f64..2.5,
            a in -12.0f64..12.0,
            within in 1e-4f64..1.0,
            pick in 0u8..3,
        ) {
            let act = act();
            let height_m = match pick {
                0 => h.clamp(-1.0, 1.0),
                1 => 1.0 - 10f64.powi(near_stop_exp),
                _ => -1.0 + 10f64.powi(near_stop_exp),
            };
            let p = PaddleState::new(height_m, v);
            let full = act.time_to_switch(&p, a);
            let fast = act.time_to_switch_within(&p, a, within);
            if full < within {
                prop_assert_eq!(fast, full);
            } else {
                prop_assert!(fast >= within, "{} < {} (full {})", fast, within, full);
            }
        }
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(4000))]
        /// A state in the quiet box outlasts every segment up to the box's window, whatever
        /// acceleration the actuator gives (the full computation says so), and no limit
        /// blocks a command there. States cover the box and its edges.
        #[test]
        fn quiet_box_states_outlast_the_window_and_are_not_blocked(
            (a_max, v_max) in (1.0f64..500.0, 0.5f64..10.0),
            window in 1e-5f64..5e-3,
            (fh, fv, fa, fw) in (0.0f64..=1.0, -1.0f64..=1.0, -1.0f64..=1.0, 0.0f64..=1.0),
            command in -1e3f64..1e3,
        ) {
            let act = SecondOrderActuator {
                accel_max_mps2: a_max,
                velocity_max_mps: v_max,
                min_height_m: -0.35,
                max_height_m: 0.15,
            };
            let q = act.quiet_box(window);
            prop_assume!(q.max_window_s > 0.0);
            let p = PaddleState::new(
                q.min_height_m + fh * (q.max_height_m - q.min_height_m),
                fv * q.max_speed_mps,
            );
            prop_assert!(q.holds(&p));
            let w = fw.max(1e-9) * q.max_window_s;
            let a = fa * a_max;
            prop_assert!(act.time_to_switch_within(&p, a, w) >= w);
            prop_assert!(act.time_to_switch(&p, a) >= w);
            prop_assert_eq!(act.accel(&p, command).to_bits(), act.unblocked_accel(command).to_bits());
        }
    }

    /// By hand: 250 m/s^2, 4 m/s, travel [-0.35, 0.15] m, 1 ms: speed up to
    /// 4 (1 - 1e-6) - 0.25 = 3.749996 m/s, heights 1 ms (3.749996 + 0.125) m/s (1 + 1e-6)
    /// = 3.875 mm inside either stop; an actuator whose limits leave no such state has an
    /// empty box.
    #[test]
    fn the_quiet_box_by_hand() {
        let act = SecondOrderActuator {
            accel_max_mps2: 250.0,
            velocity_max_mps: 4.0,
            min_height_m: -0.35,
            max_height_m: 0.15,
        };
        let q = act.quiet_box(1e-3);
        assert!((q.max_speed_mps - 3.749_996).abs() < 1e-12);
        let d = 1e-3 * (3.749_996 + 0.125) * (1.0 + 1e-6);
        assert!((q.min_height_m - (-0.35 + d)).abs() < 1e-12);
        assert!((q.max_height_m - (0.15 - d)).abs() < 1e-12);
        assert!(!q.holds(&PaddleState::new(0.0, 3.75)));
        assert!(!q.holds(&PaddleState::new(0.15 - 0.003, 0.0)));
        assert!(q.holds(&PaddleState::new(0.15 - 0.004, -3.7)));
        assert!(!q.holds(&PaddleState::new(f64::NAN, 0.0)));
        assert_eq!(
            act.quiet_box(0.02),
            QuietBox::NEVER,
            "250 m/s^2 for 20 ms passes 4 m/s"
        );
        assert_eq!(IdealActuator.quiet_box(1e-3), QuietBox::ALWAYS);
    }

    fn act() -> SecondOrderActuator {
        SecondOrderActuator {
            accel_max_mps2: 10.0,
            velocity_max_mps: 2.0,
            min_height_m: -1.0,
            max_height_m: 1.0,
        }
    }

    /// The old spelling of [`SecondOrderActuator::accel`]: clamp, then the four blocked
    /// cases.
    fn accel_by_clamp(act: &SecondOrderActuator, p: &PaddleState<f64>, command: f64) -> f64 {
        let a = if command.is_finite() {
            command.clamp(-act.accel_max_mps2, act.accel_max_mps2)
        } else {
            0.0
        };
        let at_top = p.height_m >= act.max_height_m && p.velocity_mps >= 0.0;
        let at_bottom = p.height_m <= act.min_height_m && p.velocity_mps <= 0.0;
        if (at_top && a > 0.0) || (at_bottom && a < 0.0) {
            return 0.0;
        }
        if (p.velocity_mps >= act.velocity_max_mps && a > 0.0)
            || (p.velocity_mps <= -act.velocity_max_mps && a < 0.0)
        {
            return 0.0;
        }
        a
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(4000))]
        /// The acceleration is the old spelling's bit for bit, at and past every limit, for
        /// signed zeros and non-finite commands.
        #[test]
        fn accel_matches_clamp_and_the_four_blocked_cases(
            h in -1.2f64..1.2,
            v in -2.5f64..2.5,
            command in -20.0f64..20.0,
            pick in 0u8..8,
        ) {
            let act = act();
            let (h, v) = match pick {
                0 => (1.0, v.abs()),
                1 => (-1.0, -v.abs()),
                2 => (h, 2.0),
                3 => (h, -2.0),
                _ => (h, v),
            };
            let command = match pick {
                4 => f64::NAN,
                5 => f64::INFINITY.copysign(command),
                6 => 0.0f64.copysign(command),
                7 => 10.0f64.copysign(command),
                _ => command,
            };
            let p = PaddleState::new(h, v);
            prop_assert_eq!(act.accel(&p, command).to_bits(), accel_by_clamp(&act, &p, command).to_bits());
        }
    }

    #[test]
    fn force_limit_clamps_the_command() {
        let p = PaddleState::new(0.0, 0.0);
        assert_eq!(act().accel(&p, 100.0), 10.0);
        assert_eq!(act().accel(&p, -3.0), -3.0);
        assert_eq!(act().accel(&p, f64::NAN), 0.0);
    }

    #[test]
    fn switches_at_the_speed_limit_then_at_the_stop() {
        let a = act();
        let mut p = PaddleState::new(0.0, 0.0);
        // 10 m/s^2 from rest reaches 2 m/s after 0.2 s (0.2 m travelled)
        let t = a.time_to_switch(&p, 10.0);
        assert!((t - 0.2).abs() < 1e-15);
        p = PaddleState::new(0.2, 2.0);
        a.settle(&mut p);
        assert_eq!(a.accel(&p, 10.0), 0.0);
        // coasting at 2 m/s reaches the stop at 1 m after 0.4 s
        assert!((a.time_to_switch(&p, 0.0) - 0.4).abs() < 1e-12);
        let mut q = PaddleState::new(1.0, 2.0);
        a.settle(&mut q);
        assert_eq!(q, PaddleState::new(1.0, 0.0));
        assert_eq!(a.accel(&q, 5.0), 0.0);
        assert_eq!(a.accel(&q, -5.0), -5.0);
    }
}
