//! The spatial juggler (Rizzi & Koditschek 1994, sec. 3.1.2): a ball in 3-D batted by a
//! three-joint robot whose paddle tracks the core's eq. 13 ([`SpatialMirrorLaw`]) or the
//! modified law with a solvable flight time ([`ModifiedSpatialLaw`]) perfectly. Joint
//! conventions, kinematics, contact and impact: `docs/spatial.md`.
//!
//! # Impacts
//!
//! The first joint follows the ball's azimuth, so the ball stays in the bar's vertical plane
//! and meets the paddle where the bar's elevation equals the ball's, e_r = e_b:
//!
//! - **eq. 13**: `e_r = -k e_b - l1` with k constant in flight, so contact is
//!   e_b = psi(t) = -l1(w(t))/(1 + k), transcendental. The gap
//!   `G = b_z cos psi - rho sin psi = |b| sin(e_b - psi)` has the sign of e_b - psi; its second
//!   derivative is bounded over the search window from bounds on rho (its least value on
//!   the window), rho' (|v_h|), rho'' = h^2/rho^3 and rho''' = -3 h^2 rho'/rho^4 (h the
//!   angular momentum about z per unit mass, constant), and the root is found by
//!   [`first_root`] (bracket, then refine, capped), as for the planar juggler's eq. 14.
//! - **modified law**: the ball meets the paddle where it crosses the flight's impact plane,
//!   a quadratic in t ([`ModifiedSpatialLaw::impact_time_s`]).
//!
//! Both searches start at the flight's apex. The paddle is much heavier than the ball and
//! frictionless unless the scene sets friction ([`friction`], an effect off by default): with normal n and the paddle's velocity v_p at the ball (from the law's
//! joint rates, perfect tracking), `b'+ = b' - (1 + alpha) (n . (b' - v_p)) n`.
//!
//! # Gains that converge
//!
//! In the vertical plane through the base this is the planar juggler, so the vertical and
//! radial gains are [`crate::model::planar::juggler::JugglerParams::default`]'s, with the
//! radial ones negated (eq. 13's `-l1`). Laterally, a small roll q3 adds
//! `(1 + alpha) |u_n| q3 ~ 2 v* q3` to the lateral velocity at each impact (v* the impact
//! speed at the fixed point), so (d, d') is a double integrator sampled every T = 2 v*/gamma
//! and kicked by `2 v* (kappa20 d + kappa21 d')`: deadbeat at kappa21 = -1/(2 v*),
//! kappa20 = -1/(2 v* T). [`SpatialParams::default`] takes half of each.

use super::planar::contact::{first_root, ContactError};
use dexter_core::params::{positive, within, ParamError};
use dexter_core::spatial::{ModifiedSpatialLaw, SpatialBall, SpatialLawParams, SpatialMirrorLaw};
use serde::{Deserialize, Serialize};

pub mod analysis;
pub mod friction;
pub mod sil;

/// Most impacts of one run.
pub const MAX_BATS: usize = 100_000;

/// Which law, by name (the scene's `spatial_juggler.law`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Deserialize, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Law {
    /// eq. 13 ([`SpatialMirrorLaw`]).
    #[default]
    Mirror,
    /// The modified law with a solvable flight time ([`ModifiedSpatialLaw`]).
    Modified,
}

impl Law {
    /// The scene value (`mirror`, `modified`).
    pub fn name(self) -> &'static str {
        match self {
            Law::Mirror => "mirror",
            Law::Modified => "modified",
        }
    }
}

/// Which law the paddle tracks.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum SpatialLaw {
    /// eq. 13 (impact time transcendental).
    Mirror(SpatialMirrorLaw<f64>),
    /// The modified law (impact time a quadratic).
    Modified(ModifiedSpatialLaw<f64>),
}

/// A spatial juggler's restitution and the law's parameters.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SpatialParams {
    /// Ball-paddle restitution alpha, in (0, 1].
    pub restitution: f64,
    /// The law's gains and set point (kappa10, kappa11 in rad/m and rad s/m for eq. 13, m/m
    /// and s for the modified law).
    pub law: SpatialLawParams<f64>,
}

impl Default for SpatialParams {
    /// [`SpatialParams::suggested`] for eq. 13: alpha = 0.7, gamma = 9.81, apex 0.5 m over
    /// (rho*, phi*) = (1 m, 0).
    fn default() -> Self {
        Self::suggested(Law::Mirror, 0.7, 9.81, 0.5, 1.0, 0.0)
    }
}

