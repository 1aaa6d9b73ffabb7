//! The ball (or body) measurement from a camera that sends one small frame per image over
//! a UART (an OpenMV Cam, a Pixy or a host PC running a blob tracker), read through
//! `embedded_hal_nb::serial::Read<u8>`.
//!
//! ## Frame ([`FRAME_LEN`] = 9 bytes)
//! ```text
//!   0xA5 0x5A  seq  flags  x_lo x_hi  y_lo y_hi  crc8
//! ```
//! - `seq`: the camera's image counter (wraps at 256); a new value means a new image;
//! - `flags`: bit 0 set if a target was found in the image (the rest reserved, 0);
//! - `x`, `y`: the target's centroid, image column and row, in 1/16 pixel (u16 LE; image
//!   rows grow downwards);
//! - `crc8`: CRC-8/SMBUS (polynomial 0x07, `crc::CRC_8_SMBUS`) of the six bytes from `seq`
//!   to `y_hi`.
//!
//! [`FrameParser`] takes bytes one at a time into a sliding window of the last 9 bytes and
//! reports a frame when the window starts with the sync word and its CRC matches, so it
//! resynchronises after lost or corrupted bytes at the next intact frame, whatever the
//! bytes were (no state to get stuck in). A random window passes the 16-bit sync and the
//! CRC-8 with probability 2^-24. [`Camera`] drains the UART without blocking, a bounded
//! number of bytes per call, and keeps the newest frame.

use crc::{Crc, CRC_8_SMBUS};
use embedded_hal_nb::nb;
use embedded_hal_nb::serial::Read;

/// The two sync bytes a frame starts with.
pub const SYNC: [u8; 2] = [0xA5, 0x5A];
/// Bytes in one frame.
pub const FRAME_LEN: usize = 9;
/// Sub-pixel steps per pixel of `x` and `y`.
pub const SUBPIXELS_PER_PX: f32 = 16.0;
/// Most bytes [`Camera::poll`] reads per call: enough for 7 frames, so a 2 ms period at
/// 115 200 Bd (23 bytes per period) never falls behind, and the work per period is bounded.
pub const MAX_BYTES_PER_POLL: usize = 64;

const CRC8: Crc<u8> = Crc::<u8>::new(&CRC_8_SMBUS);
const FLAG_FOUND: u8 = 1 << 0;

/// One camera image's measurement.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct CameraFrame {
    /// The camera's image counter.
    pub seq: u8,
    /// Whether a target was found (`x_px`, `y_px` are meaningless if not).
    pub found: bool,
    /// Centroid column, px.
    pub x_px: f32,
    /// Centroid row, px (rows grow downwards).
    pub y_px: f32,
}

impl CameraFrame {
    /// The 9 bytes of this frame (tests, and a camera script written in Rust); `x_px` and
    /// `y_px` are rounded to 1/16 px and saturated to the u16 range.
    pub fn encode(&self) -> [u8; FRAME_LEN] {
        let sub = |px: f32| (px * SUBPIXELS_PER_PX + 0.5) as u16;
        let [x0, x1] = sub(self.x_px).to_le_bytes();
        let [y0, y1] = sub(self.y_px).to_le_bytes();
        let flags = if self.found { FLAG_FOUND } else { 0 };
        let body = [self.seq, flags, x0, x1, y0, y1];
        let crc = CRC8.checksum(&body);
        let [s0, s1] = SYNC;
        [s0, s1, self.seq, flags, x0, x1, y0, y1, crc]
    }
}

/// Counts of what the parser saw.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct CameraStats {
    /// Frames accepted.
    pub frames: u32,
    /// Bytes discarded while looking for a frame (noise, or parts of corrupted frames).
    pub skipped_bytes: u32,
    /// Errors the UART reported (overrun, framing, noise, parity).
    pub uart_errors: u32,
}

/// The byte-at-a-time frame parser (see the module docs).
#[derive(Clone, Debug, Default)]
pub struct FrameParser {
    window: [u8; FRAME_LEN],
    len: usize,
    stats: CameraStats,
}

impl FrameParser {
    /// An empty parser.
    pub const fn new() -> Self {
        Self {
            window: [0; FRAME_LEN],
            len: 0,
            stats: CameraStats {
                frames: 0,
                skipped_bytes: 0,
                uart_errors: 0,
            },
        }
    }

    /// Feed one byte; a complete, intact frame ends with it.
    pub fn push(&mut self, byte: u8) -> Option<CameraFrame> {
        if self.len == FRAME_LEN {
            // Slide: the oldest byte leaves the window unused.
            self.window.copy_within(1.., 0);
            self.len -= 1;
            self.stats.skipped_bytes = self.stats.skipped_bytes.saturating_add(1);
        }
        if let Some(slot) = self.window.get_mut(self.len) {
            *slot = byte;
            self.len += 1;
        }
        let frame = self.frame()?;
        self.len = 0;
        self.stats.frames = self.stats.frames.saturating_add(1);
        Some(frame)
    }

