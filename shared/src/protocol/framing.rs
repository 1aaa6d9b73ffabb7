//! Framing of one message on a byte link: `COBS(postcard(message) ++ crc32c_le) ++ 0x00`.
//!
//! - [postcard](https://docs.rs/postcard) encodes the message (varint integers, f32 as 4 bytes);
//! - a CRC-32C (Castagnoli, `crc::CRC_32_ISCSI`) of the postcard bytes, little-endian,
//!   detects corruption (any burst up to 32 bits, random errors with p = 2^-32);
//! - COBS removes every zero byte, so `0x00` only ever delimits frames and a receiver that
//!   lost bytes resynchronises at the next delimiter.
//!
//! [`FrameDecoder`] consumes a byte stream one byte at a time with a fixed buffer (COBS is
//! undone as the bytes arrive), returns one decoded message per delimiter, and counts every
//! rejected frame by reason. Encoding and decoding never panic. The framing knows no
//! message and no controller: it frames any `serde` type.

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

pub(super) const CRC32C: Crc<u32> = Crc::<u32>::new(&CRC_32_ISCSI);

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
