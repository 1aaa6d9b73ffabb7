//! The fixed-rate line-juggler controller: validate input, estimate, mirror law, track,
//! limit; or the safe state with a fault code.
//!
//! One [`Controller::step`] per control period `dt`: it takes the latest [`SensorFrame`] and
//! returns an [`ActuatorCommand`]. Its work per call is bounded and constant (no loops), it
//! allocates nothing, and it never panics: every input, finite or not, yields either a
//! finite command within the paddle limits, or the safe command with a fault code.
//!
//! ## Safe state
//! On a non-finite or out-of-range measurement, or when the sample sequence number has not
//! advanced for more than `stale_limit_steps` periods, the command is
//! [`Mode::Safe`] with the [`Fault`] and a braking acceleration that brings the last known
//! paddle velocity to rest as fast as `accel_max` allows (the paddle stops where it is; it
//! is not driven anywhere). The estimator is reset. The fault is not latched: the next valid
//! frame restarts estimation, the paddle is held at `home_height_m` ([`Mode::Hold`]) until
//! the estimate is valid again, and then tracks ([`Mode::Track`]).

use crate::estimate::{BallEstimator, Estimate, EstimatorParams};
use crate::fixed_rate::{reply_from_fields, Fault, FixedRate, Mode, Telemetry};
use crate::freshness::Freshness;
use crate::math::Real;
use crate::mirror::{MirrorLaw, PaddleReference};
use crate::params::{finite, positive, within, ParamError};
use crate::state::PaddleState;
use crate::track::{PaddleLimits, Tracker};
use serde::{Deserialize, Serialize};

/// One sample of the line juggler's plant, sent to its controller every control period.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct SensorFrame {
    /// Sample sequence number; a controller that sees it not advance counts the input stale.
    pub seq: u32,
    /// Measured ball height above the impact plane, m (NaN if the sensor lost the ball).
    pub ball_height_m: f32,
    /// Measured paddle height, m.
    pub paddle_height_m: f32,
    /// Measured paddle velocity, m/s.
    pub paddle_velocity_mps: f32,
}

/// The line juggler's output for one control period.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct ActuatorCommand {
    /// Sequence number of the sensor frame this command answers.
    pub seq: u32,
    /// Commanded paddle acceleration, m/s^2, held for one control period (zero-order hold).
    pub paddle_accel_mps2: f32,
    /// Paddle height reference the command tracks, m (informational).
    pub paddle_height_ref_m: f32,
    /// Paddle velocity reference, m/s (informational).
    pub paddle_velocity_ref_mps: f32,
    /// Mode of operation.
    pub mode: Mode,
    /// Fault code; `Fault::None` unless `mode == Mode::Safe`.
    pub fault: Fault,
}

/// Everything a line-juggler controller needs, SI units, f32 (sent over the wire in HIL).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct ControllerParams {
    /// Control period, s (> 0).
    pub dt_s: f32,
    /// Gravity, m/s^2 (> 0).
    pub gravity_mps2: f32,
    /// Mirror gain kappa0, dimensionless, in [0, 1) (Rizzi & Koditschek eq. 5).
    pub kappa0: f32,
    /// Energy-feedback gain kappa1, s^2/m^2 (>= 0) (eq. 5).
    pub kappa1_s2pm2: f32,
    /// Target apex height h*, m (> 0); eta* = g h*.
    pub target_apex_m: f32,
    /// Tracking stiffness, 1/s^2.
    pub kp_per_s2: f32,
    /// Tracking damping, 1/s.
    pub kd_per_s: f32,
    /// Paddle height held while there is no valid estimate, m (within the limits).
    pub home_height_m: f32,
    /// Paddle limits.
    pub limits: PaddleLimits,
    /// Ball estimator tuning.
    pub estimator: EstimatorParams,
    /// Plausible ball heights, m: measurements outside `[min, max]` are a fault.
    pub ball_height_min_m: f32,
    /// See `ball_height_min_m`.
    pub ball_height_max_m: f32,
    /// Periods without a new sample before the input counts as stale (>= 1).
    pub stale_limit_steps: u16,
}

