//! Framing of one message on a byte link: `COBS(postcard(message) ++ crc32c_le) ++ 0x00`.
//!
//! - [postcard](https://docs.rs/postcard) encodes the message (varint integers, f32 as 4 bytes);
//! - a CRC-32C (Castagnoli, `crc::CRC_32_ISCSI`) of the postcard bytes, little-endian,
//!   detects corruption (any burst up to 32 bits, random errors with p = 2^-32);
//! - COBS removes every zero byte, so `0x00` only ever delimits frames and a receiver that
//!   lost bytes resynchronises at the next delimiter.
//!
//! [`FrameDecoder`] consumes a byte stream a byte or a chunk at a time with a fixed buffer
//! (COBS is undone in place at the delimiter), returns one decoded message per delimiter,
//! and counts every rejected frame by reason. Encoding and decoding never panic. The framing knows no
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
///
/// postcard writes the payload straight into `out` after the room COBS needs for its first
/// code byte; the CRC is appended behind it and COBS done in place
/// (`cobs_encode_in_place`), so the message is written once and never copied (the `cobs`
/// crate's encoder is the fallback for a payload it cannot encode in place).
pub fn encode<T: Serialize>(message: &T, out: &mut [u8]) -> Result<usize, EncodeError> {
    let area_end = out.len().min(1 + MAX_PAYLOAD_LEN);
    let area = out
        .get_mut(1..area_end)
        .ok_or(EncodeError::BufferTooSmall)?;
    let n = postcard::to_slice(message, area)
        .map_err(|_| EncodeError::BufferTooSmall)?
        .len();
    finish_frame(out, n)
}

/// The CRC, COBS and delimiter of a frame whose `n`-byte payload is in `out[1..=n]`.
#[inline(never)] // compiled once, in the core, with its speed-optimised profile (Cargo.toml)
fn finish_frame(out: &mut [u8], n: usize) -> Result<usize, EncodeError> {
    let raw_len = n + CRC_LEN;
    let (payload, rest) = out
        .get_mut(1..)
        .and_then(|raw| raw.split_at_mut_checked(n))
        .ok_or(EncodeError::BufferTooSmall)?;
    let crc = crc32c(payload).to_le_bytes();
    *rest
        .first_chunk_mut::<CRC_LEN>()
        .ok_or(EncodeError::BufferTooSmall)? = crc;
    if let Some(len) = cobs_encode_in_place(out, raw_len) {
        return Ok(len);
    }
    // A block of 254 non-zero bytes needs a code byte inside the payload: encode a copy.
    let mut raw = [0u8; MAX_PAYLOAD_LEN + CRC_LEN];
    let copy = raw.get_mut(..raw_len).ok_or(EncodeError::BufferTooSmall)?;
    copy.copy_from_slice(out.get(1..=raw_len).ok_or(EncodeError::BufferTooSmall)?);
    let len = cobs::try_encode(copy, out).map_err(|_| EncodeError::BufferTooSmall)?;
    *out.get_mut(len).ok_or(EncodeError::BufferTooSmall)? = 0;
    Ok(len + 1)
}

/// COBS-encode the `len` raw bytes in `out[1..=len]` in place, with the `0x00` delimiter
/// behind them: each zero becomes the distance to the next one (or to the delimiter), and
/// `out[0]` the distance to the first. Returns the frame's length, delimiter included, or
/// `None` (and `out` half encoded) if a block of 254 non-zero bytes would need a code byte
/// inserted, or `out` cannot hold the delimiter. Byte for byte the `cobs` crate's encoding
/// wherever it returns `Some` (`protocol/tests.rs`).
///
/// The zeros are found a word at a time: a frame's bytes are mostly not zero.
pub(super) fn cobs_encode_in_place(out: &mut [u8], len: usize) -> Option<usize> {
    /// The largest code that is followed by a zero (`0xFF` is not).
    const MAX_DISTANCE: usize = 0xFE;
    let end = len.checked_add(1)?;
    let frame = out.get_mut(..=end)?;
    // Where the current block's code byte goes (a zero of the raw bytes, or `out[0]`).
    let mut code_at = 0;
    let mut mark = |frame: &mut [u8], zero_at: usize| -> Option<()> {
        let distance = zero_at - code_at;
        if distance > MAX_DISTANCE {
            return None;
        }
        *frame.get_mut(code_at)? = distance as u8;
        code_at = zero_at;
        Some(())
    };
    let mut at = 1;
    while at + 4 <= end {
        let w = u32::from_le_bytes(*frame.get(at..)?.first_chunk::<4>()?);
        // The high bit of each zero byte of `w`, exactly.
        let mut zeros = !(((w & 0x7F7F_7F7F).wrapping_add(0x7F7F_7F7F)) | w | 0x7F7F_7F7F);
        while zeros != 0 {
            mark(frame, at + (zeros.trailing_zeros() / 8) as usize)?;
            zeros &= zeros - 1;
        }
        at += 4;
    }
    while at < end {
        if *frame.get(at)? == 0 {
            mark(frame, at)?;
        }
        at += 1;
    }
    mark(frame, end)?;
    *frame.get_mut(end)? = 0;
    Some(end + 1)
}

