//! Rizzi & Koditschek's spatial juggler (`[spatial_juggler]` scenes, sec. 3.1.2): a ball in
//! 3-D batted by a three-joint robot whose paddle tracks eq. 13 or the modified law with a
//! solvable flight time perfectly. Physics in [`crate::model::spatial`]; kinematics, keys
//! and output in `docs/spatial.md`.
//!
//! On the vertical plane through the base at phi*, with the ball over rho* at rest at its
//! apex, the motion is the line juggler's (eq. 8): its fixed point ([`summary::ClosedForm`])
//! is what every run is compared with.

pub mod analyze;
pub mod plots;
pub mod sil;
pub mod summary;
pub mod trace;

use self::sil::SilTable;
use self::summary::{ControllerFigures, SpatialOutcome};
use self::trace::SpatialRow;
use crate::controller::StepController;
use crate::model::spatial::sil::{self as closed_loop, SilEnd, SilPlant};
use crate::model::spatial::{Law, SpatialEnd, SpatialJuggler, SpatialParams, MAX_BATS};
use crate::scene::{deserialize, SceneError, SceneFile};
use crate::system::{Failure, RunLength, Setup, System};
use dexter_core::params::ParamError;
use dexter_core::spatial::SpatialBall;
use dexter_core::spatial_control::{SpatialControlParams, SpatialController};
use serde::{Deserialize, Serialize};
use std::time::Instant;

/// Why a run ended, snake_case.
pub fn end_name(e: SpatialEnd) -> &'static str {
    match e {
        SpatialEnd::Completed => "completed",
        SpatialEnd::NoContact => "no_contact",
        SpatialEnd::SearchCap => "search_cap",
        SpatialEnd::BadContact => "bad_contact",
        SpatialEnd::OverBase => "over_base",
        SpatialEnd::NonFinite => "non_finite",
    }
}

/// Why a closed-loop run ended, snake_case.
pub fn sil_end_name(e: SilEnd) -> &'static str {
    match e {
        SilEnd::Completed => "completed",
        SilEnd::Dropped => "dropped",
        SilEnd::SearchCap => "search_cap",
        SilEnd::NonFinite => "non_finite",
        SilEnd::StepCap => "step_cap",
    }
}

/// The `[spatial_juggler]` table (every key, unit and default: `docs/spatial.md`). A gain
/// left out takes [`SpatialParams::suggested`]'s value for the table's law, restitution,
/// gravity and set point.
#[derive(Clone, Debug, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields, default)]
pub struct SpatialTable {
    /// `law`: `"mirror"` (eq. 13) or `"modified"` (solvable flight time).
    pub law: Law,
    /// `restitution`: ball-paddle restitution alpha, in (0, 1].
    pub restitution: f64,
    /// `gravity_mps2`: gamma, m/s^2 (> 0).
    pub gravity_mps2: f64,
    /// `target_apex_m`: apex height h* above the base, m (> 0).
    pub target_apex_m: f64,
    /// `target_radius_m`: the set point's horizontal radius rho*, m (> 0).
    pub target_radius_m: f64,
    /// `target_azimuth_rad`: the set point's azimuth phi*, rad.
    pub target_azimuth_rad: f64,
    /// `kappa0`: mirror gain at eta*, >= 0.
    pub kappa0: Option<f64>,
    /// `kappa1_s2pm2`: energy gain, s^2/m^2, >= 0.
    pub kappa1_s2pm2: Option<f64>,
    /// `kappa10`: radial P gain, rad/m (eq. 13) or m/m (modified).
    pub kappa10: Option<f64>,
    /// `kappa11`: radial D gain, rad s/m (eq. 13) or s (modified).
    pub kappa11: Option<f64>,
    /// `kappa20_radpm`: lateral P gain, rad/m.
    pub kappa20_radpm: Option<f64>,
    /// `kappa21_radspm`: lateral D gain, rad s/m.
    pub kappa21_radspm: Option<f64>,
    /// `initial_position_m`: the ball's (b_x, b_y, b_z) at t = 0, m.
    pub initial_position_m: [f64; 3],
    /// `initial_velocity_mps`: its velocity, m/s.
    pub initial_velocity_mps: [f64; 3],
    /// `impacts`: bats to simulate, 1 ..= [`MAX_BATS`].
    pub impacts: usize,
    /// `friction_coefficient`: Coulomb friction at the bats, >= 0 (0: off, the default).
    pub friction_coefficient: f64,
    /// `[spatial_juggler.sil]`: run through the fixed-rate controller (camera, encoders,
    /// joint limits) instead of perfect tracking.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub sil: Option<SilTable>,
}

