//! The paddle's position from a quadrature encoder counted by a hardware timer.
//!
//! embedded-hal 1.0 has no encoder trait (0.2's `Qei` was dropped), so [`QuadratureCounter`]
//! is ours: a timer in encoder mode is a free-running up/down counter of `BITS` bits (16 on
//! an STM32's TIM3/TIM4, 32 on TIM2/TIM5). [`Encoder`] extends it to an unbounded position:
//! each update adds the difference since the last read, taken modulo `2^BITS` and read as a
//! signed number, which is exact as long as the shaft turns less than `2^(BITS-1)` counts
//! between two reads (32 767 counts per 2 ms period on a 16-bit timer: 16 M counts/s, far
//! above any encoder's rate). [`PaddleEncoder`] turns it into the paddle's height and
//! velocity (backward difference over the control period).

use crate::actuator::{positive, ConfigError};

/// A hardware up/down counter in quadrature (encoder) mode.
pub trait QuadratureCounter {
    /// Width of the counter, bits (1 ..= 32); it wraps modulo `2^BITS`.
    const BITS: u32;
    /// The raw count; bits above `BITS` are ignored.
    fn count(&mut self) -> u32;
}

/// A quadrature counter extended to a position that does not wrap.
pub struct Encoder<Q> {
    counter: Q,
    last: u32,
    position_counts: i64,
}

impl<Q: QuadratureCounter> Encoder<Q> {
    const MASK: u32 = {
        assert!(Q::BITS >= 1 && Q::BITS <= 32);
        u32::MAX >> (32 - Q::BITS)
    };

    /// An encoder whose position is 0 at the counter's current value.
    pub fn new(mut counter: Q) -> Self {
        let last = counter.count() & Self::MASK;
        Self {
            counter,
            last,
            position_counts: 0,
        }
    }

    /// Read the counter and return the position, counts since [`Encoder::new`].
    pub fn update(&mut self) -> i64 {
        let now = self.counter.count() & Self::MASK;
        self.position_counts += Self::signed_delta(self.last, now);
        self.last = now;
        self.position_counts
    }

    /// `now - last` modulo `2^BITS`, as a signed number in `[-2^(BITS-1), 2^(BITS-1))`.
    fn signed_delta(last: u32, now: u32) -> i64 {
        let d = now.wrapping_sub(last) & Self::MASK;
        let half = 1u64 << (Q::BITS - 1);
        if u64::from(d) >= half {
            i64::from(d) - (1i64 << Q::BITS)
        } else {
            i64::from(d)
        }
    }

    /// The position at the last update, counts.
    pub fn position_counts(&self) -> i64 {
        self.position_counts
    }
}

/// The paddle's measured state.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct PaddleSample {
    /// Height above the impact plane's zero, m.
    pub height_m: f32,
    /// Velocity, m/s (backward difference over the last period).
    pub velocity_mps: f32,
}

/// The paddle's height and velocity from its encoder.
pub struct PaddleEncoder<Q> {
    encoder: Encoder<Q>,
    m_per_count: f32,
    zero_height_m: f32,
    dt_s: f32,
    last_counts: i64,
}

impl<Q: QuadratureCounter> PaddleEncoder<Q> {
    /// The paddle is at `zero_height_m` now (e.g. resting on its lower stop); the encoder
    /// moves it `m_per_count` metres per count (negative if counting down means up), sampled
    /// every `dt_s` seconds. The error names the figure that is not finite and non-zero.
    pub fn new(
        counter: Q,
        m_per_count: f32,
        zero_height_m: f32,
        dt_s: f32,
    ) -> Result<Self, ConfigError> {
        positive("m_per_count (magnitude)", m_per_count.abs())?;
        if !zero_height_m.is_finite() {
            return Err(ConfigError::NotPositive("zero_height_m (finite)"));
        }
        positive("dt_s", dt_s)?;
        Ok(Self {
            encoder: Encoder::new(counter),
            m_per_count,
            zero_height_m,
            dt_s,
            last_counts: 0,
        })
    }

    /// The position at the last [`PaddleEncoder::sample`], counts from where it started
    /// (what calibration reads: metres per count is a distance over this difference).
    pub fn counts(&self) -> i64 {
        self.last_counts
    }

