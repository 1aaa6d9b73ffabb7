//! The hopper closed through a fixed-rate controller: the valve-driven plant
//! ([`super::valve`]), a sensor with rate, noise, quantization and latency ([`sensor`]), and
//! the core's [`HopController`] behind a [`StepController`] (the core linked in, [`Sil`], or
//! the firmware in QEMU, HIL), so a thrust timing can be checked at the rate a board runs it.
//!
//! One control step at t_k = k dt: the samples due are taken, the frame (the newest
//! delivered sample) goes to the controller, its command sets the valve for
//! [t_k, t_k+1) (zero-order hold), and the plant is advanced exactly to t_k+1, stopping at
//! the sensor's own sample times in between. Every true event (touchdown, bottom, liftoff,
//! apex) has its exact time; a cycle runs from one touchdown to the next.
//!
//! What a run reports ([`SampledRun`], [`SampledSummary`] for JSON):
//! - `period`: the settled period of the hop heights ([`stats::settled_period`]: every phase
//!   of the orbit within `settle_tolerance` over the last 64 hops and no trend in its
//!   amplitude), `None` if not settled;
//! - `fixed_point_error`: the largest |h - h*| / h* between the settled orbit's hop heights
//!   h (apex - chi_l, the mean of each phase of the orbit over the last 32 hops) and the
//!   nearest hop height h* of the same model's orbit with exactly timed thrust, and the other
//!   way round ([`reference::exact_orbit`]: eq. 17 for the tuned linear model with Raibert's
//!   thrust, else the exact event-driven simulator); `None` unless both settled;
//! - `phase_detection_errors` ([`stats::PhaseDetectionErrors`]);
//! - the safe steps by fault code, invalid commands, how the run ended.
//!
//! Memory is bounded for any run length: per-cycle records and the timeline are kept only
//! when asked for (at most [`MAX_CYCLE_RECORDS`] and [`MAX_TIMELINE_ROWS`]), every cycle can
//! be streamed to a sink instead ([`run_sampled_with`], for traces), and everything else is
//! a fixed-size summary.

pub mod reference;
pub mod sensor;
pub mod stats;
mod tracker;

pub use reference::{exact_orbit, ExactOrbit};
pub use stats::{settled_period, EventErrors, PhaseDetectionErrors, Settle, Timing};
pub use tracker::{SampledCycle, TimelineRow};

use super::valve::{PlantError, ValveModel, ValvePlant};
use super::{HopperError, ThrustLaw};
use crate::closed_loop::{drive, SampledPlant};
use crate::controller::{ControllerError, EveryFault, SafeSteps, Sil, StepController};
use dexter_core::hop::{EnergyServoThrust, RaibertThrust, StancePhase};
use dexter_core::hop_control::{HopCommand, HopController, HopFrame, HopParams, HopThrust};
use dexter_core::params::ParamError;
use sensor::{
    AtControlSteps, Clock, Delay, Exact, HopSensor, Latency, Measure, NoLatency, Periodic, Truth,
};
use serde::Serialize;
use std::ops::ControlFlow;
use tracker::Tracker;

/// Most control steps one run may take (`hopper.control.max_time_s` x rate).
pub const MAX_STEPS: u64 = 1_000_000_000;
/// Most cycles one run may ask for.
pub const MAX_CYCLES: usize = 10_000_000;
/// Fastest sensor, as a multiple of the control rate.
pub const MAX_SENSOR_RATE_RATIO: f64 = 16.0;
/// Most samples in flight in the sensor's latency line.
pub const MAX_PENDING_SAMPLES: f64 = 4096.0;
/// Most timeline rows kept.
pub const MAX_TIMELINE_ROWS: usize = 200_000;
/// Most per-cycle records kept in [`SampledRun::records`] (the first ones; stream them with
/// [`run_sampled_with`] for longer runs).
pub const MAX_CYCLE_RECORDS: usize = 1_000_000;
/// Apex heights reported as `late_apex_heights_m`.
pub const LATE_APEXES: usize = 8;

/// Relative rounding of the control period to f32 (half an ulp, with room).
const PERIOD_ROUNDING: f64 = f32::EPSILON as f64;

/// Slack for comparing sample and control times, s.
const TIME_SLACK_S: f64 = 1e-12;

