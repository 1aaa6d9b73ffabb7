//! The fixed-rate trajectory tracker of the one-joint arm (Akella, Huang, Lynch & Mason,
//! sec. 2): it plays a planned cubic B-spline joint trajectory ([`crate::bspline`]) and
//! tracks it with the existing PD-plus-feed-forward [`Tracker`], then turns the
//! acceleration command into a joint torque within the motor's limit.
//!
//! ## Time
//! The core owns no clock: trajectory time is `t = (seq - seq_0) dt`, where `seq_0` is the
//! sequence number of the first valid frame. A lost frame therefore does not delay the
//! trajectory.
//!
//! ## Reference
//! For `t` in `[0, T]` the reference is the spline (angle, velocity and acceleration as
//! feed-forward). After `T` the joint moves to rest by the time-optimal bang-bang of
//! [`crate::bang_bang`] under `brake_accel_radps2` and the speed limit, then holds:
//! without `catches` it brakes from the spline's end velocity `w_T` to rest
//! wherever that stops it (the paper's release: "the arm is maximally decelerated at the
//! release point"),
//!
//! ```text
//! theta_ref(T + s) = theta_T + w_T s - sgn(w_T) a_b s^2 / 2,   s <= |w_T| / a_b
//! theta_ref        = theta_T + sgn(w_T) w_T^2 / (2 a_b),        afterwards
//! ```
//!
//! and with it, it reaches rest at `catch_angle_rad` (sec. 2.5: "if the arm is also to catch the
//! object, it follows a bang-bang trajectory to reach the catching configuration"). The
//! move is computed once, by [`FixedRate::new`]; a step evaluates one of its arcs.
//!
//! The reference is clamped into the joint limits as the tracker does for the paddle.
//!
//! ## Torque
//! The tracker's acceleration command `u` (within `±accel_max_radps2`) becomes the joint
//! torque by the rigid-arm inverse dynamics
//!
//! ```text
//! tau = J u + tau_g cos(theta + phi_g)
//! ```
//!
//! with `J` the inertia about the joint (arm and payload), `tau_g` the gravity torque with
//! the arm's centre of mass level and `phi_g` the angle of that centre of mass above the
//! link. Validation requires `J accel_max + |tau_g| <= torque_max`, so the commanded
//! acceleration is always realizable; the torque is clamped to `±torque_max_nm` as well.
//!
//! ## Safe state
//! A non-finite or implausible measurement, a stale input, or a tracking error above
//! `max_tracking_error_rad` puts the controller in [`Mode::Safe`] with the [`Fault`]; the
//! fault is latched (a trajectory cannot be resumed after a gap): every later command
//! brakes the joint to rest and holds it there with gravity compensation, and repeats the
//! first fault code. A new controller (a new `Configure`) clears it.
//!
//! Every step does bounded, loop-free work (one spline segment, one polynomial cosine),
//! allocates nothing and never panics.

use crate::bang_bang::BangBang;
use crate::bspline::{Knots, SplineSample};
use crate::fixed_rate::{reply_from_fields, Fault, FixedRate, Mode, Telemetry};
use crate::freshness::Freshness;
use crate::math::{cos_poly_f32, Real};
use crate::mirror::PaddleReference;
use crate::params::{finite, non_negative, positive, ParamError};
use crate::state::PaddleState;
use crate::track::{PaddleLimits, Tracker};
use serde::{Deserialize, Serialize};

/// Limits of the joint, SI units.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct JointLimits {
    /// Lowest joint angle, rad.
    pub min_angle_rad: f32,
    /// Highest joint angle, rad (> min).
    pub max_angle_rad: f32,
    /// Largest joint speed, rad/s (> 0).
    pub velocity_max_radps: f32,
    /// Largest commanded joint acceleration, rad/s^2 (> 0).
    pub accel_max_radps2: f32,
    /// Largest joint torque magnitude, N m (> 0).
    pub torque_max_nm: f32,
}

