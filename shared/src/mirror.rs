//! The line-juggler mirror law with energy feedback (Rizzi & Koditschek 1994, sec. 2.1).
//!
//! Ball height b (m, above the impact plane) and velocity b' (m/s); the paddle tracks
//!
//! ```text
//! r = -k(w) b,   k(w) = kappa0 + kappa1 (eta* - eta),   eta = b'^2/2 + g b      (eq. 5)
//! ```
//!
//! The extracted eq. 5 reads `r = k(w) b`; the minus sign is restored from eq. 9, whose apex
//! map `(alpha + k (1 + alpha))^2` only follows if the paddle velocity at impact is
//! r' = -k b' (eq. 6 with the sign of eq. 5 restored): the paddle mirrors the ball about the
//! impact plane, scaled by k. Since eta is constant in flight, so is k, hence along the
//! ballistic flow r' = -k b' and r'' = -k b'' = k g.
//!
//! With k < 1 the ball and paddle meet only at b = 0, where the restitution law
//! b'+ = -alpha b'- + (1 + alpha) r' maps an impact speed v = -b'- to
//! `v [alpha + (1 + alpha) k(v^2/2)]`; with `kappa0 = (1 - alpha)/(1 + alpha)` this is eq. 8,
//! `v [1 - beta (v^2 - v*^2)]`, `beta = (1 + alpha) kappa1 / 2`, `v*^2 = 2 eta*`.

use crate::math::Real;
use crate::params::{finite, non_negative, positive, within, ParamError};
use crate::state::BallState;

/// Paddle reference along the ballistic flow: position, velocity, acceleration.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct PaddleReference<R> {
    /// Reference paddle height r, m.
    pub height_m: R,
    /// Reference paddle velocity r', m/s.
    pub velocity_mps: R,
    /// Reference paddle acceleration r'', m/s^2 (feed-forward for a tracking controller).
    pub accel_mps2: R,
}

/// Line-juggler mirror law with energy feedback (Rizzi & Koditschek eq. 5, sign as eq. 9).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MirrorLaw<R> {
    kappa0: R,
    kappa1_s2pm2: R,
    target_energy_jpkg: R,
    gravity_mps2: R,
}

impl<R: Real> MirrorLaw<R> {
    /// A mirror law.
    ///
    /// - `kappa0`: mirror gain at the target energy, dimensionless, in `[0, 1)` (the paper's
    ///   physical assumption k < 1 keeps impacts on b = 0).
    /// - `kappa1_s2pm2`: energy-feedback gain, s^2/m^2 (1 per J/kg), >= 0.
    /// - `target_apex_m`: the apex height to regulate to, m, > 0; eta* = g * target.
    /// - `gravity_mps2`: g, m/s^2, > 0.
    pub fn new(
        kappa0: R,
        kappa1_s2pm2: R,
        target_apex_m: R,
        gravity_mps2: R,
    ) -> Result<Self, ParamError> {
        let kappa0 = finite("kappa0", kappa0)?;
        if !(kappa0 >= R::ZERO && kappa0 < R::ONE) {
            return Err(ParamError::OutOfRange("kappa0"));
        }
        let kappa1_s2pm2 = non_negative("kappa1", kappa1_s2pm2)?;
        let target_apex_m = positive("target_apex_m", target_apex_m)?;
        let gravity_mps2 = positive("gravity_mps2", gravity_mps2)?;
        Ok(Self {
            kappa0,
            kappa1_s2pm2,
            target_energy_jpkg: gravity_mps2 * target_apex_m,
            gravity_mps2,
        })
    }

    /// The gain `kappa0 = (1 - alpha)/(1 + alpha)` that makes the target apex a fixed point
    /// for restitution `alpha` in `[0, 1]` (the eq. 8 form of the return map).
    pub fn matched_kappa0(alpha: R) -> Result<R, ParamError> {
        let alpha = within("alpha", alpha, R::ZERO, R::ONE)?;
        Ok((R::ONE - alpha) / (R::ONE + alpha))
    }