impl Default for ControllerParams {
    /// A 500 Hz controller for a 1 m juggle with restitution 0.8.
    fn default() -> Self {
        let alpha = 0.8f32;
        Self {
            dt_s: 0.002,
            gravity_mps2: 9.81,
            kappa0: (1.0 - alpha) / (1.0 + alpha),
            kappa1_s2pm2: 0.02,
            target_apex_m: 1.0,
            kp_per_s2: 2500.0,
            kd_per_s: 100.0,
            home_height_m: 0.0,
            limits: PaddleLimits::default(),
            estimator: EstimatorParams {
                restitution: alpha,
                ..EstimatorParams::default()
            },
            ball_height_min_m: -0.5,
            ball_height_max_m: 20.0,
            stale_limit_steps: 5,
        }
    }
}

impl ControllerParams {
    /// Check every field; the error names the first bad one.
    pub fn validate(&self) -> Result<(), ParamError> {
        positive("dt_s", self.dt_s)?;
        MirrorLaw::new(
            self.kappa0,
            self.kappa1_s2pm2,
            self.target_apex_m,
            self.gravity_mps2,
        )?;
        Tracker::new(self.kp_per_s2, self.kd_per_s, self.limits, self.dt_s)?;
        within(
            "home_height_m",
            self.home_height_m,
            self.limits.min_height_m,
            self.limits.max_height_m,
        )?;
        self.estimator.validate()?;
        finite("ball_height_min_m", self.ball_height_min_m)?;
        finite("ball_height_max_m", self.ball_height_max_m)?;
        if self.ball_height_max_m <= self.ball_height_min_m {
            return Err(ParamError::OutOfRange("ball_height_max_m"));
        }
        if self.stale_limit_steps == 0 {
            return Err(ParamError::NotPositive("stale_limit_steps"));
        }
        Ok(())
    }
}

/// The line-juggler controller (mirror law + estimator + tracker), stepped at a fixed rate.
#[derive(Clone, Debug)]
pub struct Controller {
    params: ControllerParams,
    law: MirrorLaw<f32>,
    tracker: Tracker,
    estimator: BallEstimator,
    estimate: Estimate,
    /// Whether each frame carries a new sample.
    seq: Freshness,
    /// Last valid paddle measurement, dead-reckoned with our own commands while faulted.
    paddle: PaddleState<f32>,
    /// Plausible paddle measurements, computed once from the limits (see [`Self::check`]).
    plausible: PlausiblePaddle,
}

/// The plausible range of a paddle measurement: the travel range widened by 5 % of its
/// length on each side, and speeds up to twice the limit. Computed once (it depends only on
/// the parameters), so the step does not recompute it.
#[derive(Clone, Copy, Debug)]
struct PlausiblePaddle {
    min_height_m: f32,
    max_height_m: f32,
    max_speed_mps: f32,
}

impl PlausiblePaddle {
    /// Saturated at the largest finite `f32`s, so the bounds are finite for any valid
    /// limits (however large): [`Controller::check`] relies on a non-finite measurement
    /// failing them.
    fn new(l: &PaddleLimits) -> Self {
        let travel_margin_m = 0.05 * (l.max_height_m - l.min_height_m);
        Self {
            min_height_m: (l.min_height_m - travel_margin_m).max_r(f32::MIN),
            max_height_m: (l.max_height_m + travel_margin_m).min_r(f32::MAX),
            max_speed_mps: (2.0 * l.velocity_max_mps).min_r(f32::MAX),
        }
    }
}

impl Controller {
    /// The mirror law in use.
    pub fn law(&self) -> &MirrorLaw<f32> {
        &self.law
    }

    /// The latest ball estimate.
    pub fn estimate(&self) -> &Estimate {
        &self.estimate
    }

