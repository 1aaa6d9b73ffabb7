//! The 1JOC parts feeder (`[feeder]` scenes) of Akella, Huang, Lynch & Mason, sec. 3: a
//! one-joint fence over a conveyor brings a polygonal part from its arrival pose to one goal
//! edge and contact radius. `run` plans the feed (sec. 3.3), simulates the plan with the
//! quasistatic mechanics (noise optional) and prints the summary; `sweep` feeds many
//! arrivals (`--range feeder.arrival.seed=1:200:200`) and reports the fraction fed.
//! Physics and planner in [`crate::model::feeder`]; keys, output and figures in
//! `docs/feeder.md`.

pub mod plots;
pub mod scene;
pub mod summary;
pub mod sweep;
pub mod trace;

use self::summary::FeederOutcome;
use self::trace::FeederRow;
use crate::controller::StepController;
use crate::model::feeder::execute::{execute_observed, summarize};
use crate::model::feeder::planner::plan;
use crate::model::feeder::FeederError;
use crate::scene::{deserialize, SceneError, SceneFile};
use crate::system::{Failure, NoController, RunLength, Setup, System};
use scene::{Built, FeederFile, FeederScene};
use std::time::Instant;

/// The feeder system.
#[derive(Clone, Copy, Debug, Default)]
pub struct FeederSystem;

/// A parsed, validated feeder scene.
#[derive(Clone, Debug, PartialEq)]
pub struct FeederConfig {
    /// The scene's name (the file stem).
    pub name: String,
    /// The `[feeder]` table as given.
    pub scene: FeederScene,
    /// The validated cell, arrival, planner options and noise.
    pub built: Built,
}

/// A model error as a scene error naming its key (an infeasible plan names its cause).
pub fn scene_error(e: FeederError) -> SceneError {
    match e {
        FeederError::Param { key, requirement } => SceneError::new(key, requirement),
        other => SceneError::whole(other),
    }
}

impl FeederConfig {
    /// Deserialize and validate a scene table named `name`.
    pub fn from_table(name: &str, table: toml::Table) -> Result<Self, SceneError> {
        let scene = deserialize::<FeederFile>(table)?.feeder;
        let built = scene.build().map_err(scene_error)?;
        Ok(Self {
            name: name.to_string(),
            scene,
            built,
        })
    }
}

impl System for FeederSystem {
    const NAME: &'static str = "feeder";
    /// A feed runs its plan: it has no event count or time limit to set.
    const LENGTH: RunLength = RunLength::Fixed;
    type Config = FeederConfig;
    type Controller = NoController;
    type Row = FeederRow;
    type Outcome = FeederOutcome;
    type Plots = plots::FeederPlots;

    fn claims(table: &toml::Table) -> bool {
        table.contains_key("feeder")
    }

    fn parse(file: &SceneFile, table: toml::Table) -> Result<FeederConfig, SceneError> {
        FeederConfig::from_table(&file.stem, table)
    }

    fn run(
        cfg: &FeederConfig,
        _: Option<&mut dyn StepController<NoController>>,
        _: &Setup,
        rows: &mut dyn FnMut(&FeederRow),
    ) -> Result<FeederOutcome, Failure> {
        let b = &cfg.built;
        let t0 = Instant::now();
        let p = plan(&b.feeder, b.arrival, &b.options).map_err(Failure::scene)?;
        let wall_s = t0.elapsed().as_secs_f64();
        let names: Vec<&'static str> = p.steps.iter().map(|s| s.name()).collect();
        let ex = execute_observed(&b.feeder, &p, b.arrival, b.noise.as_ref(), &mut |r| {
            rows(&FeederRow::new(r, names.get(r.step).copied().unwrap_or("")))
        });
        Ok(FeederOutcome::new(cfg, summarize(&b.feeder, p, ex, wall_s)))
    }
}
