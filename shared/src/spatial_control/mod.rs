//! The spatial juggler's fixed-rate controller: a camera's ball positions and three joint
//! encoders in, three joint accelerations out (Rizzi & Koditschek 1994, sec. 3.1.2, eq. 13
//! with k(w) of eq. 5, [`SpatialMirrorLaw`]).
//!
//! One [`FixedRate::step`] per control period `dt`:
//!
//! 1. **check** the frame: joint angles within their limits (5 % of each range of margin),
//!    joint rates within twice their speed limits, the ball within `ball_range_m` of the
//!    base in each coordinate; a NaN or infinite value is [`Fault::NonFinite`], an
//!    implausible one [`Fault::OutOfRange`], a sequence number that stops advancing for more
//!    than `stale_limit_steps` periods [`Fault::Stale`];
//! 2. **estimate** the ball ([`estimate`]): the three-axis alpha-beta filter around the
//!    ballistic flight, with the paddle's restitution law where the predicted ball crosses
//!    the paddle's plane at the measured joints moved back by the camera's latency;
//! 3. **law**: the joint references of eq. 13 at the estimate, and their rates along the
//!    ballistic flow ([`SpatialMirrorLaw::reference`]); the acceleration feed-forward is the
//!    change of those rates over one period of the flow,
//!    `r'' = (r'(F^dt(w)) - r'(w)) / dt` (the flow is exact, so this differences no noise);
//! 4. **track** each joint with the PD-plus-feed-forward [`Tracker`] within its position,
//!    velocity and acceleration limits. Until the estimate is valid, or while the law is
//!    undefined (the ball over the base), the joints are held at `home_rad` ([`Mode::Hold`]).
//!
//! ## Safe state
//! As the line juggler's ([`crate::control`]): on a fault each joint is braked to rest where
//! it is, as fast as its acceleration limit allows, from the last measured joint state
//! dead-reckoned under those commands; the estimator is reset. The fault is not latched: the
//! next valid frame restarts estimation ([`Mode::Hold`], then [`Mode::Track`]).
//!
//! ## Work per step
//! No loop runs more than three times and none depends on the input: three polynomial
//! sine/cosine pairs (the paddle's frame for the estimator), two evaluations of the law (two
//! `atan2`s and a handful of square roots each), three trackers. The static worst case is
//! published with [`FixedRate::STEP_INSTRUCTION_BUDGET`].

pub mod estimate;

use self::estimate::{SpatialEstimate, SpatialEstimator};
use crate::estimate::EstimatorParams;
use crate::fixed_rate::{reply_from_fields, Fault, FixedRate, Mode, Telemetry};
use crate::freshness::Freshness;
use crate::math::sin_cos_poly_f32;
use crate::mirror::PaddleReference;
use crate::params::{finite, positive, ParamError};
use crate::spatial::{PaddleFrame, SpatialLawParams, SpatialMirrorLaw};
use crate::state::PaddleState;
use crate::track::{PaddleLimits, Tracker};
use serde::{Deserialize, Serialize};

/// Limits of one joint, SI units.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct AxisLimits {
    /// Lowest angle, rad.
    pub min_rad: f32,
    /// Highest angle, rad (> min).
    pub max_rad: f32,
    /// Largest speed, rad/s (> 0).
    pub velocity_max_radps: f32,
    /// Largest commanded acceleration, rad/s^2 (> 0).
    pub accel_max_radps2: f32,
}

impl AxisLimits {
    /// The same limits in the tracker's (unit-agnostic) form.
    fn tracker_limits(&self) -> PaddleLimits {
        PaddleLimits {
            min_height_m: self.min_rad,
            max_height_m: self.max_rad,
            velocity_max_mps: self.velocity_max_radps,
            accel_max_mps2: self.accel_max_radps2,
        }
    }

