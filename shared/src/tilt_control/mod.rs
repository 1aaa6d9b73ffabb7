//! The fixed-rate kappa-tilt controller with energy feedback (Zumel & Erdmann, "Balancing of
//! a Planar Bouncing Object", sec. 2): camera poses in, table tilt and stroke accelerations
//! out, or the safe state with a fault code.
//!
//! One [`TiltController::step`] per control period `dt_s` takes a [`TiltFrame`] (the body's
//! pose from a camera, the table's measured angle, height and their rates) and returns a
//! [`TiltCommand`]. It implements [`FixedRate`], so the simulator's SIL loop, the HIL driver
//! and the firmware server step it exactly as they step the line juggler.
//!
//! # Pipeline
//!
//! 1. **Validate** the frame: non-finite values, values outside their plausible ranges, or a
//!    sequence number that has not advanced for more than `stale_limit_steps` periods give
//!    the safe state (as [`crate::control`]).
//! 2. **Estimate** the body's flight ([`flight`]): a recursive least-squares fit of the exact
//!    flight (parabola in x, y, theta linear in t), latency compensated, re-initialised at
//!    each planned impact by eq. 2/21 and restarted from the measurements when they disagree.
//! 3. **Predict** the next contact ([`contact`]): eq. 7 against the planned table (its line
//!    passes through the contact point at the impact height), `contact_iterations`
//!    safeguarded Newton steps warm-started from the previous plan's root.
//! 4. **Target** ([`plan`]): alpha = kappa theta (sec. 2.1, [`crate::tilt::TiltLaw`]; plus
//!    the optional tilt-rate term of [`TiltParams::kappa_rate_s`]) and the table velocity of
//!    eq. 25 ([`crate::tilt::EnergyFeedback`]) along the table normal, at the predicted
//!    impact, through the table's geometry to a pivot height and velocity.
//! 5. **Plan and track** each axis ([`axis`]): a cubic from the reference to the target at
//!    the predicted time, re-planned while the impact is further than `commit_s`, then
//!    frozen and checked against the limits; PD plus feed-forward within the axis's limits
//!    (the paddle tracker's law, [`crate::track::Tracker`]). When a target or the profile
//!    exceeds an axis's limits, or the tracker saturates, the command says so
//!    ([`PlanStatus::Limited`]); it is never silent.
//!
//! Steps 3 to 5 form a **pipeline that does one stage per control period** (module
//! `Stage`): snapshot the estimate, bracket the contact, (start, without a warm start), N
//! Newton steps, the angle at impact, the law, the table's motion, apply; after a commit,
//! four limit checks. A plan is therefore re-made every N + 6 or N + 7 periods
//! ([`TiltParams::cycle_periods`]) from an estimate that old (the apply stage moves the
//! predicted time to the period it takes effect in), and between plans the axes follow the
//! cubics' accelerations. In the period in which the estimator applies an impact no stage
//! runs; the next plan starts from the references where they are.
//!
//! # Modes
//!
//! [`Mode::Hold`]: no valid estimate yet; both axes go to their home positions.
//! [`Mode::Track`]: following the plan ([`PlanStatus`] says how). [`Mode::Safe`]: a fault;
//! both axes brake to rest where they are (their last measured state dead-reckoned), the
//! estimator is reset; the next valid frames restart from `Hold`.
//!
//! # Trig and the step budget (Cortex-M4F)
//!
//! The sine/cosine source is a type parameter ([`sincos::SinCos`]); the shipped controller
//! is [`TiltController`] = [`TiltControllerWith`]`<PolySinCos>` ([`crate::math::sin_cos_poly_f32`],
//! one range reduction, ~55 instructions a call with its moves). libm's `sinf` costs ~1350
//! instructions a call on the M4F and is only there to measure what accuracy costs.
//!
//! The work of one period is bounded by constants, whatever the parameters: there is no
//! loop over data (two fixed two-element loops over the axes, one fixed seven-element scan
//! on the fault path), no recursion, and the pipeline runs **at most one stage per
//! period**; `contact_iterations` (<= [`contact::MAX_CONTACT_ITERATIONS`]) changes only how
//! many periods a plan takes, never the work of one. Per period (S = sine/cosine pairs,
//! R = square roots, D = divisions):
//!
//! | part | S | R | D | runs |
//! | --- | --- | --- | --- | --- |
//! | validate (ten comparisons) | 0 | 0 | 0 | every period |
//! | estimator update, fresh sample (two divisions for the gains) | 0 | 0 | 2 | fresh periods |
//! | estimator impact (eq. 2/21; sin, cos from the plan's, rotated) instead of the update | 0 | 1 | 2 | impact periods |
//! | feed-forward, two axis commands (one stopping-distance `sqrt` each), two reference advances | 0 | 2 | 2 | Hold and Track |
//! | safe state (two brakes) instead of all the above | 0 | 0 | 2 | faults |
//! | stage: snapshot / bracket / start | 0 | 0 / 2 / 2 | 0 | one stage per |
//! | stage: Newton step / angle / law | 1 | 0 | 1 / 0 / 0 | Track period, |
//! | stage: motion / apply | 0 | 0 | 1 | none in an |
//! | stage: check dynamics / check travel (per axis) | 0 | 0 / 1 | 1 / 2 | impact period |
//!
//! The worst period is a fresh sample plus the costliest stage (a Newton step, the law, or a
//! travel check); the impact period carries no stage. Measured with a throwaway QEMU build
//! (mps2-an386, `-icount`, the `PolySinCos` controller, N = 1..4, a closed loop on the
//! target): at most 568 instructions per period (Hold at most 410, impact periods at most
//! 460); BENCHMARKS.md gets the figures of the firmware build at integration.

pub mod axis;
pub mod contact;
pub mod flight;
pub mod plan;
pub mod sincos;

use crate::checks::Checks;
use crate::fields;
use crate::fixed_rate::{reply_from_fields, Fault, FixedRate, Mode, Telemetry};
use crate::freshness::Freshness;
use crate::math::Real;
use crate::params::ParamError;
use crate::state::PaddleState;
use crate::tilt::TiltLaw;
use axis::Axis;

use contact::{
    ContactGeometry, ContactInput, ContactPrediction, ContactSolver, MAX_CONTACT_ITERATIONS,
};
use core::marker::PhantomData;
use flight::{BodyFlight, FlightEstimator, FlightTuning, ImpactModel, PlannedImpact};
use plan::{
    table_angle, table_motion, AxisLimits, BodyAtImpact, Cubic, ImpactTarget, LawConstants,
    TableAngle,
};
use serde::{Deserialize, Serialize};
use sincos::{PolySinCos, SinCos};

