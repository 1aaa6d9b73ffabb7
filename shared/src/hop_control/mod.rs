//! The fixed-rate hopper thrust controller: phases detected from sampled leg compression and
//! a foot switch, Raibert's fixed thrust or the energy servo held for delta from the
//! (estimated) bottom, or the safe state with a fault code (Koditschek & Bühler 1991,
//! sec. 1.2, 3.1, eq. 8/10; [`crate::hop`]).
//!
//! One [`HopController::step`] per control period dt takes a [`HopFrame`] and returns a
//! [`HopCommand`]: open or close the thrust valve, and the thrust (force per unit body mass,
//! m/s^2) to apply while it is open. The valve switches only at control-step boundaries
//! (zero-order hold).
//!
//! ## Phases (sec. 3.1), detected from samples
//!
//! | detected phase | ends when (each on fresh samples only) |
//! | --- | --- |
//! | `Flight` | **touchdown**: switch closed and compression >= `touchdown_compression_m`, for `debounce_samples` samples in a row |
//! | `Compression` | **bottom**: the compression has fallen more than `bottom_hysteresis_m` below its running maximum in this stance |
//! | `Thrust` | the valve has been open for the planned number of periods (below) |
//! | `Decompression` | **liftoff** (from any stance phase): switch open, or compression < `liftoff_compression_m`, for `debounce_samples` samples in a row |
//!
//! Touchdown and liftoff use a hysteresis band (`liftoff_compression_m` <=
//! `touchdown_compression_m`) and a debounce count: a noise excursion or a switch bounce
//! shorter than `debounce_samples` samples changes nothing, and a true transition is
//! declared `debounce_samples - 1` samples after its first sample (plus the time the
//! compression takes to cross its threshold). The bottom test needs a fall of more than the
//! hysteresis below the running maximum, so noise below it cannot end the compression
//! early.
//!
//! ## How late the bottom is seen, and the compensation
//!
//! The true bottom (maximal compression) lies between the samples around the largest one.
//! Waiting for the compression to fall, the controller sees it at the first sample more
//! than the hysteresis below the maximum: with no hysteresis the first decreasing sample,
//! between dt/2 and 3 dt/2 after the true bottom for a symmetric peak; with hysteresis h
//! about sqrt(2 h / |c''|) later; plus the sensor latency.
//!
//! The compensation (`predict_bottom`, for low-noise sensors) fits the parabola through the
//! last three rising samples ([`BottomSearch::predicted_vertex_steps`]) and opens the valve
//! at the control step nearest to its vertex (less the known `sensor_latency_s`; also on a
//! step without a new sample, for a sensor slower than the control rate): the
//! opening is then within half a period of the true bottom, before or after, instead of
//! always late by about one period. The fall test stays as the fallback.
//!
//! With `end_thrust_at_estimate` (the default) the valve closes at the step nearest to the
//! estimated bottom + delta (the estimate: the predicted vertex, or after a late detection
//! the vertex through the maximum sample and its neighbours,
//! [`BottomSearch::vertex_offset_steps`]): round(delta/dt - lateness) periods, at least 0.
//! Otherwise it is held for round(delta/dt) periods from the opening. With the prediction
//! both ends of the thrust are then within half a period of the exact law's. After a late
//! detection (`predict_bottom` off, or noise) ending at the estimate shortens the thrust,
//! and measured on the tuned linear model at 1 kHz (`host-sim/tests/integration/hopper_sampled.rs`)
//! that is the worse choice: the impulse lost at the late start is not recovered, while a
//! thrust shifted whole only feels the small change of the spring force it replaces.
//!
//! ## Energy servo: the touchdown energy from the flight time
//!
//! The servo needs the touchdown energy E_n = chi'_td^2 / 2 ([`crate::hop::flight_energy_jpkg`]
//! with zero potential at the touchdown height). Flight is ballistic and starts and ends at
//! chi_l, so chi'_td = g T / 2 with T the flight time, and E_n = g^2 T^2 / 8: a product, no
//! transcendental function and no model of the spring. T is counted in control periods from
//! the detected liftoff to the detected touchdown; both detections are late by the same
//! debounce and latency, which cancel, and by the sampling (each uniform in one period),
//! which leaves an error below one period (relative error of E below 2 dt / T). The
//! thresholds lengthen T by (c_on + c_off)/chi'_td; that is removed to first order,
//! T_c = T - 2 (c_on + c_off) / (g T) (positive parts of the thresholds). Before the first
//! measured flight (a run that starts in the air) the energy comes from the highest
//! body-height sample of the flight, g (h - chi_l), when the frame carries one, else the
//! servo applies its nominal thrust tau0.
//!
//! ## Modes and the safe state
//!
//! The controller starts unarmed ([`Mode::Hold`]: valve closed, phases still tracked) and arms
//! ([`Mode::Track`]) at its first detected liftoff or flight, so that it never thrusts in a
//! stance it did not see from touchdown. A non-finite or out-of-range sample, or a sequence
//! number that does not advance for more than `stale_limit_steps` periods, gives the safe
//! command: [`Mode::Safe`] with the [`Fault`], valve closed, thrust 0. The state is reset
//! (phase `Flight`, unarmed, no flight timing), so after the fault the controller holds the
//! valve closed until it has seen a flight again.
//!
//! ## Work per step (budget: <= 300 instructions on the Cortex-M4F)
//!
//! The step has no loop, no recursion and no call (no transcendental function, no soft-float
//! helper): every path is a fixed sequence of compares, multiply-adds, float/int conversions
//! and at most 4 `vdiv.f32` (one parabola vertex, or the flight-time correction). Its work
//! therefore does not depend on the parameters: the longest path through the compiled
//! function bounds every step of every configuration the validator accepts.
//!
//! Static count of `HopController::step` (behind an `extern "C"` wrapper that stores the
//! command) compiled for `thumbv7em-none-eabihf` with the firmware's release profile
//! (`lto = "fat"`, `opt-level = 3`, `codegen-units = 1`), by a longest-path search over the
//! control-flow graph of its disassembly, which is acyclic (the search finds no cycle and no
//! `bl`/`blx`): **463 instructions in the function, longest path 209 instructions**, at most
//! 4 `vdiv.f32` on one path (9 in the function), no `vsqrt.f32`. Weighting `vdiv.f32` at its
//! 14 cycles and everything else at 1, the worst path is about 255 cycles. The branches, in
//! the order a step runs:
//!
//! | branch | what it does | taken |
//! | --- | --- | --- |
//! | check | finite and range tests of 1-2 floats, sequence freshness | every step |
//! | flight sample | apex tracking, arming and touchdown debounce | flight, fresh sample |
//! | touchdown | flight-time energy (1 division), servo clamp, bottom search reset | once per hop |
//! | stance sample | liftoff debounce, running maximum, fall test | stance, fresh sample |
//! | prediction | parabola through the last three samples (4 divisions) | compression, no fall |
//! | due bottom | open at the step nearest the predicted bottom (also between samples) | compression, every step |
//! | bottom | vertex around the maximum (4 divisions) after a fall, or the predicted one; the plan (1 conversion) | once per hop |
//! | liftoff | reset timers | once per hop |
//! | valve | thrust countdown, command | every step |
//! | safe | reset, safe command | a fault |
//!
//! At most one of touchdown / bottom / liftoff runs in a step (one phase transition per
//! sample), and the fall test and the prediction exclude each other, so the longest path is
//! check + stance sample + one vertex + plan + valve. The QEMU icount measurement of the
//! firmware build comes with the firmware integration.

