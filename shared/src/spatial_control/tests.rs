use super::*;
use crate::spatial::SpatialBall;
use proptest::prelude::*;

fn controller() -> SpatialController {
    SpatialController::new(SpatialControlParams::default()).expect("defaults are valid")
}

/// A frame with the ball at `ball` and the joints at home, at rest.
fn frame(seq: u32, ball: [f32; 3]) -> SpatialFrame {
    SpatialFrame {
        seq,
        ball_m: ball,
        joints_rad: SpatialControlParams::default().home_rad,
        joint_rates_radps: [0.0; 3],
    }
}

#[test]
fn validation_names_the_bad_field() {
    let bad = |f: fn(&mut SpatialControlParams)| {
        let mut p = SpatialControlParams::default();
        f(&mut p);
        SpatialController::new(p).err()
    };
    assert_eq!(bad(|p| p.dt_s = 0.0), Some(ParamError::NotPositive("dt_s")));
    assert_eq!(
        bad(|p| p.limits[1].max_rad = p.limits[1].min_rad),
        Some(ParamError::OutOfRange("limits.q2.max_rad"))
    );
    assert_eq!(
        bad(|p| p.limits[2].accel_max_radps2 = -1.0),
        Some(ParamError::NotPositive("limits.q3.accel_max_radps2"))
    );
    assert_eq!(
        bad(|p| p.home_rad[0] = 4.0),
        Some(ParamError::OutOfRange("home_rad.q1"))
    );
    assert_eq!(
        bad(|p| p.law.target_radius_m = 0.0),
        Some(ParamError::NotPositive("target_radius_m"))
    );
    assert_eq!(
        bad(|p| p.stale_limit_steps = 0),
        Some(ParamError::NotPositive("stale_limit_steps"))
    );
}

#[test]
fn a_bad_frame_is_the_safe_state_with_its_fault_and_brakes() {
    let mut c = controller();
    let mut f = frame(1, [1.0, 0.0, 0.5]);
    f.joint_rates_radps = [1.0, -2.0, 0.5];
    c.step(&f);
    let mut nan = frame(2, [f32::NAN, 0.0, 0.5]);
    nan.joint_rates_radps = f.joint_rates_radps;
    let cmd = c.step(&nan);
    assert_eq!((cmd.mode, cmd.fault), (Mode::Safe, Fault::NonFinite));
    // each joint braked against its rate, at most its limit
    for (u, w) in cmd.accel_radps2.iter().zip(f.joint_rates_radps) {
        assert!(u * w < 0.0 && u.abs() <= 500.0, "{u} against {w}");
    }
    let far = frame(3, [11.0, 0.0, 0.5]);
    assert_eq!(c.step(&far).fault, Fault::OutOfRange);
    let mut bent = frame(4, [1.0, 0.0, 0.5]);
    bent.joints_rad[1] = 0.0; // past the shoulder's limit and its margin
    assert_eq!(c.step(&bent).fault, Fault::OutOfRange);
    // not latched: a good frame is served again
    assert_eq!(c.step(&frame(5, [1.0, 0.0, 0.5])).mode, Mode::Hold);
}

#[test]
fn a_frame_that_stops_advancing_goes_stale_after_the_limit() {
    let mut c = controller();
    let f = frame(7, [1.0, 0.0, 0.5]);
    for _ in 0..=SpatialControlParams::default().stale_limit_steps {
        assert_ne!(c.step(&f).mode, Mode::Safe);
    }
    assert_eq!(c.step(&f).fault, Fault::Stale);
}

/// The ball's true flight sampled by the controller at the default rate, joints at home:
/// the estimate converges to the ball, then the command tracks the law's references.
#[test]
fn a_ballistic_ball_is_estimated_and_the_law_tracked() {
    let mut c = controller();
    let g = 9.81;
    let start = SpatialBall::new([1.05f64, 0.05, 0.6], [-0.1, 0.05, 0.0]);
    let dt = 0.001;
    let mut last = SpatialCommand::default();
    for k in 0..200u32 {
        let b = start.flown(k as f64 * dt, g);
        let p = b.position_m.map(|x| x as f32);
        last = c.step(&frame(k + 1, p));
    }
    assert_eq!(last.mode, Mode::Track);
    let truth = start.flown(199.0 * dt, g);
    let est = c.estimate().ball;
    for i in 0..3 {
        assert!((est.position_m[i] as f64 - truth.position_m[i]).abs() < 1e-4);
        assert!((est.velocity_mps[i] as f64 - truth.velocity_mps[i]).abs() < 1e-2);
    }
    let r = c.law().reference(&est);
    assert_eq!(last.angle_ref_rad, r.angles_rad);
}

