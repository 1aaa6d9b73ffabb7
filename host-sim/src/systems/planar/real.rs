//! The `[real_table]` scene table: the planar body on a real table (tilt and stroke drives
//! with limits, a camera, the core's fixed-rate `TiltController` in the loop, SIL or
//! `--hil`), physics in [`crate::model::planar::real_table`]. Without the table a planar
//! scene runs the paper's ideal table. Keys, units and defaults: `docs/planar.md`, "The real
//! table".

use crate::effects::sensor::MAX_PENDING;
use crate::model::planar::camera::CameraConfig;
use crate::model::planar::real_table::{controller_params_for, DriveLimits, RealTable};
use crate::model::planar::{ContactLaw, PlanarModel, PlanarParams};
use crate::scene::SceneError;
use dexter_core::tilt_control::TiltParams;
use serde::{Deserialize, Serialize};

/// Lowest control rate, Hz (the core's largest period, 20 ms).
pub const MIN_CONTROL_RATE_HZ: f64 = 50.0;
/// Highest control rate, Hz (a bound on a run's work per simulated second).
pub const MAX_CONTROL_RATE_HZ: f64 = 10_000.0;
/// Highest camera rate, Hz (a bound on the plant's events per simulated second).
pub const MAX_CAMERA_RATE_HZ: f64 = 100_000.0;
/// Longest `real_table.max_duration_s`, s (a bound on a run's control steps).
pub const MAX_DURATION_S: f64 = 86_400.0;
/// Longest camera latency, s (excluded): the core's estimator compensates less than 0.1 s
/// (`dexter_core::tilt_control::FlightTuning`).
pub const MAX_LATENCY_S: f64 = 0.1;
/// The core's longest plan freeze before an impact, s (`TiltParams::commit_s`, <= 0.2).
pub const MAX_COMMIT_S: f32 = 0.2;

/// Whether the drives obey their limits.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Drives {
    /// Each axis follows its commanded acceleration within its limits (the default).
    #[default]
    Limited,
    /// Each axis follows its commanded acceleration exactly (the "off" effect); the
    /// controller still plans within the limits.
    Ideal,
}

/// `[real_table.tilt]`: the tilt drive, rad.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct TiltDrive {
    /// Lower travel stop, rad (>= -1.2).
    pub min_rad: f64,
    /// Upper travel stop, rad (> min_rad, <= 1.2).
    pub max_rad: f64,
    /// Speed limit, rad/s.
    pub rate_max_radps: f64,
    /// Acceleration limit, rad/s^2.
    pub accel_max_radps2: f64,
}

/// `[real_table.stroke]`: the vertical stroke drive, m.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct StrokeDrive {
    /// Lower travel stop, m.
    pub min_m: f64,
    /// Upper travel stop, m (> min_m).
    pub max_m: f64,
    /// Speed limit, m/s.
    pub velocity_max_mps: f64,
    /// Acceleration limit, m/s^2.
    pub accel_max_mps2: f64,
}

/// `[real_table.stage]`: the x range the table can be under the body's centre of mass, m
/// (its x stage's travel plus the table's half length): the run ends `out_of_travel` when
/// the centre of mass leaves it.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct StageTable {
    /// Lowest x, m (<= 0: the body starts at x = 0).
    pub min_m: f64,
    /// Highest x, m (>= 0).
    pub max_m: f64,
}

/// `[real_table.camera]`: the camera (noise seed: `planar.seed`).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct CameraTable {
    /// false: the true pose at every control step, no latency (the "off" effect).
    pub enabled: bool,
    /// Samples per second, Hz.
    pub rate_hz: f64,
    /// Position noise (sigma) on x and y, m.
    pub noise_m: f64,
    /// Angle noise (sigma), rad.
    pub noise_rad: f64,
    /// Delay from a sample to the controller, s.
    pub latency_s: f64,
    /// Position quantization step, m (0 = none).
    pub quantization_m: f64,
    /// Angle quantization step, rad (0 = none).
    pub quantization_rad: f64,
}