impl JointLimits {
    /// The same limits in the tracker's (unit-agnostic) form.
    fn tracker_limits(&self) -> PaddleLimits {
        PaddleLimits {
            min_height_m: self.min_angle_rad,
            max_height_m: self.max_angle_rad,
            velocity_max_mps: self.velocity_max_radps,
            accel_max_mps2: self.accel_max_radps2,
        }
    }
}

/// Everything an arm controller needs, SI units, f32 (sent over the wire in HIL; about
/// 130 bytes postcard-encoded).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct ArmParams {
    /// Control period, s (> 0).
    pub dt_s: f32,
    /// Tracking stiffness, 1/s^2 (>= 0).
    pub kp_per_s2: f32,
    /// Tracking damping, 1/s (>= 0).
    pub kd_per_s: f32,
    /// Joint limits.
    pub limits: JointLimits,
    /// Inertia about the joint, arm and payload, kg m^2 (> 0).
    pub inertia_kgm2: f32,
    /// Gravity torque with the centre of mass level, N m (>= 0): m g r.
    pub gravity_torque_nm: f32,
    /// Angle of the centre of mass above the link direction, rad (finite).
    pub gravity_phase_rad: f32,
    /// Acceleration bound of the move to rest after the trajectory's end, rad/s^2
    /// (> 0, <= accel_max).
    pub brake_accel_radps2: f32,
    /// Whether the move after the trajectory goes to rest at `catch_angle_rad` (the
    /// catching configuration, by the bang-bang move); `false` brakes to rest wherever
    /// that stops (a throw's release).
    pub catches: bool,
    /// The catching joint angle, rad (finite, within the angle limits; read only when
    /// `catches`).
    pub catch_angle_rad: f32,
    /// Tracking error that faults the controller, rad (> 0).
    pub max_tracking_error_rad: f32,
    /// Periods without a new sample before the input counts as stale (>= 1).
    pub stale_limit_steps: u16,
    /// The planned joint trajectory.
    pub trajectory: Knots,
}

impl Default for ArmParams {
    /// A 1 kHz controller for an NSK-like arm (J = 2.2 kg m^2, 100 N m), holding 0 rad.
    fn default() -> Self {
        Self {
            dt_s: 0.001,
            kp_per_s2: 3600.0,
            kd_per_s: 120.0,
            limits: JointLimits {
                min_angle_rad: -1.6,
                max_angle_rad: 1.6,
                velocity_max_radps: 8.0,
                accel_max_radps2: 30.0,
                torque_max_nm: 100.0,
            },
            inertia_kgm2: 2.2,
            gravity_torque_nm: 25.0,
            gravity_phase_rad: 0.0,
            brake_accel_radps2: 30.0,
            catches: false,
            catch_angle_rad: 0.0,
            max_tracking_error_rad: 0.2,
            stale_limit_steps: 5,
            trajectory: Knots::default(),
        }
    }
}

impl ArmParams {
    /// Check every field; the error names the first bad one.
    pub fn validate(&self) -> Result<(), ParamError> {
        self.tracker().map(|_| ())
    }

    /// Validate, and the tracker of these gains and limits: one copy of the checks for
    /// [`validate`](Self::validate) and [`ArmController::new`] (cold code, kept out of
    /// line: it runs once per `Configure`). The joint's limits are checked first under
    /// their own names, so [`Tracker::new`] (which names a paddle's) only ever rejects the
    /// gains (`tracking.kp_per_s2`, `tracking.kd_per_s`).
    #[inline(never)]
    fn tracker(&self) -> Result<Tracker, ParamError> {
        positive("dt_s", self.dt_s)?;
        self.limits.validate()?;
        let l = &self.limits;
        let tracker = Tracker::new(self.kp_per_s2, self.kd_per_s, l.tracker_limits(), self.dt_s)?;
        positive("inertia_kgm2", self.inertia_kgm2)?;
        non_negative("gravity_torque_nm", self.gravity_torque_nm)?;
        finite("gravity_phase_rad", self.gravity_phase_rad)?;
        if self.inertia_kgm2 * l.accel_max_radps2 + self.gravity_torque_nm > l.torque_max_nm {
            return Err(ParamError::OutOfRange("limits.accel_max_radps2"));
        }
        positive("brake_accel_radps2", self.brake_accel_radps2)?;
        if self.brake_accel_radps2 > l.accel_max_radps2 {
            return Err(ParamError::OutOfRange("brake_accel_radps2"));
        }
        positive("max_tracking_error_rad", self.max_tracking_error_rad)?;
        if self.stale_limit_steps == 0 {
            return Err(ParamError::NotPositive("stale_limit_steps"));
        }
        self.trajectory.validate()?;
        self.validate_trajectory_limits()?;
        Ok(tracker)
    }

