//! A planar body bouncing on a tilted, moving table under the kappa-tilt law with the energy
//! feedback of eq. 25 (Zumel & Erdmann, "Balancing of a Planar Bouncing Object", sec. 2),
//! and the planar juggler of Rizzi & Koditschek (1994) sec. 3.1.1 and 4 ([`juggler`]).
//!
//! # Model
//!
//! State (x, y, theta, x', y', theta') in m, rad, m/s, rad/s; radius of gyration rho (m),
//! contact point at distance l (m) below the centre of mass when theta = 0 (the paper's
//! "rod", fig. 1); gravity G along -y on a frictionless inclined plane. Flight is closed form
//! (eq. 6). The table is a line at angle alpha through a point, translating with velocity
//! v_T; the gap of the contact point above it is transcendental (eq. 7) and solved by
//! [`contact::first_contact`] (bracket, then refine; never misses the first contact).
//!
//! Impacts ([`impact`]): eq. 21 (frictionless, restitution e; e = 1, v_T = 0 is eq. 1/5)
//! from the core, or Coulomb friction with sliding/sticking (Routh's method, derived in
//! [`impact`]).
//!
//! # The table: perfect sensing and control (sec. 2), and timing noise (sec. 2.3)
//!
//! The controlled table meets the contact point on the impact line y = 0 (sec. 2.1: "tilt
//! the table while simultaneously moving it so that impact always occurs at a given height
//! ... y = 0"), at the predicted time tau of eq. 7. At that instant it is at the commanded
//! angle alpha = kappa theta ([`dexter_core::tilt::TiltLaw`]) and moves with the velocity of
//! eq. 25 ([`dexter_core::tilt::EnergyFeedback`]) computed from the body's state at impact.
//!
//! **Timing noise** (sec. 2.3: noise "to the calculation of impact time used by the table.
//! This changes the angle and velocity of the table at impact time, as well as the y-height
//! at which contact is made"). Modelled as: the table believes the impact happens at
//! `t_est = tau + delta`, delta ~ N(0, sigma^2) clamped to ±4 sigma (and to
//! `t_est >= tau/2`). It commands angle and velocity from the body's (perfectly sensed,
//! ballistically predicted) state at t_est, and moves so that its line passes through the
//! predicted contact point at t_est: the line at time t is through
//! `P_est + v_T (t - t_est)` with angle alpha held through the impact window. The true
//! impact is the first contact of the body with this moving line (transcendental gap,
//! [`contact`]); it happens at another time and height than planned, with the table's angle
//! and velocity taken from the wrong state. With sigma = 0 this reduces exactly to the
//! noise-free table. Two corner cases: if the body starts (just after the previous impact)
//! below the table's extrapolated approach line and never provably clears it, the contact is
//! taken at t_est, where the gap is zero by construction; if after an impact below y = 0 the
//! contact point never rises above y = 0, the table plans the next impact at the height the
//! contact point left from ([`PlanarModel::ideal_contact_time_s`]).
//!
//! # Point mass (eq. 3–4)
//!
//! [`Body::PointMass`] has rho = l = 0; its "theta" for the law is the angle of the incoming
//! velocity to the vertical, `atan2(x', -y')` (sec. 2.1), and the gap is a quadratic solved in
//! closed form ([`crate::engine::roots::first_contact`]).
//!
//! # Tip-over
//!
//! The run ends [`RunEnd::TippedOver`] when |theta| at an impact reaches the tip angle
//! (`planar.tip_angle_rad`: pi/2 for the paper's rod; for the isosceles triangle standing on
//! its apex, atan(2 h / b) = atan(4) = 1.3258 rad, where a base corner drops below the apex).
//!
//! Submodules: [`params`] (the scene's `[planar]` table), [`analysis`] (fixed point,
//! the engine's linearization at it, verdict; stability map), [`juggler`] (the planar
//! juggler).

