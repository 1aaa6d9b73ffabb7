//! The line juggler's scene schema: one struct per TOML table, defaults in `Default` impls
//! (every key, its unit and its default: `docs/scenes.md`).
//!
//! A table that is absent switches its effect off (`[sensor]`, `[jitter]`, `[drag]`).
//! Parsing goes `toml::Table -> (--set overrides) -> Scene` with unknown keys rejected
//! (`deny_unknown_fields`) and every error carrying the dotted key path; then
//! [`Scene::validate`] checks ranges and cross-field rules.

use crate::scene::{apply_set, deserialize, SceneError};
use dexter_core::control::ControllerParams;
use serde::Deserialize;
use std::path::Path;

/// An f32 default as the f64 with the same shortest decimal form (0.02f32 -> 0.02).
fn widen(x: f32) -> f64 {
    x.to_string().parse().unwrap_or(f64::from(x))
}

/// A whole scene file.
#[derive(Clone, Debug, Default, PartialEq, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Scene {
    /// `[scene]`: name and model.
    pub scene: Meta,
    /// `[physics]`: gravity and restitution.
    pub physics: Physics,
    /// `[ball]`: initial ball state.
    pub ball: Ball,
    /// `[stop]`: when a run ends.
    pub stop: Stop,
    /// `[control]`: who moves the paddle.
    pub control: Control,
    /// `[table]`: the fixed surface when `control.mode = "none"`.
    pub table: Table,
    /// `[actuator]`: how the commanded acceleration becomes paddle motion (SIL/HIL).
    pub actuator: Actuator,
    /// `[sensor]`: sampled, noisy, delayed, quantized ball measurement; absent = the
    /// controller sees the true ball height at every control step.
    pub sensor: Option<Sensor>,
    /// `[jitter]`: impact-timing jitter; absent = off.
    pub jitter: Option<Jitter>,
    /// `[drag]`: quadratic air drag on the ball (numerically integrated); absent = off.
    pub drag: Option<Drag>,
    /// `[zeno]`: when infinitely many bounces in finite time become resting contact.
    pub zeno: Zeno,
    /// `[analysis]`: convergence and period detection.
    pub analysis: Analysis,
}

/// The mechanical model a scene describes.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Model {
    /// A ball and a paddle (or table) on a vertical line (Rizzi & Koditschek sec. 2).
    #[default]
    Line,
}

/// `[scene]`.
#[derive(Clone, Debug, Default, PartialEq, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Meta {
    /// A name for reports and plot file stems (default: the file stem, or `scene`).
    pub name: Option<String>,
    /// The model: `line` (default). Planar and hopper models slot in here.
    pub model: Model,
}

/// `[physics]`.
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Physics {
    /// Gravity g, m/s^2 (> 0). Default 9.81.
    pub gravity_mps2: f64,
    /// Coefficient of restitution e (alpha in the paper), dimensionless, in [0, 1]. Default 0.8.
    pub restitution: f64,
}

impl Default for Physics {
    fn default() -> Self {
        Self {
            gravity_mps2: 9.81,
            restitution: 0.8,
        }
    }
}

/// `[ball]`: the initial state at t = 0.
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Ball {
    /// Initial height above the impact plane, m. Default 1.0.
    pub height_m: f64,
    /// Initial vertical velocity, m/s, positive up. Default 0.0 (dropped from rest: an apex).
    pub velocity_mps: f64,
}

impl Default for Ball {
    fn default() -> Self {
        Self {
            height_m: 1.0,
            velocity_mps: 0.0,
        }
    }
}

/// `[stop]`: a run ends at whichever limit comes first.
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Stop {
    /// Impacts to simulate (>= 1). Default 100.
    pub impacts: u64,
    /// Simulated time limit, s (> 0). Default 600.
    pub duration_s: f64,
}

impl Default for Stop {
    fn default() -> Self {
        Self {
            impacts: 100,
            duration_s: 600.0,
        }
    }
}

