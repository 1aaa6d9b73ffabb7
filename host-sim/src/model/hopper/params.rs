//! The scene's `[hopper]` table (documented key by key in `docs/hopper.md`).
//!
//! Units: SI, per unit body mass (the paper's body has unit mass, sec. 3.1). A scene file
//! for the hopper holds only this table; [`HopperParams::from_toml_str`] reads it and
//! [`HopperParams::build`] validates it into a [`Hopper`], naming the key at fault.

use super::{
    FullNonlinear, Hopper, HopperError, HopperModel, Integrator, LinearSpring, SimplifiedNonlinear,
    Start, ThrustLaw,
};
use dexter_core::hop::{EnergyServoThrust, RaibertThrust};
use dexter_core::params::{finite, positive, ParamError};
use serde::Deserialize;

/// `value` is finite, else a [`HopperError`] naming `name`.
pub(crate) fn check_finite(name: &'static str, value: f64) -> Result<f64, HopperError> {
    Ok(finite(name, value)?)
}

/// Which equation of the paper the scene simulates (`hopper.model`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ModelKind {
    /// `"simplified_nonlinear"`: eq. 9 (figs. 11, 13).
    SimplifiedNonlinear,
    /// `"linear"`: eq. 10 / 16 (figs. 8–10).
    Linear,
    /// `"full"`: eq. 8 (fig. 12), the only model with integrated phases.
    Full,
}

/// The full model's integration method (`hopper.integrator`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum IntegratorKind {
    /// `"rk4"`: fixed step `hopper.step_s`.
    Rk4,
    /// `"rk45"` (default): adaptive Dormand-Prince 5(4) with `hopper.tolerance_m`.
    #[default]
    Rk45,
}

/// `[hopper.servo]`: the core's energy servo instead of Raibert's fixed thrust; absent =
/// fixed thrust `hopper.thrust_tau_mps2`.
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ServoParams {
    /// E*, target touchdown energy per unit mass, J/kg (> 0; E*/g is the apex above
    /// chi_l, m). Required.
    pub target_energy_jpkg: f64,
    /// k_E, thrust per energy error, 1/m (>= 0). Default 5.
    #[serde(default = "default_servo_gain")]
    pub gain_per_m: f64,
    /// tau_max, the actuator's largest thrust, m/s^2 (>= `hopper.thrust_tau_mps2`, the
    /// nominal thrust tau0). Default 2 tau0.
    pub max_thrust_mps2: Option<f64>,
}

fn default_servo_gain() -> f64 {
    5.0
}

