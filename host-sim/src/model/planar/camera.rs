//! The camera the tilt controller sees: the body's pose (x, y, theta) with rate, noise,
//! latency and quantization.
//!
//! Both are the one sampled sensor ([`crate::effects::sensor::Sampled`]) of three channels.
//! [`PerfectCamera`]: the true pose at every control step (as f32), sequence number = step,
//! no latency: the "off" effect, which costs nothing. [`SampledCamera`]: samples every
//! `1/rate` s (sample times are events of the plant, so the pose is exact at the sample
//! time), adds independent Gaussian noise to x, y (m) and theta (rad), rounds to the
//! quantization steps, and delivers each sample `latency` s later; each control frame
//! carries the newest delivered sample and its sequence number (a repeated number tells the
//! controller nothing new arrived). Until the first sample is delivered the frame carries
//! sample 0 (its value and number): the controller sees it as one sample, then as stale
//! repeats.

use crate::effects::sensor::{
    AtControlSteps, Clock, Delay, Exact, Latency, Measure, Measured, NoLatency, Periodic, Sampled,
};

/// A camera: sample events inside the plant, frames at control steps.
pub trait Camera {
    /// Time of the next sample, s (infinite for a camera that samples at control steps).
    fn next_sample_time_s(&self) -> f64;
    /// Take the sample due at `t_s` of the true pose `[x m, y m, theta rad]`.
    fn sample(&mut self, t_s: f64, pose: [f64; 3]);
    /// The frame content at control step `step` (time `t_s`): sequence number and the
    /// measured pose, given the true pose now (NaN before any sample).
    fn frame(&mut self, step: u64, t_s: f64, pose: [f64; 3]) -> (u32, [f32; 3]);
    /// The camera's latency, s.
    fn latency_s(&self) -> f64;
}

impl<C: Clock, M: Measure<3>, D: Delay<3>> Camera for Sampled<3, C, M, D> {
    #[inline]
    fn next_sample_time_s(&self) -> f64 {
        Sampled::next_sample_time_s(self)
    }
    #[inline]
    fn sample(&mut self, t_s: f64, pose: [f64; 3]) {
        self.take(t_s, pose);
    }
    #[inline]
    fn frame(&mut self, _step: u64, t_s: f64, pose: [f64; 3]) -> (u32, [f32; 3]) {
        self.deliver(t_s, pose)
            .map_or((0, [f32::NAN; 3]), |s| (s.seq, s.values.map(|v| v as f32)))
    }
    #[inline]
    fn latency_s(&self) -> f64 {
        Sampled::latency_s(self)
    }
}

/// The true pose at every control step, sequence number = step: the camera off.
pub type PerfectCamera = Sampled<3, AtControlSteps, Exact, NoLatency<3>>;

/// A camera's settings (the scene's camera table).
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CameraConfig {
    /// Samples per second, Hz (> 0).
    pub rate_hz: f64,
    /// Standard deviation of the position noise on x and y, m (>= 0).
    pub noise_m: f64,
    /// Standard deviation of the angle noise, rad (>= 0).
    pub noise_rad: f64,
    /// Delay from a sample to its delivery, s (>= 0).
    pub latency_s: f64,
    /// Position quantization step, m (0 = none).
    pub quantization_m: f64,
    /// Angle quantization step, rad (0 = none).
    pub quantization_rad: f64,
    /// Random seed of the noise.
    pub seed: u64,
}

impl CameraConfig {
    /// A realistic camera for the tilt table: 500 Hz, 1 mm and 5 mrad noise, 4 ms latency,
    /// 0.1 mm and 1 mrad quantization.
    pub fn realistic(seed: u64) -> Self {
        Self {
            rate_hz: 500.0,
            noise_m: 0.001,
            noise_rad: 0.005,
            latency_s: 0.004,
            quantization_m: 1e-4,
            quantization_rad: 1e-3,
            seed,
        }
    }
}