/// Who moves the paddle.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ControlMode {
    /// No controller: the ball bounces on a fixed table (`[table]`).
    #[default]
    None,
    /// The paper's gedanken juggler: the paddle follows r = -k(w) b exactly and
    /// continuously from the true ball state (f64 mirror law, no sensor, no actuator).
    IdealMirror,
    /// The core's f32 `Controller`, stepped at `control.rate_hz` (software in the loop, or
    /// the firmware in QEMU with `dexter run --hil`).
    Sil,
}

/// `[control]`: the mirror law and, for `sil`, the core controller's parameters.
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Control {
    /// `none` (default), `ideal_mirror` or `sil`.
    pub mode: ControlMode,
    /// Target apex height h*, m (> 0). Required unless `mode = "none"`.
    pub target_apex_m: Option<f64>,
    /// Mirror gain kappa0, dimensionless, in [0, 1). Default: matched,
    /// (1 - e)/(1 + e) with e = `physics.restitution`.
    pub kappa0: Option<f64>,
    /// Energy-feedback gain kappa1, s^2/m^2 (>= 0). Default 0.02.
    pub kappa1_s2pm2: f64,
    /// Control rate, Hz (> 0), `sil` only. Default 500.
    pub rate_hz: f64,
    /// Tracking stiffness, 1/s^2 (>= 0), `sil` only. Default 2500.
    pub kp_per_s2: f64,
    /// Tracking damping, 1/s (>= 0), `sil` only. Default 100.
    pub kd_per_s: f64,
    /// Paddle height held without a valid estimate, m. Default 0.
    pub home_height_m: f64,
    /// Lowest plausible measured ball height, m. Default -0.5.
    pub ball_height_min_m: f64,
    /// Highest plausible measured ball height, m. Default 20.
    pub ball_height_max_m: f64,
    /// Control periods without a new sample before the input is stale (>= 1). Default 5.
    pub stale_limit_steps: u16,
    /// `[control.limits]`: the paddle limits the controller enforces.
    pub limits: Limits,
    /// `[control.estimator]`: the core's ball estimator.
    pub estimator: Estimator,
}

impl Default for Control {
    fn default() -> Self {
        let p = ControllerParams::default();
        Self {
            mode: ControlMode::None,
            target_apex_m: None,
            kappa0: None,
            kappa1_s2pm2: widen(p.kappa1_s2pm2),
            rate_hz: 1.0 / widen(p.dt_s),
            kp_per_s2: widen(p.kp_per_s2),
            kd_per_s: widen(p.kd_per_s),
            home_height_m: widen(p.home_height_m),
            ball_height_min_m: widen(p.ball_height_min_m),
            ball_height_max_m: widen(p.ball_height_max_m),
            stale_limit_steps: p.stale_limit_steps,
            limits: Limits::default(),
            estimator: Estimator::default(),
        }
    }
}

/// `[control.limits]`: paddle limits the core's tracker enforces.
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Limits {
    /// Lowest paddle height, m. Default -0.3.
    pub min_height_m: f64,
    /// Highest paddle height, m (> min). Default 0.1.
    pub max_height_m: f64,
    /// Largest paddle speed, m/s (> 0). Default 3.
    pub velocity_max_mps: f64,
    /// Largest paddle acceleration, m/s^2 (> 0). Default 200.
    pub accel_max_mps2: f64,
}

impl Default for Limits {
    fn default() -> Self {
        let l = ControllerParams::default().limits;
        Self {
            min_height_m: widen(l.min_height_m),
            max_height_m: widen(l.max_height_m),
            velocity_max_mps: widen(l.velocity_max_mps),
            accel_max_mps2: widen(l.accel_max_mps2),
        }
    }
}

