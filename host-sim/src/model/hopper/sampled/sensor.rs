//! The hopper's sensor: leg compression, foot switch and (optionally) body height, sampled
//! at a rate, with noise, quantization and latency. Each effect is a type parameter with a
//! zero-sized "off" type, so a plant assembled without it pays nothing:
//!
//! | effect | off | on |
//! | --- | --- | --- |
//! | rate | [`AtControlSteps`]: one sample at every control step, sequence number = step | [`Periodic`]: samples every 1/rate s, the plant stops at each |
//! | noise | [`NoNoise`] | [`GaussianNoise`]: N(0, sigma) on compression and height (seeded) |
//! | quantization | [`NoQuantization`] | [`Quantization`]: round to a multiple of q |
//! | latency | [`NoLatency`]: a sample is seen at once | [`Latency`]: seen `latency_s` after it was taken |
//!
//! The foot switch is exact (no noise, no quantization) but is delayed with its sample.
//! A control frame carries the newest delivered sample; before the first delivery (the
//! first `latency_s` of a run) it carries the first sample taken.

use dexter_core::hop_control::HopFrame;
use rand::SeedableRng;
use rand_distr::{Distribution, Normal};
use std::collections::VecDeque;

/// What the sensor measures, true values.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Truth {
    /// Leg compression chi_l - chi in stance, 0 in flight, m.
    pub compression_m: f64,
    /// Foot on the ground.
    pub contact: bool,
    /// Body height chi, m.
    pub height_m: f64,
}

/// One measured sample.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Measured {
    /// Sequence number.
    pub seq: u32,
    /// Compression, m.
    pub compression_m: f64,
    /// Foot switch.
    pub contact: bool,
    /// Body height, m.
    pub height_m: f64,
}

/// When samples are taken.
pub trait Clock {
    /// Time of the next sample between control steps, s (infinite: none, samples are taken
    /// at control steps).
    fn next_sample_time_s(&self) -> f64;
    /// True if a sample is taken at every control step.
    fn at_control_steps(&self) -> bool;
    /// Mark the next sample taken; its sequence number.
    fn advance(&mut self) -> u32;
}

/// One sample at every control step.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct AtControlSteps {
    next: u32,
}

impl Clock for AtControlSteps {
    #[inline(always)]
    fn next_sample_time_s(&self) -> f64 {
        f64::INFINITY
    }
    #[inline(always)]
    fn at_control_steps(&self) -> bool {
        true
    }
    #[inline(always)]
    fn advance(&mut self) -> u32 {
        let s = self.next;
        self.next = self.next.wrapping_add(1);
        s
    }
}

/// Samples every `1/rate` s, at their own times.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Periodic {
    period_s: f64,
    next_index: u64,
}

impl Periodic {
    /// Samples at `rate_hz` (> 0), the first at t = 0.
    pub fn new(rate_hz: f64) -> Self {
        Self {
            period_s: 1.0 / rate_hz,
            next_index: 0,
        }
    }
}

impl Clock for Periodic {
    fn next_sample_time_s(&self) -> f64 {
        self.next_index as f64 * self.period_s
    }
    fn at_control_steps(&self) -> bool {
        false
    }
    fn advance(&mut self) -> u32 {
        let s = self.next_index as u32;
        self.next_index += 1;
        s
    }
}

/// Measurement noise.
pub trait Noise {
    /// (compression, height) with noise added.
    fn perturb(&mut self, compression_m: f64, height_m: f64) -> (f64, f64);
}

/// No noise.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct NoNoise;

impl Noise for NoNoise {
    #[inline(always)]
    fn perturb(&mut self, compression_m: f64, height_m: f64) -> (f64, f64) {
        (compression_m, height_m)
    }
}

/// Gaussian noise, reproducible from a seed.
#[derive(Clone, Debug)]
pub struct GaussianNoise {
    compression: Option<Normal<f64>>,
    height: Option<Normal<f64>>,
    rng: rand::rngs::StdRng,
}

