//! The line juggler's plant: a ball on a vertical line over a surface, advanced from event
//! to event with only the effects it was assembled with ([`table`]: the passive bounce on a
//! fixed table in closed form).

pub mod table;

use super::impact::ImpactRow;
use super::surface::Surface;
use crate::effects::jitter::{Jitter, Unphysical};
use crate::engine::zeno::{remaining_time_s, ZenoPolicy};
use crate::engine::{Flight, FlightEnd};
use dexter_core::state::{restitution_velocity, BallState};

/// Most flight segments in one [`LinePlant::advance_to`] call (a safety cap: a segment ends
/// at an impact, an actuator limit, or the requested time).
pub const MAX_SEGMENTS_PER_CALL: u32 = 1_000_000;

/// Why [`LinePlant::advance_to`] returned.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Advance {
    /// The requested time was reached.
    Reached,
    /// The requested number of impacts was reached (the time is that of the last impact).
    ImpactLimit,
    /// The ball rests on a surface that will never throw it again.
    RestForever,
    /// A safety cap on segments was hit before the requested time (the caller may continue).
    SegmentCap,
}

/// A resting-contact episode.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RestEvent {
    /// Time the ball came to rest on the paddle, s (the Zeno limit time if it was summed).
    pub time_s: f64,
    /// Impacts before the contact began.
    pub after_impacts: u64,
    /// True if the rest was forced by the per-segment impact cap rather than detected.
    pub forced: bool,
}

/// The plant: gravity, restitution, a flight model, a surface, and impact jitter.
#[derive(Clone, Debug)]
pub struct LinePlant<F, S, J> {
    /// Gravity, m/s^2.
    pub gravity_mps2: f64,
    /// Restitution, dimensionless.
    pub restitution: f64,
    /// The flight model.
    pub flight: F,
    /// The surface.
    pub surface: S,
    /// Impact-timing jitter.
    pub jitter: J,
    /// Zeno policy.
    pub zeno: ZenoPolicy,
    /// Time now, s.
    pub time_s: f64,
    /// Ball state now.
    pub ball: BallState<f64>,
    /// True while the ball rests on the paddle.
    pub resting: bool,
    /// Impacts so far.
    pub impacts: u64,
    /// Resting-contact episodes so far (bounded list: the first 64).
    pub rests: Vec<RestEvent>,
    /// Resting-contact episodes in total.
    pub rest_count: u64,
    /// Grazing contacts (zero relative speed) so far.
    pub grazing_contacts: u64,
    /// The last impact (meaningful once `impacts > 0`): built in place, so a caller that
    /// wants the last row reads it here instead of copying every row it is passed.
    pub last_row: ImpactRow,
}

/// Rest events kept in [`LinePlant::rests`].
const MAX_REST_EVENTS: usize = 64;

impl<F: Flight, S: Surface, J: Jitter> LinePlant<F, S, J> {
    /// A plant at t = 0 with `ball`.
    pub fn new(
        gravity_mps2: f64,
        restitution: f64,
        flight: F,
        surface: S,
        jitter: J,
        zeno: ZenoPolicy,
        ball: BallState<f64>,
    ) -> Self {
        Self {
            gravity_mps2,
            restitution,
            flight,
            surface,
            jitter,
            zeno,
            time_s: 0.0,
            ball,
            resting: false,
            impacts: 0,
            rests: Vec::new(),
            rest_count: 0,
            grazing_contacts: 0,
            last_row: ImpactRow::default(),
        }
    }

    fn come_to_rest(&mut self, time_s: f64, forced: bool) {
        self.resting = true;
        self.rest_count += 1;
        if self.rests.len() < MAX_REST_EVENTS {
            self.rests.push(RestEvent {
                time_s,
                after_impacts: self.impacts,
                forced,
            });
        }
    }

    /// Advance to `t_end_s` (s), stopping early once `max_impacts` impacts have happened in
    /// total; each impact is passed to `on_impact`.
    #[inline(always)]
    pub fn advance_to(
        &mut self,
        t_end_s: f64,
        max_impacts: u64,
        on_impact: &mut impl FnMut(&ImpactRow),
    ) -> Advance {
        self.advance_segments(t_end_s, max_impacts, MAX_SEGMENTS_PER_CALL, on_impact)
    }

    /// Advance to `t_end_s` in one closed-form flight if that is provably all that happens;
    /// true if it did. Otherwise false, with the plant untouched: the caller takes the
    /// general path ([`advance_to`](Self::advance_to)). "Provably": the ball is not
    /// resting; the surface is calm ([`Surface::calm`]: its regime outlasts any segment up
    /// to the bound's window, so no limit splits this one) and its speed and acceleration
    /// are bounded; the flight model clears the ball of any paddle within that bound over
    /// the window ([`Flight::clear_flight`]: a closed-form flight, no contact). Then
    /// [`advance_to`](Self::advance_to) takes the window as one segment that reaches its
    /// end, and flies it as this does, operation for operation (a property test:
    /// `tests::quiet_periods_are_the_general_loops`). A control period in the SIL loop is
    /// almost always one of these (BENCHMARKS.md, "SIL at 1 kHz").
    #[inline(always)]
    pub fn quiet_to(&mut self, t_end_s: f64) -> bool {
        if !Self::QUIET_PERIODS || self.resting {
            return false;
        }
        let Some(bound) = self.surface.calm() else {
            return false;
        };
        let window = t_end_s - self.time_s;
        if !(window > 0.0 && window <= bound.window_s) {
            return false;
        }
        let poly = self.surface.poly();
        let g = self.gravity_mps2;
        match self
            .flight
            .clear_flight(&self.ball, &poly, &bound, window, g)
        {
            Some(ball) => {
                self.ball = ball;
                self.surface.advance(window, false);
                self.time_s = t_end_s;
                true
            }
            None => false,
        }
    }

