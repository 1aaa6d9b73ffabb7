//! Parameters of the fixed-rate hopper controller and their validation.

use crate::checks::Checks;
use crate::hop::EnergyServoThrust;
use crate::params::ParamError;
use serde::{Deserialize, Serialize};

/// Longest thrust the controller holds, in control periods (delta / dt).
pub const MAX_THRUST_STEPS: f32 = 1.0e6;
/// Longest known sensor latency, in control periods (latency / dt).
pub const MAX_LATENCY_STEPS: f32 = 1.0e4;
/// Most consecutive samples a phase transition can be made to wait for.
pub const MAX_DEBOUNCE_SAMPLES: u8 = 64;

/// The thrust law of each stance (Koditschek & Bühler 1991, sec. 1.2; [`crate::hop`]): the
/// energy servo tau_n = clamp(tau0 + k_E (E* - E_n), 0, tau_max) with E_n the touchdown
/// energy, estimated from the measured flight time ([`EnergyServoThrust`]). Raibert's fixed
/// thrust ([`RaibertThrust`](crate::hop::RaibertThrust)) is the servo without gain, tau0 = tau_max = tau
/// ([`HopThrust::raibert`]): one code path in the step.
///
/// A struct of four numbers rather than an enum with a variant per law, so that it has one
/// shape on the wire (every value of it encodes to at most the same 16 bytes).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct HopThrust {
    /// tau0, m/s^2, in [0, tau_max] (Raibert's tau).
    pub nominal_thrust_mps2: f32,
    /// k_E, 1/m (>= 0; 0 = Raibert's fixed thrust).
    pub gain_per_m: f32,
    /// E*, J/kg (> 0): the target apex is E*/g above the touchdown height (no effect when
    /// `gain_per_m` is 0).
    pub target_energy_jpkg: f32,
    /// tau_max, m/s^2 (>= tau0).
    pub max_thrust_mps2: f32,
}

impl HopThrust {
    /// Raibert's fixed thrust: tau every stance (the servo with k_E = 0, tau0 = tau_max =
    /// tau; E* = 1 J/kg is a placeholder the law multiplies by 0).
    pub const fn raibert(thrust_mps2: f32) -> Self {
        Self {
            nominal_thrust_mps2: thrust_mps2,
            gain_per_m: 0.0,
            target_energy_jpkg: 1.0,
            max_thrust_mps2: thrust_mps2,
        }
    }

    /// Whether this is Raibert's fixed thrust (no gain: tau0 every stance).
    pub fn is_raibert(&self) -> bool {
        self.gain_per_m == 0.0
    }

    /// The largest thrust this law can command, m/s^2.
    pub fn max_thrust_mps2(&self) -> f32 {
        self.max_thrust_mps2
    }
}