    /// Validate a frame; `Ok(true)` if it carries a new sample, `Ok(false)` if it repeats
    /// the last one (within the stale limit).
    fn check(&mut self, frame: &SensorFrame) -> Result<bool, Fault> {
        let p = &self.params;
        let q = &self.plausible;
        let ball_range = p.ball_height_min_m..=p.ball_height_max_m;
        let paddle_range = q.min_height_m..=q.max_height_m;
        // NaN fails every comparison, so one pass of range checks also rejects every
        // non-finite frame (the bounds are finite); only a rejected frame pays for telling
        // the two faults apart
        if !(ball_range.contains(&frame.ball_height_m)
            && paddle_range.contains(&frame.paddle_height_m)
            && frame.paddle_velocity_mps.abs() <= q.max_speed_mps)
        {
            let values = [
                frame.ball_height_m,
                frame.paddle_height_m,
                frame.paddle_velocity_mps,
            ];
            return Err(if values.iter().any(|v| !v.is_finite()) {
                Fault::NonFinite
            } else {
                Fault::OutOfRange
            });
        }
        // a sample is new if its sequence number moved forward (wrapping arithmetic)
        self.seq.check(frame.seq, self.params.stale_limit_steps)
    }
}

impl FixedRate for Controller {
    type Params = ControllerParams;
    type Frame = SensorFrame;
    type Command = ActuatorCommand;
    /// The line-juggler goal (BENCHMARKS.md, "Control step on the target").
    const STEP_INSTRUCTION_BUDGET: u32 = 300;

    /// A controller; the error names the first invalid parameter.
    fn new(params: ControllerParams) -> Result<Self, ParamError> {
        params.validate()?;
        let law = MirrorLaw::new(
            params.kappa0,
            params.kappa1_s2pm2,
            params.target_apex_m,
            params.gravity_mps2,
        )?;
        let tracker = Tracker::new(
            params.kp_per_s2,
            params.kd_per_s,
            params.limits,
            params.dt_s,
        )?;
        let estimator = BallEstimator::new(params.estimator, params.dt_s, params.gravity_mps2)?;
        Ok(Self {
            params,
            law,
            tracker,
            estimator,
            estimate: Estimate::default(),
            seq: Freshness::new(),
            paddle: PaddleState::new(params.home_height_m, 0.0),
            plausible: PlausiblePaddle::new(&params.limits),
        })
    }

    /// The parameters this controller runs with.
    fn params(&self) -> &ControllerParams {
        &self.params
    }

    /// One control period: the command for `frame`.
    fn step(&mut self, frame: &SensorFrame) -> ActuatorCommand {
        match self.check(frame) {
            Err(fault) => self.safe(frame.seq, fault),
            Ok(fresh) => {
                let paddle = PaddleState::new(frame.paddle_height_m, frame.paddle_velocity_mps);
                self.paddle = paddle;
                let estimate = if fresh {
                    self.estimator.update(frame.ball_height_m, &paddle)
                } else {
                    self.estimator.coast(&paddle)
                };
                // Field by field: a whole-struct copy stored the two flags as bytes and
                // read them back as one word, a store-forwarding stall on every step.
                self.estimate.ball = estimate.ball;
                self.estimate.valid = estimate.valid;
                self.estimate.impact = estimate.impact;
                let (reference, mode) = if self.estimate.valid {
                    let r = self
                        .tracker
                        .clamp_reference(self.law.reference(&self.estimate.ball));
                    (r, Mode::Track)
                } else {
                    let home = PaddleReference {
                        height_m: self.params.home_height_m,
                        velocity_mps: 0.0,
                        accel_mps2: 0.0,
                    };
                    (home, Mode::Hold)
                };
                ActuatorCommand {
                    seq: frame.seq,
                    paddle_accel_mps2: self.tracker.command(&reference, &paddle),
                    paddle_height_ref_m: reference.height_m,
                    paddle_velocity_ref_mps: reference.velocity_mps,
                    mode,
                    fault: Fault::None,
                }
            }
        }
    }

    /// The safe command for an external fault (e.g. the firmware's link timeout).
    fn safe(&mut self, seq: u32, fault: Fault) -> ActuatorCommand {
        self.estimator.reset();
        self.estimate.valid = false;
        let u = self.tracker.brake_and_coast(&mut self.paddle);
        ActuatorCommand {
            seq,
            paddle_accel_mps2: u,
            paddle_height_ref_m: self.paddle.height_m,
            paddle_velocity_ref_mps: 0.0,
            mode: Mode::Safe,
            fault,
        }
    }

