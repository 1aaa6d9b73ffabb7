//! Fixed-rate estimator of the planar body's flight from camera poses (x, y, theta).
//!
//! # Model
//!
//! Between impacts the flight is exact (Zumel & Erdmann eq. 6): x and theta are linear in
//! time, y is a parabola with the known gravity G. Each coordinate is therefore a
//! straight-line (or gravity-corrected) least-squares fit, computed recursively by the
//! growing-memory polynomial filter (Morrison's expanding-memory filter of degree 1): after
//! the n-th sample, with the prediction `p-`, `v-` over the sample spacing T,
//!
//! ```text
//! r = z - p-,   p = p- + a_n r,   v = v- + (b_n / T) r,
//! a_n = 2 (2n - 1) / (n (n + 1)),   b_n = 6 / (n (n + 1))
//! ```
//!
//! which is exactly the least-squares line through all n samples of the flight (a_2 = b_2 =
//! 1 is the two-point difference). n is capped at `memory_samples` (then it is a fixed-gain
//! alpha-beta filter that forgets unmodelled effects) and the estimate is valid from
//! `settle_samples` on. Work per sample is constant: two divisions and ~30 flops.
//!
//! # Impacts
//!
//! The controller plans each impact ([`PlannedImpact`]: its time and the table's angle and
//! normal velocity there). When the estimator's prediction passes that time it applies the
//! impact model of eq. 2 and 21 (table much heavier than the body, restitution e; the same
//! law as [`crate::tilt::impact`]; sin and cos of the angle come from the plan's, rotated by
//! the small difference to the estimate, so the step calls no trig) and carries on with the post-impact flight, with n reduced
//! to `impact_prior_samples` (the model's prediction is worth that many samples). If the
//! measurements disagree with the model (innovation beyond the gate `gate_m` or `gate_rad`
//! `reinit_after` times in a row: an unplanned or mistimed impact), the filter restarts from
//! the measurements (n = 1). So impacts are predicted by the model and detected from the
//! measurements. The sample of the period in which the model applies an impact is not used
//! (one sample per flight), so that period does the impact instead of the update; also when
//! the model finds the contact not closing (then the flight carries on unchanged).
//!
//! # Latency
//!
//! A camera sample that arrives now was taken `latency_s` earlier. The filter state lives at
//! the sample time; [`FlightEstimator::now`] flies it forward by its age (latency plus the
//! control periods since the sample), which is exact in flight.

use crate::checks::Checks;
use crate::math::Real;
use crate::params::{positive, ParamError};
use serde::{Deserialize, Serialize};

/// The body's flight state, f32: centre of mass (m), angle (rad) and their rates.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct BodyFlight {
    /// Centre of mass x, m.
    pub x_m: f32,
    /// Centre of mass y, m.
    pub y_m: f32,
    /// Angle theta, rad, counterclockwise, 0 = upright.
    pub theta_rad: f32,
    /// x', m/s.
    pub x_dot_mps: f32,
    /// y', m/s.
    pub y_dot_mps: f32,
    /// theta', rad/s.
    pub theta_dot_radps: f32,
}

impl BodyFlight {
    /// Ballistic flight for `t_s` seconds under gravity `gravity_mps2` (eq. 6), exact.
    #[inline]
    pub fn flown(&self, t_s: f32, gravity_mps2: f32) -> Self {
        let half_gt = 0.5 * gravity_mps2 * t_s;
        Self {
            x_m: self.x_m + self.x_dot_mps * t_s,
            y_m: self.y_m + (self.y_dot_mps - half_gt) * t_s,
            theta_rad: self.theta_rad + self.theta_dot_radps * t_s,
            x_dot_mps: self.x_dot_mps,
            y_dot_mps: self.y_dot_mps - 2.0 * half_gt,
            theta_dot_radps: self.theta_dot_radps,
        }
    }
}