impl GaussianNoise {
    /// Standard deviations (m, >= 0, finite; anything else counts as 0) on the compression
    /// and the height.
    pub fn new(compression_sigma_m: f64, height_sigma_m: f64, seed: u64) -> Self {
        let normal = |s: f64| (s > 0.0).then(|| Normal::new(0.0, s).ok()).flatten();
        Self {
            compression: normal(compression_sigma_m),
            height: normal(height_sigma_m),
            rng: rand::rngs::StdRng::seed_from_u64(seed),
        }
    }
}

impl Noise for GaussianNoise {
    fn perturb(&mut self, compression_m: f64, height_m: f64) -> (f64, f64) {
        let mut draw = |n: &Option<Normal<f64>>| n.map_or(0.0, |n| n.sample(&mut self.rng));
        (
            compression_m + draw(&self.compression),
            height_m + draw(&self.height),
        )
    }
}

/// Quantization of compression and height.
pub trait Quantizer {
    /// The quantized value.
    fn quantize(&self, value_m: f64) -> f64;
}

/// No quantization.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct NoQuantization;

impl Quantizer for NoQuantization {
    #[inline(always)]
    fn quantize(&self, value_m: f64) -> f64 {
        value_m
    }
}

/// Rounding to the nearest multiple of `step_m`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Quantization {
    /// q, m (> 0).
    pub step_m: f64,
}

impl Quantizer for Quantization {
    fn quantize(&self, value_m: f64) -> f64 {
        (value_m / self.step_m).round() * self.step_m
    }
}

/// When a sample becomes visible to the controller.
pub trait Delay {
    /// A sample taken at `t_s`.
    fn push(&mut self, t_s: f64, sample: Measured);
    /// The newest sample visible at `t_s`.
    fn latest(&mut self, t_s: f64) -> Option<Measured>;
}

/// A sample is visible at once.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct NoLatency {
    last: Option<Measured>,
}

impl Delay for NoLatency {
    #[inline(always)]
    fn push(&mut self, _t_s: f64, sample: Measured) {
        self.last = Some(sample);
    }
    #[inline(always)]
    fn latest(&mut self, _t_s: f64) -> Option<Measured> {
        self.last
    }
}

/// A sample is visible `latency_s` after it was taken.
#[derive(Clone, Debug)]
pub struct Latency {
    latency_s: f64,
    pending: VecDeque<(f64, Measured)>,
    last: Option<Measured>,
    capacity: usize,
}

impl Latency {
    /// A delay of `latency_s` (s, >= 0) for samples every `sample_period_s` (s, > 0): at
    /// most latency / period + 2 samples are in flight.
    pub fn new(latency_s: f64, sample_period_s: f64) -> Self {
        let capacity = (latency_s / sample_period_s).ceil() as usize + 2;
        Self {
            latency_s,
            pending: VecDeque::with_capacity(capacity),
            last: None,
            capacity,
        }
    }
}

/// Slack for the rounding of sample and control times, s.
const TIME_SLACK_S: f64 = 1e-9;

impl Delay for Latency {
    fn push(&mut self, t_s: f64, sample: Measured) {
        if self.pending.len() >= self.capacity {
            // cannot happen for the configured rate; keeps memory bounded regardless
            if let Some((_, s)) = self.pending.pop_front() {
                self.last = Some(s);
            }
        }
        self.pending.push_back((t_s + self.latency_s, sample));
    }

    fn latest(&mut self, t_s: f64) -> Option<Measured> {
        while let Some(&(due, s)) = self.pending.front() {
            if due > t_s + TIME_SLACK_S {
                break;
            }
            self.last = Some(s);
            self.pending.pop_front();
        }
        self.last.or_else(|| self.pending.front().map(|&(_, s)| s))
    }
}

/// The sensor, assembled from its four effects.
#[derive(Clone, Debug)]
pub struct HopSensor<C, N, Q, D> {
    clock: C,
    noise: N,
    quantizer: Q,
    delay: D,
    body_height: bool,
}

