//! The spatial juggler's mirror law and a modified one with a solvable flight time (Rizzi & Koditschek, "Further progress in robot juggling:
//! solvable mirror laws", 1994, sec. 3.1.2, eq. 13, with k(w) of eq. 5).
//!
//! A ball flies in 3-D, position b = (b_x, b_y, b_z) (m, b_z up) under gravity
//! a_p = (0, 0, -gamma) (eq. 3 with b in R^3). A three-joint robot at the origin bats it with a
//! paddle on a bar. The paper gives the law but not the machine's joint conventions; these
//! are the ones used here (docs/spatial.md derives the kinematics):
//!
//! | joint | angle | zero | positive |
//! | --- | --- | --- | --- |
//! | q1, azimuth | rad | the bar over the b_x axis | counterclockwise about +z |
//! | q2, shoulder | rad | the bar straight up; -pi/2 is the bar horizontal, over its azimuth | raises the bar |
//! | q3, paddle roll about the bar | rad | the paddle's normal in the bar's vertical plane | tilts the normal toward the lateral direction t = (-sin q1, cos q1, 0) |
//!
//! so the bar points along u = (cos e cos q1, cos e sin q1, sin e), with elevation
//! e = q2 + pi/2 above the horizontal. The inverse kinematic image of the ball (the joint
//! angles that put the bar's axis through it, and the distance along the bar) is
//!
//! ```text
//! g^-1(b) = (atan2(b_y, b_x), atan2(b_z, rho) - pi/2, |b|),   rho = sqrt(b_x^2 + b_y^2)
//! ```
//!
//! # The law (eq. 13)
//!
//! ```text
//! r1 = [g^-1]_1(b) = phi_b                                   (the azimuth follows the ball)
//! r2 = -pi/2 - k(w) ([g^-1]_2(b) + pi/2) - l1(b, b') = -pi/2 - k(w) e_b - l1
//! r3 = l2(b, b')
//! k(w) = kappa0 + kappa1 (eta* - eta),   eta = |b'|^2/2 + gamma b_z                  (eq. 5)
//! l1 = kappa10 (rho - rho*) + kappa11 rho'                          (radial PD, rad)
//! l2 = kappa20 d + kappa21 d',   d = rho sin(phi_b - phi*)          (lateral PD, rad)
//! ```
//!
//! e_b = atan2(b_z, rho) is the ball's elevation, (rho*, phi*) the set point's horizontal
//! radius and azimuth, and d the ball's signed distance from the vertical plane through the
//! z axis and the set point (positive counterclockwise of it).
//!
//! Reading of the printed eq. 13: its second row `-pi/2 - k([g^-1]_2(b) + pi/2) + -l_1` mirrors
//! the ball's angle from the horizontal (`[g^-1]_2 + pi/2` = e_b) about the horizontal
//! (q2 = -pi/2) with `-k`, the sign eq. 5 lost in extraction (restored in [`crate::mirror`] and
//! [`crate::planar`]); the `+ -` is read as a minus. In elevation, the bar's reference is
//! `e_r = r2 + pi/2 = -k e_b - l1`: the planar law of eq. 12, `theta_r = -k theta_b + l`, with
//! `l = -l1`. So in the vertical plane through the base (b_y = b_y' = 0, phi* = 0) this law is
//! [`crate::planar::PlanarMirrorLaw`] with kappa10, kappa11 negated, and r1 = r3 = 0; the
//! tests check that. The paper does not define l1 and l2 beyond "linear affine
//! transformations implementing proportional-derivative spatial regulation terms in the
//! radial and lateral directions"; the radial and lateral distances above are this crate's
//! reading.
//!
//! [`ModifiedSpatialLaw`] is a version with a solvable flight time, in the manner of eq. 15–16:
//! the bar meets the ball where it crosses an [`ImpactPlane`] fixed for the flight.
//!
//! The rates along the ballistic flow, for a tracking controller's feed-forward, use that
//! eta (so k), the horizontal velocity and h = b_x b_y' - b_y b_x' (the angular momentum
//! about z per unit mass) are constant in flight. Every angle and rate is undefined over the
//! base (rho = 0): non-finite there.

use crate::math::Real;
use crate::params::{finite, non_negative, positive, ParamError};
use crate::planar::quadratic_roots;
use serde::{Deserialize, Serialize};

/// A ball in 3-D: position (m) and velocity (m/s), b_z up.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct SpatialBall<R> {
    /// Position b = (b_x, b_y, b_z), m.
    pub position_m: [R; 3],
    /// Velocity b' = (b_x', b_y', b_z'), m/s.
    pub velocity_mps: [R; 3],
}

impl<R: Real> SpatialBall<R> {
    /// A ball at `position_m` (m) with `velocity_mps` (m/s).
    pub const fn new(position_m: [R; 3], velocity_mps: [R; 3]) -> Self {
        Self {
            position_m,
            velocity_mps,
        }
    }

    /// Scaled total energy eta = |b'|^2/2 + gamma b_z, J/kg (eq. 5).
    #[inline]
    pub fn energy_jpkg(&self, gravity_mps2: R) -> R {
        let [u, v, w] = self.velocity_mps;
        R::HALF * (u * u + v * v + w * w) + gravity_mps2 * self.position_m[2]
    }

    /// Ballistic flight for `dt_s` seconds (eq. 3), exact; `dt_s` may be negative.
    #[inline]
    pub fn flown(&self, dt_s: R, gravity_mps2: R) -> Self {
        let [x, y, z] = self.position_m;
        let [u, v, w] = self.velocity_mps;
        Self {
            position_m: [
                x + u * dt_s,
                y + v * dt_s,
                z + w * dt_s - R::HALF * gravity_mps2 * dt_s * dt_s,
            ],
            velocity_mps: [u, v, w - gravity_mps2 * dt_s],
        }
    }