/// Everything the hopper controller needs, SI units, f32 (sent over the wire in HIL). Its
/// serde form is its fields as one flat tuple (the crate's `fields` module).
///
/// Sensor convention: `leg_compression_m` is chi_l minus the leg length, m (0 with the leg
/// fully extended, positive in stance; in stance with the foot at height 0 the body height
/// is chi = chi_l - compression).
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct HopParams {
    /// Control period dt, s (> 0, <= 1).
    pub dt_s: f32,
    /// Gravity g, m/s^2 (> 0): the flight-time energy estimate E = g^2 T^2 / 8.
    pub gravity_mps2: f32,
    /// The thrust law.
    pub thrust: HopThrust,
    /// delta, how long the valve is held open from the (estimated) bottom, s (>= 0;
    /// delta / dt <= [`MAX_THRUST_STEPS`]).
    pub thrust_duration_s: f32,
    /// Touchdown needs the foot switch closed and a compression of at least this, m
    /// (in [0, `max_compression_m`)).
    pub touchdown_compression_m: f32,
    /// Liftoff is the foot switch open, or a compression below this, m (in
    /// [-`max_compression_m`, `touchdown_compression_m`]: the hysteresis band; at
    /// -`max_compression_m` only the switch counts).
    pub liftoff_compression_m: f32,
    /// The bottom is detected once the compression has fallen more than this below its
    /// running maximum in the stance, m (in [0, `max_compression_m`]; 0 = the first
    /// decreasing sample). Set it above the sensor noise.
    pub bottom_hysteresis_m: f32,
    /// Consecutive fresh samples a touchdown or liftoff condition must hold before the
    /// phase changes (in 1..=[`MAX_DEBOUNCE_SAMPLES`]; 1 = no debounce).
    pub debounce_samples: u8,
    /// Open the valve at the control step nearest to the bottom predicted from the last
    /// three rising samples (the parabola through them), rather than at the first sample
    /// that shows the compression falling (which stays the fallback). For sensors whose
    /// noise and quantization are well below |c''| dt^2 / 8 (about 1 um at 1 kHz).
    pub predict_bottom: bool,
    /// Close the valve at the step nearest to the estimated bottom + delta (true), or hold
    /// it open for round(delta / dt) periods from the opening (false). With
    /// `predict_bottom` the first centres both ends of the thrust on the exact law's; after
    /// a late detection it shortens the thrust, which costs more than it saves (module doc;
    /// with 0.1 mm of noise at 1 kHz it kept the linear hopper from settling at all).
    pub end_thrust_at_estimate: bool,
    /// The sensor's latency the controller compensates for, s (>= 0; latency / dt <=
    /// [`MAX_LATENCY_STEPS`]).
    pub sensor_latency_s: f32,
    /// Plausible compressions are within +-this, m (> 0); beyond is a fault.
    pub max_compression_m: f32,
    /// chi_l, the body height at touchdown and liftoff, m (finite): the apex energy from a
    /// body-height sample, g (h - chi_l).
    pub liftoff_height_m: f32,
    /// Plausible body heights, m: a sample outside `[min, max]` is a fault.
    pub body_height_min_m: f32,
    /// See `body_height_min_m`.
    pub body_height_max_m: f32,
    /// Periods without a new sample before the input counts as stale (>= 1).
    pub stale_limit_steps: u16,
}

impl Default for HopParams {
    /// A 1 kHz controller with Raibert's thrust of Table 1 (tau = 41.86 m/s^2 for 0.05 s),
    /// noise-free thresholds, the bottom predicted, the thrust ended at the estimated bottom + delta.
    fn default() -> Self {
        Self {
            dt_s: 0.001,
            gravity_mps2: 9.81,
            thrust: HopThrust::raibert(41.86),
            thrust_duration_s: 0.05,
            touchdown_compression_m: 0.0,
            liftoff_compression_m: -1.0,
            bottom_hysteresis_m: 0.0,
            debounce_samples: 1,
            predict_bottom: true,
            end_thrust_at_estimate: true,
            sensor_latency_s: 0.0,
            max_compression_m: 1.0,
            liftoff_height_m: 0.5,
            body_height_min_m: -10.0,
            body_height_max_m: 100.0,
            stale_limit_steps: 5,
        }
    }
}

impl HopParams {
    /// Check every field; the error names the first bad one.
    #[inline]
    pub fn validate(&self) -> Result<(), ParamError> {
        let mut c = Checks::default();
        c.positive("dt_s", self.dt_s);
        c.within("dt_s", self.dt_s, 0.0, 1.0);
        c.positive("gravity_mps2", self.gravity_mps2);
        c.non_negative("thrust_duration_s", self.thrust_duration_s);
        let steps = self.thrust_duration_s / self.dt_s;
        c.within("thrust_duration_s", steps, 0.0, MAX_THRUST_STEPS);
        self.check_thrust(&mut c);
        let c_max = self.max_compression_m;
        c.positive("max_compression_m", c_max);
        let on = self.touchdown_compression_m;
        c.within("touchdown_compression_m", on, 0.0, c_max);
        c.in_range(on < c_max, "touchdown_compression_m");
        c.within(
            "liftoff_compression_m",
            self.liftoff_compression_m,
            -c_max,
            on,
        );
        c.within("bottom_hysteresis_m", self.bottom_hysteresis_m, 0.0, c_max);
        let debounce = self.debounce_samples;
        c.in_range(
            debounce > 0 && debounce <= MAX_DEBOUNCE_SAMPLES,
            "debounce_samples",
        );
        c.non_negative("sensor_latency_s", self.sensor_latency_s);
        let lat = self.sensor_latency_s / self.dt_s;
        c.within("sensor_latency_s", lat, 0.0, MAX_LATENCY_STEPS);
        c.finite("liftoff_height_m", self.liftoff_height_m);
        c.finite("body_height_min_m", self.body_height_min_m);
        c.finite("body_height_max_m", self.body_height_max_m);
        let heights_ok = self.body_height_max_m > self.body_height_min_m;
        c.in_range(heights_ok, "body_height_max_m");
        c.positive_count(self.stale_limit_steps > 0, "stale_limit_steps");
        c.result()
    }

