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
    /// Snap the state onto the limit that was just reached (removes rounding).
    fn settle(&self, paddle: &mut PaddleState<f64>);
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

impl Actuator for SecondOrderActuator {
    fn accel(&self, p: &PaddleState<f64>, command_mps2: f64) -> f64 {
        let a = if command_mps2.is_finite() {
            command_mps2.clamp(-self.accel_max_mps2, self.accel_max_mps2)
        } else {
            0.0
        };
        let at_top = p.height_m >= self.max_height_m && p.velocity_mps >= 0.0;
        let at_bottom = p.height_m <= self.min_height_m && p.velocity_mps <= 0.0;
        if (at_top && a > 0.0) || (at_bottom && a < 0.0) {
            return 0.0;
        }
        if (p.velocity_mps >= self.velocity_max_mps && a > 0.0)
            || (p.velocity_mps <= -self.velocity_max_mps && a < 0.0)
        {
            return 0.0;
        }
        a
    }

    fn time_to_switch(&self, p: &PaddleState<f64>, a: f64) -> f64 {
        let mut t = f64::INFINITY;
        if a > 0.0 && p.velocity_mps < self.velocity_max_mps {
            t = t.min((self.velocity_max_mps - p.velocity_mps) / a);
        } else if a < 0.0 && p.velocity_mps > -self.velocity_max_mps {
            t = t.min((-self.velocity_max_mps - p.velocity_mps) / a);
        }
        // travel stops: first time the room to each stop closes
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
}

#[cfg(test)]
mod tests {
    use super::*;

    fn act() -> SecondOrderActuator {
        SecondOrderActuator {
            accel_max_mps2: 10.0,
            velocity_max_mps: 2.0,
            min_height_m: -1.0,
            max_height_m: 1.0,
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