/// `[control.estimator]`: the core's alpha-beta ball estimator.
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Estimator {
    /// Position gain, dimensionless, in (0, 1]. Default 0.1.
    pub gain_position: f64,
    /// Velocity gain (applied as gain/dt), dimensionless, in (0, 2). Default 0.005.
    pub gain_velocity: f64,
    /// Largest accepted innovation, m (> 0). Default 0.05.
    pub gate_m: f64,
    /// Consecutive outliers before re-initialisation (>= 1). Default 3.
    pub reinit_after: u8,
    /// Accepted samples before the estimate is valid. Default 25.
    pub settle_samples: u8,
    /// Latency the estimator compensates, s (>= 0). Default: `sensor.latency_s` (0 without a sensor).
    pub latency_s: Option<f64>,
    /// Restitution the estimator's impact model assumes, in [0, 1]. Default: `physics.restitution`.
    pub restitution: Option<f64>,
}

impl Default for Estimator {
    fn default() -> Self {
        let e = ControllerParams::default().estimator;
        Self {
            gain_position: widen(e.gain_position),
            gain_velocity: widen(e.gain_velocity),
            gate_m: widen(e.gate_m),
            reinit_after: e.reinit_after,
            settle_samples: e.settle_samples,
            latency_s: None,
            restitution: None,
        }
    }
}

/// `[table]`: the fixed surface of a passive scene.
#[derive(Clone, Debug, Default, PartialEq, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Table {
    /// Table height, m. Default 0.
    pub height_m: f64,
}

/// How a commanded paddle acceleration becomes paddle motion.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ActuatorKind {
    /// The paddle's acceleration equals the command over each control period (zero-order
    /// hold): no limits.
    #[default]
    Ideal,
    /// The paddle is a driven mass (second order: force -> acceleration -> velocity ->
    /// position) with a force limit per unit mass (`accel_max_mps2`), a speed limit and
    /// hard travel stops.
    SecondOrder,
}

/// `[actuator]`.
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Actuator {
    /// `ideal` (default) or `second_order`.
    pub kind: ActuatorKind,
    /// Paddle height at t = 0, m. Default 0.
    pub initial_height_m: f64,
    /// `second_order`: largest force per unit paddle mass, m/s^2 (> 0). Default 250.
    pub accel_max_mps2: f64,
    /// `second_order`: largest paddle speed, m/s (> 0). Default 4.
    pub velocity_max_mps: f64,
    /// `second_order`: lower travel stop, m. Default -0.35.
    pub min_height_m: f64,
    /// `second_order`: upper travel stop, m (> min). Default 0.15.
    pub max_height_m: f64,
}

impl Default for Actuator {
    fn default() -> Self {
        Self {
            kind: ActuatorKind::Ideal,
            initial_height_m: 0.0,
            accel_max_mps2: 250.0,
            velocity_max_mps: 4.0,
            min_height_m: -0.35,
            max_height_m: 0.15,
        }
    }
}

/// `[sensor]`: a sampled ball-height sensor.
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Sensor {
    /// Sample rate, Hz (> 0). Default: `control.rate_hz`.
    pub rate_hz: Option<f64>,
    /// Standard deviation of additive Gaussian noise, m (>= 0). Default 0.
    pub noise_sigma_m: f64,
    /// Delay from sampling to delivery, s (>= 0). Default 0.
    pub latency_s: f64,
    /// Quantization step of the reported height, m (>= 0, 0 = none). Default 0.
    pub quantization_m: f64,
    /// Seed of the noise generator. Default 1.
    pub seed: u64,
}

impl Default for Sensor {
    fn default() -> Self {
        Self {
            rate_hz: None,
            noise_sigma_m: 0.0,
            latency_s: 0.0,
            quantization_m: 0.0,
            seed: 1,
        }
    }
}

/// `[jitter]`: impact-timing jitter (Zumel & Erdmann: about 10 ms).
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Jitter {
    /// Standard deviation of the impact-time offset, s (>= 0). Default 0.01.
    pub sigma_s: f64,
    /// Seed of the jitter generator. Default 2.
    pub seed: u64,
}

impl Default for Jitter {
    fn default() -> Self {
        Self {
            sigma_s: 0.01,
            seed: 2,
        }
    }
}