pub mod analysis;
pub mod camera;
pub mod contact;
pub mod impact;
pub mod juggler;
pub mod params;
pub mod real_table;
pub mod stats;
pub mod table_run;

pub use params::PlanarParams;

use contact::{first_contact, ContactError, Gap};
use dexter_core::params::ParamError;
use dexter_core::tilt::{BodyState, EnergyFeedback, TiltLaw};
use impact::{FrictionMode, ImpactError, ImpactGeometry};
use rand::SeedableRng;
use rand_distr::{Distribution, Normal};

/// Most impacts one run simulates (`planar.impacts`): a bound on its time (about a
/// microsecond per impact); its memory does not grow with the impacts.
pub const MAX_IMPACTS: usize = 1_000_000_000;

/// Why a planar model could not be built. Parameter errors name the scene key.
#[derive(Clone, Debug, PartialEq)]
#[non_exhaustive]
pub enum PlanarError {
    /// A single parameter is invalid; the name is the `[planar]` key, e.g.
    /// `planar.restitution is out of its allowed range`.
    Param(ParamError),
    /// A parameter violates a relation with others (`param` must satisfy `requirement`).
    Relation {
        /// The `[planar]` key at fault.
        param: &'static str,
        /// What it must satisfy, in words.
        requirement: &'static str,
    },
    /// The scene text is not valid TOML or does not fit the `[planar]` schema.
    Toml(String),
    /// The analysis could not find or linearize the fixed point.
    Analysis(&'static str),
}

impl core::fmt::Display for PlanarError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            PlanarError::Param(e) => write!(f, "{e}"),
            PlanarError::Relation { param, requirement } => {
                write!(f, "{param} must satisfy {requirement}")
            }
            PlanarError::Toml(m) => write!(f, "planar scene: {m}"),
            PlanarError::Analysis(m) => write!(f, "planar analysis: {m}"),
        }
    }
}

impl std::error::Error for PlanarError {}

impl From<ParamError> for PlanarError {
    fn from(e: ParamError) -> Self {
        PlanarError::Param(e)
    }
}

/// The body's full state: position (m), angle (rad), velocities (m/s, rad/s).
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize)]
pub struct PlanarState {
    /// Centre of mass x, m.
    pub x_m: f64,
    /// Centre of mass y, m (table impact line at y = 0).
    pub y_m: f64,
    /// Orientation theta, rad, counterclockwise, 0 = upright.
    pub theta_rad: f64,
    /// x', m/s.
    pub x_dot_mps: f64,
    /// y', m/s.
    pub y_dot_mps: f64,
    /// theta', rad/s.
    pub theta_dot_radps: f64,
}

impl PlanarState {
    /// Ballistic flight for `dt_s` (eq. 6), exact.
    #[inline]
    pub fn flown(&self, dt_s: f64, gravity_mps2: f64) -> Self {
        Self {
            x_m: self.x_m + self.x_dot_mps * dt_s,
            y_m: self.y_m + self.y_dot_mps * dt_s - 0.5 * gravity_mps2 * dt_s * dt_s,
            theta_rad: self.theta_rad + self.theta_dot_radps * dt_s,
            x_dot_mps: self.x_dot_mps,
            y_dot_mps: self.y_dot_mps - gravity_mps2 * dt_s,
            theta_dot_radps: self.theta_dot_radps,
        }
    }

    /// The contact point (x + l sin theta, y - l cos theta), m.
    #[inline]
    pub fn contact_point(&self, l_m: f64) -> [f64; 2] {
        let (s, c) = self.theta_rad.sin_cos();
        [self.x_m + l_m * s, self.y_m - l_m * c]
    }

    /// The core's impact-state view (theta, x', y', theta').
    #[inline]
    pub fn body_state(&self) -> BodyState<f64> {
        BodyState::new(
            self.theta_rad,
            self.x_dot_mps,
            self.y_dot_mps,
            self.theta_dot_radps,
        )
    }