    /// The horizontal radius rho = sqrt(b_x^2 + b_y^2), m.
    #[inline]
    pub fn horizontal_radius_m(&self) -> R {
        let [x, y, _] = self.position_m;
        (x * x + y * y).sqrt()
    }

    /// The distance from the base |b| = `[g^-1(b)]_3`, m.
    #[inline]
    pub fn radius_m(&self) -> R {
        let [x, y, z] = self.position_m;
        (x * x + y * y + z * z).sqrt()
    }

    /// The ball's azimuth phi_b = `[g^-1(b)]_1` = atan2(b_y, b_x), rad.
    #[inline]
    pub fn azimuth_rad(&self) -> R {
        self.position_m[1].atan2(self.position_m[0])
    }

    /// The ball's elevation above the horizontal e_b = atan2(b_z, rho) =
    /// `[g^-1(b)]_2 + pi/2`, rad.
    #[inline]
    pub fn elevation_rad(&self) -> R {
        self.position_m[2].atan2(self.horizontal_radius_m())
    }

    /// rho' = (b_x b_x' + b_y b_y') / rho, m/s.
    #[inline]
    pub fn radial_rate_mps(&self) -> R {
        let ([x, y, _], [u, v, _]) = (self.position_m, self.velocity_mps);
        (x * u + y * v) / self.horizontal_radius_m()
    }

    /// The horizontal velocity across the radius, rho phi_b' = (b_x b_y' - b_y b_x') / rho,
    /// m/s (positive counterclockwise).
    #[inline]
    pub fn lateral_velocity_mps(&self) -> R {
        let ([x, y, _], [u, v, _]) = (self.position_m, self.velocity_mps);
        (x * v - y * u) / self.horizontal_radius_m()
    }

    /// phi_b' = (b_x b_y' - b_y b_x') / rho^2, rad/s.
    #[inline]
    pub fn azimuth_rate_radps(&self) -> R {
        self.lateral_velocity_mps() / self.horizontal_radius_m()
    }

    /// e_b' = (rho b_z' - b_z rho') / |b|^2, rad/s.
    #[inline]
    pub fn elevation_rate_radps(&self) -> R {
        let rho = self.horizontal_radius_m();
        let r = self.radius_m();
        (rho * self.velocity_mps[2] - self.position_m[2] * self.radial_rate_mps()) / (r * r)
    }
}

/// Joint references q1, q2, q3 (rad) and their rates along the ballistic flow (rad/s).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct JointReference<R> {
    /// Joint angles (azimuth, shoulder, paddle roll), rad (module docs).
    pub angles_rad: [R; 3],
    /// Joint rates, rad/s (feed-forward for a tracking controller).
    pub rates_radps: [R; 3],
}

/// The parameters of [`SpatialMirrorLaw`].
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct SpatialLawParams<R> {
    /// Mirror gain at the target energy, dimensionless, >= 0.
    pub kappa0: R,
    /// Energy gain, s^2/m^2, >= 0.
    pub kappa1_s2pm2: R,
    /// Apex height b_z to regulate to, m, > 0 (eta* = gamma times it).
    pub target_apex_m: R,
    /// Radial proportional gain kappa10, finite: rad/m in [`SpatialMirrorLaw`] (l1 is an
    /// angle), dimensionless in [`ModifiedSpatialLaw`] (m of target height per m).
    pub kappa10: R,
    /// Radial derivative gain kappa11, finite: rad s/m in [`SpatialMirrorLaw`], s in
    /// [`ModifiedSpatialLaw`].
    pub kappa11: R,
    /// Lateral proportional gain kappa20, rad/m, finite.
    pub kappa20_radpm: R,
    /// Lateral derivative gain kappa21, rad s/m, finite.
    pub kappa21_radspm: R,
    /// The set point's horizontal radius rho*, m, > 0.
    pub target_radius_m: R,
    /// The set point's azimuth phi*, rad, finite.
    pub target_azimuth_rad: R,
    /// Gravity gamma, m/s^2, > 0.
    pub gravity_mps2: R,
}

impl<R: Real> SpatialLawParams<R> {
    /// Gains that converge (docs/spatial.md, "Gains that converge") for restitution
    /// `alpha`, gravity `gamma` (m/s^2), the apex h* (m) over (rho*, phi*) (m, rad), under
    /// eq. 13 (`modified` false) or the modified law: kappa0 matched, (1 - alpha)/(1 + alpha);
    /// kappa1 = 0.5/((1 + alpha) v*^2) (eq. 8's slope 1/2); the planar juggler's radial gains
    /// (0.12, 0.08), negated under eq. 13 (its `-l1`); the lateral gains half of deadbeat,
    /// kappa21 = -1/(4 v*), kappa20 = -1/(4 v* T), with v*^2 = 2 gamma h* and T = 2 v*/gamma.
    /// Not validated: [`SpatialMirrorLaw::new`] is.
    pub fn suggested(
        modified: bool,
        alpha: R,
        gamma: R,
        apex_m: R,
        radius_m: R,
        azimuth_rad: R,
    ) -> Self {
        let two = R::ONE + R::ONE;
        let v = (two * gamma * apex_m).sqrt();
        let flight_s = two * v / gamma;
        let radial = if modified { R::ONE } else { -R::ONE };
        Self {
            kappa0: (R::ONE - alpha) / (R::ONE + alpha),
            kappa1_s2pm2: R::HALF / ((R::ONE + alpha) * v * v),
            target_apex_m: apex_m,
            kappa10: radial * R::of(0.12),
            kappa11: radial * R::of(0.08),
            kappa20_radpm: -R::HALF / (two * v * flight_s),
            kappa21_radspm: -R::HALF / (two * v),
            target_radius_m: radius_m,
            target_azimuth_rad: azimuth_rad,
            gravity_mps2: gamma,
        }
    }
}

