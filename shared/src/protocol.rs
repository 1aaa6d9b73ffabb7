//! Wire protocol between the plant (simulator, or a real sensor/actuator front end) and the
//! controller (firmware, or the core linked into the simulator).
//!
//! A frame on the byte link is `COBS(postcard(message) ++ crc32c_le) ++ 0x00`:
//! - [postcard](https://docs.rs/postcard) encodes the message (varint integers, f32 as 4 bytes);
//! - a CRC-32C (Castagnoli, `crc::CRC_32_ISCSI`) of the postcard bytes, little-endian,
//!   detects corruption (any burst up to 32 bits, random errors with p = 2^-32);
//! - COBS removes every zero byte, so `0x00` only ever delimits frames and a receiver that
//!   lost bytes resynchronises at the next delimiter.
//!
//! [`FrameDecoder`] consumes a byte stream one byte at a time with a fixed buffer, returns
//! one decoded message per delimiter, and counts every rejected frame by reason.

use crc::{Crc, CRC_32_ISCSI};
use serde::{Deserialize, Serialize};

/// The largest encoded frame (COBS overhead and delimiter included), bytes.
pub const MAX_FRAME_LEN: usize = 128;
/// The largest postcard payload before CRC and COBS, bytes.
pub const MAX_PAYLOAD_LEN: usize = MAX_FRAME_LEN - 8;
/// Length of the CRC trailer, bytes.
pub const CRC_LEN: usize = 4;

const CRC32C: Crc<u32> = Crc::<u32>::new(&CRC_32_ISCSI);

/// One sample of the plant, sent to the controller every control period.
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

/// What the controller is doing with the paddle.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[repr(u8)]
pub enum Mode {
    /// No valid ball estimate yet: the paddle is held at its home height.
    #[default]
    Hold = 0,
    /// Tracking the mirror law.
    Track = 1,
    /// Safe state after a fault: the paddle is braked to rest where it is.
    Safe = 2,
}

/// Why the controller is in its safe state (0 = no fault).
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
}

/// The controller's output for one control period.
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

/// Status the firmware reports alongside each command.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Telemetry {
    /// Instructions (or cycles, on hardware) the last control step took.
    pub step_instructions: u32,
    /// Frames rejected by the link so far (CRC, COBS, decode, overlong).
    pub link_errors: u32,
    /// Frames accepted by the link so far.
    pub frames_ok: u32,
    /// Estimated ball height, m.
    pub ball_height_est_m: f32,
    /// Estimated ball velocity, m/s.
    pub ball_velocity_est_mps: f32,
    /// Whether the estimate is valid.
    pub estimate_valid: bool,
}

/// Controller parameters sent by the host to configure the firmware before a run; the same
/// values build the SIL controller. See [`crate::control::ControllerParams`].
pub use crate::control::ControllerParams;

/// A message from the plant side (host) to the controller (firmware).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum HostMessage {
    /// (Re)configure the controller; answered with [`DeviceMessage::Configured`].
    Configure(ControllerParams),
    /// A sensor sample; answered with [`DeviceMessage::Output`].
    Sensor(SensorFrame),
    /// Ask the firmware to end the run (it exits the emulator with success).
    Stop,
}

/// A message from the controller (firmware) to the plant side (host).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum DeviceMessage {
    /// Configuration result: `Ok` or the rejected parameter's error code.
    Configured {
        /// True if the parameters were accepted.
        ok: bool,
    },
    /// The command for one sensor frame, with telemetry.
    Output {
        /// The actuator command.
        command: ActuatorCommand,
        /// Status of the firmware.
        telemetry: Telemetry,
    },
}

/// Why a frame could not be encoded.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[non_exhaustive]
pub enum EncodeError {
    /// The output buffer is too small for the frame.
    BufferTooSmall,
}

/// Why a received frame was rejected.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[non_exhaustive]
pub enum DecodeError {
    /// The frame is longer than [`MAX_FRAME_LEN`]; its bytes were discarded.
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
/// (including the trailing `0x00`).
pub fn encode<T: Serialize>(message: &T, out: &mut [u8]) -> Result<usize, EncodeError> {
    let mut raw = [0u8; MAX_PAYLOAD_LEN + CRC_LEN];
    let n = postcard::to_slice(message, &mut raw[..MAX_PAYLOAD_LEN])
        .map_err(|_| EncodeError::BufferTooSmall)?
        .len();
    let crc = CRC32C.checksum(&raw[..n]);
    raw[n..n + CRC_LEN].copy_from_slice(&crc.to_le_bytes());
    let raw = &raw[..n + CRC_LEN];
    if out.len() < cobs::max_encoding_length(raw.len()) + 1 {
        return Err(EncodeError::BufferTooSmall);
    }
    let len = cobs::encode(raw, out);
    out[len] = 0;
    Ok(len + 1)
}

/// Decode one frame's bytes (between delimiters, without the `0x00`); `frame` is used as
/// scratch space for the in-place COBS decode.
pub fn decode<'de, T: Deserialize<'de>>(frame: &'de mut [u8]) -> Result<T, DecodeError> {
    let n = cobs::decode_in_place(frame).map_err(|_| DecodeError::Cobs)?;
    if n < CRC_LEN {
        return Err(DecodeError::TooShort);
    }
    let (payload, trailer) = frame[..n].split_at(n - CRC_LEN);
    let mut crc_bytes = [0u8; CRC_LEN];
    crc_bytes.copy_from_slice(trailer);
    if CRC32C.checksum(payload) != u32::from_le_bytes(crc_bytes) {
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

/// Streaming frame decoder with a fixed `N`-byte buffer: feed it bytes as they arrive.
///
/// Empty frames (two delimiters in a row) are ignored, which lets a sender flush a
/// receiver's partial frame by sending a lone `0x00`. After an overlong frame the decoder
/// discards bytes up to the next delimiter, then resumes.
#[derive(Debug)]
pub struct FrameDecoder<const N: usize = MAX_FRAME_LEN> {
    buf: [u8; N],
    len: usize,
    overflowed: bool,
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
            len: 0,
            overflowed: false,
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
            if self.len < N {
                self.buf[self.len] = byte;
                self.len += 1;
            } else {
                self.overflowed = true;
            }
            return None;
        }
        let (len, overflowed) = (self.len, self.overflowed);
        self.len = 0;
        self.overflowed = false;
        let result = if overflowed {
            Err(DecodeError::Overlong)
        } else if len == 0 {
            return None;
        } else {
            decode::<T>(&mut self.buf[..len])
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

    #[test]
    fn round_trip_through_stream_decoder() {
        let msg = HostMessage::Sensor(frame());
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
        let msg = HostMessage::Sensor(frame());
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
}
