//! What the table must do at a predicted impact (kappa-tilt, eq. 25, the table's geometry),
//! and the cubic each axis follows to get there.
//!
//! # The table
//!
//! A line at angle alpha through a pivot at height h; the pivot is carried horizontally under
//! the body's centre of mass (an ideal x stage, so the paper's infinite table needs no
//! horizontal travel; only the tilt and the vertical stroke are actuated, each with limits).
//! At the impact the line passes through the contact point (x + l sin theta, y_imp), so
//!
//! ```text
//! h* = y_imp - tan(alpha) l sin(theta)
//! ```
//!
//! and the table surface at the contact moves along its normal n = (-sin alpha, cos alpha)
//! with `cos(alpha) h' - sin(alpha) x' + alpha' s` (pivot velocity (x', h'), s the distance
//! from the pivot along the table). The plan arrives with alpha' = 0, so eq. 25's table
//! velocity v_T = -[(1-e)/(1+e) + kappa_E (eta* - eta)] v_c is met along the normal, the only
//! component a frictionless impact (eq. 21) sees, by
//!
//! ```text
//! h'* = (n . v_T + sin(alpha) x') / cos(alpha)
//! ```
//!
//! with alpha = kappa theta (sec. 2.1; plus kappa_w theta' if that option is on, see
//! [`super::TiltParams::kappa_rate_s`], and the horizontal regulation - kappa_x x - kappa_x' x',
//! see [`super::TiltParams::kappa_x_pm`]), eta = G l cos theta + y'^2/2 and v_c the contact
//! point's velocity (eq. 23), all at the predicted impact. Targets outside an axis's travel
//! or speed are clamped and reported (`clamped`).
//!
//! # Each axis between impacts
//!
//! The cubic (Hermite) p(t) from the reference's position and velocity now to the target
//! position and velocity at the predicted time tau; re-solved at every plan (one pipeline
//! cycle of the controller) while the impact is further than the commit time, then
//! frozen. Its acceleration is linear in t, so
//! its largest magnitude is at an end; its velocity is a quadratic (extreme at the vertex)
//! and its position a cubic (extremes where the velocity is zero, closed form):
//! [`Cubic::within`] checks all three against the axis's limits in constant work. The
//! target is computed in two halves ([`table_angle`], [`table_motion`]) and the check in two
//! ([`Cubic::within_dynamics`], [`Cubic::within_travel`]) so that the controller can spread
//! them over control periods.

use super::sincos::SinCos;
use crate::math::Real;

/// Limits of one table axis in its own unit u (rad for the tilt, m for the stroke).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AxisLimits {
    /// Lowest position, u.
    pub min: f32,
    /// Highest position, u.
    pub max: f32,
    /// Largest speed, u/s.
    pub velocity_max: f32,
    /// Largest acceleration, u/s^2.
    pub accel_max: f32,
}

/// The laws' constants, f32, validated by the controller.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LawConstants {
    /// kappa of alpha = kappa theta.
    pub kappa: f32,
    /// kappa_w of the tilt-rate term alpha = kappa theta + kappa_w theta', s (0: the
    /// paper's law; see [`super::TiltParams::kappa_rate_s`]).
    pub kappa_rate_s: f32,
    /// kappa_x of the horizontal regulation term alpha -= kappa_x x, rad/m (0: the
    /// paper's law; see [`super::TiltParams::kappa_x_pm`]).
    pub kappa_x_pm: f32,
    /// kappa_x' of the same term on x', alpha -= kappa_x' x', s/m (0: the paper's law;
    /// see [`super::TiltParams::kappa_xdot_spm`]).
    pub kappa_xdot_spm: f32,
    /// kappa_E of eq. 25, s^2/m^2.
    pub kappa_e_s2pm2: f32,
    /// eta*, J/kg.
    pub target_energy_jpkg: f32,
    /// (1-e)/(1+e).
    pub compensation: f32,
    /// G, m/s^2.
    pub gravity_mps2: f32,
    /// l, m.
    pub l_m: f32,
    /// y_imp: height of the contact point at every planned impact, m.
    pub impact_height_m: f32,
}

