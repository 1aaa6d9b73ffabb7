//! The ball-height sensor the controller sees.
//!
//! [`PerfectSensor`]: the frame at each control step carries the true height (as f32).
//! [`SampledSensor`]: samples every `1/rate` s, adds Gaussian noise, quantizes, and
//! delivers each sample `latency` s later; each control frame carries the newest delivered
//! sample and its sequence number (a repeated number tells the controller nothing new
//! arrived). Until the first sample is delivered the frame repeats sample 0's value.

use rand::SeedableRng;
use rand_distr::{Distribution, Normal};
use std::collections::VecDeque;

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
    normal: Option<Normal<f64>>,
    rng: rand::rngs::StdRng,
    next_index: u64,
    /// `next_index * period_s`, s (kept: the loop asks for it several times per step).
    next_time_s: f64,
    /// (delivery time, sequence, value)
    pending: VecDeque<(f64, u32, f32)>,
    latest: Option<(u32, f32)>,
}

/// Most samples in flight (taken, not yet delivered): the validator refuses a
/// `sensor.latency_s` x `sensor.rate_hz` above it, so none is ever dropped.
pub const MAX_PENDING: usize = 4096;

impl SampledSensor {
    /// A sensor sampling at `rate_hz` (> 0) with noise `sigma_m` (m), latency `latency_s`
    /// (s) and quantization `quantization_m` (m, 0 = none), reproducible from `seed`.
    pub fn new(rate_hz: f64, sigma_m: f64, latency_s: f64, quantization_m: f64, seed: u64) -> Self {
        Self {
            period_s: 1.0 / rate_hz,
            latency_s,
            quantization_m,
            normal: (sigma_m > 0.0)
                .then(|| Normal::new(0.0, sigma_m).ok())
                .flatten(),
            rng: rand::rngs::StdRng::seed_from_u64(seed),
            next_index: 0,
            next_time_s: 0.0,
            pending: VecDeque::new(),
            latest: None,
        }
    }

    fn measure(&mut self, height_m: f64) -> f32 {
        let mut z = height_m;
        if let Some(n) = &self.normal {
            z += n.sample(&mut self.rng);
        }
        if self.quantization_m > 0.0 {
            z = round_half_away(z / self.quantization_m) * self.quantization_m;
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
    let t = x as i64 as f64;
    let r = if x - t >= 0.5 {
        t + 1.0
    } else if x - t <= -0.5 {
        t - 1.0
    } else {
        t
    };
    r.copysign(x)
}

impl Sensor for SampledSensor {
    #[inline]
    fn next_sample_time_s(&self) -> f64 {
        self.next_time_s
    }

    fn sample(&mut self, t_s: f64, height_m: f64) {
        let z = self.measure(height_m);
        let seq = self.next_index as u32;
        if self.pending.len() >= MAX_PENDING {
            self.pending.pop_front();
        }
        self.pending.push_back((t_s + self.latency_s, seq, z));
        self.next_index += 1;
        self.next_time_s = self.next_index as f64 * self.period_s;
    }

    fn frame(&mut self, _step: u64, t_s: f64, _height_m: f64) -> (u32, f32) {
        // deliver everything due by now (1e-9 s of slack for the rounding of t)
        while let Some(&(due, seq, z)) = self.pending.front() {
            if due <= t_s + 1e-9 {
                self.latest = Some((seq, z));
                self.pending.pop_front();
            } else {
                break;
            }
        }
        match self.latest {
            Some(l) => l,
            None => self
                .pending
                .front()
                .map_or((0, f32::NAN), |&(_, s, z)| (s, z)),
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
