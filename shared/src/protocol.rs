//! Wire protocol between the plant (simulator, or a real sensor/actuator front end) and the
//! controller (firmware, or the core linked into the simulator), for every controller kind.
//!
//! ## Framing
//! A frame on the byte link is `COBS(postcard(message) ++ crc32c_le) ++ 0x00`:
//! - [postcard](https://docs.rs/postcard) encodes the message (varint integers, f32 as 4 bytes);
//! - a CRC-32C (Castagnoli, `crc::CRC_32_ISCSI`) of the postcard bytes, little-endian,
//!   detects corruption (any burst up to 32 bits, random errors with p = 2^-32);
//! - COBS removes every zero byte, so `0x00` only ever delimits frames and a receiver that
//!   lost bytes resynchronises at the next delimiter.
//!
//! [`FrameDecoder`] consumes a byte stream one byte at a time with a fixed buffer (COBS is
//! undone as the bytes arrive), returns one decoded message per delimiter, and counts every
//! rejected frame by reason. Encoding and decoding never panic.
//!
//! ## Messages: one set for every controller kind
//! The host sends [`HostMessage::Configure`] with a [`Config`] (which controller, with what
//! parameters), then one [`HostMessage::Sensor`] [`Frame`] per control period, each answered
//! by [`DeviceMessage::Output`] with a [`Command`] and controller-neutral [`Telemetry`].
//! [`Config`], [`Frame`] and [`Command`] have one variant per controller [`Kind`]; the
//! [`Wire`] trait maps a [`FixedRate`] controller to its variants, so the host's HIL driver
//! and the firmware's server are written once for all kinds. A frame of another kind than
//! the configured controller's is answered with [`DeviceMessage::Rejected`]
//! ([`Rejection::WrongKind`]), never a panic.
//!
//! ## Adding a controller kind
//! 1. Implement [`FixedRate`] for it (its params, frame and command types derive
//!    `Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize`, and hold only
//!    fixed-size fields: numbers, bools, fieldless enums, arrays and structs of them — no
//!    `Option`, slices or strings, so every message has one worst-case size).
//! 2. Add one line `Name => path::Controller` at the **end** of the list in the
//!    `controller_kinds!` invocation below (the position is the wire tag: append only). That
//!    line generates the [`Kind`], [`Config`], [`Frame`] and [`Command`] variants and the
//!    controller's [`Wire`] impl.
//! 3. Add `Name(path::Controller)` to the firmware's `hosted!` list (`firmware/src/hosted.rs`).
//!
//! `shared/tests/protocol_props.rs` then checks that every message of the new kind fits
//! [`MAX_PAYLOAD_LEN`] (worst case over every value) and round-trips; the HIL driver
//! (`dexter_sim::hil::LockStep::<path::Controller>`) runs it in QEMU unchanged.

use crate::fixed_rate::FixedRate;
use crc::{Crc, CRC_32_ISCSI};
use serde::{Deserialize, Serialize};

/// The largest postcard payload before CRC and COBS, bytes. Sized for a 48-field f32
/// parameter set (the kappa-tilt table needs ~40) with headroom; every message of every
/// kind is checked against it, worst case over all values, by `shared/tests/protocol_props.rs`.
pub const MAX_PAYLOAD_LEN: usize = 256;
/// Length of the CRC trailer, bytes.
pub const CRC_LEN: usize = 4;
/// The largest encoded frame: COBS of payload and CRC, plus the `0x00` delimiter, bytes.
pub const MAX_FRAME_LEN: usize = cobs::max_encoding_length(MAX_PAYLOAD_LEN + CRC_LEN) + 1;
/// Length of the controller-defined estimate in [`Telemetry::estimate`]: the main state of
/// each kind (the line juggler's ball height and velocity; a planar body's pose; a hopper's
/// leg length, velocity and phase). Every slot costs 4 bytes in every `Output` frame, on a
/// real UART too, so it is kept small.
pub const ESTIMATE_LEN: usize = 3;

const CRC32C: Crc<u32> = Crc::<u32>::new(&CRC_32_ISCSI);

/// One sample of the line juggler's plant, sent to its controller every control period.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct SensorFrame {
    /// Sample sequence number; a controller that sees it not advance counts the input stale.
    pub seq: u32,
    /// Measured ball height above the impact plane, m (NaN if the sensor lost the ball).
    pub ball_height_m: f32,
    /// Measured paddle height, m.
    pub paddle_height_m: f32,
    /// Measured paddle velocity, m/s.
    pub paddle_velocity_mps: f32,
}

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