/// The `[hopper]` table. Every key, its meaning, unit and default (also in
/// `docs/hopper.md`).
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct HopperParams {
    /// `model`: `"simplified_nonlinear"` (eq. 9), `"linear"` (eq. 10/16) or `"full"`
    /// (eq. 8). Required.
    pub model: ModelKind,
    /// `liftoff_height_m`: chi_l = chi_td, body height with the leg fully extended
    /// (touchdown and liftoff), m (> 0 for the pneumatic models). Default 0.5.
    #[serde(default = "default_liftoff")]
    pub liftoff_height_m: f64,
    /// `spring_eta1`: eta1, the compression spring constant per unit body mass (> 0):
    /// pneumatic models p_td A chi_td, m^2/s^2 (force eta1/chi); linear model the stiffness,
    /// 1/s^2 (force eta1 (chi_0 - chi)). Required.
    pub spring_eta1: f64,
    /// `thrust_tau_mps2`: tau, the thrust force per unit mass p_th A, m/s^2 (>= 0; > g for
    /// the linear model with delta > 0 and for the full model); the energy servo's nominal
    /// thrust tau0. Required.
    pub thrust_tau_mps2: f64,
    /// `thrust_delta_s`: delta, thrust duration from bottom, s (>= 0; must be 0 for eq. 9).
    /// Default 0.
    #[serde(default)]
    pub thrust_delta_s: f64,
    /// `friction_gamma_per_s`: gamma, viscous friction per unit mass in stance, 1/s (>= 0;
    /// linear model gamma^2 < 4 eta1; ignored by eq. 9, which has none). Default 0.
    #[serde(default)]
    pub friction_gamma_per_s: f64,
    /// `gravity_mps2`: g, m/s^2 (> 0). Eq. 9 applies it in flight only (Table 1's "0/10").
    /// Default 9.81.
    #[serde(default = "default_gravity")]
    pub gravity_mps2: f64,
    /// `spring_rest_m`: chi_0, the linear spring's relaxed position, m (linear model only).
    /// Default: tuned, chi_l + g/eta1 (the loaded rest position is the touchdown height, as
    /// eq. 16 assumes).
    pub spring_rest_m: Option<f64>,
    /// `leg_mass_ratio`: mu', leg mass as a fraction of the body mass (>= 0); liftoff
    /// scales the velocity by 1/(1 + mu') (eq. 7). Table 1's "mass ratio" 1 is eq. 14's
    /// mu = (1/(1 + mu'))^2 = 1, i.e. mu' = 0. Default 0.
    #[serde(default)]
    pub leg_mass_ratio: f64,
    /// `initial_heights_m`: chi(0), m: one trajectory per entry, each starting at rest: at or
    /// above chi_l an apex in flight, below chi_l a bottom. Default [chi_l + 0.5].
    pub initial_heights_m: Option<Vec<f64>>,
    /// `initial_velocity_mps`: chi'(0), m/s, for flight starts only. Default 0.
    #[serde(default)]
    pub initial_velocity_mps: f64,
    /// `cycles`: hops to simulate per trajectory (>= 1). Default 100.
    #[serde(default = "default_cycles")]
    pub cycles: usize,
    /// `integrator`: `"rk45"` (default) or `"rk4"`; full model only.
    #[serde(default)]
    pub integrator: IntegratorKind,
    /// `step_s`: RK4 step, or RK45 first step, s (> 0). Default 1e-4.
    #[serde(default = "default_step")]
    pub step_s: f64,
    /// `tolerance_m`: RK45 local error tolerance, m (> 0). Default 1e-10.
    #[serde(default = "default_tolerance")]
    pub tolerance_m: f64,
    /// `samples_per_phase`: dense samples per phase and hop for phase portraits (0 = none;
    /// at most [`super::MAX_SAMPLES_PER_PHASE`]; a run keeps at most [`super::MAX_SAMPLES`]).
    /// Default 0.
    #[serde(default)]
    pub samples_per_phase: usize,
    /// `[hopper.servo]`: energy servo; absent = Raibert's fixed thrust.
    pub servo: Option<ServoParams>,
}

fn default_liftoff() -> f64 {
    0.5
}
fn default_gravity() -> f64 {
    9.81
}
fn default_cycles() -> usize {
    100
}
fn default_step() -> f64 {
    1e-4
}
fn default_tolerance() -> f64 {
    1e-10
}

