//! The `[spatial_juggler.sil]` table: the scene runs through the core's fixed-rate
//! [`SpatialController`] (SIL, or the firmware with `--hil`) on the closed-loop plant of
//! [`crate::model::spatial::sil`], with a camera, encoders and joint limits. Every key, unit
//! and default: `docs/spatial.md`, "Closed loop".

use super::SpatialTable;
use crate::effects::sensor::MAX_PENDING;
use crate::model::spatial::sil::{Camera, SilPlant};
use crate::model::spatial::Law;
use crate::scene::SceneError;
use dexter_core::estimate::EstimatorParams;
use dexter_core::fixed_rate::FixedRate;
use dexter_core::params::ParamError;
use dexter_core::spatial::{SpatialBall, SpatialLawParams};
use dexter_core::spatial_control::{AxisLimits, SpatialControlParams, SpatialController};
use serde::{Deserialize, Serialize};

/// The `[spatial_juggler.sil]` table.
#[derive(Clone, Debug, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields, default)]
pub struct SilTable {
    /// `control_rate_hz`: the controller's (and the camera's) rate, Hz (> 0).
    pub control_rate_hz: f64,
    /// `kp_per_s2`: joint tracking stiffness, 1/s^2.
    pub kp_per_s2: f64,
    /// `kd_per_s`: joint tracking damping, 1/s.
    pub kd_per_s: f64,
    /// `camera_sigma_m`: camera noise per coordinate, m (>= 0).
    pub camera_sigma_m: f64,
    /// `camera_latency_s`: camera latency, s (>= 0), compensated by the estimator.
    pub camera_latency_s: f64,
    /// `seed`: the camera noise's seed.
    pub seed: u64,
    /// `encoder_resolution_rad`: joint encoder resolution, rad (>= 0, 0 = exact).
    pub encoder_resolution_rad: f64,
    /// `min_rad`: lowest angle of (q1, q2, q3), rad.
    pub min_rad: [f64; 3],
    /// `max_rad`: highest angle of each joint, rad.
    pub max_rad: [f64; 3],
    /// `velocity_max_radps`: speed limit of each joint, rad/s.
    pub velocity_max_radps: [f64; 3],
    /// `accel_max_radps2`: acceleration limit of each joint (controller and drive), rad/s^2.
    pub accel_max_radps2: [f64; 3],
    /// `home_rad`: the joints at t = 0 and while the controller has no estimate, rad.
    pub home_rad: [f64; 3],
    /// `reach_m`: the blade's length along the bar, m.
    pub reach_m: f64,
    /// `half_width_m`: half the blade's width, m.
    pub half_width_m: f64,
    /// `gain_position`: the estimator's position gain, in (0, 1].
    pub gain_position: f64,
    /// `gain_velocity`: the estimator's velocity gain, in (0, 2).
    pub gain_velocity: f64,
    /// `gate_m`: the estimator's innovation gate, m.
    pub gate_m: f64,
}

impl Default for SilTable {
    fn default() -> Self {
        let c = SpatialControlParams::default();
        let each = |f: fn(&AxisLimits) -> f32| c.limits.each_ref().map(|l| f64::from(f(l)));
        Self {
            control_rate_hz: 1.0 / f64::from(c.dt_s),
            kp_per_s2: c.kp_per_s2.into(),
            kd_per_s: c.kd_per_s.into(),
            camera_sigma_m: 5e-4,
            camera_latency_s: 0.005,
            seed: 1,
            encoder_resolution_rad: 1e-4,
            min_rad: each(|l| l.min_rad),
            max_rad: each(|l| l.max_rad),
            velocity_max_radps: each(|l| l.velocity_max_radps),
            accel_max_radps2: each(|l| l.accel_max_radps2),
            home_rad: c.home_rad.map(f64::from),
            reach_m: 2.0,
            half_width_m: 0.2,
            gain_position: c.estimator.gain_position.into(),
            gain_velocity: c.estimator.gain_velocity.into(),
            gate_m: c.estimator.gate_m.into(),
        }
    }
}

/// The scene key of a field of the core's `SpatialControlParams`.
fn core_key(field: &str) -> String {
    let key = match field {
        "dt_s" => "control_rate_hz".to_string(),
        "ball_range_m" | "stale_limit_steps" => return format!("the controller's {field}"),
        f => match f.strip_prefix("estimator.") {
            Some("latency_s") => "camera_latency_s".into(),
            Some(rest) => rest.into(),
            None => {
                let f = f.strip_prefix("limits.").unwrap_or(f);
                let f = f
                    .strip_prefix("home_rad.")
                    .map_or(f.to_string(), |q| format!("home_rad ({q})"));
                // limits.q2.max_rad -> max_rad (q2)
                match f.split_once('.') {
                    Some((q, rest)) => format!("{rest} ({q})"),
                    None => f,
                }
            }
        },
    };
    format!("spatial_juggler.sil.{key}")
}