/// Estimator tuning (part of the controller's parameters, sent on the wire).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct FlightTuning {
    /// Age of a camera sample when it reaches the controller, s (>= 0, < 0.1).
    pub latency_s: f32,
    /// Largest position innovation accepted, m (> 0).
    pub gate_m: f32,
    /// Largest angle innovation accepted, rad (> 0).
    pub gate_rad: f32,
    /// Cap of the growing memory n, samples (>= 2).
    pub memory_samples: u16,
    /// Samples after a restart before the estimate is valid (>= 2, <= memory_samples).
    pub settle_samples: u8,
    /// n after a modelled impact (>= settle_samples, so the estimate stays valid).
    pub impact_prior_samples: u8,
    /// Outliers in a row that restart the filter from the measurements (>= 1).
    pub reinit_after: u8,
}

impl Default for FlightTuning {
    /// For a camera with ~1 mm and 5 mrad noise at 250–1000 Hz.
    fn default() -> Self {
        Self {
            latency_s: 0.0,
            gate_m: 0.01,
            gate_rad: 0.06,
            memory_samples: 400,
            settle_samples: 8,
            impact_prior_samples: 10,
            reinit_after: 3,
        }
    }
}

impl FlightTuning {
    /// Check every field; the error names the first bad one.
    #[inline]
    pub fn validate(&self) -> Result<(), ParamError> {
        let mut c = Checks::default();
        self.check(&mut c);
        c.result()
    }

    /// [`FlightTuning::validate`]'s checks, into `c`.
    pub(crate) fn check(&self, c: &mut Checks) {
        c.non_negative("estimator.latency_s", self.latency_s);
        c.in_range(self.latency_s < 0.1, "estimator.latency_s");
        c.positive("estimator.gate_m", self.gate_m);
        c.positive("estimator.gate_rad", self.gate_rad);
        c.in_range(self.memory_samples >= 2, "estimator.memory_samples");
        let settle = self.settle_samples;
        let settle_ok = settle >= 2 && u16::from(settle) <= self.memory_samples;
        c.in_range(settle_ok, "estimator.settle_samples");
        let prior_ok = self.impact_prior_samples >= settle;
        c.in_range(prior_ok, "estimator.impact_prior_samples");
        c.positive_count(self.reinit_after > 0, "estimator.reinit_after");
    }
}

/// The table at a planned impact, as the impact model needs it, and the body's angle there
/// as the plan predicted it.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct PlannedImpact {
    /// Time of the impact after the estimator's state time, s.
    pub in_s: f32,
    /// The body's angle at the impact as planned, rad.
    pub theta_rad: f32,
    /// sin of `theta_rad`.
    pub sin_theta: f32,
    /// cos of `theta_rad`.
    pub cos_theta: f32,
    /// sin alpha of the table angle at impact.
    pub sin_alpha: f32,
    /// cos alpha of the table angle at impact.
    pub cos_alpha: f32,
    /// Velocity of the table surface at the contact point along the table normal
    /// (-sin alpha, cos alpha), m/s.
    pub normal_velocity_mps: f32,
}

/// No planned impact.
const NO_PLAN: PlannedImpact = PlannedImpact {
    in_s: f32::INFINITY,
    theta_rad: 0.0,
    sin_theta: 0.0,
    cos_theta: 1.0,
    sin_alpha: 0.0,
    cos_alpha: 1.0,
    normal_velocity_mps: 0.0,
};

/// What one estimator step did.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct FlightUpdate {
    /// The planned impact was applied in this step.
    pub impact: bool,
    /// The filter restarted from the measurements (outliers) or started (first sample).
    pub restarted: bool,
}

/// The body's geometry and restitution, for the impact model (eq. 2, 21).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ImpactModel {
    /// Radius of gyration rho, m (> 0).
    pub rho_m: f32,
    /// Contact distance l, m (> 0).
    pub l_m: f32,
    /// Restitution e in [0, 1].
    pub restitution: f32,
}