    /// Total energy per unit mass, J/kg: (x'^2 + y'^2 + rho^2 theta'^2)/2 + G y.
    pub fn total_energy_jpkg(&self, rho_m: f64, gravity_mps2: f64) -> f64 {
        0.5 * (self.x_dot_mps * self.x_dot_mps
            + self.y_dot_mps * self.y_dot_mps
            + rho_m * rho_m * self.theta_dot_radps * self.theta_dot_radps)
            + gravity_mps2 * self.y_m
    }
}

/// The bouncing body.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Body {
    /// A point mass (rho = l = 0); the law's angle is the incoming velocity's angle to the
    /// vertical (eq. 3–4).
    PointMass,
    /// A rigid body with radius of gyration `rho_m` (m, > 0) and contact distance `l_m`
    /// (m, > 0).
    Rigid {
        /// rho, m.
        rho_m: f64,
        /// l, m.
        l_m: f64,
    },
}

impl Body {
    /// (rho, l), m.
    pub fn geometry(&self) -> ImpactGeometry {
        match *self {
            Body::PointMass => ImpactGeometry {
                rho_m: 0.0,
                l_m: 0.0,
            },
            Body::Rigid { rho_m, l_m } => ImpactGeometry { rho_m, l_m },
        }
    }

    /// The angle the tilt law uses, rad: theta for a rigid body, `atan2(x', -y')` for a
    /// point mass.
    pub fn law_angle_rad(&self, s: &PlanarState) -> f64 {
        match self {
            Body::PointMass => s.x_dot_mps.atan2(-s.y_dot_mps),
            Body::Rigid { .. } => s.theta_rad,
        }
    }
}

/// The contact model at the table.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum ContactLaw {
    /// Frictionless, eq. 21.
    Frictionless,
    /// Coulomb friction with coefficient `mu` (> 0), Routh/Poisson ([`impact::coulomb`]).
    Coulomb {
        /// mu, dimensionless.
        mu: f64,
    },
}

/// The table's command at one impact: angle and velocity.
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize)]
pub struct TableCommand {
    /// alpha = kappa theta, rad.
    pub alpha_rad: f64,
    /// v_T from eq. 25, m/s.
    pub velocity_mps: [f64; 2],
}

/// The validated planar model: body, contact law, the core's tilt law and energy feedback,
/// gravity, timing noise and tip angle.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PlanarModel {
    /// The body.
    pub body: Body,
    /// Frictionless or Coulomb.
    pub contact: ContactLaw,
    /// alpha = kappa theta (core).
    pub tilt: TiltLaw<f64>,
    /// eq. 25 (core): e, kappa_E, eta*.
    pub feedback: EnergyFeedback<f64>,
    /// G, m/s^2.
    pub gravity_mps2: f64,
    /// sigma of the table's impact-time error, s (0 = perfect timing).
    pub timing_noise_s: f64,
    /// |theta| at an impact at which the body has tipped over, rad.
    pub tip_angle_rad: f64,
}

/// One impact of a run.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct ImpactRecord {
    /// Impact index n (0 = the first).
    pub index: usize,
    /// Time since the start, s.
    pub time_s: f64,
    /// State just before the impact.
    pub before: PlanarState,
    /// State just after the impact.
    pub after: PlanarState,
    /// The table at the impact.
    pub table: TableCommand,
    /// eta = G l cos theta + y'^2/2 before the impact, J/kg (eq. 25).
    pub energy_jpkg: f64,
    /// The contact was grazing (zero closing speed within rounding).
    pub grazing: bool,
    /// The tangential regime ([`FrictionMode`]).
    pub mode: FrictionMode,
}

