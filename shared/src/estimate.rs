//! Fixed-rate ball-state estimator for sampled, noisy ball-height measurements.
//!
//! A steady-state alpha-beta filter around the exact ballistic model (gravity known):
//!
//! ```text
//! predict   b- = b + v dt - g dt^2/2,   v- = v - g dt
//! impact    if b- < r and v- < r':  v- = -e v- + (1 + e) r',  b- = r + (r - b-)   (restitution, eq. 4)
//! update    y = z - b-;  b = b- + a y;  v = v- + (c/dt) y     (|y| <= gate)
//! ```
//!
//! Impacts are handled by the model: the measured paddle state and the model restitution
//! `e` re-initialise the velocity at the crossing, so the filter does not have to re-converge
//! after every impact. A measurement whose innovation exceeds the gate is treated as an
//! outlier (the estimate coasts on the model); `reinit_after` outliers in a row mean the
//! model lost the ball (an unmodelled impact, a wrong restitution), and the filter
//! re-initialises from the last two measurements. Every step does a fixed amount of work.
//!
//! Sensor latency `L`: a ball sample that arrives now was taken L seconds ago, while the
//! paddle measurement is current. The filter state therefore lives at the sample time t - L
//! and its impact checks use the paddle moved back to then (`r - r' L`); the output is the
//! filter state flown L seconds forward to now, with the impact check against the current
//! paddle state.

use crate::params::{non_negative, positive, within, ParamError};
use crate::state::{restitution_velocity, BallState, PaddleState};
use serde::{Deserialize, Serialize};

/// Estimator tuning, f32 (what the controller runs).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct EstimatorParams {
    /// Position gain a of the alpha-beta update, dimensionless, in (0, 1].
    pub gain_position: f32,
    /// Velocity gain c of the alpha-beta update, dimensionless, in (0, 2) (applied as c/dt).
    pub gain_velocity: f32,
    /// Largest innovation accepted as a measurement, m (> 0).
    pub gate_m: f32,
    /// Consecutive outliers after which the estimate is re-initialised (>= 1).
    pub reinit_after: u8,
    /// Accepted updates after (re)initialisation before the estimate is reported valid.
    pub settle_samples: u8,
    /// Measurement latency to compensate, s (>= 0).
    pub latency_s: f32,
    /// Ball–paddle restitution assumed by the impact model, dimensionless, in [0, 1].
    pub restitution: f32,
}

impl Default for EstimatorParams {
    fn default() -> Self {
        Self {
            gain_position: 0.1,
            gain_velocity: 0.005,
            gate_m: 0.05,
            reinit_after: 3,
            settle_samples: 25,
            latency_s: 0.0,
            restitution: 0.8,
        }
    }
}

impl EstimatorParams {
    /// Check every field; the error names the first bad one.
    pub fn validate(&self) -> Result<(), ParamError> {
        within(
            "estimator.gain_position",
            self.gain_position,
            f32::MIN_POSITIVE,
            1.0,
        )?;
        within(
            "estimator.gain_velocity",
            self.gain_velocity,
            f32::MIN_POSITIVE,
            1.999,
        )?;
        positive("estimator.gate_m", self.gate_m)?;
        if self.reinit_after == 0 {
            return Err(ParamError::NotPositive("estimator.reinit_after"));
        }
        non_negative("estimator.latency_s", self.latency_s)?;
        within("estimator.restitution", self.restitution, 0.0, 1.0)?;
        Ok(())
    }
}

/// Where the estimator is in its cycle.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Phase {
    /// No measurement yet.
    Empty,
    /// One measurement (the height), waiting for a second to difference.
    OneSample(f32),
    /// Filtering; `accepted` updates since (re)initialisation.
    Tracking { accepted: u8 },
}

/// The estimator's output: the state at the current time (latency compensated).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Estimate {
    /// Estimated ball state now.
    pub ball: BallState<f32>,
    /// True once the filter has settled after its last (re)initialisation.
    pub valid: bool,
    /// True if the model predicted an impact in this step.
    pub impact: bool,
}

