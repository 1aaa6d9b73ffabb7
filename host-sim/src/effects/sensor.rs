//! The ball-height sensor the controller sees.
//!
//! [`PerfectSensor`]: the frame at each control step carries the true height (as f32).
//! [`SampledSensor`]: samples every `1/rate` s, adds Gaussian noise, quantizes, and
//! delivers each sample `latency` s later; each control frame carries the newest delivered
//! sample and its sequence number (a repeated number tells the controller nothing new
//! arrived). Until the first sample is delivered the frame repeats sample 0's value.

use rand::SeedableRng;
use rand_distr::{Distribution, Normal};

/// A ball sensor: sample events inside the plant, frames at control steps.
pub trait Sensor {
    /// Time of the next sample, s (infinite if the sensor samples only at control steps).
    fn next_sample_time_s(&self) -> f64;
    /// Take the sample due at `t_s` of the true height `height_m` (m).
    fn sample(&mut self, t_s: f64, height_m: f64);
    /// The frame content at control step `step` (time `t_s`): sequence number and the
    /// measured height (m), given the true height now.
    fn frame(&mut self, step: u64, t_s: f64, height_m: f64) -> (u32, f32);
}

/// The true height at every control step, sequence number = step.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct PerfectSensor;

impl Sensor for PerfectSensor {
    #[inline(always)]
    fn next_sample_time_s(&self) -> f64 {
        f64::INFINITY
    }
    #[inline(always)]
    fn sample(&mut self, _: f64, _: f64) {}
    #[inline(always)]
    fn frame(&mut self, step: u64, _: f64, height_m: f64) -> (u32, f32) {
        (step as u32, height_m as f32)
    }
}

/// A sampled sensor with noise, quantization and latency.
#[derive(Clone, Debug)]
pub struct SampledSensor {
    period_s: f64,
    latency_s: f64,
    quantization_m: f64,
    /// `1 / quantization_m`, 1/m (0 without quantization): the quantizer multiplies
    /// instead of dividing on every sample (a division was a tenth of the SIL loop's time).
    /// The level boundaries then sit within an ulp of the exact half-multiples of the step.
    per_quantum: f64,
    normal: Option<Normal<f64>>,
    rng: rand::rngs::StdRng,
    next_index: u64,
    /// `next_index * period_s`, s (kept: the loop asks for it several times per step).
    next_time_s: f64,
    /// Samples taken and not yet delivered, (delivery time s, value m), sample `j` in slot
    /// `j & mask`: a ring sized once for the latency (a power of two), so a step's push and
    /// delivery are an index and a mask (a `VecDeque` cost ~40 instructions a step).
    pending: Box<[(f64, f32)]>,
    mask: u64,
    /// Index of the oldest undelivered sample (`next_index` if none).
    delivered: u64,
    latest: Option<(u32, f32)>,
}

/// The time of step or sample `index` at period `period_s`, s: `index as f64 * period_s`
/// exactly (an index below 2^63 converts through `i64` to the same `f64`), in one
/// instruction on x86-64 where a `u64` conversion takes seven.
#[inline]
pub fn index_time_s(index: u64, period_s: f64) -> f64 {
    debug_assert!(index < 1 << 63);
    index as i64 as f64 * period_s
}

/// Most samples in flight (taken, not yet delivered): the validator refuses a
/// `sensor.latency_s` x `sensor.rate_hz` above it, so none is ever dropped.
pub const MAX_PENDING: usize = 4096;

/// Ring slots for samples `latency_s` old at `rate_hz`: a power of two holding at least
/// twice the samples in flight plus a few (at most [`MAX_PENDING`]).
fn ring_slots(latency_s: f64, rate_hz: f64) -> usize {
    let in_flight = (latency_s * rate_hz).ceil();
    if in_flight.is_finite() && in_flight >= 0.0 && in_flight < MAX_PENDING as f64 {
        (2 * in_flight as usize + 8)
            .next_power_of_two()
            .min(MAX_PENDING)
    } else {
        MAX_PENDING
    }
}