/// Why a run ended.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum RunEnd {
    /// All requested impacts were simulated.
    Completed,
    /// |theta| reached the tip angle at an impact.
    TippedOver,
    /// After an impact the contact point does not move away from the table (no flight),
    /// or (the real table) impacts pile up within one control period.
    NoSeparation,
    /// No contact before the gap's horizon (the body never comes back to the table).
    NoContact,
    /// The contact search hit one of its iteration caps (an internal limit, not the
    /// physics: the run is reported as cut short).
    SearchCap,
    /// Painlevé jam in a frictional impact.
    Jam,
    /// A state became non-finite.
    NonFinite,
    /// The run's time limit passed before the requested impacts (only the real table has
    /// one: `real_table.max_duration_s`).
    TimeLimit,
    /// The body's centre of mass left the x range the real table can be under
    /// (`real_table.stage`): the body fell off the table.
    OutOfTravel,
}

/// How a streamed run ([`PlanarModel::run_streaming`]) ended.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Streamed {
    /// Why the run ended.
    pub end: RunEnd,
    /// Impacts simulated (each passed on).
    pub impacts: usize,
    /// Gap evaluations of all contact searches.
    pub gap_evaluations: usize,
}

/// A finished run.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct PlanarRun {
    /// One record per impact.
    pub impacts: Vec<ImpactRecord>,
    /// Why the run ended.
    pub end: RunEnd,
    /// Gap evaluations of all contact searches (the cost of the exact contact).
    pub gap_evaluations: usize,
}

impl PlanarModel {
    /// rho, m (0 for a point mass).
    pub fn rho_m(&self) -> f64 {
        self.body.geometry().rho_m
    }
    /// l, m (0 for a point mass).
    pub fn l_m(&self) -> f64 {
        self.body.geometry().l_m
    }

    /// The table command for a body in state `s` at (its believed) impact: alpha = kappa
    /// theta, v_T from eq. 25.
    pub fn command(&self, s: &PlanarState) -> TableCommand {
        TableCommand {
            alpha_rad: self.tilt.table_angle_rad(self.body.law_angle_rad(s)),
            velocity_mps: self.feedback.table_velocity(&s.body_state()),
        }
    }

    /// The impact of the body in state `s` with the table `cmd` (eq. 21 or Coulomb).
    pub fn collide(
        &self,
        s: &PlanarState,
        cmd: &TableCommand,
    ) -> Result<(PlanarState, FrictionMode), ImpactError> {
        let geo = self.body.geometry();
        let v = [s.x_dot_mps, s.y_dot_mps, s.theta_dot_radps];
        let e = self.feedback.e();
        let r = match self.contact {
            ContactLaw::Frictionless => {
                impact::frictionless(geo, s.theta_rad, v, cmd.alpha_rad, cmd.velocity_mps, e)
            }
            ContactLaw::Coulomb { mu } => {
                impact::coulomb(geo, s.theta_rad, v, cmd.alpha_rad, cmd.velocity_mps, e, mu)?
            }
        };
        let mut out = *s;
        out.x_dot_mps = r.velocity[0];
        out.y_dot_mps = r.velocity[1];
        out.theta_dot_radps = r.velocity[2];
        Ok((out, r.mode))
    }

    /// The eq. 7 gap of a body in state `s` (t = 0 now) above the impact line y = 0, or, for
    /// a table line through `point` at time `t_est` moving with `velocity` at angle `alpha`,
    /// above that line (module docs).
    pub fn gap(&self, s: &PlanarState, table: Option<(&TableCommand, [f64; 2], f64)>) -> Gap {
        let l = self.l_m();
        let g = self.gravity_mps2;
        match table {
            None => Gap {
                c0: s.y_m,
                c1: s.y_dot_mps,
                c2: -0.5 * g,
                l_m: l,
                phi0_rad: s.theta_rad,
                omega_radps: s.theta_dot_radps,
            },
            Some((cmd, point, t_est)) => {
                let (sa, ca) = cmd.alpha_rad.sin_cos();
                let n = [-sa, ca];
                let nv = n[0] * cmd.velocity_mps[0] + n[1] * cmd.velocity_mps[1];
                Gap {
                    c0: n[0] * (s.x_m - point[0]) + n[1] * (s.y_m - point[1]) + nv * t_est,
                    c1: n[0] * s.x_dot_mps + n[1] * s.y_dot_mps - nv,
                    c2: -0.5 * g * ca,
                    l_m: l,
                    phi0_rad: s.theta_rad - cmd.alpha_rad,
                    omega_radps: s.theta_dot_radps,
                }
            }
        }
    }