/// The sensor's effects (all off by default).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SensorConfig {
    /// Sample rate, Hz; `None` = one sample at every control step.
    pub rate_hz: Option<f64>,
    /// Gaussian noise on the leg compression, m (0 = off).
    pub compression_noise_m: f64,
    /// Gaussian noise on the body height, m (0 = off).
    pub height_noise_m: f64,
    /// Quantization step of compression and height, m (0 = off).
    pub quantization_m: f64,
    /// Latency from sampling to delivery, s (0 = off).
    pub latency_s: f64,
    /// Whether the frames carry the body height.
    pub body_height: bool,
    /// Noise seed.
    pub seed: u64,
}

impl Default for SensorConfig {
    fn default() -> Self {
        Self {
            rate_hz: None,
            compression_noise_m: 0.0,
            height_noise_m: 0.0,
            quantization_m: 0.0,
            latency_s: 0.0,
            body_height: false,
            seed: 1,
        }
    }
}

/// The controller's phase-detection settings (see [`HopParams`] for each).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DetectorOptions {
    /// [`HopParams::touchdown_compression_m`], m.
    pub touchdown_compression_m: f64,
    /// [`HopParams::liftoff_compression_m`], m; `None` = only the foot switch.
    pub liftoff_compression_m: Option<f64>,
    /// [`HopParams::bottom_hysteresis_m`], m.
    pub bottom_hysteresis_m: f64,
    /// [`HopParams::debounce_samples`].
    pub debounce_samples: u8,
    /// [`HopParams::predict_bottom`].
    pub predict_bottom: bool,
    /// [`HopParams::end_thrust_at_estimate`].
    pub end_thrust_at_estimate: bool,
    /// [`HopParams::max_compression_m`], m.
    pub max_compression_m: f64,
    /// [`HopParams::stale_limit_steps`].
    pub stale_limit_steps: u16,
}

impl Default for DetectorOptions {
    fn default() -> Self {
        Self {
            touchdown_compression_m: 0.0,
            liftoff_compression_m: None,
            bottom_hysteresis_m: 0.0,
            debounce_samples: 1,
            predict_bottom: true,
            end_thrust_at_estimate: true,
            max_compression_m: 2.0,
            stale_limit_steps: 5,
        }
    }
}

/// Which cycles' control steps to keep as timeline rows (for a plot of a few hops).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct TimelineWindow {
    /// First cycle kept (0 = from the start of the run).
    pub first_cycle: usize,
    /// Cycles kept.
    pub cycles: usize,
}

/// Everything a sampled run needs.
#[derive(Clone, Debug, PartialEq)]
pub struct SampledConfig {
    /// The plant.
    pub model: ValveModel,
    /// The run starts at rest at this apex, m (>= chi_l).
    pub start_height_m: f64,
    /// The controller's parameters (SIL builds the controller from them; HIL sends them).
    /// The exact-thrust reference uses the same thrust law, in f64.
    pub control: HopParams,
    /// The sensor.
    pub sensor: SensorConfig,
    /// Cycles to complete (touchdown to touchdown).
    pub cycles: usize,
    /// Longest simulated time, s: the run ends (`TimeLimit`) if the cycles take longer.
    pub max_time_s: f64,
    /// Relative tolerance for the settled period.
    pub settle_tolerance: f64,
    /// Compute the exact-thrust orbit and the fixed-point error.
    pub compare_exact: bool,
    /// Keep one record per cycle (the first [`MAX_CYCLE_RECORDS`]).
    pub record_cycles: bool,
    /// Keep timeline rows for these cycles.
    pub timeline: Option<TimelineWindow>,
}

/// Why a sampled run could not be set up or run.
#[derive(Debug)]
pub enum SampledError {
    /// A setting is invalid; `key` is its scene key.
    Param {
        /// The scene key, e.g. `hopper.sensor.rate_hz`.
        key: &'static str,
        /// What it must satisfy.
        message: String,
    },
    /// The hopper (model, law) is invalid.
    Hopper(HopperError),
    /// The controller failed (parameters rejected, or the HIL link).
    Controller(ControllerError),
}

impl std::fmt::Display for SampledError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            SampledError::Param { key, message } => write!(f, "{key} {message}"),
            SampledError::Hopper(e) => write!(f, "{e}"),
            SampledError::Controller(e) => write!(f, "{e}"),
        }
    }
}