    /// Check every field under `names` (min, max, velocity, acceleration), so that the
    /// tracker built from them cannot reject them.
    fn validate(&self, names: [&'static str; 4]) -> Result<(), ParamError> {
        finite(names[0], self.min_rad)?;
        finite(names[1], self.max_rad)?;
        if self.max_rad <= self.min_rad {
            return Err(ParamError::OutOfRange(names[1]));
        }
        positive(names[2], self.velocity_max_radps)?;
        positive(names[3], self.accel_max_radps2)?;
        Ok(())
    }

    /// Whether a measured angle and rate are plausible: within the range widened by 5 % at
    /// each end, and within twice the speed limit (false for NaN).
    #[inline]
    fn plausible(&self, angle_rad: f32, rate_radps: f32) -> bool {
        let margin = 0.05 * (self.max_rad - self.min_rad);
        angle_rad >= self.min_rad - margin
            && angle_rad <= self.max_rad + margin
            && rate_radps.abs() <= 2.0 * self.velocity_max_radps
    }
}

/// The scene-facing names of each joint's limits, for validation errors.
const LIMIT_NAMES: [[&str; 4]; 3] = [
    [
        "limits.q1.min_rad",
        "limits.q1.max_rad",
        "limits.q1.velocity_max_radps",
        "limits.q1.accel_max_radps2",
    ],
    [
        "limits.q2.min_rad",
        "limits.q2.max_rad",
        "limits.q2.velocity_max_radps",
        "limits.q2.accel_max_radps2",
    ],
    [
        "limits.q3.min_rad",
        "limits.q3.max_rad",
        "limits.q3.velocity_max_radps",
        "limits.q3.accel_max_radps2",
    ],
];

/// Everything a spatial juggler's controller needs, SI units, f32 (sent over the wire in
/// HIL).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct SpatialControlParams {
    /// Control period, s (> 0): the camera samples once per period.
    pub dt_s: f32,
    /// The law's gains, set point and gravity (eq. 13, validated by
    /// [`SpatialMirrorLaw::new`]).
    pub law: SpatialLawParams<f32>,
    /// Tracking stiffness, 1/s^2 (>= 0), every joint.
    pub kp_per_s2: f32,
    /// Tracking damping, 1/s (>= 0), every joint.
    pub kd_per_s: f32,
    /// Limits of q1 (azimuth), q2 (shoulder) and q3 (paddle roll).
    pub limits: [AxisLimits; 3],
    /// Joint angles held while there is no valid estimate, rad (within the limits).
    pub home_rad: [f32; 3],
    /// Ball estimator tuning (the line juggler's: gains, gate, latency, restitution).
    pub estimator: EstimatorParams,
    /// Plausible ball positions, m (> 0): a coordinate farther than this from the base is
    /// a fault.
    pub ball_range_m: f32,
    /// Periods without a new sample before the input counts as stale (>= 1).
    pub stale_limit_steps: u16,
}

impl Default for SpatialControlParams {
    /// A 1 kHz controller for a 0.5 m juggle over (rho*, phi*) = (1 m, 0) with restitution
    /// 0.7 ([`SpatialLawParams::suggested`]).
    fn default() -> Self {
        let alpha = 0.7;
        let axis = |min_rad, max_rad| AxisLimits {
            min_rad,
            max_rad,
            velocity_max_radps: 20.0,
            accel_max_radps2: 500.0,
        };
        Self {
            dt_s: 0.001,
            law: SpatialLawParams::suggested(false, alpha, 9.81, 0.5, 1.0, 0.0),
            kp_per_s2: 2500.0,
            kd_per_s: 100.0,
            limits: [axis(-3.0, 3.0), axis(-2.8, -0.35), axis(-1.0, 1.0)],
            home_rad: [0.0, -1.65, 0.0],
            // low gains: the model (flight and restitution) carries the ball between
            // samples; measured on scenes/spatial-juggler-sil.toml (docs/spatial.md)
            estimator: EstimatorParams {
                gain_position: 0.02,
                gain_velocity: 0.0002,
                restitution: alpha,
                ..EstimatorParams::default()
            },
            ball_range_m: 10.0,
            stale_limit_steps: 5,
        }
    }
}

impl SpatialControlParams {
    /// Check every field; the error names the first bad one.
    pub fn validate(&self) -> Result<(), ParamError> {
        positive("dt_s", self.dt_s)?;
        law_of(&self.law)?;
        crate::params::non_negative("kp_per_s2", self.kp_per_s2)?;
        crate::params::non_negative("kd_per_s", self.kd_per_s)?;
        for (l, names) in self.limits.iter().zip(LIMIT_NAMES) {
            l.validate(names)?;
        }
        const HOME: [&str; 3] = ["home_rad.q1", "home_rad.q2", "home_rad.q3"];
        for ((l, h), name) in self.limits.iter().zip(self.home_rad).zip(HOME) {
            crate::params::within(name, h, l.min_rad, l.max_rad)?;
        }
        self.estimator.validate()?;
        positive("ball_range_m", self.ball_range_m)?;
        if self.stale_limit_steps == 0 {
            return Err(ParamError::NotPositive("stale_limit_steps"));
        }
        Ok(())
    }
}

/// eq. 13 of `p`, with the set point's direction from the core's polynomial sine.
fn law_of(p: &SpatialLawParams<f32>) -> Result<SpatialMirrorLaw<f32>, ParamError> {
    let phi = finite("target_azimuth_rad", p.target_azimuth_rad)?;
    SpatialMirrorLaw::with_direction(*p, sin_cos_poly_f32(phi))
}

