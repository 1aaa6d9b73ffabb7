//! Range and cross-field checks; every error names the dotted key.

use super::scene::*;
use crate::effects::sensor::MAX_PENDING;
use crate::scene::SceneError;
use dexter_core::control::ControllerParams;
use dexter_core::estimate::EstimatorParams;
use dexter_core::params::ParamError;
use dexter_core::track::PaddleLimits;

/// Longest period `analysis.max_period` may ask for: the summary keeps the last
/// 5 x `max_period` apexes (`summary::ApexStats`).
pub const MAX_PERIOD: u32 = 1024;

/// Fastest control loop, Hz (`control.rate_hz`): 100 kHz, ten times what the firmware's
/// step budget allows on its 25 MHz target; a run's control steps are
/// `stop.duration_s x control.rate_hz`.
pub const MAX_CONTROL_RATE_HZ: f64 = 1e5;

/// Fastest ball sensor, Hz (`sensor.rate_hz`): each sample is an event of the plant, so a
/// run simulates `stop.duration_s x sensor.rate_hz` of them.
pub const MAX_SENSOR_RATE_HZ: f64 = 1e6;

/// Shortest drag integrator step, s (`drag.step_s`): a flight second is at most a
/// million steps (RK4).
pub const MIN_DRAG_STEP_S: f64 = 1e-6;

/// Tightest drag tolerance, m (`drag.tolerance`, RK45): a tolerance near the rounding of
/// the height (1e-16 m per metre) cannot be met and would shrink the step without end.
pub const MIN_DRAG_TOLERANCE_M: f64 = 1e-12;

fn finite(key: &str, v: f64) -> Result<f64, SceneError> {
    if v.is_finite() {
        Ok(v)
    } else {
        Err(SceneError::new(
            key,
            format!("must be a finite number, got {v}"),
        ))
    }
}

fn positive(key: &str, v: f64) -> Result<f64, SceneError> {
    if finite(key, v)? > 0.0 {
        Ok(v)
    } else {
        Err(SceneError::new(key, format!("must be > 0, got {v}")))
    }
}

fn non_negative(key: &str, v: f64) -> Result<f64, SceneError> {
    if finite(key, v)? >= 0.0 {
        Ok(v)
    } else {
        Err(SceneError::new(key, format!("must be >= 0, got {v}")))
    }
}

/// A number as a user reads it: plain, or in e-notation when tiny or huge.
fn num(v: f64) -> String {
    if v != 0.0 && !(1e-3..1e6).contains(&v.abs()) {
        format!("{v:e}")
    } else {
        format!("{v}")
    }
}

/// `v` in (0, `max`]; `why` says what the bound protects.
fn up_to(key: &str, v: f64, max: f64, why: &str) -> Result<f64, SceneError> {
    if positive(key, v)? <= max {
        Ok(v)
    } else {
        Err(SceneError::new(
            key,
            format!("must be <= {} ({why}), got {}", num(max), num(v)),
        ))
    }
}

/// `v` >= `min`; `why` says what the bound protects.
fn at_least(key: &str, v: f64, min: f64, why: &str) -> Result<f64, SceneError> {
    if finite(key, v)? >= min {
        Ok(v)
    } else {
        Err(SceneError::new(
            key,
            format!("must be >= {} ({why}), got {}", num(min), num(v)),
        ))
    }
}

fn within(key: &str, v: f64, lo: f64, hi: f64) -> Result<f64, SceneError> {
    if finite(key, v)? >= lo && v <= hi {
        Ok(v)
    } else {
        Err(SceneError::new(
            key,
            format!("must be in [{lo}, {hi}], got {v}"),
        ))
    }
}

impl Scene {
    /// Check every value's range and the rules between keys; the error names the key.
    pub fn validate(&self) -> Result<(), SceneError> {
        if let Some(name) = &self.scene.name {
            check_name(name)?;
        }
        let p = &self.physics;
        positive("physics.gravity_mps2", p.gravity_mps2)?;
        within("physics.restitution", p.restitution, 0.0, 1.0)?;
        finite("ball.height_m", self.ball.height_m)?;
        finite("ball.velocity_mps", self.ball.velocity_mps)?;
        if self.stop.impacts == 0 {
            return Err(SceneError::new("stop.impacts", "must be >= 1"));
        }
        positive("stop.duration_s", self.stop.duration_s)?;
        finite("table.height_m", self.table.height_m)?;
        self.validate_control()?;
        self.validate_actuator()?;
        self.validate_effects()?;
        self.validate_zeno_and_analysis()
    }