/// The paddle's orientation and angular velocity at joint angles (q1, q2, q3) and rates
/// (module docs' conventions; docs/spatial.md derives them): the bar
/// u = (cos e cos q1, cos e sin q1, sin e), e = q2 + pi/2; the normal of the paddle,
/// n = cos q3 n0 + sin q3 t with n0 = du/de = (-sin e cos q1, -sin e sin q1, cos e) and
/// t = (-sin q1, cos q1, 0); and omega = q1' z - e' t - q3' u (rad/s), so that
/// du/dt = omega x u and dn/dt = omega x n (with (u, t, n0) right-handed,
/// (-t) x u = n0 and (-u) x n0 = t). The paddle is the plane through the base with normal
/// n; the signed distance of a point b from it is n . b, positive on the side n points to.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct PaddleFrame<R> {
    /// The bar's direction u, unit.
    pub bar: [R; 3],
    /// The paddle's unit normal n.
    pub normal: [R; 3],
    /// The paddle's angular velocity omega, rad/s.
    pub angular_velocity_radps: [R; 3],
}

/// The cross product a x b.
#[inline]
pub fn cross<R: Real>(a: &[R; 3], b: &[R; 3]) -> [R; 3] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

/// The dot product a . b.
#[inline]
pub fn dot<R: Real>(a: &[R; 3], b: &[R; 3]) -> R {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

impl<R: Real> PaddleFrame<R> {
    /// The frame from (sin, cos) of q1, of e = q2 + pi/2 and of q3 (the caller picks the
    /// sine source: the controller a polynomial, the simulator f64's own), and the joint
    /// rates (q1', q2', q3'), rad/s (e' = q2').
    #[inline]
    pub fn from_sin_cos(sc: [(R, R); 3], rates_radps: [R; 3]) -> Self {
        let [(s1, c1), (se, ce), (s3, c3)] = sc;
        let bar = [ce * c1, ce * s1, se];
        let n0 = [-se * c1, -se * s1, ce];
        let t = [-s1, c1, R::ZERO];
        let [q1_dot, e_dot, q3_dot] = rates_radps;
        Self {
            bar,
            normal: core::array::from_fn(|i| c3 * n0[i] + s3 * t[i]),
            angular_velocity_radps: core::array::from_fn(|i| {
                -e_dot * t[i] - q3_dot * bar[i] + if i == 2 { q1_dot } else { R::ZERO }
            }),
        }
    }

    /// Signed distance of `point_m` from the paddle's plane, n . b, m.
    #[inline]
    pub fn gap_m(&self, point_m: &[R; 3]) -> R {
        dot(&self.normal, point_m)
    }

    /// Velocity of the paddle's point at `point_m`, omega x b, m/s.
    #[inline]
    pub fn velocity_at_mps(&self, point_m: &[R; 3]) -> [R; 3] {
        cross(&self.angular_velocity_radps, point_m)
    }

    /// Rate of [`Self::gap_m`] for `ball`: n . b' + (omega x n) . b, m/s.
    #[inline]
    pub fn gap_rate_mps(&self, ball: &SpatialBall<R>) -> R {
        let n_dot = cross(&self.angular_velocity_radps, &self.normal);
        dot(&self.normal, &ball.velocity_mps) + dot(&n_dot, &ball.position_m)
    }

    /// The ball's velocity after a frictionless impact with the paddle at `ball`'s position,
    /// b'+ = b' - (1 + alpha) (n . (b' - v_p)) n with v_p the paddle's velocity there; `None`
    /// if the ball is not approaching the paddle (n . (b' - v_p) >= 0, or NaN).
    #[inline]
    pub fn bounce(&self, ball: &SpatialBall<R>, restitution: R) -> Option<[R; 3]> {
        let v_p = self.velocity_at_mps(&ball.position_m);
        let v = ball.velocity_mps;
        let un = dot(&self.normal, &[v[0] - v_p[0], v[1] - v_p[1], v[2] - v_p[2]]);
        // NaN is no impact either
        if un.partial_cmp(&R::ZERO) != Some(core::cmp::Ordering::Less) {
            return None;
        }
        let j = (R::ONE + restitution) * un;
        Some(core::array::from_fn(|i| v[i] - j * self.normal[i]))
    }
}

/// The spatial mirror law, eq. 13 with the sign of eq. 5 restored (module docs).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SpatialMirrorLaw<R> {
    p: SpatialLawParams<R>,
    target_energy_jpkg: R,
    /// (cos phi*, sin phi*): d = rho sin(phi_b - phi*) is computed without an angle.
    target_direction: [R; 2],
}

impl<R: Real> SpatialMirrorLaw<R> {
    /// The law of `p`; an error names the first parameter out of its range.
    pub fn new(p: SpatialLawParams<R>) -> Result<Self, ParamError> {
        let phi = p.target_azimuth_rad;
        Self::with_direction(p, (phi.sin(), phi.cos()))
    }

    /// [`Self::new`] with the set point azimuth's `(sin phi*, cos phi*)` from the caller's
    /// sine (the fixed-rate controller's polynomial, so that its image links no libm `sinf`
    /// only for this).
    pub fn with_direction(p: SpatialLawParams<R>, sin_cos: (R, R)) -> Result<Self, ParamError> {
        non_negative("kappa0", p.kappa0)?;
        non_negative("kappa1", p.kappa1_s2pm2)?;
        positive("target_apex_m", p.target_apex_m)?;
        finite("kappa10", p.kappa10)?;
        finite("kappa11", p.kappa11)?;
        finite("kappa20", p.kappa20_radpm)?;
        finite("kappa21", p.kappa21_radspm)?;
        positive("target_radius_m", p.target_radius_m)?;
        finite("target_azimuth_rad", p.target_azimuth_rad)?;
        positive("gravity_mps2", p.gravity_mps2)?;
        Ok(Self {
            p,
            target_energy_jpkg: p.gravity_mps2 * p.target_apex_m,
            target_direction: [sin_cos.1, sin_cos.0],
        })
    }

