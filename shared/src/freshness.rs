//! Whether a sample is new: the sequence-number check every controller runs on its frames.
//!
//! A frame carries the plant's sample sequence number. A sample is new if the number moved
//! forward, with wrapping arithmetic, by 1 ..= 2^31 - 2 (`u32::MAX / 2 - 1`): the counter
//! wraps forward up to half its range, and a jump of 2^31 - 1 or more counts as going
//! back. A repeat (or a step back) is allowed for `stale_limit_steps` periods in a row;
//! one more is [`Fault::Stale`]. The first frame is always new.

use crate::fixed_rate::Fault;

/// The last new sequence number and the periods since it.
#[derive(Clone, Copy, Debug, Default)]
pub struct Freshness {
    /// The last new sample's number; meaningless until `seen`. A `u32` and a flag rather
    /// than an `Option<u32>`: the arm's step reads it as its trajectory clock without a
    /// branch, and the three fields pack into 8 bytes.
    last_seq: u32,
    stale_steps: u16,
    seen: bool,
}

impl Freshness {
    /// No sample seen yet.
    pub const fn new() -> Self {
        Self {
            last_seq: 0,
            stale_steps: 0,
            seen: false,
        }
    }

    /// The sequence number of the last new sample, 0 before the first.
    pub fn last_seq(&self) -> u32 {
        self.last_seq
    }

    /// Whether a new sample has been seen.
    pub fn seen(&self) -> bool {
        self.seen
    }

    /// Account for a frame numbered `seq`: `Ok(true)` if it is a new sample, `Ok(false)` if
    /// it repeats the last one within `stale_limit_steps` periods, else [`Fault::Stale`].
    #[inline(always)]
    pub fn check(&mut self, seq: u32, stale_limit_steps: u16) -> Result<bool, Fault> {
        // forward by 1 ..= 2^31 - 2: `ahead - 1` below 2^31 - 2, one unsigned comparison (a
        // repeat wraps to u32::MAX)
        let ahead = seq.wrapping_sub(self.last_seq);
        if !self.seen || ahead.wrapping_sub(1) < u32::MAX / 2 - 1 {
            self.last_seq = seq;
            self.seen = true;
            self.stale_steps = 0;
            Ok(true)
        } else {
            self.stale_steps = self.stale_steps.saturating_add(1);
            if self.stale_steps > stale_limit_steps {
                Err(Fault::Stale)
            } else {
                Ok(false)
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_first_sample_is_new_and_a_repeat_is_stale_one_past_the_limit() {
        let mut f = Freshness::new();
        assert_eq!((f.last_seq(), f.seen()), (0, false));
        // the first sample is new whatever its number, 0 (the initial value) too
        assert_eq!(Freshness::new().check(0, 2), Ok(true));
        assert_eq!(f.check(7, 2), Ok(true));
        assert_eq!(f.check(7, 2), Ok(false));
        assert_eq!(f.check(7, 2), Ok(false));
        assert_eq!(f.check(7, 2), Err(Fault::Stale));
        // a new sample resets the count
        assert_eq!(f.check(8, 2), Ok(true));
        assert_eq!(f.check(8, 2), Ok(false));
        assert_eq!((f.last_seq(), f.seen()), (8, true));
    }

    #[test]
    fn forward_is_1_to_2_pow_31_minus_2_with_wrapping() {
        for (ahead, fresh) in [
            (1u32, true),
            ((1 << 31) - 2, true),
            ((1 << 31) - 1, false),
            (1 << 31, false),
            (u32::MAX, false),
        ] {
            for last in [0u32, u32::MAX, 1 << 31] {
                let mut f = Freshness::new();
                f.check(last, 5).unwrap();
                let seq = last.wrapping_add(ahead);
                assert_eq!(f.check(seq, 5), Ok(fresh), "{last} + {ahead}");
                assert_eq!(f.last_seq(), if fresh { seq } else { last });
            }
        }
    }
}