    /// True if [`quiet_to`](Self::quiet_to) can advance this plant (a closed-form flight
    /// over a surface of short segments); false: it never does.
    pub const QUIET_PERIODS: bool = S::SHORT_SEGMENTS && F::CLOSED_FORM;

    /// As [`advance_to`](Self::advance_to), with at most `max_segments` flight segments
    /// ([`Advance::SegmentCap`] after them).
    #[inline(always)]
    pub fn advance_segments(
        &mut self,
        t_end_s: f64,
        max_impacts: u64,
        max_segments: u32,
        on_impact: &mut impl FnMut(&ImpactRow),
    ) -> Advance {
        let g = self.gravity_mps2;
        let mut segment_impacts = 0u32;
        for _ in 0..max_segments {
            let window = t_end_s - self.time_s;
            if window <= 0.0 {
                return Advance::Reached;
            }
            let to_switch = self.surface.max_segment_s(window);
            let (h, hits_switch) = if to_switch < window {
                (to_switch, true)
            } else {
                (window, false)
            };
            if self.resting {
                if self.surface.rest_is_final() {
                    return Advance::RestForever;
                }
                if self.surface.poly().accel_mps2 >= -g {
                    // the ball rides on the paddle
                    self.surface.advance(h, hits_switch);
                    let p = self.surface.state(&self.ball);
                    self.ball = BallState::new(p.height_m, p.velocity_mps);
                    if !hits_switch {
                        self.time_s = t_end_s;
                        return Advance::Reached;
                    }
                    self.time_s += h;
                    continue;
                }
                // the paddle accelerates down faster than gravity: the ball leaves it
                self.resting = false;
            }
            let poly = self.surface.poly();
            let end = match S::SHORT_SEGMENTS {
                true => self.flight.fly_short(&mut self.ball, &poly, h, g),
                false => self.flight.fly(&mut self.ball, &poly, h, g),
            };
            match end {
                FlightEnd::Reached(dt) => {
                    let whole = dt >= h;
                    self.surface.advance(dt, whole && hits_switch);
                    if whole && !hits_switch {
                        // the end: return now rather than on the next pass (whose window
                        // would be 0), which cost the SIL loop a pass of setup per step
                        self.time_s = t_end_s;
                        return Advance::Reached;
                    }
                    self.time_s += dt;
                }
                FlightEnd::Contact { dt_s, grazing } => {
                    self.surface.advance(dt_s, false);
                    self.time_s += dt_s;
                    if grazing {
                        self.grazing_contacts += 1;
                    }
                    self.impact(on_impact);
                    segment_impacts += 1;
                    if !self.resting
                        && !self.surface.rest_is_final()
                        && segment_impacts >= self.zeno.max_impacts_per_segment
                    {
                        let t = self.time_s;
                        self.stick();
                        self.come_to_rest(t, true);
                    }
                    if self.impacts >= max_impacts {
                        return Advance::ImpactLimit;
                    }
                }
            }
        }
        Advance::SegmentCap
    }

    /// Put the ball on the paddle, moving with it.
    fn stick(&mut self) {
        let p = self.surface.state(&self.ball);
        self.ball = BallState::new(p.height_m, p.velocity_mps);
    }