/// The CRC-32C table of one nibble (4 bits) a step: entry `n` is the `crc` crate's
/// byte table's entry `n << 4` (whose low 4 bits of zeros shift out without a XOR).
/// 64 bytes of flash, where the byte table takes 1 KiB: the QEMU image's 32 KiB of flash is
/// the tighter budget, and two small steps a byte cost about 2.5 instructions a byte more
/// than one large one (BENCHMARKS.md, "HIL guest instructions").
static CRC32C_NIBBLES: [u32; 16] = {
    let bytes = CRC32C.table()[0];
    let mut nibbles = [0; 16];
    let mut n = 0;
    while n < 16 {
        nibbles[n] = bytes[n << 4];
        n += 1;
    }
    nibbles
};

/// CRC-32C (`CRC_32_ISCSI`) of `bytes`, as `crc::Crc::<u32>::new(&CRC_32_ISCSI).checksum`
/// computes it, from the crate's table ([`CRC32C_NIBBLES`]), reading a word at a time
/// (`protocol/tests.rs` checks it against the crate).
pub(super) fn crc32c(bytes: &[u8]) -> u32 {
    let table = &CRC32C_NIBBLES;
    let nibble = |crc: u32| table[(crc & 0xF) as usize] ^ (crc >> 4);
    let byte = |crc: u32| nibble(nibble(crc));
    let (words, tail) = bytes.as_chunks::<4>();
    let mut crc = !0u32;
    for word in words {
        crc ^= u32::from_le_bytes(*word);
        crc = byte(byte(byte(byte(crc))));
    }
    for &b in tail {
        crc = byte(crc ^ u32::from(b));
    }
    !crc
}

/// Decode one frame's bytes (between delimiters, without the `0x00`); `frame` is used as
/// scratch space for the in-place COBS decode. Never panics.
pub fn decode<'de, T: Deserialize<'de>>(frame: &'de mut [u8]) -> Result<T, DecodeError> {
    let n = cobs::decode_in_place(frame).map_err(|_| DecodeError::Cobs)?;
    decode_exact(check_crc(frame.get(..n).ok_or(DecodeError::Cobs)?)?)
}

/// Check the CRC trailer of a COBS-decoded frame: the payload before it.
fn check_crc(decoded: &[u8]) -> Result<&[u8], DecodeError> {
    let (payload, trailer) = decoded
        .split_last_chunk::<CRC_LEN>()
        .ok_or(DecodeError::TooShort)?;
    if crc32c(payload) != u32::from_le_bytes(*trailer) {
        return Err(DecodeError::Crc);
    }
    Ok(payload)
}