    /// Read the encoder once per control period: height and velocity.
    pub fn sample(&mut self) -> PaddleSample {
        let counts = self.encoder.update();
        let moved = counts - self.last_counts;
        self.last_counts = counts;
        PaddleSample {
            height_m: self.zero_height_m + counts as f32 * self.m_per_count,
            velocity_mps: moved as f32 * self.m_per_count / self.dt_s,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    /// A counter of `B` bits that plays back raw counts.
    struct Replay<const B: u32> {
        counts: Vec<u32>,
        next: usize,
    }

    impl<const B: u32> QuadratureCounter for Replay<B> {
        const BITS: u32 = B;
        fn count(&mut self) -> u32 {
            self.next += 1;
            self.counts[self.next - 1]
        }
    }

    fn replay<const B: u32>(counts: &[u32]) -> Replay<B> {
        Replay {
            counts: counts.to_vec(),
            next: 0,
        }
    }

    #[test]
    fn a_16_bit_counter_wraps_both_ways_without_a_jump() {
        // 65530 -> 4 is +10 through the wrap; 4 -> 65526 is -14 back through it.
        let mut e = Encoder::new(replay::<16>(&[65_530, 4, 65_526, 65_526]));
        assert_eq!(e.update(), 10);
        assert_eq!(e.update(), -4);
        assert_eq!(e.update(), -4);
    }

    #[test]
    fn bits_above_the_width_are_ignored_and_32_bit_counters_wrap_too() {
        // a 16-bit timer read through a 32-bit register with junk in the upper half
        let mut e = Encoder::new(replay::<16>(&[0xdead_0000, 0xbeef_0005]));
        assert_eq!(e.update(), 5);
        let mut e = Encoder::new(replay::<32>(&[u32::MAX - 1, 3]));
        assert_eq!(e.update(), 5);
    }

    #[test]
    fn the_largest_step_each_way_is_exact_and_half_a_turn_reads_as_backwards() {
        // +32767 is the largest forward step a 16-bit counter can tell; +32768 is ambiguous
        // and reads as -32768 (the documented limit).
        let mut e = Encoder::new(replay::<16>(&[0, 32_767, 0, 32_768]));
        assert_eq!(e.update(), 32_767);
        assert_eq!(e.update(), 0);
        assert_eq!(e.update(), -32_768);
    }

    proptest! {
        /// Any walk whose steps stay under half the counter's range is tracked exactly.
        #[test]
        fn a_walk_of_small_steps_is_tracked_exactly(
            start in 0u32..65_536,
            steps in proptest::collection::vec(-32_767i64..=32_767, 1..200),
        ) {
            let mut truth = i64::from(start);
            let mut raw = vec![start];
            for s in &steps {
                truth += s;
                raw.push(truth.rem_euclid(65_536) as u32);
            }
            let mut e = Encoder::new(replay::<16>(&raw));
            let mut last = 0;
            for _ in &steps {
                last = e.update();
            }
            prop_assert_eq!(last, truth - i64::from(start));
        }
    }

    #[test]
    fn height_and_velocity_follow_the_counts() {
        // 0.1 mm per count, 2 ms period, paddle starts at -0.05 m.
        let counts = [100, 150, 150, 90];
        let mut p = PaddleEncoder::new(replay::<16>(&counts), 1e-4, -0.05, 0.002).unwrap();
        let a = p.sample(); // +50 counts = +5 mm in 2 ms
        assert!((a.height_m - (-0.045)).abs() < 1e-7);
        assert!((a.velocity_mps - 2.5).abs() < 1e-5);
        let b = p.sample();
        assert_eq!(b.velocity_mps, 0.0);
        let c = p.sample(); // -60 counts = -6 mm
        assert!((c.height_m - (-0.051)).abs() < 1e-7);
        assert!((c.velocity_mps - (-3.0)).abs() < 1e-5);
    }

    #[test]
    fn a_zero_scale_or_period_is_refused() {
        assert!(PaddleEncoder::new(replay::<16>(&[0]), 0.0, 0.0, 0.002).is_err());
        assert!(PaddleEncoder::new(replay::<16>(&[0]), 1e-4, 0.0, 0.0).is_err());
        assert!(PaddleEncoder::new(replay::<16>(&[0]), 1e-4, f32::NAN, 0.002).is_err());
    }
}