/// The body at the predicted impact.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct BodyAtImpact {
    /// theta, rad.
    pub theta_rad: f32,
    /// x of the centre of mass, m (in the table's frame: 0 is the middle of its x stage).
    pub x_m: f32,
    /// sin theta.
    pub sin_theta: f32,
    /// cos theta.
    pub cos_theta: f32,
    /// x', m/s.
    pub x_dot_mps: f32,
    /// y', m/s.
    pub y_dot_mps: f32,
    /// theta', rad/s.
    pub theta_dot_radps: f32,
}

/// The table's pose and velocity at the predicted impact.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct ImpactTarget {
    /// Table angle alpha, rad (kappa theta, clamped into the tilt travel).
    pub alpha_rad: f32,
    /// sin alpha.
    pub sin_alpha: f32,
    /// cos alpha.
    pub cos_alpha: f32,
    /// Pivot height h*, m.
    pub height_m: f32,
    /// Pivot vertical velocity h'*, m/s.
    pub velocity_mps: f32,
    /// Table surface velocity along its normal at the contact, m/s (eq. 25's n . v_T unless
    /// clamped).
    pub normal_velocity_mps: f32,
    /// eta = G l cos theta + y'^2/2 at the impact, J/kg (eq. 25).
    pub energy_jpkg: f32,
    /// A target was outside its axis's travel or speed and was clamped.
    pub clamped: bool,
}

/// The first half of [`impact_target`]: eq. 25's gain and contact velocity, and the table
/// angle (kappa-tilt, clamped into the tilt travel) with its sine and cosine.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct TableAngle {
    /// alpha = kappa theta as the law asks, rad.
    pub alpha_law_rad: f32,
    /// alpha clamped into the tilt travel, rad.
    pub alpha_rad: f32,
    /// sin alpha.
    pub sin_alpha: f32,
    /// cos alpha.
    pub cos_alpha: f32,
    /// The bracket of eq. 25, (1-e)/(1+e) + kappa_E (eta* - eta).
    pub gain: f32,
    /// Contact-point velocity v_c (eq. 23), m/s.
    pub contact_velocity_mps: [f32; 2],
    /// eta at the impact, J/kg.
    pub energy_jpkg: f32,
}

/// eq. 25's gain and v_c, and alpha = kappa theta + kappa_w theta' clamped into `tilt`; one
/// sine/cosine pair.
pub fn table_angle<T: SinCos>(
    law: &LawConstants,
    tilt: &AxisLimits,
    b: &BodyAtImpact,
) -> TableAngle {
    let l = law.l_m;
    let energy = law.gravity_mps2 * l * b.cos_theta + 0.5 * b.y_dot_mps * b.y_dot_mps;
    let gain = law.compensation + law.kappa_e_s2pm2 * (law.target_energy_jpkg - energy);
    let w = l * b.theta_dot_radps;
    let alpha_law = law.kappa * b.theta_rad + law.kappa_rate_s * b.theta_dot_radps
        - law.kappa_x_pm * b.x_m
        - law.kappa_xdot_spm * b.x_dot_mps;
    let alpha = alpha_law.clamp_r(tilt.min, tilt.max);
    let (sa, ca) = T::sin_cos(alpha);
    TableAngle {
        alpha_law_rad: alpha_law,
        alpha_rad: alpha,
        sin_alpha: sa,
        cos_alpha: ca,
        gain,
        contact_velocity_mps: [b.x_dot_mps + w * b.cos_theta, b.y_dot_mps + w * b.sin_theta],
        energy_jpkg: energy,
    }
}

/// The second half of [`impact_target`]: the normal velocity of eq. 25 and the pivot's
/// height and velocity through the table's geometry, clamped into `stroke`; one division.
pub fn table_motion(
    law: &LawConstants,
    stroke: &AxisLimits,
    b: &BodyAtImpact,
    a: &TableAngle,
) -> ImpactTarget {
    let (sa, ca) = (a.sin_alpha, a.cos_alpha);
    let [vcx, vcy] = a.contact_velocity_mps;
    let vn_law = -a.gain * (-sa * vcx + ca * vcy);
    let inv_ca = 1.0 / ca;
    let h_law = law.impact_height_m - sa * inv_ca * law.l_m * b.sin_theta;
    let hd_law = (vn_law + sa * b.x_dot_mps) * inv_ca;
    let h = h_law.clamp_r(stroke.min, stroke.max);
    let hd = hd_law.clamp_r(-stroke.velocity_max, stroke.velocity_max);
    let clamped = a.alpha_rad != a.alpha_law_rad || h != h_law || hd != hd_law;
    let vn = if hd == hd_law {
        vn_law
    } else {
        ca * hd - sa * b.x_dot_mps
    };
    ImpactTarget {
        alpha_rad: a.alpha_rad,
        sin_alpha: sa,
        cos_alpha: ca,
        height_m: h,
        velocity_mps: hd,
        normal_velocity_mps: vn,
        energy_jpkg: a.energy_jpkg,
        clamped,
    }
}