/// Largest |tilt| travel the validator accepts, rad (cos alpha >= 0.36: the pivot height
/// and velocity targets divide by it).
pub const MAX_TILT_TRAVEL_RAD: f32 = 1.2;

/// The tilt axis: limits, tracking gains and home, rad.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct TiltAxisParams {
    /// Lowest table angle, rad (>= -1.2).
    pub min_rad: f32,
    /// Highest table angle, rad (> min, <= 1.2).
    pub max_rad: f32,
    /// Largest tilt rate, rad/s (> 0).
    pub rate_max_radps: f32,
    /// Largest tilt acceleration, rad/s^2 (> 0).
    pub accel_max_radps2: f32,
    /// Tracking stiffness, 1/s^2 (>= 0).
    pub kp_per_s2: f32,
    /// Tracking damping, 1/s (>= 0).
    pub kd_per_s: f32,
    /// Angle held while there is no valid estimate, rad (within the travel).
    pub home_rad: f32,
}

/// The vertical stroke: limits, tracking gains and home, m.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct StrokeAxisParams {
    /// Lowest pivot height, m.
    pub min_m: f32,
    /// Highest pivot height, m (> min).
    pub max_m: f32,
    /// Largest stroke speed, m/s (> 0).
    pub velocity_max_mps: f32,
    /// Largest stroke acceleration, m/s^2 (> 0).
    pub accel_max_mps2: f32,
    /// Tracking stiffness, 1/s^2 (>= 0).
    pub kp_per_s2: f32,
    /// Tracking damping, 1/s (>= 0).
    pub kd_per_s: f32,
    /// Pivot height held while there is no valid estimate, m (within the travel).
    pub home_m: f32,
}

/// Everything a tilt controller needs, SI units, f32 (sent over the wire in HIL; about 135
/// bytes postcard-encoded). Its serde form is its fields as one flat tuple (the private `fields` module).
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct TiltParams {
    /// Control period, s (> 0, <= 0.02).
    pub dt_s: f32,
    /// G in the plane of motion, m/s^2 (> 0).
    pub gravity_mps2: f32,
    /// Radius of gyration rho, m (> 0).
    pub rho_m: f32,
    /// Contact distance l from the centre of mass, m (> 0).
    pub l_m: f32,
    /// Restitution e, in [0, 1] (eq. 21).
    pub restitution: f32,
    /// kappa of alpha = kappa theta (>= 0).
    pub kappa: f32,
    /// kappa_E of eq. 25, s^2/m^2 (>= 0).
    pub kappa_e_s2pm2: f32,
    /// kappa_w of an added tilt-rate term, alpha = kappa theta + kappa_w theta' at the
    /// impact, s, in [0, 0.1]. **0 is the paper's law** (sec. 2.1), whose tilt mode is only
    /// neutrally stable (eq. 11: eigenvalues on the unit circle for 1 < kappa < kappa_crit):
    /// independent errors in alpha random-walk its amplitude, and on the sec. 2.3 triangle
    /// errors of 1e-3 rad rms (what a camera with 5 mrad noise gives at 500 Hz) tip the body
    /// within tens of impacts. A small kappa_w > 0 adds damping (the tilt oscillation turns
    /// by about 72 degrees per impact, so a term in theta' acts as a phase lead); measured
    /// in `host-sim/tests/integration/planar_real_table.rs`. Not in the paper.
    pub kappa_rate_s: f32,
    /// kappa_x of an added horizontal regulation term on the centre of mass's x at the
    /// impact, alpha = kappa theta + kappa_w theta' - kappa_x x - kappa_x' x', rad/m, in
    /// [0, 1]. **0 is the paper's law**, which does not hold x: its x' eigenvalue is 1, so
    /// the body wanders (tens of metres over 300 impacts with a 1 mm camera), which a real
    /// table's x stage of finite travel cannot follow. Not in the paper; derived here.
    ///
    /// Why the minus sign. Each frictionless impact changes x' by -sin(alpha) P/m (the
    /// impulse P along n = (-sin alpha, cos alpha)) and theta' by P l sin(theta - alpha) /
    /// (m rho^2): the body turns until alpha = theta. A bias d added to kappa theta thus
    /// moves the tilt mode's rest to theta = alpha = d / (1 - kappa), of the opposite sign
    /// to d for kappa > 1 (-10 d at kappa 1.1). A bias that changes slowly against the
    /// tilt cycle (about 72 degrees per impact, five impacts a cycle) acts through that
    /// rest: the bias d = -(kappa_x x + kappa_x' x') gives alpha ~ (kappa_x x + kappa_x'
    /// x') / (kappa - 1), positive for x, x' > 0, and the impacts push the body back
    /// towards x = 0, in the manner of the planar juggler's horizontal regulation l(w) of
    /// b_x (Rizzi & Koditschek eq. 12). The plus
    /// sign drives x' away and tips the body within tens of impacts (measured). Gains must
    /// stay small against the tilt mode: on the sec. 2.3 triangle kappa_x 0.002 /m and
    /// kappa_x' 0.005 s/m keep x within 0.5 m over 300 impacts, 0.005 and 0.02 tip it
    /// (`host-sim/tests/integration/planar_real_table.rs`).
    pub kappa_x_pm: f32,
    /// kappa_x' of the same term on x', s/m, in [0, 1]: the regulation's damping (see
    /// [`TiltParams::kappa_x_pm`]). Not in the paper.
    pub kappa_xdot_spm: f32,
    /// Apex of the centre of mass above the impact height, m (> l): eta* = G apex.
    pub target_apex_m: f32,
    /// Height of the contact point at every planned impact, m (within the stroke travel).
    pub impact_height_m: f32,
    /// The tilt axis.
    pub tilt: TiltAxisParams,
    /// The vertical stroke.
    pub stroke: StrokeAxisParams,
    /// The flight estimator.
    pub estimator: FlightTuning,
    /// The plan is frozen this long before the predicted impact, s (<= 0.2; more than the
    /// latency plus one planning cycle, [`TiltParams::cycle_periods`], plus one period).
    pub commit_s: f32,
    /// Plausible |x| of the centre of mass, m (> 0): beyond it a pose is out of range. The
    /// law does not hold x (its x' eigenvalue is 1: the body wanders, metres over hundreds
    /// of impacts with noise), so this is a sanity bound, 1000 m by default.
    pub x_max_m: f32,
    /// Plausible lowest y of the centre of mass, m.
    pub y_min_m: f32,
    /// Plausible highest y of the centre of mass, m (> y_min).
    pub y_max_m: f32,
    /// Plausible |theta|, rad, in (0, pi/2].
    pub theta_max_rad: f32,
    /// Safeguarded Newton steps per period for the contact time, 1 ..= 4.
    pub contact_iterations: u8,
    /// Periods without a new camera sample before the input counts as stale (>= 1).
    pub stale_limit_steps: u16,
}

