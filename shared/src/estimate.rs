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

/// A ballistic flight of fixed duration with its gravity terms computed once:
/// [`BallState::flown`] bit for bit (`h + v t - ((g/2) t) t`, `v - g t`), without the
/// three multiplications of `g` and `t` on every step (the estimator flies twice a step).
#[derive(Clone, Copy, Debug)]
struct FixedFlight {
    duration_s: f32,
    /// `((g / 2) t) t`, m, as `flown` computes it.
    drop_m: f32,
    /// `g t`, m/s.
    speed_lost_mps: f32,
}

impl FixedFlight {
    fn new(duration_s: f32, gravity_mps2: f32) -> Self {
        Self {
            duration_s,
            drop_m: 0.5 * gravity_mps2 * duration_s * duration_s,
            speed_lost_mps: gravity_mps2 * duration_s,
        }
    }

    /// `ball.flown(duration_s, gravity_mps2)`.
    #[inline(always)]
    fn fly(&self, ball: &BallState<f32>) -> BallState<f32> {
        BallState::new(
            ball.height_m + ball.velocity_mps * self.duration_s - self.drop_m,
            ball.velocity_mps - self.speed_lost_mps,
        )
    }
}

/// Alpha-beta ball estimator with a ballistic model and impact re-initialisation.
#[derive(Clone, Debug)]
pub struct BallEstimator {
    params: EstimatorParams,
    dt_s: f32,
    /// 1/dt, 1/s, computed once: the step multiplies instead of dividing (a `vdiv.f32` is
    /// 14 cycles on a Cortex-M4, a `vmul.f32` 1); within 1 ulp of dividing by dt.
    inv_dt_per_s: f32,
    /// The velocity gain c/dt, 1/s, computed once (bit-identical to dividing every step).
    gain_velocity_per_s: f32,
    gravity_mps2: f32,
    /// One sample period's flight (the prediction).
    period: FixedFlight,
    /// The latency's flight (the output, now).
    latency: FixedFlight,
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
            inv_dt_per_s: 1.0 / dt_s,
            gain_velocity_per_s: params.gain_velocity / dt_s,
            gravity_mps2,
            period: FixedFlight::new(dt_s, gravity_mps2),
            latency: FixedFlight::new(params.latency_s, gravity_mps2),
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
        let mut impact = false;
        match self.phase {
            Phase::Empty => {
                self.phase = Phase::OneSample(z_m);
            }
            Phase::OneSample(z0) => {
                self.initialise(z0, z_m);
            }
            Phase::Tracking { accepted } => {
                let mut pred = self.period.fly(&self.ball);
                impact = self.apply_impact(&mut pred, &self.paddle_at_sample_time(paddle));
                let innovation = z_m - pred.height_m;
                if innovation.abs() <= self.params.gate_m {
                    pred.height_m += self.params.gain_position * innovation;
                    pred.velocity_mps += self.gain_velocity_per_s * innovation;
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
            let mut pred = self.period.fly(&self.ball);
            impact = self.apply_impact(&mut pred, &self.paddle_at_sample_time(paddle));
            self.ball = pred;
        }
        self.output(paddle, impact)
    }

    fn initialise(&mut self, z0: f32, z1: f32) {
        let dt = self.dt_s;
        // b(t) = z0 + v0 t - g t^2/2 through both samples; velocity at the second one
        self.ball = BallState::new(
            z1,
            (z1 - z0) * self.inv_dt_per_s - 0.5 * self.gravity_mps2 * dt,
        );
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
        let mut now = self.latency.fly(&self.ball);
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

    /// The estimator's fixed flights are `BallState::flown` bit for bit.
    #[test]
    fn fixed_flights_are_flown_bit_for_bit() {
        let mut x = 0x1234_5678u32;
        let mut next = || {
            x ^= x << 13;
            x ^= x >> 17;
            x ^= x << 5;
            x as f32 / u32::MAX as f32
        };
        for _ in 0..100_000 {
            let (t, g) = (next() * 0.02, 1.0 + next() * 20.0);
            let ball = BallState::new(next() * 4.0 - 1.0, next() * 20.0 - 10.0);
            let (want, got) = (ball.flown(t, g), FixedFlight::new(t, g).fly(&ball));
            assert_eq!(
                got.height_m.to_bits(),
                want.height_m.to_bits(),
                "{ball:?} {t} {g}"
            );
            assert_eq!(got.velocity_mps.to_bits(), want.velocity_mps.to_bits());
        }
    }

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

    /// A ball falling from `h0` onto a paddle that moves at constant velocity: the f64 truth
    /// the estimator is checked against, with the impact time solved in closed form.
    struct FallOntoMovingPaddle {
        h0: f64,
        p0: f64,
        vp: f64,
        e: f64,
        t_hit: f64,
    }

    impl FallOntoMovingPaddle {
        fn new(h0: f64, p0: f64, vp: f64, e: f64) -> Self {
            // h0 - g t^2/2 = p0 + vp t: the positive root of g t^2/2 + vp t - (h0 - p0) = 0
            let g = G as f64;
            let t_hit = (-vp + (vp * vp + 2.0 * g * (h0 - p0)).sqrt()) / g;
            Self {
                h0,
                p0,
                vp,
                e,
                t_hit,
            }
        }
        fn paddle(&self, t: f64) -> f64 {
            self.p0 + self.vp * t
        }
        /// Ball (height, velocity) at time t.
        fn ball(&self, t: f64) -> (f64, f64) {
            let g = G as f64;
            if t < self.t_hit {
                (self.h0 - 0.5 * g * t * t, -g * t)
            } else {
                // eq. 4 at the impact, then free flight
                let v_out = -self.e * (-g * self.t_hit) + (1.0 + self.e) * self.vp;
                let s = t - self.t_hit;
                (
                    self.paddle(self.t_hit) + v_out * s - 0.5 * g * s * s,
                    v_out - g * s,
                )
            }
        }
    }

    /// The settle count, derived from its doc: update 1 stores the first sample, update 2
    /// initialises (0 accepted updates), update k >= 3 is the (k - 2)-th accepted one; so the
    /// estimate is first valid at update `settle_samples + 2`, for every count.
    #[test]
    fn valid_after_exactly_settle_samples_accepted_updates() {
        let dt = 0.002;
        let paddle = PaddleState::new(-1.0, 0.0);
        for n in [0u8, 1, 2, 25] {
            let params = EstimatorParams {
                settle_samples: n,
                ..EstimatorParams::default()
            };
            let mut est = BallEstimator::new(params, dt, G).unwrap();
            for k in 1..=(n as u32 + 5) {
                let z = BallState::new(1.0f32, 0.0)
                    .flown((k - 1) as f32 * dt, G)
                    .height_m;
                let out = est.update(z, &paddle);
                assert_eq!(out.valid, k >= n as u32 + 2, "settle {n}, update {k}");
            }
        }
    }

    /// Coasting (no measurement) and outliers are not accepted updates; a re-initialisation
    /// restarts the count from 0.
    #[test]
    fn coasting_and_outliers_do_not_count_and_reinit_restarts_the_count() {
        let dt = 0.002f32;
        let paddle = PaddleState::new(-1.0, 0.0);
        let params = EstimatorParams {
            settle_samples: 3,
            ..EstimatorParams::default()
        };
        let truth = |k: u32| BallState::new(1.0f32, 0.0).flown(k as f32 * dt, G).height_m;
        let mut est = BallEstimator::new(params, dt, G).unwrap();
        est.update(truth(0), &paddle);
        est.update(truth(1), &paddle); // initialised, 0 accepted
        assert!(!est.coast(&paddle).valid); // k = 2 passes without a sample
        assert!(!est.update(truth(3), &paddle).valid); // 1 accepted
        assert!(!est.update(truth(4), &paddle).valid); // 2
        assert!(est.update(truth(5), &paddle).valid); // 3
                                                      // two outliers (reinit_after = 3): still valid, the count is kept
        assert!(est.update(truth(6) + 1.0, &paddle).valid);
        assert!(est.update(truth(7) + 1.0, &paddle).valid);
        // the third re-initialises from the last two measurements: count 0, not valid
        assert!(!est.update(truth(8) + 1.0, &paddle).valid);
        assert!(!est.update(truth(9) + 1.0, &paddle).valid); // 1
        assert!(!est.update(truth(10) + 1.0, &paddle).valid); // 2
        assert!(est.update(truth(11) + 1.0, &paddle).valid); // 3
    }

    /// Initialisation from two samples: the parabola through them with known gravity gives
    /// the velocity at the second, v = (z1 - z0)/dt - g dt/2 (by hand), so two exact samples
    /// give the exact state at once.
    #[test]
    fn two_samples_give_the_exact_state() {
        let dt = 0.004f32;
        let params = EstimatorParams {
            settle_samples: 0,
            ..EstimatorParams::default()
        };
        let mut est = BallEstimator::new(params, dt, G).unwrap();
        let paddle = PaddleState::new(-1.0, 0.0);
        let (h0, v0) = (2.0f64, 3.0f64);
        let g = G as f64;
        let z = |t: f64| (h0 + v0 * t - 0.5 * g * t * t) as f32;
        assert!(!est.update(z(0.0), &paddle).valid);
        let out = est.update(z(dt as f64), &paddle);
        assert!(out.valid);
        let v1 = v0 - g * dt as f64;
        assert!((out.ball.height_m as f64 - z(dt as f64) as f64).abs() < 1e-6);
        // f32 samples of ~2 m carry 1.2e-7 m of rounding: / dt = 3e-5 m/s
        assert!(
            (out.ball.velocity_mps as f64 - v1).abs() < 1e-4,
            "{out:?} vs {v1}"
        );
    }

    /// One update by hand: innovation y = z - (b + v dt - g dt^2/2); inside the gate
    /// b += a y and v += (c/dt) y; beyond it the prediction stands (the sample is ignored).
    #[test]
    fn alpha_beta_update_and_gate_by_hand() {
        let dt = 0.002f32;
        let params = EstimatorParams {
            gain_position: 0.25,
            gain_velocity: 0.125,
            gate_m: 0.01,
            settle_samples: 0,
            ..EstimatorParams::default()
        };
        let paddle = PaddleState::new(-1.0, 0.0);
        let start = |est: &mut BallEstimator| {
            // two samples of a ball at rest at 1 m: b = 1, v = -g dt/2 at the second
            est.update(1.0, &paddle);
            est.update(1.0, &paddle);
        };
        let g = G as f64;
        let (b, v, dt64) = (1.0f64, -0.5 * g * dt as f64, dt as f64);
        let (b_pred, v_pred) = (b + v * dt64 - 0.5 * g * dt64 * dt64, v - g * dt64);
        for y in [0.008f64, -0.008, 0.012, -0.012] {
            let mut est = BallEstimator::new(params, dt, G).unwrap();
            start(&mut est);
            let out = est.update((b_pred + y) as f32, &paddle);
            let (want_b, want_v) = if y.abs() <= 0.01 {
                (b_pred + 0.25 * y, v_pred + 0.125 / dt64 * y)
            } else {
                (b_pred, v_pred)
            };
            assert!(
                (out.ball.height_m as f64 - want_b).abs() < 2e-6,
                "y {y}: {out:?}"
            );
            assert!(
                (out.ball.velocity_mps as f64 - want_v).abs() < 2e-3,
                "y {y}: {out:?} vs {want_v}"
            );
        }
    }

    /// Re-initialisation after `reinit_after` outliers uses the last two measurements (both
    /// outliers), by the two-sample formula.
    #[test]
    fn reinitialises_from_the_last_two_outliers() {
        let dt = 0.002f32;
        let mut est = BallEstimator::new(EstimatorParams::default(), dt, G).unwrap();
        let paddle = PaddleState::new(-1.0, 0.0);
        for _ in 0..5 {
            est.update(1.0, &paddle);
        }
        est.update(3.0, &paddle);
        est.update(3.01, &paddle);
        let out = est.update(3.03, &paddle); // third outlier: re-initialise from 3.01, 3.03
        let v = (3.03f64 - 3.01) / dt as f64 - 0.5 * G as f64 * dt as f64;
        assert!((out.ball.height_m - 3.03).abs() < 1e-6);
        assert!(
            (out.ball.velocity_mps as f64 - v).abs() < 1e-3,
            "{out:?} vs {v}"
        );
        assert!(!out.valid);
    }

    /// The impact step in the filter, derived by hand. Let the true impact happen s seconds
    /// before the sample (0 <= s < dt) at paddle velocity r' (constant), incoming ball speed
    /// v_in. Without the impact the model predicts b- = p_h + v_in s - g s^2/2 and
    /// v- = v_in - g s; reflecting with restitution e about the paddle p_h + r' s gives
    /// b = p_h + v_out s + e g s^2/2 and v = v_out + e g s, where v_out = -e v_in + (1+e) r'
    /// (eq. 4), against the truth p_h + v_out s - g s^2/2 and v_out - g s. So before the
    /// alpha-beta update the errors are (1+e) g s^2/2 and (1+e) g s, and the update with the
    /// innovation y = -(1+e) g s^2/2 leaves (1-a)(1+e) g s^2/2 and (1+e) g s + (c/dt) y.
    ///
    /// Under latency L the filter state lives at the sample time, so its impact check must
    /// use the paddle moved back by L: the impact is seen at the first sample taken at or
    /// after the true impact, for a paddle rising or falling.
    #[test]
    fn impact_in_the_filter_matches_the_hand_derived_reflection_under_latency() {
        let dt = 0.002f64;
        let latency = 0.010f64;
        let g = G as f64;
        for (vp, e) in [(1.5f64, 0.8f64), (-0.8, 0.6), (0.0, 0.8)] {
            let params = EstimatorParams {
                latency_s: latency as f32,
                restitution: e as f32,
                ..EstimatorParams::default()
            };
            let (a, c) = (params.gain_position as f64, params.gain_velocity as f64);
            let mut est = BallEstimator::new(params, dt as f32, G).unwrap();
            // drop height chosen so the impact falls 0.35 dt before sample 150
            let t_hit = 149.65 * dt;
            let p0 = -0.2;
            let h0 = p0 + vp * t_hit + 0.5 * g * t_hit * t_hit;
            let truth = FallOntoMovingPaddle::new(h0, p0, vp, e);
            assert!((truth.t_hit - t_hit).abs() < 1e-12);
            let first_after = 150;
            let s = first_after as f64 * dt - truth.t_hit;
            for j in 0..=first_after {
                // sample j was taken at j dt; it arrives with the paddle measured at j dt + L
                let now = j as f64 * dt + latency;
                let p = PaddleState::new(truth.paddle(now) as f32, vp as f32);
                est.update(truth.ball(j as f64 * dt).0 as f32, &p);
                let filt = est.state_at_measurement();
                if (1..first_after).contains(&j) {
                    assert!(
                        filt.velocity_mps < 0.0,
                        "vp {vp}: impact seen at sample {j}"
                    );
                }
            }
            let filt = est.state_at_measurement();
            let (b_true, v_true) = truth.ball(first_after as f64 * dt);
            let y = -(1.0 + e) * g * s * s / 2.0;
            let db = (1.0 - a) * (1.0 + e) * g * s * s / 2.0;
            let dv = (1.0 + e) * g * s + c / dt * y;
            let (err_b, err_v) = (
                filt.height_m as f64 - b_true,
                filt.velocity_mps as f64 - v_true,
            );
            assert!(
                (err_b - db).abs() < 2e-6,
                "vp {vp}: height error {err_b:e}, hand-derived {db:e}"
            );
            assert!(
                (err_v - dv).abs() < 2e-4,
                "vp {vp}: velocity error {err_v:e}, hand-derived {dv:e}"
            );
        }
    }

    /// Without latency the output is the filter state; with latency it is the filter state
    /// flown L seconds forward (exact ballistic flight) with an impact against the current
    /// paddle: when the flight to now crosses the paddle, the output is the reflection.
    #[test]
    fn output_is_the_filter_state_flown_forward_by_the_latency() {
        let dt = 0.002f32;
        let latency = 0.008f32;
        let params = EstimatorParams {
            latency_s: latency,
            ..EstimatorParams::default()
        };
        let mut est = BallEstimator::new(params, dt, G).unwrap();
        let paddle = PaddleState::new(-1.0, 0.0);
        let mut out = Estimate::default();
        for k in 0..40 {
            out = est.update(
                BallState::new(1.0f32, 2.0).flown(k as f32 * dt, G).height_m,
                &paddle,
            );
        }
        let at_sample = est.state_at_measurement();
        let g = G as f64;
        let l = latency as f64;
        let (b, v) = (at_sample.height_m as f64, at_sample.velocity_mps as f64);
        assert!((out.ball.height_m as f64 - (b + v * l - 0.5 * g * l * l)).abs() < 1e-6);
        assert!((out.ball.velocity_mps as f64 - (v - g * l)).abs() < 1e-5);
        assert!(!out.impact);
    }

    /// Coasting during tracking flies the state one period by the exact ballistic model and
    /// keeps the estimate valid; the reported state is that prediction.
    #[test]
    fn coasting_predicts_by_the_ballistic_model() {
        let dt = 0.002f32;
        let mut est = BallEstimator::new(EstimatorParams::default(), dt, G).unwrap();
        let paddle = PaddleState::new(-1.0, 0.0);
        for k in 0..30 {
            est.update(
                BallState::new(2.0f32, 1.0).flown(k as f32 * dt, G).height_m,
                &paddle,
            );
        }
        let before = est.state_at_measurement();
        let out = est.coast(&paddle);
        let (b, v, dt64, g) = (
            before.height_m as f64,
            before.velocity_mps as f64,
            dt as f64,
            G as f64,
        );
        assert!(out.valid && !out.impact);
        assert!((out.ball.height_m as f64 - (b + v * dt64 - 0.5 * g * dt64 * dt64)).abs() < 1e-6);
        assert!((out.ball.velocity_mps as f64 - (v - g * dt64)).abs() < 1e-6);
        assert_eq!(est.state_at_measurement(), out.ball);
    }

    /// The impact flag: set on the step whose filter prediction crosses the paddle (here
    /// without latency, so the output adds no impact of its own), and on no other.
    #[test]
    fn impact_flag_marks_the_filter_impact_step() {
        let dt = 0.002f64;
        let g = G as f64;
        let mut est = BallEstimator::new(EstimatorParams::default(), dt as f32, G).unwrap();
        let t_hit = 99.5 * dt;
        let truth = FallOntoMovingPaddle::new(0.5 * g * t_hit * t_hit, 0.0, 0.0, 0.8);
        let p = PaddleState::new(0.0, 0.0);
        let flags: Vec<bool> = (0..=110)
            .map(|j| est.update(truth.ball(j as f64 * dt).0 as f32, &p).impact)
            .collect();
        let at: Vec<usize> = (0..flags.len()).filter(|&j| flags[j]).collect();
        assert_eq!(at, [100]);
    }

    #[test]
    fn reset_forgets_the_state() {
        let dt = 0.002f32;
        let params = EstimatorParams {
            settle_samples: 0,
            ..EstimatorParams::default()
        };
        let mut est = BallEstimator::new(params, dt, G).unwrap();
        let paddle = PaddleState::new(-1.0, 0.0);
        est.update(1.0, &paddle);
        assert!(est.update(1.0, &paddle).valid);
        est.reset();
        // one sample after a reset is not enough, and coasting produces nothing valid
        assert!(!est.coast(&paddle).valid);
        assert!(!est.update(2.0, &paddle).valid);
        let out = est.update(2.0, &paddle);
        assert!(out.valid);
        assert!((out.ball.height_m - 2.0).abs() < 1e-6);
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