/// The line juggler's output for one control period.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct ActuatorCommand {
    /// Sequence number of the sensor frame this command answers.
    pub seq: u32,
    /// Commanded paddle acceleration, m/s^2, held for one control period (zero-order hold).
    pub paddle_accel_mps2: f32,
    /// Paddle height reference the command tracks, m (informational).
    pub paddle_height_ref_m: f32,
    /// Paddle velocity reference, m/s (informational).
    pub paddle_velocity_ref_mps: f32,
    /// Mode of operation.
    pub mode: Mode,
    /// Fault code; `Fault::None` unless `mode == Mode::Safe`.
    pub fault: Fault,
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

/// Controller parameters of the line juggler, re-exported where the protocol uses them.
pub use crate::control::ControllerParams;

/// How a [`FixedRate`] controller travels on the wire: its [`Kind`], and the variants of
/// [`Config`], [`Frame`] and [`Command`] that carry its parameters, frames and commands.
///
/// Implemented by the `controller_kinds!` list in this module (one line per kind); see the
/// module documentation for adding a kind.
pub trait Wire: FixedRate {
    /// The controller's kind.
    const KIND: Kind;
    /// The `Configure` payload for `params`.
    fn config(params: Self::Params) -> Config;
    /// This kind's parameters, if `config` is of this kind.
    fn params_of(config: &Config) -> Option<&Self::Params>;
    /// The `Sensor` payload for `frame`.
    fn frame(frame: Self::Frame) -> Frame;
    /// This kind's frame, if `frame` is of this kind.
    fn frame_of(frame: &Frame) -> Option<&Self::Frame>;
    /// The `Output` payload for `command`.
    fn command(command: Self::Command) -> Command;
    /// This kind's command, if `command` is of this kind.
    fn command_of(command: &Command) -> Option<Self::Command>;
}