    /// The restitution law at a contact, then the Zeno check.
    fn impact(&mut self, on_impact: &mut impl FnMut(&ImpactRow)) {
        let g = self.gravity_mps2;
        let e = self.restitution;
        let before = self.ball;
        let (surface_v, ra) = self.surface.at_impact(&before, g);
        let rv = surface_v + ra * self.jitter.offset_s();
        let paddle = self.surface.state(&before);
        let mut v_after = restitution_velocity(before.velocity_mps, rv, e);
        if J::ON && v_after < surface_v {
            // the ball would leave into the paddle: no physical impact does that. The
            // jitter keeps the first such impact for the caller, which fails the run when
            // `advance_to` returns; until then the ball leaves with the paddle.
            self.jitter.note_unphysical(Unphysical {
                time_s: self.time_s,
                ball_velocity_mps: v_after,
                surface_velocity_mps: surface_v,
            });
            v_after = surface_v;
        }
        // the ball is on the paddle surface at a contact: remove rounding in the height
        self.ball = BallState::new(paddle.height_m, v_after);
        let relative = v_after - rv;
        self.last_row = ImpactRow {
            index: self.impacts,
            time_s: self.time_s,
            ball_height_m: paddle.height_m,
            ball_velocity_before_mps: before.velocity_mps,
            ball_velocity_after_mps: v_after,
            paddle_height_m: paddle.height_m,
            paddle_velocity_mps: rv,
            apex_height_m: self.flight.apex_m(&self.ball, g),
        };
        self.impacts += 1;
        on_impact(&self.last_row);
        if self.zeno.is_zeno(relative, rv) {
            // the bounces that follow are a geometric series: sum them in closed form
            // against the surface's current acceleration, then rest on the paddle
            let g_eff = g + self.surface.poly().accel_mps2;
            let rest_time = match remaining_time_s(relative.max(0.0), g_eff, e) {
                Some(dt) if self.surface.rest_is_final() => self.time_s + dt,
                _ => self.time_s,
            };
            if self.surface.rest_is_final() {
                self.time_s = rest_time;
            }
            self.stick();
            self.come_to_rest(rest_time, false);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::effects::actuator::SecondOrderActuator;
    use crate::effects::jitter::NoJitter;
    use crate::engine::Ballistic;
    use crate::model::surface::Actuated;
    use proptest::prelude::*;

    type Plant = LinePlant<Ballistic, Actuated<SecondOrderActuator>, NoJitter>;

    fn plant(ball: (f64, f64), paddle: (f64, f64), command: f64, period: f64) -> Plant {
        let act = SecondOrderActuator {
            accel_max_mps2: 250.0,
            velocity_max_mps: 4.0,
            min_height_m: -0.35,
            max_height_m: 0.15,
        };
        let mut surface = Actuated::new(act, paddle.0).quiet_for(period * (1.0 + 1e-6), 9.81);
        surface.paddle.velocity_mps = paddle.1;
        surface.command(command);
        let zeno = ZenoPolicy {
            velocity_threshold_mps: 1e-3,
            relative_threshold: 1e-3,
            max_impacts_per_segment: 1000,
        };
        let ball = BallState::new(ball.0, ball.1);
        LinePlant::new(9.81, 0.8, Ballistic, surface, NoJitter, zeno, ball)
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(20000))]
        /// Where a period is quiet, the general loop takes it as one flight to its end, with
        /// the same ball, paddle and time bit for bit and no event; states from the ball on
        /// the paddle to far above, paddles at and past every limit, commands past the force
        /// limit, late step times.
        #[test]
        fn quiet_periods_are_the_general_loops(
            (gap, bv) in (-0.01f64..1.5, -8.0f64..8.0),
            (ph, pv) in (-0.4f64..0.2, -4.5f64..4.5),
            command in -400.0f64..400.0,
            (period, k) in (prop_oneof![Just(1e-3), Just(2e-3), 1e-4f64..1e-2], 0u64..10_000_000),
        ) {
            let mut quiet = plant((ph + gap, bv), (ph, pv), command, period);
            quiet.time_s = k as f64 * period;
            let mut general = quiet.clone();
            let t_end = (k + 1) as f64 * period;
            if quiet.quiet_to(t_end) {
                let end = general.advance_to(t_end, u64::MAX, &mut |_| panic!("an impact"));
                prop_assert_eq!(end, Advance::Reached);
                prop_assert_eq!(general.impacts, 0);
                let bits = |p: &Plant| {
                    let s = p.surface;
                    [p.ball.height_m, p.ball.velocity_mps, s.paddle.height_m,
                     s.paddle.velocity_mps, s.accel_mps2, p.time_s].map(f64::to_bits)
                };
                prop_assert_eq!(bits(&quiet), bits(&general));
            }
        }
    }

    /// By hand: a ball half a metre above a paddle at rest mid-travel is quiet for a 1 ms
    /// period; on the paddle, or with the paddle at a stop or at its speed limit, it is not
    /// (the general loop decides).
    #[test]
    fn a_period_is_quiet_only_clear_of_the_paddle_and_its_limits() {
        let quiet =
            |ball: (f64, f64), paddle: (f64, f64)| plant(ball, paddle, 10.0, 1e-3).quiet_to(1e-3);
        assert!(quiet((0.5, -3.0), (-0.1, 0.5)));
        assert!(!quiet((-0.1, -3.0), (-0.1, 0.5)), "on the paddle");
        assert!(!quiet((0.5, -3.0), (0.15, 0.0)), "at the upper stop");
        assert!(!quiet((0.5, -3.0), (-0.1, 4.0)), "at the speed limit");
        let mut resting = plant((0.5, -3.0), (-0.1, 0.5), 10.0, 1e-3);
        resting.resting = true;
        assert!(!resting.quiet_to(1e-3));
        let mut long = plant((0.5, -3.0), (-0.1, 0.5), 10.0, 1e-3);
        assert!(!long.quiet_to(2e-3), "longer than the box's period");
        let mut moved = plant((0.5, -3.0), (-0.1, 0.5), 10.0, 1e-3);
        moved.surface.advance(1e-4, false);
        assert!(!moved.quiet_to(1e-3), "the paddle moved since its command");
    }
}