impl Default for TiltParams {
    /// The triangle of sec. 2.3 (rho 9.428 cm, l = 2/3 of 20 cm, e 0.5, kappa 1.1,
    /// kappa_E 0.165, 25 cm apex) at 500 Hz, a camera with 4 ms latency, and a table with
    /// +-0.7 rad, 8 rad/s, 300 rad/s^2 of tilt and +-10 cm, 2 m/s, 60 m/s^2 of stroke.
    fn default() -> Self {
        Self {
            dt_s: 0.002,
            gravity_mps2: 9.81,
            rho_m: 0.094_28,
            l_m: 0.2 * 2.0 / 3.0,
            restitution: 0.5,
            kappa: 1.1,
            kappa_e_s2pm2: 0.165,
            kappa_rate_s: 0.0,
            kappa_x_pm: 0.0,
            kappa_xdot_spm: 0.0,
            target_apex_m: 0.25,
            impact_height_m: 0.0,
            tilt: TiltAxisParams {
                min_rad: -0.7,
                max_rad: 0.7,
                rate_max_radps: 8.0,
                accel_max_radps2: 300.0,
                kp_per_s2: 2500.0,
                kd_per_s: 100.0,
                home_rad: 0.0,
            },
            stroke: StrokeAxisParams {
                min_m: -0.1,
                max_m: 0.1,
                velocity_max_mps: 2.0,
                accel_max_mps2: 60.0,
                kp_per_s2: 2500.0,
                kd_per_s: 100.0,
                home_m: 0.0,
            },
            estimator: FlightTuning {
                latency_s: 0.004,
                ..FlightTuning::default()
            },
            commit_s: 0.03,
            x_max_m: 1000.0,
            y_min_m: -0.5,
            y_max_m: 5.0,
            theta_max_rad: 1.4,
            contact_iterations: 2,
            stale_limit_steps: 5,
        }
    }
}

impl TiltAxisParams {
    #[inline]
    fn limits(&self) -> AxisLimits {
        AxisLimits {
            min: self.min_rad,
            max: self.max_rad,
            velocity_max: self.rate_max_radps,
            accel_max: self.accel_max_radps2,
        }
    }

    fn check(&self, c: &mut Checks) {
        let travel = MAX_TILT_TRAVEL_RAD;
        c.within("tilt.min_rad", self.min_rad, -travel, travel);
        c.within("tilt.max_rad", self.max_rad, -travel, travel);
        c.in_range(self.max_rad > self.min_rad, "tilt.max_rad");
        c.positive("tilt.rate_max_radps", self.rate_max_radps);
        c.positive("tilt.accel_max_radps2", self.accel_max_radps2);
        c.non_negative("tilt.kp_per_s2", self.kp_per_s2);
        c.non_negative("tilt.kd_per_s", self.kd_per_s);
        c.within("tilt.home_rad", self.home_rad, self.min_rad, self.max_rad);
    }
}

impl StrokeAxisParams {
    #[inline]
    fn limits(&self) -> AxisLimits {
        AxisLimits {
            min: self.min_m,
            max: self.max_m,
            velocity_max: self.velocity_max_mps,
            accel_max: self.accel_max_mps2,
        }
    }

    fn check(&self, c: &mut Checks) {
        c.finite("stroke.min_m", self.min_m);
        c.finite("stroke.max_m", self.max_m);
        c.in_range(self.max_m > self.min_m, "stroke.max_m");
        c.positive("stroke.velocity_max_mps", self.velocity_max_mps);
        c.positive("stroke.accel_max_mps2", self.accel_max_mps2);
        c.non_negative("stroke.kp_per_s2", self.kp_per_s2);
        c.non_negative("stroke.kd_per_s", self.kd_per_s);
        c.within("stroke.home_m", self.home_m, self.min_m, self.max_m);
    }
}

impl TiltParams {
    /// Most control periods from one plan to the next while re-planning: snapshot,
    /// bracket, start (without a warm start), `contact_iterations` Newton steps, angle, law,
    /// motion, apply.
    pub fn cycle_periods(&self) -> u16 {
        u16::from(self.contact_iterations) + 7
    }

    /// Check every field; the error names the first bad one.
    #[inline]
    pub fn validate(&self) -> Result<(), ParamError> {
        let mut c = Checks::default();
        c.within("dt_s", self.dt_s, f32::MIN_POSITIVE, 0.02);
        c.positive("gravity_mps2", self.gravity_mps2);
        c.positive("rho_m", self.rho_m);
        c.positive("l_m", self.l_m);
        c.within("restitution", self.restitution, 0.0, 1.0);
        c.note(TiltLaw::new(self.kappa));
        c.non_negative("kappa_e_s2pm2", self.kappa_e_s2pm2);
        c.within("kappa_rate_s", self.kappa_rate_s, 0.0, 0.1);
        c.within("kappa_x_pm", self.kappa_x_pm, 0.0, 1.0);
        c.within("kappa_xdot_spm", self.kappa_xdot_spm, 0.0, 1.0);
        c.positive("target_apex_m", self.target_apex_m);
        c.in_range(self.target_apex_m > self.l_m, "target_apex_m");
        self.tilt.check(&mut c);
        self.stroke.check(&mut c);
        let s = &self.stroke;
        c.within("impact_height_m", self.impact_height_m, s.min_m, s.max_m);
        self.estimator.check(&mut c);
        c.within("commit_s", self.commit_s, 0.0, 0.2);
        let n = self.contact_iterations;
        c.in_range(n > 0 && n <= MAX_CONTACT_ITERATIONS, "contact_iterations");
        // a plan is applied every cycle_periods(); the commit must come before the impact
        // is due in the estimator (one latency after it)
        let cycle_s = f32::from(self.cycle_periods()) * self.dt_s;
        let due_s = self.estimator.latency_s + cycle_s + self.dt_s;
        c.in_range(self.commit_s > due_s, "commit_s");
        c.positive("x_max_m", self.x_max_m);
        c.finite("y_min_m", self.y_min_m);
        c.finite("y_max_m", self.y_max_m);
        c.in_range(self.y_max_m > self.y_min_m, "y_max_m");
        let upright = core::f32::consts::FRAC_PI_2;
        c.within(
            "theta_max_rad",
            self.theta_max_rad,
            f32::MIN_POSITIVE,
            upright,
        );
        c.positive_count(self.stale_limit_steps > 0, "stale_limit_steps");
        c.result()
    }
}

