//! The sampled hopper's scene: the `[hopper]` table of the exact hopper (model, thrust law,
//! start, cycles; `[hopper.servo]` for the energy servo) plus `[hopper.control]` (the
//! controller's rate and phase detection) and `[hopper.sensor]` (rate, noise, quantization,
//! latency; every effect off by default). Every key, its unit and default:
//! `docs/hopper.md`, "The hopper on the MCU".

use super::super::HopperConfig;
use crate::model::hopper::sampled::{
    DetectorOptions, SampledConfig, SampledError, SensorConfig, TimelineWindow,
    MAX_SENSOR_RATE_RATIO,
};
use crate::model::hopper::valve::ValveModel;
use crate::model::hopper::{HopperModel, Start};
use crate::scene::{deserialize, SceneError};
use serde::Deserialize;

/// Fastest control rate a scene may ask for, Hz.
pub const MAX_RATE_HZ: f64 = 100_000.0;
/// Most hops the `--plot` timeline draws.
pub const MAX_TIMELINE_CYCLES: usize = 10;

/// `[hopper.control]`: the fixed-rate controller (`dexter_core::hop_control`).
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct ControlTable {
    /// Control rate, Hz (> 0, <= [`MAX_RATE_HZ`]). Default 1000.
    pub rate_hz: f64,
    /// Touchdown needs the foot switch and at least this compression, m. Default 0.
    pub touchdown_compression_m: f64,
    /// Liftoff below this compression (besides the foot switch), m; absent = the switch
    /// alone.
    pub liftoff_compression_m: Option<f64>,
    /// The bottom is the compression this far below its running maximum, m. Default 0.
    pub bottom_hysteresis_m: f64,
    /// Consecutive samples a contact change must hold (1..=64). Default 1.
    pub debounce_samples: u8,
    /// Open the valve at the step nearest to the predicted bottom. Default true.
    pub predict_bottom: bool,
    /// Close it at the step nearest to the estimated bottom + delta. Default true.
    pub end_thrust_at_estimate: bool,
    /// Plausible compressions are within +-this, m. Default 2.
    pub max_compression_m: f64,
    /// Periods without a new sample before the input is stale. Default 5.
    pub stale_limit_steps: u16,
    /// Longest simulated time, s. Default 10 + 60 per cycle.
    pub max_time_s: Option<f64>,
    /// Relative tolerance of the settled period (in (0, 1)). Default 1e-3.
    pub settle_tolerance: f64,
    /// Hops the `--plot` timeline draws, the last ones of the run (1..=10). Default 3.
    pub timeline_cycles: usize,
}

impl Default for ControlTable {
    fn default() -> Self {
        let d = DetectorOptions::default();
        Self {
            rate_hz: 1000.0,
            touchdown_compression_m: d.touchdown_compression_m,
            liftoff_compression_m: d.liftoff_compression_m,
            bottom_hysteresis_m: d.bottom_hysteresis_m,
            debounce_samples: d.debounce_samples,
            predict_bottom: d.predict_bottom,
            end_thrust_at_estimate: d.end_thrust_at_estimate,
            max_compression_m: d.max_compression_m,
            stale_limit_steps: d.stale_limit_steps,
            max_time_s: None,
            settle_tolerance: 1e-3,
            timeline_cycles: 3,
        }
    }
}

impl ControlTable {
    fn detector(&self) -> DetectorOptions {
        DetectorOptions {
            touchdown_compression_m: self.touchdown_compression_m,
            liftoff_compression_m: self.liftoff_compression_m,
            bottom_hysteresis_m: self.bottom_hysteresis_m,
            debounce_samples: self.debounce_samples,
            predict_bottom: self.predict_bottom,
            end_thrust_at_estimate: self.end_thrust_at_estimate,
            max_compression_m: self.max_compression_m,
            stale_limit_steps: self.stale_limit_steps,
        }
    }
}

/// `[hopper.sensor]`: every effect off by default (costing nothing when off).
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct SensorTable {
    /// Sample rate, Hz; absent = one sample at every control step.
    pub rate_hz: Option<f64>,
    /// Gaussian noise on the leg compression, m. Default 0.
    pub noise_sigma_m: f64,
    /// Gaussian noise on the body height, m. Default 0.
    pub height_noise_sigma_m: f64,
    /// Quantization step, m. Default 0.
    pub quantization_m: f64,
    /// Latency from sampling to delivery, s (the controller compensates it). Default 0.
    pub latency_s: f64,
    /// Frames carry the body height (the servo's energy from it). Default false.
    pub body_height: bool,
    /// Noise seed. Default 1.
    pub seed: u64,
}

impl Default for SensorTable {
    fn default() -> Self {
        let d = SensorConfig::default();
        Self {
            rate_hz: d.rate_hz,
            noise_sigma_m: d.compression_noise_m,
            height_noise_sigma_m: d.height_noise_m,
            quantization_m: d.quantization_m,
            latency_s: d.latency_s,
            body_height: d.body_height,
            seed: d.seed,
        }
    }
}

