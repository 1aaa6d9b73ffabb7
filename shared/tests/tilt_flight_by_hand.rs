//! The tilt controller's flight estimator (`tilt_control::flight`) against hand
//! computations: the tuning checks at their exact edges, the state's age (latency plus
//! coasted periods) and the flight it predicts (z(t) = z0 + v0 t - g t^2 / 2), the planned
//! impact's bookkeeping (counted from now, stored from the state's time, dropped by
//! `clear_plan` and `reset`), the outlier count that restarts the fit, and the impact model
//! applied at an angle the plan got slightly wrong (Zumel & Erdmann eq. 2 and 21 computed
//! here in f64 with exact trig). A mutation pass over `tilt_control` found each of these
//! unpinned by the core's own tests.

use dexter_core::params::ParamError;
use dexter_core::tilt_control::flight::{
    BodyFlight, FlightEstimator, FlightTuning, FlightUpdate, ImpactModel, PlannedImpact,
};

mod common;
use common::tilt::{flight, G};

const DT: f32 = 0.002;
const RHO: f64 = 0.094_28;
const L: f64 = 0.133_33;
const E: f64 = 0.5;

fn estimator(latency_s: f32) -> FlightEstimator {
    let tuning = FlightTuning {
        latency_s,
        ..FlightTuning::default()
    };
    let model = ImpactModel {
        rho_m: RHO as f32,
        l_m: L as f32,
        restitution: E as f32,
    };
    FlightEstimator::new(tuning, model, DT, G as f32).unwrap()
}

/// The camera's pose of `s`, f32.
fn pose(s: [f64; 6]) -> [f32; 3] {
    [s[0] as f32, s[1] as f32, s[2] as f32]
}

/// (x, y, theta, x', y', theta') of an estimate, f64.
fn state(b: BodyFlight) -> [f64; 6] {
    [
        b.x_m,
        b.y_m,
        b.theta_rad,
        b.x_dot_mps,
        b.y_dot_mps,
        b.theta_dot_radps,
    ]
    .map(f64::from)
}

fn assert_close(got: [f64; 6], expect: [f64; 6], tol: f64, what: &str) {
    for i in 0..6 {
        assert!(
            (got[i] - expect[i]).abs() < tol,
            "{what}: component {i}: {got:?} vs {expect:?}"
        );
    }
}

/// A flight whose samples are taken every DT from t = 0: fed `n` of them.
const S0: [f64; 6] = [0.05, 0.30, 0.10, 0.40, 1.20, 1.50];

fn fed(latency_s: f32, n: u32) -> FlightEstimator {
    let mut est = estimator(latency_s);
    for k in 0..n {
        est.step(Some(pose(flight(S0, f64::from(DT) * f64::from(k)))));
    }
    est
}

fn refused(t: FlightTuning, err: ParamError) {
    assert_eq!(t.validate(), Err(err), "{t:?}");
}

#[test]
fn the_tuning_checks_hold_at_their_documented_edges() {
    let d = FlightTuning::default();
    assert_eq!(d.validate(), Ok(()));
    // latency: >= 0 and < 0.1 s; 0.1 itself is out
    let latency = |latency_s| FlightTuning { latency_s, ..d };
    assert_eq!(latency(0.0).validate(), Ok(()));
    assert_eq!(latency(0.099_99).validate(), Ok(()));
    refused(latency(0.1), ParamError::OutOfRange("estimator.latency_s"));
    // settle: >= 2 and <= memory_samples, both edges in, one past each out
    let settle = |memory_samples, settle_samples| FlightTuning {
        memory_samples,
        settle_samples,
        impact_prior_samples: settle_samples,
        ..d
    };
    assert_eq!(settle(2, 2).validate(), Ok(()));
    assert_eq!(settle(8, 8).validate(), Ok(()));
    let bad = ParamError::OutOfRange("estimator.settle_samples");
    refused(settle(400, 1), bad);
    refused(settle(8, 9), bad);
    // an impact must leave the estimate valid: prior >= settle
    let prior = FlightTuning {
        impact_prior_samples: d.settle_samples - 1,
        ..d
    };
    refused(
        prior,
        ParamError::OutOfRange("estimator.impact_prior_samples"),
    );
    // one outlier at least before a restart
    let reinit = |reinit_after| FlightTuning { reinit_after, ..d };
    assert_eq!(reinit(1).validate(), Ok(()));
    refused(reinit(0), ParamError::NotPositive("estimator.reinit_after"));
}