impl fields::Fields for TiltParams {
    const COUNT: usize = 40;
    const NAME: &'static str = "TiltParams";

    fn blank() -> Self {
        let axis = AxisLimitsBlank::ZERO;
        Self {
            dt_s: 0.0,
            gravity_mps2: 0.0,
            rho_m: 0.0,
            l_m: 0.0,
            restitution: 0.0,
            kappa: 0.0,
            kappa_e_s2pm2: 0.0,
            kappa_rate_s: 0.0,
            kappa_x_pm: 0.0,
            kappa_xdot_spm: 0.0,
            target_apex_m: 0.0,
            impact_height_m: 0.0,
            tilt: axis.tilt,
            stroke: axis.stroke,
            estimator: FlightTuning::default(),
            commit_s: 0.0,
            x_max_m: 0.0,
            y_min_m: 0.0,
            y_max_m: 0.0,
            theta_max_rad: 0.0,
            contact_iterations: 0,
            stale_limit_steps: 0,
        }
    }

    fn fields<V: fields::FieldVisit>(&mut self, v: &mut V) {
        for x in [
            &mut self.dt_s,
            &mut self.gravity_mps2,
            &mut self.rho_m,
            &mut self.l_m,
            &mut self.restitution,
            &mut self.kappa,
            &mut self.kappa_e_s2pm2,
            &mut self.kappa_rate_s,
            &mut self.kappa_x_pm,
            &mut self.kappa_xdot_spm,
            &mut self.target_apex_m,
            &mut self.impact_height_m,
        ] {
            v.f32(x);
        }
        let (t, s) = (&mut self.tilt, &mut self.stroke);
        for x in [
            &mut t.min_rad,
            &mut t.max_rad,
            &mut t.rate_max_radps,
            &mut t.accel_max_radps2,
            &mut t.kp_per_s2,
            &mut t.kd_per_s,
            &mut t.home_rad,
            &mut s.min_m,
            &mut s.max_m,
            &mut s.velocity_max_mps,
            &mut s.accel_max_mps2,
            &mut s.kp_per_s2,
            &mut s.kd_per_s,
            &mut s.home_m,
        ] {
            v.f32(x);
        }
        let e = &mut self.estimator;
        for x in [&mut e.latency_s, &mut e.gate_m, &mut e.gate_rad] {
            v.f32(x);
        }
        v.u16(&mut e.memory_samples);
        for x in [
            &mut e.settle_samples,
            &mut e.impact_prior_samples,
            &mut e.reinit_after,
        ] {
            v.u8(x);
        }
        for x in [
            &mut self.commit_s,
            &mut self.x_max_m,
            &mut self.y_min_m,
            &mut self.y_max_m,
            &mut self.theta_max_rad,
        ] {
            v.f32(x);
        }
        v.u8(&mut self.contact_iterations);
        v.u16(&mut self.stale_limit_steps);
    }
}

/// Zero axes for [`fields::Fields::blank`].
struct AxisLimitsBlank {
    tilt: TiltAxisParams,
    stroke: StrokeAxisParams,
}

impl AxisLimitsBlank {
    const ZERO: Self = Self {
        tilt: TiltAxisParams {
            min_rad: 0.0,
            max_rad: 0.0,
            rate_max_radps: 0.0,
            accel_max_radps2: 0.0,
            kp_per_s2: 0.0,
            kd_per_s: 0.0,
            home_rad: 0.0,
        },
        stroke: StrokeAxisParams {
            min_m: 0.0,
            max_m: 0.0,
            velocity_max_mps: 0.0,
            accel_max_mps2: 0.0,
            kp_per_s2: 0.0,
            kd_per_s: 0.0,
            home_m: 0.0,
        },
    };
}

impl Serialize for TiltParams {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        fields::serialize(self, s)
    }
}

impl<'de> Deserialize<'de> for TiltParams {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        fields::deserialize(d)
    }
}

/// One sample of the plant: the camera's newest pose of the body and the table's encoders.
/// Its serde form is its fields as one flat tuple (the private `fields` module).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct TiltFrame {
    /// Sequence number of the camera sample; a controller that sees it not advance counts
    /// the input stale.
    pub seq: u32,
    /// Centre of mass x, m (NaN if the camera lost the body).
    pub body_x_m: f32,
    /// Centre of mass y, m.
    pub body_y_m: f32,
    /// Body angle theta, rad (counterclockwise, 0 = upright).
    pub body_theta_rad: f32,
    /// Table angle alpha, rad.
    pub table_angle_rad: f32,
    /// Table tilt rate, rad/s (the tilt drive's velocity estimate).
    pub table_rate_radps: f32,
    /// Pivot height h, m.
    pub table_height_m: f32,
    /// Pivot vertical velocity, m/s (the stroke drive's velocity estimate).
    pub table_velocity_mps: f32,
}

impl fields::Fields for TiltFrame {
    const COUNT: usize = 8;
    const NAME: &'static str = "TiltFrame";

    fn blank() -> Self {
        Self::default()
    }

    fn fields<V: fields::FieldVisit>(&mut self, v: &mut V) {
        v.u32(&mut self.seq);
        for x in [
            &mut self.body_x_m,
            &mut self.body_y_m,
            &mut self.body_theta_rad,
            &mut self.table_angle_rad,
            &mut self.table_rate_radps,
            &mut self.table_height_m,
            &mut self.table_velocity_mps,
        ] {
            v.f32(x);
        }
    }
}

impl Serialize for TiltFrame {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        fields::serialize(self, s)
    }
}

impl<'de> Deserialize<'de> for TiltFrame {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        fields::deserialize(d)
    }
}

/// How the table's plan stands (a command field: every limitation is reported).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[repr(u8)]
pub enum PlanStatus {
    /// No plan: no valid estimate, the safe state, or the period right after an impact.
    #[default]
    Idle = 0,
    /// Tracking a plan to the predicted impact, within every limit.
    Planned = 1,
    /// The plan is frozen (within `commit_s` of the impact), within every limit.
    Committed = 2,
    /// The plan needs more than an axis can do: a target clamped into its travel or speed,
    /// a profile beyond its acceleration, speed or travel, or the tracker saturated. The
    /// command stays within the limits; the table will not arrive as planned.
    Limited = 3,
    /// No descending contact ahead: the contact point is already below the impact height.
    /// The axes' references brake to rest.
    Unreachable = 4,
    /// The body spins so fast that the predicted contact is not provably its first
    /// ([`contact`]); the plan follows it anyway.
    Ambiguous = 5,
}

