//! The scene's `[planar]` table (documented key by key in `docs/planar.md`).
//!
//! Units: SI, per unit body mass. A planar scene file holds only this table;
//! [`PlanarParams::from_toml_str`] reads it and [`PlanarParams::build`] validates it into a
//! [`PlanarModel`], naming the key at fault.

use super::{Body, ContactLaw, PlanarError, PlanarModel, PlanarState};
use dexter_core::params::{finite, non_negative, positive, within, ParamError};
use dexter_core::tilt::{EnergyFeedback, TiltLaw};
use serde::{Deserialize, Serialize};

/// Which body bounces (`planar.body`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Deserialize, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum BodyKind {
    /// `"rigid"` (default): radius of gyration and contact distance from the table.
    #[default]
    Rigid,
    /// `"point_mass"`: rho = l = 0 (eq. 3–4); `radius_of_gyration_m`, `contact_distance_m`,
    /// `initial_theta_rad`, `initial_theta_dot_radps` and `tip_angle_rad` are ignored.
    PointMass,
}

/// The `[planar]` table. Every key, its meaning, unit and default (also in
/// `docs/planar.md`).
#[derive(Clone, Debug, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct PlanarParams {
    /// `body`: `"rigid"` or `"point_mass"`. Default `"rigid"`.
    #[serde(default)]
    pub body: BodyKind,
    /// `radius_of_gyration_m`: rho about the centre of mass, m (> 0). Default 0.09428 (the
    /// paper's triangle "as stated", sec. 2.3).
    #[serde(default = "default_rho")]
    pub radius_of_gyration_m: f64,
    /// `contact_distance_m`: l, centre of mass to contact point, m (> 0). Default 0.13333
    /// (2/3 of the triangle's 20 cm height: the apex, fig. 1).
    #[serde(default = "default_l")]
    pub contact_distance_m: f64,
    /// `gravity_mps2`: G along -y in the inclined plane, m/s^2 (> 0). Default 9.81.
    #[serde(default = "default_gravity")]
    pub gravity_mps2: f64,
    /// `restitution`: e, in [0, 1] (eq. 21). Default 0.5.
    #[serde(default = "default_e")]
    pub restitution: f64,
    /// `friction_mu`: Coulomb coefficient mu between table and body (>= 0; 0 =
    /// frictionless, eq. 21). Default 0.
    #[serde(default)]
    pub friction_mu: f64,
    /// `kappa`: tilt gain, alpha = kappa theta, dimensionless (>= 0). Default 1.1.
    #[serde(default = "default_kappa")]
    pub kappa: f64,
    /// `kappa_e_s2pm2`: energy gain kappa_E of eq. 25, s^2/m^2 (>= 0). Default 0.
    #[serde(default)]
    pub kappa_e_s2pm2: f64,
    /// `target_apex_m`: desired apex height of the centre of mass above the impact line,
    /// m (> l for a rigid body): eta* = G * target_apex_m. Default: the initial apex, i.e.
    /// eta of the first impact (eq. 8: the energy surface set by the drop).
    pub target_apex_m: Option<f64>,
    /// `initial_height_m`: y(0) of the centre of mass above the impact line, m (the contact
    /// point must be above the line: y(0) > l cos theta(0)). Default 0.2.
    #[serde(default = "default_height")]
    pub initial_height_m: f64,
    /// `initial_theta_rad`: theta(0), rad. Default 0.3.
    #[serde(default = "default_theta")]
    pub initial_theta_rad: f64,
    /// `initial_x_dot_mps`: x'(0), m/s. Default 0.
    #[serde(default)]
    pub initial_x_dot_mps: f64,
    /// `initial_y_dot_mps`: y'(0), m/s. Default 0.
    #[serde(default)]
    pub initial_y_dot_mps: f64,
    /// `initial_theta_dot_radps`: theta'(0), rad/s. Default 0.
    #[serde(default)]
    pub initial_theta_dot_radps: f64,
    /// `timing_noise_s`: sigma of the table's impact-time error (sec. 2.3), s (>= 0;
    /// clamped at ±4 sigma). Default 0.
    #[serde(default)]
    pub timing_noise_s: f64,
    /// `seed`: random seed of the timing noise. Default 1.
    #[serde(default = "default_seed")]
    pub seed: u64,
    /// `impacts`: impacts to simulate (1 ..= 1e6). Default 100.
    #[serde(default = "default_impacts")]
    pub impacts: usize,
    /// `tip_angle_rad`: |theta| at an impact at which the body has tipped over, rad, in
    /// (0, pi/2]. Default pi/2 (the rod lies flat); the triangle on its apex: atan(4).
    #[serde(default = "default_tip")]
    pub tip_angle_rad: f64,
}

fn default_rho() -> f64 {
    0.094_28
}
fn default_l() -> f64 {
    0.2 * 2.0 / 3.0
}
fn default_gravity() -> f64 {
    9.81
}
fn default_e() -> f64 {
    0.5
}
fn default_kappa() -> f64 {
    1.1
}
fn default_height() -> f64 {
    0.2
}
fn default_theta() -> f64 {
    0.3
}
fn default_seed() -> u64 {
    1
}
fn default_impacts() -> usize {
    100
}
fn default_tip() -> f64 {
    core::f64::consts::FRAC_PI_2
}