impl std::error::Error for SampledError {}

impl From<HopperError> for SampledError {
    fn from(e: HopperError) -> Self {
        SampledError::Hopper(e)
    }
}

impl From<ControllerError> for SampledError {
    fn from(e: ControllerError) -> Self {
        SampledError::Controller(e)
    }
}

fn param(key: &'static str, message: impl Into<String>) -> SampledError {
    SampledError::Param {
        key,
        message: message.into(),
    }
}

/// The controller's parameters for the hopper `model` with the exact simulator's thrust
/// `law`, at `rate_hz`, the sensor `sensor` (its latency is what the controller
/// compensates) and the detector settings.
pub fn controller_params(
    model: &ValveModel,
    law: &ThrustLaw,
    rate_hz: f64,
    sensor: &SensorConfig,
    detector: &DetectorOptions,
) -> Result<HopParams, SampledError> {
    if !(rate_hz.is_finite() && rate_hz > 0.0) {
        return Err(param("hopper.control.rate_hz", "must be a number > 0"));
    }
    let thrust = match law {
        ThrustLaw::Raibert(r) => HopThrust::raibert(r.thrust_mps2() as f32),
        ThrustLaw::EnergyServo(s) => HopThrust {
            nominal_thrust_mps2: s.nominal_thrust_mps2() as f32,
            gain_per_m: s.gain_per_m() as f32,
            target_energy_jpkg: s.target_energy_jpkg() as f32,
            max_thrust_mps2: s.max_thrust_mps2() as f32,
        },
    };
    let chi_l = model.liftoff_m();
    let c_max = detector.max_compression_m;
    let p = HopParams {
        dt_s: (1.0 / rate_hz) as f32,
        gravity_mps2: model.gravity_mps2() as f32,
        thrust,
        thrust_duration_s: law.duration_s() as f32,
        touchdown_compression_m: detector.touchdown_compression_m as f32,
        liftoff_compression_m: detector.liftoff_compression_m.unwrap_or(-c_max) as f32,
        bottom_hysteresis_m: detector.bottom_hysteresis_m as f32,
        debounce_samples: detector.debounce_samples,
        predict_bottom: detector.predict_bottom,
        end_thrust_at_estimate: detector.end_thrust_at_estimate,
        sensor_latency_s: sensor.latency_s as f32,
        max_compression_m: c_max as f32,
        liftoff_height_m: chi_l as f32,
        body_height_min_m: (chi_l - c_max - 1.0) as f32,
        body_height_max_m: (chi_l + 1.0e3) as f32,
        stale_limit_steps: detector.stale_limit_steps,
    };
    p.validate().map_err(control_error)?;
    Ok(p)
}

/// A rejected controller parameter, named by its scene key.
fn control_error(e: ParamError) -> SampledError {
    let name = match e {
        ParamError::NotFinite(n)
        | ParamError::NotPositive(n)
        | ParamError::Negative(n)
        | ParamError::OutOfRange(n) => n,
        _ => "",
    };
    let key = match name {
        "dt_s" => "hopper.control.rate_hz",
        "gravity_mps2" => "hopper.gravity_mps2",
        "thrust_mps2" | "nominal_thrust_mps2" | "thrust.nominal_thrust_mps2" => {
            "hopper.thrust_tau_mps2"
        }
        "thrust_duration_s" | "duration_s" => "hopper.thrust_delta_s",
        "gain_per_m" | "thrust.gain_per_m" => "hopper.servo.gain_per_m",
        "target_energy_jpkg" | "thrust.target_energy_jpkg" => "hopper.servo.target_energy_jpkg",
        "max_thrust_mps2" | "thrust.max_thrust_mps2" => "hopper.servo.max_thrust_mps2",
        "touchdown_compression_m" => "hopper.control.touchdown_compression_m",
        "liftoff_compression_m" => "hopper.control.liftoff_compression_m",
        "bottom_hysteresis_m" => "hopper.control.bottom_hysteresis_m",
        "debounce_samples" => "hopper.control.debounce_samples",
        "max_compression_m" => "hopper.control.max_compression_m",
        "stale_limit_steps" => "hopper.control.stale_limit_steps",
        "sensor_latency_s" => "hopper.sensor.latency_s",
        "liftoff_height_m" => "hopper.liftoff_height_m",
        _ => "",
    };
    let why = match e {
        ParamError::NotFinite(_) => {
            "is invalid: not a finite number (the controller holds it as an f32, below 3.4e38 in size)"
        }
        ParamError::NotPositive(_) => "is invalid: must be > 0",
        ParamError::Negative(_) => "is invalid: must be >= 0",
        _ => "is invalid: out of its allowed range (docs/hopper.md, \"The hopper on the MCU\")",
    };
    match key {
        // a controller parameter no scene key maps to: the table, with the field
        "" => param("hopper.control", format!("is invalid ({e})")),
        key => param(key, why),
    }
}

