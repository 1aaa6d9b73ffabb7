//! The controller side of a closed-loop run, behind one trait so the same plant can be
//! closed through the core linked in (SIL) or through the firmware in QEMU (HIL).
//!
//! [`StepController`] is generic over the core's controller kind ([`FixedRate`]): a plant
//! sends that controller's frames and applies its commands, whether the controller is the
//! core linked in ([`Sil`]) or the firmware behind a link (`crate::hil`).

use dexter_core::control::Controller;
use dexter_core::fixed_rate::FixedRate;
use dexter_core::params::ParamError;
use dexter_core::protocol::Telemetry;

/// What one control step returns: a command of the controller kind `C`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct StepOutput<Cmd = dexter_core::protocol::ActuatorCommand> {
    /// The command to apply for the next control period.
    pub command: Cmd,
    /// Telemetry, when the controller reports it (the firmware does; SIL fills what the core knows).
    pub telemetry: Telemetry,
}

/// Why a controller could not be stepped.
#[derive(Debug)]
pub enum ControllerError {
    /// The parameters were rejected.
    Params(ParamError),
    /// The link to an external controller failed (I/O, timeout, emulator exited).
    Link(String),
}

impl std::fmt::Display for ControllerError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            ControllerError::Params(e) => write!(f, "controller parameter error: {e}"),
            ControllerError::Link(e) => write!(f, "controller link error: {e}"),
        }
    }
}

impl std::error::Error for ControllerError {}

/// Timing and link figures of a hardware-in-the-loop run (the `--json` keys HIL adds).
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize)]
pub struct HilReport {
    /// Fewest instructions one control step took on the target.
    pub step_instructions_min: u32,
    /// Mean instructions per control step on the target.
    pub step_instructions_mean: f64,
    /// Most instructions one control step took on the target.
    pub step_instructions_max: u32,
    /// Steps whose firmware command differed (bit for bit) from the SIL core's.
    pub sil_mismatches: u64,
    /// Frames rejected on the link, both directions (CRC, framing, decode).
    pub link_errors: u64,
    /// Control steps that exceeded the instruction budget.
    pub over_budget_steps: u64,
    /// Steps the firmware answered in its safe state because of a link timeout.
    pub link_timeouts: u64,
    /// Control steps per wall-clock second over the link.
    pub steps_per_wall_second: f64,
}

/// A controller of kind `C` stepped once per control period with the plant's sensor frame.
pub trait StepController<C: FixedRate = Controller> {
    /// One control step.
    fn step(&mut self, frame: &C::Frame) -> Result<StepOutput<C::Command>, ControllerError>;
    /// HIL figures, for controllers that run on the target (None for SIL).
    fn hil_report(&self) -> Option<HilReport> {
        None
    }
}

/// Software in the loop: the shared core, linked in, f32, the same code the firmware runs.
pub struct Sil<C = Controller> {
    controller: C,
}

impl<C: FixedRate> Sil<C> {
    /// A SIL controller from parameters.
    pub fn new(params: C::Params) -> Result<Self, ControllerError> {
        Ok(Self {
            controller: C::new(params).map_err(ControllerError::Params)?,
        })
    }

    /// The controller inside.
    pub fn controller(&self) -> &C {
        &self.controller
    }
}

impl<C: FixedRate> StepController<C> for Sil<C> {
    fn step(&mut self, frame: &C::Frame) -> Result<StepOutput<C::Command>, ControllerError> {
        let command = self.controller.step(frame);
        Ok(StepOutput {
            command,
            telemetry: self.controller.telemetry(),
        })
    }
}