impl Default for PlanarParams {
    fn default() -> Self {
        Self {
            body: BodyKind::Rigid,
            radius_of_gyration_m: default_rho(),
            contact_distance_m: default_l(),
            gravity_mps2: default_gravity(),
            restitution: default_e(),
            friction_mu: 0.0,
            kappa: default_kappa(),
            kappa_e_s2pm2: 0.0,
            target_apex_m: None,
            initial_height_m: default_height(),
            initial_theta_rad: default_theta(),
            initial_x_dot_mps: 0.0,
            initial_y_dot_mps: 0.0,
            initial_theta_dot_radps: 0.0,
            timing_noise_s: 0.0,
            seed: default_seed(),
            impacts: default_impacts(),
            tip_angle_rad: default_tip(),
        }
    }
}

impl PlanarParams {
    /// The initial state (validated: finite, contact point above the impact line).
    pub fn start(&self) -> Result<PlanarState, PlanarError> {
        let rigid = self.body == BodyKind::Rigid;
        let s = PlanarState {
            x_m: 0.0,
            y_m: finite("planar.initial_height_m", self.initial_height_m)?,
            theta_rad: if rigid {
                finite("planar.initial_theta_rad", self.initial_theta_rad)?
            } else {
                0.0
            },
            x_dot_mps: finite("planar.initial_x_dot_mps", self.initial_x_dot_mps)?,
            y_dot_mps: finite("planar.initial_y_dot_mps", self.initial_y_dot_mps)?,
            theta_dot_radps: if rigid {
                finite(
                    "planar.initial_theta_dot_radps",
                    self.initial_theta_dot_radps,
                )?
            } else {
                0.0
            },
        };
        let l = if rigid { self.contact_distance_m } else { 0.0 };
        if s.y_m - l * s.theta_rad.cos() <= 0.0 {
            return Err(PlanarError::Relation {
                param: "planar.initial_height_m",
                requirement: "initial_height_m > contact_distance_m * cos(initial_theta_rad) (contact point above the impact line)",
            });
        }
        Ok(s)
    }

    /// eta at the first impact, J/kg: G y(0) + y'(0)^2/2 (vertical energy is conserved in
    /// flight; at impact it equals eq. 25's eta = G l cos theta + y'^2/2).
    pub fn initial_energy_jpkg(&self) -> f64 {
        self.gravity_mps2 * self.initial_height_m + 0.5 * self.initial_y_dot_mps.powi(2)
    }

    /// The validated model (errors name the key, e.g. `planar.restitution is out of its
    /// allowed range`).
    pub fn build(&self) -> Result<PlanarModel, PlanarError> {
        let g = positive("planar.gravity_mps2", self.gravity_mps2)?;
        let body = match self.body {
            BodyKind::PointMass => Body::PointMass,
            BodyKind::Rigid => Body::Rigid {
                rho_m: positive("planar.radius_of_gyration_m", self.radius_of_gyration_m)?,
                l_m: positive("planar.contact_distance_m", self.contact_distance_m)?,
            },
        };
        let e = within("planar.restitution", self.restitution, 0.0, 1.0)?;
        let mu = non_negative("planar.friction_mu", self.friction_mu)?;
        let kappa = non_negative("planar.kappa", self.kappa)?;
        let kappa_e = non_negative("planar.kappa_e_s2pm2", self.kappa_e_s2pm2)?;
        let sigma = non_negative("planar.timing_noise_s", self.timing_noise_s)?;
        let tip = within(
            "planar.tip_angle_rad",
            self.tip_angle_rad,
            0.0,
            core::f64::consts::FRAC_PI_2,
        )?;
        if tip == 0.0 {
            return Err(ParamError::NotPositive("planar.tip_angle_rad").into());
        }
        if self.impacts == 0 || self.impacts > super::MAX_IMPACTS {
            return Err(ParamError::OutOfRange("planar.impacts").into());
        }
        let start = self.start()?;
        let l = body.geometry().l_m;
        let eta_star = match self.target_apex_m {
            Some(h) => {
                let h = positive("planar.target_apex_m", h)?;
                if h <= l {
                    return Err(PlanarError::Relation {
                        param: "planar.target_apex_m",
                        requirement: "target_apex_m > contact_distance_m (the body must fly)",
                    });
                }
                g * h
            }
            None => g * start.y_m + 0.5 * start.y_dot_mps * start.y_dot_mps,
        };
        let feedback = EnergyFeedback::new(e, kappa_e, eta_star, g, l).map_err(|err| {
            PlanarError::Param(match err {
                ParamError::OutOfRange(_) => ParamError::OutOfRange("planar.restitution"),
                ParamError::Negative(_) => ParamError::Negative("planar.kappa_e_s2pm2"),
                other => other,
            })
        })?;
        let tilt = TiltLaw::new(kappa).map_err(|_| ParamError::Negative("planar.kappa"))?;
        Ok(PlanarModel {
            body,
            contact: if mu > 0.0 {
                ContactLaw::Coulomb { mu }
            } else {
                ContactLaw::Frictionless
            },
            tilt,
            feedback,
            gravity_mps2: g,
            timing_noise_s: sigma,
            tip_angle_rad: tip,
        })
    }

    /// Build, then run the scene's `impacts` from its start with its seed.
    pub fn simulate(&self) -> Result<super::PlanarRun, PlanarError> {
        let model = self.build()?;
        Ok(model.run(self.start()?, self.impacts, self.seed))
    }
}