/// The controller's output for one control period (zero-order hold).
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct TiltCommand {
    /// Sequence number of the frame this command answers.
    pub seq: u32,
    /// Commanded tilt acceleration, rad/s^2, within the tilt limit.
    pub tilt_accel_radps2: f32,
    /// Commanded stroke acceleration, m/s^2, within the stroke limit.
    pub stroke_accel_mps2: f32,
    /// Tilt reference the command tracks, rad (informational).
    pub tilt_ref_rad: f32,
    /// Pivot height reference, m (informational).
    pub stroke_ref_m: f32,
    /// Time from this frame to the planned impact, s (0 without a plan; negative when the
    /// planned time has passed and the impact is not yet seen).
    pub impact_in_s: f32,
    /// Mode of operation.
    pub mode: Mode,
    /// Fault code; `Fault::None` unless `mode == Mode::Safe`.
    pub fault: Fault,
    /// How the plan stands.
    pub plan: PlanStatus,
}

reply_from_fields!(TiltCommand);

/// The plan both axes follow: the cubics' accelerations a(t) = a0 + jerk t from its start,
/// until the impact `tau_s` after it.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Active {
    elapsed_s: f32,
    tau_s: f32,
    /// (a0, jerk) of the tilt and of the stroke.
    ff: [(f32, f32); 2],
    /// Planned, Committed, Limited or Ambiguous.
    status: PlanStatus,
}

/// The frame's plausible ranges, precomputed from the parameters: each two-sided range
/// [lo, hi] as its centre and half-width, so that one comparison checks it,
/// |v - (lo + hi)/2| <= (hi - lo)/2 (the same range up to the rounding of the centre and
/// half-width: a relative 6e-8 of the range).
#[derive(Clone, Copy, Debug, PartialEq)]
struct Bounds {
    x_max: f32,
    y_mid: f32,
    y_half: f32,
    theta_max: f32,
    tilt_mid: f32,
    tilt_half: f32,
    rate_max: f32,
    stroke_mid: f32,
    stroke_half: f32,
    velocity_max: f32,
}

impl Bounds {
    /// Poses within the camera's plausible box; table values within their travel plus 5 %
    /// of it, rates within twice their limits.
    #[inline]
    fn new(p: &TiltParams) -> Self {
        let (t, s) = (&p.tilt, &p.stroke);
        // the travel plus 5 % of it on each side: half-width 0.55 of the travel
        Self {
            x_max: p.x_max_m,
            y_mid: 0.5 * (p.y_min_m + p.y_max_m),
            y_half: 0.5 * (p.y_max_m - p.y_min_m),
            theta_max: p.theta_max_rad,
            tilt_mid: 0.5 * (t.min_rad + t.max_rad),
            tilt_half: 0.55 * (t.max_rad - t.min_rad),
            rate_max: 2.0 * t.rate_max_radps,
            stroke_mid: 0.5 * (s.min_m + s.max_m),
            stroke_half: 0.55 * (s.max_m - s.min_m),
            velocity_max: 2.0 * s.velocity_max_mps,
        }
    }

    /// All values in range (false for NaN: every comparison with NaN is false).
    #[inline]
    fn contain(&self, f: &TiltFrame) -> bool {
        f.body_x_m.abs() <= self.x_max
            && (f.body_y_m - self.y_mid).abs() <= self.y_half
            && f.body_theta_rad.abs() <= self.theta_max
            && (f.table_angle_rad - self.tilt_mid).abs() <= self.tilt_half
            && f.table_rate_radps.abs() <= self.rate_max
            && (f.table_height_m - self.stroke_mid).abs() <= self.stroke_half
            && f.table_velocity_mps.abs() <= self.velocity_max
    }
}

/// The planning pipeline's stages, one per control period (module docs).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Stage {
    /// Take the estimate now.
    Snapshot,
    /// Bracket the contact.
    Bracket,
    /// Without a warm start: the solver's start.
    Start,
    /// Newton step k + 1 of `contact_iterations`.
    Newton(u8),
    /// The angle at the contact: the body at impact.
    Angle,
    /// kappa-tilt and eq. 25: the table angle.
    Law,
    /// The pivot's height and velocity.
    Motion,
    /// Both cubics from the references now; commit when the impact is close.
    Apply,
    /// Committed: nothing until the impact.
    Wait,
}

/// The pipeline's intermediate results.
#[derive(Clone, Copy, Debug)]
struct Pipeline {
    stage: Stage,
    /// Control periods since the snapshot.
    periods: u16,
    /// Warm start for the next snapshot's contact time, s (NaN: none).
    guess_s: f32,
    now: BodyFlight,
    solver: ContactSolver,
    pred: ContactPrediction,
    body: BodyAtImpact,
    angle: TableAngle,
    target: ImpactTarget,
}

impl Pipeline {
    fn new() -> Self {
        Self {
            stage: Stage::Snapshot,
            periods: 0,
            guess_s: f32::NAN,
            now: BodyFlight::default(),
            solver: ContactSolver::default(),
            pred: ContactPrediction::default(),
            body: BodyAtImpact::default(),
            angle: TableAngle::default(),
            target: ImpactTarget::default(),
        }
    }

    /// Start over at the next period, without a warm start.
    fn restart(&mut self) {
        self.stage = Stage::Snapshot;
        self.periods = 0;
        self.guess_s = f32::NAN;
    }
}

/// The kappa-tilt controller that ships: sine and cosine from [`PolySinCos`].
pub type TiltController = TiltControllerWith<PolySinCos>;

/// The kappa-tilt controller, stepped at a fixed rate, with the sine/cosine source `T`
/// (module docs; [`TiltController`] is the one that ships).
#[derive(Clone, Debug)]
pub struct TiltControllerWith<T: SinCos> {
    params: TiltParams,
    law: LawConstants,
    geo: ContactGeometry,
    estimator: FlightEstimator,
    tilt: Axis,
    stroke: Axis,
    /// Plausible ranges of the frame's values (module `check`).
    bounds: Bounds,
    pipeline: Pipeline,
    active: Option<Active>,
    /// The last snapshot found no contact ahead (cleared by the next applied plan).
    unreachable: bool,
    /// Last measured (or, in the safe state, dead-reckoned) tilt and stroke.
    table: [PaddleState<f32>; 2],
    /// Whether each frame carries a new sample.
    seq: Freshness,
    mode: Mode,
    _sin_cos: PhantomData<T>,
}

impl<T: SinCos> TiltControllerWith<T> {
    /// The body's estimated flight state now (latency compensated).
    pub fn estimate(&self) -> BodyFlight {
        self.estimator.now()
    }