    /// kappa0, dimensionless.
    pub fn kappa0(&self) -> R {
        self.kappa0
    }
    /// kappa1, s^2/m^2.
    pub fn kappa1_s2pm2(&self) -> R {
        self.kappa1_s2pm2
    }
    /// eta* = g h*, J/kg.
    pub fn target_energy_jpkg(&self) -> R {
        self.target_energy_jpkg
    }
    /// h* = eta*/g, m.
    pub fn target_apex_m(&self) -> R {
        self.target_energy_jpkg / self.gravity_mps2
    }
    /// g, m/s^2.
    pub fn gravity_mps2(&self) -> R {
        self.gravity_mps2
    }

    /// The mirror gain k(w) = kappa0 + kappa1 (eta* - eta), dimensionless (eq. 5).
    #[inline]
    pub fn gain(&self, ball: &BallState<R>) -> R {
        self.kappa0
            + self.kappa1_s2pm2 * (self.target_energy_jpkg - ball.energy_jpkg(self.gravity_mps2))
    }

    /// The paddle reference r = -k b with its derivatives along the ballistic flow:
    /// r' = -k b', r'' = k g (k is constant in flight since eta is).
    #[inline]
    pub fn reference(&self, ball: &BallState<R>) -> PaddleReference<R> {
        let k = self.gain(ball);
        PaddleReference {
            height_m: -k * ball.height_m,
            velocity_mps: -k * ball.velocity_mps,
            accel_mps2: k * self.gravity_mps2,
        }
    }

    /// Closed-form impact-to-impact map of impact speed v (m/s, > 0 downward speed) for an
    /// ideal paddle and restitution `alpha`: `v [alpha + (1 + alpha) k(v^2/2)]`. For
    /// `kappa0 = (1-alpha)/(1+alpha)` this is eq. 8. A non-positive result means the ball
    /// is not thrown up again (it stays on the paddle).
    #[inline]
    pub fn impact_speed_map(&self, speed_mps: R, alpha: R) -> R {
        let k = self.kappa0
            + self.kappa1_s2pm2 * (self.target_energy_jpkg - R::HALF * speed_mps * speed_mps);
        speed_mps * (alpha + (R::ONE + alpha) * k)
    }

    /// Closed-form apex-to-apex map (eq. 9): `h' = (alpha + k (1 + alpha))^2 h`, m, with k
    /// evaluated at the energy eta = g h of the incoming flight.
    #[inline]
    pub fn apex_map(&self, apex_m: R, alpha: R) -> R {
        let k = self.kappa0
            + self.kappa1_s2pm2 * (self.target_energy_jpkg - self.gravity_mps2 * apex_m);
        let s = alpha + k * (R::ONE + alpha);
        s * s * apex_m
    }

    /// The eq. 8 parameter beta = (1 + alpha) kappa1 / 2, s^2/m^2.
    #[inline]
    pub fn beta(&self, alpha: R) -> R {
        R::HALF * (R::ONE + alpha) * self.kappa1_s2pm2
    }

    /// The impact speed of the period-1 orbit, m/s, if one exists: the positive root of
    /// `alpha + (1 + alpha) k(v^2/2) = 1`, i.e. `v^2 = 2 eta* + 2 (kappa0 - (1-alpha)/(1+alpha)) / kappa1`.
    /// `None` without energy feedback (kappa1 = 0) unless kappa0 is matched (then every
    /// speed is a fixed point and this returns the target's).
    pub fn fixed_point_speed_mps(&self, alpha: R) -> Option<R> {
        let matched = (R::ONE - alpha) / (R::ONE + alpha);
        let v2 = if self.kappa1_s2pm2 > R::ZERO {
            R::TWO * self.target_energy_jpkg + R::TWO * (self.kappa0 - matched) / self.kappa1_s2pm2
        } else if self.kappa0 == matched {
            R::TWO * self.target_energy_jpkg
        } else {
            return None;
        };
        if v2 > R::ZERO {
            Some(v2.sqrt())
        } else {
            None
        }
    }