/// The longest time whose control steps of `dt_s` are at most [`MAX_STEPS`]: the default
/// `max_time_s` at a fast rate. It is computed from the controller's own (f32) period, so
/// that `time / dt_s` never rounds past the cap ([`SampledConfig::validate`]).
pub fn longest_time_s(dt_s: f64) -> f64 {
    let cap = MAX_STEPS as f64;
    let mut t = cap * dt_s;
    while t / dt_s > cap {
        t = t.next_down();
    }
    t
}

impl SampledConfig {
    /// A configuration with the controller's parameters from `law` ([`controller_params`]),
    /// `cycles` hops from an apex at `start_height_m`, at most 60 s per requested cycle plus
    /// 10 s (and at most [`MAX_STEPS`] control steps), period tolerance 1e-3, exact
    /// comparison on, nothing recorded.
    pub fn new(
        model: ValveModel,
        law: &ThrustLaw,
        rate_hz: f64,
        detector: &DetectorOptions,
        sensor: SensorConfig,
        start_height_m: f64,
        cycles: usize,
    ) -> Result<Self, SampledError> {
        let control = controller_params(&model, law, rate_hz, &sensor, detector)?;
        let dt_s = f64::from(control.dt_s);
        Ok(Self {
            model,
            start_height_m,
            control,
            sensor,
            cycles,
            max_time_s: (10.0 + 60.0 * cycles as f64).min(longest_time_s(dt_s)),
            settle_tolerance: 1e-3,
            compare_exact: true,
            record_cycles: false,
            timeline: None,
        })
    }

    /// The control period, s (the f32 period widened exactly).
    pub fn dt_s(&self) -> f64 {
        f64::from(self.control.dt_s)
    }

    /// Control steps the run may take at most.
    #[inline]
    pub fn max_steps(&self) -> u64 {
        (self.max_time_s / self.dt_s()).ceil() as u64
    }

    /// The exact simulator's thrust law for the controller's parameters (f64).
    pub fn exact_law(&self) -> Result<ThrustLaw, SampledError> {
        let delta = f64::from(self.control.thrust_duration_s);
        let t = self.control.thrust;
        Ok(if t.is_raibert() {
            // no gain: tau0 every stance
            ThrustLaw::Raibert(
                RaibertThrust::new(f64::from(t.nominal_thrust_mps2), delta)
                    .map_err(control_error)?,
            )
        } else {
            ThrustLaw::EnergyServo(
                EnergyServoThrust::new(
                    f64::from(t.nominal_thrust_mps2),
                    f64::from(t.gain_per_m),
                    f64::from(t.target_energy_jpkg),
                    f64::from(t.max_thrust_mps2),
                    delta,
                )
                .map_err(control_error)?,
            )
        })
    }

    /// Check every setting; the error names the scene key.
    pub fn validate(&self) -> Result<(), SampledError> {
        self.control.validate().map_err(control_error)?;
        let chi_l = self.model.liftoff_m();
        if !(self.start_height_m.is_finite() && self.start_height_m >= chi_l) {
            return Err(param(
                "hopper.initial_heights_m",
                "must be >= hopper.liftoff_height_m (a sampled run starts in flight)",
            ));
        }
        if self.cycles == 0 || self.cycles > MAX_CYCLES {
            return Err(param(
                "hopper.cycles",
                format!("must be in 1..={MAX_CYCLES}"),
            ));
        }
        if !(self.max_time_s.is_finite() && self.max_time_s > 0.0) {
            return Err(param("hopper.control.max_time_s", "must be a number > 0"));
        }
        if self.max_time_s / self.dt_s() > MAX_STEPS as f64 {
            return Err(param(
                "hopper.control.max_time_s",
                format!("x hopper.control.rate_hz must be <= {MAX_STEPS} control steps"),
            ));
        }
        if !(self.settle_tolerance.is_finite() && self.settle_tolerance > 0.0) {
            return Err(param(
                "hopper.control.settle_tolerance",
                "must be a number > 0",
            ));
        }
        self.validate_sensor()
    }