impl ImpactModel {
    /// eq. 2 and 21 against a table with angle (sin, cos) = (`sa`, `ca`) whose surface moves
    /// with `vn` along its normal at the contact, applied to `s` in place (positions kept).
    /// `sin_cos_theta` is (sin theta, cos theta) of `s`. Returns false (and leaves `s`) if
    /// the contact is not closing.
    #[inline]
    pub fn collide(
        &self,
        s: &mut BodyFlight,
        sin_cos_theta: (f32, f32),
        sa: f32,
        ca: f32,
        vn: f32,
    ) -> bool {
        let (st, ct) = sin_cos_theta;
        let (rho, l) = (self.rho_m, self.l_m);
        // beta = theta - alpha
        let sb = st * ca - ct * sa;
        let k = 1.0 / Real::sqrt(rho * rho + l * l * sb * sb);
        let n = [-sa * rho * k, ca * rho * k, l * sb * k];
        let rel =
            n[0] * s.x_dot_mps + n[1] * s.y_dot_mps + n[2] * rho * s.theta_dot_radps - rho * k * vn;
        // not closing (NaN included): no impact
        if rel.partial_cmp(&0.0) != Some(core::cmp::Ordering::Less) {
            return false;
        }
        let j = (1.0 + self.restitution) * rel;
        s.x_dot_mps -= j * n[0];
        s.y_dot_mps -= j * n[1];
        s.theta_dot_radps -= j * n[2] / rho;
        true
    }
}

/// The flight estimator (module docs).
#[derive(Clone, Debug)]
pub struct FlightEstimator {
    tuning: FlightTuning,
    model: ImpactModel,
    dt_s: f32,
    gravity_mps2: f32,
    /// State at the newest sample's time.
    state: BodyFlight,
    /// n: samples in the current fit (0: empty).
    samples: u16,
    /// Control periods since the newest sample.
    since_sample: u16,
    outliers: u8,
    /// The planned impact; `in_s` infinite when there is none (cheaper than an Option
    /// on the step's hot path).
    planned: PlannedImpact,
}

impl FlightEstimator {
    /// An estimator stepped every `dt_s` (> 0) under gravity `gravity_mps2` (> 0).
    #[inline]
    pub fn new(
        tuning: FlightTuning,
        model: ImpactModel,
        dt_s: f32,
        gravity_mps2: f32,
    ) -> Result<Self, ParamError> {
        tuning.validate()?;
        positive("dt_s", dt_s)?;
        positive("gravity_mps2", gravity_mps2)?;
        Ok(Self::new_validated(tuning, model, dt_s, gravity_mps2))
    }

    /// [`FlightEstimator::new`] for values the caller has validated (the controller's
    /// parameters: validated once, not twice in flash).
    #[inline]
    pub(crate) fn new_validated(
        tuning: FlightTuning,
        model: ImpactModel,
        dt_s: f32,
        gravity_mps2: f32,
    ) -> Self {
        Self {
            tuning,
            model,
            dt_s,
            gravity_mps2,
            state: BodyFlight::default(),
            samples: 0,
            since_sample: 0,
            outliers: 0,
            planned: NO_PLAN,
        }
    }

    /// Forget everything (after a fault).
    pub fn reset(&mut self) {
        self.samples = 0;
        self.since_sample = 0;
        self.outliers = 0;
        self.drop_plan();
    }

    /// True once the fit holds `settle_samples` samples.
    #[inline]
    pub fn valid(&self) -> bool {
        self.samples >= u16::from(self.tuning.settle_samples)
    }

    /// Samples in the current fit.
    pub fn samples(&self) -> u16 {
        self.samples
    }

    /// Age of the state: latency plus the periods since the newest sample, s.
    #[inline]
    pub fn age_s(&self) -> f32 {
        self.tuning.latency_s + f32::from(self.since_sample) * self.dt_s
    }

    /// The estimate now (the state flown forward by its age).
    #[inline]
    pub fn now(&self) -> BodyFlight {
        self.state.flown(self.age_s(), self.gravity_mps2)
    }

    /// The estimate at the newest sample's time.
    pub fn at_sample(&self) -> BodyFlight {
        self.state
    }

    /// Plan the next impact: `planned.in_s` counts from now (it is stored from the state's
    /// time); the table's angle and normal velocity and the body's angle there as predicted.
    #[inline]
    pub fn plan_impact(&mut self, planned: PlannedImpact) {
        self.planned = PlannedImpact {
            in_s: planned.in_s + self.age_s(),
            ..planned
        };
    }

    /// Drop the planned impact.
    pub fn clear_plan(&mut self) {
        self.drop_plan();
    }

    /// No planned impact: `in_s` infinite (the other fields are not read then).
    #[inline]
    fn drop_plan(&mut self) {
        self.planned.in_s = f32::INFINITY;
    }

