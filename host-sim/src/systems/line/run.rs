//! Running a line scene: the plant is assembled once from the scene (only the enabled
//! effects, as concrete types: [`super::assemble`]), then either jumps from impact to
//! impact (no controller) or steps a [`StepController`] at its fixed rate with the
//! firmware's `SensorFrame`/`ActuatorCommand` ([`super::loops`]).
//!
//! Every impact is passed on as it happens ([`run_streaming`]); the outcome keeps its
//! apex statistics in constant memory ([`super::apexes::ApexStats`]), and keeps every row
//! only when asked ([`RunOptions::record_rows`], for tests). The outcome's types live in
//! [`super::outcome`] (below the loops that fill them) and are the run API's too.

use super::outcome::Recorder;
pub use super::outcome::{End, RunError, RunOptions, RunOutcome, MAX_PHASE_SAMPLES};
use super::scene::{ControlMode, Scene};
use super::trace::ImpactRow;
use crate::controller::StepController;

/// Run `scene` with `options`, passing every impact to `on_impact` as it happens. For
/// `control.mode = "sil"` the controller is `controller` if given (e.g. the firmware in
/// QEMU), else the core linked in ([`crate::controller::Sil`]).
pub fn run_streaming(
    scene: &Scene,
    options: &RunOptions,
    controller: Option<&mut dyn StepController>,
    on_impact: &mut dyn FnMut(&ImpactRow),
) -> Result<RunOutcome, RunError> {
    if controller.is_some() && scene.control.mode != ControlMode::Sil {
        return Err(super::needs_sil(scene).into());
    }
    let mut rec = Recorder::new(scene, options.record_rows, on_impact);
    super::assemble::run(scene, options, controller, &mut rec)?;
    rec.out.check_finite();
    Ok(rec.out)
}

/// Run `scene` with `options` (as [`run_streaming`], keeping rows only if
/// [`RunOptions::record_rows`]).
pub fn run_scene(
    scene: &Scene,
    options: &RunOptions,
    controller: Option<&mut dyn StepController>,
) -> Result<RunOutcome, RunError> {
    run_streaming(scene, options, controller, &mut |_| {})
}