/// Decode a message from all of `payload` (a frame's, CRC checked); trailing bytes after a
/// valid message mean the frame is not what the sender encoded ([`DecodeError::Payload`]).
pub fn decode_exact<'de, T: Deserialize<'de>>(payload: &'de [u8]) -> Result<T, DecodeError> {
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

/// Where a [`FrameDecoder`] is in the frame it receives: COBS is undone as the bytes
/// arrive, so a code byte's zero is written when the next block starts (the last block's is
/// not part of the frame).
#[derive(Clone, Copy, Debug, Default)]
struct Unstuff {
    /// Decoded bytes in the buffer.
    decoded: usize,
    /// Encoded bytes of the frame so far (saturating).
    encoded: usize,
    /// Data bytes left in the current block; 0: the next byte is a code byte.
    left: u8,
    /// Whether the current block ends in a zero (its code was not `0xFF`), to be written
    /// when the next block starts.
    zero: bool,
}

/// Undo COBS on `bytes` into `buf` up to the first delimiter: the bytes consumed, and
/// whether a delimiter was the last of them. Bytes that `buf` cannot hold are counted in
/// `state.encoded` only (the frame is overlong).
#[inline(never)] // compiled once, in the core, with its speed-optimised profile (Cargo.toml)
fn unstuff(state: &mut Unstuff, buf: &mut [u8], bytes: &[u8]) -> (usize, bool) {
    let mut s = *state;
    let mut read = 0;
    let mut delimited = false;
    while let Some(&byte) = bytes.get(read) {
        if s.left == 0 {
            // a code byte, or the delimiter between blocks
            if byte == 0 {
                delimited = true;
                break;
            }
            if s.zero {
                if let Some(slot) = buf.get_mut(s.decoded) {
                    *slot = 0;
                    s.decoded += 1;
                }
            }
            (s.left, s.zero) = (byte - 1, byte != 0xFF);
            read += 1;
            continue;
        }
        // the block's data bytes in `bytes`, copied up to a zero (a delimiter inside
        // the block: the frame is invalid, its bytes no longer matter)
        let rest = bytes.get(read..).unwrap_or(&[]);
        let run = rest.get(..usize::from(s.left)).unwrap_or(rest);
        let room = buf.get_mut(s.decoded..).unwrap_or(&mut []);
        let mut n = 0;
        if room.len() >= run.len() {
            for (&b, slot) in run.iter().zip(room.iter_mut()) {
                if b == 0 {
                    break;
                }
                *slot = b;
                n += 1;
            }
            s.decoded += n;
        } else {
            n = run.iter().position(|&b| b == 0).unwrap_or(run.len());
        }
        read += n;
        s.left -= n as u8;
        if n < run.len() {
            delimited = true;
            break;
        }
    }
    s.encoded = s.encoded.saturating_add(read);
    *state = s;
    if delimited {
        (read + 1, true)
    } else {
        (bytes.len(), false)
    }
}

/// Streaming frame decoder with a fixed buffer: feed it bytes as they arrive. A frame of
/// more than `N` encoded bytes (delimiter excluded) is rejected as overlong.
///
/// COBS is undone as the bytes arrive (a chunk at a time with [`feed`](Self::feed)), so
/// the delimiter only has to check the CRC and hand the payload to the caller's decoder:
/// a message is decoded straight into wherever the caller keeps it. Empty frames (two
/// delimiters in a row) are ignored, which lets a sender flush a receiver's partial frame
/// by sending a lone `0x00`. After an overlong frame the decoder discards bytes up to the
/// next delimiter, then resumes.
#[derive(Debug)]
pub struct FrameDecoder<const N: usize = MAX_FRAME_LEN> {
    /// The current frame's decoded bytes.
    buf: [u8; N],
    state: Unstuff,
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
            state: Unstuff {
                decoded: 0,
                encoded: 0,
                left: 0,
                zero: false,
            },
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
        self.feed(core::slice::from_ref(&byte), |payload| {
            decode_exact::<T>(payload)
        })
        .1
    }

    /// Feed `bytes` up to and including the first delimiter: returns how many were
    /// consumed and, if they complete a non-empty frame, `decode` of its payload (COBS
    /// undone, CRC checked) or why the frame was rejected, already counted in
    /// [`stats`](Self::stats) (an error of `decode` is counted, and returned, as
    /// [`DecodeError::Payload`]). Call again with the bytes left over.
    pub fn feed<R>(
        &mut self,
        bytes: &[u8],
        decode: impl FnOnce(&[u8]) -> Result<R, DecodeError>,
    ) -> (usize, Option<Result<R, DecodeError>>) {
        let (consumed, delimited) = unstuff(&mut self.state, &mut self.buf, bytes);
        if !delimited {
            return (consumed, None);
        }
        let frame = core::mem::take(&mut self.state);
        let result = if frame.encoded == 0 {
            return (consumed, None);
        } else if frame.encoded > N {
            Err(DecodeError::Overlong)
        } else if frame.left != 0 {
            // the frame ended inside a block
            Err(DecodeError::Cobs)
        } else {
            self.buf
                .get(..frame.decoded)
                .ok_or(DecodeError::Cobs)
                .and_then(check_crc)
                .and_then(|payload| decode(payload).map_err(|_| DecodeError::Payload))
        };
        self.stats
            .count(result.as_ref().map(|_| ()).map_err(|e| *e));
        (consumed, Some(result))
    }
}