    /// The planned impact, if any (time from the state's time).
    pub fn planned(&self) -> Option<PlannedImpact> {
        self.planned.in_s.is_finite().then_some(self.planned)
    }

    /// One control period; `pose` is a new camera sample (x m, y m, theta rad; finite,
    /// checked by the caller) or `None` if no new sample arrived: [`FlightEstimator::coast`],
    /// [`FlightEstimator::impact_period`] if [`FlightEstimator::impact_due`], else
    /// [`FlightEstimator::sample_period`].
    pub fn step(&mut self, pose: Option<[f32; 3]>) -> FlightUpdate {
        match pose {
            None => {
                self.coast();
                FlightUpdate::default()
            }
            Some(_) if self.impact_due() => self.impact_period(),
            Some(z) => self.sample_period(z),
        }
    }

    /// A period without a new sample: the state ages by one period.
    #[inline]
    pub fn coast(&mut self) {
        self.since_sample = self.since_sample.saturating_add(1);
    }

    /// Whether a new sample this period would pass the planned impact: then the period
    /// is [`FlightEstimator::impact_period`] (the impact model instead of the update).
    #[inline]
    pub fn impact_due(&self) -> bool {
        self.samples != 0 && self.planned.in_s < self.span_to_next()
    }

    /// Time from the state's sample to a sample arriving this period, s.
    #[inline]
    fn span_to_next(&self) -> f32 {
        f32::from(self.since_sample.saturating_add(1)) * self.dt_s
    }

    /// A period with a new sample when [`FlightEstimator::impact_due`]: the impact model
    /// carries the state through the planned impact to the sample's time. The sample
    /// itself is not used, whether the contact closes or not: the impact model replaces
    /// the update, so the period's work is the larger of the two, not their sum (the step
    /// budget's static argument), at the cost of one sample per flight.
    pub fn impact_period(&mut self) -> FlightUpdate {
        let span = self.span_to_next();
        self.since_sample = 0;
        let impact = self.impact(span);
        self.outliers = 0;
        FlightUpdate {
            impact,
            restarted: false,
        }
    }

    /// A period with a new sample `z` (x, y, theta) when no impact is due: the
    /// recursive least-squares update, or a (re)start of the fit from `z` (the first
    /// sample, or `reinit_after` outliers in a row).
    pub fn sample_period(&mut self, z: [f32; 3]) -> FlightUpdate {
        let [zx, zy, zt] = z;
        let span = self.span_to_next();
        self.since_sample = 0;
        if self.samples == 0 {
            self.restart(zx, zy, zt);
            return FlightUpdate {
                impact: false,
                restarted: true,
            };
        }
        // no plan inside the span: infinity stays infinity
        self.planned.in_s -= span;
        let mut pred = self.state.flown(span, self.gravity_mps2);
        let r = [zx - pred.x_m, zy - pred.y_m, zt - pred.theta_rad];
        let t = &self.tuning;
        if r[0].abs() <= t.gate_m && r[1].abs() <= t.gate_m && r[2].abs() <= t.gate_rad {
            let n = self.samples.saturating_add(1).min(t.memory_samples);
            let nf = f32::from(n);
            let inv = 1.0 / (nf * (nf + 1.0));
            let a = 2.0 * (2.0 * nf - 1.0) * inv;
            let b = 6.0 * inv / span;
            pred.x_m += a * r[0];
            pred.y_m += a * r[1];
            pred.theta_rad += a * r[2];
            pred.x_dot_mps += b * r[0];
            pred.y_dot_mps += b * r[1];
            pred.theta_dot_radps += b * r[2];
            self.state = pred;
            self.samples = n;
            self.outliers = 0;
            return FlightUpdate::default();
        }
        self.state = pred;
        self.outliers = self.outliers.saturating_add(1);
        let restarted = self.outliers >= t.reinit_after;
        if restarted {
            self.restart(zx, zy, zt);
        }
        FlightUpdate {
            impact: false,
            restarted,
        }
    }