/// Integration method for effects without a closed form.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Integrator {
    /// Classical fixed-step Runge-Kutta 4 with `step_s`.
    #[default]
    Rk4,
    /// Adaptive Dormand-Prince 5(4) with `tolerance`, first step `step_s`.
    Rk45,
}

/// `[drag]`: quadratic air drag, b'' = -g - c |b'| b'.
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Drag {
    /// Drag coefficient c = rho C_d A / (2 m), 1/m (>= 0). Default 0.01 (a ~ table-tennis ball is ~0.1).
    pub coefficient_per_m: f64,
    /// `rk4` (default) or `rk45`.
    pub integrator: Integrator,
    /// RK4 step, or RK45 initial step, s (> 0). Default 0.001.
    pub step_s: f64,
    /// RK45 local error tolerance, m (> 0). Default 1e-9.
    pub tolerance: f64,
}

impl Default for Drag {
    fn default() -> Self {
        Self {
            coefficient_per_m: 0.01,
            integrator: Integrator::Rk4,
            step_s: 1e-3,
            tolerance: 1e-9,
        }
    }
}

/// `[zeno]`: resting-contact detection.
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Zeno {
    /// A bounce whose relative take-off speed is below this is the start of a Zeno
    /// sequence, m/s (>= 0). Default 1e-6.
    pub velocity_threshold_mps: f64,
    /// Relative part of the threshold, times the paddle speed at impact (>= 0). Default 1e-6.
    pub relative_threshold: f64,
    /// Cap on impacts inside one segment before contact is forced (>= 1). Default 10000.
    pub max_impacts_per_segment: u32,
}

impl Default for Zeno {
    fn default() -> Self {
        Self {
            velocity_threshold_mps: 1e-6,
            relative_threshold: 1e-6,
            max_impacts_per_segment: 10_000,
        }
    }
}

/// `[analysis]`.
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Analysis {
    /// Relative band around the target apex that counts as converged. Default 0.01.
    pub converge_tolerance: f64,
    /// Relative tolerance for period detection over the last apexes. Default 1e-3.
    pub period_tolerance: f64,
    /// Longest period searched for, impacts (>= 1). Default 8.
    pub max_period: u32,
}

impl Default for Analysis {
    fn default() -> Self {
        Self {
            converge_tolerance: 0.01,
            period_tolerance: 1e-3,
            max_period: 8,
        }
    }
}

impl Scene {
    /// Parse and validate a scene from TOML text, after applying `overrides`
    /// (`key.path=value` pairs, see [`crate::scene::parse_set`]).
    pub fn from_toml_str(
        text: &str,
        overrides: &[(String, toml::Value)],
    ) -> Result<Self, SceneError> {
        let mut table: toml::Table = text.parse().map_err(|e: toml::de::Error| {
            SceneError::whole(format!("not valid TOML: {}", e.message()))
        })?;
        for (key, value) in overrides {
            apply_set(&mut table, key, value.clone())?;
        }
        Self::from_table(table)
    }

    /// Deserialize and validate a scene from an already parsed table.
    pub fn from_table(table: toml::Table) -> Result<Self, SceneError> {
        let scene: Scene = deserialize(table)?;
        scene.validate()?;
        Ok(scene)
    }

    /// Read, parse and validate a scene file; overrides as in [`Scene::from_toml_str`].
    pub fn load(path: &Path, overrides: &[(String, toml::Value)]) -> Result<Self, SceneError> {
        let file = crate::scene::SceneFile::read(path)?;
        Self::from_table(file.table_with(overrides)?)
    }
}

/// Give a scene table without `scene.name` the name `stem`.
pub fn name_after(table: &mut toml::Table, stem: &str) -> Result<(), SceneError> {
    let named = matches!(table.get("scene"), Some(toml::Value::Table(m)) if m.contains_key("name"));
    if named || matches!(table.get("scene"), Some(v) if !v.is_table()) {
        return Ok(());
    }
    apply_set(table, "scene.name", toml::Value::String(stem.to_string()))
}
