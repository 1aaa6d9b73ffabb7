//! The hopper on the MCU: a `[hopper]` scene with a `[hopper.control]` table
//! closes its loop through the core's fixed-rate thrust controller
//! ([`dexter_core::hop_control::HopController`]): in SIL the core linked in, with `--hil`
//! the firmware in QEMU, lock-step and bit for bit. The plant is the valve-driven hopper of
//! [`crate::model::hopper::sampled`] (linear eq. 10/16 or full eq. 8, exact between control
//! steps; the sensor's rate, noise, quantization and latency each off unless asked for).
//!
//! | module | what it holds |
//! | --- | --- |
//! | [`scene`] | `[hopper.control]`, `[hopper.sensor]` and their checks |
//! | [`summary`] | the JSON keys (`docs/hopper.md`) and the text summary |
//! | [`trace`] | one CSV row per hop |
//! | [`plots`] | the timeline of the last hops: leg, phases, valve |
//!
//! Commands and keys: `docs/hopper.md`, "The hopper on the MCU".

pub mod plots;
pub mod scene;
pub mod summary;
pub mod trace;

use self::scene::{has_control, scene_error, SampledHopperConfig};
use self::summary::SampledOutcome;
use self::trace::SampledRow;
use crate::controller::{Paced, Sil, StepController};
use crate::model::hopper::sampled::{run_sampled_with, SampledError, MAX_CYCLES};
use crate::progress::Progress;
use crate::scene::{SceneError, SceneFile};
use crate::system::{Failure, RunLength, Setup, System};
use dexter_core::hop_control::{HopController, HopParams};
use std::cell::Cell;
use std::time::Instant;

/// The sampled hopper: `[hopper]` scenes with a `[hopper.control]` table.
#[derive(Clone, Copy, Debug, Default)]
pub struct SampledHopperSystem;

impl System for SampledHopperSystem {
    const NAME: &'static str = "sampled hopper";
    const LENGTH: RunLength = RunLength::Events {
        key: "hopper.cycles",
        max: MAX_CYCLES as u64,
    };
    type Config = SampledHopperConfig;
    type Controller = HopController;
    type Row = SampledRow;
    type Outcome = SampledOutcome;
    type Plots = plots::SampledPlots;

    /// A `[hopper]` table with `[hopper.control]` (the exact hopper takes the others).
    fn claims(table: &toml::Table) -> bool {
        has_control(table)
    }

    fn parse(file: &SceneFile, table: toml::Table) -> Result<SampledHopperConfig, SceneError> {
        SampledHopperConfig::from_table(&file.stem, table)
    }

    fn controller_params(cfg: &SampledHopperConfig) -> Result<Option<HopParams>, SceneError> {
        Ok(Some(cfg.sampled.control))
    }

    fn run(
        cfg: &SampledHopperConfig,
        ctrl: Option<&mut dyn StepController<HopController>>,
        setup: &Setup,
        rows: &mut dyn FnMut(&SampledRow),
    ) -> Result<SampledOutcome, Failure> {
        let mut sampled = cfg.sampled.clone();
        if setup.plot {
            sampled.timeline = Some(cfg.timeline());
        }
        let mut sil;
        let inner: &mut dyn StepController<HopController> = match ctrl {
            Some(c) => c,
            None => {
                sil = Sil::<HopController>::new(sampled.control).map_err(Failure::run)?;
                &mut sil
            }
        };
        // the bar moves with simulated time too: a stalled hopper completes no cycle
        let limits = [
            (sampled.cycles as f64, "cycles"),
            (sampled.max_steps() as f64 * sampled.dt_s(), "s simulated"),
        ];
        let cycles = Cell::new(0);
        let bar = Progress::new(limits, setup.progress);
        let mut paced = Paced::new(inner, bar, &cycles, sampled.dt_s());
        let wall = Instant::now();
        let run = run_sampled_with(&sampled, &mut paced, &mut |c| {
            rows(&SampledRow(*c));
            cycles.set(c.index as u64 + 1);
        })
        .map_err(failure)?;
        paced.finish();
        Ok(SampledOutcome::new(cfg, run, wall.elapsed().as_secs_f64()))
    }
}

/// A bad setting is a bad scene (exit 2); a failed link a failed run (exit 1).
fn failure(e: SampledError) -> Failure {
    match e {
        SampledError::Controller(c) => Failure::run(c),
        other => Failure::scene(scene_error(other)),
    }
}