/// Independent of the controller: a ball falling straight onto the paddle held level
/// (q2 = -pi/2, normal up) leaves it at -alpha times its impact speed; the estimator's
/// prediction applies that at the crossing, before any sample after it.
#[test]
fn the_estimator_bounces_the_ball_off_the_paddles_plane() {
    let p = SpatialControlParams::default();
    let mut est = SpatialEstimator::new(p.estimator, p.dt_s, 9.81).unwrap();
    let level = PaddleFrame::from_sin_cos([(0.0, 1.0), (0.0, 1.0), (0.0, 1.0)], [0.0; 3]);
    let g = 9.81f32;
    // falling from 0.2 m: crosses z = 0 after sqrt(0.4/g) = 0.2019 s
    let mut e = SpatialEstimate::default();
    let mut k = 0;
    while k < 201 {
        let t = k as f32 * p.dt_s;
        e = est.step(Some(&[1.0, 0.0, 0.2 - 0.5 * g * t * t]), &level);
        k += 1;
    }
    let before = e.ball.velocity_mps[2];
    assert!(before < -1.9, "{before}");
    let mut bounced = e;
    for _ in 0..5 {
        bounced = est.step(None, &level);
        if bounced.ball.velocity_mps[2] > 0.0 {
            break;
        }
    }
    let v = bounced.ball.velocity_mps[2];
    let expected = -p.estimator.restitution * before; // within one period's gravity
    assert!((v - expected).abs() < 0.05, "{v} against {expected}");
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(256))]
    /// Whatever the frame, the command is finite and within each joint's acceleration
    /// limit, or the safe command with a fault.
    #[test]
    fn every_command_is_within_the_limits_or_safe(
        ball in prop::array::uniform3(-12.0f32..12.0),
        joints in prop::array::uniform3(-4.0f32..4.0),
        rates in prop::array::uniform3(-50.0f32..50.0),
        steps in 1u32..40,
    ) {
        let mut c = controller();
        let l = SpatialControlParams::default().limits;
        for k in 0..steps {
            let f = SpatialFrame { seq: k + 1, ball_m: ball, joints_rad: joints, joint_rates_radps: rates };
            let cmd = c.step(&f);
            if cmd.mode == Mode::Safe {
                prop_assert_ne!(cmd.fault, Fault::None);
            }
            for (u, l) in cmd.accel_radps2.iter().zip(&l) {
                prop_assert!(u.is_finite() && u.abs() <= l.accel_max_radps2);
            }
        }
    }
}

/// With no feedback gains the command is the feed-forward alone: the second derivative of
/// eq. 13's angles along the ball's flight, computed here by central differences of the
/// angles (f64), not of the law's rates.
#[test]
fn with_no_feedback_the_command_is_the_references_acceleration_along_the_flight() {
    let mut p = SpatialControlParams::default();
    (p.kp_per_s2, p.kd_per_s) = (0.0, 0.0);
    let mut c = SpatialController::new(p).unwrap();
    let g = 9.81;
    let start = SpatialBall::new([1.05f64, 0.06, 0.6], [-0.2, 0.1, 0.5]);
    let dt = 0.001;
    let mut last = SpatialCommand::default();
    let steps = 150u32;
    for k in 0..steps {
        let b = start.flown(k as f64 * dt, g);
        last = c.step(&frame(k + 1, b.position_m.map(|x| x as f32)));
    }
    assert_eq!(last.mode, Mode::Track);
    let l64 = p.law;
    let law = crate::spatial::SpatialMirrorLaw::new(crate::spatial::SpatialLawParams {
        kappa0: l64.kappa0.into(),
        kappa1_s2pm2: l64.kappa1_s2pm2.into(),
        target_apex_m: l64.target_apex_m.into(),
        kappa10: l64.kappa10.into(),
        kappa11: l64.kappa11.into(),
        kappa20_radpm: l64.kappa20_radpm.into(),
        kappa21_radspm: l64.kappa21_radspm.into(),
        target_radius_m: l64.target_radius_m.into(),
        target_azimuth_rad: l64.target_azimuth_rad.into(),
        gravity_mps2: l64.gravity_mps2.into(),
    })
    .unwrap();
    let t = (steps - 1) as f64 * dt;
    let h = 1e-3;
    let angle = |s: f64| law.reference(&start.flown(s, g)).angles_rad;
    let (a, b, m) = (angle(t + h), angle(t - h), angle(t));
    for i in 0..3 {
        let want = (a[i] - 2.0 * m[i] + b[i]) / (h * h);
        let got = f64::from(last.accel_radps2[i]);
        assert!(
            (got - want).abs() < 0.02 * want.abs().max(1.0),
            "joint {i}: {got} against {want}"
        );
    }
    assert!(
        f64::from(last.accel_radps2[1]).abs() > 0.1,
        "a real acceleration"
    );
}

/// A camera that delivers each position `latency_s` late: the estimate is the ball now,
/// the delayed sample flown forward by the latency (checked against the true flight).
#[test]
fn the_estimate_is_the_ball_now_despite_the_cameras_latency() {
    let mut p = SpatialControlParams::default();
    p.estimator.latency_s = 0.01;
    let mut c = SpatialController::new(p).unwrap();
    let g = 9.81;
    let start = SpatialBall::new([1.0f64, -0.05, 0.7], [0.1, 0.2, 0.3]);
    let dt = 0.001;
    for k in 0..200u32 {
        let seen = start.flown(k as f64 * dt - 0.01, g);
        c.step(&frame(k + 1, seen.position_m.map(|x| x as f32)));
    }
    let now = start.flown(199.0 * dt, g);
    let est = c.estimate().ball;
    for i in 0..3 {
        assert!(
            (f64::from(est.position_m[i]) - now.position_m[i]).abs() < 2e-4,
            "axis {i}"
        );
        assert!(
            (f64::from(est.velocity_mps[i]) - now.velocity_mps[i]).abs() < 1e-2,
            "axis {i}"
        );
    }
}