    /// `[control]`: the target and the mirror gains; for `sil`, the core's own checks.
    fn validate_control(&self) -> Result<(), SceneError> {
        let c = &self.control;
        if c.mode == ControlMode::None {
            if self.ball.height_m < self.table.height_m {
                return Err(SceneError::new(
                    "ball.height_m",
                    "must not start below table.height_m",
                ));
            }
            return Ok(());
        }
        let target = c.target_apex_m.ok_or_else(|| {
            SceneError::new(
                "control.target_apex_m",
                "missing: a target apex is required when control.mode is not \"none\"",
            )
        })?;
        positive("control.target_apex_m", target)?;
        self.validate_kappa0()?;
        non_negative("control.kappa1_s2pm2", c.kappa1_s2pm2)?;
        if self.ball.height_m < 0.0 {
            return Err(SceneError::new(
                "ball.height_m",
                "must be >= 0 (above the impact plane) for a juggling scene",
            ));
        }
        if c.mode == ControlMode::Sil {
            up_to(
                "control.rate_hz",
                c.rate_hz,
                MAX_CONTROL_RATE_HZ,
                "the run steps the controller stop.duration_s x control.rate_hz times",
            )?;
            // the core validates its own parameters; map its names to scene keys
            self.controller_params()?
                .validate()
                .map_err(|e| param_error(&e))?;
        }
        Ok(())
    }

    /// `control.kappa0`, or its default matched to the restitution, in [0, 1).
    fn validate_kappa0(&self) -> Result<(), SceneError> {
        if let Some(k0) = self.control.kappa0 {
            if !(finite("control.kappa0", k0)? >= 0.0 && k0 < 1.0) {
                return Err(SceneError::new(
                    "control.kappa0",
                    format!("must be in [0, 1), got {k0}"),
                ));
            }
        } else if self.kappa0() >= 1.0 {
            return Err(SceneError::new(
                "control.kappa0",
                format!(
                    "its default, matched to the restitution, (1 - e)/(1 + e) = {} for physics.restitution = {}, is not < 1: set control.kappa0",
                    self.kappa0(),
                    self.physics.restitution
                ),
            ));
        }
        Ok(())
    }

    /// `[actuator]`.
    fn validate_actuator(&self) -> Result<(), SceneError> {
        let a = &self.actuator;
        finite("actuator.initial_height_m", a.initial_height_m)?;
        if a.kind != ActuatorKind::SecondOrder {
            return Ok(());
        }
        positive("actuator.accel_max_mps2", a.accel_max_mps2)?;
        positive("actuator.velocity_max_mps", a.velocity_max_mps)?;
        finite("actuator.min_height_m", a.min_height_m)?;
        finite("actuator.max_height_m", a.max_height_m)?;
        if a.max_height_m <= a.min_height_m {
            return Err(SceneError::new(
                "actuator.max_height_m",
                "must be > actuator.min_height_m",
            ));
        }
        within(
            "actuator.initial_height_m",
            a.initial_height_m,
            a.min_height_m,
            a.max_height_m,
        )?;
        Ok(())
    }

    /// `[sensor]`, `[jitter]`, `[drag]` when present.
    fn validate_effects(&self) -> Result<(), SceneError> {
        if let Some(s) = &self.sensor {
            let rate = match s.rate_hz {
                Some(r) => up_to(
                    "sensor.rate_hz",
                    r,
                    MAX_SENSOR_RATE_HZ,
                    "each sample is an event the run simulates",
                )?,
                None => self.control.rate_hz,
            };
            non_negative("sensor.noise_sigma_m", s.noise_sigma_m)?;
            non_negative("sensor.latency_s", s.latency_s)?;
            non_negative("sensor.quantization_m", s.quantization_m)?;
            let in_flight = s.latency_s * rate;
            if in_flight > MAX_PENDING as f64 {
                return Err(SceneError::new(
                    "sensor.latency_s",
                    format!("x sensor.rate_hz is {in_flight} samples in flight, more than the {MAX_PENDING} the sensor holds"),
                ));
            }
        }
        if let Some(j) = &self.jitter {
            non_negative("jitter.sigma_s", j.sigma_s)?;
        }
        if let Some(d) = &self.drag {
            non_negative("drag.coefficient_per_m", d.coefficient_per_m)?;
            let steps = "at most a million integrator steps per simulated second";
            at_least("drag.step_s", d.step_s, MIN_DRAG_STEP_S, steps)?;
            let rounding = "a tighter one is below the rounding of the height";
            at_least(
                "drag.tolerance",
                d.tolerance,
                MIN_DRAG_TOLERANCE_M,
                rounding,
            )?;
        }
        Ok(())
    }