    /// The window as a frame, if it is a full, intact one.
    fn frame(&self) -> Option<CameraFrame> {
        let [s0, s1, seq, flags, x0, x1, y0, y1, crc] = self.window;
        if self.len != FRAME_LEN || [s0, s1] != SYNC {
            return None;
        }
        if CRC8.checksum(&[seq, flags, x0, x1, y0, y1]) != crc {
            return None;
        }
        let px = |lo: u8, hi: u8| f32::from(u16::from_le_bytes([lo, hi])) / SUBPIXELS_PER_PX;
        Some(CameraFrame {
            seq,
            found: flags & FLAG_FOUND != 0,
            x_px: px(x0, x1),
            y_px: px(y0, y1),
        })
    }

    /// What the parser has seen so far.
    pub fn stats(&self) -> CameraStats {
        self.stats
    }
}

/// A camera on a UART: drains it without blocking and keeps the newest frame.
pub struct Camera<R> {
    uart: R,
    parser: FrameParser,
}

impl<R: Read<u8>> Camera<R> {
    /// A camera on `uart` (configured for the camera's baud rate, 8N1).
    pub fn new(uart: R) -> Self {
        Self {
            uart,
            parser: FrameParser::new(),
        }
    }

    /// Read what the UART holds (at most [`MAX_BYTES_PER_POLL`] bytes) and return the
    /// newest frame completed by them, if any. A UART error is counted
    /// ([`CameraStats::uart_errors`]) and reading goes on: the parser resynchronises.
    pub fn poll(&mut self) -> Option<CameraFrame> {
        let mut newest = None;
        for _ in 0..MAX_BYTES_PER_POLL {
            match self.uart.read() {
                Ok(byte) => newest = self.parser.push(byte).or(newest),
                Err(nb::Error::WouldBlock) => break,
                Err(nb::Error::Other(_)) => {
                    let errors = &mut self.parser.stats.uart_errors;
                    *errors = errors.saturating_add(1);
                }
            }
        }
        newest
    }

    /// What the parser has seen so far.
    pub fn stats(&self) -> CameraStats {
        self.parser.stats()
    }
}

/// Image row to height for a camera that looks at the ball's line of flight from the side:
/// `height = (row_at_zero_px - row_px) * m_per_px` (rows grow downwards). A pinhole camera
/// far from the line (distance much larger than the juggle's height) is linear to within
/// its lens distortion; calibrate with two known heights.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct RowToHeight {
    /// The image row of height 0 (the impact plane), px.
    pub row_at_zero_px: f32,
    /// Metres per pixel along the line of flight (> 0).
    pub m_per_px: f32,
}

impl RowToHeight {
    /// A calibration; the error names the figure that is not finite (and positive).
    pub fn new(row_at_zero_px: f32, m_per_px: f32) -> Result<Self, crate::ConfigError> {
        if !row_at_zero_px.is_finite() {
            return Err(crate::ConfigError::NotPositive("row_at_zero_px (finite)"));
        }
        crate::actuator::positive("m_per_px", m_per_px)?;
        Ok(Self {
            row_at_zero_px,
            m_per_px,
        })
    }

