//! The planar juggler's mirror law and the modified law with a solvable flight time
//! (Rizzi & Koditschek, "Further progress in robot juggling: solvable mirror laws", 1994,
//! sec. 3.1.1 and 4.1, eq. 10–16).
//!
//! A ball slides on an inclined plane, position b = (b_x, b_z) (m) with b_z "up the plane",
//! under the in-plane gravity component (0, -gamma) (eq. 10). A one-joint bar pivoting at
//! the origin bats it; the bar's inverse kinematics is
//! `g^-1(b) = (atan2(b_z, b_x), |b|)` (eq. 11), so the ball's angle is theta_b = atan2(b_z, b_x)
//! (rad, counterclockwise from the b_x axis). The laws assume the ball stays in the right
//! half plane (b_x > 0), where theta_b is in (-pi/2, pi/2).
//!
//! # Sign of the mirror (eq. 12)
//!
//! The extracted eq. 12 reads `r = k(w) [g^-1(b)]_1 + l(w)`, "k(w) defined as in (5)"; eq. 5 lost
//! its minus sign in extraction (restored in [`crate::mirror`] from eq. 9). The same sign is
//! restored here, so the bar mirrors the ball's angle about the horizontal:
//!
//! ```text
//! r = -k(w) theta_b + l(w),   k(w) = kappa0 + kappa1 (eta* - eta),   eta = |b'|^2/2 + gamma b_z
//! l(w) = kappa10 (b_x - b_x*) + kappa11 b_x'                                    (rad)
//! ```
//!
//! Evidence in the text for the minus sign: bar and ball meet where r = theta_b, i.e. at
//! theta_b = l/(1 + k), near the horizontal like the line juggler's impacts at b = 0; the
//! spatial law eq. 13 mirrors explicitly with `-k`; and the return map eq. 19–21 carries the
//! factor `(1 + alpha)(k + 1) theta_b'`, the relative bar-ball angular velocity
//! `theta_b' - r' = (1 + k) theta_b'` that r' = -k theta_b' produces (a `+k` law would give
//! `(1 - k)`).
//!
//! # The modified law (eq. 15–16)
//!
//! Printed: `r = k [g^-1]_1(b) + (1 - k) [g^-1]_1(l o F^ta(w))`, with
//! `l(w) = [kappa10 (b_x - b_x*) + kappa11 b_x', b_x]` a point of the ball's configuration space
//! and F^ta the flight to the apex, and the impact condition printed as
//! `b_z = [l]_1(w_bar) / (1 - k)` (eq. 16). With the same sign restored (k -> -k):
//!
//! ```text
//! r = -k theta_b + (1 + k) theta_l,   theta_l = atan2(kappa10 (b_x_bar - b_x*) + kappa11 b_x_bar', b_x_bar)
//! ```
//!
//! where w_bar = F^ta(w) is the apex of the current flight, so k and theta_l are constant
//! during a flight. Reading of the garbled parts: the PD term of l is a **height** (m, so
//! kappa10 is dimensionless and kappa11 in s) and b_x_bar the horizontal coordinate, i.e.
//! l = (b_x_bar, PD) in (x, z) order, which is the order eq. 16 uses when it equates b_z with
//! `[l]_1`; the printed component order `[PD, b_x]` would put the target near theta = pi/2,
//! directly above the pivot. Then r = theta_b iff (1 + k)(theta_b - theta_l) = 0, i.e. the
//! ball meets the bar when it crosses the ray at theta_l: `cos(theta_l) b_z(t) =
//! sin(theta_l) b_x(t)`, a quadratic in t (footnote 5). Eq. 16's `1/(1 - k)` is the weight of
//! the printed eq. 15 and cancels in r = theta_b; eq. 16's `b_z = [l]_1` is this condition when
//! b_x(t) = b_x_bar (no horizontal drift). [`ModifiedPlanarLaw::impact_time_s`] solves the
//! exact condition.

use crate::math::Real;
use crate::params::{finite, non_negative, positive, ParamError};