/// `[real_table]`.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct RealTableScene {
    /// The controller's rate, Hz (one step per period).
    pub control_rate_hz: f64,
    /// kappa_w of the tilt-rate term, s (0 = the paper's law; `TiltParams::kappa_rate_s`).
    pub kappa_rate_s: f64,
    /// kappa_x of the horizontal regulation term, rad/m (0 = the paper's law;
    /// `TiltParams::kappa_x_pm`).
    pub kappa_x_pm: f64,
    /// kappa_x' of the same term on x', s/m (`TiltParams::kappa_xdot_spm`).
    pub kappa_xdot_spm: f64,
    /// Safeguarded Newton steps per period for eq. 7's contact time, 1 ..= 4.
    pub contact_iterations: u8,
    /// `limited` or `ideal`.
    pub drives: Drives,
    /// The run ends after this simulated time, s.
    pub max_duration_s: f64,
    /// The tilt drive.
    pub tilt: TiltDrive,
    /// The stroke drive.
    pub stroke: StrokeDrive,
    /// The x range under the body.
    pub stage: StageTable,
    /// The camera.
    pub camera: CameraTable,
}

impl Default for RealTableScene {
    /// [`RealTable::realistic`]: 500 Hz, tilt-rate damping 0.01 s, 2 Newton steps, the
    /// controller's default drive limits, the realistic camera.
    fn default() -> Self {
        let t = RealTable::realistic(0);
        let c = t.controller;
        let cam = CameraConfig::realistic(0);
        Self {
            control_rate_hz: (1.0 / f64::from(c.dt_s)).round(),
            kappa_rate_s: f64::from(c.kappa_rate_s),
            kappa_x_pm: f64::from(c.kappa_x_pm),
            kappa_xdot_spm: f64::from(c.kappa_xdot_spm),
            contact_iterations: c.contact_iterations,
            drives: Drives::Limited,
            max_duration_s: t.max_duration_s,
            tilt: TiltDrive {
                min_rad: f64::from(c.tilt.min_rad),
                max_rad: f64::from(c.tilt.max_rad),
                rate_max_radps: f64::from(c.tilt.rate_max_radps),
                accel_max_radps2: f64::from(c.tilt.accel_max_radps2),
            },
            stroke: StrokeDrive {
                min_m: f64::from(c.stroke.min_m),
                max_m: f64::from(c.stroke.max_m),
                velocity_max_mps: f64::from(c.stroke.velocity_max_mps),
                accel_max_mps2: f64::from(c.stroke.accel_max_mps2),
            },
            stage: StageTable {
                min_m: t.x_range_m[0],
                max_m: t.x_range_m[1],
            },
            camera: CameraTable {
                enabled: true,
                rate_hz: cam.rate_hz,
                noise_m: cam.noise_m,
                noise_rad: cam.noise_rad,
                latency_s: cam.latency_s,
                quantization_m: cam.quantization_m,
                quantization_rad: cam.quantization_rad,
            },
        }
    }
}

impl Default for TiltDrive {
    fn default() -> Self {
        RealTableScene::default().tilt
    }
}

impl Default for StrokeDrive {
    fn default() -> Self {
        RealTableScene::default().stroke
    }
}

impl Default for StageTable {
    fn default() -> Self {
        RealTableScene::default().stage
    }
}

impl StageTable {
    fn range(&self) -> Result<[f64; 2], SceneError> {
        check("real_table.stage.min_m", self.min_m, -1e3, 0.0, false)?;
        check("real_table.stage.max_m", self.max_m, 0.0, 1e3, false)?;
        ordered("real_table.stage.max_m", self.min_m, self.max_m)?;
        Ok([self.min_m, self.max_m])
    }
}

impl Default for CameraTable {
    fn default() -> Self {
        RealTableScene::default().camera
    }
}

