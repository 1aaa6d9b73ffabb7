//! Ball and paddle states on the vertical line (heights up, m; velocities up, m/s).

use crate::math::Real;

/// State of a ball in vertical flight: height above the impact plane and vertical velocity.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct BallState<R> {
    /// Height above the nominal impact plane (paddle zero), m.
    pub height_m: R,
    /// Vertical velocity, positive up, m/s.
    pub velocity_mps: R,
}

impl<R: Real> BallState<R> {
    /// A ball state from height (m) and vertical velocity (m/s).
    pub const fn new(height_m: R, velocity_mps: R) -> Self {
        Self {
            height_m,
            velocity_mps,
        }
    }

    /// Scaled total energy eta = b'^2/2 + g b, J/kg (Rizzi & Koditschek eq. 5).
    #[inline]
    pub fn energy_jpkg(&self, gravity_mps2: R) -> R {
        R::HALF * self.velocity_mps * self.velocity_mps + gravity_mps2 * self.height_m
    }

    /// The apex height this state reaches in free flight, m: b + b'^2/(2g) = eta/g.
    #[inline]
    pub fn apex_height_m(&self, gravity_mps2: R) -> R {
        self.energy_jpkg(gravity_mps2) / gravity_mps2
    }

    /// Ballistic flight for `dt_s` seconds under gravity (Rizzi & Koditschek eq. 3), exact.
    #[inline]
    pub fn flown(&self, dt_s: R, gravity_mps2: R) -> Self {
        Self {
            height_m: self.height_m + self.velocity_mps * dt_s
                - R::HALF * gravity_mps2 * dt_s * dt_s,
            velocity_mps: self.velocity_mps - gravity_mps2 * dt_s,
        }
    }
}

/// State of the paddle (actuator) on the vertical line.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct PaddleState<R> {
    /// Paddle surface height, m.
    pub height_m: R,
    /// Paddle velocity, positive up, m/s.
    pub velocity_mps: R,
}

impl<R: Real> PaddleState<R> {
    /// A paddle state from height (m) and velocity (m/s).
    pub const fn new(height_m: R, velocity_mps: R) -> Self {
        Self {
            height_m,
            velocity_mps,
        }
    }
}

/// Coefficient-of-restitution impact with a much heavier paddle (Rizzi & Koditschek eq. 4):
/// b'+ = -alpha b'- + (1 + alpha) r', m/s. `alpha` in [0, 1] is dimensionless.
#[inline]
pub fn restitution_velocity<R: Real>(ball_velocity_mps: R, paddle_velocity_mps: R, alpha: R) -> R {
    -alpha * ball_velocity_mps + (R::ONE + alpha) * paddle_velocity_mps
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn flight_conserves_energy_and_reaches_apex() {
        let g = 9.81f64;
        let s = BallState::new(0.0, 4.0);
        let apex = s.flown(4.0 / g, g);
        assert!((apex.velocity_mps).abs() < 1e-15);
        assert!((apex.height_m - 16.0 / (2.0 * g)).abs() < 1e-15);
        assert!((s.apex_height_m(g) - apex.height_m).abs() < 1e-15);
        assert!((apex.energy_jpkg(g) - s.energy_jpkg(g)).abs() < 1e-13);
    }

    #[test]
    fn restitution_against_resting_paddle_reverses_and_scales() {
        assert_eq!(restitution_velocity(-5.0f64, 0.0, 0.8), 4.0);
        // moving paddle: b'+ - r' = -alpha (b'- - r')
        let (b, r, a) = (-3.0f64, 0.5, 0.5);
        let out = restitution_velocity(b, r, a);
        assert!(((out - r) + a * (b - r)).abs() < 1e-15);
    }
}