/// State of a ball on the inclined plane: position (m) and velocity (m/s).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct PlanarBall<R> {
    /// Horizontal position b_x, m (the laws assume b_x > 0).
    pub x_m: R,
    /// Position up the plane b_z, m.
    pub z_m: R,
    /// Horizontal velocity b_x', m/s.
    pub x_dot_mps: R,
    /// Velocity up the plane b_z', m/s.
    pub z_dot_mps: R,
}

impl<R: Real> PlanarBall<R> {
    /// A ball state from b_x (m), b_z (m), b_x' (m/s), b_z' (m/s).
    pub const fn new(x_m: R, z_m: R, x_dot_mps: R, z_dot_mps: R) -> Self {
        Self {
            x_m,
            z_m,
            x_dot_mps,
            z_dot_mps,
        }
    }

    /// Scaled total energy eta = |b'|^2/2 + gamma b_z, J/kg (as eq. 5, in the plane).
    #[inline]
    pub fn energy_jpkg(&self, gravity_mps2: R) -> R {
        R::HALF * (self.x_dot_mps * self.x_dot_mps + self.z_dot_mps * self.z_dot_mps)
            + gravity_mps2 * self.z_m
    }

    /// Ballistic flight for `dt_s` seconds (eq. 3/10), exact; `dt_s` may be negative.
    #[inline]
    pub fn flown(&self, dt_s: R, gravity_mps2: R) -> Self {
        Self {
            x_m: self.x_m + self.x_dot_mps * dt_s,
            z_m: self.z_m + self.z_dot_mps * dt_s - R::HALF * gravity_mps2 * dt_s * dt_s,
            x_dot_mps: self.x_dot_mps,
            z_dot_mps: self.z_dot_mps - gravity_mps2 * dt_s,
        }
    }

    /// The ball's angle theta_b = `[g^-1(b)]_1` = atan2(b_z, b_x), rad (eq. 11).
    #[inline]
    pub fn angle_rad(&self) -> R {
        self.z_m.atan2(self.x_m)
    }

    /// The ball's distance from the pivot |b| = `[g^-1(b)]_2`, m (eq. 11).
    #[inline]
    pub fn radius_m(&self) -> R {
        (self.x_m * self.x_m + self.z_m * self.z_m).sqrt()
    }

    /// theta_b' = (b_x b_z' - b_z b_x') / |b|^2, rad/s (undefined at the pivot: non-finite).
    #[inline]
    pub fn angle_rate_radps(&self) -> R {
        (self.x_m * self.z_dot_mps - self.z_m * self.x_dot_mps)
            / (self.x_m * self.x_m + self.z_m * self.z_m)
    }
}

/// A bar angle reference and its rate along the ballistic flow.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct AngleReference<R> {
    /// Bar angle r, rad, counterclockwise from the b_x axis.
    pub angle_rad: R,
    /// Bar angular rate r', rad/s (feed-forward for a tracking controller).
    pub rate_radps: R,
}

/// The planar mirror law, eq. 12 with the sign of eq. 5 restored (module docs):
/// `r = -k(w) theta_b + kappa10 (b_x - b_x*) + kappa11 b_x'`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PlanarMirrorLaw<R> {
    kappa0: R,
    kappa1_s2pm2: R,
    target_energy_jpkg: R,
    kappa10_radpm: R,
    kappa11_radspm: R,
    target_x_m: R,
    gravity_mps2: R,
}

impl<R: Real> PlanarMirrorLaw<R> {
    /// A planar mirror law.
    ///
    /// - `kappa0`: mirror gain at the target energy, dimensionless, >= 0.
    /// - `kappa1_s2pm2`: energy gain, s^2/m^2, >= 0.
    /// - `target_apex_m`: apex height b_z to regulate to, m, > 0; eta* = gamma * target.
    /// - `kappa10_radpm`: horizontal proportional gain, rad/m, finite.
    /// - `kappa11_radspm`: horizontal derivative gain, rad s/m, finite.
    /// - `target_x_m`: horizontal set point b_x*, m, > 0 (right half plane).
    /// - `gravity_mps2`: in-plane gravity gamma, m/s^2, > 0.
    pub fn new(
        kappa0: R,
        kappa1_s2pm2: R,
        target_apex_m: R,
        kappa10_radpm: R,
        kappa11_radspm: R,
        target_x_m: R,
        gravity_mps2: R,
    ) -> Result<Self, ParamError> {
        let gravity_mps2 = positive("gravity_mps2", gravity_mps2)?;
        Ok(Self {
            kappa0: non_negative("kappa0", kappa0)?,
            kappa1_s2pm2: non_negative("kappa1", kappa1_s2pm2)?,
            target_energy_jpkg: gravity_mps2 * positive("target_apex_m", target_apex_m)?,
            kappa10_radpm: finite("kappa10", kappa10_radpm)?,
            kappa11_radspm: finite("kappa11", kappa11_radspm)?,
            target_x_m: positive("target_x_m", target_x_m)?,
            gravity_mps2,
        })
    }

