//! The planar juggler (Rizzi & Koditschek 1994, sec. 3.1.1 and 4): a ball on an inclined
//! plane (eq. 10) batted by a bar on a revolute joint at the origin (eq. 11), the bar
//! tracking the core's mirror law ([`PlanarMirrorLaw`], eq. 12 with the restored minus sign)
//! or the modified law ([`ModifiedPlanarLaw`], eq. 15) perfectly.
//!
//! # Impacts
//!
//! The bar meets the ball where its reference equals the ball's angle, r = theta_b:
//!
//! - **eq. 12**: `r = -k theta_b + l(w)` with k constant in flight and l linear in t, so
//!   contact is theta_b = psi(t) = l(w(t))/(1 + k), a transcendental equation (eq. 14). With
//!   `B = b_x + i b_z` the gap `G = Im(e^{-i psi} B) = |b| sin(theta_b - psi)` has the sign of
//!   theta_b - psi and `G'' = Im(e^{-i psi} (B'' - 2 i psi' B' - psi'^2 B))`, so
//!   `|G''| <= gamma + 2 |psi'| |B'| + psi'^2 |B|`, bounded over the search window; the root is
//!   found by [`super::contact::first_root`] (bracket, then refine, capped).
//! - **eq. 15**: the ball meets the bar on the ray at theta_l fixed by the flight's apex, a
//!   quadratic in t solved in closed form by [`ModifiedPlanarLaw::impact_time_s`] (eq. 16).
//!
//! Both searches start at the flight's apex (the laws meet the ball on its way down; the
//! references jump at an impact, when k and l change, and a real bar lags that jump).
//! The bar is much heavier than the ball and frictionless: with bar normal
//! n = (-sin r, cos r) and the bar's velocity at the ball `r' (-b_z, b_x)` (r' from the law's
//! reference, perfect tracking), `b'+ = b' - (1 + alpha) (n . (b' - v_bar)) n` (restitution
//! alpha, as eq. 4).
//!
//! # Gains that converge
//!
//! Near a horizontal bar the normal velocity maps as the line juggler's,
//! `v+ = (alpha + (1 + alpha) k) v`, so kappa0 = (1 - alpha)/(1 + alpha) keeps the energy and
//! kappa1 > 0 regulates it (slope 1 - (1 + alpha) kappa1 v*^2 at the fixed point). A bar tilted
//! by a small angle psi adds `-2 v psi` to b_x', so the PD terms act on a double integrator
//! sampled at the flight time; [`JugglerParams::default`] picks gains at about half the
//! deadbeat values (see `docs/planar.md`).

use super::contact::{first_root, ContactError};
use dexter_core::params::{positive, within, ParamError};
use dexter_core::planar::{ModifiedPlanarLaw, PlanarBall, PlanarMirrorLaw};
use serde::Serialize;

/// Most impacts of one juggler run.
pub const MAX_JUGGLES: usize = 100_000;

/// Which law the bar tracks.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum JugglerLaw {
    /// eq. 12 (impact time transcendental, eq. 14).
    Mirror(PlanarMirrorLaw<f64>),
    /// eq. 15 (impact time in closed form, eq. 16).
    Modified(ModifiedPlanarLaw<f64>),
}

/// Gains and set points of a planar juggler (both laws take the same numbers; the PD gains
/// are rad/m and rad s/m for eq. 12, m/m and s for eq. 15).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct JugglerParams {
    /// Ball-bar restitution alpha, in (0, 1].
    pub restitution: f64,
    /// In-plane gravity gamma, m/s^2 (> 0).
    pub gravity_mps2: f64,
    /// kappa0 (dimensionless, >= 0).
    pub kappa0: f64,
    /// kappa1, s^2/m^2 (>= 0).
    pub kappa1_s2pm2: f64,
    /// Target apex height b_z, m (> 0).
    pub target_apex_m: f64,
    /// kappa10: rad/m (eq. 12) or m/m (eq. 15).
    pub kappa10: f64,
    /// kappa11: rad s/m (eq. 12) or s (eq. 15).
    pub kappa11: f64,
    /// Horizontal set point b_x*, m (> 0).
    pub target_x_m: f64,
}