/// `key` must be finite and in `lo ..= hi` (`lo` excluded if `open`).
fn check(key: &str, v: f64, lo: f64, hi: f64, open: bool) -> Result<(), SceneError> {
    let ok = v.is_finite() && v <= hi && if open { v > lo } else { v >= lo };
    match ok {
        true => Ok(()),
        false => Err(SceneError::new(
            key,
            format!(
                "must be in {}{lo}, {hi}], got {v}",
                if open { "(" } else { "[" }
            ),
        )),
    }
}

/// `max` must exceed `min` (keys `prefix.min_u`, `prefix.max_u`).
fn ordered(key: &str, min: f64, max: f64) -> Result<(), SceneError> {
    match max > min {
        true => Ok(()),
        false => Err(SceneError::new(
            key,
            format!("must be above the lower stop, got {max} <= {min}"),
        )),
    }
}

impl TiltDrive {
    fn limits(&self) -> Result<DriveLimits, SceneError> {
        check("real_table.tilt.min_rad", self.min_rad, -1.2, 1.2, false)?;
        check("real_table.tilt.max_rad", self.max_rad, -1.2, 1.2, false)?;
        ordered("real_table.tilt.max_rad", self.min_rad, self.max_rad)?;
        check(
            "real_table.tilt.rate_max_radps",
            self.rate_max_radps,
            0.0,
            1e3,
            true,
        )?;
        let a = self.accel_max_radps2;
        check("real_table.tilt.accel_max_radps2", a, 0.0, 1e5, true)?;
        Ok(DriveLimits {
            min: self.min_rad,
            max: self.max_rad,
            velocity_max: self.rate_max_radps,
            accel_max: a,
        })
    }
}

impl StrokeDrive {
    fn limits(&self) -> Result<DriveLimits, SceneError> {
        check("real_table.stroke.min_m", self.min_m, -10.0, 10.0, false)?;
        check("real_table.stroke.max_m", self.max_m, -10.0, 10.0, false)?;
        ordered("real_table.stroke.max_m", self.min_m, self.max_m)?;
        let v = self.velocity_max_mps;
        check("real_table.stroke.velocity_max_mps", v, 0.0, 1e3, true)?;
        let a = self.accel_max_mps2;
        check("real_table.stroke.accel_max_mps2", a, 0.0, 1e5, true)?;
        Ok(DriveLimits {
            min: self.min_m,
            max: self.max_m,
            velocity_max: v,
            accel_max: a,
        })
    }
}

impl CameraTable {
    /// The camera with noise seed `seed`, `None` if disabled.
    fn config(&self, seed: u64) -> Result<Option<CameraConfig>, SceneError> {
        if !self.enabled {
            return Ok(None);
        }
        let k = |name: &str| format!("real_table.camera.{name}");
        check(&k("rate_hz"), self.rate_hz, 0.0, MAX_CAMERA_RATE_HZ, true)?;
        check(&k("noise_m"), self.noise_m, 0.0, 1.0, false)?;
        check(&k("noise_rad"), self.noise_rad, 0.0, 1.0, false)?;
        let latency = self.latency_s;
        if !(latency.is_finite() && latency >= 0.0 && (latency as f32) < MAX_LATENCY_S as f32) {
            return Err(SceneError::new(
                k("latency_s"),
                format!(
                    "must be in [0, {MAX_LATENCY_S}) s (the controller predicts across less than {MAX_LATENCY_S} s of delay), got {latency}"
                ),
            ));
        }
        let in_flight = latency * self.rate_hz;
        if in_flight > MAX_PENDING as f64 {
            return Err(SceneError::new(
                k("latency_s"),
                format!(
                    "x real_table.camera.rate_hz is {in_flight} samples in flight, more than the {MAX_PENDING} the camera holds"
                ),
            ));
        }
        check(&k("quantization_m"), self.quantization_m, 0.0, 1.0, false)?;
        check(
            &k("quantization_rad"),
            self.quantization_rad,
            0.0,
            1.0,
            false,
        )?;
        Ok(Some(CameraConfig {
            rate_hz: self.rate_hz,
            noise_m: self.noise_m,
            noise_rad: self.noise_rad,
            latency_s: self.latency_s,
            quantization_m: self.quantization_m,
            quantization_rad: self.quantization_rad,
            seed,
        }))
    }
}