    /// eta* = gamma h*, J/kg.
    pub fn target_energy_jpkg(&self) -> R {
        self.target_energy_jpkg
    }

    /// The mirror gain k(w) = kappa0 + kappa1 (eta* - eta), dimensionless (eq. 5, 12).
    #[inline]
    pub fn gain(&self, ball: &PlanarBall<R>) -> R {
        self.kappa0
            + self.kappa1_s2pm2 * (self.target_energy_jpkg - ball.energy_jpkg(self.gravity_mps2))
    }

    /// The PD term l(w) = kappa10 (b_x - b_x*) + kappa11 b_x', rad (eq. 12).
    #[inline]
    pub fn offset_rad(&self, ball: &PlanarBall<R>) -> R {
        self.kappa10_radpm * (ball.x_m - self.target_x_m) + self.kappa11_radspm * ball.x_dot_mps
    }

    /// The bar reference r = -k theta_b + l(w) and its rate along the ballistic flow,
    /// r' = -k theta_b' + kappa10 b_x' (k is constant in flight since eta is, and b_x'' = 0).
    #[inline]
    pub fn reference(&self, ball: &PlanarBall<R>) -> AngleReference<R> {
        let k = self.gain(ball);
        AngleReference {
            angle_rad: -k * ball.angle_rad() + self.offset_rad(ball),
            rate_radps: -k * ball.angle_rate_radps() + self.kappa10_radpm * ball.x_dot_mps,
        }
    }
}

/// Real roots of `a t^2 + b t + c = 0`, ascending, by the cancellation-free formula
/// `q = -(b + sign(b) sqrt(b^2 - 4ac))/2`, roots `q/a` and `c/q`, after scaling the
/// coefficients by their largest magnitude (no overflow of b^2 for huge coefficients).
///
/// A linear equation (a = 0 after scaling) returns its root twice. `None` if there is no
/// real root, if all coefficients vanish (every t is a root) or if any is non-finite.
pub fn quadratic_roots<R: Real>(a: R, b: R, c: R) -> Option<[R; 2]> {
    if !(a.is_finite() && b.is_finite() && c.is_finite()) {
        return None;
    }
    let m = a.abs().max_r(b.abs()).max_r(c.abs());
    if m == R::ZERO {
        return None;
    }
    let (a, b, c) = (a / m, b / m, c / m);
    if a == R::ZERO {
        if b == R::ZERO {
            return None;
        }
        let r = -c / b;
        return Some([r, r]);
    }
    let disc = b * b - R::of(4.0) * a * c;
    // finite: the scaled coefficients are at most 1 in magnitude
    if disc < R::ZERO {
        return None;
    }
    let s = disc.sqrt();
    let q = if b >= R::ZERO {
        -R::HALF * (b + s)
    } else {
        R::HALF * (s - b)
    };
    if q == R::ZERO {
        // b = 0 and disc = 0, hence c = 0: double root at 0
        return Some([R::ZERO, R::ZERO]);
    }
    let (r1, r2) = (q / a, c / q);
    Some(if r1 <= r2 { [r1, r2] } else { [r2, r1] })
}

/// The modified planar mirror law with a solvable flight time, eq. 15–16 with the sign of
/// eq. 5 restored (module docs): `r = -k theta_b + (1 + k) theta_l`, with theta_l computed from
/// the apex of the current flight.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ModifiedPlanarLaw<R> {
    kappa0: R,
    kappa1_s2pm2: R,
    target_energy_jpkg: R,
    kappa10: R,
    kappa11_s: R,
    target_x_m: R,
    gravity_mps2: R,
}