impl Default for JugglerParams {
    /// alpha = 0.7, gamma = 9.81, apex 0.5 m at b_x* = 1 m; kappa0 = (1 - alpha)/(1 + alpha);
    /// kappa1 = 0.5/((1 + alpha) v*^2) with v*^2 = 2 gamma h*; PD gains about half deadbeat.
    fn default() -> Self {
        let alpha = 0.7;
        let g = 9.81;
        let h = 0.5;
        let v2 = 2.0 * g * h;
        Self {
            restitution: alpha,
            gravity_mps2: g,
            kappa0: (1.0 - alpha) / (1.0 + alpha),
            kappa1_s2pm2: 0.5 / ((1.0 + alpha) * v2),
            target_apex_m: h,
            kappa10: 0.12,
            kappa11: 0.08,
            target_x_m: 1.0,
        }
    }
}

impl JugglerParams {
    /// A juggler tracking eq. 12.
    pub fn mirror(&self) -> Result<PlanarJuggler, ParamError> {
        let law = PlanarMirrorLaw::new(
            self.kappa0,
            self.kappa1_s2pm2,
            self.target_apex_m,
            self.kappa10,
            self.kappa11,
            self.target_x_m,
            self.gravity_mps2,
        )?;
        PlanarJuggler::new(JugglerLaw::Mirror(law), self.restitution, self.gravity_mps2)
    }

    /// A juggler tracking eq. 15.
    pub fn modified(&self) -> Result<PlanarJuggler, ParamError> {
        let law = ModifiedPlanarLaw::new(
            self.kappa0,
            self.kappa1_s2pm2,
            self.target_apex_m,
            self.kappa10,
            self.kappa11,
            self.target_x_m,
            self.gravity_mps2,
        )?;
        PlanarJuggler::new(
            JugglerLaw::Modified(law),
            self.restitution,
            self.gravity_mps2,
        )
    }
}

/// A ball, a bar, a law.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PlanarJuggler {
    law: JugglerLaw,
    restitution: f64,
    gravity_mps2: f64,
}

/// One bat.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Bat {
    /// Impact index.
    pub index: usize,
    /// Time since the start, s.
    pub time_s: f64,
    /// Ball just before: (b_x, b_z, b_x', b_z'), m, m/s.
    pub before: [f64; 4],
    /// Ball just after.
    pub after: [f64; 4],
    /// Bar angle r = theta_b at the impact, rad.
    pub bar_angle_rad: f64,
    /// Bar rate r', rad/s.
    pub bar_rate_radps: f64,
    /// Apex of the following flight (b_x, b_z), m.
    pub apex: [f64; 2],
    /// Ball energy after the impact, eta = |b'|^2/2 + gamma b_z, J/kg.
    pub energy_jpkg: f64,
}

/// Why a juggler run ended.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum JuggleEnd {
    /// All impacts done.
    Completed,
    /// No contact within the search window (ball missed the bar).
    NoContact,
    /// The contact search hit one of its iteration caps (an internal limit, not the
    /// physics: the run is reported as cut short).
    SearchCap,
    /// The ball was not approaching the bar at the contact, or 1 + k <= 0.
    BadContact,
    /// The ball left the right half plane b_x > 0 the laws assume.
    LeftHalfPlane,
    /// A value became non-finite.
    NonFinite,
}

/// A juggler run.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct JuggleRun {
    /// One record per bat.
    pub bats: Vec<Bat>,
    /// Why it ended.
    pub end: JuggleEnd,
}

fn arr(b: &PlanarBall<f64>) -> [f64; 4] {
    [b.x_m, b.z_m, b.x_dot_mps, b.z_dot_mps]
}

impl PlanarJuggler {
    /// A juggler: `restitution` alpha in (0, 1], `gravity_mps2` gamma > 0 (the law's own).
    pub fn new(law: JugglerLaw, restitution: f64, gravity_mps2: f64) -> Result<Self, ParamError> {
        let restitution = positive("restitution", within("restitution", restitution, 0.0, 1.0)?)?;
        Ok(Self {
            law,
            restitution,
            gravity_mps2: positive("gravity_mps2", gravity_mps2)?,
        })
    }