/// The planar keys the real table cannot honour, as errors naming them.
fn planar_keys_fit(p: &PlanarParams, model: &PlanarModel) -> Result<(), SceneError> {
    if p.timing_noise_s != 0.0 {
        return Err(SceneError::new(
            "planar.timing_noise_s",
            "must be 0 with a [real_table] (its noise is the camera's, real_table.camera)",
        ));
    }
    if !matches!(model.contact, ContactLaw::Frictionless) {
        return Err(SceneError::new(
            "planar.friction_mu",
            "must be 0 with a [real_table] (the controller plans eq. 21's frictionless impact)",
        ));
    }
    Ok(())
}

impl RealTableScene {
    /// The validated real table for `model` (scene `p`): every range error names its key.
    pub fn table(&self, p: &PlanarParams, model: &PlanarModel) -> Result<RealTable, SceneError> {
        planar_keys_fit(p, model)?;
        let rate = self.control_rate_hz;
        check(
            "real_table.control_rate_hz",
            rate,
            MIN_CONTROL_RATE_HZ,
            MAX_CONTROL_RATE_HZ,
            false,
        )?;
        check(
            "real_table.kappa_rate_s",
            self.kappa_rate_s,
            0.0,
            0.1,
            false,
        )?;
        check("real_table.kappa_x_pm", self.kappa_x_pm, 0.0, 1.0, false)?;
        check(
            "real_table.kappa_xdot_spm",
            self.kappa_xdot_spm,
            0.0,
            1.0,
            false,
        )?;
        if !(1..=4).contains(&self.contact_iterations) {
            return Err(SceneError::new(
                "real_table.contact_iterations",
                format!("must be in 1..=4, got {}", self.contact_iterations),
            ));
        }
        check(
            "real_table.max_duration_s",
            self.max_duration_s,
            0.0,
            MAX_DURATION_S,
            true,
        )?;
        let (tilt, stroke) = (self.tilt.limits()?, self.stroke.limits()?);
        let x_range_m = self.stage.range()?;
        let camera = self.camera.config(p.seed)?;
        let mut base = self.controller_base(&tilt, &stroke);
        base.commit_s = self.commit_s(camera.as_ref())?;
        let controller = controller_params_for(model, &base, camera.as_ref())
            .map_err(|e| SceneError::new("real_table", e.to_string()))?;
        let limited = self.drives == Drives::Limited;
        let table = RealTable {
            controller,
            tilt: limited.then_some(tilt),
            stroke: limited.then_some(stroke),
            camera,
            initial_tilt_rad: 0.0,
            initial_height_m: 0.0,
            max_duration_s: self.max_duration_s,
            x_range_m,
        };
        table
            .validate(model)
            .map_err(|e| SceneError::new("real_table", e.to_string()))?;
        Ok(table)
    }

