//! Ball flight between events, against a paddle that moves as a quadratic in time.

use super::roots::{clearly_apart, first_contact};
use dexter_core::state::BallState;

/// The paddle over one segment, in segment-local time t (s):
/// `r(t) = height_m + velocity_mps t + accel_mps2 t^2 / 2`.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Poly {
    /// Height at the segment start, m.
    pub height_m: f64,
    /// Velocity at the segment start, m/s.
    pub velocity_mps: f64,
    /// Constant acceleration over the segment, m/s^2.
    pub accel_mps2: f64,
}

impl Poly {
    /// Height at local time `t_s`, m.
    #[inline]
    pub fn height_at(&self, t_s: f64) -> f64 {
        self.height_m + t_s * (self.velocity_mps + 0.5 * self.accel_mps2 * t_s)
    }
    /// Velocity at local time `t_s`, m/s.
    #[inline]
    pub fn velocity_at(&self, t_s: f64) -> f64 {
        self.velocity_mps + self.accel_mps2 * t_s
    }
}

/// How a flight segment ended.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum FlightEnd {
    /// No contact; the ball flew for the given time, s (the whole window, or less if an
    /// integrator hit its step cap).
    Reached(f64),
    /// Contact with the paddle after the given time, s.
    Contact {
        /// Local time of the contact, s.
        dt_s: f64,
        /// True if the paddle was only touched (zero relative velocity).
        grazing: bool,
    },
}

/// A model of the ball's free flight.
pub trait Flight {
    /// Fly `ball` for at most `h_s` seconds against `paddle`; on return `ball` is the state
    /// at the end of the flight (at the contact, if there was one).
    fn fly(&mut self, ball: &mut BallState<f64>, paddle: &Poly, h_s: f64, g: f64) -> FlightEnd;
    /// Apex height of the free flight from `ball`, m (its height if it is moving down).
    fn apex_m(&self, ball: &BallState<f64>, g: f64) -> f64;
    /// As [`fly`](Flight::fly), for segments that mostly end with the ball well clear of
    /// the paddle (a control period): a model may first rule a contact out cheaply. The
    /// result is the same as `fly`'s, bit for bit.
    #[inline]
    fn fly_short(
        &mut self,
        ball: &mut BallState<f64>,
        paddle: &Poly,
        h_s: f64,
        g: f64,
    ) -> FlightEnd {
        self.fly(ball, paddle, h_s, g)
    }
}

/// Drag-free flight in closed form (Rizzi & Koditschek eq. 3); contacts are roots of the
/// quadratic gap `b(t) - r(t)`.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Ballistic;

impl Flight for Ballistic {
    #[inline]
    fn fly(&mut self, ball: &mut BallState<f64>, paddle: &Poly, h_s: f64, g: f64) -> FlightEnd {
        let c0 = ball.height_m - paddle.height_m;
        let c1 = ball.velocity_mps - paddle.velocity_mps;
        let c2 = -0.5 * (g + paddle.accel_mps2);
        match first_contact(c0, c1, c2, h_s) {
            Some(c) => {
                *ball = ball.flown(c.time_s, g);
                FlightEnd::Contact {
                    dt_s: c.time_s,
                    grazing: c.grazing,
                }
            }
            None => {
                *ball = ball.flown(h_s, g);
                FlightEnd::Reached(h_s)
            }
        }
    }

    /// [`clearly_apart`] first: no square root or division when the gap cannot close.
    #[inline]
    fn fly_short(
        &mut self,
        ball: &mut BallState<f64>,
        paddle: &Poly,
        h_s: f64,
        g: f64,
    ) -> FlightEnd {
        let c0 = ball.height_m - paddle.height_m;
        let c1 = ball.velocity_mps - paddle.velocity_mps;
        let c2 = -0.5 * (g + paddle.accel_mps2);
        if clearly_apart(c0, c1, c2, h_s) {
            *ball = ball.flown(h_s, g);
            return FlightEnd::Reached(h_s);
        }
        self.fly(ball, paddle, h_s, g)
    }

    #[inline]
    fn apex_m(&self, ball: &BallState<f64>, g: f64) -> f64 {
        if ball.velocity_mps > 0.0 {
            ball.height_m + ball.velocity_mps * ball.velocity_mps / (2.0 * g)
        } else {
            ball.height_m
        }
    }
}
