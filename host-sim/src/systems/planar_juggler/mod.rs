//! Rizzi & Koditschek's planar juggler (`[planar_juggler]` scenes): a ball on an inclined
//! plane batted by a bar on a revolute joint that tracks the mirror law (eq. 12) or the
//! modified law with a solvable flight time (eq. 15) perfectly. Physics in
//! [`crate::model::planar::juggler`]; keys and output in `docs/planar.md`, "The planar
//! juggler".
//!
//! On the line b_x = b_x*, b_x' = 0 (where both laws' PD terms vanish) the bar meets the
//! ball horizontally on the b_x axis and the vertical motion is exactly the line juggler's:
//! the impact speed maps as eq. 8, v+ = (alpha + (1 + alpha) k(w)) v. Its fixed point
//! ([`summary::ClosedForm`]) is what every run is compared with.

pub mod plots;
pub mod summary;
pub mod trace;

use self::summary::{ClosedForm, JugglerOutcome};
use self::trace::BatRow;
use crate::controller::StepController;
use crate::model::planar::juggler::{JuggleEnd, JugglerParams, PlanarJuggler, MAX_JUGGLES};
use crate::scene::{deserialize, SceneError, SceneFile};
use crate::system::{Failure, NoController, RunLength, Setup, System};
use dexter_core::params::ParamError;
use dexter_core::planar::PlanarBall;
use serde::{Deserialize, Serialize};
use std::time::Instant;

/// Which law the bar tracks (`planar_juggler.law`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Deserialize, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Law {
    /// eq. 12 (the impact time solves the transcendental eq. 14).
    #[default]
    Mirror,
    /// eq. 15 (the impact time solves the quadratic eq. 16).
    Modified,
}

impl Law {
    /// The scene value (`mirror`, `modified`).
    pub fn name(self) -> &'static str {
        match self {
            Law::Mirror => "mirror",
            Law::Modified => "modified",
        }
    }

    /// The paper's equation.
    pub fn equation(self) -> &'static str {
        match self {
            Law::Mirror => "eq. 12",
            Law::Modified => "eq. 15",
        }
    }
}

/// Why a run ended, snake_case.
pub fn end_name(e: JuggleEnd) -> &'static str {
    match e {
        JuggleEnd::Completed => "completed",
        JuggleEnd::NoContact => "no_contact",
        JuggleEnd::SearchCap => "search_cap",
        JuggleEnd::BadContact => "bad_contact",
        JuggleEnd::LeftHalfPlane => "left_half_plane",
        JuggleEnd::NonFinite => "non_finite",
    }
}

/// The `[planar_juggler]` table (every key, unit and default: `docs/planar.md`).
#[derive(Clone, Debug, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields, default)]
pub struct JugglerTable {
    /// `law`: `"mirror"` (eq. 12) or `"modified"` (eq. 15).
    pub law: Law,
    /// `restitution`: ball-bar restitution alpha, in (0, 1].
    pub restitution: f64,
    /// `gravity_mps2`: in-plane gravity gamma, m/s^2 (> 0).
    pub gravity_mps2: f64,
    /// `target_apex_m`: apex height h* above the pivot, m (> 0); eta* = gamma h*.
    pub target_apex_m: f64,
    /// `target_x_m`: horizontal set point b_x*, m (> 0).
    pub target_x_m: f64,
    /// `kappa0`: mirror gain at eta*, >= 0. Default matched: (1 - alpha)/(1 + alpha).
    pub kappa0: Option<f64>,
    /// `kappa1_s2pm2`: energy gain, s^2/m^2, >= 0. Default 0.5/((1 + alpha) v*^2),
    /// v*^2 = 2 gamma h*: an energy slope of 0.5 at the fixed point.
    pub kappa1_s2pm2: Option<f64>,
    /// `kappa10`: horizontal P gain, rad/m (eq. 12) or m/m (eq. 15).
    pub kappa10: f64,
    /// `kappa11`: horizontal D gain, rad s/m (eq. 12) or s (eq. 15).
    pub kappa11: f64,
    /// `initial_x_m`: b_x(0), m (> 0).
    pub initial_x_m: f64,
    /// `initial_z_m`: b_z(0), m.
    pub initial_z_m: f64,
    /// `initial_x_dot_mps`: b_x'(0), m/s.
    pub initial_x_dot_mps: f64,
    /// `initial_z_dot_mps`: b_z'(0), m/s.
    pub initial_z_dot_mps: f64,
    /// `impacts`: bats to simulate, 1 ..= [`MAX_JUGGLES`].
    pub impacts: usize,
}

impl Default for JugglerTable {
    fn default() -> Self {
        let p = JugglerParams::default();
        Self {
            law: Law::Mirror,
            restitution: p.restitution,
            gravity_mps2: p.gravity_mps2,
            target_apex_m: p.target_apex_m,
            target_x_m: p.target_x_m,
            kappa0: None,
            kappa1_s2pm2: None,
            kappa10: p.kappa10,
            kappa11: p.kappa11,
            initial_x_m: 0.7,
            initial_z_m: 0.4,
            initial_x_dot_mps: 0.2,
            initial_z_dot_mps: 0.0,
            impacts: 80,
        }
    }
}

/// A planar juggler scene file: only a `[planar_juggler]` table.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct JugglerFile {
    planar_juggler: JugglerTable,
}

/// The planar juggler system.
#[derive(Clone, Copy, Debug, Default)]
pub struct PlanarJugglerSystem;

/// A parsed, validated planar juggler scene.
#[derive(Clone, Debug, PartialEq)]
pub struct JugglerConfig {
    /// The scene's name (the file stem).
    pub name: String,
    /// The table as given.
    pub table: JugglerTable,
    /// The gains in use (defaults resolved).
    pub params: JugglerParams,
    /// The validated juggler.
    pub juggler: PlanarJuggler,
    /// The initial ball state.
    pub start: PlanarBall<f64>,
}

