//! The link check: a [`FixedRate`] controller with no plant behind it, which answers each
//! frame with its value times a gain.
//!
//! It is what to run first on a new link or board: every frame must come back scaled, with
//! its sequence number, and a non-finite value must come back as the safe state. Its step
//! is a handful of instructions, so a HIL run with it times the link alone (encode, link,
//! decode; see BENCHMARKS.md, "HIL lock-step"). It is also the second kind that proves the
//! protocol generic: the firmware hosts it beside the line juggler, and the HIL tests
//! switch between the two and send frames of the wrong kind.

use crate::fixed_rate::{reply_from_fields, Fault, FixedRate, Mode, Telemetry};
use crate::params::{finite, ParamError};
use serde::{Deserialize, Serialize};

/// Parameters of the link check.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct EchoParams {
    /// Factor applied to each frame's value, dimensionless (finite).
    pub gain: f32,
}

impl Default for EchoParams {
    /// Gain 1: the value comes back unchanged.
    fn default() -> Self {
        Self { gain: 1.0 }
    }
}

/// One frame of the link check.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct EchoFrame {
    /// Sequence number, echoed in the command.
    pub seq: u32,
    /// The value to scale, arbitrary unit.
    pub value: f32,
}

/// The link check's answer to one frame.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct EchoCommand {
    /// Sequence number of the frame this answers.
    pub seq: u32,
    /// `gain * value` of the frame (0 in the safe state).
    pub value: f32,
    /// [`Mode::Track`], or [`Mode::Safe`] on a fault.
    pub mode: Mode,
    /// [`Fault::NonFinite`] for a non-finite product, or an external fault.
    pub fault: Fault,
}

reply_from_fields!(EchoCommand);

/// The link-check controller.
#[derive(Clone, Copy, Debug)]
pub struct Echo {
    params: EchoParams,
    last: EchoCommand,
}

impl FixedRate for Echo {
    type Params = EchoParams;
    type Frame = EchoFrame;
    type Command = EchoCommand;
    /// Straight-line code (one multiply, one finiteness test, no loops): ~20 instructions
    /// for every input; the budget leaves room for the compiler's layout.
    const STEP_INSTRUCTION_BUDGET: u32 = 60;

    fn new(params: EchoParams) -> Result<Self, ParamError> {
        finite("gain", params.gain)?;
        Ok(Self {
            params,
            last: EchoCommand::default(),
        })
    }

    fn params(&self) -> &EchoParams {
        &self.params
    }

    fn step(&mut self, frame: &EchoFrame) -> EchoCommand {
        let value = self.params.gain * frame.value;
        if !value.is_finite() {
            return self.safe(frame.seq, Fault::NonFinite);
        }
        self.last = EchoCommand {
            seq: frame.seq,
            value,
            mode: Mode::Track,
            fault: Fault::None,
        };
        self.last
    }

    fn safe(&mut self, seq: u32, fault: Fault) -> EchoCommand {
        self.last = EchoCommand {
            seq,
            value: 0.0,
            mode: Mode::Safe,
            fault,
        };
        self.last
    }

    /// Estimate slot 0: the last value sent back; valid unless in the safe state.
    fn telemetry(&self) -> Telemetry {
        Telemetry::with_estimate(&[self.last.value], self.last.mode == Mode::Track)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn echoes_the_scaled_value_with_its_sequence_number() {
        let mut c = Echo::new(EchoParams { gain: -2.5 }).unwrap();
        let cmd = c.step(&EchoFrame { seq: 9, value: 4.0 });
        assert_eq!((cmd.seq, cmd.value, cmd.mode), (9, -10.0, Mode::Track));
        assert_eq!(c.telemetry().estimate[0], -10.0);
        assert!(c.telemetry().estimate_valid);
    }

    #[test]
    fn a_non_finite_product_is_the_safe_state_and_a_bad_gain_is_refused() {
        let mut c = Echo::new(EchoParams { gain: 1e30 }).unwrap();
        let cmd = c.step(&EchoFrame {
            seq: 3,
            value: 1e30,
        });
        assert_eq!(
            (cmd.mode, cmd.fault, cmd.value),
            (Mode::Safe, Fault::NonFinite, 0.0)
        );
        assert!(!c.telemetry().estimate_valid);
        assert_eq!(
            Echo::new(EchoParams { gain: f32::NAN }).err(),
            Some(ParamError::NotFinite("gain"))
        );
    }
}