mod detect;
mod params;

pub use detect::{BottomSearch, Debounce};
pub use params::{HopParams, HopThrust, MAX_DEBOUNCE_SAMPLES, MAX_LATENCY_STEPS, MAX_THRUST_STEPS};

use crate::fixed_rate::{reply_from_fields, Fault, FixedRate, Mode, Telemetry};
use crate::freshness::Freshness;
use crate::hop::{EnergyServoThrust, StancePhase};
use crate::math::Real;
use crate::params::ParamError;
use serde::{Deserialize, Serialize};

/// One sample of the hopper, sent to the controller every control period. Its serde form
/// is its fields as one flat tuple (the crate's `fields` module).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct HopFrame {
    /// Sample sequence number; a controller that sees it not advance counts the input stale.
    pub seq: u32,
    /// Leg compression, chi_l minus the leg length, m: 0 with the leg fully extended,
    /// positive in stance (noise may make it slightly negative in flight).
    pub leg_compression_m: f32,
    /// The foot switch: true while the foot touches the ground.
    pub contact: bool,
    /// Whether `body_height_m` holds a sample (false: the hopper has no height sensor, or it
    /// gave none this period).
    pub has_body_height: bool,
    /// Body height chi, m, when `has_body_height` (then a non-finite value is a fault);
    /// ignored otherwise. A flag and a number rather than an `Option`, so that the frame has
    /// one shape on the wire.
    pub body_height_m: f32,
}