/// Alpha-beta ball estimator with a ballistic model and impact re-initialisation.
#[derive(Clone, Debug)]
pub struct BallEstimator {
    params: EstimatorParams,
    dt_s: f32,
    gravity_mps2: f32,
    phase: Phase,
    /// State at the time of the last measurement.
    ball: BallState<f32>,
    outliers: u8,
    last_z: f32,
}

impl BallEstimator {
    /// An estimator for samples every `dt_s` seconds (> 0) under gravity `gravity_mps2` (> 0).
    pub fn new(params: EstimatorParams, dt_s: f32, gravity_mps2: f32) -> Result<Self, ParamError> {
        params.validate()?;
        positive("dt_s", dt_s)?;
        positive("gravity_mps2", gravity_mps2)?;
        Ok(Self {
            params,
            dt_s,
            gravity_mps2,
            phase: Phase::Empty,
            ball: BallState::default(),
            outliers: 0,
            last_z: 0.0,
        })
    }

    /// Forget everything (after a fault): the next samples re-initialise.
    pub fn reset(&mut self) {
        self.phase = Phase::Empty;
        self.outliers = 0;
    }

    /// Advance one sample period with the measured ball height `z_m` (finite, checked by the
    /// caller) and the measured paddle state; returns the latency-compensated estimate.
    pub fn update(&mut self, z_m: f32, paddle: &PaddleState<f32>) -> Estimate {
        let dt = self.dt_s;
        let mut impact = false;
        match self.phase {
            Phase::Empty => {
                self.phase = Phase::OneSample(z_m);
            }
            Phase::OneSample(z0) => {
                self.initialise(z0, z_m);
            }
            Phase::Tracking { accepted } => {
                let mut pred = self.ball.flown(dt, self.gravity_mps2);
                impact = self.apply_impact(&mut pred, &self.paddle_at_sample_time(paddle));
                let innovation = z_m - pred.height_m;
                if innovation.abs() <= self.params.gate_m {
                    pred.height_m += self.params.gain_position * innovation;
                    pred.velocity_mps += (self.params.gain_velocity / dt) * innovation;
                    self.ball = pred;
                    self.outliers = 0;
                    self.phase = Phase::Tracking {
                        accepted: accepted.saturating_add(1),
                    };
                } else {
                    self.outliers = self.outliers.saturating_add(1);
                    if self.outliers >= self.params.reinit_after {
                        self.initialise(self.last_z, z_m);
                    } else {
                        self.ball = pred;
                    }
                }
            }
        }
        self.last_z = z_m;
        self.output(paddle, impact)
    }

    /// Advance one sample period without a measurement (the sample was stale or rejected).
    pub fn coast(&mut self, paddle: &PaddleState<f32>) -> Estimate {
        let mut impact = false;
        if let Phase::Tracking { .. } = self.phase {
            let mut pred = self.ball.flown(self.dt_s, self.gravity_mps2);
            impact = self.apply_impact(&mut pred, &self.paddle_at_sample_time(paddle));
            self.ball = pred;
        }
        self.output(paddle, impact)
    }

    fn initialise(&mut self, z0: f32, z1: f32) {
        let dt = self.dt_s;
        // b(t) = z0 + v0 t - g t^2/2 through both samples; velocity at the second one
        self.ball = BallState::new(z1, (z1 - z0) / dt - 0.5 * self.gravity_mps2 * dt);
        self.outliers = 0;
        self.phase = Phase::Tracking { accepted: 0 };
    }

    /// The restitution law at a predicted crossing of the paddle surface (eq. 4).
    fn apply_impact(&self, pred: &mut BallState<f32>, paddle: &PaddleState<f32>) -> bool {
        if pred.height_m < paddle.height_m && pred.velocity_mps < paddle.velocity_mps {
            let e = self.params.restitution;
            pred.velocity_mps = restitution_velocity(pred.velocity_mps, paddle.velocity_mps, e);
            // reflect the penetration: the ball spent it moving away after the impact
            pred.height_m = paddle.height_m + e * (paddle.height_m - pred.height_m);
            true
        } else {
            false
        }
    }