    /// The whole reference stays within the joint limits (B-spline convex hull: every
    /// control point within the angle range, every difference `|P_i+1 - P_i| / h` within
    /// the speed limit, the catching angle and the move's braking stop within the range).
    fn validate_trajectory_limits(&self) -> Result<(), ParamError> {
        let l = &self.limits;
        let k = &self.trajectory;
        let range = l.min_angle_rad..=l.max_angle_rad;
        if k.points().iter().any(|p| !range.contains(p)) {
            return Err(ParamError::OutOfRange("trajectory.points_rad"));
        }
        let too_fast = k
            .points()
            .windows(2)
            .any(|w| (w[1] - w[0]).abs() > l.velocity_max_radps * k.segment_s);
        if too_fast {
            return Err(ParamError::OutOfRange("trajectory.points_rad"));
        }
        if self.catches {
            finite("catch_angle_rad", self.catch_angle_rad)?;
            if !range.contains(&self.catch_angle_rad) {
                return Err(ParamError::OutOfRange("catch_angle_rad"));
            }
        }
        // the move's extremes: the spline's end, the braking stop, the end angle
        let (stop, _) = self.tail().extremes_rad();
        if !range.contains(&stop) {
            return Err(ParamError::OutOfRange("brake_accel_radps2"));
        }
        Ok(())
    }

    /// The move to rest after the trajectory ([`crate::bang_bang`]).
    fn tail(&self) -> BangBang<f32> {
        let k = &self.trajectory;
        let end = k.sample(k.duration_s()).unwrap_or_default();
        let (x, w, a) = (end.angle_rad, end.velocity_radps, self.brake_accel_radps2);
        match self.catches {
            false => BangBang::brake(x, w, a),
            true => {
                let v = self.limits.velocity_max_radps;
                BangBang::to_rest_at(x, w, self.catch_angle_rad, a, v)
            }
        }
    }
}

impl JointLimits {
    /// Check every field with the joint's names, so that the tracker built from them
    /// ([`Tracker::new`], which names a paddle's limits) cannot reject them.
    fn validate(&self) -> Result<(), ParamError> {
        finite("limits.min_angle_rad", self.min_angle_rad)?;
        finite("limits.max_angle_rad", self.max_angle_rad)?;
        if self.max_angle_rad <= self.min_angle_rad {
            return Err(ParamError::OutOfRange("limits.max_angle_rad"));
        }
        positive("limits.velocity_max_radps", self.velocity_max_radps)?;
        positive("limits.accel_max_radps2", self.accel_max_radps2)?;
        positive("limits.torque_max_nm", self.torque_max_nm)?;
        Ok(())
    }
}

/// One sample of the arm's joint, sent to the controller every control period.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct ArmFrame {
    /// Sample sequence number (advances by one per control period).
    pub seq: u32,
    /// Measured joint angle, rad.
    pub angle_rad: f32,
    /// Measured joint velocity, rad/s.
    pub velocity_radps: f32,
}