impl HopFrame {
    /// The body-height sample, if the frame carries one.
    #[inline]
    pub fn body_height(&self) -> Option<f32> {
        self.has_body_height.then_some(self.body_height_m)
    }
}

impl crate::fields::Fields for HopFrame {
    const COUNT: usize = 5;
    const NAME: &'static str = "HopFrame";

    fn blank() -> Self {
        Self::default()
    }

    fn fields<V: crate::fields::FieldVisit>(&mut self, v: &mut V) {
        v.u32(&mut self.seq);
        v.f32(&mut self.leg_compression_m);
        v.bool(&mut self.contact);
        v.bool(&mut self.has_body_height);
        v.f32(&mut self.body_height_m);
    }
}

impl Serialize for HopFrame {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        crate::fields::serialize(self, s)
    }
}

impl<'de> Deserialize<'de> for HopFrame {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        crate::fields::deserialize(d)
    }
}

/// The controller's output for one control period (held for the period).
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct HopCommand {
    /// Sequence number of the frame this command answers.
    pub seq: u32,
    /// Open the thrust valve for this period.
    pub valve_open: bool,
    /// Thrust force per unit body mass while the valve is open, m/s^2 (0 when closed;
    /// finite, within [0, the law's largest thrust]).
    pub thrust_mps2: f32,
    /// The detected phase after this frame.
    pub phase: StancePhase,
    /// [`Mode::Hold`] (unarmed, valve closed), [`Mode::Track`] (armed) or [`Mode::Safe`].
    pub mode: Mode,
    /// Fault code; [`Fault::None`] unless `mode == Mode::Safe`.
    pub fault: Fault,
}

reply_from_fields!(HopCommand);

/// The fixed-rate hopper thrust controller.
#[derive(Clone, Debug)]
pub struct HopController {
    params: HopParams,
    law: EnergyServoThrust<f32>,
    /// delta / dt.
    delta_steps: f32,
    /// latency / dt.
    latency_steps: f32,
    /// g^2 / 8, the touchdown energy per squared flight time, J/kg/s^2.
    energy_per_s2: f32,
    /// 2 (c_on+ + c_off+) / g, s^2: the threshold correction of the flight time.
    threshold_s2: f32,
    /// Index of the current step (wrapping).
    step: u32,
    phase: StancePhase,
    armed: bool,
    touchdown: Debounce,
    liftoff: Debounce,
    bottom: BottomSearch,
    thrust_left: u32,
    stance_thrust_mps2: f32,
    liftoff_step: Option<u32>,
    /// The latest bottom prediction: (step it was made, true bottom that many steps later).
    predicted: Option<(u32, f32)>,
    apex_m: f32,
    energy_jpkg: f32,
    /// Whether each frame carries a new sample.
    seq: Freshness,
    /// The last two fresh compression samples and their steps (older first), for telemetry.
    samples: [(f32, u32); 2],
}

impl HopController {
    /// The detected phase.
    pub fn phase(&self) -> StancePhase {
        self.phase
    }

    /// True once the controller has seen a flight (and since its last fault).
    pub fn armed(&self) -> bool {
        self.armed
    }

    /// The touchdown energy estimated at the last detected touchdown, J/kg (NaN if none).
    pub fn touchdown_energy_jpkg(&self) -> f32 {
        self.energy_jpkg
    }

    /// The thrust of the current (or last) stance, m/s^2.
    pub fn stance_thrust_mps2(&self) -> f32 {
        self.stance_thrust_mps2
    }

    fn enter_safe(&mut self, seq: u32, fault: Fault) -> HopCommand {
        self.phase = StancePhase::Flight;
        self.armed = false;
        self.thrust_left = 0;
        self.predicted = None;
        self.touchdown.reset();
        self.liftoff.reset();
        self.liftoff_step = None;
        self.apex_m = f32::NEG_INFINITY;
        HopCommand {
            seq,
            valve_open: false,
            thrust_mps2: 0.0,
            phase: StancePhase::Flight,
            mode: Mode::Safe,
            fault,
        }
    }