    /// The paddle (measured now) moved back to the time the ball sample was taken.
    fn paddle_at_sample_time(&self, paddle: &PaddleState<f32>) -> PaddleState<f32> {
        PaddleState::new(
            paddle.height_m - paddle.velocity_mps * self.params.latency_s,
            paddle.velocity_mps,
        )
    }

    fn output(&self, paddle: &PaddleState<f32>, impact: bool) -> Estimate {
        let valid = matches!(self.phase, Phase::Tracking { accepted } if accepted >= self.params.settle_samples);
        let mut now = self.ball.flown(self.params.latency_s, self.gravity_mps2);
        let impact = self.apply_impact(&mut now, paddle) || impact;
        Estimate {
            ball: now,
            valid,
            impact,
        }
    }

    /// The (unvalidated-range) estimate at the last measurement time, for telemetry.
    pub fn state_at_measurement(&self) -> BallState<f32> {
        self.ball
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const G: f32 = 9.81;

    #[test]
    fn noiseless_flight_is_tracked_exactly_after_two_samples() {
        let dt = 0.002;
        let mut est = BallEstimator::new(EstimatorParams::default(), dt, G).unwrap();
        let truth = BallState::new(1.0f32, 0.5);
        let paddle = PaddleState::new(-0.1, 0.0);
        let mut out = Estimate::default();
        for k in 0..60 {
            out = est.update(truth.flown(k as f32 * dt, G).height_m, &paddle);
        }
        let t = truth.flown(59.0 * dt, G);
        assert!(out.valid);
        assert!((out.ball.height_m - t.height_m).abs() < 1e-5);
        assert!((out.ball.velocity_mps - t.velocity_mps).abs() < 1e-3);
    }

    #[test]
    fn impact_model_reinitialises_velocity_at_the_paddle() {
        let dt = 0.002;
        let e = 0.8;
        let params = EstimatorParams {
            restitution: e,
            ..EstimatorParams::default()
        };
        let mut est = BallEstimator::new(params, dt, G).unwrap();
        let paddle = PaddleState::new(0.0, 0.0);
        // ball falls from 0.3 m; true bounce at t0 = sqrt(2 h / g)
        let h0 = 0.3f64;
        let g = G as f64;
        let t0 = (2.0 * h0 / g).sqrt();
        let v0 = g * t0;
        let truth = |t: f64| -> f64 {
            if t < t0 {
                h0 - 0.5 * g * t * t
            } else {
                let s = t - t0;
                (e as f64) * v0 * s - 0.5 * g * s * s
            }
        };
        let mut out = Estimate::default();
        let n = ((t0 + 0.05) / dt as f64) as usize;
        for k in 0..n {
            out = est.update(truth(k as f64 * dt as f64) as f32, &paddle);
        }
        let t = (n - 1) as f64 * dt as f64;
        let v_true = (e as f64) * v0 - g * (t - t0);
        assert!(out.valid, "estimate should stay valid through the impact");
        assert!(
            (out.ball.velocity_mps as f64 - v_true).abs() < 0.05,
            "{} vs {v_true}",
            out.ball.velocity_mps
        );
    }

    #[test]
    fn persistent_outliers_reinitialise_instead_of_diverging() {
        let dt = 0.002;
        let mut est = BallEstimator::new(EstimatorParams::default(), dt, G).unwrap();
        let paddle = PaddleState::new(-1.0, 0.0);
        for k in 0..40 {
            est.update(
                BallState::new(1.0f32, 0.0).flown(k as f32 * dt, G).height_m,
                &paddle,
            );
        }
        // the ball jumps (an unmodelled hit): the estimate must follow within a few samples
        let mut out = Estimate::default();
        for k in 0..80 {
            let z = BallState::new(2.0f32, 1.0).flown(k as f32 * dt, G).height_m;
            out = est.update(z, &paddle);
        }
        let t = BallState::new(2.0f32, 1.0).flown(79.0 * dt, G);
        assert!((out.ball.height_m - t.height_m).abs() < 1e-3);
        assert!((out.ball.velocity_mps - t.velocity_mps).abs() < 1e-2);
    }

    #[test]
    fn latency_is_compensated_by_prediction() {
        let dt = 0.002;
        let latency = 0.006;
        let params = EstimatorParams {
            latency_s: latency,
            ..EstimatorParams::default()
        };
        let mut est = BallEstimator::new(params, dt, G).unwrap();
        let truth = BallState::new(1.0f32, 2.0);
        let paddle = PaddleState::new(-1.0, 0.0);
        let mut out = Estimate::default();
        for k in 0..50 {
            // the sample taken at k dt arrives now, at k dt + latency
            out = est.update(truth.flown(k as f32 * dt, G).height_m, &paddle);
        }
        let now = truth.flown(49.0 * dt + latency, G);
        assert!((out.ball.height_m - now.height_m).abs() < 1e-5);
    }

    /// Regression: with latency, an impact must be predicted when the ball meets the paddle
    /// now, not when it meets where the paddle will be L seconds later (which flipped the
    /// estimate, and the mirror reference, up to a control period early).
    #[test]
    fn latency_compensated_impact_is_not_predicted_early() {
        let dt = 0.002f64;
        let latency = 0.004f64;
        let e = 0.8f64;
        let g = G as f64;
        let params = EstimatorParams {
            latency_s: latency as f32,
            restitution: e as f32,
            ..EstimatorParams::default()
        };
        let mut est = BallEstimator::new(params, dt as f32, G).unwrap();
        // paddle rises at 1 m/s from -0.1 m; ball falls from 1 m; meet when
        // 1 - g t^2/2 = -0.1 + t  (the positive root)
        let vp = 1.0f64;
        let paddle = |t: f64| -0.1 + vp * t;
        let t_hit = (-vp + (vp * vp + 2.0 * g * 1.1).sqrt()) / g;
        let ball = |t: f64| {
            if t < t_hit {
                1.0 - 0.5 * g * t * t
            } else {
                let v_in = -g * t_hit;
                let v_out = -e * v_in + (1.0 + e) * vp;
                let s = t - t_hit;
                paddle(t_hit) + v_out * s - 0.5 * g * s * s
            }
        };
        let steps = ((t_hit + 0.03) / dt) as usize;
        let mut first_up = None;
        for k in 3..steps {
            let now = k as f64 * dt;
            let p = PaddleState::new(paddle(now) as f32, vp as f32);
            let out = est.update(ball(now - latency) as f32, &p);
            if out.valid && out.ball.velocity_mps > 0.0 && first_up.is_none() {
                first_up = Some(now);
            }
        }
        let first_up = first_up.expect("the estimate never saw the bounce");
        // the estimate turns upward at the first sample at or after the true impact
        assert!(
            first_up >= t_hit - 1e-9,
            "impact predicted {:.4} s early",
            t_hit - first_up
        );
        assert!(
            first_up < t_hit + dt + 1e-9,
            "impact predicted {:.4} s late",
            first_up - t_hit
        );
    }

    #[test]
    fn bad_params_are_named() {
        let p = EstimatorParams {
            gain_position: 0.0,
            ..EstimatorParams::default()
        };
        assert_eq!(
            BallEstimator::new(p, 0.002, G).unwrap_err(),
            ParamError::OutOfRange("estimator.gain_position")
        );
        assert_eq!(
            BallEstimator::new(EstimatorParams::default(), 0.0, G).unwrap_err(),
            ParamError::NotPositive("dt_s")
        );
    }
}