    /// The thrust law's fields, each by its own key, tau0 first (Raibert's one number).
    fn check_thrust(&self, c: &mut Checks) {
        let t = &self.thrust;
        c.non_negative("thrust.nominal_thrust_mps2", t.nominal_thrust_mps2);
        c.non_negative("thrust.max_thrust_mps2", t.max_thrust_mps2);
        let tau0_ok = t.nominal_thrust_mps2 <= t.max_thrust_mps2;
        c.in_range(tau0_ok, "thrust.nominal_thrust_mps2");
        c.non_negative("thrust.gain_per_m", t.gain_per_m);
        c.positive("thrust.target_energy_jpkg", t.target_energy_jpkg);
    }

    /// The core's thrust law for these parameters; the error names the first invalid
    /// field of [`HopThrust`] (`thrust.` and the field) or `thrust_duration_s`.
    #[inline]
    pub fn thrust_law(&self) -> Result<EnergyServoThrust<f32>, ParamError> {
        let mut c = Checks::default();
        self.check_thrust(&mut c);
        c.non_negative("thrust_duration_s", self.thrust_duration_s);
        c.result()?;
        self.law_of_checked()
    }

    /// The law for parameters whose thrust fields have been checked (its own checks then
    /// pass; they are not repeated by ours).
    #[inline]
    pub(crate) fn law_of_checked(&self) -> Result<EnergyServoThrust<f32>, ParamError> {
        let t = &self.thrust;
        EnergyServoThrust::new(
            t.nominal_thrust_mps2,
            t.gain_per_m,
            t.target_energy_jpkg,
            t.max_thrust_mps2,
            self.thrust_duration_s,
        )
    }
}

impl crate::fields::Fields for HopParams {
    const COUNT: usize = 19;
    const NAME: &'static str = "HopParams";

    fn blank() -> Self {
        Self {
            dt_s: 0.0,
            gravity_mps2: 0.0,
            thrust: HopThrust::raibert(0.0),
            thrust_duration_s: 0.0,
            touchdown_compression_m: 0.0,
            liftoff_compression_m: 0.0,
            bottom_hysteresis_m: 0.0,
            debounce_samples: 0,
            predict_bottom: false,
            end_thrust_at_estimate: false,
            sensor_latency_s: 0.0,
            max_compression_m: 0.0,
            liftoff_height_m: 0.0,
            body_height_min_m: 0.0,
            body_height_max_m: 0.0,
            stale_limit_steps: 0,
        }
    }

    fn fields<V: crate::fields::FieldVisit>(&mut self, v: &mut V) {
        let t = &mut self.thrust;
        for x in [
            &mut self.dt_s,
            &mut self.gravity_mps2,
            &mut t.nominal_thrust_mps2,
            &mut t.gain_per_m,
            &mut t.target_energy_jpkg,
            &mut t.max_thrust_mps2,
            &mut self.thrust_duration_s,
            &mut self.touchdown_compression_m,
            &mut self.liftoff_compression_m,
            &mut self.bottom_hysteresis_m,
        ] {
            v.f32(x);
        }
        v.u8(&mut self.debounce_samples);
        v.bool(&mut self.predict_bottom);
        v.bool(&mut self.end_thrust_at_estimate);
        for x in [
            &mut self.sensor_latency_s,
            &mut self.max_compression_m,
            &mut self.liftoff_height_m,
            &mut self.body_height_min_m,
            &mut self.body_height_max_m,
        ] {
            v.f32(x);
        }
        v.u16(&mut self.stale_limit_steps);
    }
}

impl Serialize for HopParams {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        crate::fields::serialize(self, s)
    }
}

impl<'de> Deserialize<'de> for HopParams {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        crate::fields::deserialize(d)
    }
}