    /// Whether the flight estimate is valid.
    pub fn estimate_valid(&self) -> bool {
        self.estimator.valid()
    }

    /// The latest table target (valid once a plan has been made).
    pub fn target(&self) -> ImpactTarget {
        self.pipeline.target
    }

    /// One control period: the command for `frame`.
    #[inline(never)]
    pub fn step(&mut self, frame: &TiltFrame) -> TiltCommand {
        match self.check(frame) {
            Err(fault) => self.safe(frame.seq, fault),
            Ok(fresh) => self.track(frame, fresh),
        }
    }

    /// The safe command for an external fault: both axes brake to rest from their last
    /// known state (dead-reckoned), the estimator is reset.
    #[inline(never)]
    pub fn safe(&mut self, seq: u32, fault: Fault) -> TiltCommand {
        self.estimator.reset();
        self.pipeline.restart();
        self.active = None;
        self.mode = Mode::Safe;
        let dt = self.params.dt_s;
        let [tilt, stroke] = self.table;
        let (ut, us) = (self.tilt.brake(&tilt), self.stroke.brake(&stroke));
        // dead-reckoned under the braking, for the next safe period
        let ahead = |s: PaddleState<f32>, u: f32| {
            PaddleState::new(
                s.height_m + (s.velocity_mps + 0.5 * u * dt) * dt,
                s.velocity_mps + u * dt,
            )
        };
        self.table = [ahead(tilt, ut), ahead(stroke, us)];
        let [tilt, stroke] = self.table;
        TiltCommand {
            seq,
            tilt_accel_radps2: ut,
            stroke_accel_mps2: us,
            tilt_ref_rad: tilt.height_m,
            stroke_ref_m: stroke.height_m,
            impact_in_s: 0.0,
            mode: Mode::Safe,
            fault,
            plan: PlanStatus::Idle,
        }
    }

    /// A valid frame: estimate, one pipeline stage, feed-forward, track. Before the axis
    /// commands, the command's fields that come from the controller's own state (the next
    /// references and the time to the impact) are checked to be finite (not expected to
    /// fail for validated input: a guard against an overflow inside); if one is not, the
    /// command is the safe state ([`Fault::NonFinite`]) instead of the axis commands, so
    /// the step's longest path holds one of the two, not both. The accelerations are
    /// finite in any case: [`axis::Axis::command`] clamps them into the limits, NaN
    /// included.
    fn track(&mut self, frame: &TiltFrame, fresh: bool) -> TiltCommand {
        let dt = self.params.dt_s;
        let tilt_m = PaddleState::new(frame.table_angle_rad, frame.table_rate_radps);
        let stroke_m = PaddleState::new(frame.table_height_m, frame.table_velocity_mps);
        self.table = [tilt_m, stroke_m];
        let pose = [frame.body_x_m, frame.body_y_m, frame.body_theta_rad];
        // the estimator's period, and the planning stage with it: in the period in which
        // the impact model runs (the planned impact's time has come, closing or not) or the
        // fit restarts there is none, and the code says so by its branches (each holds at
        // most one of the impact model and a stage: the step's static bound)
        if fresh && self.estimator.impact_due() {
            self.estimator.impact_period();
            self.pipeline.restart();
        } else {
            let restarted = if fresh {
                self.estimator.sample_period(pose).restarted
            } else {
                self.estimator.coast();
                false
            };
            if restarted {
                self.pipeline.restart();
            } else if self.mode == Mode::Track && self.estimator.valid() {
                self.run_stage();
            }
        }
        let (ff, plan, impact_in_s) = if self.estimator.valid() {
            if self.mode != Mode::Track {
                // entering Track (no stage ran): plan from where the table is
                self.tilt.p = tilt_m.height_m;
                self.tilt.v = tilt_m.velocity_mps;
                self.stroke.p = stroke_m.height_m;
                self.stroke.v = stroke_m.velocity_mps;
                self.active = None;
                self.pipeline.restart();
                self.mode = Mode::Track;
            }
            self.feed_forward()
        } else {
            self.mode = Mode::Hold;
            self.active = None;
            self.estimator.clear_plan();
            // both axes home (written out: no loop in the step)
            (self.tilt.p, self.tilt.v) = (self.tilt.home, 0.0);
            (self.stroke.p, self.stroke.v) = (self.stroke.home, 0.0);
            ([0.0, 0.0], PlanStatus::Idle, 0.0)
        };
        let [ff_t, ff_s] = ff;
        let (tilt_next, stroke_next) =
            (self.tilt.advanced(ff_t, dt), self.stroke.advanced(ff_s, dt));
        // one test for three values: the sum of finite values is finite unless it
        // overflows (beyond 1e38: not a plan either)
        if !(tilt_next.0 + stroke_next.0 + impact_in_s).is_finite() {
            return self.safe(frame.seq, Fault::NonFinite);
        }
        let (ut, sat_t) = self.tilt.command(ff_t, &tilt_m, dt);
        let (us, sat_s) = self.stroke.command(ff_s, &stroke_m, dt);
        (self.tilt.p, self.tilt.v) = tilt_next;
        (self.stroke.p, self.stroke.v) = stroke_next;
        TiltCommand {
            seq: frame.seq,
            tilt_accel_radps2: ut,
            stroke_accel_mps2: us,
            tilt_ref_rad: tilt_next.0,
            stroke_ref_m: stroke_next.0,
            impact_in_s,
            mode: self.mode,
            fault: Fault::None,
            plan: match plan {
                PlanStatus::Planned | PlanStatus::Committed | PlanStatus::Ambiguous
                    if sat_t || sat_s =>
                {
                    PlanStatus::Limited
                }
                other => other,
            },
        }
    }

    /// This period's feed-forward of both axes from the active plan (the cubics until the
    /// impact time; on at the impact velocity through the impact window; then braking),
    /// the plan's status and the time to the impact.
    fn feed_forward(&mut self) -> ([f32; 2], PlanStatus, f32) {
        let dt = self.params.dt_s;
        let window = self.params.estimator.latency_s + 2.0 * dt;
        // without a plan, or past its impact window: brake the references (one code path)
        let (status, impact_in_s) = match self.active.as_mut() {
            Some(a) => {
                let t = a.elapsed_s;
                a.elapsed_s = t + dt;
                let [(a0t, jt), (a0s, js)] = a.ff;
                if t < a.tau_s {
                    let tm = t + 0.5 * dt;
                    return ([a0t + jt * tm, a0s + js * tm], a.status, a.tau_s - t);
                } else if t < a.tau_s + window {
                    return ([0.0, 0.0], a.status, a.tau_s - t);
                }
                (a.status, a.tau_s - t)
            }
            None if self.unreachable => (PlanStatus::Unreachable, 0.0),
            None => (PlanStatus::Idle, 0.0),
        };
        let ff = [self.tilt.brake_reference(), self.stroke.brake_reference()];
        (ff, status, impact_in_s)
    }