impl SpatialParams {
    /// Gains that converge (module docs) for `law`, restitution alpha, gravity gamma, the
    /// apex h* (m) over (rho*, phi*) (m, rad): the core's [`SpatialLawParams::suggested`].
    /// Not validated: [`Self::juggler`] is.
    pub fn suggested(
        law: Law,
        restitution: f64,
        gravity_mps2: f64,
        apex_m: f64,
        radius_m: f64,
        azimuth_rad: f64,
    ) -> Self {
        Self {
            restitution,
            law: SpatialLawParams::suggested(
                law == Law::Modified,
                restitution,
                gravity_mps2,
                apex_m,
                radius_m,
                azimuth_rad,
            ),
        }
    }

    /// A juggler tracking eq. 13.
    pub fn mirror(&self) -> Result<SpatialJuggler, ParamError> {
        let law = SpatialLaw::Mirror(SpatialMirrorLaw::new(self.law)?);
        SpatialJuggler::new(law, self.restitution, self.law.gravity_mps2)
    }

    /// A juggler tracking the modified law.
    pub fn modified(&self) -> Result<SpatialJuggler, ParamError> {
        let law = SpatialLaw::Modified(ModifiedSpatialLaw::new(self.law)?);
        SpatialJuggler::new(law, self.restitution, self.law.gravity_mps2)
    }

    /// A juggler tracking `law`.
    pub fn juggler(&self, law: Law) -> Result<SpatialJuggler, ParamError> {
        match law {
            Law::Mirror => self.mirror(),
            Law::Modified => self.modified(),
        }
    }
}

/// A ball, a three-joint paddle, a law.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SpatialJuggler {
    law: SpatialLaw,
    restitution: f64,
    gravity_mps2: f64,
    /// Coulomb friction at the bats ([`friction`]); `None`: off, no code runs.
    friction: Option<f64>,
}

/// One bat.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct SpatialBat {
    /// Impact index.
    pub index: usize,
    /// Time since the start, s.
    pub time_s: f64,
    /// Ball just before: (b_x, b_y, b_z, b_x', b_y', b_z'), m, m/s.
    pub before: [f64; 6],
    /// Ball just after.
    pub after: [f64; 6],
    /// Joint angles (q1, q2, q3) at the impact, rad.
    pub joints_rad: [f64; 3],
    /// Joint rates, rad/s.
    pub joint_rates_radps: [f64; 3],
    /// Apex of the following flight (b_x, b_y, b_z), m.
    pub apex_m: [f64; 3],
    /// Ball energy after the impact, eta = |b'|^2/2 + gamma b_z, J/kg.
    pub energy_jpkg: f64,
}

/// Why a run ended.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum SpatialEnd {
    /// All impacts done.
    Completed,
    /// No contact within the search window (the ball missed the paddle).
    NoContact,
    /// The contact search hit one of its iteration caps (an internal limit, not the
    /// physics: the run is reported as cut short).
    SearchCap,
    /// The ball was not approaching the paddle at the contact, or 1 + k <= 0.
    BadContact,
    /// The ball's flight passes over the base (rho = 0), where the azimuth is undefined.
    OverBase,
    /// A value became non-finite.
    NonFinite,
}

/// A run.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct SpatialRun {
    /// One record per bat.
    pub bats: Vec<SpatialBat>,
    /// Why it ended.
    pub end: SpatialEnd,
}

fn state(b: &SpatialBall<f64>) -> [f64; 6] {
    let ([x, y, z], [u, v, w]) = (b.position_m, b.velocity_mps);
    [x, y, z, u, v, w]
}

/// Search window from the apex, s: until the ball has fallen |b| + 1 m below it (twice).
fn window_s(apex: &SpatialBall<f64>, g: f64) -> f64 {
    (2.0 * (apex.position_m[2].abs() + apex.radius_m() + 1.0) / g).sqrt() * 2.0
}

/// Least horizontal radius of the flight from `apex` over [0, `window`], m.
fn least_radius_m(apex: &SpatialBall<f64>, window: f64) -> f64 {
    let ([x, y, _], [u, v, _]) = (apex.position_m, apex.velocity_mps);
    let speed2 = u * u + v * v;
    let t = if speed2 > 0.0 {
        (-(x * u + y * v) / speed2).clamp(0.0, window)
    } else {
        0.0
    };
    ((x + u * t).powi(2) + (y + v * t).powi(2)).sqrt()
}