/// One sample of the spatial juggler's plant, sent to its controller every control period.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct SpatialFrame {
    /// Sample sequence number: a frame whose number did not advance repeats the last camera
    /// sample (the estimator coasts); for more than `stale_limit_steps` periods, a fault.
    pub seq: u32,
    /// The camera's ball position (b_x, b_y, b_z), m, taken `estimator.latency_s` ago.
    pub ball_m: [f32; 3],
    /// Joint angles (q1, q2, q3), rad, now.
    pub joints_rad: [f32; 3],
    /// Joint rates, rad/s, now.
    pub joint_rates_radps: [f32; 3],
}

/// The spatial juggler's output for one control period.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct SpatialCommand {
    /// Sequence number of the frame this command answers.
    pub seq: u32,
    /// Joint accelerations, rad/s^2, held for one period (zero-order hold); each within its
    /// joint's `accel_max_radps2`.
    pub accel_radps2: [f32; 3],
    /// The joint angles the command tracks, rad (informational).
    pub angle_ref_rad: [f32; 3],
    /// Mode of operation.
    pub mode: Mode,
    /// Fault code; [`Fault::None`] unless `mode == Mode::Safe`.
    pub fault: Fault,
}

reply_from_fields!(SpatialCommand);

/// The spatial juggler's controller (eq. 13, estimator, three trackers), stepped at a fixed
/// rate.
#[derive(Clone, Debug)]
pub struct SpatialController {
    params: SpatialControlParams,
    law: SpatialMirrorLaw<f32>,
    trackers: [Tracker; 3],
    estimator: SpatialEstimator,
    estimate: SpatialEstimate,
    seq: Freshness,
    /// Last measured joints, dead-reckoned under our own commands while faulted.
    joints: [PaddleState<f32>; 3],
}

impl SpatialController {
    /// The law the controller runs.
    pub fn law(&self) -> &SpatialMirrorLaw<f32> {
        &self.law
    }

    /// The latest ball estimate.
    pub fn estimate(&self) -> &SpatialEstimate {
        &self.estimate
    }

    /// Validate a frame; `Ok(true)` if it carries a new sample.
    fn check(&mut self, frame: &SpatialFrame) -> Result<bool, Fault> {
        let r = self.params.ball_range_m;
        let joints_ok = (0..3).all(|i| {
            self.params.limits[i].plausible(frame.joints_rad[i], frame.joint_rates_radps[i])
        });
        // NaN fails every comparison: one pass rejects every non-finite frame too, and only
        // a rejected frame pays for telling the two faults apart
        if !(joints_ok && frame.ball_m.iter().all(|b| b.abs() <= r)) {
            let finite = frame
                .ball_m
                .iter()
                .chain(&frame.joints_rad)
                .chain(&frame.joint_rates_radps)
                .all(|v| v.is_finite());
            return Err(if finite {
                Fault::OutOfRange
            } else {
                Fault::NonFinite
            });
        }
        self.seq.check(frame.seq, self.params.stale_limit_steps)
    }

    /// The paddle's frame at the camera's sample time: the measured joints moved back by
    /// the latency.
    fn paddle_at_sample_time(&self, frame: &SpatialFrame) -> PaddleFrame<f32> {
        let l = self.params.estimator.latency_s;
        let [q1, q2, q3] = frame.joints_rad;
        let [w1, w2, w3] = frame.joint_rates_radps;
        let e = q2 + core::f32::consts::FRAC_PI_2;
        PaddleFrame::from_sin_cos(
            [
                sin_cos_poly_f32(q1 - w1 * l),
                sin_cos_poly_f32(e - w2 * l),
                sin_cos_poly_f32(q3 - w3 * l),
            ],
            frame.joint_rates_radps,
        )
    }

    /// The references of eq. 13 at the estimate with the flow's acceleration, or `None`
    /// where the law is undefined (non-finite: the ball over the base).
    fn references(&self) -> Option<[PaddleReference<f32>; 3]> {
        let ball = &self.estimate.ball;
        let g = self.params.law.gravity_mps2;
        let dt = self.params.dt_s;
        let r = self.law.reference(ball);
        let next = self.law.reference(&ball.flown(dt, g));
        let refs: [PaddleReference<f32>; 3] = core::array::from_fn(|i| PaddleReference {
            height_m: r.angles_rad[i],
            velocity_mps: r.rates_radps[i],
            accel_mps2: (next.rates_radps[i] - r.rates_radps[i]) / dt,
        });
        let finite = refs
            .iter()
            .all(|r| (r.height_m + r.velocity_mps + r.accel_mps2).is_finite());
        finite.then_some(refs)
    }