impl Default for SpatialTable {
    fn default() -> Self {
        let p = SpatialParams::default();
        Self {
            law: Law::Mirror,
            restitution: p.restitution,
            gravity_mps2: p.law.gravity_mps2,
            target_apex_m: p.law.target_apex_m,
            target_radius_m: p.law.target_radius_m,
            target_azimuth_rad: p.law.target_azimuth_rad,
            kappa0: None,
            kappa1_s2pm2: None,
            kappa10: None,
            kappa11: None,
            kappa20_radpm: None,
            kappa21_radspm: None,
            initial_position_m: [1.06, 0.08, 0.6],
            initial_velocity_mps: [0.0; 3],
            impacts: 40,
            friction_coefficient: 0.0,
            sil: None,
        }
    }
}

/// A spatial juggler scene file: only a `[spatial_juggler]` table.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct SpatialFile {
    spatial_juggler: SpatialTable,
}

/// The spatial juggler system.
#[derive(Clone, Copy, Debug, Default)]
pub struct SpatialJugglerSystem;

/// A parsed, validated spatial juggler scene.
#[derive(Clone, Debug, PartialEq)]
pub struct SpatialConfig {
    /// The scene's name (the file stem).
    pub name: String,
    /// The table as given.
    pub table: SpatialTable,
    /// The gains in use (defaults resolved).
    pub params: SpatialParams,
    /// The validated juggler.
    pub juggler: SpatialJuggler,
    /// The initial ball state.
    pub start: SpatialBall<f64>,
    /// The closed loop's controller and plant (`[spatial_juggler.sil]`).
    pub sil: Option<(SpatialControlParams, SilPlant)>,
}

/// A core parameter error with its `[spatial_juggler]` key.
pub(crate) fn param_error(e: ParamError) -> SceneError {
    SceneError::of_param(e, "docs/spatial.md", |name| {
        let key = match name {
            "kappa1" => "kappa1_s2pm2",
            "kappa20" => "kappa20_radpm",
            "kappa21" => "kappa21_radspm",
            n => n,
        };
        format!("spatial_juggler.{key}")
    })
}

impl SpatialTable {
    /// The gains with their defaults resolved.
    pub fn params(&self) -> SpatialParams {
        let mut p = SpatialParams::suggested(
            self.law,
            self.restitution,
            self.gravity_mps2,
            self.target_apex_m,
            self.target_radius_m,
            self.target_azimuth_rad,
        );
        let l = &mut p.law;
        for (given, slot) in [
            (self.kappa0, &mut l.kappa0),
            (self.kappa1_s2pm2, &mut l.kappa1_s2pm2),
            (self.kappa10, &mut l.kappa10),
            (self.kappa11, &mut l.kappa11),
            (self.kappa20_radpm, &mut l.kappa20_radpm),
            (self.kappa21_radspm, &mut l.kappa21_radspm),
        ] {
            if let Some(v) = given {
                *slot = v;
            }
        }
        p
    }

    /// The keys the default gains are computed from must be in range first.
    fn check_base(&self) -> Result<(), SceneError> {
        if !(self.restitution > 0.0 && self.restitution <= 1.0) {
            return Err(SceneError::new(
                "spatial_juggler.restitution",
                format!("must be in (0, 1], got {}", self.restitution),
            ));
        }
        for (k, v) in [
            ("gravity_mps2", self.gravity_mps2),
            ("target_apex_m", self.target_apex_m),
            ("target_radius_m", self.target_radius_m),
        ] {
            if !(v.is_finite() && v > 0.0) {
                let key = format!("spatial_juggler.{k}");
                return Err(SceneError::new(
                    key,
                    format!("must be finite and > 0, got {v}"),
                ));
            }
        }
        Ok(())
    }

    /// The default gains divide by v*^2 = 2 gamma h*: a tiny product makes those left out
    /// infinite, reported under the keys the user set.
    fn defaults_fit(&self) -> Result<(), SceneError> {
        let d = SpatialParams::suggested(
            self.law,
            self.restitution,
            self.gravity_mps2,
            self.target_apex_m,
            1.0,
            0.0,
        )
        .law;
        let unset = [
            (self.kappa1_s2pm2, d.kappa1_s2pm2),
            (self.kappa20_radpm, d.kappa20_radpm),
            (self.kappa21_radspm, d.kappa21_radspm),
        ];
        if unset
            .iter()
            .all(|(given, d)| given.is_some() || d.is_finite())
        {
            return Ok(());
        }
        Err(SceneError::new(
            "spatial_juggler.gravity_mps2",
            format!(
                "is too small: with spatial_juggler.target_apex_m = {} m, v*^2 = 2 g apex = {:e} m^2/s^2 makes the default gains infinite; raise gravity_mps2 or target_apex_m, or set kappa1_s2pm2, kappa20_radpm and kappa21_radspm",
                self.target_apex_m,
                2.0 * self.gravity_mps2 * self.target_apex_m
            ),
        ))
    }