    fn validate_sensor(&self) -> Result<(), SampledError> {
        let s = &self.sensor;
        let rate_c = 1.0 / self.dt_s();
        let rate = s.rate_hz.unwrap_or(rate_c);
        if !(rate.is_finite() && rate > 0.0) {
            return Err(param("hopper.sensor.rate_hz", "must be a number > 0"));
        }
        // rate_c is 1 / the f32 period, within f32's rounding of the scene's rate (whose
        // exact limit the scene checks, `check_control`): allow that rounding here
        if rate > MAX_SENSOR_RATE_RATIO * rate_c * (1.0 + PERIOD_ROUNDING) {
            return Err(param(
                "hopper.sensor.rate_hz",
                format!("must be <= {MAX_SENSOR_RATE_RATIO} x hopper.control.rate_hz"),
            ));
        }
        // a slower sensor repeats its sample for rate_c / rate steps: not stale
        let repeats = (rate_c / rate * (1.0 - 1e-9)).ceil();
        if repeats > f64::from(self.control.stale_limit_steps) {
            return Err(param(
                "hopper.control.stale_limit_steps",
                format!(
                    "must be >= {repeats}: the sensor repeats each sample that many control steps"
                ),
            ));
        }
        let nonneg = |key, v: f64| {
            if v.is_finite() && v >= 0.0 {
                Ok(())
            } else {
                Err(param(key, "must be a number >= 0"))
            }
        };
        nonneg("hopper.sensor.noise_sigma_m", s.compression_noise_m)?;
        nonneg("hopper.sensor.height_noise_sigma_m", s.height_noise_m)?;
        nonneg("hopper.sensor.quantization_m", s.quantization_m)?;
        nonneg("hopper.sensor.latency_s", s.latency_s)?;
        if s.latency_s * rate > MAX_PENDING_SAMPLES {
            return Err(param(
                "hopper.sensor.latency_s",
                format!("x the sample rate must be <= {MAX_PENDING_SAMPLES} samples in flight"),
            ));
        }
        Ok(())
    }
}

/// How a sampled run ended.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum SampledEnd {
    /// All requested cycles completed.
    Completed,
    /// `max_time_s` passed first (e.g. the hopper stalled on the ground).
    TimeLimit,
    /// The plant's state became non-finite.
    NonFinite,
    /// The full model's integrator hit its step cap.
    StepCap,
    /// Too many events within one control period.
    PieceCap,
}

impl From<PlantError> for SampledEnd {
    fn from(e: PlantError) -> Self {
        match e {
            PlantError::NonFinite => SampledEnd::NonFinite,
            PlantError::StepCap => SampledEnd::StepCap,
            PlantError::PieceCap => SampledEnd::PieceCap,
        }
    }
}

/// Everything a sampled run produced.
#[derive(Clone, Debug, PartialEq)]
pub struct SampledRun {
    /// Completed cycles.
    pub cycles: usize,
    /// The settled period and how it was judged.
    pub settle: Settle,
    /// Apex heights of the last [`LATE_APEXES`] cycles, m.
    pub late_apex_heights_m: Vec<f64>,
    /// Hop heights (apex - chi_l) of the last 64 cycles, m.
    pub recent_hop_heights_m: Vec<f64>,
    /// The exact-thrust orbit, if asked for and settled.
    pub exact: Option<ExactOrbit>,
    /// See the module doc.
    pub fixed_point_error: Option<f64>,
    /// Detected against true phase transitions.
    pub phase_detection_errors: PhaseDetectionErrors,
    /// Control steps taken.
    pub control_steps: u64,
    /// Steps answered with the safe command, by fault.
    pub safe: SafeSteps,
    /// Commands with an open valve and a thrust that is not finite or outside
    /// [0, the law's maximum] (the plant closed the valve instead).
    pub invalid_commands: u64,
    /// Liftoffs with the valve still open.
    pub early_liftoffs: u64,
    /// Simulated time at the end, s.
    pub sim_time_s: f64,
    /// How the run ended.
    pub end: SampledEnd,
    /// Integrator steps (full model).
    pub integrator_steps: u64,
    /// Per-cycle records (if asked for).
    pub records: Vec<SampledCycle>,
    /// Timeline rows (if asked for).
    pub timeline: Vec<TimelineRow>,
}

