//! Ball flight between events, against a paddle that moves as a quadratic in time.

use super::roots::{apart_by_margin, apart_by_margin_of, clearly_apart, first_contact};
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

    /// The coefficients of the gap `ball - paddle = c0 + c1 t + c2 t^2` over the segment,
    /// under gravity `g`: m, m/s, m/s^2.
    #[inline(always)]
    pub fn gap_to(&self, ball: &BallState<f64>, g: f64) -> (f64, f64, f64) {
        (
            ball.height_m - self.height_m,
            ball.velocity_mps - self.velocity_mps,
            -0.5 * (g + self.accel_mps2),
        )
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
    /// True if the flight is in closed form and [`clear_flight`](Flight::clear_flight) can
    /// answer (`false`: it never does, and a loop skips asking).
    const CLOSED_FORM: bool = false;
    /// The ball after `h_s` seconds (`0 < h_s <= bound.window_s`) if a cheap test proves it
    /// cannot meet `paddle`, whose speed and acceleration stay within `bound` over the
    /// segment: what [`fly_short`](Flight::fly_short) gives then, bit for bit. `None` when
    /// it cannot tell (the default: no such test, as for an integrated flight): the caller
    /// flies the segment.
    #[inline(always)]
    fn clear_flight(
        &self,
        ball: &BallState<f64>,
        paddle: &Poly,
        bound: &PaddleBound,
        h_s: f64,
        g: f64,
    ) -> Option<BallState<f64>> {
        let _ = (ball, paddle, bound, h_s, g);
        None
    }
}

/// What bounds a paddle over a segment under gravity `g`: its speed, the gap's curvature
/// `|g + r''| / 2 <= (g + a) / 2` for accelerations up to `a` (g > 0), and the segment's
/// length.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PaddleBound {
    /// Largest paddle speed, m/s.
    pub speed_mps: f64,
    /// Longest segment `W`, s.
    pub window_s: f64,
    /// `((g + a) / 2) W`, m/s: the curvature bound times the segment, computed once.
    pub curvature_term_mps: f64,
    /// `g / 2`, m/s^2 (exact), for the flight.
    pub half_gravity_mps2: f64,
}

impl PaddleBound {
    /// The bound for speeds up to `speed_mps`, accelerations up to `accel_mps2` in
    /// magnitude, gravity `gravity_mps2` (> 0) and segments up to `window_s`.
    pub fn new(speed_mps: f64, accel_mps2: f64, gravity_mps2: f64, window_s: f64) -> Self {
        Self {
            speed_mps,
            window_s,
            curvature_term_mps: (0.5 * (gravity_mps2 + accel_mps2)).abs() * window_s,
            half_gravity_mps2: 0.5 * gravity_mps2,
        }
    }
}

/// Drag-free flight in closed form (Rizzi & Koditschek eq. 3); contacts are roots of the
/// quadratic gap `b(t) - r(t)`.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Ballistic;

impl Flight for Ballistic {
    #[inline]
    fn fly(&mut self, ball: &mut BallState<f64>, paddle: &Poly, h_s: f64, g: f64) -> FlightEnd {
        let (c0, c1, c2) = paddle.gap_to(ball, g);
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
        let (c0, c1, c2) = paddle.gap_to(ball, g);
        if clearly_apart(c0, c1, c2, h_s) {
            *ball = ball.flown(h_s, g);
            return FlightEnd::Reached(h_s);
        }
        self.fly(ball, paddle, h_s, g)
    }

    const CLOSED_FORM: bool = true;