impl SampledSensor {
    /// A sensor sampling at `rate_hz` (> 0) with noise `sigma_m` (m), latency `latency_s`
    /// (s) and quantization `quantization_m` (m, 0 = none), reproducible from `seed`.
    pub fn new(rate_hz: f64, sigma_m: f64, latency_s: f64, quantization_m: f64, seed: u64) -> Self {
        let slots = ring_slots(latency_s, rate_hz);
        Self {
            period_s: 1.0 / rate_hz,
            latency_s,
            quantization_m,
            per_quantum: if quantization_m > 0.0 {
                1.0 / quantization_m
            } else {
                0.0
            },
            normal: (sigma_m > 0.0)
                .then(|| Normal::new(0.0, sigma_m).ok())
                .flatten(),
            rng: rand::rngs::StdRng::seed_from_u64(seed),
            next_index: 0,
            next_time_s: 0.0,
            pending: vec![(0.0, 0.0); slots].into_boxed_slice(),
            mask: slots as u64 - 1,
            delivered: 0,
            latest: None,
        }
    }

    fn slot(&self, index: u64) -> (f64, f32) {
        self.pending[(index & self.mask) as usize]
    }

    fn measure(&mut self, height_m: f64) -> f32 {
        let mut z = height_m;
        if let Some(n) = &self.normal {
            z += n.sample(&mut self.rng);
        }
        if self.quantization_m > 0.0 {
            z = round_half_away(z * self.per_quantum) * self.quantization_m;
        }
        z as f32
    }
}

/// `x.round()` (half away from zero, the sign of zero kept), bit for bit, without the
/// library call `f64::round` becomes on x86-64's baseline (no SSE4.1 `roundsd`): the
/// truncation `x as i64` is one instruction and `x - t` is exact. Values of magnitude
/// 2^52 and more are integers already (and NaN and infinities are returned as they are).
#[inline]
pub fn round_half_away(x: f64) -> f64 {
    const INTEGRAL: f64 = 4_503_599_627_370_496.0; // 2^52
    if x.is_nan() || x.abs() >= INTEGRAL {
        return x;
    }
    // Integer arithmetic instead of branches: whether the fraction reaches one half is as
    // random as the sensor noise, so a branch on it is mispredicted half the time (it was
    // the costliest line of the SIL loop, `BENCHMARKS.md`). The result is the same: every
    // integer of magnitude below 2^53 converts exactly.
    let t = x as i64;
    let fraction = x - t as f64;
    let step = i64::from(fraction >= 0.5) - i64::from(fraction <= -0.5);
    ((t + step) as f64).copysign(x)
}

impl Sensor for SampledSensor {
    #[inline]
    fn next_sample_time_s(&self) -> f64 {
        self.next_time_s
    }

    fn sample(&mut self, t_s: f64, height_m: f64) {
        let z = self.measure(height_m);
        if self.next_index - self.delivered > self.mask {
            self.delivered += 1; // full (never, for a validated scene): drop the oldest
        }
        self.pending[(self.next_index & self.mask) as usize] = (t_s + self.latency_s, z);
        self.next_index += 1;
        self.next_time_s = index_time_s(self.next_index, self.period_s);
    }