    /// The next contact of `ball` (in flight) with the bar: time from now, s.
    pub fn next_contact_s(&self, ball: &PlanarBall<f64>) -> Result<f64, JuggleEnd> {
        let g = self.gravity_mps2;
        let t_a = (ball.z_dot_mps / g).max(0.0);
        let apex = ball.flown(t_a, g);
        match &self.law {
            JugglerLaw::Modified(law) => {
                let (top, _) = law.apex_state(&apex);
                let theta_l = law.target_angle_rad(&top);
                law.impact_time_s(&top, theta_l)
                    .map(|t| t_a + t)
                    .ok_or(JuggleEnd::NoContact)
            }
            JugglerLaw::Mirror(law) => {
                let k = law.gain(ball);
                if k.is_nan() || 1.0 + k <= 0.0 {
                    return Err(JuggleEnd::BadContact);
                }
                let psi = |b: &PlanarBall<f64>| law.offset_rad(b) / (1.0 + k);
                // psi is affine in t: its rate from two exact points one second apart
                let psi_rate = psi(&apex.flown(1.0, g)) - psi(&apex);
                let gap = |t: f64| {
                    let b = apex.flown(t, g);
                    let p = psi(&b);
                    let (s, c) = p.sin_cos();
                    let value = b.z_m * c - b.x_m * s;
                    let rate =
                        (b.z_dot_mps * c - b.x_dot_mps * s) - psi_rate * (b.x_m * c + b.z_m * s);
                    (value, rate)
                };
                // search window: until the ball has fallen |b| + 1 m below the apex
                let radius = apex.radius_m() + 1.0;
                let window = (2.0 * (apex.z_m.abs() + radius) / g).sqrt() * 2.0;
                let b_end = apex.x_dot_mps.abs() + g * window;
                let r_end = radius + apex.x_dot_mps.abs() * window + 0.5 * g * window * window;
                let a = g + 2.0 * psi_rate.abs() * b_end + psi_rate * psi_rate * r_end;
                let tol = 64.0 * f64::EPSILON * r_end;
                match first_root(gap, a, 0.0, window, tol) {
                    Ok(Some(c)) => Ok(t_a + c.time_s),
                    Ok(None) => Err(JuggleEnd::NoContact),
                    Err(ContactError::Cap(_)) => Err(JuggleEnd::SearchCap),
                    Err(ContactError::NonFinite) => Err(JuggleEnd::NonFinite),
                }
            }
        }
    }

    /// The bar's reference rate r' at the ball's state, rad/s.
    fn bar_rate(&self, ball: &PlanarBall<f64>) -> f64 {
        match &self.law {
            JugglerLaw::Mirror(law) => law.reference(ball).rate_radps,
            JugglerLaw::Modified(law) => law.reference(ball).rate_radps,
        }
    }

    /// Run `impacts` bats from `start`.
    pub fn run(&self, start: PlanarBall<f64>, impacts: usize) -> JuggleRun {
        let g = self.gravity_mps2;
        let mut ball = start;
        let mut time = 0.0;
        let mut bats = Vec::new();
        let end = 'run: {
            for index in 0..impacts.min(MAX_JUGGLES) {
                let dt = match self.next_contact_s(&ball) {
                    Ok(t) => t,
                    Err(e) => break 'run e,
                };
                let before = ball.flown(dt, g);
                time += dt;
                if !(before.x_m.is_finite() && before.z_m.is_finite()) {
                    break 'run JuggleEnd::NonFinite;
                }
                if before.x_m <= 0.0 {
                    break 'run JuggleEnd::LeftHalfPlane;
                }
                let r = before.angle_rad();
                let rd = self.bar_rate(&before);
                let (s, c) = r.sin_cos();
                let n = [-s, c];
                let v_bar = [-rd * before.z_m, rd * before.x_m];
                let un =
                    n[0] * (before.x_dot_mps - v_bar[0]) + n[1] * (before.z_dot_mps - v_bar[1]);
                if un.is_nan() || un >= 0.0 {
                    break 'run JuggleEnd::BadContact;
                }
                let j = (1.0 + self.restitution) * un;
                let mut after = before;
                after.x_dot_mps -= j * n[0];
                after.z_dot_mps -= j * n[1];
                let t_a = (after.z_dot_mps / g).max(0.0);
                let top = after.flown(t_a, g);
                bats.push(Bat {
                    index,
                    time_s: time,
                    before: arr(&before),
                    after: arr(&after),
                    bar_angle_rad: r,
                    bar_rate_radps: rd,
                    apex: [top.x_m, top.z_m],
                    energy_jpkg: after.energy_jpkg(g),
                });
                ball = after;
            }
            JuggleEnd::Completed
        };
        JuggleRun { bats, end }
    }
}