impl<C: Clock, N: Noise, Q: Quantizer, D: Delay> HopSensor<C, N, Q, D> {
    /// A sensor; `body_height`: whether frames carry the body height.
    pub fn new(clock: C, noise: N, quantizer: Q, delay: D, body_height: bool) -> Self {
        Self {
            clock,
            noise,
            quantizer,
            delay,
            body_height,
        }
    }

    /// Time of the next sample between control steps, s (infinite: none).
    #[inline]
    pub fn next_sample_time_s(&self) -> f64 {
        self.clock.next_sample_time_s()
    }

    /// Take a sample of `truth` at `t_s`.
    #[inline]
    pub fn sample(&mut self, t_s: f64, truth: Truth) {
        let seq = self.clock.advance();
        let (c, h) = self.noise.perturb(truth.compression_m, truth.height_m);
        let m = Measured {
            seq,
            compression_m: self.quantizer.quantize(c),
            contact: truth.contact,
            height_m: self.quantizer.quantize(h),
        };
        self.delay.push(t_s, m);
    }

    /// The frame at a control step at `t_s` (taking the step's sample first when the sensor
    /// samples at control steps), and the measured sample it carries.
    #[inline]
    pub fn frame(&mut self, t_s: f64, truth: Truth) -> (HopFrame, Option<Measured>) {
        if self.clock.at_control_steps() {
            self.sample(t_s, truth);
        }
        match self.delay.latest(t_s) {
            Some(m) => (
                HopFrame {
                    seq: m.seq,
                    leg_compression_m: m.compression_m as f32,
                    contact: m.contact,
                    has_body_height: self.body_height,
                    body_height_m: if self.body_height {
                        m.height_m as f32
                    } else {
                        0.0
                    },
                },
                Some(m),
            ),
            // a periodic sensor has taken its first sample at t = 0, before any frame
            None => (HopFrame::default(), None),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn truth(c: f64) -> Truth {
        Truth {
            compression_m: c,
            contact: c > 0.0,
            height_m: 0.5 - c,
        }
    }

    #[test]
    fn off_sensor_passes_the_truth_with_the_step_as_sequence() {
        let mut s = HopSensor::new(
            AtControlSteps::default(),
            NoNoise,
            NoQuantization,
            NoLatency::default(),
            true,
        );
        for k in 0..3 {
            let (f, _) = s.frame(k as f64 * 1e-3, truth(0.01 * k as f64));
            assert_eq!(f.seq, k);
            assert_eq!(f.leg_compression_m, (0.01 * k as f64) as f32);
            assert_eq!(f.contact, k > 0);
            assert_eq!(f.body_height(), Some((0.5 - 0.01 * k as f64) as f32));
        }
        assert_eq!(std::mem::size_of::<NoNoise>(), 0);
        assert_eq!(std::mem::size_of::<NoQuantization>(), 0);
    }

    #[test]
    fn latency_quantization_and_noise() {
        // 2.5 ms latency at 1 kHz: the frame at 10 ms carries the sample of 7 ms (due 9.5 ms)
        let mut s = HopSensor::new(
            AtControlSteps::default(),
            NoNoise,
            Quantization { step_m: 1e-3 },
            Latency::new(2.5e-3, 1e-3),
            false,
        );
        let mut last = None;
        for k in 0..=10u32 {
            last = Some(s.frame(f64::from(k) * 1e-3, truth(0.0101 * f64::from(k))).0);
        }
        let f = last.unwrap();
        assert_eq!(f.seq, 7);
        assert!(
            (f64::from(f.leg_compression_m) - 0.071).abs() < 1e-7,
            "{f:?}"
        );
        assert_eq!(f.body_height(), None);
        // noise: sample spread matches sigma
        let mut n = GaussianNoise::new(2e-3, 0.0, 3);
        let xs: Vec<f64> = (0..20_000).map(|_| n.perturb(0.0, 1.0).0).collect();
        let sd = (xs.iter().map(|x| x * x).sum::<f64>() / xs.len() as f64).sqrt();
        assert!((sd - 2e-3).abs() < 1e-4, "{sd}");
        assert_eq!(n.perturb(0.0, 1.0).1, 1.0);
    }
}
