//! The one shape of every controller in the core: validated parameters, one
//! [`FixedRate::step`] per control period from a sensor frame to a command, and a safe
//! state with a fault code.
//!
//! Every controller the firmware hosts (the line juggler's [`Controller`], the link check,
//! the tilt table, the hopper's thrust, the arm's trajectory tracker and the spatial juggler's
//! controller) implements
//! [`FixedRate`], and its command type implements [`Reply`]. The simulator's SIL loop, the
//! host's HIL driver and the firmware's server are written once against these two traits
//! and [`Wire`] (how a controller's types travel on the link): a new controller needs its
//! own parameter, frame and command types and its variants in the protocol's kinds, not a
//! new loop (see [`crate::protocol`], "Adding a controller kind").
//!
//! What every command and the telemetry say whatever the kind ([`Mode`], [`Fault`],
//! [`Telemetry`]) is defined here too, so a controller imports nothing of the protocol.
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
use serde::{Deserialize, Serialize};

/// Length of the controller-defined estimate in [`Telemetry::estimate`]: the main state of
/// each kind (the line juggler's ball height and velocity; a planar body's pose; a hopper's
/// leg length, velocity and phase). Every slot costs 4 bytes in every `Output` frame, on a
/// real UART too, so it is kept small.
pub const ESTIMATE_LEN: usize = 3;

/// What a controller is doing with its actuator.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[repr(u8)]
pub enum Mode {
    /// No valid estimate yet: the actuator is held at its home position.
    #[default]
    Hold = 0,
    /// Tracking the control law.
    Track = 1,
    /// Safe state after a fault: the actuator is braked to rest where it is.
    Safe = 2,
}

/// Why a controller is in its safe state (0 = no fault).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[repr(u8)]
pub enum Fault {
    /// No fault.
    #[default]
    None = 0,
    /// A measurement was NaN or infinite.
    NonFinite = 1,
    /// A measurement was outside its plausible range.
    OutOfRange = 2,
    /// No new sample (the sequence number did not advance) within the stale limit.
    Stale = 3,
    /// No valid frame arrived on the link within its timeout (set by the firmware).
    LinkTimeout = 4,
    /// The control period's work ran past the next tick (set by a board's fixed-rate loop).
    Overrun = 5,
}

/// Status the firmware reports alongside each command, the same for every controller kind.
///
/// The core fills [`estimate`](Self::estimate) and [`estimate_valid`](Self::estimate_valid)
/// ([`FixedRate::telemetry`]); the firmware adds the timing and link counts. What the
/// estimate's slots hold is the controller's to document (the line juggler: ball height,
/// m, and velocity, m/s; unused slots are 0).
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Telemetry {
    /// Instructions (or cycles, on hardware) the last control step took.
    pub step_instructions: u32,
    /// Frames rejected by the firmware's decoder so far (CRC, COBS, decode, overlong).
    pub link_errors: u32,
    /// Frames accepted by the firmware's decoder so far.
    pub frames_ok: u32,
    /// The controller's state estimate, SI units, slots defined by the controller kind.
    pub estimate: [f32; ESTIMATE_LEN],
    /// Whether the estimate is valid.
    pub estimate_valid: bool,
}

impl Telemetry {
    /// Telemetry with the first `values.len()` (at most [`ESTIMATE_LEN`]) estimate slots
    /// set, the rest 0, and no timing or link counts (the core's part).
    pub fn with_estimate(values: &[f32], valid: bool) -> Self {
        let mut estimate = [0.0; ESTIMATE_LEN];
        for (slot, v) in estimate.iter_mut().zip(values) {
            *slot = *v;
        }
        Self {
            estimate,
            estimate_valid: valid,
            ..Self::default()
        }
    }
}

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

/// The longest postcard encoding of a command of any kind, bytes: the stack buffer
/// [`Reply::bit_identical`] encodes into. The largest command (the tilt table's: a varint
/// `u32` of up to 5 bytes, five `f32`s of 4 and three one-byte enums) takes 28;
/// `shared/tests/bit_identical.rs` checks every kind's worst case against it.
pub const MAX_COMMAND_LEN: usize = 32;

/// What every command says about itself, whatever its actuator fields.
pub trait Reply: Copy + Serialize {
    /// Sequence number of the sensor frame this command answers.
    fn seq(&self) -> u32;
    /// The controller's mode when it produced this command.
    fn mode(&self) -> Mode;
    /// The fault code; [`Fault::None`] unless `mode() == Mode::Safe`.
    fn fault(&self) -> Fault;
    /// Whether two commands are identical bit for bit, as the HIL check of firmware against
    /// SIL needs: their postcard encodings (what the link carries; every `f32` as its bits,
    /// so `-0.0` and `0.0`, or two NaN payloads, differ) are the same bytes. Every field
    /// counts, one added later too. No allocation: each is encoded into a
    /// [`MAX_COMMAND_LEN`]-byte stack buffer; a command that does not fit is never
    /// identical (the tests rule that out for every kind).
    fn bit_identical(&self, other: &Self) -> bool {
        let (mut a, mut b) = ([0u8; MAX_COMMAND_LEN], [0u8; MAX_COMMAND_LEN]);
        match (
            postcard::to_slice(self, &mut a),
            postcard::to_slice(other, &mut b),
        ) {
            (Ok(a), Ok(b)) => a == b,
            _ => false,
        }
    }
}

/// Implements [`Reply`] for a command struct that carries the three answers as its fields
/// `seq: u32`, `mode: Mode` and `fault: Fault`, as every command in the core does.
macro_rules! reply_from_fields {
    ($command:ty) => {
        impl $crate::fixed_rate::Reply for $command {
            fn seq(&self) -> u32 {
                self.seq
            }

            fn mode(&self) -> $crate::fixed_rate::Mode {
                self.mode
            }

            fn fault(&self) -> $crate::fixed_rate::Fault {
                self.fault
            }
        }
    };
}
pub(crate) use reply_from_fields;