    /// Telemetry fields the core knows (the firmware adds timing and link counts): estimate
    /// slot 0 is the ball height, m, slot 1 its velocity, m/s.
    fn telemetry(&self) -> Telemetry {
        let ball = &self.estimate.ball;
        Telemetry::with_estimate(&[ball.height_m, ball.velocity_mps], self.estimate.valid)
    }
}

reply_from_fields!(ActuatorCommand);

#[cfg(test)]
mod tests {
    use super::*;
    use crate::fixed_rate::Reply;

    fn frame(seq: u32, ball: f32) -> SensorFrame {
        SensorFrame {
            seq,
            ball_height_m: ball,
            paddle_height_m: 0.0,
            paddle_velocity_mps: 0.0,
        }
    }

    #[test]
    fn holds_home_until_estimate_is_valid_then_tracks() {
        let mut c = Controller::new(ControllerParams::default()).unwrap();
        let g = 9.81f32;
        let mut mode = Mode::Hold;
        for k in 0..60u32 {
            let t = k as f32 * 0.002;
            let cmd = c.step(&frame(k, 1.0 - 0.5 * g * t * t));
            if k == 0 {
                assert_eq!(cmd.mode, Mode::Hold);
            }
            mode = cmd.mode;
            assert!(cmd.paddle_accel_mps2.abs() <= 200.0);
        }
        assert_eq!(mode, Mode::Track);
        // reference is the mirror image: r = -k b with b ~ 1 - ... > 0, so r < 0
        let cmd = c.step(&frame(60, 0.5));
        assert!(cmd.paddle_height_ref_m < 0.0);
    }

    #[test]
    fn nan_and_out_of_range_give_safe_state_with_fault() {
        let mut c = Controller::new(ControllerParams::default()).unwrap();
        let cmd = c.step(&frame(0, f32::NAN));
        assert_eq!((cmd.mode, cmd.fault), (Mode::Safe, Fault::NonFinite));
        let cmd = c.step(&frame(1, 1e6));
        assert_eq!((cmd.mode, cmd.fault), (Mode::Safe, Fault::OutOfRange));
        let mut f = frame(2, 0.5);
        f.paddle_velocity_mps = f32::INFINITY;
        assert_eq!(c.step(&f).fault, Fault::NonFinite);
        // recovers on valid input
        assert_eq!(c.step(&frame(3, 0.5)).fault, Fault::None);
    }

    /// Every non-finite field is `NonFinite`, also with limits so large that the plausible
    /// range (the travel widened by 5 %, twice the speed limit) exceeds `f32` and must
    /// saturate: the step's single pass of range checks relies on finite bounds.
    #[test]
    fn non_finite_fields_are_refused_even_with_the_largest_limits() {
        let mut huge = ControllerParams::default();
        huge.limits.min_height_m = -f32::MAX;
        huge.limits.max_height_m = f32::MAX;
        huge.limits.velocity_max_mps = f32::MAX;
        huge.home_height_m = 0.0;
        for params in [ControllerParams::default(), huge] {
            let mut c = Controller::new(params).unwrap();
            for bad in [f32::NAN, f32::INFINITY, f32::NEG_INFINITY] {
                for field in 0..3 {
                    let mut f = frame(0, 0.5);
                    match field {
                        0 => f.ball_height_m = bad,
                        1 => f.paddle_height_m = bad,
                        _ => f.paddle_velocity_mps = bad,
                    }
                    let cmd = c.step(&f);
                    assert_eq!(cmd.fault, Fault::NonFinite, "field {field} = {bad}");
                }
            }
            // a finite measurement far out of range is the other fault
            let mut f = frame(0, 0.5);
            f.paddle_height_m = 1e3;
            let want = if params.limits.max_height_m > 1e3 {
                Fault::None
            } else {
                Fault::OutOfRange
            };
            assert_eq!(c.step(&f).fault, want);
        }
    }