/// A sampled camera with noise, quantization and latency.
pub type SampledCamera = Sampled<3, Periodic, Measured<3>, Latency<3>>;

impl SampledCamera {
    /// A camera from `config` (validated by the caller: rate > 0, the rest >= 0).
    pub fn new(config: CameraConfig) -> Self {
        let (m, rad) = (config.noise_m, config.noise_rad);
        let (qm, qrad) = (config.quantization_m, config.quantization_rad);
        Sampled::with(
            Periodic::new(config.rate_hz),
            Measured::new([m, m, rad], [qm, qm, qrad], config.seed),
            Latency::new(config.latency_s),
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn latency_delays_delivery_and_quantization_rounds() {
        let mut c = SampledCamera::new(CameraConfig {
            rate_hz: 100.0,
            noise_m: 0.0,
            noise_rad: 0.0,
            latency_s: 0.02,
            quantization_m: 0.01,
            quantization_rad: 0.1,
            seed: 1,
        });
        for k in 0..4 {
            let t = c.next_sample_time_s();
            assert!((t - 0.01 * k as f64).abs() < 1e-15);
            let v = 0.123 + 0.111 * k as f64;
            c.sample(t, [v, -v, 0.26 * k as f64]);
        }
        // at t = 0.025 the sample taken at 0 (due 0.02) is delivered, not the one at 0.01
        let (seq, z) = c.frame(0, 0.025, [0.0; 3]);
        assert_eq!(seq, 0);
        assert!(
            (z[0] - 0.12).abs() < 1e-6 && (z[1] + 0.12).abs() < 1e-6,
            "{z:?}"
        );
        let (seq, z) = c.frame(1, 0.05, [0.0; 3]);
        assert_eq!(seq, 3);
        // 0.456 -> 0.46, theta 0.78 -> 0.8
        assert!(
            (z[0] - 0.46).abs() < 1e-6 && (z[2] - 0.8).abs() < 1e-6,
            "{z:?}"
        );
    }

    #[test]
    fn noise_has_the_requested_spread_per_coordinate() {
        let mut cfg = CameraConfig::realistic(3);
        cfg.latency_s = 0.0;
        cfg.quantization_m = 0.0;
        cfg.quantization_rad = 0.0;
        let mut c = SampledCamera::new(cfg);
        let n = 20_000u64;
        let mut sums = [0.0f64; 3];
        let mut squares = [0.0f64; 3];
        for k in 0..n {
            let t = c.next_sample_time_s();
            c.sample(t, [1.0, 2.0, 0.3]);
            let (_, z) = c.frame(k, t, [0.0; 3]);
            for (i, truth) in [1.0, 2.0, 0.3].into_iter().enumerate() {
                let e = f64::from(z[i]) - truth;
                sums[i] += e;
                squares[i] += e * e;
            }
        }
        for (i, sigma) in [0.001, 0.001, 0.005].into_iter().enumerate() {
            let mean = sums[i] / n as f64;
            let sd = (squares[i] / n as f64 - mean * mean).sqrt();
            // standard error of the sd ~ sigma / sqrt(2 n) = 0.5 % of sigma
            assert!((sd - sigma).abs() < 0.03 * sigma, "coordinate {i}: sd {sd}");
            assert!(
                mean.abs() < 5.0 * sigma / (n as f64).sqrt(),
                "coordinate {i}: {mean}"
            );
        }
    }

    #[test]
    fn perfect_camera_is_the_truth_now() {
        // one frame per control step from step 0: the sequence number is the step
        let mut c = PerfectCamera::default();
        for k in 0..7 {
            c.frame(k, 0.002 * k as f64, [0.0; 3]);
        }
        assert_eq!(
            c.frame(7, 0.014, [0.5, 0.25, -0.125]),
            (7, [0.5, 0.25, -0.125])
        );
        assert_eq!(c.next_sample_time_s(), f64::INFINITY);
    }
}