impl SampledRun {
    /// The settled period (`None`: not settled).
    pub fn period(&self) -> Option<usize> {
        self.settle.period
    }

    /// The JSON summary: the settled period, its distance from the exact orbit, phase
    /// detection and the run's health.
    pub fn summary(&self) -> SampledSummary<'_> {
        SampledSummary {
            cycles: self.cycles,
            period: self.settle.period,
            late_apex_heights_m: &self.late_apex_heights_m,
            fixed_point_error: self.fixed_point_error,
            exact_orbit: self.exact.as_ref(),
            phase_detection_errors: &self.phase_detection_errors,
            settle: &self.settle,
            end: self.end,
            control_steps: self.control_steps,
            safe_steps: self.safe.safe_steps,
            faults: self.safe.every_fault(),
            invalid_commands: self.invalid_commands,
            early_liftoffs: self.early_liftoffs,
            sim_time_s: self.sim_time_s,
            integrator_steps: self.integrator_steps,
        }
    }
}

/// The JSON summary of a sampled run (`serde_json::to_value(run.summary())`).
#[derive(Clone, Copy, Debug, Serialize)]
pub struct SampledSummary<'a> {
    /// Completed cycles.
    pub cycles: usize,
    /// Settled period, `null` if not settled.
    pub period: Option<usize>,
    /// Apex heights of the last cycles, m.
    pub late_apex_heights_m: &'a [f64],
    /// Relative error of the settled hop heights against the exact-thrust orbit.
    pub fixed_point_error: Option<f64>,
    /// The exact-thrust orbit (`hop_heights_m`, `source`).
    pub exact_orbit: Option<&'a ExactOrbit>,
    /// Detected against true phase transitions.
    pub phase_detection_errors: &'a PhaseDetectionErrors,
    /// How the period was judged.
    pub settle: &'a Settle,
    /// How the run ended.
    pub end: SampledEnd,
    /// Control steps.
    pub control_steps: u64,
    /// Safe-state steps.
    pub safe_steps: u64,
    /// Safe steps by fault (every fault code, 0 for those that did not occur).
    pub faults: EveryFault<'a>,
    /// Rejected commands.
    pub invalid_commands: u64,
    /// Liftoffs during the thrust.
    pub early_liftoffs: u64,
    /// Simulated time, s.
    pub sim_time_s: f64,
    /// Integrator steps (full model).
    pub integrator_steps: u64,
}

/// Run `cfg` with the core linked in (SIL).
pub fn run_sil(cfg: &SampledConfig) -> Result<SampledRun, SampledError> {
    let mut sil = Sil::<HopController>::new(cfg.control)?;
    run_sampled(cfg, &mut sil)
}

/// Run `cfg` closed through `controller` (SIL, or HIL: the firmware configured with
/// `cfg.control`).
pub fn run_sampled(
    cfg: &SampledConfig,
    controller: &mut dyn StepController<HopController>,
) -> Result<SampledRun, SampledError> {
    run_sampled_with(cfg, controller, &mut |_| {})
}

/// [`run_sampled`], handing every completed cycle to `on_cycle` as it completes (a trace
/// streamed to disk, whatever the run's length).
pub fn run_sampled_with(
    cfg: &SampledConfig,
    controller: &mut dyn StepController<HopController>,
    on_cycle: &mut dyn FnMut(&SampledCycle),
) -> Result<SampledRun, SampledError> {
    cfg.validate()?;
    let s = &cfg.sensor;
    let exact = s.compression_noise_m <= 0.0 && s.height_noise_m <= 0.0 && s.quantization_m <= 0.0;
    let (c, k) = (controller, on_cycle);
    match (s.rate_hz, exact) {
        (None, true) => with_delay(cfg, c, k, AtControlSteps::default(), Exact),
        (None, false) => with_delay(cfg, c, k, AtControlSteps::default(), measured(s)),
        (Some(r), true) => with_delay(cfg, c, k, Periodic::new(r), Exact),
        (Some(r), false) => with_delay(cfg, c, k, Periodic::new(r), measured(s)),
    }
}

