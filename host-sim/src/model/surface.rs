//! What the ball hits: a fixed table, the paper's ideal mirror paddle, or an actuated
//! paddle driven by a controller's acceleration commands.

use crate::effects::actuator::{Actuator, QuietBox};
use crate::engine::{PaddleBound, Poly};
use dexter_core::mirror::MirrorLaw;
use dexter_core::state::{BallState, PaddleState};

/// The surface the ball bounces on.
pub trait Surface {
    /// The surface over the coming segment as a quadratic in local time (for contact roots).
    fn poly(&self) -> Poly;
    /// How long [`poly`](Surface::poly) stays valid on its own (until a limit switches the
    /// regime), s: exact when shorter than `within_s` (the segment the caller wants), else
    /// any value `>= within_s` (the regime outlasts the segment: no need to know by how much).
    fn max_segment_s(&self, within_s: f64) -> f64;
    /// Move along the current polynomial by `dt_s`; `to_switch` if that reaches the end of
    /// [`max_segment_s`](Surface::max_segment_s).
    fn advance(&mut self, dt_s: f64, to_switch: bool);
    /// Paddle velocity (m/s) and acceleration (m/s^2) the restitution law sees at a
    /// contact with `ball` (the state just before the impact).
    fn at_impact(&self, ball: &BallState<f64>, g: f64) -> (f64, f64);
    /// The paddle state for reports, given the ball state.
    fn state(&self, ball: &BallState<f64>) -> PaddleState<f64>;
    /// Apply a new acceleration command, m/s^2 (ignored by surfaces that are not driven).
    fn command(&mut self, accel_mps2: f64);
    /// True if a ball resting on this surface rests forever (nothing will throw it).
    fn rest_is_final(&self) -> bool;
    /// If the current regime provably outlasts every segment up to the bound's window (a
    /// cheap, conservative [`max_segment_s`](Surface::max_segment_s)`(w) >= w`): how fast
    /// the surface moves and accelerates over such a segment. `None` if it cannot tell (by
    /// default).
    #[inline(always)]
    fn calm(&self) -> Option<PaddleBound> {
        None
    }
    /// True if the plant's segments on this surface are short (a control period) and
    /// mostly end without a contact: the plant then asks the flight model to rule a
    /// contact out cheaply first ([`crate::engine::Flight::fly_short`]).
    const SHORT_SEGMENTS: bool = false;
}

/// A fixed, horizontal table.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Table {
    /// Table height, m.
    pub height_m: f64,
}

impl Surface for Table {
    #[inline]
    fn poly(&self) -> Poly {
        Poly {
            height_m: self.height_m,
            velocity_mps: 0.0,
            accel_mps2: 0.0,
        }
    }
    #[inline]
    fn max_segment_s(&self, _: f64) -> f64 {
        f64::INFINITY
    }
    #[inline]
    fn advance(&mut self, _: f64, _: bool) {}
    #[inline]
    fn at_impact(&self, _: &BallState<f64>, _: f64) -> (f64, f64) {
        (0.0, 0.0)
    }
    fn state(&self, _: &BallState<f64>) -> PaddleState<f64> {
        PaddleState::new(self.height_m, 0.0)
    }
    fn command(&mut self, _: f64) {}
    fn rest_is_final(&self) -> bool {
        true
    }
}

/// The gedanken juggler's paddle (Rizzi & Koditschek sec. 2.1): r = -k(w) b exactly and
/// continuously, from the true ball state, f64. With k < 1 the ball and paddle meet only
/// at b = 0, where r = 0 and r' = -k b' (eq. 6), so for contact purposes the surface is
/// the plane b = 0.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct IdealMirror {
    /// The mirror law (f64).
    pub law: MirrorLaw<f64>,
}

impl Surface for IdealMirror {
    #[inline]
    fn poly(&self) -> Poly {
        Poly::default()
    }
    #[inline]
    fn max_segment_s(&self, _: f64) -> f64 {
        f64::INFINITY
    }
    #[inline]
    fn advance(&mut self, _: f64, _: bool) {}
    #[inline]
    fn at_impact(&self, ball: &BallState<f64>, _: f64) -> (f64, f64) {
        let r = self.law.reference(ball);
        (r.velocity_mps, r.accel_mps2)
    }
    fn state(&self, ball: &BallState<f64>) -> PaddleState<f64> {
        let r = self.law.reference(ball);
        PaddleState::new(r.height_m, r.velocity_mps)
    }
    fn command(&mut self, _: f64) {}
    fn rest_is_final(&self) -> bool {
        // a ball at rest on b = 0 has r = r' = 0: the law never throws it again
        true
    }
}