    /// `[zeno]` and `[analysis]`.
    fn validate_zeno_and_analysis(&self) -> Result<(), SceneError> {
        let z = &self.zeno;
        non_negative("zeno.velocity_threshold_mps", z.velocity_threshold_mps)?;
        non_negative("zeno.relative_threshold", z.relative_threshold)?;
        if z.max_impacts_per_segment == 0 {
            return Err(SceneError::new(
                "zeno.max_impacts_per_segment",
                "must be >= 1",
            ));
        }
        let an = &self.analysis;
        positive("analysis.converge_tolerance", an.converge_tolerance)?;
        positive("analysis.period_tolerance", an.period_tolerance)?;
        if an.max_period == 0 || an.max_period > MAX_PERIOD {
            return Err(SceneError::new(
                "analysis.max_period",
                format!("must be in 1..={MAX_PERIOD}, got {}", an.max_period),
            ));
        }
        Ok(())
    }

    /// The mirror gain kappa0 in use: `control.kappa0`, or matched to the restitution.
    pub fn kappa0(&self) -> f64 {
        self.control
            .kappa0
            .unwrap_or((1.0 - self.physics.restitution) / (1.0 + self.physics.restitution))
    }

    /// The scene's name: `scene.name`, or `scene`.
    pub fn name(&self) -> &str {
        self.scene.name.as_deref().unwrap_or("scene")
    }

    /// The core controller's parameters (f32) for a `sil` scene.
    pub fn controller_params(&self) -> Result<ControllerParams, SceneError> {
        let c = &self.control;
        let target = c
            .target_apex_m
            .ok_or_else(|| SceneError::new("control.target_apex_m", "missing"))?;
        let e = &c.estimator;
        let sensor_latency = self.sensor.as_ref().map_or(0.0, |s| s.latency_s);
        Ok(ControllerParams {
            dt_s: (1.0 / c.rate_hz) as f32,
            gravity_mps2: self.physics.gravity_mps2 as f32,
            kappa0: self.kappa0() as f32,
            kappa1_s2pm2: c.kappa1_s2pm2 as f32,
            target_apex_m: target as f32,
            kp_per_s2: c.kp_per_s2 as f32,
            kd_per_s: c.kd_per_s as f32,
            home_height_m: c.home_height_m as f32,
            limits: PaddleLimits {
                min_height_m: c.limits.min_height_m as f32,
                max_height_m: c.limits.max_height_m as f32,
                velocity_max_mps: c.limits.velocity_max_mps as f32,
                accel_max_mps2: c.limits.accel_max_mps2 as f32,
            },
            estimator: EstimatorParams {
                gain_position: e.gain_position as f32,
                gain_velocity: e.gain_velocity as f32,
                gate_m: e.gate_m as f32,
                reinit_after: e.reinit_after,
                settle_samples: e.settle_samples,
                latency_s: e.latency_s.unwrap_or(sensor_latency) as f32,
                restitution: e.restitution.unwrap_or(self.physics.restitution) as f32,
            },
            ball_height_min_m: c.ball_height_min_m as f32,
            ball_height_max_m: c.ball_height_max_m as f32,
            stale_limit_steps: c.stale_limit_steps,
        })
    }
}

/// A core parameter error as a scene error with the scene's key path.
pub fn param_error(e: &ParamError) -> SceneError {
    let name = match e {
        ParamError::NotFinite(n)
        | ParamError::NotPositive(n)
        | ParamError::Negative(n)
        | ParamError::OutOfRange(n) => *n,
        _ => "",
    };
    let key = match name {
        "dt_s" => "control.rate_hz".to_string(),
        "gravity_mps2" => "physics.gravity_mps2".to_string(),
        "kappa1" => "control.kappa1_s2pm2".to_string(),
        n if n.starts_with("tracking.") => format!("control.{}", &n["tracking.".len()..]),
        n => format!("control.{n}"),
    };
    SceneError::new(key, e.to_string())
}

/// Longest `scene.name`, bytes (it is a plot file's stem: a suffix such as `-phase.svg`
/// is added, and a file name holds 255 bytes).
pub const MAX_NAME_BYTES: usize = 200;