/// A core parameter error with its `[planar_juggler]` key.
fn param_error(e: ParamError) -> SceneError {
    SceneError::of_param(e, "docs/planar.md", |name| {
        let key = if name == "kappa1" {
            "kappa1_s2pm2"
        } else {
            name
        };
        format!("planar_juggler.{key}")
    })
}

impl JugglerTable {
    /// The gains with their defaults resolved (module docs of [`JugglerTable`]).
    pub fn params(&self) -> JugglerParams {
        let alpha = self.restitution;
        let v2 = 2.0 * self.gravity_mps2 * self.target_apex_m;
        JugglerParams {
            restitution: alpha,
            gravity_mps2: self.gravity_mps2,
            kappa0: self.kappa0.unwrap_or((1.0 - alpha) / (1.0 + alpha)),
            kappa1_s2pm2: self.kappa1_s2pm2.unwrap_or(0.5 / ((1.0 + alpha) * v2)),
            target_apex_m: self.target_apex_m,
            kappa10: self.kappa10,
            kappa11: self.kappa11,
            target_x_m: self.target_x_m,
        }
    }

    /// Without `kappa1_s2pm2`, its default 0.5 / ((1 + alpha) v*^2), v*^2 = 2 g apex, must be
    /// finite: a tiny gravity or apex is reported under the keys the user set.
    fn default_kappa1_fits(&self) -> Result<(), SceneError> {
        let (g, apex) = (self.gravity_mps2, self.target_apex_m);
        let given = g.is_finite() && g > 0.0 && apex.is_finite() && apex > 0.0;
        if self.kappa1_s2pm2.is_some() || !given || self.params().kappa1_s2pm2.is_finite() {
            return Ok(());
        }
        Err(SceneError::new(
            "planar_juggler.gravity_mps2",
            format!(
                "is too small: with planar_juggler.target_apex_m = {apex} m, v*^2 = 2 g apex = {:e} m^2/s^2 makes the default gain 0.5 / ((1 + restitution) v*^2) infinite; raise gravity_mps2 or target_apex_m, or set planar_juggler.kappa1_s2pm2",
                2.0 * g * apex
            ),
        ))
    }

    /// Validate into a config named `name`.
    pub fn config(self, name: &str) -> Result<JugglerConfig, SceneError> {
        // the gains' defaults depend on alpha: check it first
        if !(self.restitution > 0.0 && self.restitution <= 1.0) {
            return Err(SceneError::new(
                "planar_juggler.restitution",
                format!("must be in (0, 1], got {}", self.restitution),
            ));
        }
        self.default_kappa1_fits()?;
        let params = self.params();
        let juggler = match self.law {
            Law::Mirror => params.mirror(),
            Law::Modified => params.modified(),
        }
        .map_err(param_error)?;
        if !(1..=MAX_JUGGLES).contains(&self.impacts) {
            return Err(SceneError::new(
                "planar_juggler.impacts",
                format!("must be in 1..={MAX_JUGGLES}, got {}", self.impacts),
            ));
        }
        let start = self.start()?;
        Ok(JugglerConfig {
            name: name.to_string(),
            table: self,
            params,
            juggler,
            start,
        })
    }

    fn start(&self) -> Result<PlanarBall<f64>, SceneError> {
        let keys = [
            ("initial_x_m", self.initial_x_m),
            ("initial_z_m", self.initial_z_m),
            ("initial_x_dot_mps", self.initial_x_dot_mps),
            ("initial_z_dot_mps", self.initial_z_dot_mps),
        ];
        if let Some((k, v)) = keys.iter().find(|(_, v)| !v.is_finite()) {
            let key = format!("planar_juggler.{k}");
            return Err(SceneError::new(
                key,
                format!("must be a finite number, got {v}"),
            ));
        }
        if self.initial_x_m <= 0.0 {
            return Err(SceneError::new(
                "planar_juggler.initial_x_m",
                "must be > 0 (the laws assume the right half plane b_x > 0)",
            ));
        }
        Ok(PlanarBall::new(
            self.initial_x_m,
            self.initial_z_m,
            self.initial_x_dot_mps,
            self.initial_z_dot_mps,
        ))
    }
}

impl System for PlanarJugglerSystem {
    const NAME: &'static str = "planar juggler";
    const LENGTH: RunLength = RunLength::Events {
        key: "planar_juggler.impacts",
        max: MAX_JUGGLES as u64,
    };
    type Config = JugglerConfig;
    type Controller = NoController;
    type Row = BatRow;
    type Outcome = JugglerOutcome;
    type Plots = plots::JugglerPlots;

    fn claims(table: &toml::Table) -> bool {
        table.contains_key("planar_juggler")
    }

    fn parse(file: &SceneFile, table: toml::Table) -> Result<JugglerConfig, SceneError> {
        deserialize::<JugglerFile>(table)?
            .planar_juggler
            .config(&file.stem)
    }

    fn run(
        cfg: &JugglerConfig,
        _: Option<&mut dyn StepController<NoController>>,
        _: &Setup,
        rows: &mut dyn FnMut(&BatRow),
    ) -> Result<JugglerOutcome, Failure> {
        let t0 = Instant::now();
        let run = cfg.juggler.run(cfg.start, cfg.table.impacts);
        let wall_s = t0.elapsed().as_secs_f64();
        for bat in &run.bats {
            rows(&BatRow(*bat));
        }
        let closed = ClosedForm::of(&cfg.params);
        Ok(JugglerOutcome::new(cfg, closed, &run, wall_s))
    }
}