/// The table's target at an impact (module docs): [`table_angle`] then [`table_motion`].
pub fn impact_target<T: SinCos>(
    law: &LawConstants,
    tilt: &AxisLimits,
    stroke: &AxisLimits,
    b: &BodyAtImpact,
) -> ImpactTarget {
    table_motion(law, stroke, b, &table_angle::<T>(law, tilt, b))
}

/// p(t) = c0 + c1 t + c2 t^2 + c3 t^3, one axis's reference between impacts.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Cubic {
    /// Position at t = 0, u.
    pub c0: f32,
    /// Velocity at t = 0, u/s.
    pub c1: f32,
    /// Half the acceleration at t = 0, u/s^2.
    pub c2: f32,
    /// u/s^3.
    pub c3: f32,
}

impl Cubic {
    /// The cubic from (p0, v0) at t = 0 to (p1, v1) at t = tau, given `inv_tau` = 1/tau.
    #[inline]
    pub fn hermite(p0: f32, v0: f32, p1: f32, v1: f32, inv_tau: f32) -> Self {
        let slope = (p1 - p0) * inv_tau;
        Self {
            c0: p0,
            c1: v0,
            c2: (3.0 * slope - 2.0 * v0 - v1) * inv_tau,
            c3: (v0 + v1 - 2.0 * slope) * inv_tau * inv_tau,
        }
    }

    /// p(t), u.
    #[inline]
    pub fn position(&self, t: f32) -> f32 {
        self.c0 + t * (self.c1 + t * (self.c2 + t * self.c3))
    }

    /// p'(t), u/s.
    #[inline]
    pub fn velocity(&self, t: f32) -> f32 {
        self.c1 + t * (2.0 * self.c2 + 3.0 * self.c3 * t)
    }

    /// The acceleration that, held over [t, t + dt], changes the velocity exactly as the
    /// cubic does: p''(t + dt/2), u/s^2.
    #[inline]
    pub fn mean_accel(&self, t: f32, dt: f32) -> f32 {
        2.0 * self.c2 + 6.0 * self.c3 * (t + 0.5 * dt)
    }

    /// Whether position, velocity and acceleration stay within `lim` on [0, tau]:
    /// [`Cubic::within_dynamics`] and [`Cubic::within_travel`].
    pub fn within(&self, tau: f32, lim: &AxisLimits) -> bool {
        self.within_dynamics(tau, lim) && self.within_travel(tau, lim)
    }

    /// Acceleration (linear: extremes at the ends) and velocity (a quadratic: ends and
    /// vertex) within `lim` on [0, tau]; one division.
    pub fn within_dynamics(&self, tau: f32, lim: &AxisLimits) -> bool {
        let (a0, a1) = (2.0 * self.c2, 2.0 * self.c2 + 6.0 * self.c3 * tau);
        let mut ok = a0.abs() <= lim.accel_max && a1.abs() <= lim.accel_max;
        ok &= self.c1.abs() <= lim.velocity_max && self.velocity(tau).abs() <= lim.velocity_max;
        // vertex of v(t) = c1 + 2 c2 t + 3 c3 t^2; c3 = 0 gives inf or NaN, never inside
        let tv = -self.c2 / (3.0 * self.c3);
        if tv > 0.0 && tv < tau {
            ok &= self.velocity(tv).abs() <= lim.velocity_max;
        }
        ok
    }