fn measured(s: &SensorConfig) -> sensor::Measured<3> {
    let (c, h, q) = (s.compression_noise_m, s.height_noise_m, s.quantization_m);
    sensor::measured(c, h, q, s.seed)
}

type Sink<'a> = &'a mut dyn FnMut(&SampledCycle);

fn with_delay<C: Clock, M: Measure<3>>(
    cfg: &SampledConfig,
    ctrl: &mut dyn StepController<HopController>,
    sink: Sink<'_>,
    clock: C,
    measure: M,
) -> Result<SampledRun, SampledError> {
    let s = &cfg.sensor;
    let h = s.body_height;
    if s.latency_s > 0.0 {
        let delay = Latency::new(s.latency_s);
        stepped(cfg, ctrl, sink, HopSensor::new(clock, measure, delay, h))
    } else {
        let delay = NoLatency::default();
        stepped(cfg, ctrl, sink, HopSensor::new(clock, measure, delay, h))
    }
}

fn truth(plant: &ValvePlant) -> Truth {
    let s = plant.state();
    Truth {
        compression_m: plant.compression_m(),
        contact: s.contact,
        height_m: s.height_m,
    }
}

/// The true phase at a control step, before its command applies.
fn true_phase(plant: &ValvePlant) -> StancePhase {
    let s = plant.state();
    match (s.contact, s.valve_open, s.velocity_mps < 0.0) {
        (false, _, _) => StancePhase::Flight,
        (true, true, _) => StancePhase::Thrust,
        (true, false, true) => StancePhase::Compression,
        (true, false, false) => StancePhase::Decompression,
    }
}

/// The hopper sampled at the controller's rate: the plant, its sensor, the run's records.
struct Sampled<'a, C, M, D> {
    cfg: &'a SampledConfig,
    plant: ValvePlant,
    sensor: HopSensor<C, M, D>,
    tr: Tracker<'a>,
    /// Largest valid thrust, m/s^2.
    max_thrust: f64,
    /// The truth and true phase at the current step, and the measured compression (m) its
    /// frame carries.
    at_step: (Truth, StancePhase, Option<f64>),
    invalid_commands: u64,
}

impl<C: Clock, M: Measure<3>, D: Delay<3>> SampledPlant<HopController> for Sampled<'_, C, M, D> {
    type End = SampledEnd;
    type Error = SampledError;

    fn done(&self) -> Option<SampledEnd> {
        (self.tr.completed() >= self.cfg.cycles).then_some(SampledEnd::Completed)
    }

    fn frame(&mut self, _k: u64, t_k: f64) -> HopFrame {
        // samples due now are taken before the frame is formed
        for _ in 0..64 {
            if self.sensor.next_sample_time_s() > t_k + TIME_SLACK_S {
                break;
            }
            self.sensor.sample(t_k, truth(&self.plant));
        }
        let truth_k = truth(&self.plant);
        let phase_k = true_phase(&self.plant);
        let (frame, measured) = self.sensor.frame(t_k, truth_k);
        self.at_step = (truth_k, phase_k, measured.map(|m| m.compression_m));
        frame
    }

    fn apply(&mut self, _k: u64, t_k: f64, cmd: &HopCommand) {
        let valid = cmd.thrust_mps2.is_finite()
            && f64::from(cmd.thrust_mps2) >= 0.0
            && f64::from(cmd.thrust_mps2) <= self.max_thrust;
        if cmd.valve_open && !valid {
            self.invalid_commands += 1;
        }
        let open = cmd.valve_open && valid;
        let (truth_k, phase_k, measured) = self.at_step;
        self.tr
            .on_command(t_k, cmd, open, truth_k, phase_k, measured);
        self.plant.set_valve(open, f64::from(cmd.thrust_mps2));
    }

    fn advance(&mut self, _k: u64, t_next: f64) -> Result<ControlFlow<SampledEnd>, SampledError> {
        let tr = &mut self.tr;
        // the sensor's own samples between the steps: the plant stops at each
        for _ in 0..64 {
            let ts = self.sensor.next_sample_time_s();
            if ts >= t_next - TIME_SLACK_S {
                break;
            }
            if let Err(e) = self.plant.advance_to(ts, &mut |e| tr.on_event(e)) {
                return Ok(ControlFlow::Break(e.into()));
            }
            self.sensor.sample(ts, truth(&self.plant));
        }
        Ok(
            match self.plant.advance_to(t_next, &mut |e| tr.on_event(e)) {
                Err(e) => ControlFlow::Break(e.into()),
                Ok(()) => ControlFlow::Continue(()),
            },
        )
    }
}