    /// Two tests, each of which implies [`clearly_apart`] (so `fly_short` flies the ball
    /// without a contact): first `apart_by_margin` on bounds of the gap's coefficients,
    /// all but `c0` constants of the loop (`|c1| = |b' - r'| <= |b'| + speed`, `|c2| =
    /// |g + r''| / 2 <= (g + accel) / 2` for g > 0, the segment at most `window`; the test
    /// is monotone in each, every rounding being, so where it holds for the bounds it holds
    /// for the segment's own coefficients); where that is too wide (near the paddle, a
    /// paddle without limits), on the segment's own coefficients.
    #[inline(always)]
    fn clear_flight(
        &self,
        ball: &BallState<f64>,
        paddle: &Poly,
        bound: &PaddleBound,
        h_s: f64,
        g: f64,
    ) -> Option<BallState<f64>> {
        let apart = apart_by_bound(ball, paddle.height_m, bound) || {
            let (c0, c1, c2) = paddle.gap_to(ball, g);
            apart_by_margin(c0, c1, c2, h_s)
        };
        apart.then(|| flown_half(ball, h_s, g, bound.half_gravity_mps2))
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

/// `apart_by_margin` on the bound's coefficients (see [`Ballistic`]'s `clear_flight`).
#[inline(always)]
fn apart_by_bound(ball: &BallState<f64>, paddle_height_m: f64, bound: &PaddleBound) -> bool {
    let c0 = ball.height_m - paddle_height_m;
    let c1 = ball.velocity_mps.abs() + bound.speed_mps;
    apart_by_margin_of(c0, c1, bound.curvature_term_mps, bound.window_s)
}

/// `ball.flown(h_s, g)` given `half_g = g / 2` (exact, so the same roundings): `h + v t -
/// ((g/2) t) t`, `v - g t`.
#[inline(always)]
fn flown_half(ball: &BallState<f64>, h_s: f64, g: f64, half_g: f64) -> BallState<f64> {
    BallState::new(
        ball.height_m + ball.velocity_mps * h_s - half_g * h_s * h_s,
        ball.velocity_mps - g * h_s,
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(20000))]
        /// Where the bounded test clears a flight, the flight against any paddle within the
        /// bound (speed, acceleration, segment) is the one `fly_short` flies, bit for bit: no
        /// contact, the whole segment. Balls from on the paddle to far above, both ways.
        #[test]
        fn a_cleared_flight_is_the_short_flight(
            (gap_exp, bv) in (-6.0f64..1.0, -12.0f64..12.0),
            (ph, fv, fa) in (-0.5f64..0.5, -1.0f64..=1.0, -1.0f64..=1.0),
            (speed, accel, g) in (0.0f64..5.0, 0.0f64..500.0, 1.0f64..20.0),
            (window_exp, fw) in (-5.0f64..-1.0, 0.0f64..=1.0),
        ) {
            let window = 10f64.powf(window_exp);
            let bound = PaddleBound::new(speed, accel, g, window);
            let ball = BallState::new(ph + 10f64.powf(gap_exp), bv);
            let h = fw.max(1e-6) * window;
            let paddle = Poly { height_m: ph, velocity_mps: fv * speed, accel_mps2: fa * accel };
            if apart_by_bound(&ball, ph, &bound) {
                let cleared = Ballistic.clear_flight(&ball, &paddle, &bound, h, g);
                prop_assert!(cleared.is_some());
                let cleared = cleared.unwrap();
                let mut flown = ball;
                prop_assert_eq!(Ballistic.fly_short(&mut flown, &paddle, h, g), FlightEnd::Reached(h));
                prop_assert_eq!(cleared.height_m.to_bits(), flown.height_m.to_bits());
                prop_assert_eq!(cleared.velocity_mps.to_bits(), flown.velocity_mps.to_bits());
            }
        }

        /// The same for the test on the segment's own coefficients.
        #[test]
        fn a_flight_cleared_of_the_paddle_is_the_short_flight(
            (gap_exp, bv) in (-6.0f64..1.0, -12.0f64..12.0),
            (ph, pv, pa) in (-0.5f64..0.5, -5.0f64..5.0, -500.0f64..500.0),
            (g, h_exp) in (1.0f64..20.0, -5.0f64..-1.0),
        ) {
            let h = 10f64.powf(h_exp);
            let ball = BallState::new(ph + 10f64.powf(gap_exp), bv);
            let paddle = Poly { height_m: ph, velocity_mps: pv, accel_mps2: pa };
            // a bound that never clears: only the segment's own coefficients decide
            let unbounded = PaddleBound::new(f64::INFINITY, f64::INFINITY, g, h);
            if let Some(cleared) = Ballistic.clear_flight(&ball, &paddle, &unbounded, h, g) {
                let mut flown = ball;
                prop_assert_eq!(Ballistic.fly_short(&mut flown, &paddle, h, g), FlightEnd::Reached(h));
                prop_assert_eq!(cleared.height_m.to_bits(), flown.height_m.to_bits());
                prop_assert_eq!(cleared.velocity_mps.to_bits(), flown.velocity_mps.to_bits());
            }
        }

        /// `flown_half` is `BallState::flown`, bit for bit.
        #[test]
        fn flown_with_half_gravity_is_flown(
            h in -10.0f64..10.0, v in -50.0f64..50.0, t in 0.0f64..1.0, g in 0.1f64..30.0,
        ) {
            let ball = BallState::new(h, v);
            let (a, b) = (flown_half(&ball, t, g, 0.5 * g), ball.flown(t, g));
            prop_assert_eq!(a.height_m.to_bits(), b.height_m.to_bits());
            prop_assert_eq!(a.velocity_mps.to_bits(), b.velocity_mps.to_bits());
        }
    }

    /// The bound's test looks at the bound, not the paddle's own state: a ball 2 mm above
    /// a paddle at rest with a 3 m/s, 250 m/s^2 bound over 1 ms is not cleared by it (3 mm
    /// of closing could pass), 5 mm above it is; an unbounded paddle clears nothing. The
    /// flight is then cleared by the segment's own coefficients where those allow: the
    /// paddle at rest, not one rising at 3 m/s.
    #[test]
    fn the_bound_decides_the_clearance() {
        let bound = PaddleBound::new(3.0, 250.0, 9.81, 1e-3);
        let at = |gap: f64| BallState::new(gap, 0.0);
        assert!(!apart_by_bound(&at(0.002), 0.0, &bound));
        assert!(apart_by_bound(&at(0.005), 0.0, &bound));
        let no_bound = PaddleBound::new(f64::INFINITY, f64::INFINITY, 9.81, 0.0);
        assert!(!apart_by_bound(&at(1.0), 0.0, &no_bound));
        let resting = Poly::default();
        let rising = Poly {
            velocity_mps: 3.0,
            ..Poly::default()
        };
        let clear = |p: &Poly| Ballistic.clear_flight(&at(0.002), p, &bound, 1e-3, 9.81);
        assert!(clear(&resting).is_some());
        assert!(clear(&rising).is_none());
    }
}