impl<R: Real> ModifiedPlanarLaw<R> {
    /// A modified planar mirror law.
    ///
    /// - `kappa0` (dimensionless, >= 0), `kappa1_s2pm2` (s^2/m^2, >= 0), `target_apex_m`
    ///   (m, > 0): the gain k(w) as in eq. 5.
    /// - `kappa10`: horizontal proportional gain, m of target height per m of error,
    ///   dimensionless, finite.
    /// - `kappa11_s`: horizontal derivative gain, m per m/s = s, finite.
    /// - `target_x_m`: horizontal set point b_x*, m, > 0.
    /// - `gravity_mps2`: in-plane gravity gamma, m/s^2, > 0.
    pub fn new(
        kappa0: R,
        kappa1_s2pm2: R,
        target_apex_m: R,
        kappa10: R,
        kappa11_s: R,
        target_x_m: R,
        gravity_mps2: R,
    ) -> Result<Self, ParamError> {
        let gravity_mps2 = positive("gravity_mps2", gravity_mps2)?;
        Ok(Self {
            kappa0: non_negative("kappa0", kappa0)?,
            kappa1_s2pm2: non_negative("kappa1", kappa1_s2pm2)?,
            target_energy_jpkg: gravity_mps2 * positive("target_apex_m", target_apex_m)?,
            kappa10: finite("kappa10", kappa10)?,
            kappa11_s: finite("kappa11", kappa11_s)?,
            target_x_m: positive("target_x_m", target_x_m)?,
            gravity_mps2,
        })
    }

    /// The mirror gain k(w) = kappa0 + kappa1 (eta* - eta), dimensionless (eq. 5, 15).
    #[inline]
    pub fn gain(&self, ball: &PlanarBall<R>) -> R {
        self.kappa0
            + self.kappa1_s2pm2 * (self.target_energy_jpkg - ball.energy_jpkg(self.gravity_mps2))
    }

    /// The apex of the ball's current flight and the time to reach it, `(F^ta(w), t_a)` with
    /// t_a = b_z'/gamma, s (eq. 17; negative once the ball is falling: the apex it fell from).
    #[inline]
    pub fn apex_state(&self, ball: &PlanarBall<R>) -> (PlanarBall<R>, R) {
        let t_a = ball.z_dot_mps / self.gravity_mps2;
        let mut apex = ball.flown(t_a, self.gravity_mps2);
        apex.z_dot_mps = R::ZERO; // exact by definition; removes rounding
        (apex, t_a)
    }

    /// The target angle theta_l = atan2(kappa10 (b_x_bar - b_x*) + kappa11 b_x_bar', b_x_bar),
    /// rad, from the apex state w_bar: the bar angle at which it meets the ball.
    #[inline]
    pub fn target_angle_rad(&self, apex: &PlanarBall<R>) -> R {
        let height = self.kappa10 * (apex.x_m - self.target_x_m) + self.kappa11_s * apex.x_dot_mps;
        height.atan2(apex.x_m)
    }

    /// The bar reference r = -k theta_b + (1 + k) theta_l and its rate r' = -k theta_b' along
    /// the flow (k and theta_l are constant in flight: eta is, and so is the flight's apex).
    pub fn reference(&self, ball: &PlanarBall<R>) -> AngleReference<R> {
        let k = self.gain(ball);
        let (apex, _) = self.apex_state(ball);
        let theta_l = self.target_angle_rad(&apex);
        AngleReference {
            angle_rad: -k * ball.angle_rad() + (R::ONE + k) * theta_l,
            rate_radps: -k * ball.angle_rate_radps(),
        }
    }