/// The arm controller's output for one control period.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct ArmCommand {
    /// Sequence number of the frame this command answers.
    pub seq: u32,
    /// Joint torque, N m, held for one period; within `±torque_max_nm`.
    pub torque_nm: f32,
    /// Acceleration the torque is meant to produce, rad/s^2.
    pub accel_cmd_radps2: f32,
    /// Reference angle, rad (informational).
    pub angle_ref_rad: f32,
    /// Reference velocity, rad/s (informational).
    pub velocity_ref_radps: f32,
    /// [`Mode::Track`] on the trajectory, [`Mode::Hold`] after it, [`Mode::Safe`] faulted.
    pub mode: Mode,
    /// Fault code; [`Fault::None`] unless `mode == Mode::Safe`.
    pub fault: Fault,
}

reply_from_fields!(ArmCommand);

/// The arm's trajectory-tracking controller, stepped at a fixed rate.
#[derive(Clone, Debug)]
pub struct ArmController {
    params: ArmParams,
    tracker: Tracker,
    /// The move to rest after the trajectory.
    tail: BangBang<f32>,
    /// The first new sample's sequence number: the trajectory's start (0 before it).
    first_seq: u32,
    /// Whether each frame carries a new sample (the last new one is the trajectory time).
    seq: Freshness,
    fault: Fault,
    /// Last valid joint measurement, dead-reckoned with our own commands while faulted.
    joint: PaddleState<f32>,
    last_error_rad: f32,
}

impl ArmController {
    /// The reference at trajectory time `t_s`: the spline, then the move to rest, then
    /// holding.
    pub fn reference(&self, t_s: f32) -> SplineSample<f32> {
        let k = &self.params.trajectory;
        let end_s = k.duration_s();
        if t_s <= end_s {
            return k.sample(t_s).unwrap_or_default();
        }
        self.tail.sample(t_s - end_s)
    }

    /// Whether the reference is at rest for good at trajectory time `t_s`.
    fn settled(&self, t_s: f32) -> bool {
        t_s - self.params.trajectory.duration_s() >= self.tail.duration_s()
    }

    /// Torque for acceleration `accel_radps2` at angle `angle_rad` (inverse dynamics),
    /// clamped to `±torque_max_nm`. Out of line: `step` and `safe` share one copy.
    #[inline(never)]
    pub fn torque_for(&self, accel_radps2: f32, angle_rad: f32) -> f32 {
        let p = &self.params;
        let tau = p.inertia_kgm2 * accel_radps2
            + p.gravity_torque_nm * cos_poly_f32(angle_rad + p.gravity_phase_rad);
        let m = p.limits.torque_max_nm;
        tau.clamp_r(-m, m)
    }

    /// Reference minus measured angle at the last step, rad.
    pub fn tracking_error_rad(&self) -> f32 {
        self.last_error_rad
    }

    /// The latched fault, [`Fault::None`] while running.
    pub fn fault(&self) -> Fault {
        self.fault
    }

    /// Validate a frame and count stale repeats (a repeated sample keeps the time).
    fn check(&mut self, frame: &ArmFrame) -> Result<(), Fault> {
        if !frame.angle_rad.is_finite() || !frame.velocity_radps.is_finite() {
            return Err(Fault::NonFinite);
        }
        let l = &self.params.limits;
        let margin = 0.05 * (l.max_angle_rad - l.min_angle_rad);
        let range = (l.min_angle_rad - margin)..=(l.max_angle_rad + margin);
        if !range.contains(&frame.angle_rad)
            || frame.velocity_radps.abs() > 2.0 * l.velocity_max_radps
        {
            return Err(Fault::OutOfRange);
        }
        self.seq.check(frame.seq, self.params.stale_limit_steps)?;
        Ok(())
    }
}