/// The fixed-rate run, closed by [`drive`].
fn stepped<C: Clock, M: Measure<3>, D: Delay<3>>(
    cfg: &SampledConfig,
    ctrl: &mut dyn StepController<HopController>,
    sink: Sink<'_>,
    sensor: HopSensor<C, M, D>,
) -> Result<SampledRun, SampledError> {
    let plant = ValvePlant::new(cfg.model, cfg.start_height_m, 0.0);
    let mut run = Sampled {
        cfg,
        at_step: (truth(&plant), true_phase(&plant), None),
        plant,
        sensor,
        tr: Tracker::new(cfg, sink),
        max_thrust: f64::from(cfg.control.thrust.max_thrust_mps2()),
        invalid_commands: 0,
    };
    let driven = drive(ctrl, &mut run, cfg.dt_s(), cfg.max_steps())?;
    let end = match driven.end {
        Some(e) => e,
        None if run.tr.completed() >= cfg.cycles => SampledEnd::Completed,
        None => SampledEnd::TimeLimit,
    };
    finish(cfg, run, driven.safe, end)
}

fn finish<C, M, D>(
    cfg: &SampledConfig,
    run: Sampled<'_, C, M, D>,
    safe: SafeSteps,
    end: SampledEnd,
) -> Result<SampledRun, SampledError> {
    let (tr, plant) = (run.tr, &run.plant);
    let recent = tr.recent_hop_heights();
    let settle = settled_period(&recent, cfg.settle_tolerance);
    let exact = if cfg.compare_exact {
        exact_orbit(&cfg.model, &cfg.exact_law()?, cfg.start_height_m)?
    } else {
        None
    };
    let fixed_point_error = match (settle.period, &exact) {
        (Some(p), Some(ex)) => Some(orbit_error(&recent, p, ex)),
        _ => None,
    };
    let parts = tr.into_parts();
    Ok(SampledRun {
        cycles: parts.completed,
        settle,
        late_apex_heights_m: parts.late_apexes,
        recent_hop_heights_m: recent,
        exact,
        fixed_point_error,
        phase_detection_errors: parts.errors,
        control_steps: safe.steps,
        safe,
        invalid_commands: run.invalid_commands,
        early_liftoffs: parts.early_liftoffs,
        sim_time_s: plant.state().time_s,
        end,
        integrator_steps: plant.integrator_steps(),
        records: parts.records,
        timeline: parts.timeline,
    })
}

/// The relative distance between the settled orbit and the exact one: each phase mean of
/// the settled orbit (its last window) against the nearest exact value, and each exact
/// value against the nearest phase mean, the largest |h - h*| / h*. Periods may differ (a
/// sampled orbit locked into a small 2-cycle around an exact fixed point, or sitting on one
/// branch of an exact 2-cycle, both count at their distance).
fn orbit_error(recent: &[f64], p: usize, exact: &ExactOrbit) -> f64 {
    let w = stats::SETTLE_WINDOW.min(recent.len());
    let tail = &recent[recent.len() - w..];
    let means: Vec<f64> = (0..p)
        .map(|j| {
            let (sum, n) = tail
                .iter()
                .skip(j)
                .step_by(p)
                .fold((0.0, 0.0), |(s, n), v| (s + v, n + 1.0));
            sum / f64::max(n, 1.0)
        })
        .collect();
    let rel = |m: f64, e: f64| (m - e).abs() / e.abs();
    let nearest = |m: f64| {
        exact
            .hop_heights_m
            .iter()
            .map(|&e| rel(m, e))
            .fold(f64::INFINITY, f64::min)
    };
    let covered = |e: f64| {
        means
            .iter()
            .map(|&m| rel(m, e))
            .fold(f64::INFINITY, f64::min)
    };
    let a = means.iter().map(|&m| nearest(m)).fold(0.0, f64::max);
    let b = exact
        .hop_heights_m
        .iter()
        .map(|&e| covered(e))
        .fold(0.0, f64::max);
    a.max(b)
}