    #[test]
    fn repeated_sequence_number_becomes_stale_after_the_limit() {
        let mut c = Controller::new(ControllerParams::default()).unwrap();
        assert_eq!(c.step(&frame(10, 0.5)).fault, Fault::None);
        for _ in 0..5 {
            assert_eq!(c.step(&frame(10, 0.5)).fault, Fault::None);
        }
        let cmd = c.step(&frame(10, 0.5));
        assert_eq!((cmd.mode, cmd.fault), (Mode::Safe, Fault::Stale));
        assert_eq!(c.step(&frame(11, 0.5)).fault, Fault::None);
    }

    #[test]
    fn safe_state_brakes_the_paddle_to_rest() {
        let mut c = Controller::new(ControllerParams::default()).unwrap();
        let mut f = frame(0, 0.5);
        f.paddle_velocity_mps = 1.0;
        c.step(&f);
        let mut v = 1.0f32;
        for k in 0..10 {
            let cmd = c.step(&frame(1 + k, f32::NAN));
            v += cmd.paddle_accel_mps2 * 0.002;
        }
        assert!(v.abs() < 1e-5, "paddle still moving at {v}");
    }

    /// A settled controller: a ball in free fall from 1 m for 40 steps (valid after 27).
    fn tracking_controller() -> (Controller, u32) {
        let mut c = Controller::new(ControllerParams::default()).unwrap();
        let g = 9.81f32;
        for k in 0..40u32 {
            let t = k as f32 * 0.002;
            assert_eq!(c.step(&frame(k, 1.0 - 0.5 * g * t * t)).fault, Fault::None);
        }
        (c, 40)
    }

    #[test]
    fn telemetry_reports_the_estimate() {
        let (c, _) = tracking_controller();
        let t = c.telemetry();
        let e = c.estimate();
        assert!(e.valid && t.estimate_valid);
        let [height_m, velocity_mps, unused] = t.estimate;
        assert_eq!(height_m, e.ball.height_m);
        assert_eq!(velocity_mps, e.ball.velocity_mps);
        assert_eq!(unused, 0.0);
        // the estimate is the falling ball at step 39: b = 1 - g t^2/2, v = -g t
        let t39 = 39.0 * 0.002f32;
        assert!((height_m - (1.0 - 0.5 * 9.81 * t39 * t39)).abs() < 1e-5);
        assert!((velocity_mps + 9.81 * t39).abs() < 1e-3);
        assert!(height_m != 0.0 && velocity_mps != 0.0);
    }

    /// The safe state dead-reckons the paddle under its own braking command, by hand:
    /// from (0.05 m, 1 m/s) with a_max = 200 m/s^2 and dt = 2 ms, u = max(-v/dt, -200):
    /// u = -200 -> (0.0516, 0.6); u = -200 -> (0.0524, 0.2); u = -100 -> (0.0526, 0).
    #[test]
    fn safe_state_dead_reckons_the_paddle_by_hand() {
        let mut c = Controller::new(ControllerParams::default()).unwrap();
        let mut f = frame(0, 0.5);
        f.paddle_height_m = 0.05;
        f.paddle_velocity_mps = 1.0;
        c.step(&f);
        let want = [
            (-200.0, 0.0516),
            (-200.0, 0.0524),
            (-100.0, 0.0526),
            (0.0, 0.0526),
        ];
        for (k, (u, h)) in want.into_iter().enumerate() {
            let cmd = c.step(&frame(1 + k as u32, f32::NAN));
            assert_eq!((cmd.mode, cmd.fault), (Mode::Safe, Fault::NonFinite));
            assert!(
                (cmd.paddle_accel_mps2 - u).abs() < 1e-2,
                "step {k}: {cmd:?}"
            );
            assert!(
                (cmd.paddle_height_ref_m - h).abs() < 1e-6,
                "step {k}: {cmd:?}"
            );
            assert_eq!(cmd.paddle_velocity_ref_mps, 0.0);
        }
    }