    /// Hold the joints at home.
    fn home(&self) -> [PaddleReference<f32>; 3] {
        core::array::from_fn(|i| PaddleReference {
            height_m: self.params.home_rad[i],
            velocity_mps: 0.0,
            accel_mps2: 0.0,
        })
    }
}

impl FixedRate for SpatialController {
    type Params = SpatialControlParams;
    type Frame = SpatialFrame;
    type Command = SpatialCommand;
    /// 1 500 instructions, for every input and every configuration the validator accepts:
    /// the step has no input-dependent loop (module docs, "Work per step"), and the static
    /// worst case over every path of `<SpatialController as FixedRate>::step` in the spatial
    /// image as flashed, callees included (`scripts/wcet.py`, run by `scripts/test.sh` with
    /// `--max-instructions 1490`), is 1 443 instructions, 2 897 Cortex-M4 cycles
    /// (2026-12-07; 3 divisions and 6 square roots on that path; 1 442 and 2 892 on
    /// 2026-12-04). The HIL measurement
    /// window adds about 8, as for the arm's.
    const STEP_INSTRUCTION_BUDGET: u32 = 1500;

    /// A controller; the error names the first invalid parameter.
    #[inline(never)]
    fn new(params: SpatialControlParams) -> Result<Self, ParamError> {
        params.validate()?;
        let law = law_of(&params.law)?;
        let tracker = |l: &AxisLimits| {
            Tracker::new(
                params.kp_per_s2,
                params.kd_per_s,
                l.tracker_limits(),
                params.dt_s,
            )
        };
        let [l1, l2, l3] = &params.limits;
        let trackers = [tracker(l1)?, tracker(l2)?, tracker(l3)?];
        let estimator =
            SpatialEstimator::new(params.estimator, params.dt_s, params.law.gravity_mps2)?;
        Ok(Self {
            params,
            law,
            trackers,
            estimator,
            estimate: SpatialEstimate::default(),
            seq: Freshness::new(),
            joints: core::array::from_fn(|i| PaddleState::new(params.home_rad[i], 0.0)),
        })
    }

    fn params(&self) -> &SpatialControlParams {
        &self.params
    }

    /// One control period: the command for `frame`. Out of line, so the firmware has one
    /// symbol for the static worst-case tool (`scripts/wcet.py`).
    #[inline(never)]
    fn step(&mut self, frame: &SpatialFrame) -> SpatialCommand {
        let fresh = match self.check(frame) {
            Ok(fresh) => fresh,
            Err(fault) => return self.safe(frame.seq, fault),
        };
        self.joints = core::array::from_fn(|i| {
            PaddleState::new(frame.joints_rad[i], frame.joint_rates_radps[i])
        });
        let paddle = self.paddle_at_sample_time(frame);
        self.estimate = self.estimator.step(fresh.then_some(&frame.ball_m), &paddle);
        let tracked = match self.estimate.valid {
            true => self.references(),
            false => None,
        };
        let (refs, mode) = match tracked {
            Some(r) => (r, Mode::Track),
            None => (self.home(), Mode::Hold),
        };
        let mut cmd = SpatialCommand {
            seq: frame.seq,
            mode,
            ..SpatialCommand::default()
        };
        for (i, (t, r)) in self.trackers.iter().zip(refs).enumerate() {
            let r = t.clamp_reference(r);
            cmd.accel_radps2[i] = t.command(&r, &self.joints[i]);
            cmd.angle_ref_rad[i] = r.height_m;
        }
        cmd
    }

    /// The safe command: brake every joint to rest where it is; forget the ball.
    fn safe(&mut self, seq: u32, fault: Fault) -> SpatialCommand {
        self.estimator.reset();
        self.estimate.valid = false;
        let mut cmd = SpatialCommand {
            seq,
            mode: Mode::Safe,
            fault,
            ..SpatialCommand::default()
        };
        for (i, (t, j)) in self.trackers.iter().zip(&mut self.joints).enumerate() {
            cmd.accel_radps2[i] = t.brake_and_coast(j);
            cmd.angle_ref_rad[i] = j.height_m;
        }
        cmd
    }

    /// The ball's height (m), vertical velocity (m/s) and horizontal radius (m).
    fn telemetry(&self) -> Telemetry {
        let b = &self.estimate.ball;
        Telemetry::with_estimate(
            &[b.position_m[2], b.velocity_mps[2], b.horizontal_radius_m()],
            self.estimate.valid,
        )
    }
}

#[cfg(test)]
mod tests;
