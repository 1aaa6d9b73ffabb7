//! The hopper's sensor: leg compression, foot switch and (optionally) body height, sampled
//! at a rate, with noise, quantization and latency: the one sampled sensor
//! ([`crate::effects::sensor::Sampled`]) of three channels (compression, foot switch as 0
//! or 1, height), each effect a type parameter with a zero-sized "off" type, so a plant
//! assembled without it pays nothing (rate: [`AtControlSteps`] or [`Periodic`]; noise and
//! quantization: [`Exact`] or [`Measured`]; latency: [`NoLatency`] or [`Latency`]).
//!
//! The foot switch is exact (no noise, no quantization) but is delayed with its sample;
//! compression and height share the noise's seed and the quantization step.
//! A control frame carries the newest delivered sample; before the first delivery (the
//! first `latency_s` of a run) it carries the first sample taken.

pub use crate::effects::sensor::{
    AtControlSteps, Clock, Delay, Exact, Latency, Measure, Measured, NoLatency, Periodic,
};
use crate::effects::sensor::{Sample, Sampled};
use dexter_core::hop_control::HopFrame;

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
pub struct HopSample {
    /// Sequence number.
    pub seq: u32,
    /// Compression, m.
    pub compression_m: f64,
    /// Foot switch.
    pub contact: bool,
    /// Body height, m.
    pub height_m: f64,
}

/// Noise (standard deviations on compression and height, m; 0 = none) and quantization
/// (step, m; 0 = none) of the hopper's channels, from `seed`.
pub fn measured(
    compression_sigma_m: f64,
    height_sigma_m: f64,
    step_m: f64,
    seed: u64,
) -> Measured<3> {
    Measured::new(
        [compression_sigma_m, 0.0, height_sigma_m],
        [step_m, 0.0, step_m],
        seed,
    )
}

/// The sensor, assembled from its effects.
#[derive(Clone, Debug)]
pub struct HopSensor<C, M, D> {
    sensor: Sampled<3, C, M, D>,
    body_height: bool,
}

impl<C: Clock, M: Measure<3>, D: Delay<3>> HopSensor<C, M, D> {
    /// A sensor; `body_height`: whether frames carry the body height.
    pub fn new(clock: C, measure: M, delay: D, body_height: bool) -> Self {
        Self {
            sensor: Sampled::with(clock, measure, delay),
            body_height,
        }
    }

    /// Time of the next sample between control steps, s (infinite: none).
    #[inline]
    pub fn next_sample_time_s(&self) -> f64 {
        self.sensor.next_sample_time_s()
    }

    /// Take a sample of `truth` at `t_s`.
    #[inline]
    pub fn sample(&mut self, t_s: f64, truth: Truth) {
        self.sensor.take(t_s, channels(truth));
    }

    /// The frame at a control step at `t_s` (taking the step's sample first when the sensor
    /// samples at control steps), and the measured sample it carries.
    #[inline]
    pub fn frame(&mut self, t_s: f64, truth: Truth) -> (HopFrame, Option<HopSample>) {
        match self
            .sensor
            .deliver(t_s, channels(truth))
            .map(measured_sample)
        {
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

/// The sensor's channels of `truth`.
#[inline]
fn channels(truth: Truth) -> [f64; 3] {
    [
        truth.compression_m,
        if truth.contact { 1.0 } else { 0.0 },
        truth.height_m,
    ]
}

/// A sample of the three channels as the hopper reads it.
#[inline]
fn measured_sample(s: Sample<3>) -> HopSample {
    let [compression_m, contact, height_m] = s.values;
    HopSample {
        seq: s.seq,
        compression_m,
        contact: contact != 0.0,
        height_m,
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
        let mut s = HopSensor::new(AtControlSteps::default(), Exact, NoLatency::default(), true);
        for k in 0..3 {
            let (f, _) = s.frame(k as f64 * 1e-3, truth(0.01 * k as f64));
            assert_eq!(f.seq, k);
            assert_eq!(f.leg_compression_m, (0.01 * k as f64) as f32);
            assert_eq!(f.contact, k > 0);
            assert_eq!(f.body_height(), Some((0.5 - 0.01 * k as f64) as f32));
        }
        assert_eq!(std::mem::size_of::<Exact>(), 0);
    }

    #[test]
    fn latency_quantization_and_noise() {
        // 2.5 ms latency at 1 kHz: the frame at 10 ms carries the sample of 7 ms (due 9.5 ms)
        let mut s = HopSensor::new(
            AtControlSteps::default(),
            measured(0.0, 0.0, 1e-3, 1),
            Latency::new(2.5e-3),
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
        assert!(f.contact, "the foot switch is neither noisy nor quantized");
        assert_eq!(f.body_height(), None);
        // noise: sample spread matches sigma, and the height channel is left alone
        let mut n = measured(2e-3, 0.0, 0.0, 3);
        let xs: Vec<[f64; 3]> = (0..20_000).map(|_| n.measure([0.0, 1.0, 1.0])).collect();
        let sd = (xs.iter().map(|x| x[0] * x[0]).sum::<f64>() / xs.len() as f64).sqrt();
        assert!((sd - 2e-3).abs() < 1e-4, "{sd}");
        assert!(xs.iter().all(|x| x[1] == 1.0 && x[2] == 1.0));
    }
}