impl HopperParams {
    /// The validated hopper (errors name the key, e.g. `hopper.spring_eta1 must be > 0`).
    pub fn build(&self) -> Result<Hopper, HopperError> {
        let g = self.gravity_mps2;
        let model = match self.model {
            ModelKind::SimplifiedNonlinear => {
                HopperModel::SimplifiedNonlinear(SimplifiedNonlinear::new(
                    self.liftoff_height_m,
                    self.spring_eta1,
                    self.leg_mass_ratio,
                    g,
                )?)
            }
            ModelKind::Linear => {
                let eta1 = dexter_core::params::positive("hopper.spring_eta1", self.spring_eta1)?;
                let rest = self
                    .spring_rest_m
                    .unwrap_or(self.liftoff_height_m + g / eta1);
                HopperModel::Linear(LinearSpring::new(
                    self.liftoff_height_m,
                    eta1,
                    self.friction_gamma_per_s,
                    rest,
                    self.leg_mass_ratio,
                    g,
                )?)
            }
            ModelKind::Full => {
                let integrator = match self.integrator {
                    IntegratorKind::Rk4 => Integrator::Rk4 {
                        step_s: positive("hopper.step_s", self.step_s)?,
                    },
                    IntegratorKind::Rk45 => Integrator::Rk45 {
                        tolerance_m: positive("hopper.tolerance_m", self.tolerance_m)?,
                        initial_step_s: positive("hopper.step_s", self.step_s)?,
                    },
                };
                HopperModel::Full(FullNonlinear::new(
                    self.liftoff_height_m,
                    self.spring_eta1,
                    self.friction_gamma_per_s,
                    self.leg_mass_ratio,
                    g,
                    integrator,
                )?)
            }
        };
        if self.model == ModelKind::SimplifiedNonlinear && self.friction_gamma_per_s != 0.0 {
            return Err(HopperError::Relation {
                param: "hopper.friction_gamma_per_s",
                requirement: "gamma = 0 for the simplified nonlinear model (eq. 9 has no friction)",
            });
        }
        let raibert =
            RaibertThrust::new(self.thrust_tau_mps2, self.thrust_delta_s).map_err(rename_thrust)?;
        let law = match &self.servo {
            None => ThrustLaw::Raibert(raibert),
            Some(s) => ThrustLaw::EnergyServo(
                EnergyServoThrust::new(
                    raibert.thrust_mps2(),
                    s.gain_per_m,
                    s.target_energy_jpkg,
                    s.max_thrust_mps2.unwrap_or(2.0 * raibert.thrust_mps2()),
                    self.thrust_delta_s,
                )
                .map_err(rename_servo)?,
            ),
        };
        if self.cycles == 0 {
            return Err(HopperError::Param(ParamError::NotPositive("hopper.cycles")));
        }
        if self.samples_per_phase > super::MAX_SAMPLES_PER_PHASE {
            return Err(HopperError::Relation {
                param: "hopper.samples_per_phase",
                requirement:
                    "<= 10000 (samples per phase and hop; a run keeps at most 200000 in all)",
            });
        }
        Hopper::new(model, law)
    }

    /// The run starts: one per `initial_heights_m` entry (validated, finite).
    pub fn starts(&self) -> Result<Vec<Start>, HopperError> {
        let chi_l = self.liftoff_height_m;
        let heights = self
            .initial_heights_m
            .clone()
            .unwrap_or_else(|| vec![chi_l + 0.5]);
        let v = check_finite("hopper.initial_velocity_mps", self.initial_velocity_mps)?;
        heights
            .into_iter()
            .map(|h| {
                let h = check_finite("hopper.initial_heights_m", h)?;
                match Start::at_rest(h, chi_l) {
                    Start::Flight { height_m, .. } => Ok(Start::Flight {
                        height_m,
                        velocity_mps: v,
                    }),
                    b if v == 0.0 => Ok(b),
                    _ => Err(HopperError::Relation {
                        param: "hopper.initial_velocity_mps",
                        requirement: "= 0 when an initial height is below hopper.liftoff_height_m (a stance start is a bottom)",
                    }),
                }
            })
            .collect()
    }

    /// Run options from `samples_per_phase`.
    pub fn run_options(&self) -> super::RunOptions {
        super::RunOptions {
            times: true,
            samples_per_phase: self.samples_per_phase,
        }
    }
}

fn rename_thrust(e: ParamError) -> HopperError {
    let key = match e {
        ParamError::NotFinite("duration_s") | ParamError::Negative("duration_s") => {
            "hopper.thrust_delta_s"
        }
        _ => "hopper.thrust_tau_mps2",
    };
    HopperError::Param(match e {
        ParamError::NotFinite(_) => ParamError::NotFinite(key),
        ParamError::Negative(_) => ParamError::Negative(key),
        ParamError::NotPositive(_) => ParamError::NotPositive(key),
        _ => ParamError::OutOfRange(key),
    })
}

fn rename_servo(e: ParamError) -> HopperError {
    let key = |p: &str| match p {
        "gain_per_m" => "hopper.servo.gain_per_m",
        "target_energy_jpkg" => "hopper.servo.target_energy_jpkg",
        "max_thrust_mps2" | "nominal_thrust_mps2" => "hopper.servo.max_thrust_mps2",
        "duration_s" => "hopper.thrust_delta_s",
        _ => "hopper.servo",
    };
    HopperError::Param(match e {
        ParamError::NotFinite(p) => ParamError::NotFinite(key(p)),
        ParamError::Negative(p) => ParamError::Negative(key(p)),
        ParamError::NotPositive(p) => ParamError::NotPositive(key(p)),
        ParamError::OutOfRange(p) => ParamError::OutOfRange(key(p)),
        other => other,
    })
}