    /// The parameters.
    pub fn params(&self) -> &SpatialLawParams<R> {
        &self.p
    }

    /// The mirror gain k(w) = kappa0 + kappa1 (eta* - eta), dimensionless (eq. 5, 13).
    #[inline]
    pub fn gain(&self, ball: &SpatialBall<R>) -> R {
        self.p.kappa0
            + self.p.kappa1_s2pm2
                * (self.target_energy_jpkg - ball.energy_jpkg(self.p.gravity_mps2))
    }

    /// The ball's signed distance from the set point's vertical plane,
    /// d = rho sin(phi_b - phi*) = b_y cos phi* - b_x sin phi*, m.
    #[inline]
    pub fn lateral_offset_m(&self, ball: &SpatialBall<R>) -> R {
        let [c, s] = self.target_direction;
        ball.position_m[1] * c - ball.position_m[0] * s
    }

    /// d' = b_y' cos phi* - b_x' sin phi*, m/s (constant in flight).
    #[inline]
    pub fn lateral_offset_rate_mps(&self, ball: &SpatialBall<R>) -> R {
        let [c, s] = self.target_direction;
        ball.velocity_mps[1] * c - ball.velocity_mps[0] * s
    }

    /// The radial PD term l1 = kappa10 (rho - rho*) + kappa11 rho', rad (eq. 13).
    #[inline]
    pub fn radial_term_rad(&self, ball: &SpatialBall<R>) -> R {
        self.p.kappa10 * (ball.horizontal_radius_m() - self.p.target_radius_m)
            + self.p.kappa11 * ball.radial_rate_mps()
    }

    /// The lateral PD term l2 = kappa20 d + kappa21 d', rad (eq. 13).
    #[inline]
    pub fn lateral_term_rad(&self, ball: &SpatialBall<R>) -> R {
        self.p.kappa20_radpm * self.lateral_offset_m(ball)
            + self.p.kappa21_radspm * self.lateral_offset_rate_mps(ball)
    }

    /// The joint references of eq. 13 and their rates along the ballistic flow:
    /// r1' = phi_b', r2' = -k e_b' - (kappa10 rho' + kappa11 rho''), r3' = kappa20 d', with
    /// rho'' = (rho phi_b')^2 / rho (no horizontal force) and d'' = 0.
    pub fn reference(&self, ball: &SpatialBall<R>) -> JointReference<R> {
        let k = self.gain(ball);
        let rho = ball.horizontal_radius_m();
        let lateral = ball.lateral_velocity_mps();
        let radial_accel = lateral * lateral / rho;
        let half_pi = R::HALF * R::PI;
        JointReference {
            angles_rad: [
                ball.azimuth_rad(),
                -half_pi - k * ball.elevation_rad() - self.radial_term_rad(ball),
                self.lateral_term_rad(ball),
            ],
            rates_radps: [
                ball.azimuth_rate_radps(),
                -k * ball.elevation_rate_radps()
                    - self.p.kappa10 * ball.radial_rate_mps()
                    - self.p.kappa11 * radial_accel,
                self.p.kappa20_radpm * self.lateral_offset_rate_mps(ball),
            ],
        }
    }
}

/// The plane a ball meets the paddle in under [`ModifiedSpatialLaw`], fixed for a flight:
/// through the base, containing the horizontal line across azimuth phi_l, rising at
/// elevation e_l0 over azimuth phi_l. Its normal is
/// n_l = (-sin e_l0 cos phi_l, -sin e_l0 sin phi_l, cos e_l0); in azimuth phi it rises at
/// e_l(phi) = atan(tan e_l0 cos(phi - phi_l)).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct ImpactPlane<R> {
    /// phi_l, rad.
    pub azimuth_rad: R,
    /// e_l0, rad, in (-pi/2, pi/2).
    pub elevation_rad: R,
}

impl<R: Real> ImpactPlane<R> {
    /// e_l(phi) = atan2(sin e_l0 cos(phi - phi_l), cos e_l0), rad: the plane's elevation in
    /// azimuth `azimuth_rad`.
    #[inline]
    pub fn elevation_at(&self, azimuth_rad: R) -> R {
        let delta = azimuth_rad - self.azimuth_rad;
        (self.elevation_rad.sin() * delta.cos()).atan2(self.elevation_rad.cos())
    }

    /// de_l/dphi = -sin e_l0 cos e_l0 sin(phi - phi_l) / (cos^2 e_l0 + sin^2 e_l0 cos^2(phi - phi_l)),
    /// rad per rad of azimuth.
    #[inline]
    pub fn slope_at(&self, azimuth_rad: R) -> R {
        let delta = azimuth_rad - self.azimuth_rad;
        let (s, c) = (self.elevation_rad.sin(), self.elevation_rad.cos());
        let sc = s * delta.cos();
        -s * c * delta.sin() / (c * c + sc * sc)
    }
}

/// The modified spatial law with a solvable flight time, in the manner of eq. 15–16 (the
/// paper says only that one exists, "related to (13)" as eq. 15 is to eq. 12; this is this
/// crate's construction, docs/spatial.md):
///
/// ```text
/// r1 = phi_b
/// r2 = -pi/2 - k e_b + (1 + k) e_l(phi_b)
/// r3 = l2(w_bar)
/// e_l0 = atan2(kappa10 (rho_bar - rho*) + kappa11 rho_bar', rho_bar),   phi_l = phi_bar
/// ```
///
/// with w_bar the apex of the current flight, so k, the [`ImpactPlane`] and r3 are constant
/// in flight. The bar meets the ball (e_r = e_b) iff (1 + k)(e_l(phi_b) - e_b) = 0, i.e. when
/// the ball crosses the impact plane: a linear condition in b, so the flight time solves a
/// quadratic ([`ModifiedSpatialLaw::impact_time_s`]). In the plane through the base
/// (b_y = b_y' = 0) it is [`crate::planar::ModifiedPlanarLaw`] (eq. 15–16).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ModifiedSpatialLaw<R> {
    law: SpatialMirrorLaw<R>,
}