impl SpatialJuggler {
    /// A juggler: `restitution` alpha in (0, 1], `gravity_mps2` gamma > 0 (the law's own).
    pub fn new(law: SpatialLaw, restitution: f64, gravity_mps2: f64) -> Result<Self, ParamError> {
        let restitution = positive("restitution", within("restitution", restitution, 0.0, 1.0)?)?;
        Ok(Self {
            law,
            restitution,
            gravity_mps2: positive("gravity_mps2", gravity_mps2)?,
            friction: None,
        })
    }

    /// The same juggler with Coulomb friction of coefficient `mu` at the bats (0: off).
    pub fn with_friction(self, mu: f64) -> Result<Self, ParamError> {
        let mu = dexter_core::params::non_negative("friction_coefficient", mu)?;
        Ok(Self {
            friction: (mu > 0.0).then_some(mu),
            ..self
        })
    }

    /// The next contact of `ball` (in flight) with the paddle: time from now, s.
    pub fn next_contact_s(&self, ball: &SpatialBall<f64>) -> Result<f64, SpatialEnd> {
        let g = self.gravity_mps2;
        let t_a = (ball.velocity_mps[2] / g).max(0.0);
        let apex = ball.flown(t_a, g);
        let t = match &self.law {
            SpatialLaw::Modified(law) => {
                let (top, _) = law.apex_state(&apex);
                law.impact_time_s(&top, &law.impact_plane(&top))
                    .ok_or(SpatialEnd::NoContact)?
            }
            SpatialLaw::Mirror(law) => mirror_contact_s(law, &apex, g)?,
        };
        Ok(t_a + t)
    }

    /// The joint references at the ball's state.
    fn joints(&self, ball: &SpatialBall<f64>) -> dexter_core::spatial::JointReference<f64> {
        match &self.law {
            SpatialLaw::Mirror(law) => law.reference(ball),
            SpatialLaw::Modified(law) => law.reference(ball),
        }
    }

    /// The ball just after an impact at `before`, and the joints there; `BadContact` if
    /// the ball is not approaching the paddle.
    fn bat(
        &self,
        before: &SpatialBall<f64>,
    ) -> Result<(SpatialBall<f64>, [[f64; 3]; 2]), SpatialEnd> {
        let r = self.joints(before);
        let [q1, q2, q3] = r.angles_rad;
        let [q1_dot, e_dot, _] = r.rates_radps;
        let e = q2 + core::f64::consts::FRAC_PI_2;
        let (s1, c1) = q1.sin_cos();
        let (se, ce) = e.sin_cos();
        let (s3, c3) = q3.sin_cos();
        let n0 = [-se * c1, -se * s1, ce];
        let t = [-s1, c1, 0.0];
        let n: [f64; 3] = core::array::from_fn(|i| c3 * n0[i] + s3 * t[i]);
        let radius = before.radius_m();
        let v_p: [f64; 3] = core::array::from_fn(|i| radius * (q1_dot * ce * t[i] + e_dot * n0[i]));
        let un: f64 = (0..3)
            .map(|i| n[i] * (before.velocity_mps[i] - v_p[i]))
            .sum();
        if un.is_nan() || un >= 0.0 {
            return Err(SpatialEnd::BadContact);
        }
        let j = (1.0 + self.restitution) * un;
        let mut after = *before;
        for (v, n) in after.velocity_mps.iter_mut().zip(n) {
            *v -= j * n;
        }
        if let Some(mu) = self.friction {
            let (b, a) = (&before.velocity_mps, &mut after.velocity_mps);
            friction::add_friction(mu, &n, b, &v_p, self.restitution, a);
        }
        Ok((after, [r.angles_rad, r.rates_radps]))
    }

    /// Run `impacts` bats from `start`.
    pub fn run(&self, start: SpatialBall<f64>, impacts: usize) -> SpatialRun {
        let g = self.gravity_mps2;
        let mut ball = start;
        let mut time = 0.0;
        let mut bats = Vec::new();
        let end = 'run: {
            for index in 0..impacts.min(MAX_BATS) {
                let dt = match self.next_contact_s(&ball) {
                    Ok(t) => t,
                    Err(e) => break 'run e,
                };
                let before = ball.flown(dt, g);
                time += dt;
                if !before.position_m.iter().all(|p| p.is_finite()) {
                    break 'run SpatialEnd::NonFinite;
                }
                let (after, [joints_rad, joint_rates_radps]) = match self.bat(&before) {
                    Ok(x) => x,
                    Err(e) => break 'run e,
                };
                let top = after.flown((after.velocity_mps[2] / g).max(0.0), g);
                bats.push(SpatialBat {
                    index,
                    time_s: time,
                    before: state(&before),
                    after: state(&after),
                    joints_rad,
                    joint_rates_radps,
                    apex_m: top.position_m,
                    energy_jpkg: after.energy_jpkg(g),
                });
                ball = after;
            }
            SpatialEnd::Completed
        };
        SpatialRun { bats, end }
    }
}