    /// One stage of the planning pipeline (module docs).
    fn run_stage(&mut self) {
        let p = &mut self.pipeline;
        p.periods = p.periods.saturating_add(1);
        match p.stage {
            Stage::Snapshot => {
                p.now = self.estimator.now();
                p.stage = Stage::Bracket;
            }
            Stage::Bracket => self.bracket(),
            Stage::Start => {
                p.solver.cold_start(&self.geo);
                p.stage = Stage::Newton(0);
            }
            Stage::Newton(k) => {
                p.solver.iterate::<T>(&self.geo);
                let next = k.saturating_add(1);
                p.stage = if next >= self.params.contact_iterations {
                    Stage::Angle
                } else {
                    Stage::Newton(next)
                };
            }
            Stage::Angle => {
                p.pred = p.solver.finish::<T>();
                let (now, tau) = (&p.now, p.pred.time_s);
                p.body = BodyAtImpact {
                    theta_rad: now.theta_rad + now.theta_dot_radps * tau,
                    x_m: now.x_m + now.x_dot_mps * tau,
                    sin_theta: p.pred.sin_theta,
                    cos_theta: p.pred.cos_theta,
                    x_dot_mps: now.x_dot_mps,
                    y_dot_mps: now.y_dot_mps - self.law.gravity_mps2 * tau,
                    theta_dot_radps: now.theta_dot_radps,
                };
                p.stage = Stage::Law;
            }
            Stage::Law => {
                p.angle = table_angle::<T>(&self.law, &self.tilt.limits, &p.body);
                p.stage = Stage::Motion;
            }
            Stage::Motion => {
                p.target = table_motion(&self.law, &self.stroke.limits, &p.body, &p.angle);
                p.stage = Stage::Apply;
            }
            Stage::Apply => self.apply(),
            Stage::Wait => {
                // the estimator applies the impact one latency after its time; far past
                // that the plan was missed: plan afresh
                if let Some(a) = self.active {
                    let late = self.params.estimator.latency_s + 4.0 * self.params.dt_s;
                    if a.elapsed_s > a.tau_s + late {
                        p.restart();
                    }
                }
            }
        }
    }

    /// Bracket the contact from the snapshot (or find none ahead).
    fn bracket(&mut self) {
        let p = &mut self.pipeline;
        let now = &p.now;
        let input = ContactInput {
            height_above_m: now.y_m - self.law.impact_height_m,
            y_dot_mps: now.y_dot_mps,
            theta_rad: now.theta_rad,
            theta_dot_radps: now.theta_dot_radps,
        };
        // the last cycle's contact time, moved to this snapshot (`periods` ago, this
        // period included: the snapshot was the previous one)
        let guess = p.guess_s - f32::from(p.periods.saturating_sub(1)) * self.params.dt_s;
        p.periods = 1;
        match ContactSolver::bracket(&self.geo, &input, guess) {
            Some(solver) => {
                p.stage = if solver.needs_start() {
                    Stage::Start
                } else {
                    Stage::Newton(0)
                };
                p.solver = solver;
            }
            None => {
                p.guess_s = f32::NAN;
                p.stage = Stage::Snapshot;
                self.unreachable = true;
                self.active = None;
                self.estimator.clear_plan();
            }
        }
    }

    /// Both cubics from the references now to the target; commit when close.
    fn apply(&mut self) {
        let dt = self.params.dt_s;
        let p = &mut self.pipeline;
        // the snapshot was `periods` periods ago (this one included)
        let since = f32::from(p.periods) * dt;
        let tau = (p.pred.time_s - since).max_r(dt);
        let t = &p.target;
        let inv_tau = 1.0 / tau;
        let tilt = Cubic::hermite(self.tilt.p, self.tilt.v, t.alpha_rad, 0.0, inv_tau);
        let stroke = Cubic::hermite(
            self.stroke.p,
            self.stroke.v,
            t.height_m,
            t.velocity_mps,
            inv_tau,
        );
        let committed = tau <= self.params.commit_s;
        let status = if t.clamped {
            PlanStatus::Limited
        } else if !p.pred.unique {
            PlanStatus::Ambiguous
        } else if committed {
            PlanStatus::Committed
        } else {
            PlanStatus::Planned
        };
        self.active = Some(Active {
            elapsed_s: 0.0,
            tau_s: tau,
            ff: [
                (2.0 * tilt.c2, 6.0 * tilt.c3),
                (2.0 * stroke.c2, 6.0 * stroke.c3),
            ],
            status,
        });
        self.unreachable = false;
        self.estimator.plan_impact(PlannedImpact {
            in_s: tau,
            theta_rad: p.body.theta_rad,
            sin_theta: p.body.sin_theta,
            cos_theta: p.body.cos_theta,
            sin_alpha: t.sin_alpha,
            cos_alpha: t.cos_alpha,
            normal_velocity_mps: t.normal_velocity_mps,
        });
        p.guess_s = p.pred.time_s;
        if committed {
            p.stage = Stage::Wait;
        } else {
            // the periods to the next snapshot count from the snapshot
            p.stage = Stage::Snapshot;
        }
    }

    /// Validate a frame; `Ok(true)` if it carries a new camera sample, `Ok(false)` if it
    /// repeats the last one (within the stale limit).
    fn check(&mut self, frame: &TiltFrame) -> Result<bool, Fault> {
        // every comparison is false for NaN, so a non-finite value fails here too; which
        // fault it was is sorted out only on that path
        let in_range = self.bounds.contain(frame);
        if !in_range {
            // x * 0 is 0 for every finite x (however large) and NaN otherwise
            let f = frame;
            let probe = f.body_x_m * 0.0
                + f.body_y_m * 0.0
                + f.body_theta_rad * 0.0
                + f.table_angle_rad * 0.0
                + f.table_rate_radps * 0.0
                + f.table_height_m * 0.0
                + f.table_velocity_mps * 0.0;
            return Err(if probe == 0.0 {
                Fault::OutOfRange
            } else {
                Fault::NonFinite
            });
        }
        self.seq.check(frame.seq, self.params.stale_limit_steps)
    }
}