#[test]
fn samples_counts_the_fit_up_to_its_memory_and_reset_forgets_everything() {
    let mut est = estimator(0.004);
    assert_eq!(est.samples(), 0);
    for k in 0..12u16 {
        est.step(Some(pose(flight(S0, f64::from(DT) * f64::from(k)))));
        assert_eq!(est.samples(), k + 1);
        assert_eq!(est.valid(), k + 1 >= 8, "settle_samples is 8");
    }
    est.coast();
    est.plan_impact(PlannedImpact {
        in_s: 0.05,
        ..PlannedImpact::default()
    });
    assert!(est.planned().is_some());
    est.reset();
    assert_eq!(est.samples(), 0);
    assert!(!est.valid());
    assert_eq!(est.planned(), None);
    // no periods since a sample: only the latency remains
    assert_eq!(est.age_s(), 0.004);
    // the next sample starts a new fit
    let u = est.step(Some([0.0, 0.0, 0.0]));
    assert_eq!(
        u,
        FlightUpdate {
            impact: false,
            restarted: true
        }
    );
    assert_eq!(est.samples(), 1);

    // the growing memory stops at memory_samples
    let mut short = FlightEstimator::new(
        FlightTuning {
            memory_samples: 5,
            settle_samples: 3,
            impact_prior_samples: 4,
            ..FlightTuning::default()
        },
        ImpactModel {
            rho_m: RHO as f32,
            l_m: L as f32,
            restitution: E as f32,
        },
        DT,
        G as f32,
    )
    .unwrap();
    for k in 0..9 {
        short.step(Some(pose(flight(S0, f64::from(DT) * f64::from(k)))));
    }
    assert_eq!(short.samples(), 5);
}

#[test]
fn the_age_is_the_latency_plus_the_coasted_periods_and_now_flies_the_state_that_far() {
    let latency = 0.004f32;
    let mut est = fed(latency, 20);
    let t_sample = 19.0 * f64::from(DT);
    assert!((f64::from(est.age_s()) - 0.004).abs() < 1e-9);
    // noiseless samples of an exact flight: the fit is the flight
    assert_close(
        state(est.at_sample()),
        flight(S0, t_sample),
        1e-4,
        "at sample",
    );
    for periods in 1..=3u32 {
        // a period without a sample (step(None) is coast)
        if periods == 1 {
            assert_eq!(est.step(None), FlightUpdate::default());
        } else {
            est.coast();
        }
        let age = 0.004 + f64::from(periods) * 0.002;
        assert!(
            (f64::from(est.age_s()) - age).abs() < 1e-7,
            "{} vs {age}",
            est.age_s()
        );
        // now = the flight at sample time + age; the sample's state does not move
        assert_close(state(est.now()), flight(S0, t_sample + age), 1e-4, "now");
        assert_close(
            state(est.at_sample()),
            flight(S0, t_sample),
            1e-4,
            "at sample",
        );
    }
    // the next sample (three periods late) lands on the flight: an inlier
    let u = est.step(Some(pose(flight(S0, t_sample + 0.008))));
    assert_eq!(u, FlightUpdate::default());
    assert_eq!(est.samples(), 21);
    assert!((f64::from(est.age_s()) - 0.004).abs() < 1e-9);
}

#[test]
fn a_plan_counts_from_now_and_is_kept_from_the_states_time_until_cleared() {
    let mut est = fed(0.004, 10);
    est.coast();
    est.coast();
    // age 4 ms latency + 2 periods = 8 ms: an impact 30 ms from now is 38 ms after the state
    let plan = PlannedImpact {
        in_s: 0.03,
        theta_rad: 0.1,
        sin_theta: 0.1f32.sin(),
        cos_theta: 0.1f32.cos(),
        sin_alpha: 0.05f32.sin(),
        cos_alpha: 0.05f32.cos(),
        normal_velocity_mps: 0.4,
    };
    est.plan_impact(plan);
    let got = est.planned().expect("a plan");
    assert!((got.in_s - 0.038).abs() < 1e-7, "{}", got.in_s);
    assert_eq!(
        PlannedImpact { in_s: 0.038, ..got },
        PlannedImpact {
            in_s: 0.038,
            ..plan
        }
    );
    // a sample 3 periods after the state's moves the state time on by 6 ms
    est.step(Some(pose(flight(S0, 12.0 * f64::from(DT)))));
    let left = est.planned().expect("still planned").in_s;
    assert!((left - 0.032).abs() < 1e-7, "{left}");
    est.clear_plan();
    assert_eq!(est.planned(), None);
    // without a plan no period is an impact
    assert!(!est.impact_due());
}