/// A core controller's parameter error with its scene key: the law's under
/// `[spatial_juggler]`, the rest under `[spatial_juggler.sil]`.
fn param_error(e: ParamError) -> SceneError {
    let name = match e {
        ParamError::NotFinite(n)
        | ParamError::NotPositive(n)
        | ParamError::Negative(n)
        | ParamError::OutOfRange(n) => n,
        other => return SceneError::whole(other),
    };
    if name.starts_with("kappa") || name.starts_with("target_") || name == "gravity_mps2" {
        return super::param_error(e);
    }
    let mut err = SceneError::of_param(e, "docs/spatial.md", core_key);
    let specific = match (e, name) {
        (ParamError::NotFinite(_), _) => "must be a finite number (and below 3.4e38: an f32)",
        (ParamError::OutOfRange(_), n) if n.ends_with(".max_rad") => "must be above min_rad",
        (ParamError::OutOfRange(_), n) if n.starts_with("home_rad.") => {
            "must be within its joint's min_rad ..= max_rad"
        }
        (ParamError::OutOfRange(_), "estimator.gain_position") => "must be in (0, 1]",
        (ParamError::OutOfRange(_), "estimator.gain_velocity") => "must be in (0, 2)",
        _ => return err,
    };
    err.reason = specific.into();
    err
}

impl SilTable {
    /// The controller's parameters for `table` (its law, restitution and gravity).
    pub fn controller_params(
        &self,
        table: &SpatialTable,
    ) -> Result<SpatialControlParams, SceneError> {
        if table.law != Law::Mirror {
            return Err(SceneError::new(
                "spatial_juggler.law",
                "must be \"mirror\" with [spatial_juggler.sil]: the fixed-rate controller runs eq. 13",
            ));
        }
        let rate = self.control_rate_hz;
        if !(rate.is_finite() && rate > 0.0) {
            return Err(SceneError::new(
                "spatial_juggler.sil.control_rate_hz",
                format!("must be finite and > 0, got {rate}"),
            ));
        }
        let l = table.params().law;
        let f = |x: f64| x as f32;
        let law = SpatialLawParams {
            kappa0: f(l.kappa0),
            kappa1_s2pm2: f(l.kappa1_s2pm2),
            target_apex_m: f(l.target_apex_m),
            kappa10: f(l.kappa10),
            kappa11: f(l.kappa11),
            kappa20_radpm: f(l.kappa20_radpm),
            kappa21_radspm: f(l.kappa21_radspm),
            target_radius_m: f(l.target_radius_m),
            target_azimuth_rad: f(l.target_azimuth_rad),
            gravity_mps2: f(l.gravity_mps2),
        };
        let limits = core::array::from_fn(|i| AxisLimits {
            min_rad: f(self.min_rad[i]),
            max_rad: f(self.max_rad[i]),
            velocity_max_radps: f(self.velocity_max_radps[i]),
            accel_max_radps2: f(self.accel_max_radps2[i]),
        });
        let d = SpatialControlParams::default();
        let p = SpatialControlParams {
            dt_s: f(1.0 / rate),
            law,
            kp_per_s2: f(self.kp_per_s2),
            kd_per_s: f(self.kd_per_s),
            limits,
            home_rad: self.home_rad.map(f),
            estimator: EstimatorParams {
                gain_position: f(self.gain_position),
                gain_velocity: f(self.gain_velocity),
                gate_m: f(self.gate_m),
                latency_s: f(self.camera_latency_s),
                restitution: f(table.restitution),
                ..d.estimator
            },
            ..d
        };
        SpatialController::new(p).map_err(param_error)?;
        Ok(p)
    }

    /// The plant for `table`, its ball starting at `start`.
    pub fn plant(
        &self,
        table: &SpatialTable,
        start: SpatialBall<f64>,
    ) -> Result<SilPlant, SceneError> {
        for (k, v) in [
            ("camera_sigma_m", self.camera_sigma_m),
            ("encoder_resolution_rad", self.encoder_resolution_rad),
        ] {
            if !(v.is_finite() && v >= 0.0) {
                let key = format!("spatial_juggler.sil.{k}");
                return Err(SceneError::new(
                    key,
                    format!("must be finite and >= 0, got {v}"),
                ));
            }
        }
        let in_flight = self.camera_latency_s * self.control_rate_hz;
        if in_flight > MAX_PENDING as f64 {
            return Err(SceneError::new(
                "spatial_juggler.sil.camera_latency_s",
                format!(
                    "x control_rate_hz is {in_flight} samples in flight, more than the {MAX_PENDING} the camera holds"
                ),
            ));
        }
        for (k, v) in [
            ("reach_m", self.reach_m),
            ("half_width_m", self.half_width_m),
        ] {
            if !(v.is_finite() && v > 0.0) {
                let key = format!("spatial_juggler.sil.{k}");
                return Err(SceneError::new(
                    key,
                    format!("must be finite and > 0, got {v}"),
                ));
            }
        }
        Ok(SilPlant {
            restitution: table.restitution,
            gravity_mps2: table.gravity_mps2,
            dt_s: 1.0 / self.control_rate_hz,
            camera: Camera {
                sigma_m: self.camera_sigma_m,
                latency_s: self.camera_latency_s,
                seed: self.seed,
            },
            resolution_rad: self.encoder_resolution_rad,
            accel_max_radps2: self.accel_max_radps2,
            reach_m: self.reach_m,
            half_width_m: self.half_width_m,
            friction: (table.friction_coefficient > 0.0).then_some(table.friction_coefficient),
            ball: start,
            joints_rad: self.home_rad,
        })
    }
}

/// The controller's instruction budget per step, for the summary.
pub const STEP_BUDGET: u32 = <SpatialController as FixedRate>::STEP_INSTRUCTION_BUDGET;