/// `scene.name` must make a file stem: 1 ..= [`MAX_NAME_BYTES`] bytes, no path
/// separator or control character, not `.` or `..` (checked before the run, not at the plots).
fn check_name(name: &str) -> Result<(), SceneError> {
    let n = name.len();
    let why = if n == 0 {
        "must not be empty (it names the plot files)".to_string()
    } else if n > MAX_NAME_BYTES {
        format!("must be at most {MAX_NAME_BYTES} bytes (it names the plot files), got {n}")
    } else if name.contains(['/', '\\']) || name.chars().any(char::is_control) {
        "must not hold a path separator (/ or \\) or a control character (it names the plot files)"
            .to_string()
    } else if name == "." || name == ".." {
        format!("must not be {name:?} (it names the plot files)")
    } else {
        return Ok(());
    };
    Err(SceneError::new("scene.name", why))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn err(text: &str) -> SceneError {
        Scene::from_toml_str(text, &[]).unwrap_err()
    }

    #[test]
    fn unknown_key_is_named_with_its_path() {
        let e = err("[physics]\nrestitutoin = 0.5\n");
        assert_eq!(e.key, "physics.restitutoin");
        assert!(e.reason.contains("unknown field"), "{e}");
        assert_eq!(err("bogus = 1\n").key, "bogus");
    }

    #[test]
    fn wrong_type_is_named_with_its_path() {
        let e = err("[control]\nkappa1_s2pm2 = \"big\"\n");
        assert_eq!(e.key, "control.kappa1_s2pm2");
        assert!(e.reason.contains("invalid type"), "{e}");
        assert_eq!(
            err("[drag]\nintegrator = \"euler\"\n").key,
            "drag.integrator"
        );
    }

    #[test]
    fn restitution_out_of_range_is_named() {
        for bad in ["-0.1", "1.5", "nan"] {
            let e = err(&format!("[physics]\nrestitution = {bad}\n"));
            assert_eq!(e.key, "physics.restitution", "{bad}");
        }
    }

    #[test]
    fn missing_target_is_named() {
        let e = err("[control]\nmode = \"sil\"\n");
        assert_eq!(e.key, "control.target_apex_m");
        assert!(e.reason.contains("missing"));
    }

    #[test]
    fn core_parameter_errors_map_to_scene_keys() {
        let e = err("[control]\nmode = \"sil\"\ntarget_apex_m = 1.0\nhome_height_m = 5.0\n");
        assert_eq!(e.key, "control.home_height_m");
        let e = err("[control]\nmode = \"sil\"\ntarget_apex_m = 1.0\n[control.estimator]\ngain_position = 0.0\n");
        assert_eq!(e.key, "control.estimator.gain_position");
    }

    #[test]
    fn defaults_are_the_documented_decimal_values() {
        let s = Scene::default();
        assert_eq!(s.control.kappa1_s2pm2, 0.02);
        assert_eq!(s.control.rate_hz, 500.0);
        assert_eq!(s.control.limits.min_height_m, -0.3);
        assert_eq!(s.control.limits.max_height_m, 0.1);
        assert_eq!(s.control.estimator.gain_velocity, 0.005);
        assert_eq!((s.physics.gravity_mps2, s.physics.restitution), (9.81, 0.8));
        assert_eq!((s.stop.impacts, s.stop.duration_s), (100, 600.0));
    }

    #[test]
    fn unmatched_default_gain_is_explained() {
        let e = err("[physics]\nrestitution = 0.0\n[control]\nmode = \"ideal_mirror\"\ntarget_apex_m = 1.0\n");
        assert_eq!(e.key, "control.kappa0");
        assert!(e.reason.contains("physics.restitution"), "{e}");
        let ok = "[physics]\nrestitution = 0.0\n[control]\nmode = \"ideal_mirror\"\ntarget_apex_m = 1.0\nkappa0 = 0.5\n";
        assert!(Scene::from_toml_str(ok, &[]).is_ok());
    }

    #[test]
    fn overrides_pass_the_same_checks() {
        let o = vec![crate::scene::parse_set("physics.restitution=2").unwrap()];
        assert_eq!(
            Scene::from_toml_str("", &o).unwrap_err().key,
            "physics.restitution"
        );
        let o = vec![crate::scene::parse_set("physics.nope=2").unwrap()];
        assert_eq!(
            Scene::from_toml_str("", &o).unwrap_err().key,
            "physics.nope"
        );
        let o = vec![crate::scene::parse_set("physics.restitution=0.5").unwrap()];
        assert_eq!(
            Scene::from_toml_str("", &o).unwrap().physics.restitution,
            0.5
        );
    }
}
