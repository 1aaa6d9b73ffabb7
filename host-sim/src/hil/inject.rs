//! Fault injection on the host-to-device bytes, and the prediction of what the firmware's
//! receiver sees, made independently of the protocol's decoder.
//!
//! The firmware delimits frames at `0x00` and must reject every frame that is not exactly
//! what the host encoded. So the host needs no decoder to know the outcome: it splits the
//! bytes it actually sent at `0x00`, exactly as any receiver must, and a non-empty segment
//! is [`Segment::Intact`] only if it is byte for byte the frame it encoded (CRC-32C misses
//! a random corruption with p = 2^-32). A decoder bug on either side (a weakened CRC, a
//! COBS slip) therefore shows up as a disagreement, instead of being mirrored by the
//! host's own copy of the same decoder.

use super::CORRUPTION_SEED;
use dexter_core::protocol::MAX_FRAME_LEN;
use rand::rngs::StdRng;
use rand::{Rng, SeedableRng};

/// One frame as the firmware's receiver delimits it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Segment {
    /// Exactly the frame the host encoded: the firmware must accept it.
    Intact,
    /// Anything else (corrupted, merged with a neighbour, truncated): it must be rejected.
    Corrupt,
}

/// Byte corruption (seeded) and the receiver's view of the stream.
pub(super) struct Injector {
    rate: f64,
    rng: StdRng,
    /// Bytes the receiver holds since its last delimiter (at most `MAX_FRAME_LEN`).
    pending: Vec<u8>,
    /// The pending segment is longer than any frame (so it cannot be intact).
    pending_overflow: bool,
}

impl Injector {
    /// No corruption at `rate` 0; otherwise each byte is dropped or has one bit flipped
    /// with probability `rate`.
    pub(super) fn new(rate: f64) -> Self {
        Self {
            rate,
            rng: StdRng::seed_from_u64(CORRUPTION_SEED),
            pending: Vec::with_capacity(MAX_FRAME_LEN),
            pending_overflow: false,
        }
    }

    /// `bytes` as they travel: copied into `out` with the injected faults; the bytes sent.
    pub(super) fn corrupt<'a>(&mut self, bytes: &[u8], out: &'a mut [u8]) -> &'a [u8] {
        let mut n = 0;
        for &b in bytes {
            let byte = if self.rate > 0.0 && self.rng.random::<f64>() < self.rate {
                if self.rng.random_bool(0.5) {
                    continue; // dropped
                }
                b ^ (1u8 << self.rng.random_range(0..8u32))
            } else {
                b
            };
            out[n] = byte; // n < bytes.len() <= out.len(): one slot per kept byte
            n += 1;
        }
        &out[..n]
    }

    /// The segments that `sent` completes, in order, given that the host meant to send
    /// `intact` (the encoded frame without its delimiter).
    pub(super) fn segments(&mut self, sent: &[u8], intact: &[u8], mut each: impl FnMut(Segment)) {
        for &b in sent {
            if b != 0 {
                if self.pending.len() < MAX_FRAME_LEN {
                    self.pending.push(b);
                } else {
                    self.pending_overflow = true;
                }
                continue;
            }
            if self.pending.is_empty() && !self.pending_overflow {
                continue; // an empty frame: ignored by the receiver
            }
            let segment = if !self.pending_overflow && self.pending == intact {
                Segment::Intact
            } else {
                Segment::Corrupt
            };
            self.pending.clear();
            self.pending_overflow = false;
            each(segment);
        }
    }

    /// Whether the receiver holds a partial frame (which a lone `0x00` would complete as a
    /// corrupt segment).
    pub(super) fn has_partial_frame(&self) -> bool {
        !self.pending.is_empty() || self.pending_overflow
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn collect(inj: &mut Injector, sent: &[u8], intact: &[u8]) -> Vec<Segment> {
        let mut v = Vec::new();
        inj.segments(sent, intact, |s| v.push(s));
        v
    }

    #[test]
    fn an_intact_frame_and_its_flush_delimiter_make_one_intact_segment() {
        let mut inj = Injector::new(0.0);
        assert_eq!(
            collect(&mut inj, &[5, 6, 7, 0, 0], &[5, 6, 7]),
            [Segment::Intact]
        );
        assert!(!inj.has_partial_frame());
    }

    #[test]
    fn a_flipped_byte_a_split_and_a_merge_are_corrupt_segments() {
        let mut inj = Injector::new(0.0);
        assert_eq!(
            collect(&mut inj, &[5, 9, 7, 0, 0], &[5, 6, 7]),
            [Segment::Corrupt]
        );
        // a byte flipped to 0x00 splits the frame in two
        assert_eq!(
            collect(&mut inj, &[5, 0, 7, 0, 0], &[5, 6, 7]),
            [Segment::Corrupt, Segment::Corrupt]
        );
        // both delimiters lost: the bytes stay pending and merge with the next frame
        assert!(collect(&mut inj, &[5, 6, 7], &[5, 6, 7]).is_empty());
        assert!(inj.has_partial_frame());
        assert_eq!(
            collect(&mut inj, &[5, 6, 7, 0, 0], &[5, 6, 7]),
            [Segment::Corrupt]
        );
    }

    #[test]
    fn an_overlong_run_is_one_corrupt_segment() {
        let mut inj = Injector::new(0.0);
        let long = vec![1u8; 3 * MAX_FRAME_LEN];
        assert!(collect(&mut inj, &long, &[1]).is_empty());
        assert_eq!(collect(&mut inj, &[0], &[1]), [Segment::Corrupt]);
    }

    #[test]
    fn corruption_at_rate_one_drops_or_flips_one_bit_of_every_byte() {
        let bytes = [0x0fu8; 200];
        let mut out = [0u8; 256];
        let mut inj = Injector::new(0.0);
        assert_eq!(inj.corrupt(&bytes, &mut out), &bytes[..]);
        let mut inj = Injector::new(1.0);
        let sent = inj.corrupt(&bytes, &mut out);
        assert!(
            sent.len() < bytes.len() && !sent.is_empty(),
            "{}",
            sent.len()
        );
        // 0x0f has 4 bits set; one flipped bit leaves 3 or 5
        assert!(sent
            .iter()
            .all(|b| b.count_ones() == 3 || b.count_ones() == 5));
    }
}