    /// Slope of [`impact_speed_map`](Self::impact_speed_map) at its period-1 orbit,
    /// dimensionless: `1 - (1 + alpha) kappa1 v*^2` (= `1 - 2 beta v*^2` for matched kappa0).
    /// The orbit is locally stable iff |slope| < 1; at slope -1 it period-doubles, i.e. at
    /// `beta v*^2 = 1` in eq. 8's terms.
    pub fn fixed_point_slope(&self, alpha: R) -> Option<R> {
        let v = self.fixed_point_speed_mps(alpha)?;
        Some(R::ONE - (R::ONE + alpha) * self.kappa1_s2pm2 * v * v)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const G: f64 = 9.81;

    fn law(alpha: f64, kappa1: f64, apex: f64) -> MirrorLaw<f64> {
        MirrorLaw::new(MirrorLaw::matched_kappa0(alpha).unwrap(), kappa1, apex, G).unwrap()
    }

    #[test]
    fn reference_mirrors_ball_and_is_consistent_with_flight() {
        let l = law(0.8, 0.05, 1.0);
        let ball = BallState::new(0.7, -1.3);
        let r = l.reference(&ball);
        let k = l.gain(&ball);
        assert_eq!(r.height_m, -k * 0.7);
        assert_eq!(r.velocity_mps, k * 1.3);
        // along the flow, r(t) = -k b(t) with constant k: finite difference of r matches r'
        let dt = 1e-6;
        let later = l.reference(&ball.flown(dt, G));
        assert!(((later.height_m - r.height_m) / dt - r.velocity_mps).abs() < 1e-5);
        assert!(((later.velocity_mps - r.velocity_mps) / dt - r.accel_mps2).abs() < 1e-6);
    }

    #[test]
    fn impact_map_equals_hand_derived_eq8_cubic() {
        // by hand: alpha = 0.5 -> kappa0 = 1/3; kappa1 = 0.02; h* = 1 m -> v*^2 = 2 g = 19.62
        // beta = 1.5 * 0.02 / 2 = 0.015; v = 5: 5 [1 - 0.015 (25 - 19.62)] = 5 * 0.9193 = 4.5965
        let l = law(0.5, 0.02, 1.0);
        let out = l.impact_speed_map(5.0, 0.5);
        assert!((out - 4.5965).abs() < 1e-12, "{out}");
        // and the general form v [alpha + (1+alpha)(kappa0 + kappa1 (eta* - v^2/2))]
        let direct = 5.0 * (0.5 + 1.5 * (1.0 / 3.0 + 0.02 * (G - 12.5)));
        assert!((out - direct).abs() < 1e-12);
        assert!((l.beta(0.5) - 0.015).abs() < 1e-15);
    }

    #[test]
    fn impact_map_matches_restitution_with_mirror_paddle_velocity() {
        // independent computation: apply the restitution law to b'- = -v with r' = -k b'-
        let l = MirrorLaw::new(0.2, 0.03, 0.8, G).unwrap();
        for &v in &[0.5, 2.0, 3.96, 6.0] {
            let ball = BallState::new(0.0, -v);
            let r = l.reference(&ball);
            let after = crate::state::restitution_velocity(-v, r.velocity_mps, 0.7);
            assert!((after - l.impact_speed_map(v, 0.7)).abs() < 1e-12);
        }
    }

    #[test]
    fn apex_map_is_square_of_speed_ratio() {
        let l = MirrorLaw::new(0.15, 0.04, 1.2, G).unwrap();
        let h = 0.6;
        let v = (2.0 * G * h).sqrt();
        let v1 = l.impact_speed_map(v, 0.6);
        let h1 = v1 * v1 / (2.0 * G);
        assert!((l.apex_map(h, 0.6) - h1).abs() < 1e-12);
    }

    #[test]
    fn fixed_point_and_period_doubling_threshold() {
        let alpha = 0.8;
        let l = law(alpha, 0.05, 1.0);
        let v = l.fixed_point_speed_mps(alpha).unwrap();
        assert!((v - (2.0 * G).sqrt()).abs() < 1e-12);
        assert!((l.impact_speed_map(v, alpha) - v).abs() < 1e-12);
        // slope 1 - 2 beta v*^2 with beta = 0.9 * 0.05 = 0.045, v*^2 = 19.62
        let s = l.fixed_point_slope(alpha).unwrap();
        assert!((s - (1.0 - 2.0 * 0.045 * 19.62)).abs() < 1e-12);
        // beta v*^2 = 1 at kappa1 = 1/(0.9 * 19.62): slope exactly -1 (period doubling)
        let l2 = law(alpha, 1.0 / (0.9 * 2.0 * G), 1.0);
        assert!((l2.fixed_point_slope(alpha).unwrap() + 1.0).abs() < 1e-12);
        // mismatched kappa0 shifts the fixed point: v^2 = 2 eta* + 2 (kappa0 - matched)/kappa1
        let l3 = MirrorLaw::new(0.2, 0.05, 1.0, G).unwrap();
        let v3 = l3.fixed_point_speed_mps(alpha).unwrap();
        assert!((l3.impact_speed_map(v3, alpha) - v3).abs() < 1e-12);
    }

    #[test]
    fn accessors_return_the_parameters_and_eta_star_is_g_h() {
        let l = MirrorLaw::new(0.2, 0.03, 1.5, 9.0).unwrap();
        assert_eq!(l.kappa0(), 0.2);
        assert_eq!(l.kappa1_s2pm2(), 0.03);
        assert_eq!(l.gravity_mps2(), 9.0);
        assert!((l.target_energy_jpkg() - 13.5).abs() < 1e-12);
        assert!((l.target_apex_m() - 1.5).abs() < 1e-12);
        // k(w) at the target energy is kappa0; 1 J/kg below it, kappa0 + kappa1
        assert!((l.gain(&BallState::new(1.5, 0.0)) - 0.2).abs() < 1e-12);
        assert!((l.gain(&BallState::new(0.0, (2.0f64 * 12.5).sqrt())) - 0.23).abs() < 1e-12);
    }

    /// Without energy feedback (kappa1 = 0) only matched kappa0 has period-1 orbits (every
    /// speed is one; the target's is returned, v = sqrt(2 g h)); where the root is v^2 = 0
    /// there is no orbit (no flight).
    #[test]
    fn fixed_point_without_feedback_and_at_zero_speed() {
        let alpha = 0.6;
        let matched = MirrorLaw::new(MirrorLaw::matched_kappa0(alpha).unwrap(), 0.0, 1.5, G);
        let v = matched.unwrap().fixed_point_speed_mps(alpha).unwrap();
        assert!((v - (2.0 * G * 1.5).sqrt()).abs() < 1e-12);
        let unmatched = MirrorLaw::new(0.3, 0.0, 1.5, G).unwrap();
        assert_eq!(unmatched.fixed_point_speed_mps(alpha), None);
        // alpha = 0: matched kappa0 = 1; kappa0 = 0.5, kappa1 = 0.25, eta* = 4 * 0.5 = 2:
        // v^2 = 2 * 2 + 2 (0.5 - 1) / 0.25 = 0 exactly
        let l = MirrorLaw::new(0.5, 0.25, 0.5, 4.0).unwrap();
        assert_eq!(l.fixed_point_speed_mps(0.0), None);
        assert_eq!(l.fixed_point_slope(0.0), None);
    }

    #[test]
    fn constructor_names_bad_parameters() {
        assert_eq!(
            ParamError::OutOfRange("kappa0").to_string(),
            "kappa0 is out of its allowed range"
        );
        assert_eq!(ParamError::NotPositive("g").to_string(), "g must be > 0");
        assert_eq!(ParamError::Negative("k").to_string(), "k must be >= 0");
        assert_eq!(
            ParamError::NotFinite("h").to_string(),
            "h must be a finite number"
        );
        assert_eq!(
            MirrorLaw::new(1.0, 0.1, 1.0, G).unwrap_err(),
            ParamError::OutOfRange("kappa0")
        );
        assert_eq!(
            MirrorLaw::new(0.1, -0.1, 1.0, G).unwrap_err(),
            ParamError::Negative("kappa1")
        );
        assert_eq!(
            MirrorLaw::new(0.1, 0.1, f64::NAN, G).unwrap_err(),
            ParamError::NotFinite("target_apex_m")
        );
        assert_eq!(
            MirrorLaw::<f64>::matched_kappa0(1.5).unwrap_err(),
            ParamError::OutOfRange("alpha")
        );
    }
}