    /// Time to the next contact with the ideal impact line y = 0 (eq. 7), s, from a state
    /// in flight; `Err` names the failure. Point masses use the closed-form quadratic.
    ///
    /// After an impact below the line (timing noise) the contact point may never rise above
    /// y = 0 again; then the table plans the next impact where the contact point comes back
    /// down to the height it left from (the line is lowered to that height).
    pub fn ideal_contact_time_s(&self, s: &PlanarState) -> Result<(f64, bool, usize), RunEnd> {
        let gap = self.gap(s, None);
        match self.solve(&gap) {
            Err(RunEnd::NoContact) => {
                let yc = s.contact_point(self.l_m())[1];
                if yc >= 0.0 {
                    return Err(RunEnd::NoContact);
                }
                let lowered = Gap {
                    c0: gap.c0 - yc,
                    ..gap
                };
                self.solve(&lowered)
            }
            other => other,
        }
    }

    fn solve(&self, gap: &Gap) -> Result<(f64, bool, usize), RunEnd> {
        if gap.l_m == 0.0 {
            // quadratic: closed form
            let horizon = gap.horizon_s().ok_or(RunEnd::NoContact)?;
            return match crate::engine::roots::first_contact(
                gap.c0,
                gap.c1,
                gap.c2,
                horizon * 2.0 + 1.0,
            ) {
                Some(c) => Ok((c.time_s, c.grazing, 1)),
                None => Err(RunEnd::NoContact),
            };
        }
        match first_contact(gap) {
            Ok(Some(c)) => Ok((c.time_s, c.grazing, c.evaluations)),
            Ok(None) => Err(RunEnd::NoContact),
            Err(ContactError::NonFinite) => Err(RunEnd::NonFinite),
            Err(ContactError::Cap(_)) => Err(RunEnd::SearchCap),
        }
    }

    /// Simulate `impacts` impacts from `start` (in flight, contact point above y = 0),
    /// with timing noise drawn from `seed` when `timing_noise_s > 0`, keeping every impact
    /// (memory grows with the run: the CLI streams with [`PlanarModel::run_streaming`]).
    pub fn run(&self, start: PlanarState, impacts: usize, seed: u64) -> PlanarRun {
        let mut records = Vec::with_capacity(impacts.min(1 << 16));
        let done = self.run_streaming(start, impacts, seed, &mut |r| records.push(*r));
        PlanarRun {
            impacts: records,
            end: done.end,
            gap_evaluations: done.gap_evaluations,
        }
    }

    /// [`PlanarModel::run`], passing each impact to `on_impact` as it happens and keeping
    /// none (constant memory however long the run).
    pub fn run_streaming(
        &self,
        start: PlanarState,
        impacts: usize,
        seed: u64,
        on_impact: &mut dyn FnMut(&ImpactRecord),
    ) -> Streamed {
        let mut noise = (self.timing_noise_s > 0.0).then(|| {
            (
                Normal::new(0.0, self.timing_noise_s).expect("sigma validated > 0"),
                rand::rngs::StdRng::seed_from_u64(seed),
            )
        });
        let mut done = Streamed {
            end: RunEnd::Completed,
            impacts: 0,
            gap_evaluations: 0,
        };
        let mut s = start;
        let mut time = 0.0;
        for index in 0..impacts {
            let record = match self.impact(&s, index, time, &mut noise, &mut done.gap_evaluations) {
                Ok(r) => r,
                Err(end) => {
                    done.end = end;
                    break;
                }
            };
            on_impact(&record);
            done.impacts += 1;
            time = record.time_s;
            // the contact point must leave the table (relative normal velocity > 0)
            if let Err(end) = self.separates(&record) {
                done.end = end;
                break;
            }
            // the next search starts on the impact line: the table plans the next impact
            // at y = 0 again
            s = record.after;
        }
        done
    }