/// Bounds over a flight window used by the eq. 13 gap's curvature bound.
struct FlightBounds {
    /// |z| and |z'|, m and m/s.
    z: f64,
    z_dot: f64,
    /// Largest rho, |rho'|, rho'', |rho'''|, in m and its time derivatives.
    rho: f64,
    rho_dot: f64,
    rho_ddot: f64,
    rho_dddot: f64,
}

impl FlightBounds {
    fn new(apex: &SpatialBall<f64>, window: f64, g: f64, rho_min: f64) -> Self {
        let ([x, y, z], [u, v, _]) = (apex.position_m, apex.velocity_mps);
        let speed = u.hypot(v);
        let h2 = (x * v - y * u).powi(2);
        Self {
            z: z.abs().max((z - 0.5 * g * window * window).abs()),
            z_dot: g * window,
            rho: apex.horizontal_radius_m() + speed * window,
            rho_dot: speed,
            rho_ddot: h2 / rho_min.powi(3),
            rho_dddot: 3.0 * h2 * speed / rho_min.powi(4),
        }
    }
}

/// The eq. 13 contact after `apex` (the top of the flight, b_z' <= 0): time from the apex, s.
fn mirror_contact_s(
    law: &SpatialMirrorLaw<f64>,
    apex: &SpatialBall<f64>,
    g: f64,
) -> Result<f64, SpatialEnd> {
    let k = law.gain(apex);
    if k.is_nan() || 1.0 + k <= 0.0 {
        return Err(SpatialEnd::BadContact);
    }
    let window = window_s(apex, g);
    let rho_min = least_radius_m(apex, window);
    // NaN or a pass over the base: no azimuth to follow
    if rho_min.is_nan() || rho_min <= 1e-9 * (1.0 + apex.radius_m()) {
        return Err(SpatialEnd::OverBase);
    }
    let p = law.params();
    let (k10, k11) = (p.kappa10 / (1.0 + k), p.kappa11 / (1.0 + k));
    let gap = |t: f64| {
        let b = apex.flown(t, g);
        // one square root per evaluation (the ball's own accessors take one each)
        let ([x, y, _], [u, v, _]) = (b.position_m, b.velocity_mps);
        let rho = (x * x + y * y).sqrt();
        let rho_dot = (x * u + y * v) / rho;
        let lateral = (x * v - y * u) / rho;
        let rho_ddot = lateral * lateral / rho;
        let psi = -(k10 * (rho - p.target_radius_m) + k11 * rho_dot);
        let psi_dot = -(k10 * rho_dot + k11 * rho_ddot);
        let (s, c) = psi.sin_cos();
        let [_, _, z] = b.position_m;
        let z_dot = b.velocity_mps[2];
        let value = z * c - rho * s;
        let rate = z_dot * c - rho_dot * s - psi_dot * (z * s + rho * c);
        (value, rate)
    };
    let f = FlightBounds::new(apex, window, g, rho_min);
    let psi1 = k10.abs() * f.rho_dot + k11.abs() * f.rho_ddot;
    let psi2 = k10.abs() * f.rho_ddot + k11.abs() * f.rho_dddot;
    // |G''| <= |z''| + 2 |z'| |psi'| + |z| (|psi''| + psi'^2) + |rho''| + 2 |rho'| |psi'|
    //          + rho (|psi''| + psi'^2)
    let a = g
        + 2.0 * f.z_dot * psi1
        + (f.z + f.rho) * (psi2 + psi1 * psi1)
        + f.rho_ddot
        + 2.0 * f.rho_dot * psi1;
    let tol = 64.0 * f64::EPSILON * (f.z + f.rho);
    match first_root(gap, a, 0.0, window, tol) {
        Ok(Some(c)) => Ok(c.time_s),
        Ok(None) => Err(SpatialEnd::NoContact),
        Err(ContactError::Cap(_)) => Err(SpatialEnd::SearchCap),
        Err(ContactError::NonFinite) => Err(SpatialEnd::NonFinite),
    }
}

#[cfg(test)]
pub(crate) mod tests;