    /// Plausible measurements: the ball in [ball_height_min_m, ball_height_max_m]
    /// (inclusive), the paddle within its travel widened by 5 % of its length on each side
    /// (limits -0.3..0.1 m: -0.32..0.12 m), paddle speed up to twice the limit (6 m/s).
    #[test]
    fn plausible_ranges_by_hand() {
        let p = ControllerParams::default();
        let cases: [(f32, f32, f32, bool); 12] = [
            (-0.5, 0.0, 0.0, true),
            (20.0, 0.0, 0.0, true),
            (-0.5001, 0.0, 0.0, false),
            (20.001, 0.0, 0.0, false),
            (0.5, -0.3199, 0.0, true),
            (0.5, -0.3201, 0.0, false),
            (0.5, 0.1199, 0.0, true),
            (0.5, 0.1201, 0.0, false),
            (0.5, 0.0, 6.0, true),
            (0.5, 0.0, -6.0, true),
            (0.5, 0.0, 6.001, false),
            (0.5, 0.0, -6.001, false),
        ];
        for (n, (ball, paddle, speed, ok)) in cases.into_iter().enumerate() {
            let mut c = Controller::new(p).unwrap();
            let cmd = c.step(&SensorFrame {
                seq: 0,
                ball_height_m: ball,
                paddle_height_m: paddle,
                paddle_velocity_mps: speed,
            });
            let want = if ok { Fault::None } else { Fault::OutOfRange };
            assert_eq!(cmd.fault, want, "case {n}: {cmd:?}");
        }
    }

    /// A sequence number is new if it moved forward by 1 ..= 2^31 - 2 (wrapping); a jump of
    /// 2^31 - 1 or more counts as going back (a repeat: stale after the limit).
    #[test]
    fn sequence_numbers_move_forward_with_wrapping() {
        let mut c = Controller::new(ControllerParams::default()).unwrap();
        c.step(&frame(u32::MAX - 1, 0.5));
        // wraps forward: u32::MAX, 0, 1 are new samples (the stale count never grows)
        for seq in [u32::MAX, 0, 1] {
            for _ in 0..6 {
                assert_eq!(c.step(&frame(seq, 0.5)).fault, Fault::None);
            }
        }
        let far = 1u32.wrapping_add(u32::MAX / 2 - 1);
        assert_eq!(c.step(&frame(far, 0.5)).fault, Fault::None);
        let beyond = far.wrapping_add(u32::MAX / 2);
        let faults: Vec<Fault> = (0..6).map(|_| c.step(&frame(beyond, 0.5)).fault).collect();
        assert_eq!(faults[..5], [Fault::None; 5], "5 repeats are tolerated");
        assert_eq!(faults[5], Fault::Stale);
    }

    #[test]
    fn reply_answers_are_the_commands_own_fields() {
        let (mut c, seq) = tracking_controller();
        let track = c.step(&frame(seq, 0.2));
        assert_eq!(
            (track.seq(), track.mode(), track.fault()),
            (seq, Mode::Track, Fault::None)
        );
        let safe = c.safe(77, Fault::LinkTimeout);
        assert_eq!(
            (safe.seq(), safe.mode(), safe.fault()),
            (77, Mode::Safe, Fault::LinkTimeout)
        );
    }

    #[test]
    fn invalid_params_are_named() {
        let p = ControllerParams {
            kappa0: 1.2,
            ..ControllerParams::default()
        };
        assert_eq!(
            Controller::new(p).unwrap_err(),
            ParamError::OutOfRange("kappa0")
        );
        let p = ControllerParams {
            home_height_m: 5.0,
            ..ControllerParams::default()
        };
        assert_eq!(
            Controller::new(p).unwrap_err(),
            ParamError::OutOfRange("home_height_m")
        );
    }

    #[test]
    fn bit_identical_tells_signed_zeros_and_nan_payloads_apart() {
        let a = ActuatorCommand::default();
        let mut b = a;
        assert!(a.bit_identical(&b));
        b.paddle_accel_mps2 = -0.0;
        assert!(!a.bit_identical(&b), "+0 and -0 differ in their bits");
        b = a;
        b.fault = Fault::Stale;
        assert!(!a.bit_identical(&b));
        b = a;
        b.seq = 1;
        assert!(!a.bit_identical(&b));
    }
}