    /// Position within the travel of `lim` on [0, tau]: the ends and where v(t) = 0
    /// (closed form, one `sqrt`, two divisions).
    pub fn within_travel(&self, tau: f32, lim: &AxisLimits) -> bool {
        let in_travel = |p: f32| p >= lim.min && p <= lim.max;
        let mut ok = in_travel(self.c0) && in_travel(self.position(tau));
        let (qa, qb, qc) = (3.0 * self.c3, 2.0 * self.c2, self.c1);
        let disc = qb * qb - 4.0 * qa * qc;
        if disc >= 0.0 {
            // stable roots q/A and C/q; a division by zero gives inf or NaN, which no
            // comparison below accepts (A = 0 leaves the linear root C/q = -C/B)
            let sq = Real::sqrt(disc);
            let q = -0.5 * (qb + if qb >= 0.0 { sq } else { -sq });
            for t in [q / qa, qc / q] {
                if t > 0.0 && t < tau {
                    ok &= in_travel(self.position(t));
                }
            }
        }
        ok
    }
}

#[cfg(test)]
mod tests {
    use super::super::sincos::PolySinCos;
    use super::*;

    /// kappa = 1.1 with the eq. 25 feedback (kappa_e = 0.165) towards a quarter metre of
    /// apex, on a 0.133 m body.
    fn law() -> LawConstants {
        LawConstants {
            kappa: 1.1,
            kappa_rate_s: 0.0,
            kappa_x_pm: 0.0,
            kappa_xdot_spm: 0.0,
            kappa_e_s2pm2: 0.165,
            target_energy_jpkg: 9.81 * 0.25,
            compensation: 1.0 / 3.0,
            gravity_mps2: 9.81,
            l_m: 0.133_33,
            impact_height_m: 0.0,
        }
    }

    /// A tilt drive of +-0.7 rad, 8 rad/s, 300 rad/s^2.
    fn tilt() -> AxisLimits {
        AxisLimits {
            min: -0.7,
            max: 0.7,
            velocity_max: 8.0,
            accel_max: 300.0,
        }
    }

    fn lim() -> AxisLimits {
        AxisLimits {
            min: -0.1,
            max: 0.1,
            velocity_max: 2.0,
            accel_max: 60.0,
        }
    }

    #[test]
    fn cubic_arrives_at_the_target_position_and_velocity() {
        let (p0, v0, p1, v1, tau) = (0.02f32, 0.5, -0.01, 0.7, 0.28);
        let c = Cubic::hermite(p0, v0, p1, v1, 1.0 / tau);
        assert!((c.position(0.0) - p0).abs() < 1e-7 && (c.velocity(0.0) - v0).abs() < 1e-7);
        assert!((c.position(tau) - p1).abs() < 1e-6, "{}", c.position(tau));
        assert!((c.velocity(tau) - v1).abs() < 1e-5, "{}", c.velocity(tau));
        // held mean accelerations over 2 ms steps reproduce the velocity at each step
        let dt = 0.002f32;
        let (mut p, mut v) = (p0, v0);
        for k in 0..140 {
            let t = k as f32 * dt;
            let a = c.mean_accel(t, dt);
            p += v * dt + 0.5 * a * dt * dt;
            v += a * dt;
        }
        // per period the held acceleration moves the position by j dt^3/12 more than the
        // cubic (j = 6 c3 its jerk): over tau, j dt^2 tau / 12 more
        let drift = 6.0 * c.c3 * dt * dt * tau / 12.0;
        assert!((v - v1).abs() < 1e-4, "{v}");
        assert!((p - (p1 + drift)).abs() < 1e-6, "{p} vs {}", p1 + drift);
    }

    #[test]
    fn within_checks_every_limit_against_a_dense_scan() {
        // independent check: sample the cubic densely
        let scan = |c: &Cubic, tau: f32, l: &AxisLimits| {
            (0..=2000).all(|i| {
                let t = tau * i as f32 / 2000.0;
                let a = 2.0 * c.c2 + 6.0 * c.c3 * t;
                let p = c.position(t);
                a.abs() <= l.accel_max
                    && c.velocity(t).abs() <= l.velocity_max
                    && p >= l.min - 1e-7
                    && p <= l.max + 1e-7
            })
        };
        let l = lim();
        let mut agree = 0;
        for i in 0..20 {
            for j in 0..20 {
                for k in 0..6 {
                    let (v0, v1) = (-1.5 + 0.16 * i as f32, -1.5 + 0.16 * j as f32);
                    let tau = 0.05 + 0.06 * k as f32;
                    let c = Cubic::hermite(0.0, v0, 0.03, v1, 1.0 / tau);
                    let fast = c.within(tau, &l);
                    let slow = scan(&c, tau, &l);
                    // the dense scan can only miss a violation between its points
                    assert!(
                        !fast || slow,
                        "within accepted a violating cubic {c:?} tau {tau}"
                    );
                    agree += usize::from(fast == slow);
                }
            }
        }
        assert!(agree >= 2390, "{agree} of 2400 agree");
    }