impl FixedRate for ArmController {
    type Params = ArmParams;
    type Frame = ArmFrame;
    type Command = ArmCommand;
    /// 424 instructions, for every input and every trajectory the validator accepts: the
    /// step has no loop (one spline segment, whatever the knot count; one polynomial
    /// cosine), and the static worst case over every path of
    /// `<ArmController as FixedRate>::step` in the arm image as flashed, callees
    /// included (`scripts/wcet.py`, run by `scripts/test.sh` with `--max-instructions 416`),
    /// is 396 instructions, 715 Cortex-M4 cycles (2026-12-07, with the sequence check's one
    /// comparison, `Freshness::check`, one longer on this path; 395 on 2026-12-04; 396 before the safe state's brake and coast were written once, in `Tracker::brake_and_coast`; 2026-12-02, with the move to rest
    /// computed once by `new`, brake or bang-bang alike; 415 when the brake was evaluated
    /// from the spline's end every step; at most 416 by that check). The HIL measurement
    /// window of the size-optimised firmware adds 8 to what it reports: 10 instructions between its two SysTick reads around the call
    /// (argument moves, the call, the reads of the sret command; counted in the disassembly
    /// of the image's `Server::step`), less the 2 its calibration subtracts. QEMU measures
    /// up to 400 over the four shipped scenes (tests/hil_arm.rs, `--nocapture`; 422 before
    /// the move to rest was computed once by `new`).
    const STEP_INSTRUCTION_BUDGET: u32 = 424;

    /// A controller; the error names the first invalid parameter.
    #[inline(never)]
    fn new(params: ArmParams) -> Result<Self, ParamError> {
        let tracker = params.tracker()?;
        let start = params.trajectory.sample(0.0).unwrap_or_default();
        Ok(Self {
            tail: params.tail(),
            params,
            tracker,
            first_seq: 0,
            seq: Freshness::new(),
            fault: Fault::None,
            joint: PaddleState::new(start.angle_rad, 0.0),
            last_error_rad: 0.0,
        })
    }

    fn params(&self) -> &ArmParams {
        &self.params
    }

    /// One control period: the command for `frame`. Out of line, so the firmware has one
    /// symbol for the static worst-case tool (`scripts/wcet.py`).
    #[inline(never)]
    fn step(&mut self, frame: &ArmFrame) -> ArmCommand {
        if self.fault != Fault::None {
            return self.safe(frame.seq, self.fault);
        }
        let started = self.seq.seen();
        if let Err(fault) = self.check(frame) {
            return self.safe(frame.seq, fault);
        }
        if !started {
            self.first_seq = frame.seq;
        }
        let joint = PaddleState::new(frame.angle_rad, frame.velocity_radps);
        self.joint = joint;
        let t_s = self.seq.last_seq().wrapping_sub(self.first_seq) as f32 * self.params.dt_s;
        let r = self.reference(t_s);
        let r = self.tracker.clamp_reference(PaddleReference {
            height_m: r.angle_rad,
            velocity_mps: r.velocity_radps,
            accel_mps2: r.accel_radps2,
        });
        self.last_error_rad = r.height_m - joint.height_m;
        if self.last_error_rad.abs() > self.params.max_tracking_error_rad {
            return self.safe(frame.seq, Fault::OutOfRange);
        }
        let u = self.tracker.command(&r, &joint);
        let done = t_s > self.params.trajectory.duration_s() && self.settled(t_s);
        ArmCommand {
            seq: frame.seq,
            torque_nm: self.torque_for(u, joint.height_m),
            accel_cmd_radps2: u,
            angle_ref_rad: r.height_m,
            velocity_ref_radps: r.velocity_mps,
            mode: if done { Mode::Hold } else { Mode::Track },
            fault: Fault::None,
        }
    }

    /// The safe command: latch `fault`, brake the joint to rest and hold it there.
    fn safe(&mut self, seq: u32, fault: Fault) -> ArmCommand {
        if self.fault == Fault::None {
            self.fault = fault;
        }
        let j = self.joint;
        let u = self.tracker.brake_and_coast(&mut self.joint);
        ArmCommand {
            seq,
            torque_nm: self.torque_for(u, j.height_m),
            accel_cmd_radps2: u,
            angle_ref_rad: self.joint.height_m,
            velocity_ref_radps: 0.0,
            mode: Mode::Safe,
            fault: self.fault,
        }
    }

    fn telemetry(&self) -> Telemetry {
        // No estimator: the core knows none of the telemetry's ball fields.
        Telemetry::default()
    }
}