    /// Validate into a config named `name`.
    pub fn config(self, name: &str) -> Result<SpatialConfig, SceneError> {
        self.check_base()?;
        self.defaults_fit()?;
        let params = self.params();
        let juggler = params.juggler(self.law).map_err(param_error)?;
        let juggler = juggler
            .with_friction(self.friction_coefficient)
            .map_err(param_error)?;
        if !(1..=MAX_BATS).contains(&self.impacts) {
            return Err(SceneError::new(
                "spatial_juggler.impacts",
                format!("must be in 1..={MAX_BATS}, got {}", self.impacts),
            ));
        }
        let start = self.start()?;
        let sil = match &self.sil {
            Some(t) => Some((t.controller_params(&self)?, t.plant(&self, start)?)),
            None => None,
        };
        Ok(SpatialConfig {
            name: name.to_string(),
            table: self,
            params,
            juggler,
            start,
            sil,
        })
    }

    fn start(&self) -> Result<SpatialBall<f64>, SceneError> {
        for (k, v) in [
            ("initial_position_m", self.initial_position_m),
            ("initial_velocity_mps", self.initial_velocity_mps),
        ] {
            if let Some(x) = v.iter().find(|x| !x.is_finite()) {
                let key = format!("spatial_juggler.{k}");
                return Err(SceneError::new(key, format!("must be finite, got {x}")));
            }
        }
        let [x, y, _] = self.initial_position_m;
        if x.hypot(y) <= 1e-6 * self.target_radius_m {
            return Err(SceneError::new(
                "spatial_juggler.initial_position_m",
                "must be off the base's vertical axis (the first joint follows the ball's azimuth)",
            ));
        }
        Ok(SpatialBall::new(
            self.initial_position_m,
            self.initial_velocity_mps,
        ))
    }
}

impl System for SpatialJugglerSystem {
    const NAME: &'static str = "spatial juggler";
    const LENGTH: RunLength = RunLength::Events {
        key: "spatial_juggler.impacts",
        max: MAX_BATS as u64,
    };
    type Config = SpatialConfig;
    type Controller = SpatialController;
    type Row = SpatialRow;
    type Outcome = SpatialOutcome;
    type Plots = plots::SpatialPlots;

    fn claims(table: &toml::Table) -> bool {
        table.contains_key("spatial_juggler")
    }

    fn parse(file: &SceneFile, table: toml::Table) -> Result<SpatialConfig, SceneError> {
        deserialize::<SpatialFile>(table)?
            .spatial_juggler
            .config(&file.stem)
    }

    /// The fixed-rate controller of a `[spatial_juggler.sil]` scene (`None`: perfect
    /// tracking has no controller, so `--hil` is refused).
    fn controller_params(cfg: &SpatialConfig) -> Result<Option<SpatialControlParams>, SceneError> {
        Ok(cfg.sil.map(|(p, _)| p))
    }

    fn run(
        cfg: &SpatialConfig,
        ctrl: Option<&mut dyn StepController<SpatialController>>,
        _: &Setup,
        rows: &mut dyn FnMut(&SpatialRow),
    ) -> Result<SpatialOutcome, Failure> {
        let t0 = Instant::now();
        let Some((params, plant)) = &cfg.sil else {
            let run = cfg.juggler.run(cfg.start, cfg.table.impacts);
            let wall_s = t0.elapsed().as_secs_f64();
            for bat in &run.bats {
                rows(&SpatialRow(*bat));
            }
            return Ok(SpatialOutcome::new(
                cfg,
                &run.bats,
                end_name(run.end),
                wall_s,
            ));
        };
        let on_target = ctrl.is_some();
        let mut sil;
        let ctl: &mut dyn StepController<SpatialController> = match ctrl {
            Some(c) => c,
            None => {
                sil = closed_loop::sil_controller(*params).map_err(Failure::run)?;
                &mut sil
            }
        };
        let mut bats = Vec::new();
        let mut on_bat = |b: &_| {
            rows(&SpatialRow(*b));
            bats.push(*b);
        };
        let apex = cfg.table.target_apex_m;
        let report = closed_loop::run(plant, apex, ctl, cfg.table.impacts, &mut on_bat)
            .map_err(Failure::run)?;
        let wall_s = t0.elapsed().as_secs_f64();
        let end = sil_end_name(report.end);
        let mut outcome = SpatialOutcome::new(cfg, &bats, end, wall_s);
        outcome.summary.controller = Some(ControllerFigures::new(cfg, report, on_target));
        Ok(outcome)
    }
}