    /// The controller's plan freeze, `commit_s`, derived from the keys the user sets: the
    /// core's 0.03 s default, or more when the camera's latency plus a planning cycle
    /// (`contact_iterations` + 7 periods) plus one period needs more (then one period more
    /// than that), at most [`MAX_COMMIT_S`]. Where even that is too short the error names
    /// `real_table.control_rate_hz` with the lowest rate that fits.
    fn commit_s(&self, camera: Option<&CameraConfig>) -> Result<f32, SceneError> {
        let latency = camera.map_or(0.0, |c| c.latency_s as f32);
        let dt = (1.0 / self.control_rate_hz) as f32;
        let probe = TiltParams {
            contact_iterations: self.contact_iterations,
            ..TiltParams::default()
        };
        let periods = probe.cycle_periods() + 1;
        // the core's own sum (`TiltParams::validate`), f32
        let due = latency + f32::from(periods - 1) * dt + dt;
        let commit = TiltParams::default()
            .commit_s
            .max(due + dt)
            .min(MAX_COMMIT_S);
        if commit > due {
            return Ok(commit);
        }
        let lowest_hz = f64::from(periods) / (f64::from(MAX_COMMIT_S) - f64::from(latency));
        Err(SceneError::new(
            "real_table.control_rate_hz",
            format!(
                "must be above {lowest_hz:.2} Hz with real_table.camera.latency_s = {latency} s and real_table.contact_iterations = {}: the controller freezes its plan at most {MAX_COMMIT_S} s before an impact, and later than the latency plus contact_iterations + 8 control periods; got {}",
                self.contact_iterations, self.control_rate_hz
            ),
        ))
    }

    /// The controller's parameters apart from the model's laws: rate, damping, Newton
    /// steps, and the drive limits it plans with.
    fn controller_base(&self, tilt: &DriveLimits, stroke: &DriveLimits) -> TiltParams {
        let mut c = TiltParams {
            dt_s: (1.0 / self.control_rate_hz) as f32,
            kappa_rate_s: self.kappa_rate_s as f32,
            kappa_x_pm: self.kappa_x_pm as f32,
            kappa_xdot_spm: self.kappa_xdot_spm as f32,
            contact_iterations: self.contact_iterations,
            ..TiltParams::default()
        };
        c.tilt.min_rad = tilt.min as f32;
        c.tilt.max_rad = tilt.max as f32;
        c.tilt.rate_max_radps = tilt.velocity_max as f32;
        c.tilt.accel_max_radps2 = tilt.accel_max as f32;
        c.stroke.min_m = stroke.min as f32;
        c.stroke.max_m = stroke.max as f32;
        c.stroke.velocity_max_mps = stroke.velocity_max as f32;
        c.stroke.accel_max_mps2 = stroke.accel_max as f32;
        c
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn camera(latency_s: f64) -> CameraConfig {
        CameraConfig {
            latency_s,
            ..CameraConfig::realistic(0)
        }
    }

    /// The plan freeze is the core's 0.03 s where that fits (the
    /// default table), longer where the latency and the planning cycle need it, and always
    /// one the core accepts.
    #[test]
    fn the_plan_freeze_is_derived_so_the_core_accepts_it() {
        let d = RealTableScene::default();
        assert_eq!(d.commit_s(Some(&camera(0.004))).unwrap(), 0.03);
        for (rate, iterations, latency) in [(50.0, 1, 0.0), (100.0, 2, 0.05), (61.0, 4, 0.0)] {
            let t = RealTableScene {
                control_rate_hz: rate,
                contact_iterations: iterations,
                ..RealTableScene::default()
            };
            let commit = t.commit_s(Some(&camera(latency))).unwrap();
            // latency + (iterations + 8) periods, the docs' rule
            let due = latency + f64::from(iterations + 8) / rate;
            assert!(f64::from(commit) > due, "{rate} Hz: {commit} <= {due}");
            assert!(commit <= MAX_COMMIT_S);
            let mut p = TiltParams {
                dt_s: (1.0 / rate) as f32,
                contact_iterations: iterations,
                commit_s: commit,
                ..TiltParams::default()
            };
            p.estimator.latency_s = latency as f32;
            assert_eq!(p.validate(), Ok(()), "{rate} Hz");
        }
        // exactly at the docs' bound, (4 + 8) / 0.2 s = 60 Hz, the rate must be above it
        let t = RealTableScene {
            control_rate_hz: 60.0,
            contact_iterations: 4,
            ..RealTableScene::default()
        };
        let e = t.commit_s(None).unwrap_err();
        assert_eq!(e.key, "real_table.control_rate_hz");
        assert!(e.reason.contains("above 60.00 Hz"), "{e}");
    }
}