    /// The table's command and the time to the contact (s) from `s` in flight, with the
    /// timing noise if any (module docs).
    fn contact(
        &self,
        s: &PlanarState,
        noise: &mut Option<(Normal<f64>, rand::rngs::StdRng)>,
        evals: &mut usize,
    ) -> Result<(f64, bool, TableCommand), RunEnd> {
        // predicted (ideal) impact
        let (tau, grazing0, n0) = self.ideal_contact_time_s(s)?;
        *evals += n0;
        let Some((normal, rng)) = noise.as_mut() else {
            let before = s.flown(tau, self.gravity_mps2);
            return Ok((tau, grazing0, self.command(&before)));
        };
        let sigma = self.timing_noise_s;
        let delta = normal.sample(rng).clamp(-4.0 * sigma, 4.0 * sigma);
        let t_est = (tau + delta).max(0.5 * tau);
        let predicted = s.flown(t_est, self.gravity_mps2);
        let cmd = self.command(&predicted);
        let point = predicted.contact_point(self.l_m());
        let gap = self.gap(s, Some((&cmd, point, t_est)));
        match self.solve(&gap) {
            Ok((t, gz, n)) => {
                *evals += n;
                Ok((t, gz, cmd))
            }
            // the body starts below the table's (extrapolated) approach line and never
            // provably clears it: contact where the table planned it, at t_est (the gap is
            // zero there by construction)
            Err(RunEnd::NoContact) if gap.rate(t_est) < 0.0 => Ok((t_est, false, cmd)),
            Err(e) => Err(e),
        }
    }

    /// Impact number `index` of a body in flight in state `s` at time `time_s`.
    fn impact(
        &self,
        s: &PlanarState,
        index: usize,
        time_s: f64,
        noise: &mut Option<(Normal<f64>, rand::rngs::StdRng)>,
        evals: &mut usize,
    ) -> Result<ImpactRecord, RunEnd> {
        let (dt, grazing, cmd) = self.contact(s, noise, evals)?;
        if dt.is_nan() || dt <= 0.0 {
            // contact again at once: the impact did not launch the body (no flight)
            return Err(RunEnd::NoSeparation);
        }
        let before = s.flown(dt, self.gravity_mps2);
        if !(before.y_dot_mps.is_finite() && before.theta_rad.is_finite()) {
            return Err(RunEnd::NonFinite);
        }
        if matches!(self.body, Body::Rigid { .. }) && before.theta_rad.abs() >= self.tip_angle_rad {
            return Err(RunEnd::TippedOver);
        }
        let (after, mode) = self.collide(&before, &cmd).map_err(|e| match e {
            ImpactError::Jam => RunEnd::Jam,
            ImpactError::Cap => RunEnd::NonFinite,
        })?;
        Ok(ImpactRecord {
            index,
            time_s: time_s + dt,
            before,
            after,
            table: cmd,
            energy_jpkg: self.feedback.energy_jpkg(&before.body_state()),
            grazing,
            mode,
        })
    }

    /// `Err(NoSeparation)` unless the contact point leaves the table after `r`.
    fn separates(&self, r: &ImpactRecord) -> Result<(), RunEnd> {
        let vc = r.after.body_state().contact_velocity(self.l_m());
        let (sa, ca) = r.table.alpha_rad.sin_cos();
        let v = r.table.velocity_mps;
        let rel = -sa * (vc[0] - v[0]) + ca * (vc[1] - v[1]);
        if rel.is_nan() || rel <= 0.0 {
            return Err(RunEnd::NoSeparation);
        }
        Ok(())
    }
}