    /// Validate a frame; `Ok(true)` if it carries a new sample, `Ok(false)` if it repeats
    /// the last one (within the stale limit).
    fn check(&mut self, frame: &HopFrame) -> Result<bool, Fault> {
        let c = frame.leg_compression_m;
        let h = frame.body_height();
        if !c.is_finite() || h.is_some_and(|h| !h.is_finite()) {
            return Err(Fault::NonFinite);
        }
        let p = &self.params;
        let h_out = h.is_some_and(|h| h < p.body_height_min_m || h > p.body_height_max_m);
        if c.abs() > p.max_compression_m || h_out {
            return Err(Fault::OutOfRange);
        }
        self.seq.check(frame.seq, self.params.stale_limit_steps)
    }

    /// A fresh, valid sample: phase detection.
    fn on_sample(&mut self, frame: &HopFrame) {
        let c = frame.leg_compression_m;
        let [_, last] = self.samples;
        self.samples = [last, (c, self.step)];
        let p = &self.params;
        let need = p.debounce_samples;
        let up = !frame.contact || c < p.liftoff_compression_m;
        if self.phase == StancePhase::Flight {
            if let Some(h) = frame.body_height() {
                self.apex_m = self.apex_m.max_r(h);
            }
            // unarmed: a flight seen for `need` samples arms the controller
            if !self.armed && self.liftoff.feed(up, need) {
                self.armed = true;
            }
            let down = frame.contact && c >= p.touchdown_compression_m;
            if self.touchdown.feed(down, need) {
                self.on_touchdown(c);
            }
            return;
        }
        if self.liftoff.feed(up, need) {
            self.on_liftoff();
            return;
        }
        if self.phase == StancePhase::Compression {
            self.bottom.push(c, self.step);
            if self.bottom.max_m - c > p.bottom_hysteresis_m {
                // seen late: the bottom was at the vertex around the maximum sample
                let since_max = self.step.wrapping_sub(self.bottom.max_step) as f32;
                let late = since_max - self.bottom.vertex_offset_steps();
                self.on_bottom(late + self.latency_steps);
            } else if p.predict_bottom {
                // seen ahead: the bottom's step, less the latency (acted on in `due_bottom`)
                self.predicted = self
                    .bottom
                    .predicted_vertex_steps(self.step)
                    .map(|ahead| (self.step, ahead - self.latency_steps));
            }
        }
    }

    /// Every step in compression: open at the step nearest to the predicted bottom (also
    /// between samples, for a sensor slower than the control rate).
    fn due_bottom(&mut self) {
        if self.phase != StancePhase::Compression {
            return;
        }
        if let Some((at, ahead)) = self.predicted {
            let late = self.step.wrapping_sub(at) as f32 - ahead;
            if late > -0.5 {
                self.on_bottom(late);
            }
        }
    }

    fn on_touchdown(&mut self, c: f32) {
        self.phase = StancePhase::Compression;
        self.liftoff.reset();
        self.bottom = BottomSearch::start(c, self.step);
        self.predicted = None;
        self.energy_jpkg = self.touchdown_energy();
        let e = if self.energy_jpkg.is_finite() {
            self.energy_jpkg
        } else {
            self.law.target_energy_jpkg()
        };
        self.stance_thrust_mps2 = self.law.thrust_mps2(e);
    }

    /// E_n = g^2 T_c^2 / 8 from the flight time, else g (apex - chi_l), else NaN.
    fn touchdown_energy(&self) -> f32 {
        match self.liftoff_step {
            Some(lo) => {
                let t = self.step.wrapping_sub(lo) as f32 * self.params.dt_s;
                let tc = (t - self.threshold_s2 / t).max_r(0.0);
                self.energy_per_s2 * tc * tc
            }
            None if self.apex_m.is_finite() => {
                self.params.gravity_mps2 * (self.apex_m - self.params.liftoff_height_m)
            }
            None => f32::NAN,
        }
    }

    /// The bottom decision, `late` control periods after the (estimated) true bottom
    /// (negative: before it): plan the thrust.
    fn on_bottom(&mut self, late: f32) {
        self.phase = StancePhase::Decompression;
        if !self.armed {
            return;
        }
        let plan = if self.params.end_thrust_at_estimate {
            self.delta_steps - late
        } else {
            self.delta_steps
        };
        // round half up; negative and NaN saturate to 0
        self.thrust_left = (plan + 0.5) as u32;
        if self.thrust_left > 0 {
            self.phase = StancePhase::Thrust;
        }
    }