    /// The ball's height for a frame, m; NaN if the camera did not find it (the core's
    /// controllers answer a NaN with their safe state, `Fault::NonFinite`).
    pub fn height_m(&self, frame: &CameraFrame) -> f32 {
        if frame.found {
            (self.row_at_zero_px - frame.y_px) * self.m_per_px
        } else {
            f32::NAN
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use embedded_hal_mock::eh1::serial::{Mock as SerialMock, Transaction as Serial};
    use embedded_hal_nb::nb;
    use embedded_hal_nb::serial::ErrorKind;
    use proptest::prelude::*;

    fn ball(seq: u8, y_px: f32) -> CameraFrame {
        CameraFrame {
            seq,
            found: true,
            x_px: 80.5,
            y_px,
        }
    }

    fn parse_all(bytes: &[u8]) -> Vec<CameraFrame> {
        let mut p = FrameParser::new();
        bytes.iter().filter_map(|&b| p.push(b)).collect()
    }

    #[test]
    fn a_frame_has_the_documented_bytes() {
        // y = 100.25 px = 1604/16 = 0x0644, x = 80.5 px = 1288/16 = 0x0508; CRC-8/SMBUS of
        // [07 01 08 05 44 06] with poly 0x07 is 0xD0 (the remainder of the bytes times x^8
        // divided by x^8 + x^2 + x + 1; checked below by a bitwise CRC written out here, not
        // the crate).
        let bytes = ball(7, 100.25).encode();
        assert_eq!(&bytes[..8], &[0xA5, 0x5A, 7, 1, 0x08, 0x05, 0x44, 0x06]);
        let mut crc = 0u8;
        for &b in &bytes[2..8] {
            crc ^= b;
            for _ in 0..8 {
                crc = if crc & 0x80 != 0 {
                    (crc << 1) ^ 0x07
                } else {
                    crc << 1
                };
            }
        }
        assert_eq!(bytes[8], crc);
        assert_eq!(bytes[8], 0xD0);
    }

    #[test]
    fn frames_round_trip_to_a_sixteenth_of_a_pixel() {
        let f = ball(200, 123.4375);
        assert_eq!(parse_all(&f.encode()), vec![f]);
        let lost = CameraFrame {
            seq: 3,
            found: false,
            x_px: 0.0,
            y_px: 0.0,
        };
        assert_eq!(parse_all(&lost.encode()), vec![lost]);
    }

    #[test]
    fn noise_before_a_frame_is_skipped_and_counted() {
        let mut bytes = vec![0x00, 0xA5, 0xA5, 0x5A, 0x13];
        bytes.extend(ball(1, 50.0).encode());
        let mut p = FrameParser::new();
        let got: Vec<_> = bytes.iter().filter_map(|&b| p.push(b)).collect();
        assert_eq!(got, vec![ball(1, 50.0)]);
        assert_eq!(p.stats().skipped_bytes, 5);
        assert_eq!(p.stats().frames, 1);
    }

    #[test]
    fn a_corrupted_frame_is_dropped_and_the_next_one_is_found() {
        let mut first = ball(1, 10.0).encode();
        first[6] ^= 0x04; // one bit of y
        let mut bytes = first.to_vec();
        bytes.extend(ball(2, 20.0).encode());
        assert_eq!(parse_all(&bytes), vec![ball(2, 20.0)]);
        // a frame cut short (bytes lost) before an intact one
        let mut bytes = ball(3, 30.0).encode()[..5].to_vec();
        bytes.extend(ball(4, 40.0).encode());
        assert_eq!(parse_all(&bytes), vec![ball(4, 40.0)]);
    }

    proptest! {
        /// Junk before a frame (without the first sync byte, so it cannot hold a frame of
        /// its own), and any single-bit flip inside a frame, never yield a wrong frame; the
        /// intact frame after them is always found.
        #[test]
        fn junk_and_flips_never_give_a_wrong_frame(
            junk in proptest::collection::vec(any::<u8>().prop_filter("not sync", |b| *b != SYNC[0]), 0..40),
            flip in 0usize..FRAME_LEN * 8,
            y in 0.0f32..4000.0,
        ) {
            let good = ball(9, (y * 16.0).round() / 16.0);
            let mut bad = ball(8, 1.0).encode();
            bad[flip / 8] ^= 1 << (flip % 8);
            let mut bytes = junk.clone();
            bytes.extend(bad);
            bytes.extend(good.encode());
            let got = parse_all(&bytes);
            prop_assert_eq!(got, vec![good]);
        }
    }

    #[test]
    fn the_camera_drains_the_uart_keeps_the_newest_frame_and_counts_errors() {
        let mut bytes = ball(1, 10.0).encode().to_vec();
        bytes.extend(ball(2, 20.0).encode());
        let mut expected = vec![Serial::read_many(&bytes[..12])];
        expected.push(Serial::read_error(nb::Error::Other(ErrorKind::Overrun)));
        expected.push(Serial::read_many(&bytes[12..]));
        expected.push(Serial::read_error(nb::Error::WouldBlock));
        let mut cam = Camera::new(SerialMock::new(&expected));
        assert_eq!(cam.poll(), Some(ball(2, 20.0)));
        assert_eq!(cam.stats().frames, 2);
        assert_eq!(cam.stats().uart_errors, 1);
        cam.uart.done();
    }

    #[test]
    fn one_poll_reads_a_bounded_number_of_bytes() {
        let bytes = [0x11; MAX_BYTES_PER_POLL + 5];
        let mut uart = SerialMock::new(&[Serial::read_many(&bytes[..MAX_BYTES_PER_POLL])]);
        let mut cam = Camera::new(uart.clone());
        assert_eq!(cam.poll(), None); // stops after MAX_BYTES_PER_POLL reads
        uart.done();
    }

    #[test]
    fn rows_become_heights_and_a_lost_ball_is_nan() {
        let cal = RowToHeight::new(400.0, 0.0025).unwrap();
        // 200 px above the zero row at 2.5 mm/px = 0.5 m
        assert_eq!(cal.height_m(&ball(0, 200.0)), 0.5);
        assert!((cal.height_m(&ball(0, 420.0)) + 0.05).abs() < 1e-7);
        let lost = CameraFrame::default();
        assert!(cal.height_m(&lost).is_nan());
        assert!(RowToHeight::new(400.0, -1.0).is_err());
    }
}