    fn frame(&mut self, _step: u64, t_s: f64, _height_m: f64) -> (u32, f32) {
        // deliver everything due by now (1e-9 s of slack for the rounding of t)
        while self.delivered < self.next_index {
            let (due, z) = self.slot(self.delivered);
            if due > t_s + 1e-9 {
                break;
            }
            self.latest = Some((self.delivered as u32, z));
            self.delivered += 1;
        }
        match self.latest {
            Some(l) => l,
            None if self.delivered < self.next_index => {
                (self.delivered as u32, self.slot(self.delivered).1)
            }
            None => (0, f32::NAN),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn latency_delays_delivery_and_quantization_rounds() {
        let mut s = SampledSensor::new(100.0, 0.0, 0.02, 0.01, 1);
        // samples at 0, 0.01, 0.02, 0.03 of heights 0.123, 0.234, ...
        for k in 0..4 {
            let t = s.next_sample_time_s();
            assert!((t - 0.01 * k as f64).abs() < 1e-15);
            s.sample(t, 0.123 + 0.111 * k as f64);
        }
        // at t = 0.025 the samples taken at 0 (due 0.02) is delivered, not the one at 0.01 (due 0.03)
        let (seq, z) = s.frame(0, 0.025, 0.0);
        assert_eq!(seq, 0);
        assert!((z - 0.12).abs() < 1e-6, "{z}");
        let (seq, z) = s.frame(1, 0.05, 0.0);
        assert_eq!(seq, 3);
        assert!((z - 0.46).abs() < 1e-6, "{z}"); // 0.456 -> 0.46
    }

    #[test]
    fn rounding_matches_the_standard_library_bit_for_bit() {
        let special = [
            0.0,
            -0.0,
            0.5,
            -0.5,
            1.5,
            -1.5,
            2.5,
            -2.5,
            0.49999999999999994,
            -0.49999999999999994,
            4503599627370495.5,
            -4503599627370495.5,
            4503599627370496.0,
            1e300,
            -1e300,
            f64::MIN_POSITIVE,
            -f64::MIN_POSITIVE,
            f64::INFINITY,
            f64::NEG_INFINITY,
        ];
        let mut rng = rand::rngs::StdRng::seed_from_u64(7);
        let draws = (0..200_000).map(|k| {
            use rand::Rng;
            let x: f64 = rng.random_range(-1e6..1e6);
            match k % 4 {
                0 => x,
                1 => x.trunc() + 0.5,                     // exact halves
                2 => x * 1e-7,                            // small
                _ => f64::from_bits(rng.random::<u64>()), // any bit pattern
            }
        });
        for x in special.into_iter().chain(draws) {
            let (ours, std) = (round_half_away(x), x.round());
            assert!(
                ours.to_bits() == std.to_bits() || (ours.is_nan() && std.is_nan()),
                "{x:e}: {ours:e} vs {std:e}"
            );
        }
        assert!(round_half_away(f64::NAN).is_nan());
    }

    /// Quantizing by multiplying with the reciprocal of the step gives the level that
    /// dividing by the step gives, except within a few ulps of a half-level (where the two
    /// roundings of the quotient may straddle it), for steps that are not powers of two.
    #[test]
    fn quantizing_by_the_reciprocal_matches_dividing() {
        use rand::Rng;
        let mut rng = rand::rngs::StdRng::seed_from_u64(11);
        let mut near_half = 0;
        for q in [1e-4, 1e-3, 3e-4, 0.01, 7.3e-5] {
            let s = SampledSensor::new(1000.0, 0.0, 0.0, q, 1);
            for _ in 0..20_000 {
                let z: f64 = rng.random_range(-2.0..2.0);
                let exact = z / q;
                let got = round_half_away(z * s.per_quantum) * q;
                let want = round_half_away(exact) * q;
                if (exact.abs().fract() - 0.5).abs() < 1e-12 * exact.abs().max(1.0) {
                    near_half += 1;
                    assert!((got - want).abs() <= q * (1.0 + 1e-12), "{z} / {q}");
                } else {
                    assert_eq!(got.to_bits(), want.to_bits(), "{z} / {q}");
                }
            }
        }
        assert!(near_half < 10, "{near_half}");
    }

    #[test]
    fn noise_has_the_requested_spread() {
        let mut s = SampledSensor::new(1000.0, 0.002, 0.0, 0.0, 3);
        let n = 20_000;
        let xs: Vec<f64> = (0..n)
            .map(|k| {
                let t = s.next_sample_time_s();
                s.sample(t, 1.0);
                f64::from(s.frame(k, t, 1.0).1) - 1.0
            })
            .collect();
        let mean = xs.iter().sum::<f64>() / n as f64;
        let sd = (xs.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / n as f64).sqrt();
        assert!(mean.abs() < 1e-4, "{mean}");
        assert!((sd - 0.002).abs() < 1e-4, "{sd}");
    }
}
