//! Impact-timing jitter (Zumel & Erdmann report about 10 ms on real paddles).
//!
//! Model: each contact takes effect as if it happened `delta ~ N(0, sigma^2)` seconds
//! later (clamped to ±4 sigma), so the restitution law uses the paddle velocity at
//! `t + delta`, `r' + r'' delta`. The ball's position and the impact time are unchanged.

use rand::SeedableRng;
use rand_distr::{Distribution, Normal};

/// A source of impact-time offsets.
pub trait Jitter {
    /// False for [`NoJitter`]: an impact's command is then the surface's own, and what
    /// checks the jittered command costs nothing.
    const ON: bool = true;
    /// The offset of the next impact, s.
    fn offset_s(&mut self) -> f64;
}

/// No jitter: every offset is zero.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct NoJitter;

impl Jitter for NoJitter {
    const ON: bool = false;
    #[inline(always)]
    fn offset_s(&mut self) -> f64 {
        0.0
    }
}

/// Gaussian impact-time jitter.
#[derive(Clone, Debug)]
pub struct GaussianJitter {
    sigma_s: f64,
    normal: Normal<f64>,
    rng: rand::rngs::StdRng,
}

impl GaussianJitter {
    /// Jitter with standard deviation `sigma_s` (s, >= 0), reproducible from `seed`.
    pub fn new(sigma_s: f64, seed: u64) -> Self {
        Self {
            sigma_s,
            normal: Normal::new(0.0, sigma_s.max(0.0))
                .unwrap_or_else(|_| Normal::new(0.0, 0.0).expect("sigma 0 is valid")),
            rng: rand::rngs::StdRng::seed_from_u64(seed),
        }
    }
}

impl Jitter for GaussianJitter {
    fn offset_s(&mut self) -> f64 {
        let d = self.normal.sample(&mut self.rng);
        d.clamp(-4.0 * self.sigma_s, 4.0 * self.sigma_s)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn gaussian_jitter_has_the_requested_spread() {
        let mut j = GaussianJitter::new(0.01, 7);
        let n = 20_000;
        let xs: Vec<f64> = (0..n).map(|_| j.offset_s()).collect();
        let mean = xs.iter().sum::<f64>() / n as f64;
        let var = xs.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / n as f64;
        // standard error of the mean 7e-5, of the sd ~5e-5
        assert!(mean.abs() < 3e-4, "{mean}");
        assert!((var.sqrt() - 0.01).abs() < 3e-4, "{}", var.sqrt());
        assert!(xs.iter().all(|x| x.abs() <= 0.04));
    }
}