#[test]
fn the_fit_restarts_on_the_reinit_after_th_outlier_in_a_row_not_before() {
    // reinit_after = 3 (default); gate 1 cm
    let mut est = fed(0.0, 20);
    let t0 = 19.0 * f64::from(DT);
    for k in 1..=3u32 {
        let t = t0 + f64::from(k) * f64::from(DT);
        let mut z = pose(flight(S0, t));
        z[1] += 0.05; // 5 cm off: an outlier
        let u = est.step(Some(z));
        assert_eq!(u.restarted, k == 3, "outlier {k}");
        if k < 3 {
            // the outlier is not used: the state is the prediction, the fit kept
            assert_eq!(est.samples(), 20);
            assert_close(state(est.at_sample()), flight(S0, t), 1e-4, "predicted");
        } else {
            // restarted from the measured pose
            assert_eq!(est.samples(), 1);
            assert_eq!(est.at_sample().y_m, z[1]);
        }
    }
}

/// Zumel & Erdmann eq. 2 and 21 in f64 (table much heavier than the body): the body's
/// (x', y', theta') after an impact at angle `theta` on a table at angle `alpha` whose
/// surface moves with `vn` along its normal (-sin alpha, cos alpha).
fn eq21(theta: f64, alpha: f64, v: [f64; 3], vn: f64) -> [f64; 3] {
    let beta = theta - alpha;
    let k = RHO / (RHO * RHO + L * L * beta.sin().powi(2)).sqrt();
    let n = [-alpha.sin() * k, alpha.cos() * k, L / RHO * beta.sin() * k];
    let q = [v[0], v[1], RHO * v[2]];
    let table = [-alpha.sin() * vn, alpha.cos() * vn, 0.0];
    let rel: f64 = (0..3).map(|i| n[i] * (q[i] - table[i])).sum();
    assert!(rel < 0.0, "closing contact");
    let after: Vec<f64> = (0..3).map(|i| q[i] - (1.0 + E) * rel * n[i]).collect();
    [after[0], after[1], after[2] / RHO]
}

#[test]
fn a_planned_impact_uses_the_angle_flown_to_not_the_plans() {
    // The body at the impact: theta 0.8 rad, falling; the plan said 0.79 rad (sin, cos of
    // 0.79 exact). The estimator rotates the plan's sin, cos by d = 0.01 rad to first
    // order (error d^2/2 = 5e-5); using the plan's angle, or getting the rotation's terms
    // wrong, moves sin beta by ~1e-2. Measured: the estimate is within 2.5e-4 of the hand
    // computation (theta' ~ 15 rad/s); the subtlest wrong term (sin = sin_p + d / cos_p)
    // is off by 5.6e-3 m/s in x' and 0.07 rad/s in theta'. Tolerance 1e-3.
    let (theta_c, alpha, vn) = (0.8f64, 0.3f64, 0.25f64);
    let at_hit = [0.02, 0.10, theta_c, 0.20, -1.80, 0.60];
    let dt = f64::from(DT);
    let t_hit = 19.0 * dt + 0.0007; // 0.7 ms after the 20th sample
    let s0 = flight(at_hit, -t_hit);
    let mut est = estimator(0.0);
    for k in 0..20 {
        assert!(!est.step(Some(pose(flight(s0, f64::from(k) * dt)))).impact);
    }
    let plan_theta = 0.79f64;
    est.plan_impact(PlannedImpact {
        in_s: 0.0007,
        theta_rad: plan_theta as f32,
        sin_theta: plan_theta.sin() as f32,
        cos_theta: plan_theta.cos() as f32,
        sin_alpha: alpha.sin() as f32,
        cos_alpha: alpha.cos() as f32,
        normal_velocity_mps: vn as f32,
    });
    assert!(est.impact_due());
    // the sample of this period is not used (pass a wrong one to show it)
    let u = est.step(Some([9.0, 9.0, 9.0]));
    assert_eq!(
        u,
        FlightUpdate {
            impact: true,
            restarted: false
        }
    );
    assert_eq!(est.planned(), None);
    assert!(est.valid());
    // by hand: eq. 21 at the impact, then ballistic for the rest of the period
    let v = eq21(theta_c, alpha, [at_hit[3], at_hit[4], at_hit[5]], vn);
    let after = [at_hit[0], at_hit[1], at_hit[2], v[0], v[1], v[2]];
    let expect = flight(after, dt - 0.0007);
    assert_close(state(est.at_sample()), expect, 1e-3, "after the impact");
    // and it is not the flight without the impact
    assert!((state(est.at_sample())[4] - flight(at_hit, dt - 0.0007)[4]).abs() > 1.0);
}