impl<T: SinCos> FixedRate for TiltControllerWith<T> {
    type Params = TiltParams;
    type Frame = TiltFrame;
    type Command = TiltCommand;
    /// 600 instructions with the shipped [`PolySinCos`], for every configuration the
    /// validator accepts: the step is a fixed set of paths with no loop over data and at
    /// most one pipeline stage per period (module docs, "Trig and the step budget"); the
    /// static longest path through the compiled step and its measured maximum are in
    /// BENCHMARKS.md ("Tilt controller on the MCU"). Other sources are measured against it
    /// and marked there (libm's `sinf` alone takes ~1350).
    const STEP_INSTRUCTION_BUDGET: u32 = 600;

    /// A controller; the error names the first invalid parameter.
    #[inline]
    fn new(params: TiltParams) -> Result<Self, ParamError> {
        params.validate()?;
        let p = &params;
        let law = LawConstants {
            kappa: p.kappa,
            kappa_rate_s: p.kappa_rate_s,
            kappa_x_pm: p.kappa_x_pm,
            kappa_xdot_spm: p.kappa_xdot_spm,
            kappa_e_s2pm2: p.kappa_e_s2pm2,
            // eta* = G apex and eq. 22's (1 - e)/(1 + e), as [`crate::tilt::EnergyFeedback`] computes
            // them (the test `law_constants_are_the_energy_feedbacks` checks it to the bit);
            // the parameters are validated above, so its checks are not repeated here
            target_energy_jpkg: p.gravity_mps2 * p.target_apex_m,
            compensation: (1.0 - p.restitution) / (1.0 + p.restitution),
            gravity_mps2: p.gravity_mps2,
            l_m: p.l_m,
            impact_height_m: p.impact_height_m,
        };
        let model = ImpactModel {
            rho_m: p.rho_m,
            l_m: p.l_m,
            restitution: p.restitution,
        };
        let (t, s) = (&p.tilt, &p.stroke);
        let tilt = Axis::new(t.limits(), t.kp_per_s2, t.kd_per_s, t.home_rad, p.dt_s);
        let stroke = Axis::new(s.limits(), s.kp_per_s2, s.kd_per_s, s.home_m, p.dt_s);
        Ok(Self {
            params,
            law,
            geo: ContactGeometry::new(p.gravity_mps2, p.l_m),
            // validated with the rest of the parameters above
            estimator: FlightEstimator::new_validated(p.estimator, model, p.dt_s, p.gravity_mps2),
            tilt,
            stroke,
            bounds: Bounds::new(p),
            pipeline: Pipeline::new(),
            active: None,
            unreachable: false,
            table: [
                PaddleState::new(t.home_rad, 0.0),
                PaddleState::new(s.home_m, 0.0),
            ],
            seq: Freshness::new(),
            mode: Mode::Hold,
            _sin_cos: PhantomData,
        })
    }

    /// The parameters this controller runs with.
    fn params(&self) -> &TiltParams {
        &self.params
    }

    fn step(&mut self, frame: &TiltFrame) -> TiltCommand {
        T::step(self, frame)
    }

    fn safe(&mut self, seq: u32, fault: Fault) -> TiltCommand {
        T::safe(self, seq, fault)
    }

    /// Telemetry fields the core knows: estimate slot 0 the body's centre-of-mass height y,
    /// m, slot 1 its vertical velocity y', m/s, slot 2 its angle theta, rad (latency
    /// compensated, [`FlightEstimator::now`]); valid while the flight estimate is.
    fn telemetry(&self) -> Telemetry {
        let now = self.estimator.now();
        Telemetry::with_estimate(
            &[now.y_m, now.y_dot_mps, now.theta_rad],
            self.estimator.valid(),
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::fields::{Count, Fields};
    use crate::hop_control::{HopFrame, HopParams};
    use crate::tilt::EnergyFeedback;

    #[test]
    fn law_constants_are_the_energy_feedbacks() {
        for (e, g, apex) in [
            (0.5f32, 9.81f32, 0.25f32),
            (0.0, 9.80665, 1.3),
            (1.0, 1.62, 0.3),
        ] {
            let p = TiltParams {
                restitution: e,
                gravity_mps2: g,
                target_apex_m: apex,
                ..TiltParams::default()
            };
            let c = TiltController::new(p).unwrap();
            let f = EnergyFeedback::new(e, p.kappa_e_s2pm2, g * apex, g, p.l_m).unwrap();
            assert_eq!(
                c.law.compensation.to_bits(),
                f.compensation_factor().to_bits()
            );
            assert_eq!(
                c.law.target_energy_jpkg.to_bits(),
                f.target_energy_jpkg().to_bits()
            );
        }
    }

    fn count<P: Fields + Copy>(p: P) -> usize {
        let mut c = Count(0);
        let mut p = p;
        p.fields(&mut c);
        c.0
    }

    /// The flat serde form lists every field once (COUNT is what the walk visits) and is
    /// postcard's derived encoding: the bytes are the fields' own encodings in order.
    #[test]
    fn flat_forms_visit_every_field_and_round_trip_bit_for_bit() {
        assert_eq!(count(TiltParams::default()), TiltParams::COUNT);
        assert_eq!(count(TiltFrame::default()), TiltFrame::COUNT);
        assert_eq!(count(HopParams::default()), HopParams::COUNT);
        assert_eq!(count(HopFrame::default()), HopFrame::COUNT);
        let d = TiltParams::default();
        let p = TiltParams {
            dt_s: f32::from_bits(0x7fc0_1234), // a NaN payload survives
            estimator: FlightTuning {
                memory_samples: 300,
                ..d.estimator
            },
            stale_limit_steps: 40_000,
            contact_iterations: 3,
            ..d
        };
        let bytes = postcard::to_allocvec(&p).unwrap();
        // 34 f32, the u16s 300 and 40000 as 2- and 3-byte varints, four u8
        assert_eq!(bytes.len(), 34 * 4 + 2 + 3 + 4);
        let back: TiltParams = postcard::from_bytes(&bytes).unwrap();
        assert_eq!(back.dt_s.to_bits(), p.dt_s.to_bits());
        assert_eq!(postcard::to_allocvec(&back).unwrap(), bytes);
        // a short message is an error, not a default
        assert!(postcard::from_bytes::<TiltParams>(&bytes[..bytes.len() - 1]).is_err());
        let f = TiltFrame {
            seq: 7,
            body_y_m: -0.5,
            ..TiltFrame::default()
        };
        let bytes = postcard::to_allocvec(&f).unwrap();
        assert_eq!(bytes.len(), 1 + 7 * 4);
        assert_eq!(postcard::from_bytes::<TiltFrame>(&bytes).unwrap(), f);
    }
}