/// Declares the controller kinds: for each `Name => Controller` line, a [`Kind`] variant,
/// the [`Config`], [`Frame`] and [`Command`] variants carrying `Controller`'s
/// `FixedRate::{Params, Frame, Command}`, and `impl Wire for Controller`. The order of the
/// lines is the wire tag of every variant: append, never reorder. A line
/// `Name if (<cfg predicate>) => Controller` puts its kind's values on the wire only where the predicate holds
/// ([`Kind`] always lists it); such lines come last, so the tags before them never move.
macro_rules! controller_kinds {
    ($($(#[$doc:meta])* $kind:ident $(if ($cfg:meta))? => $controller:ty),+ $(,)?) => {
        /// Which controller a configuration, frame or command is for.
        #[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
        #[cfg_attr(feature = "defmt", derive(defmt::Format))]
        pub enum Kind {
            $($(#[$doc])* $kind,)+
        }

        impl Kind {
            /// Every kind, in wire order.
            pub const ALL: &'static [Kind] = &[$(Kind::$kind),+];
        }

        /// A controller kind and its parameters ([`HostMessage::Configure`]).
        #[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
        pub enum Config {
            $($(#[$doc])* #[cfg(all($($cfg)?))] $kind(<$controller as FixedRate>::Params),)+
        }

        /// One sample of the plant for a controller kind ([`HostMessage::Sensor`]).
        #[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
        pub enum Frame {
            $($(#[$doc])* #[cfg(all($($cfg)?))] $kind(<$controller as FixedRate>::Frame),)+
        }

        /// One control period's output of a controller kind ([`DeviceMessage::Output`]).
        #[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
        pub enum Command {
            $($(#[$doc])* #[cfg(all($($cfg)?))] $kind(<$controller as FixedRate>::Command),)+
        }

        impl Config {
            /// The kind this configuration is for.
            pub fn kind(&self) -> Kind {
                match self { $(#[cfg(all($($cfg)?))] Config::$kind(_) => Kind::$kind,)+ }
            }
            /// The default parameters of `kind` (tests and size checks); `None` for a kind
            /// this build leaves off the wire.
            #[allow(unreachable_patterns)] // every kind on the wire
            pub fn default_for(kind: Kind) -> Option<Config> {
                match kind {
                    $(#[cfg(all($($cfg)?))] Kind::$kind => Some(Config::$kind(Default::default())),)+
                    _ => None,
                }
            }
        }

        impl Frame {
            /// The kind this frame is for.
            pub fn kind(&self) -> Kind {
                match self { $(#[cfg(all($($cfg)?))] Frame::$kind(_) => Kind::$kind,)+ }
            }
            /// A default (all-zero) frame of `kind` (tests and size checks); `None` for a kind
            /// this build leaves off the wire.
            #[allow(unreachable_patterns)] // every kind on the wire
            pub fn default_for(kind: Kind) -> Option<Frame> {
                match kind {
                    $(#[cfg(all($($cfg)?))] Kind::$kind => Some(Frame::$kind(Default::default())),)+
                    _ => None,
                }
            }
        }

        impl Command {
            /// The kind this command is from.
            pub fn kind(&self) -> Kind {
                match self { $(#[cfg(all($($cfg)?))] Command::$kind(_) => Kind::$kind,)+ }
            }
            /// A default command of `kind` (tests and size checks); `None` for a kind this
            /// build leaves off the wire.
            #[allow(unreachable_patterns)] // every kind on the wire
            pub fn default_for(kind: Kind) -> Option<Command> {
                match kind {
                    $(#[cfg(all($($cfg)?))] Kind::$kind => Some(Command::$kind(Default::default())),)+
                    _ => None,
                }
            }
            /// The command's sequence number, mode and fault, whatever its kind.
            pub fn reply(&self) -> (u32, Mode, Fault) {
                use crate::fixed_rate::Reply;
                match self { $(#[cfg(all($($cfg)?))] Command::$kind(c) => (c.seq(), c.mode(), c.fault()),)+ }
            }
        }

        $(
            #[allow(unreachable_patterns)] // a build with a single kind
            #[cfg(all($($cfg)?))]
            impl Wire for $controller {
                const KIND: Kind = Kind::$kind;
                fn config(params: Self::Params) -> Config {
                    Config::$kind(params)
                }
                fn params_of(config: &Config) -> Option<&Self::Params> {
                    match config { Config::$kind(p) => Some(p), _ => None }
                }
                fn frame(frame: Self::Frame) -> Frame {
                    Frame::$kind(frame)
                }
                fn frame_of(frame: &Frame) -> Option<&Self::Frame> {
                    match frame { Frame::$kind(f) => Some(f), _ => None }
                }
                fn command(command: Self::Command) -> Command {
                    Command::$kind(command)
                }
                fn command_of(command: &Command) -> Option<Self::Command> {
                    match command { Command::$kind(c) => Some(*c), _ => None }
                }
            }
        )+
    };
}

controller_kinds! {
    /// The line juggler: mirror law, estimator and paddle tracker ([`crate::control::Controller`]).
    Line => crate::control::Controller,
    /// The link check: echoes a scaled value, no actuator ([`crate::echo::Echo`]).
    Echo => crate::echo::Echo,
    /// The kappa-tilt table with energy feedback ([`crate::tilt_control::TiltController`]).
    Tilt => crate::tilt_control::TiltController,
    /// The hopper's thrust valve ([`crate::hop_control::HopController`]).
    Hop => crate::hop_control::HopController,
    /// The one-joint arm: a planned B-spline tracked with torque limits ([`crate::arm_control::ArmController`]).
    /// Its parameters, frames and commands are on the wire of every host build, and of a
    /// bare-metal build only with the feature `wire-arm` (a firmware image that hosts the
    /// arm): the wire tags of the kinds before it do not depend on it, and an image without
    /// it still names the kind (`Rejection::NotHosted(Kind::Arm)`), with no code for it.
    Arm if (any(not(target_os = "none"), feature = "wire-arm")) => crate::arm_control::ArmController,
}

/// A message from the plant side (host) to the controller (firmware).
pub type HostMessage = HostMessageOf<Config, Frame>;

/// [`HostMessage`] with the types `Configure` and `Sensor` carry as parameters. The wire
/// form is the same for any `C`, `F` whose postcard forms are [`Config`]'s and [`Frame`]'s:
/// a firmware image decodes `HostMessageOf<Partial<P>, Partial<F>>`, which decodes the
/// parameters and frames of the kinds it hosts only ([`Partial`]), so a kind it leaves out
/// costs it no decoder.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub enum HostMessageOf<C, F> {
    /// (Re)configure the controller; answered with [`DeviceMessage::Configured`].
    Configure(C),
    /// A sensor sample; answered with [`DeviceMessage::Output`] (or
    /// [`DeviceMessage::Rejected`] if no controller of its kind is configured).
    Sensor(F),
    /// Ask the firmware to end the run: it answers [`DeviceMessage::Stopped`] and exits the
    /// emulator with success.
    Stop,
}

/// The hosted part of a kind-indexed enum ([`Config`] or [`Frame`]) of a firmware image:
/// one variant per kind it hosts, in any order, decoded by [`Partial`].
pub trait HostedKinds: Sized {
    /// The kind of this value.
    fn kind(&self) -> Kind;
    /// If `kind` is hosted, its value decoded from `body` (`Ok(Ok(..))`, or the decoder's
    /// error); else `body` handed back undecoded (`Ok(Err(body))`).
    fn decode<'de, A: serde::de::VariantAccess<'de>>(
        kind: Kind,
        body: A,
    ) -> Result<Result<Self, A>, A::Error>;
}

/// A [`Config`] or [`Frame`] as an image that hosts the kinds of `T` decodes it: the value
/// of a hosted kind, or only the kind of one it does not host (the rest of the message
/// skipped undecoded, so the image holds no decoder for it).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Partial<T> {
    /// A hosted kind's value.
    Hosted(T),
    /// A kind this image does not host.
    NotHosted(Kind),
}

impl<T: HostedKinds> Partial<T> {
    /// The kind named on the wire, hosted or not.
    pub fn kind(&self) -> Kind {
        match self {
            Partial::Hosted(t) => t.kind(),
            Partial::NotHosted(kind) => *kind,
        }
    }
}

impl<'de, T: HostedKinds> Deserialize<'de> for Partial<T> {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        d.deserialize_enum("Partial", &[], PartialVisitor(core::marker::PhantomData))
    }
}

struct PartialVisitor<T>(core::marker::PhantomData<T>);

impl<'de, T: HostedKinds> serde::de::Visitor<'de> for PartialVisitor<T> {
    type Value = Partial<T>;

    fn expecting(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.write_str("a controller kind and its value")
    }

    fn visit_enum<A: serde::de::EnumAccess<'de>>(self, data: A) -> Result<Self::Value, A::Error> {
        use serde::de::{Error, Unexpected, VariantAccess};
        let (index, body) = data.variant::<u32>()?;
        let kind = Kind::ALL
            .get(index as usize)
            .copied()
            .ok_or_else(|| A::Error::invalid_value(Unexpected::Unsigned(index.into()), &self))?;
        match T::decode(kind, body)? {
            Ok(value) => Ok(Partial::Hosted(value)),
            Err(body) => body
                .newtype_variant_seed(SkipRest)
                .map(|()| Partial::NotHosted(kind)),
        }
    }
}

/// Consumes the rest of a postcard message as single bytes (the undecoded parameters of
/// a kind not hosted are the message's last field: `Configure`'s or `Sensor`'s), so the decode ends at its end.
struct SkipRest;

impl<'de> serde::de::DeserializeSeed<'de> for SkipRest {
    type Value = ();
    fn deserialize<D: serde::Deserializer<'de>>(self, d: D) -> Result<(), D::Error> {
        d.deserialize_tuple(MAX_PAYLOAD_LEN, SkipRest)
    }
}

impl<'de> serde::de::Visitor<'de> for SkipRest {
    type Value = ();

    fn expecting(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.write_str("the rest of the message")
    }

    fn visit_seq<A: serde::de::SeqAccess<'de>>(self, mut seq: A) -> Result<(), A::Error> {
        // postcard reads a byte per element and reports the end of the input as an error
        // without moving: the loop stops there, with every byte consumed.
        while let Ok(Some(_)) = seq.next_element::<u8>() {}
        Ok(())
    }
}

/// Why the firmware refused to step a frame (a protocol error of the host, or a firmware
/// that does not host the kind).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Rejection {
    /// A sensor frame arrived before any accepted `Configure`.
    NotConfigured,
    /// A sensor frame's kind is not the configured controller's.
    WrongKind {
        /// The configured controller's kind.
        configured: Kind,
        /// The frame's kind.
        received: Kind,
    },
    /// `Configure` named a kind this firmware image does not host.
    NotHosted(Kind),
    /// A frame was rejected by the link while no controller was configured (so there is no
    /// safe command to answer with), e.g. a `Configure` this firmware cannot decode.
    Undecodable(DecodeError),
}

/// What the firmware reports when the host stops the run.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct RunSummary {
    /// Control steps run (saturating).
    pub steps: u32,
    /// Safe commands sent because of a link timeout (saturating).
    pub link_timeouts: u32,
    /// Stack high-water mark since reset, bytes (painted stack, see `firmware/src/stack.rs`).
    pub stack_used_bytes: u32,
    /// Stack reserved in memory.x, bytes.
    pub stack_size_bytes: u32,
}

/// A message from the controller (firmware) to the plant side (host).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub enum DeviceMessage {
    /// Answer to `Configure`.
    Configured {
        /// The kind that was configured (or rejected).
        kind: Kind,
        /// True if the parameters were accepted.
        ok: bool,
    },
    /// The command for one sensor frame, with telemetry.
    Output {
        /// The controller's command.
        command: Command,
        /// Status of the firmware.
        telemetry: Telemetry,
    },
    /// The frame was not stepped; see [`Rejection`].
    Rejected(Rejection),
    /// Answer to `Stop`, sent just before the firmware ends the run.
    Stopped(RunSummary),
}

/// Why a frame could not be encoded.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[non_exhaustive]
pub enum EncodeError {
    /// The message's postcard encoding is longer than [`MAX_PAYLOAD_LEN`], or the output
    /// buffer is too small for the frame.
    BufferTooSmall,
}

/// Why a received frame was rejected.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[non_exhaustive]
pub enum DecodeError {
    /// The frame is longer than the decoder's buffer; its bytes were discarded.
    Overlong,
    /// The bytes between two delimiters are not valid COBS.
    Cobs,
    /// The frame is shorter than its CRC trailer.
    TooShort,
    /// The CRC does not match: the frame was corrupted.
    Crc,
    /// The CRC matched but the payload is not a valid message.
    Payload,
}

impl core::fmt::Display for DecodeError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.write_str(match self {
            DecodeError::Overlong => "frame longer than the maximum",
            DecodeError::Cobs => "invalid COBS encoding",
            DecodeError::TooShort => "frame shorter than its CRC",
            DecodeError::Crc => "CRC mismatch",
            DecodeError::Payload => "payload is not a valid message",
        })
    }
}

/// Encode `message` as one delimited frame into `out`; returns the number of bytes written
/// (including the trailing `0x00`). Never panics.
pub fn encode<T: Serialize>(message: &T, out: &mut [u8]) -> Result<usize, EncodeError> {
    let mut raw = [0u8; MAX_PAYLOAD_LEN + CRC_LEN];
    let (payload_area, _) = raw
        .split_first_chunk_mut::<MAX_PAYLOAD_LEN>()
        .ok_or(EncodeError::BufferTooSmall)?;
    let n = postcard::to_slice(message, payload_area)
        .map_err(|_| EncodeError::BufferTooSmall)?
        .len();
    let (payload, rest) = raw
        .split_at_mut_checked(n)
        .ok_or(EncodeError::BufferTooSmall)?;
    let crc = CRC32C.checksum(payload).to_le_bytes();
    let trailer = rest
        .first_chunk_mut::<CRC_LEN>()
        .ok_or(EncodeError::BufferTooSmall)?;
    *trailer = crc;
    let raw = raw.get(..n + CRC_LEN).ok_or(EncodeError::BufferTooSmall)?;
    let len = cobs::try_encode(raw, out).map_err(|_| EncodeError::BufferTooSmall)?;
    *out.get_mut(len).ok_or(EncodeError::BufferTooSmall)? = 0;
    Ok(len + 1)
}

/// Decode one frame's bytes (between delimiters, without the `0x00`); `frame` is used as
/// scratch space for the in-place COBS decode. Never panics.
pub fn decode<'de, T: Deserialize<'de>>(frame: &'de mut [u8]) -> Result<T, DecodeError> {
    let n = cobs::decode_in_place(frame).map_err(|_| DecodeError::Cobs)?;
    decode_payload(frame.get(..n).ok_or(DecodeError::Cobs)?)
}

/// Check the CRC trailer of a COBS-decoded frame and decode the message before it.
fn decode_payload<'de, T: Deserialize<'de>>(decoded: &'de [u8]) -> Result<T, DecodeError> {
    let (payload, trailer) = decoded
        .split_last_chunk::<CRC_LEN>()
        .ok_or(DecodeError::TooShort)?;
    if CRC32C.checksum(payload) != u32::from_le_bytes(*trailer) {
        return Err(DecodeError::Crc);
    }
    // Trailing bytes after a valid message mean the frame is not what the sender encoded.
    match postcard::take_from_bytes::<T>(payload) {
        Ok((value, [])) => Ok(value),
        _ => Err(DecodeError::Payload),
    }
}

/// Counts of frames accepted and rejected by a [`FrameDecoder`].
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct LinkStats {
    /// Frames decoded successfully.
    pub frames_ok: u32,
    /// Frames rejected for being overlong.
    pub overlong: u32,
    /// Frames rejected for invalid COBS or being shorter than a CRC.
    pub framing: u32,
    /// Frames rejected by the CRC.
    pub crc: u32,
    /// Frames whose CRC matched but whose payload did not decode.
    pub payload: u32,
}

impl LinkStats {
    /// All rejected frames, saturating.
    pub fn errors(&self) -> u32 {
        self.overlong
            .saturating_add(self.framing)
            .saturating_add(self.crc)
            .saturating_add(self.payload)
    }

    fn count(&mut self, result: Result<(), DecodeError>) {
        let slot = match result {
            Ok(()) => &mut self.frames_ok,
            Err(DecodeError::Overlong) => &mut self.overlong,
            Err(DecodeError::Cobs | DecodeError::TooShort) => &mut self.framing,
            Err(DecodeError::Crc) => &mut self.crc,
            Err(DecodeError::Payload) => &mut self.payload,
        };
        *slot = slot.saturating_add(1);
    }
}

/// Streaming frame decoder with a fixed buffer: feed it bytes as they arrive. A frame of
/// more than `N` encoded bytes (delimiter excluded) is rejected as overlong.
///
/// COBS is undone byte by byte as the frame arrives (`cobs::DecoderState`), so the
/// delimiter only has to check the CRC and decode the payload. Empty frames (two
/// delimiters in a row) are ignored, which lets a sender flush a receiver's partial frame
/// by sending a lone `0x00`. After an overlong frame the decoder discards bytes up to the
/// next delimiter, then resumes.
#[derive(Debug)]
pub struct FrameDecoder<const N: usize = MAX_FRAME_LEN> {
    buf: [u8; N],
    /// Decoded bytes in `buf`.
    decoded: usize,
    /// Encoded bytes of the current frame so far (saturating).
    encoded: usize,
    cobs: cobs::DecoderState,
    stats: LinkStats,
}

impl<const N: usize> Default for FrameDecoder<N> {
    fn default() -> Self {
        Self::new()
    }
}

impl<const N: usize> FrameDecoder<N> {
    /// An empty decoder.
    pub const fn new() -> Self {
        Self {
            buf: [0; N],
            decoded: 0,
            encoded: 0,
            cobs: cobs::DecoderState::Idle,
            stats: LinkStats {
                frames_ok: 0,
                overlong: 0,
                framing: 0,
                crc: 0,
                payload: 0,
            },
        }
    }

    /// Counts of accepted and rejected frames so far.
    pub fn stats(&self) -> LinkStats {
        self.stats
    }

    /// Feed one byte. Returns `Some` when `byte` completes a non-empty frame: the decoded
    /// message or why it was rejected (already counted in [`stats`](Self::stats)).
    pub fn push<T>(&mut self, byte: u8) -> Option<Result<T, DecodeError>>
    where
        T: for<'de> Deserialize<'de>,
    {
        if byte != 0 {
            self.encoded = self.encoded.saturating_add(1);
            if self.encoded <= N {
                if let Ok(cobs::DecodeResult::DataContinue(b)) = self.cobs.feed(byte) {
                    if let Some(slot) = self.buf.get_mut(self.decoded) {
                        *slot = b;
                        self.decoded += 1;
                    }
                }
            }
            return None;
        }
        let (encoded, decoded) = (self.encoded, self.decoded);
        let complete = matches!(self.cobs.feed(0), Ok(cobs::DecodeResult::DataComplete));
        self.cobs = cobs::DecoderState::Idle;
        self.encoded = 0;
        self.decoded = 0;
        let result = if encoded == 0 {
            return None;
        } else if encoded > N {
            Err(DecodeError::Overlong)
        } else if !complete {
            Err(DecodeError::Cobs)
        } else {
            self.buf
                .get(..decoded)
                .ok_or(DecodeError::Cobs)
                .and_then(decode_payload::<T>)
        };
        self.stats
            .count(result.as_ref().map(|_| ()).map_err(|e| *e));
        Some(result)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn frame() -> SensorFrame {
        SensorFrame {
            seq: 7,
            ball_height_m: 0.5,
            paddle_height_m: -0.02,
            paddle_velocity_mps: 0.25,
        }
    }

    fn sensor() -> HostMessage {
        HostMessage::Sensor(Frame::Line(frame()))
    }

    #[test]
    fn max_frame_len_covers_the_largest_payload_with_crc_cobs_and_delimiter() {
        // COBS adds one byte per started 254-byte block: 260 bytes need 2, plus the 0x00.
        assert_eq!(MAX_FRAME_LEN, MAX_PAYLOAD_LEN + CRC_LEN + 2 + 1);
    }

    #[test]
    fn round_trip_through_stream_decoder() {
        let msg = sensor();
        let mut out = [0u8; MAX_FRAME_LEN];
        let n = encode(&msg, &mut out).unwrap();
        assert_eq!(out[n - 1], 0);
        assert!(out[..n - 1].iter().all(|&b| b != 0));
        let mut dec = FrameDecoder::<MAX_FRAME_LEN>::new();
        let mut got = None;
        for &b in &out[..n] {
            if let Some(r) = dec.push::<HostMessage>(b) {
                got = Some(r);
            }
        }
        assert_eq!(got, Some(Ok(msg)));
        assert_eq!(dec.stats().frames_ok, 1);
    }

    #[test]
    fn flipped_bit_is_rejected_and_next_frame_resyncs() {
        let msg = sensor();
        let mut out = [0u8; MAX_FRAME_LEN];
        let n = encode(&msg, &mut out).unwrap();
        let mut bad = out;
        bad[3] ^= 0x10;
        let mut dec = FrameDecoder::<MAX_FRAME_LEN>::new();
        let mut results = heapless::Vec::<_, 4>::new();
        for &b in bad[..n].iter().chain(out[..n].iter()) {
            if let Some(r) = dec.push::<HostMessage>(b) {
                results.push(r).unwrap();
            }
        }
        assert_eq!(results.len(), 2);
        assert!(results[0].is_err());
        assert_eq!(results[1], Ok(msg));
        assert_eq!(dec.stats().errors(), 1);
    }

    #[test]
    fn overlong_garbage_is_counted_once_then_decoding_resumes() {
        let mut dec = FrameDecoder::<16>::new();
        for _ in 0..40 {
            assert!(dec.push::<HostMessage>(0x55).is_none());
        }
        assert_eq!(dec.push::<HostMessage>(0), Some(Err(DecodeError::Overlong)));
        let mut out = [0u8; MAX_FRAME_LEN];
        let n = encode(&HostMessage::Stop, &mut out).unwrap();
        let mut last = None;
        for &b in &out[..n] {
            last = dec.push::<HostMessage>(b).or(last);
        }
        assert_eq!(last, Some(Ok(HostMessage::Stop)));
        assert_eq!(dec.stats().overlong, 1);
    }

    #[test]
    fn a_frame_of_exactly_n_encoded_bytes_is_accepted_and_n_plus_one_is_overlong() {
        let mut out = [0u8; MAX_FRAME_LEN];
        let n = encode(&sensor(), &mut out).unwrap();
        let body = n - 1; // encoded bytes without the delimiter
        let mut exact = FrameDecoder::<64>::new();
        assert!(body < 64);
        let feed = |dec: &mut FrameDecoder<64>, bytes: &[u8]| {
            bytes
                .iter()
                .fold(None, |last, &b| dec.push::<HostMessage>(b).or(last))
        };
        assert_eq!(feed(&mut exact, &out[..n]), Some(Ok(sensor())));
        // the same frame into a decoder one byte too small
        let mut small = FrameDecoder::<8>::new();
        let r = out[..n]
            .iter()
            .fold(None, |last, &b| small.push::<HostMessage>(b).or(last));
        assert_eq!(r, Some(Err(DecodeError::Overlong)));
    }

    #[test]
    fn wire_maps_each_kind_to_its_own_variants_only() {
        use crate::control::Controller;
        use crate::echo::{Echo, EchoFrame};
        let line = <Controller as Wire>::frame(frame());
        assert_eq!(line.kind(), Kind::Line);
        assert_eq!(<Controller as Wire>::frame_of(&line), Some(&frame()));
        assert_eq!(<Echo as Wire>::frame_of(&line), None);
        let echo = <Echo as Wire>::frame(EchoFrame { seq: 1, value: 2.0 });
        assert_eq!(echo.kind(), Kind::Echo);
        assert_eq!(<Controller as Wire>::frame_of(&echo), None);
        let cmd = Command::default_for(Kind::Echo).unwrap();
        assert_eq!(<Controller as Wire>::command_of(&cmd), None);
        assert!(<Echo as Wire>::command_of(&cmd).is_some());
        let config = Config::default_for(Kind::Line).unwrap();
        assert!(<Controller as Wire>::params_of(&config).is_some());
        assert!(<Echo as Wire>::params_of(&config).is_none());
        assert_eq!(
            Kind::ALL,
            &[Kind::Line, Kind::Echo, Kind::Tilt, Kind::Hop, Kind::Arm]
        );
    }

    /// An image that hosts the line juggler and the arm only (as a firmware image's
    /// `HostedKinds` would be generated).
    #[derive(Debug, PartialEq)]
    enum LineAndArm {
        Line(<crate::control::Controller as FixedRate>::Params),
        Arm(<crate::arm_control::ArmController as FixedRate>::Params),
    }

    impl HostedKinds for LineAndArm {
        fn kind(&self) -> Kind {
            match self {
                LineAndArm::Line(_) => Kind::Line,
                LineAndArm::Arm(_) => Kind::Arm,
            }
        }
        fn decode<'de, A: serde::de::VariantAccess<'de>>(
            kind: Kind,
            body: A,
        ) -> Result<Result<Self, A>, A::Error> {
            Ok(match kind {
                Kind::Line => Ok(LineAndArm::Line(body.newtype_variant()?)),
                Kind::Arm => Ok(LineAndArm::Arm(body.newtype_variant()?)),
                _ => Err(body),
            })
        }
    }

    /// A host message as the line-and-arm image decodes it.
    type Decoded = HostMessageOf<Partial<LineAndArm>, Partial<EchoOnly>>;

    /// Frames of an image that hosts the link check only.
    #[derive(Debug, PartialEq)]
    struct EchoOnly(crate::echo::EchoFrame);

    impl HostedKinds for EchoOnly {
        fn kind(&self) -> Kind {
            Kind::Echo
        }
        fn decode<'de, A: serde::de::VariantAccess<'de>>(
            kind: Kind,
            body: A,
        ) -> Result<Result<Self, A>, A::Error> {
            Ok(match kind {
                Kind::Echo => Ok(EchoOnly(body.newtype_variant()?)),
                _ => Err(body),
            })
        }
    }

    /// Every host message through the encoder and a partial image's decoder.
    fn partial(message: &HostMessage) -> Result<Decoded, DecodeError> {
        let mut out = [0u8; MAX_FRAME_LEN];
        let n = encode(message, &mut out).unwrap();
        let mut dec = FrameDecoder::<MAX_FRAME_LEN>::new();
        out[..n]
            .iter()
            .fold(None, |last, &b| dec.push(b).or(last))
            .expect("one frame")
    }

    #[test]
    fn an_image_decodes_the_parameters_of_its_kinds_and_only_the_kind_of_the_others() {
        let mut arm = <crate::arm_control::ArmController as FixedRate>::Params::default();
        arm.trajectory.points_rad[3] = -0.25;
        let line = <crate::control::Controller as FixedRate>::Params::default();
        for kind in Kind::ALL.iter().copied() {
            let config = match kind {
                Kind::Arm => Config::Arm(arm),
                _ => Config::default_for(kind).unwrap(),
            };
            let expected = match config {
                Config::Line(p) => Partial::Hosted(LineAndArm::Line(p)),
                Config::Arm(p) => Partial::Hosted(LineAndArm::Arm(p)),
                _ => Partial::NotHosted(kind),
            };
            let got = partial(&HostMessage::Configure(config));
            assert_eq!(got, Ok(HostMessageOf::Configure(expected)), "{kind:?}");
        }
        assert!(matches!(
            partial(&HostMessage::Configure(Config::Line(line))),
            Ok(HostMessageOf::Configure(Partial::Hosted(LineAndArm::Line(p)))) if p == line
        ));
        assert_eq!(
            partial(&sensor()),
            Ok(HostMessageOf::Sensor(Partial::NotHosted(Kind::Line)))
        );
        let echo = crate::echo::EchoFrame {
            seq: 3,
            value: -1.5,
        };
        assert_eq!(
            partial(&HostMessage::Sensor(Frame::Echo(echo))),
            Ok(HostMessageOf::Sensor(Partial::Hosted(EchoOnly(echo))))
        );
        assert_eq!(partial(&HostMessage::Stop), Ok(HostMessageOf::Stop));
    }

    #[test]
    fn a_kind_index_past_the_list_is_a_payload_error() {
        // Configure (0), kind index = the number of kinds, no parameters; CRC appended.
        let payload = [0u8, Kind::ALL.len() as u8];
        let mut raw = [0u8; 6];
        raw[..2].copy_from_slice(&payload);
        raw[2..].copy_from_slice(&CRC32C.checksum(&payload).to_le_bytes());
        let mut out = [0u8; 16];
        let n = cobs::try_encode(&raw, &mut out).unwrap();
        assert_eq!(decode::<Decoded>(&mut out[..n]), Err(DecodeError::Payload));
    }
}
