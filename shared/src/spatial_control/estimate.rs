//! The spatial juggler's fixed-rate ball estimator: the line juggler's alpha-beta filter
//! ([`crate::estimate`]) on each of the three axes around the exact ballistic model in 3-D,
//! with the paddle's restitution law at a predicted crossing of the paddle's plane.
//!
//! ```text
//! predict   b- = b + b' dt + a_p dt^2/2,   b'- = b' + a_p dt,    a_p = (0, 0, -gamma)
//! impact    if n . b_prev > 0 >= n . b- and the ball approaches the paddle:
//!           b'- = b'- - (1 + e) (n . (b'- - v_p)) n,  b- = b- - (1 + e) (n . b-) n
//! update    y = z - b-;  b = b- + a y;  b' = b'- + (c/dt) y      (|y|_inf <= gate)
//! ```
//!
//! n and v_p are the paddle's normal and velocity ([`PaddleFrame`]) from the measured joints
//! moved back by the camera's latency L; the filter state lives at the sample time t - L and
//! the output is it flown L forward, as in [`crate::estimate`]. Gate, outliers,
//! re-initialisation from two samples and the settle count are that estimator's, with its
//! [`EstimatorParams`]; the innovation's largest component is gated. Every step does a fixed
//! amount of work and no square root.

use crate::estimate::EstimatorParams;
use crate::math::Real;
use crate::params::ParamError;
use crate::spatial::{PaddleFrame, SpatialBall};

/// Where the estimator is in its cycle.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Phase {
    /// No measurement yet.
    Empty,
    /// One measurement, waiting for a second to difference.
    OneSample([f32; 3]),
    /// Filtering; `accepted` updates since (re)initialisation.
    Tracking {
        /// Accepted updates.
        accepted: u8,
    },
}

/// The estimator's output: the ball now (latency compensated) and whether it is valid.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct SpatialEstimate {
    /// The ball now, m and m/s.
    pub ball: SpatialBall<f32>,
    /// At least `settle_samples` accepted updates since (re)initialisation.
    pub valid: bool,
}

/// A three-axis alpha-beta ball estimator with the paddle's restitution law.
#[derive(Clone, Debug)]
pub struct SpatialEstimator {
    params: EstimatorParams,
    dt_s: f32,
    inv_dt_per_s: f32,
    gain_velocity_per_s: f32,
    gravity_mps2: f32,
    phase: Phase,
    /// The ball at the last sample time.
    ball: SpatialBall<f32>,
    /// n . b after the last step (the side of the paddle the ball was on), m.
    last_gap_m: f32,
    outliers: u8,
    last_z: [f32; 3],
}

impl SpatialEstimator {
    /// An estimator sampled every `dt_s` under gravity `gravity_mps2`; the error names the
    /// first bad parameter.
    pub fn new(params: EstimatorParams, dt_s: f32, gravity_mps2: f32) -> Result<Self, ParamError> {
        params.validate()?;
        let dt_s = crate::params::positive("dt_s", dt_s)?;
        Ok(Self {
            params,
            dt_s,
            inv_dt_per_s: 1.0 / dt_s,
            gain_velocity_per_s: params.gain_velocity / dt_s,
            gravity_mps2,
            phase: Phase::Empty,
            ball: SpatialBall::default(),
            last_gap_m: 0.0,
            outliers: 0,
            last_z: [0.0; 3],
        })
    }

    /// Forget the ball (after a fault).
    pub fn reset(&mut self) {
        self.phase = Phase::Empty;
        self.outliers = 0;
        self.last_gap_m = 0.0;
    }

    /// The ball at the last sample time, m and m/s (telemetry).
    pub fn state_at_measurement(&self) -> SpatialBall<f32> {
        self.ball
    }

    /// One period: `z_m` is the new camera sample (finite, checked by the caller) or `None`
    /// (coast), `paddle` the paddle at the sample time.
    pub fn step(&mut self, z_m: Option<&[f32; 3]>, paddle: &PaddleFrame<f32>) -> SpatialEstimate {
        match (self.phase, z_m) {
            (Phase::Empty, Some(z)) => self.phase = Phase::OneSample(*z),
            (Phase::OneSample(z0), Some(z)) => self.initialise(&z0, z, paddle),
            (Phase::Tracking { accepted }, z) => {
                let pred = self.predict(paddle);
                match z {
                    Some(z) => self.correct(pred, z, accepted, paddle),
                    None => self.ball = pred,
                }
            }
            (_, None) => {}
        }
        if let Some(z) = z_m {
            self.last_z = *z;
        }
        self.output()
    }

    /// The ballistic flight over one period and the restitution law at a crossing.
    fn predict(&mut self, paddle: &PaddleFrame<f32>) -> SpatialBall<f32> {
        let mut pred = self.ball.flown(self.dt_s, self.gravity_mps2);
        let mut gap = paddle.gap_m(&pred.position_m);
        if self.last_gap_m > 0.0 && gap <= 0.0 {
            if let Some(v) = paddle.bounce(&pred, self.params.restitution) {
                pred.velocity_mps = v;
                let back = (1.0 + self.params.restitution) * gap;
                for (p, n) in pred.position_m.iter_mut().zip(paddle.normal) {
                    *p -= back * n;
                }
                gap = paddle.gap_m(&pred.position_m);
            }
        }
        self.last_gap_m = gap;
        pred
    }

    /// The alpha-beta update with the gate; outliers in a row re-initialise.
    fn correct(
        &mut self,
        mut pred: SpatialBall<f32>,
        z: &[f32; 3],
        accepted: u8,
        paddle: &PaddleFrame<f32>,
    ) {
        let y: [f32; 3] = core::array::from_fn(|i| z[i] - pred.position_m[i]);
        let worst = y[0].abs().max_r(y[1].abs()).max_r(y[2].abs());
        if worst <= self.params.gate_m {
            let axes = pred.position_m.iter_mut().zip(&mut pred.velocity_mps);
            for ((b, v), y) in axes.zip(y) {
                *b += self.params.gain_position * y;
                *v += self.gain_velocity_per_s * y;
            }
            self.ball = pred;
            self.outliers = 0;
            self.phase = Phase::Tracking {
                accepted: accepted.saturating_add(1),
            };
        } else {
            self.outliers = self.outliers.saturating_add(1);
            if self.outliers >= self.params.reinit_after {
                let z0 = self.last_z;
                self.initialise(&z0, z, paddle);
            } else {
                self.ball = pred;
            }
        }
    }

    /// The ball through two samples one period apart: b(t) = z0 + v0 t + a_p t^2/2.
    fn initialise(&mut self, z0: &[f32; 3], z1: &[f32; 3], paddle: &PaddleFrame<f32>) {
        let v: [f32; 3] = core::array::from_fn(|i| (z1[i] - z0[i]) * self.inv_dt_per_s);
        let mut ball = SpatialBall::new(*z1, v);
        ball.velocity_mps[2] -= 0.5 * self.gravity_mps2 * self.dt_s;
        self.ball = ball;
        self.last_gap_m = paddle.gap_m(z1);
        self.outliers = 0;
        self.phase = Phase::Tracking { accepted: 0 };
    }

    fn output(&self) -> SpatialEstimate {
        let valid = matches!(self.phase, Phase::Tracking { accepted } if accepted >= self.params.settle_samples);
        SpatialEstimate {
            ball: self.ball.flown(self.params.latency_s, self.gravity_mps2),
            valid,
        }
    }
}