impl<R: Real> ModifiedSpatialLaw<R> {
    /// The law of `p` (kappa10 dimensionless, kappa11 in s: the PD term is a height); an
    /// error names the first parameter out of its range.
    pub fn new(p: SpatialLawParams<R>) -> Result<Self, ParamError> {
        Ok(Self {
            law: SpatialMirrorLaw::new(p)?,
        })
    }

    /// The mirror gain k(w), dimensionless (eq. 5).
    #[inline]
    pub fn gain(&self, ball: &SpatialBall<R>) -> R {
        self.law.gain(ball)
    }

    /// The apex of the ball's current flight and the time to it, `(F^ta(w), t_a)` with
    /// t_a = b_z'/gamma, s (eq. 17; negative once the ball falls: the apex it fell from).
    #[inline]
    pub fn apex_state(&self, ball: &SpatialBall<R>) -> (SpatialBall<R>, R) {
        let g = self.law.p.gravity_mps2;
        let t_a = ball.velocity_mps[2] / g;
        let mut apex = ball.flown(t_a, g);
        apex.velocity_mps[2] = R::ZERO; // exact by definition; removes rounding
        (apex, t_a)
    }

    /// The impact plane of the flight through `apex`.
    #[inline]
    pub fn impact_plane(&self, apex: &SpatialBall<R>) -> ImpactPlane<R> {
        let p = &self.law.p;
        let rho = apex.horizontal_radius_m();
        let height = p.kappa10 * (rho - p.target_radius_m) + p.kappa11 * apex.radial_rate_mps();
        ImpactPlane {
            azimuth_rad: apex.azimuth_rad(),
            elevation_rad: height.atan2(rho),
        }
    }

    /// The joint references and their rates along the flow:
    /// r1' = phi_b', r2' = -k e_b' + (1 + k) e_l'(phi_b) phi_b', r3' = 0.
    pub fn reference(&self, ball: &SpatialBall<R>) -> JointReference<R> {
        let k = self.gain(ball);
        let (apex, _) = self.apex_state(ball);
        let plane = self.impact_plane(&apex);
        let (phi, phi_dot) = (ball.azimuth_rad(), ball.azimuth_rate_radps());
        JointReference {
            angles_rad: [
                phi,
                -R::HALF * R::PI - k * ball.elevation_rad()
                    + (R::ONE + k) * plane.elevation_at(phi),
                self.law.lateral_term_rad(&apex),
            ],
            rates_radps: [
                phi_dot,
                -k * ball.elevation_rate_radps() + (R::ONE + k) * plane.slope_at(phi) * phi_dot,
                R::ZERO,
            ],
        }
    }