    fn on_liftoff(&mut self) {
        self.phase = StancePhase::Flight;
        self.thrust_left = 0;
        self.touchdown.reset();
        self.liftoff_step = Some(self.step);
        self.apex_m = f32::NEG_INFINITY;
        self.armed = true;
    }

    /// The valve for this period: open while the thrust plan lasts.
    fn command(&mut self, seq: u32) -> HopCommand {
        let open = self.phase == StancePhase::Thrust && self.thrust_left > 0;
        if open {
            self.thrust_left -= 1;
        } else if self.phase == StancePhase::Thrust {
            self.phase = StancePhase::Decompression;
        }
        HopCommand {
            seq,
            valve_open: open,
            thrust_mps2: if open { self.stance_thrust_mps2 } else { 0.0 },
            phase: self.phase,
            mode: if self.armed { Mode::Track } else { Mode::Hold },
            fault: Fault::None,
        }
    }
}

impl FixedRate for HopController {
    type Params = HopParams;
    type Frame = HopFrame;
    type Command = HopCommand;
    /// 300 instructions for every configuration the validator accepts: the step has no
    /// loop and no call, so the longest path through its compiled code bounds every step
    /// (module docs, "Work per step"; the static figure and the measured maximum are in
    /// BENCHMARKS.md, "Hopper controller on the MCU").
    const STEP_INSTRUCTION_BUDGET: u32 = 300;

    /// A controller; the error names the first invalid parameter.
    #[inline]
    fn new(params: HopParams) -> Result<Self, ParamError> {
        params.validate()?;
        // validated above, thrust fields included
        let law = params.law_of_checked()?;
        let g = params.gravity_mps2;
        let lag_m =
            params.touchdown_compression_m.max_r(0.0) + params.liftoff_compression_m.max_r(0.0);
        Ok(Self {
            params,
            law,
            delta_steps: params.thrust_duration_s / params.dt_s,
            latency_steps: params.sensor_latency_s / params.dt_s,
            energy_per_s2: 0.125 * g * g,
            threshold_s2: 2.0 * lag_m / g,
            step: u32::MAX,
            phase: StancePhase::Flight,
            armed: false,
            touchdown: Debounce::default(),
            liftoff: Debounce::default(),
            bottom: BottomSearch::start(0.0, 0),
            thrust_left: 0,
            stance_thrust_mps2: 0.0,
            liftoff_step: None,
            predicted: None,
            apex_m: f32::NEG_INFINITY,
            energy_jpkg: f32::NAN,
            seq: Freshness::new(),
            samples: [(0.0, 0); 2],
        })
    }

    /// The parameters this controller runs with.
    fn params(&self) -> &HopParams {
        &self.params
    }

    /// One control period: the command for `frame`.
    #[inline(never)]
    fn step(&mut self, frame: &HopFrame) -> HopCommand {
        self.step = self.step.wrapping_add(1);
        match self.check(frame) {
            Err(fault) => self.enter_safe(frame.seq, fault),
            Ok(fresh) => {
                if fresh {
                    self.on_sample(frame);
                }
                self.due_bottom();
                self.command(frame.seq)
            }
        }
    }

    /// The safe command for an external fault (e.g. the firmware's link timeout); one
    /// control period passes.
    #[inline(never)]
    fn safe(&mut self, seq: u32, fault: Fault) -> HopCommand {
        self.step = self.step.wrapping_add(1);
        self.enter_safe(seq, fault)
    }

    /// Telemetry fields the core knows (the firmware adds timing and link counts): estimate
    /// slot 0 the last leg compression sample, m; slot 1 its rate, m/s, the difference of
    /// the last two fresh samples over the time between them (0 before two); slot 2 the
    /// touchdown energy estimated at the last touchdown, J/kg (0 before the first; the
    /// phase is in the command). Valid while armed ([`Mode::Track`]). Computed here, not in
    /// the step, so the step's budget does not pay for it.
    fn telemetry(&self) -> Telemetry {
        let [(c0, s0), (c1, s1)] = self.samples;
        let periods = s1.wrapping_sub(s0);
        let rate = if periods == 0 {
            0.0
        } else {
            (c1 - c0) / (periods as f32 * self.params.dt_s)
        };
        let energy = if self.energy_jpkg.is_finite() {
            self.energy_jpkg
        } else {
            0.0
        };
        Telemetry::with_estimate(&[c1, rate, energy], self.armed)
    }
}

#[cfg(test)]
mod tests;