    #[test]
    fn targets_follow_kappa_tilt_and_eq25_through_the_tables_geometry() {
        let (law, tilt) = (law(), tilt());
        let th = 0.25f64;
        let b = BodyAtImpact {
            theta_rad: th as f32,
            x_m: 0.0,
            sin_theta: (th as f32).sin(),
            cos_theta: (th as f32).cos(),
            x_dot_mps: 0.6,
            y_dot_mps: -1.5,
            theta_dot_radps: 1.1,
        };
        let t = impact_target::<PolySinCos>(&law, &tilt, &lim(), &b);
        assert!(!t.clamped);
        // independent f64 computation with the core's eq. 25 (v_T) and the normal
        let st = crate::tilt::BodyState::new(th, 0.6, -1.5, 1.1);
        let fb =
            crate::tilt::EnergyFeedback::new(0.5f64, 0.165, 9.81 * 0.25, 9.81, 0.133_33).unwrap();
        let vt = fb.table_velocity(&st);
        let alpha = 1.1 * th;
        let vn = -alpha.sin() * vt[0] + alpha.cos() * vt[1];
        assert!((f64::from(t.alpha_rad) - alpha).abs() < 1e-6);
        assert!((f64::from(t.normal_velocity_mps) - vn).abs() < 1e-5);
        assert!((f64::from(t.energy_jpkg) - fb.energy_jpkg(&st)).abs() < 1e-5);
        // the pivot moving with (x', h') has that normal velocity
        let hd = f64::from(t.velocity_mps);
        assert!((alpha.cos() * hd - alpha.sin() * 0.6 - vn).abs() < 1e-5);
        // the line at alpha through the pivot (x, h) passes through the contact point
        // (x + l sin th, 0)
        let h = f64::from(t.height_m);
        assert!((h + alpha.tan() * 0.133_33 * th.sin()).abs() < 1e-6);
        // beyond the tilt travel: clamped and said so
        let far = BodyAtImpact {
            theta_rad: 0.9,
            ..b
        };
        let t = impact_target::<PolySinCos>(&law, &tilt, &lim(), &far);
        assert!(t.clamped && t.alpha_rad == 0.7);
    }
    #[test]
    fn a_stroke_at_its_speed_limit_gives_the_normal_velocity_of_the_clamped_pivot() {
        let (law, tilt) = (law(), tilt());
        // a slow stroke (0.2 m/s) against a fast fall: eq. 25 asks for more
        let stroke = AxisLimits {
            velocity_max: 0.2,
            ..lim()
        };
        let th = 0.25f32;
        let b = BodyAtImpact {
            theta_rad: th,
            x_m: 0.0,
            sin_theta: th.sin(),
            cos_theta: th.cos(),
            x_dot_mps: 0.6,
            y_dot_mps: -3.0,
            theta_dot_radps: 1.1,
        };
        let free = impact_target::<PolySinCos>(&law, &tilt, &lim(), &b);
        assert!(!free.clamped && free.velocity_mps.abs() > 0.2);
        let t = impact_target::<PolySinCos>(&law, &tilt, &stroke, &b);
        assert!(t.clamped, "a stroke at its speed limit is a clamped target");
        assert_eq!(t.velocity_mps.abs(), 0.2);
        assert_eq!(t.velocity_mps.signum(), free.velocity_mps.signum());
        // the surface's normal n = (-sin a, cos a) against the pivot's velocity (x', h')
        let a = f64::from(t.alpha_rad);
        let vn = -a.sin() * 0.6 + a.cos() * f64::from(t.velocity_mps);
        assert!((f64::from(t.normal_velocity_mps) - vn).abs() < 1e-6);
        assert!(
            (f64::from(t.normal_velocity_mps) - f64::from(free.normal_velocity_mps)).abs() > 0.05
        );
    }
}