impl SensorTable {
    fn config(&self) -> SensorConfig {
        SensorConfig {
            rate_hz: self.rate_hz,
            compression_noise_m: self.noise_sigma_m,
            height_noise_m: self.height_noise_sigma_m,
            quantization_m: self.quantization_m,
            latency_s: self.latency_s,
            body_height: self.body_height,
            seed: self.seed,
        }
    }
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct SampledTables {
    control: ControlTable,
    #[serde(default)]
    sensor: SensorTable,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct SampledFile {
    hopper: SampledTables,
}

/// True if the scene's `[hopper]` table has a `[hopper.control]` table.
pub fn has_control(table: &toml::Table) -> bool {
    table
        .get("hopper")
        .and_then(toml::Value::as_table)
        .is_some_and(|h| h.contains_key("control"))
}

/// A parsed, validated sampled-hopper scene.
#[derive(Clone, Debug, PartialEq)]
pub struct SampledHopperConfig {
    /// The exact hopper's part (`[hopper]` without `control` and `sensor`).
    pub hopper: HopperConfig,
    /// `[hopper.control]` as given.
    pub control: ControlTable,
    /// `[hopper.sensor]` as given.
    pub sensor: SensorTable,
    /// The validated run (no timeline: `run` adds it for `--plot`).
    pub sampled: SampledConfig,
}

impl SampledHopperConfig {
    /// Deserialize and validate; every error names its key.
    pub fn from_table(name: &str, mut table: toml::Table) -> Result<Self, SceneError> {
        let tables = split_off(&mut table);
        let SampledTables { control, sensor } = deserialize::<SampledFile>(tables)?.hopper;
        let hopper = HopperConfig::from_table(name, table)?;
        let model = valve_model(&hopper)?;
        let start_m = single_start(&hopper)?;
        check_control(&control, &hopper)?;
        check_sensor_rate(&sensor, &control)?;
        let cycles = hopper.params.cycles;
        let mut sampled = SampledConfig::new(
            model,
            &hopper.hopper.law,
            control.rate_hz,
            &control.detector(),
            sensor.config(),
            start_m,
            cycles,
        )
        .map_err(scene_error)?;
        if let Some(t) = control.max_time_s {
            sampled.max_time_s = t;
        }
        sampled.settle_tolerance = control.settle_tolerance;
        sampled.validate().map_err(scene_error)?;
        Ok(Self {
            hopper,
            control,
            sensor,
            sampled,
        })
    }

    /// The scene's name.
    pub fn name(&self) -> &str {
        &self.hopper.name
    }

    /// The timeline window of `--plot`: the last `timeline_cycles` hops.
    pub fn timeline(&self) -> TimelineWindow {
        let n = self.control.timeline_cycles;
        TimelineWindow {
            first_cycle: self.sampled.cycles.saturating_sub(n),
            cycles: n,
        }
    }
}

/// Move `hopper.control` and `hopper.sensor` out of `table` into a table of their own.
fn split_off(table: &mut toml::Table) -> toml::Table {
    let mut hopper = toml::Table::new();
    if let Some(toml::Value::Table(h)) = table.get_mut("hopper") {
        for key in ["control", "sensor"] {
            if let Some(v) = h.remove(key) {
                hopper.insert(key.to_string(), v);
            }
        }
    }
    let mut out = toml::Table::new();
    out.insert("hopper".into(), toml::Value::Table(hopper));
    out
}

/// A model error from the sampled run's own validation, under its key.
pub fn scene_error(e: SampledError) -> SceneError {
    match e {
        SampledError::Param { key, message } => SceneError::new(key, message),
        other => SceneError::whole(other),
    }
}

fn valve_model(h: &HopperConfig) -> Result<ValveModel, SceneError> {
    match h.hopper.model {
        HopperModel::Linear(m) => Ok(ValveModel::Linear(m)),
        HopperModel::Full(m) => Ok(ValveModel::Full(m)),
        HopperModel::SimplifiedNonlinear(_) => Err(SceneError::new(
            "hopper.model",
            "is \"simplified_nonlinear\": eq. 9's thrust is an impulse at the bottom, which no valve holds; the sampled hopper ([hopper.control]) needs \"linear\" (eq. 10/16) or \"full\" (eq. 8)",
        )),
    }
}

fn single_start(h: &HopperConfig) -> Result<f64, SceneError> {
    let key = "hopper.initial_heights_m";
    match h.starts.as_slice() {
        [Start::Flight {
            height_m,
            velocity_mps,
        }] if *velocity_mps == 0.0 => Ok(*height_m),
        [Start::Flight { .. }] => Err(SceneError::new(
            "hopper.initial_velocity_mps",
            "must be 0 with [hopper.control] (a sampled run starts at rest at an apex)",
        )),
        [_] => Err(SceneError::new(
            key,
            "must be >= hopper.liftoff_height_m with [hopper.control] (a sampled run starts at an apex)",
        )),
        _ => Err(SceneError::new(
            key,
            "must hold exactly one height with [hopper.control] (one sampled run per scene)",
        )),
    }
}

/// `hopper.sensor.rate_hz` against the documented limit, 16 x `hopper.control.rate_hz`,
/// exactly (the model checks it against the f32 period, which rounds the rate).
fn check_sensor_rate(s: &SensorTable, c: &ControlTable) -> Result<(), SceneError> {
    let Some(rate) = s.rate_hz else {
        return Ok(());
    };
    let most = MAX_SENSOR_RATE_RATIO * c.rate_hz;
    if rate.is_finite() && rate > most {
        return Err(SceneError::new(
            "hopper.sensor.rate_hz",
            format!(
                "must be <= {MAX_SENSOR_RATE_RATIO} x hopper.control.rate_hz = {most} Hz, got {rate}"
            ),
        ));
    }
    Ok(())
}

fn check_control(c: &ControlTable, h: &HopperConfig) -> Result<(), SceneError> {
    if !(c.rate_hz.is_finite() && c.rate_hz > 0.0 && c.rate_hz <= MAX_RATE_HZ) {
        return Err(SceneError::new(
            "hopper.control.rate_hz",
            format!("must be in (0, {MAX_RATE_HZ}] Hz"),
        ));
    }
    if !(c.settle_tolerance > 0.0 && c.settle_tolerance < 1.0) {
        return Err(SceneError::new(
            "hopper.control.settle_tolerance",
            "must be in (0, 1)",
        ));
    }
    if !(1..=MAX_TIMELINE_CYCLES).contains(&c.timeline_cycles) {
        return Err(SceneError::new(
            "hopper.control.timeline_cycles",
            format!("must be in 1..={MAX_TIMELINE_CYCLES}"),
        ));
    }
    if h.params.thrust_delta_s <= 0.0 {
        return Err(SceneError::new(
            "hopper.thrust_delta_s",
            "must be > 0 with [hopper.control] (the valve is held open for delta s)",
        ));
    }
    if h.params.samples_per_phase != 0 {
        return Err(SceneError::new(
            "hopper.samples_per_phase",
            "must be 0 with [hopper.control] (the --plot timeline shows the control steps)",
        ));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::hopper::sampled::MAX_STEPS;

    /// `scenes/hopper-raibert-sil.toml` with `sets` applied, loaded.
    fn raibert(sets: &[(&str, toml::Value)]) -> Result<SampledHopperConfig, SceneError> {
        let text = include_str!("../../../../../scenes/hopper-raibert-sil.toml");
        let mut table: toml::Table = text.parse().unwrap();
        for (key, value) in sets {
            crate::scene::apply_set(&mut table, key, value.clone()).unwrap();
        }
        SampledHopperConfig::from_table("raibert", table)
    }

    /// Finding 13: the default time bound at the step cap, at every rate up to the
    /// documented 100 kHz, is valid (the user set only the rate and the cycles).
    #[test]
    fn the_default_time_bound_never_refuses_a_valid_rate() {
        for rate in [
            1000.0, 3000.0, 7000.0, 10_000.0, 30_000.0, 99_999.0, 100_000.0,
        ] {
            let c = raibert(&[
                ("hopper.control.rate_hz", toml::Value::Float(rate)),
                ("hopper.cycles", toml::Value::Integer(10_000_000)),
            ])
            .unwrap_or_else(|e| panic!("{rate} Hz: {e}"));
            let steps = c.sampled.max_steps();
            assert!(steps <= MAX_STEPS, "{rate} Hz: {steps} steps");
            // the bound is the cap, not far below it (10^9 steps of the f32 period)
            assert!(steps + 2 >= MAX_STEPS, "{rate} Hz: only {steps} steps");
        }
    }

    /// Finding 13: the sensor at exactly 16 x the control rate is accepted, one ulp above
    /// is refused, naming the sensor's key and the bound.
    #[test]
    fn the_sensor_rate_limit_is_exact() {
        for control in [1000.0, 3000.0, 7000.0] {
            let most: f64 = 16.0 * control;
            let set = |r: f64| {
                raibert(&[
                    ("hopper.control.rate_hz", toml::Value::Float(control)),
                    ("hopper.sensor.rate_hz", toml::Value::Float(r)),
                ])
            };
            set(most).unwrap_or_else(|e| panic!("{most} Hz at {control} Hz: {e}"));
            let e = set(most.next_up()).unwrap_err().to_string();
            assert!(e.contains("hopper.sensor.rate_hz"), "{e}");
            assert!(e.contains(&format!("{most}")), "{e}");
        }
    }
}