/// A paddle driven by acceleration commands through an actuator model.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Actuated<A> {
    /// The actuator model.
    pub actuator: A,
    /// Paddle state now.
    pub paddle: PaddleState<f64>,
    /// The last command, m/s^2.
    pub command_mps2: f64,
    /// The acceleration the paddle has now, m/s^2 (always the actuator's
    /// [`Actuator::accel`], so within its force limit).
    pub accel_mps2: f64,
    /// The states whose regime outlasts a control period ([`Self::quiet_for`]).
    quiet: QuietBox,
    /// What bounds the paddle from a state in `quiet`.
    quiet_bound: PaddleBound,
    /// The paddle was in `quiet` at the last command and has not moved since.
    calm: bool,
}

impl<A: Actuator> Actuated<A> {
    /// A paddle at rest at `height_m`.
    pub fn new(actuator: A, height_m: f64) -> Self {
        Self {
            actuator,
            paddle: PaddleState::new(height_m, 0.0),
            command_mps2: 0.0,
            accel_mps2: 0.0,
            quiet: QuietBox::NEVER,
            quiet_bound: PaddleBound::new(f64::INFINITY, f64::INFINITY, 1.0, 0.0),
            calm: false,
        }
    }

    /// Segments of at most `max_window_s` (s, the control period with its rounding) under
    /// gravity `gravity_mps2` (m/s^2, > 0) are tested for a limit by the actuator's
    /// [`QuietBox`] first ([`Surface::calm`]).
    pub fn quiet_for(mut self, max_window_s: f64, gravity_mps2: f64) -> Self {
        let q = self.actuator.quiet_box(max_window_s);
        self.quiet = q;
        self.quiet_bound = PaddleBound::new(
            q.max_speed_mps,
            q.max_accel_mps2,
            gravity_mps2,
            q.max_window_s,
        );
        self
    }

    /// A limit was reached: snap onto it and take the new regime's acceleration. Out of
    /// line and cold: it is rare, and inlined its constants were computed on every segment
    /// of the SIL loop.
    #[cold]
    #[inline(never)]
    fn switch_regime(&mut self) {
        self.actuator.settle(&mut self.paddle);
        self.accel_mps2 = self.actuator.accel(&self.paddle, self.command_mps2);
    }
}

impl<A: Actuator> Surface for Actuated<A> {
    const SHORT_SEGMENTS: bool = true;

    #[inline]
    fn poly(&self) -> Poly {
        Poly {
            height_m: self.paddle.height_m,
            velocity_mps: self.paddle.velocity_mps,
            accel_mps2: self.accel_mps2,
        }
    }
    #[inline(always)]
    fn max_segment_s(&self, within_s: f64) -> f64 {
        self.actuator
            .time_to_switch_within(&self.paddle, self.accel_mps2, within_s)
    }
    #[inline]
    fn advance(&mut self, dt: f64, to_switch: bool) {
        self.calm = false;
        let a = self.accel_mps2;
        self.paddle.height_m += dt * (self.paddle.velocity_mps + 0.5 * a * dt);
        self.paddle.velocity_mps += a * dt;
        if to_switch {
            self.switch_regime();
        }
    }
    #[inline]
    fn at_impact(&self, _: &BallState<f64>, _: f64) -> (f64, f64) {
        (self.paddle.velocity_mps, self.accel_mps2)
    }
    fn state(&self, _: &BallState<f64>) -> PaddleState<f64> {
        self.paddle
    }
    /// In the quiet box no limit blocks the command: only the force limit applies.
    #[inline(always)]
    fn command(&mut self, accel_mps2: f64) {
        self.command_mps2 = accel_mps2;
        self.calm = self.quiet.holds(&self.paddle);
        self.accel_mps2 = if self.calm {
            self.actuator.unblocked_accel(accel_mps2)
        } else {
            self.actuator.accel(&self.paddle, accel_mps2)
        };
    }
    fn rest_is_final(&self) -> bool {
        false
    }
    #[inline(always)]
    fn calm(&self) -> Option<PaddleBound> {
        self.calm.then_some(self.quiet_bound)
    }
}