    /// Time after the apex, s, at which the ball falling from `apex` crosses `plane` (where
    /// the bar meets it): the smallest root t >= 0 of
    /// `n_l . b(t) = 0`, i.e. `(gamma c/2) t^2 + (s h' - c z') t + (s h - c z) = 0` with
    /// (s, c) = (sin e_l0, cos e_l0) and h = b_x cos phi_l + b_y sin phi_l, at which the ball
    /// descends and is over the plane's own side (h > 0); `None` if there is none.
    pub fn impact_time_s(&self, apex: &SpatialBall<R>, plane: &ImpactPlane<R>) -> Option<R> {
        let (s, c) = (plane.elevation_rad.sin(), plane.elevation_rad.cos());
        let (cp, sp) = (plane.azimuth_rad.cos(), plane.azimuth_rad.sin());
        let along = |v: [R; 3]| v[0] * cp + v[1] * sp;
        let g = self.law.p.gravity_mps2;
        let roots = quadratic_roots(
            R::HALF * g * c,
            s * along(apex.velocity_mps) - c * apex.velocity_mps[2],
            s * along(apex.position_m) - c * apex.position_m[2],
        )?;
        roots.into_iter().find(|&t| {
            let b = apex.flown(t, g);
            t >= R::ZERO
                && t.is_finite()
                && b.velocity_mps[2] <= R::ZERO
                && along(b.position_m) > R::ZERO
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::planar::{ModifiedPlanarLaw, PlanarBall, PlanarMirrorLaw};
    use core::f64::consts::{FRAC_PI_2, PI};

    const G: f64 = 9.81;

    fn frame_at(q: [f64; 3], rates: [f64; 3]) -> PaddleFrame<f64> {
        let e = q[1] + FRAC_PI_2;
        PaddleFrame::from_sin_cos([q[0].sin_cos(), e.sin_cos(), q[2].sin_cos()], rates)
    }

    /// The bar and the normal are unit and perpendicular, and omega x u, omega x n equal
    /// their central differences along the joint motion (independent of omega's formula).
    #[test]
    fn the_paddle_frame_turns_with_its_angular_velocity() {
        let (q, w) = ([0.3, -1.2, 0.25], [0.7, -1.9, 0.4]);
        let f = frame_at(q, w);
        assert!((dot(&f.bar, &f.bar) - 1.0).abs() < 1e-15);
        assert!((dot(&f.normal, &f.normal) - 1.0).abs() < 1e-15);
        assert!(dot(&f.bar, &f.normal).abs() < 1e-15);
        let h = 1e-6;
        let at = |s: f64| frame_at(core::array::from_fn(|i| q[i] + w[i] * s), w);
        let (a, b) = (at(h), at(-h));
        let du = cross(&f.angular_velocity_radps, &f.bar);
        let dn = cross(&f.angular_velocity_radps, &f.normal);
        for i in 0..3 {
            assert!(
                (du[i] - (a.bar[i] - b.bar[i]) / (2.0 * h)).abs() < 1e-8,
                "u {i}"
            );
            assert!(
                (dn[i] - (a.normal[i] - b.normal[i]) / (2.0 * h)).abs() < 1e-8,
                "n {i}"
            );
        }
    }

    /// Level paddle (e = 0, no roll): the normal is up, a ball falling at 2 m/s on a paddle
    /// rising at e' r = 0.5 m/s leaves at 0.5 + alpha 2.5; a receding ball is no impact.
    #[test]
    fn a_bounce_follows_the_restitution_law_along_the_normal() {
        let f = frame_at([0.0, -FRAC_PI_2, 0.0], [0.0, 0.5, 0.0]);
        assert!((f.normal[2] - 1.0).abs() < 1e-15);
        let ball = SpatialBall::new([1.0, 0.0, 0.0], [0.3, 0.0, -2.0]);
        let v = f.bounce(&ball, 0.7).expect("approaching");
        assert!((v[2] - (0.5 + 0.7 * 2.5)).abs() < 1e-12);
        assert_eq!(v[0], 0.3);
        let away = SpatialBall::new([1.0, 0.0, 0.0], [0.0, 0.0, 1.0]);
        assert_eq!(f.bounce(&away, 0.7), None);
        assert_eq!(f.gap_m(&[1.0, 0.0, 0.25]), 0.25);
    }

    /// The host's suggested gains are the core's: kappa0 matched, deadbeat halves.
    #[test]
    fn suggested_gains_by_hand() {
        let p = SpatialLawParams::suggested(false, 0.7, G, 0.5, 1.0, 0.0);
        let v = (2.0f64 * G * 0.5).sqrt();
        assert!((p.kappa0 - 0.3 / 1.7).abs() < 1e-15);
        assert!((p.kappa21_radspm + 0.25 / v).abs() < 1e-15);
        assert!((p.kappa20_radpm + 0.25 / (v * 2.0 * v / G)).abs() < 1e-15);
        assert_eq!((p.kappa10, p.kappa11), (-0.12, -0.08));
        let m = SpatialLawParams::suggested(true, 0.7, G, 0.5, 1.0, 0.0);
        assert_eq!((m.kappa10, m.kappa11), (0.12, 0.08));
    }

    fn params() -> SpatialLawParams<f64> {
        SpatialLawParams {
            kappa0: 0.3,
            kappa1_s2pm2: 0.02,
            target_apex_m: 0.8,
            kappa10: -0.4,
            kappa11: -0.2,
            kappa20_radpm: 0.5,
            kappa21_radspm: 0.15,
            target_radius_m: 0.9,
            target_azimuth_rad: 0.0,
            gravity_mps2: G,
        }
    }

    fn close(a: f64, b: f64, tol: f64) -> bool {
        (a - b).abs() <= tol * (1.0 + b.abs())
    }

    /// Each joint rate of `reference` equals the central difference of its angle along the
    /// exact flight of one ball, at each of `times` (s).
    fn assert_rates_are_derivatives(
        reference: impl Fn(&SpatialBall<f64>) -> JointReference<f64>,
        times: &[f64],
    ) {
        let b = SpatialBall::new([0.7, -0.4, 0.9], [0.35, 0.5, 1.2]);
        let h = 1e-5;
        for &t in times {
            let at = |dt: f64| reference(&b.flown(t + dt, G)).angles_rad;
            let (ahead, behind) = (at(h), at(-h));
            let r = reference(&b.flown(t, G));
            for i in 0..3 {
                let fd = (ahead[i] - behind[i]) / (2.0 * h);
                assert!(close(r.rates_radps[i], fd, 1e-7), "joint {i} at {t}: {fd}");
            }
        }
    }

    #[test]
    fn ball_angles_and_rates_by_hand() {
        // b = (3, 4, 12): rho = 5, |b| = 13; b' = (1, -2, 3)
        let b = SpatialBall::new([3.0f64, 4.0, 12.0], [1.0, -2.0, 3.0]);
        assert_eq!(b.horizontal_radius_m(), 5.0);
        assert_eq!(b.radius_m(), 13.0);
        assert!(close(b.azimuth_rad(), (4.0f64).atan2(3.0), 1e-15));
        assert!(close(b.elevation_rad(), (12.0f64).atan2(5.0), 1e-15));
        // rho' = (3 - 8)/5 = -1; rho phi' = (3 * -2 - 4 * 1)/5 = -2; phi' = -0.4
        assert!(close(b.radial_rate_mps(), -1.0, 1e-15));
        assert!(close(b.lateral_velocity_mps(), -2.0, 1e-15));
        assert!(close(b.azimuth_rate_radps(), -0.4, 1e-15));
        // e' = (5 * 3 - 12 * -1)/169 = 27/169
        assert!(close(b.elevation_rate_radps(), 27.0 / 169.0, 1e-15));
        // eta = (1 + 4 + 9)/2 + 9.81 * 12
        assert!(close(b.energy_jpkg(G), 7.0 + G * 12.0, 1e-15));
    }

    #[test]
    fn reference_by_hand() {
        // kappa1 = 0: k = 0.3. Ball at (1, 0.2, 1), b' = (0.1, -0.3, -1), phi* = 0.
        let law = SpatialMirrorLaw::new(SpatialLawParams {
            kappa1_s2pm2: 0.0,
            ..params()
        })
        .unwrap();
        let b = SpatialBall::new([1.0, 0.2, 1.0], [0.1, -0.3, -1.0]);
        let rho = 1.04f64.sqrt();
        let rho_dot = (0.1 - 0.06) / rho;
        let l1 = -0.4 * (rho - 0.9) - 0.2 * rho_dot;
        let l2 = 0.5 * 0.2 + 0.15 * -0.3; // d = b_y, d' = b_y' at phi* = 0
        let r = law.reference(&b);
        assert!(close(r.angles_rad[0], 0.2f64.atan2(1.0), 1e-15));
        let e_b = 1.0f64.atan2(rho);
        assert!(close(r.angles_rad[1], -FRAC_PI_2 - 0.3 * e_b - l1, 1e-14));
        assert!(close(r.angles_rad[2], l2, 1e-15));
        assert!(close(r.rates_radps[2], 0.5 * -0.3, 1e-15));
    }

    /// In the vertical plane through the base, eq. 13 is eq. 12: the planar law (independent
    /// code) with the radial gains negated, the azimuth and roll at zero.
    #[test]
    fn in_the_plane_through_the_base_it_is_the_planar_law() {
        let p = params();
        let planar = PlanarMirrorLaw::new(
            p.kappa0,
            p.kappa1_s2pm2,
            p.target_apex_m,
            -p.kappa10,
            -p.kappa11,
            p.target_radius_m,
            G,
        )
        .unwrap();
        let law = SpatialMirrorLaw::new(p).unwrap();
        for i in 0..7 {
            for j in 0..7 {
                let (x, z) = (0.3 + 0.2 * i as f64, -0.5 + 0.3 * j as f64);
                let (u, w) = (-0.4 + 0.13 * j as f64, 2.0 - 0.7 * i as f64);
                let s = law.reference(&SpatialBall::new([x, 0.0, z], [u, 0.0, w]));
                let q = planar.reference(&PlanarBall::new(x, z, u, w));
                assert_eq!(s.angles_rad[0], 0.0);
                assert_eq!(s.angles_rad[2], 0.0);
                assert_eq!(s.rates_radps[2], 0.0);
                assert!(close(s.angles_rad[1] + FRAC_PI_2, q.angle_rad, 1e-13));
                assert!(close(s.rates_radps[1], q.rate_radps, 1e-13));
            }
        }
    }

    /// Turning the ball and the set point about z turns the azimuth reference with them and
    /// leaves the shoulder and the roll as they were.
    #[test]
    fn turning_about_the_vertical_turns_only_the_azimuth() {
        let b = SpatialBall::new([0.8, 0.3, 0.6], [0.2, -0.4, -1.5]);
        let base = SpatialMirrorLaw::new(params()).unwrap().reference(&b);
        for a in [0.4f64, 1.7, -2.5] {
            let (c, s) = (a.cos(), a.sin());
            let turn = |[x, y, z]: [f64; 3]| [c * x - s * y, s * x + c * y, z];
            let law = SpatialMirrorLaw::new(SpatialLawParams {
                target_azimuth_rad: a,
                ..params()
            })
            .unwrap();
            let r = law.reference(&SpatialBall::new(turn(b.position_m), turn(b.velocity_mps)));
            let dq1 = (r.angles_rad[0] - base.angles_rad[0] - a).rem_euclid(2.0 * PI);
            assert!(dq1 < 1e-12 || 2.0 * PI - dq1 < 1e-12, "{dq1}");
            for i in 1..3 {
                assert!(close(r.angles_rad[i], base.angles_rad[i], 1e-12));
            }
            for i in 0..3 {
                assert!(close(r.rates_radps[i], base.rates_radps[i], 1e-12));
            }
        }
    }

    /// The rates are the time derivatives of the angles along the exact flight (central
    /// differences, f64).
    #[test]
    fn rates_are_the_derivatives_along_the_flight() {
        let law = SpatialMirrorLaw::new(SpatialLawParams {
            target_azimuth_rad: 0.3,
            ..params()
        })
        .unwrap();
        assert_rates_are_derivatives(|b| law.reference(b), &[0.0, 0.1, 0.25]);
    }

    fn modified() -> ModifiedSpatialLaw<f64> {
        ModifiedSpatialLaw::new(SpatialLawParams {
            kappa10: 0.3,
            kappa11: 0.1,
            target_azimuth_rad: 0.2,
            ..params()
        })
        .unwrap()
    }

    /// In the plane through the base the modified law is the modified planar law (eq. 15–16,
    /// independent code): the same shoulder reference, rate and impact time.
    #[test]
    fn modified_in_the_plane_through_the_base_is_the_modified_planar_law() {
        let p = params();
        let planar = ModifiedPlanarLaw::new(
            p.kappa0,
            p.kappa1_s2pm2,
            p.target_apex_m,
            0.3,
            0.1,
            p.target_radius_m,
            G,
        )
        .unwrap();
        let law = ModifiedSpatialLaw::new(SpatialLawParams {
            kappa10: 0.3,
            kappa11: 0.1,
            ..p
        })
        .unwrap();
        for i in 0..6 {
            for j in 0..6 {
                let (x, z) = (0.4 + 0.15 * i as f64, 0.2 + 0.25 * j as f64);
                let (u, w) = (-0.3 + 0.1 * j as f64, 1.5 - 0.6 * i as f64);
                let ball = SpatialBall::new([x, 0.0, z], [u, 0.0, w]);
                let s = law.reference(&ball);
                let q = planar.reference(&PlanarBall::new(x, z, u, w));
                assert_eq!((s.angles_rad[0], s.rates_radps[0]), (0.0, 0.0));
                assert!(close(s.angles_rad[1] + FRAC_PI_2, q.angle_rad, 1e-13));
                assert!(close(s.rates_radps[1], q.rate_radps, 1e-13));
                let (apex, _) = law.apex_state(&ball);
                let plane = law.impact_plane(&apex);
                let (papex, _) = planar.apex_state(&PlanarBall::new(x, z, u, w));
                let theta_l = planar.target_angle_rad(&papex);
                assert!(close(plane.elevation_rad, theta_l, 1e-13));
                let ts = law.impact_time_s(&apex, &plane);
                let tp = planar.impact_time_s(&papex, theta_l);
                match (ts, tp) {
                    (Some(a), Some(b)) => assert!(close(a, b, 1e-12), "{a} {b}"),
                    (a, b) => assert_eq!(a.is_some(), b.is_some(), "{a:?} {b:?}"),
                }
            }
        }
    }

    /// At the impact time the bar's elevation under the law equals the ball's (the contact
    /// condition, checked through the reference itself), with lateral motion too; just
    /// before it they differ.
    #[test]
    fn modified_impact_time_is_where_the_bar_meets_the_ball() {
        let law = modified();
        let mut found = 0;
        for (y, v) in [(0.0, 0.0), (0.3, -0.2), (-0.25, 0.4), (0.1, 0.6)] {
            let ball = SpatialBall::new([0.9, y, 0.4], [0.15, v, 2.0]);
            let (apex, t_a) = law.apex_state(&ball);
            let plane = law.impact_plane(&apex);
            let t = law.impact_time_s(&apex, &plane).expect("an impact");
            let gap = |t: f64| {
                let b = apex.flown(t, G);
                law.reference(&b).angles_rad[1] + FRAC_PI_2 - b.elevation_rad()
            };
            assert!(gap(t).abs() < 1e-12, "gap {}", gap(t));
            assert!(gap(t - 0.01).abs() > 1e-4);
            assert!(t_a > 0.0);
            found += 1;
        }
        assert_eq!(found, 4);
    }

    /// With no radial terms the impact plane is the horizontal through the base, whatever
    /// the lateral velocity: the ball falls z_bar in sqrt(2 z_bar/gamma).
    #[test]
    fn modified_impact_time_by_hand() {
        let law = ModifiedSpatialLaw::new(SpatialLawParams {
            kappa10: 0.0,
            kappa11: 0.0,
            ..params()
        })
        .unwrap();
        let apex = SpatialBall::new([1.0, 0.2, 1.0], [0.1, 0.5, 0.0]);
        let plane = law.impact_plane(&apex);
        assert_eq!(plane.elevation_rad, 0.0);
        let t = law.impact_time_s(&apex, &plane).unwrap();
        assert!(close(t, (2.0 / G).sqrt(), 1e-14));
    }

    /// Turning the ball and the set point about z turns the modified law's azimuth and impact
    /// plane with them and leaves the shoulder, the roll and the impact time as they were.
    #[test]
    fn modified_law_turns_with_the_vertical() {
        let b = SpatialBall::new([0.8, 0.3, 0.6], [0.2, -0.4, 1.5]);
        let base_law = modified();
        let base = base_law.reference(&b);
        let (apex, _) = base_law.apex_state(&b);
        let base_t = base_law
            .impact_time_s(&apex, &base_law.impact_plane(&apex))
            .unwrap();
        for a in [0.4f64, 1.7, -2.5] {
            let (c, s) = (a.cos(), a.sin());
            let turn = |[x, y, z]: [f64; 3]| [c * x - s * y, s * x + c * y, z];
            let law = ModifiedSpatialLaw::new(SpatialLawParams {
                target_azimuth_rad: 0.2 + a,
                ..*base_law.law.params()
            })
            .unwrap();
            let turned = SpatialBall::new(turn(b.position_m), turn(b.velocity_mps));
            let r = law.reference(&turned);
            for i in 1..3 {
                assert!(close(r.angles_rad[i], base.angles_rad[i], 1e-12));
                assert!(close(r.rates_radps[i], base.rates_radps[i], 1e-12));
            }
            let (apex, _) = law.apex_state(&turned);
            let t = law.impact_time_s(&apex, &law.impact_plane(&apex)).unwrap();
            assert!(close(t, base_t, 1e-12), "{t} {base_t}");
        }
    }

    #[test]
    fn modified_rates_are_the_derivatives_along_the_flight() {
        let law = modified();
        assert_rates_are_derivatives(|b| law.reference(b), &[0.0, 0.1, 0.3]);
    }

    #[test]
    fn parameters_out_of_range_are_named() {
        let cases: [(SpatialLawParams<f64>, &str); 5] = [
            (
                SpatialLawParams {
                    kappa0: -0.1,
                    ..params()
                },
                "kappa0",
            ),
            (
                SpatialLawParams {
                    kappa21_radspm: f64::NAN,
                    ..params()
                },
                "kappa21",
            ),
            (
                SpatialLawParams {
                    target_radius_m: 0.0,
                    ..params()
                },
                "target_radius_m",
            ),
            (
                SpatialLawParams {
                    target_azimuth_rad: f64::INFINITY,
                    ..params()
                },
                "target_azimuth_rad",
            ),
            (
                SpatialLawParams {
                    gravity_mps2: -9.81,
                    ..params()
                },
                "gravity_mps2",
            ),
        ];
        for (p, name) in cases {
            let e = SpatialMirrorLaw::new(p).unwrap_err().to_string();
            assert!(e.starts_with(&format!("{name} ")), "{e}");
        }
    }

    #[test]
    fn runs_in_f32() {
        let p = params();
        let law32 = SpatialMirrorLaw::new(SpatialLawParams {
            kappa0: p.kappa0 as f32,
            kappa1_s2pm2: p.kappa1_s2pm2 as f32,
            target_apex_m: p.target_apex_m as f32,
            kappa10: p.kappa10 as f32,
            kappa11: p.kappa11 as f32,
            kappa20_radpm: p.kappa20_radpm as f32,
            kappa21_radspm: p.kappa21_radspm as f32,
            target_radius_m: p.target_radius_m as f32,
            target_azimuth_rad: 0.0,
            gravity_mps2: G as f32,
        })
        .unwrap();
        let r32 = law32.reference(&SpatialBall::new([0.8f32, 0.3, 0.6], [0.2, -0.4, -1.5]));
        let r64 = SpatialMirrorLaw::new(p)
            .unwrap()
            .reference(&SpatialBall::new([0.8, 0.3, 0.6], [0.2, -0.4, -1.5]));
        for i in 0..3 {
            assert!((f64::from(r32.angles_rad[i]) - r64.angles_rad[i]).abs() < 1e-5);
        }
    }
}
