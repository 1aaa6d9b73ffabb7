//! The one shape of every controller in the core: validated parameters, one
//! [`FixedRate::step`] per control period from a sensor frame to a command, and a safe
//! state with a fault code.
//!
//! Every controller the firmware hosts (the line juggler's [`Controller`], and the tilt
//! table, the hopper's thrust and the arm's trajectory tracker as they join) implements
//! [`FixedRate`], and its command type implements [`Reply`]. The simulator's SIL loop, the
//! host's HIL driver and the firmware's server are written once against these two traits
//! and [`Wire`] (how a controller's types travel on the link): a new controller needs its
//! own parameter, frame and command types and one line in the protocol's kind list, not a
//! new loop (see [`crate::protocol`], "Adding a controller kind").
//!
//! Contract of an implementation (tested per controller):
//! - `step` does bounded work (fixed iteration caps, no recursion), allocates nothing and
//!   never panics, for every input bit pattern;
//! - its command is finite and within the actuator limits, or the safe command
//!   ([`Mode::Safe`] with a [`Fault`] other than [`Fault::None`]);
//! - the core owns no clock: time comes in through `dt_s` in the parameters and the
//!   frames' sequence numbers.
//!
//! [`Controller`]: crate::control::Controller
//! [`Wire`]: crate::protocol::Wire

use crate::params::ParamError;
use crate::protocol::{ActuatorCommand, Fault, Mode, Telemetry};

/// A controller stepped once per fixed control period.
pub trait FixedRate: Sized {
    /// Everything the controller needs, SI units, f32; validated by [`FixedRate::new`].
    type Params: Copy;
    /// One sample of the plant, sent to the controller every control period.
    type Frame: Copy;
    /// The controller's output for one control period.
    type Command: Reply;
    /// Most target instructions one [`FixedRate::step`] (or [`FixedRate::safe`]) may take on
    /// the Cortex-M4F, for every configuration [`FixedRate::new`] accepts; the controller's
    /// docs give the argument. The HIL driver fails a step over it unless told otherwise.
    const STEP_INSTRUCTION_BUDGET: u32;

    /// A controller; the error names the first invalid parameter.
    fn new(params: Self::Params) -> Result<Self, ParamError>;
    /// The parameters this controller runs with.
    fn params(&self) -> &Self::Params;
    /// One control period: the command for `frame`.
    fn step(&mut self, frame: &Self::Frame) -> Self::Command;
    /// The safe command for an external fault (e.g. the firmware's link timeout or an
    /// overrun of the control period); `seq` is the sequence number it answers.
    fn safe(&mut self, seq: u32, fault: Fault) -> Self::Command;
    /// Telemetry fields the core knows (the firmware adds timing and link counts).
    fn telemetry(&self) -> Telemetry;
}

/// What every command says about itself, whatever its actuator fields.
pub trait Reply: Copy {
    /// Sequence number of the sensor frame this command answers.
    fn seq(&self) -> u32;
    /// The controller's mode when it produced this command.
    fn mode(&self) -> Mode;
    /// The fault code; [`Fault::None`] unless `mode() == Mode::Safe`.
    fn fault(&self) -> Fault;
    /// Whether two commands are identical bit for bit (every f32 compared by `to_bits`),
    /// as the HIL check of firmware against SIL needs.
    fn bit_identical(&self, other: &Self) -> bool;
}

impl Reply for ActuatorCommand {
    fn seq(&self) -> u32 {
        self.seq
    }

    fn mode(&self) -> Mode {
        self.mode
    }

    fn fault(&self) -> Fault {
        self.fault
    }

    fn bit_identical(&self, other: &Self) -> bool {
        self.seq == other.seq
            && self.paddle_accel_mps2.to_bits() == other.paddle_accel_mps2.to_bits()
            && self.paddle_height_ref_m.to_bits() == other.paddle_height_ref_m.to_bits()
            && self.paddle_velocity_ref_mps.to_bits() == other.paddle_velocity_ref_mps.to_bits()
            && self.mode == other.mode
            && self.fault == other.fault
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bit_identical_tells_signed_zeros_and_nan_payloads_apart() {
        let a = ActuatorCommand::default();
        let mut b = a;
        assert!(a.bit_identical(&b));
        b.paddle_accel_mps2 = -0.0;
        assert!(!a.bit_identical(&b), "+0 and -0 differ in their bits");
        b = a;
        b.fault = Fault::Stale;
        assert!(!a.bit_identical(&b));
        b = a;
        b.seq = 1;
        assert!(!a.bit_identical(&b));
    }
}