    /// Time after the apex, s, at which the ball falling from `apex` crosses the ray at angle
    /// `theta_l_rad` (where r = theta_b, i.e. the impact; eq. 16 and footnote 5).
    ///
    /// Solves `cos(theta_l) b_z(t) - sin(theta_l) b_x(t) = 0` with b_x = x + x' t,
    /// b_z = z + z' t - gamma t^2/2 (z' = 0 at a true apex), i.e.
    /// `(gamma cos/2) t^2 + (sin x' - cos z') t + (sin x - cos z) = 0`, by [`quadratic_roots`].
    /// Returns the smallest root t >= 0 at which the ball is descending (b_z' <= 0) and on the
    /// ray itself (not its opposite); `None` if there is none.
    pub fn impact_time_s(&self, apex: &PlanarBall<R>, theta_l_rad: R) -> Option<R> {
        let (s, c) = (theta_l_rad.sin(), theta_l_rad.cos());
        let roots = quadratic_roots(
            R::HALF * self.gravity_mps2 * c,
            s * apex.x_dot_mps - c * apex.z_dot_mps,
            s * apex.x_m - c * apex.z_m,
        )?;
        let mut best: Option<R> = None;
        for t in roots {
            if t < R::ZERO || !t.is_finite() {
                continue;
            }
            let b = apex.flown(t, self.gravity_mps2);
            let on_ray = c * b.x_m + s * b.z_m > R::ZERO;
            if on_ray && b.z_dot_mps <= R::ZERO {
                best = Some(match best {
                    Some(prev) => prev.min_r(t),
                    None => t,
                });
            }
        }
        best
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const G: f64 = 9.81;

    #[test]
    fn ball_angle_and_rate_by_hand() {
        // b = (3, 4), b' = (1, -2): theta_b' = (3 * -2 - 4 * 1)/25 = -0.4 rad/s
        let b = PlanarBall::new(3.0f64, 4.0, 1.0, -2.0);
        assert!((b.angle_rate_radps() + 0.4).abs() < 1e-15);
        assert!((b.angle_rad() - (4.0f64 / 3.0).atan()).abs() < 1e-15);
        assert_eq!(b.radius_m(), 5.0);
        // eta = (1 + 4)/2 + 9.81 * 4 = 41.74
        assert!((b.energy_jpkg(G) - 41.74).abs() < 1e-12);
    }

    #[test]
    fn planar_reference_mirrors_about_horizontal_by_hand() {
        // kappa1 = 0 so k = kappa0 = 0.4; ball at 45 deg: r = -0.4 pi/4 + l,
        // l = 0.5 (1.2 - 1.0) + 0.1 * 0.3 = 0.13 rad
        let law = PlanarMirrorLaw::new(0.4f64, 0.0, 1.0, 0.5, 0.1, 1.0, G).unwrap();
        let b = PlanarBall::new(1.2, 1.2, 0.3, -1.0);
        let r = law.reference(&b);
        assert!((r.angle_rad - (-0.4 * core::f64::consts::FRAC_PI_4 + 0.13)).abs() < 1e-15);
        // rate: theta_b' = (1.2 * -1 - 1.2 * 0.3)/2.88 = -0.541667; r' = 0.216667 + 0.15
        assert!((r.rate_radps - (0.4 * 1.56 / 2.88 + 0.15)).abs() < 1e-15);
    }

    #[test]
    fn planar_reference_rate_is_consistent_with_flight() {
        let law = PlanarMirrorLaw::new(0.3f64, 0.02, 0.8, 0.4, 0.2, 0.9, G).unwrap();
        let b = PlanarBall::new(1.1, 0.6, -0.2, 1.3);
        let r = law.reference(&b);
        let dt = 1e-6;
        let ahead = law.reference(&b.flown(dt, G));
        let behind = law.reference(&b.flown(-dt, G));
        let fd = (ahead.angle_rad - behind.angle_rad) / (2.0 * dt);
        assert!((fd - r.rate_radps).abs() < 1e-8, "{fd} vs {}", r.rate_radps);
        // with l = 0 the bar meets the ball only at theta_b = 0 (the horizontal)
        let l0 = PlanarMirrorLaw::new(0.3f64, 0.0, 0.8, 0.0, 0.0, 0.9, G).unwrap();
        let at_horizontal = PlanarBall::new(1.0, 0.0, 0.1, -3.0);
        assert_eq!(l0.reference(&at_horizontal).angle_rad, 0.0);
        assert!(l0.reference(&b).angle_rad < 0.0 && b.angle_rad() > 0.0);
    }

    #[test]
    fn quadratic_roots_hand_values_and_degenerate_cases() {
        // (t - 2)(t + 3) = t^2 + t - 6
        assert_eq!(quadratic_roots(1.0f64, 1.0, -6.0), Some([-3.0, 2.0]));
        assert_eq!(quadratic_roots(1.0f64, 0.0, 1.0), None);
        assert_eq!(quadratic_roots(0.0f64, 2.0, -1.0), Some([0.5, 0.5]));
        assert_eq!(quadratic_roots(0.0f64, 0.0, 0.0), None);
        assert_eq!(quadratic_roots(2.0f64, 0.0, 0.0), Some([0.0, 0.0]));
        assert_eq!(quadratic_roots(f64::NAN, 1.0, 1.0), None);
        assert_eq!(quadratic_roots(1.0, f64::INFINITY, 1.0), None);
    }

    #[test]
    fn quadratic_roots_cancellation_and_scale() {
        // t^2 + 1e8 t + 1 = 0: small root by series -c/b - a c^2/b^3 - 2 a^2 c^3/b^5
        // = -1e-8 - 1e-24 - ...; the naive (-b + sqrt(b^2 - 4ac))/2a gives ~ -7.45e-9
        let [big, small] = quadratic_roots(1.0f64, 1e8, 1.0).unwrap();
        let series = -1e-8 - 1e-24;
        assert!(((small - series) / series).abs() < 1e-15, "{small:e}");
        assert!(((big + 1e8) / 1e8).abs() < 1e-15);
        let naive = (-1e8f64 + (1e16f64 - 4.0).sqrt()) / 2.0;
        assert!(
            ((naive - series) / series).abs() > 1e-2,
            "the test case must cancel"
        );
        // the same equation scaled by 1e200 and 1e-200 (b^2 would overflow / underflow)
        for &m in &[1e200f64, 1e-200] {
            let [b2, s2] = quadratic_roots(m, 1e8 * m, m).unwrap();
            assert!(((s2 - series) / series).abs() < 1e-15 && ((b2 + 1e8) / 1e8).abs() < 1e-15);
        }
        // huge and tiny coefficients in one equation: 1e-150 t^2 - t + 1e149 = 0
        // (b^2 - 4ac = 1 - 0.4 > 0); Vieta: product c/a = 1e299, sum -b/a = 1e150
        let [r1, r2] = quadratic_roots(1e-150f64, -1.0, 1e149).unwrap();
        assert!(((r1 * r2 - 1e299) / 1e299).abs() < 1e-14);
        assert!(((r1 + r2 - 1e150) / 1e150).abs() < 1e-14);
    }

    fn modified() -> ModifiedPlanarLaw<f64> {
        ModifiedPlanarLaw::new(0.3, 0.02, 1.0, 0.3, 0.15, 0.8, G).unwrap()
    }

    #[test]
    fn apex_state_by_hand_and_invariant_along_flight() {
        let law = modified();
        // b = (1, 0.5), b' = (0.3, 2): t_a = 2/9.81, apex z = 0.5 + 4/19.62, x = 1 + 0.6/9.81
        let b = PlanarBall::new(1.0, 0.5, 0.3, 2.0);
        let (apex, t_a) = law.apex_state(&b);
        assert!((t_a - 2.0 / G).abs() < 1e-15);
        assert!((apex.z_m - (0.5 + 4.0 / 19.62)).abs() < 1e-15);
        assert!((apex.x_m - (1.0 + 0.6 / G)).abs() < 1e-15);
        assert_eq!(apex.z_dot_mps, 0.0);
        // the same apex from later in the same flight (falling: t_a < 0)
        let (apex2, t2) = law.apex_state(&b.flown(0.5, G));
        assert!(t2 < 0.0);
        assert!((apex2.x_m - apex.x_m).abs() < 1e-14 && (apex2.z_m - apex.z_m).abs() < 1e-14);
        // so the reference's k and theta_l are constant in flight: rate is -k theta_b'
        let r = law.reference(&b);
        let dt = 1e-6;
        let fd = (law.reference(&b.flown(dt, G)).angle_rad
            - law.reference(&b.flown(-dt, G)).angle_rad)
            / (2.0 * dt);
        assert!((fd - r.rate_radps).abs() < 1e-8);
    }

    #[test]
    fn impact_time_puts_ball_on_the_target_angle() {
        let law = modified();
        for &(x, z, xd) in &[
            (1.0f64, 1.2, 0.3),
            (0.6, 0.9, -0.2),
            (0.9, 2.0, 0.0),
            (1.4, 0.4, 0.7),
        ] {
            let apex = PlanarBall::new(x, z, xd, 0.0);
            let theta_l = law.target_angle_rad(&apex);
            let t = law.impact_time_s(&apex, theta_l).unwrap();
            assert!(t > 0.0);
            let b = apex.flown(t, G);
            assert!(
                (b.angle_rad() - theta_l).abs() < 1e-12,
                "{} vs {theta_l}",
                b.angle_rad()
            );
            assert!(b.z_dot_mps < 0.0);
            // there the reference equals the ball angle: bar and ball meet
            let r = law.reference(&b);
            assert!((r.angle_rad - b.angle_rad()).abs() < 1e-12);
        }
        // by hand: theta_l = 0, apex (1, 0.4905, 0.2): b_z = 0 at t = sqrt(2 * 0.4905 / 9.81) = 0.316228
        let t = law
            .impact_time_s(&PlanarBall::new(1.0, 0.4905, 0.2, 0.0), 0.0)
            .unwrap();
        assert!((t - 0.1f64.sqrt()).abs() < 1e-15);
        // apex already below the target ray: no impact while descending
        assert_eq!(
            law.impact_time_s(&PlanarBall::new(1.0, -0.5, 0.0, 0.0), 0.0),
            None
        );
        // only the ray at theta_l counts, not the opposite ray (theta_l + pi)
        assert_eq!(
            law.impact_time_s(&PlanarBall::new(-1.0, 0.5, 0.0, 0.0), 0.0),
            None
        );
    }

    /// f32 tolerance: the libm backend is within a few ulp; micromath's sin/cos (~1e-3 abs),
    /// atan2 (~1e-2 rad) and exp/ln are coarser (math.rs).
    #[cfg(not(feature = "fast-math"))]
    const F32_TOL: f64 = 1e-5;
    #[cfg(feature = "fast-math")]
    const F32_TOL: f64 = 3e-2;

    #[test]
    fn impact_time_in_f32() {
        let law = ModifiedPlanarLaw::new(0.3f32, 0.02, 1.0, 0.3, 0.15, 0.8, 9.81).unwrap();
        let apex = PlanarBall::new(1.0f32, 1.2, 0.3, 0.0);
        let theta_l = law.target_angle_rad(&apex);
        let t = law.impact_time_s(&apex, theta_l).unwrap();
        // against the f64 law for the same target angle
        let law64 = ModifiedPlanarLaw::new(0.3f64, 0.02, 1.0, 0.3, 0.15, 0.8, 9.81).unwrap();
        let apex64 = PlanarBall::new(1.0f64, 1.2, 0.3, 0.0);
        let t64 = law64.impact_time_s(&apex64, f64::from(theta_l)).unwrap();
        assert!((f64::from(t) - t64).abs() < F32_TOL * t64, "{t} vs {t64}");
    }

    #[test]
    fn constructors_name_bad_parameters() {
        assert_eq!(
            PlanarMirrorLaw::new(-0.1f64, 0.0, 1.0, 0.0, 0.0, 1.0, G).unwrap_err(),
            ParamError::Negative("kappa0")
        );
        assert_eq!(
            PlanarMirrorLaw::new(0.1f64, 0.0, 1.0, f64::NAN, 0.0, 1.0, G).unwrap_err(),
            ParamError::NotFinite("kappa10")
        );
        assert_eq!(
            ModifiedPlanarLaw::new(0.1f64, 0.0, 1.0, 0.0, 0.0, 0.0, G).unwrap_err(),
            ParamError::NotPositive("target_x_m")
        );
        assert_eq!(
            ModifiedPlanarLaw::new(0.1f64, 0.0, 1.0, 0.0, 0.0, 1.0, -G).unwrap_err(),
            ParamError::NotPositive("gravity_mps2")
        );
    }
}