    /// The state flown over `span` through the planned impact, which falls inside it;
    /// whether the contact closed (eq. 2/21 applied) or not (flight carries on). The plan
    /// is used up either way.
    fn impact(&mut self, span: f32) -> bool {
        let g = self.gravity_mps2;
        let p = self.planned;
        let t_c = p.in_s.max_r(0.0);
        let mut s = self.state.flown(t_c, g);
        // sin and cos of the angle now from the plan's, rotated by the small difference d
        // (|d| ~ 1e-3 rad: second-order error d^2/2 ~ 1e-6)
        let d = s.theta_rad - p.theta_rad;
        let sc = (p.sin_theta + d * p.cos_theta, p.cos_theta - d * p.sin_theta);
        let hit = self
            .model
            .collide(&mut s, sc, p.sin_alpha, p.cos_alpha, p.normal_velocity_mps);
        self.drop_plan();
        if hit {
            let prior = u16::from(self.tuning.impact_prior_samples);
            self.samples = self.samples.min(prior);
        }
        self.state = s.flown(span - t_c, g);
        hit
    }

    /// Start a new fit at the measured pose (velocities follow from the next sample).
    fn restart(&mut self, x: f32, y: f32, theta: f32) {
        self.state = BodyFlight {
            x_m: x,
            y_m: y,
            theta_rad: theta,
            ..self.state
        };
        self.samples = 1;
        self.outliers = 0;
        self.drop_plan();
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const G: f32 = 9.81;

    fn estimator(latency_s: f32) -> FlightEstimator {
        let tuning = FlightTuning {
            latency_s,
            ..FlightTuning::default()
        };
        let model = ImpactModel {
            rho_m: 0.094_28,
            l_m: 0.133_33,
            restitution: 0.5,
        };
        FlightEstimator::new(tuning, model, 0.002, G).unwrap()
    }

    #[test]
    fn exact_flight_is_recovered_from_noiseless_samples() {
        // truth in f64; samples every 2 ms, latency 4 ms
        let truth = |t: f64| {
            [
                0.1 + 0.4 * t,
                0.3 + 1.2 * t - 0.5 * 9.81 * t * t,
                -0.2 + 1.5 * t,
            ]
        };
        let mut est = estimator(0.004);
        for k in 0..40 {
            let z = truth(0.002 * f64::from(k)).map(|v| v as f32);
            est.step(Some(z));
        }
        assert!(est.valid());
        // now = last sample time (0.078 s) + latency 0.004 s
        let now = est.now();
        let t = 0.082f64;
        let expect = truth(t);
        let got = [now.x_m, now.y_m, now.theta_rad];
        for i in 0..3 {
            assert!(
                (f64::from(got[i]) - expect[i]).abs() < 2e-5,
                "{got:?} vs {expect:?}"
            );
        }
        assert!((f64::from(now.x_dot_mps) - 0.4).abs() < 1e-3);
        assert!((f64::from(now.y_dot_mps) - (1.2 - 9.81 * t)).abs() < 1e-3);
        assert!((f64::from(now.theta_dot_radps) - 1.5).abs() < 1e-3);
    }

    #[test]
    fn growing_memory_gains_are_the_least_squares_line() {
        // n noisy samples of a line: the filter's estimate equals the batch least-squares
        // fit computed independently (normal equations in f64)
        let zs: [f64; 7] = [0.0, 0.0013, 0.0017, 0.0031, 0.0038, 0.0052, 0.0059];
        let mut est = estimator(0.0);
        for &z in &zs {
            est.step(Some([z as f32, 0.0, 0.0]));
        }
        let n = zs.len() as f64;
        let ts: Vec<f64> = (0..zs.len()).map(|k| 0.002 * k as f64).collect();
        let (st, sz) = (ts.iter().sum::<f64>(), zs.iter().sum::<f64>());
        let stt = ts.iter().map(|t| t * t).sum::<f64>();
        let stz = ts.iter().zip(&zs).map(|(t, z)| t * z).sum::<f64>();
        let slope = (n * stz - st * sz) / (n * stt - st * st);
        let icpt = (sz - slope * st) / n;
        let s = est.at_sample();
        assert!(
            (f64::from(s.x_dot_mps) - slope).abs() < 1e-4,
            "{} vs {slope}",
            s.x_dot_mps
        );
        let last = icpt + slope * ts[6];
        assert!((f64::from(s.x_m) - last).abs() < 1e-6);
    }

    #[test]
    fn impact_model_matches_the_cores_eq21() {
        let m = ImpactModel {
            rho_m: 0.094_28,
            l_m: 0.133_33,
            restitution: 0.5,
        };
        let (theta, alpha, vn) = (0.27f64, 0.31f64, 0.45f64);
        let mut s = BodyFlight {
            theta_rad: theta as f32,
            x_dot_mps: 0.3,
            y_dot_mps: -1.6,
            theta_dot_radps: -0.7,
            ..BodyFlight::default()
        };
        let before = s;
        let sc = ((theta as f32).sin(), (theta as f32).cos());
        assert!(m.collide(
            &mut s,
            sc,
            (alpha as f32).sin(),
            (alpha as f32).cos(),
            vn as f32
        ));
        // the core's f64 law with a translating table along its normal
        let n = crate::tilt::impact_normal(alpha, theta, 0.133_33, 0.094_28);
        let vt = [-alpha.sin() * vn, alpha.cos() * vn];
        let v = crate::tilt::impact([0.3, -1.6, 0.094_28 * -0.7], vt, n, 0.5);
        assert!((f64::from(s.x_dot_mps) - v[0]).abs() < 1e-5);
        assert!((f64::from(s.y_dot_mps) - v[1]).abs() < 1e-5);
        assert!((f64::from(s.theta_dot_radps) - v[2] / 0.094_28).abs() < 1e-4);
        // a contact that opens is left alone
        let mut up = before;
        up.y_dot_mps = 2.0;
        assert!(!m.collide(&mut up, sc, 0.0, 1.0, 0.0));
        assert_eq!(
            up,
            BodyFlight {
                y_dot_mps: 2.0,
                ..before
            }
        );
    }

    #[test]
    fn planned_impact_reinitialises_the_flight_and_mistimed_one_restarts() {
        // body falls onto a flat table at rest: a planned impact at the right time keeps the
        // estimate valid and turns the velocity up (e = 0.5); with the plan 20 ms late, the
        // measurements restart the filter (and drop the stale plan) before it comes due
        for (delay, expect_restart, expect_impacts) in [(0.0f32, false, 1), (0.02, true, 0)] {
            let mut est = estimator(0.0);
            let e = 0.5f64;
            let t_hit = 0.05f64;
            let v_in = -1.5f64;
            let truth = |t: f64| -> f64 {
                if t < t_hit {
                    0.2 + v_in * (t - t_hit) - 0.5 * 9.81 * (t - t_hit) * (t - t_hit)
                } else {
                    let s = t - t_hit;
                    0.2 - e * v_in * s - 0.5 * 9.81 * s * s
                }
            };
            let mut restarted = false;
            let mut impacts = 0;
            for k in 0..60 {
                let t = 0.002 * f64::from(k);
                if k == 10 {
                    // from this sample time the impact is (t_hit - t) ahead: plan it
                    est.plan_impact(PlannedImpact {
                        in_s: (t_hit - 0.018) as f32 + delay,
                        ..NO_PLAN
                    });
                }
                let u = est.step(Some([0.0, truth(t) as f32, 0.0]));
                restarted |= u.restarted && k > 0;
                impacts += usize::from(u.impact);
            }
            assert_eq!(impacts, expect_impacts, "delay {delay}");
            assert_eq!(restarted, expect_restart, "delay {delay}");
            let now = est.now();
            let v_true = -e * v_in - 9.81 * (0.118 - t_hit);
            assert!(
                (f64::from(now.y_dot_mps) - v_true).abs() < 0.02,
                "delay {delay}: {} vs {v_true}",
                now.y_dot_mps
            );
        }
    }

    #[test]
    fn bad_tuning_is_named() {
        let t = FlightTuning {
            impact_prior_samples: 2,
            ..FlightTuning::default()
        };
        assert_eq!(
            t.validate(),
            Err(ParamError::OutOfRange("estimator.impact_prior_samples"))
        );
        let t = FlightTuning {
            gate_m: f32::NAN,
            ..FlightTuning::default()
        };
        assert_eq!(t.validate(), Err(ParamError::NotFinite("estimator.gate_m")));
    }
}
