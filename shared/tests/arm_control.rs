//! The arm's B-spline tracker: tracking on an ideal joint, the braking tail in closed
//! form, torque limits for any input, the latched safe state, parameter names, wire size.

use dexter_core::arm_control::{ArmCommand, ArmController, ArmFrame, ArmParams};
use dexter_core::bspline::{Knots, MAX_KNOTS};
use dexter_core::fixed_rate::FixedRate;
use dexter_core::fixed_rate::{Fault, Mode};
use dexter_core::params::ParamError;
use proptest::prelude::*;

/// A windup-and-swing trajectory: rest at 0, back to -0.3 rad, up to 0.6 rad, moving.
fn params() -> ArmParams {
    let pts = [0.0, 0.0, 0.0, -0.3, -0.2, 0.3, 0.6, 0.9];
    ArmParams {
        trajectory: Knots::from_slice(&pts, 0.15).unwrap(),
        ..ArmParams::default()
    }
}

/// The joint the controller's model describes: J theta'' = tau - tau_g cos(theta),
/// integrated exactly enough (RK4, 10 substeps per period, torque held).
fn plant_step(p: &ArmParams, angle: f64, vel: f64, tau: f64) -> (f64, f64) {
    let acc = |th: f64| {
        (tau - p.gravity_torque_nm as f64 * (th + p.gravity_phase_rad as f64).cos())
            / p.inertia_kgm2 as f64
    };
    let h = p.dt_s as f64 / 10.0;
    let (mut x, mut v) = (angle, vel);
    for _ in 0..10 {
        let (k1x, k1v) = (v, acc(x));
        let (k2x, k2v) = (v + 0.5 * h * k1v, acc(x + 0.5 * h * k1x));
        let (k3x, k3v) = (v + 0.5 * h * k2v, acc(x + 0.5 * h * k2x));
        let (k4x, k4v) = (v + h * k3v, acc(x + h * k3x));
        x += h / 6.0 * (k1x + 2.0 * k2x + 2.0 * k3x + k4x);
        v += h / 6.0 * (k1v + 2.0 * k2v + 2.0 * k3v + k4v);
    }
    (x, v)
}

fn run(p: &ArmParams, steps: u32) -> (Vec<ArmCommand>, Vec<(f64, f64)>) {
    run_on(p, p, steps)
}

/// The controller built from `p` on the plant described by `plant`.
fn run_on(p: &ArmParams, plant: &ArmParams, steps: u32) -> (Vec<ArmCommand>, Vec<(f64, f64)>) {
    let mut c = ArmController::new(*p).unwrap();
    let (mut x, mut v) = (0.0f64, 0.0f64);
    let mut cmds = Vec::new();
    let mut states = Vec::new();
    for k in 0..steps {
        let cmd = c.step(&ArmFrame {
            seq: 100 + k,
            angle_rad: x as f32,
            velocity_radps: v as f32,
        });
        states.push((x, v));
        (x, v) = plant_step(plant, x, v, cmd.torque_nm as f64);
        cmds.push(cmd);
    }
    (cmds, states)
}

#[test]
fn tracks_the_spline_closely_within_the_torque_limit() {
    let p = params();
    let (cmds, states) = run(&p, 1500);
    let ctl = ArmController::new(p).unwrap();
    let mut worst = 0.0f64;
    for (k, (cmd, (x, _))) in cmds.iter().zip(&states).enumerate() {
        assert!(cmd.torque_nm.abs() <= p.limits.torque_max_nm);
        assert_eq!(cmd.fault, Fault::None);
        let r = ctl.reference(k as f32 * p.dt_s).angle_rad as f64;
        worst = worst.max((r - x).abs());
    }
    // feed-forward through the exact inverse dynamics: error from f32, ZOH and the
    // polynomial cosine only
    assert!(worst < 2e-3, "worst tracking error {worst} rad");
    assert_eq!(cmds[0].mode, Mode::Track);
    assert_eq!(cmds.last().unwrap().mode, Mode::Hold);
}

#[test]
fn dropping_the_gravity_term_makes_tracking_worse() {
    // the controller without its gravity model, on the same plant: only PD fights gravity
    let p = params();
    let (_, good) = run(&p, 900);
    let blind = ArmParams {
        gravity_torque_nm: 0.0,
        ..p
    };
    let (_, bad) = run_on(&blind, &p, 900);
    let ctl = ArmController::new(p).unwrap();
    let err = |s: &[(f64, f64)]| {
        s.iter()
            .enumerate()
            .map(|(k, (x, _))| (ctl.reference(k as f32 * 0.001).angle_rad as f64 - x).abs())
            .fold(0.0, f64::max)
    };
    assert!(err(&good) < 2e-3, "{}", err(&good));
    assert!(
        err(&bad) > 3.0 * err(&good),
        "{} vs {}",
        err(&bad),
        err(&good)
    );
}

#[test]
fn after_the_spline_the_joint_brakes_at_the_set_rate_then_holds() {
    let p = params();
    let c = ArmController::new(p).unwrap();
    let t_end = p.trajectory.duration_s();
    let end = p.trajectory.sample(t_end).unwrap();
    let w = end.velocity_radps as f64;
    assert!(w > 0.5, "test trajectory ends moving");
    let a = p.brake_accel_radps2 as f64;
    let s = 0.5 * w / a;
    let r = c.reference(t_end + s as f32);
    let expect = end.angle_rad as f64 + w * s - 0.5 * a * s * s;
    assert!((r.angle_rad as f64 - expect).abs() < 1e-5);
    assert!((r.velocity_radps as f64 - 0.5 * w).abs() < 1e-4);
    assert_eq!(r.accel_radps2 as f64, -a);
    let hold = c.reference(t_end + 10.0);
    let stop = end.angle_rad as f64 + w * w / (2.0 * a);
    assert!((hold.angle_rad as f64 - stop).abs() < 1e-5);
    assert_eq!((hold.velocity_radps, hold.accel_radps2), (0.0, 0.0));
}

#[test]
fn time_follows_sequence_numbers_not_calls() {
    let p = params();
    let mut a = ArmController::new(p).unwrap();
    let mut b = ArmController::new(p).unwrap();
    let f = |seq| ArmFrame {
        seq,
        angle_rad: 0.0,
        velocity_radps: 0.0,
    };
    a.step(&f(7));
    let ca = a.step(&f(207)); // 200 periods later, one call
    b.step(&f(7));
    for s in 8..=207 {
        b.step(&f(s));
    }
    let cb = b.step(&f(207)); // repeated sample: same time
    assert_eq!(ca.angle_ref_rad, cb.angle_ref_rad);
    assert_eq!(ca.angle_ref_rad, a.reference(0.2).angle_rad);
}

#[test]
fn faults_latch_and_the_safe_state_brakes_to_rest() {
    let p = params();
    let mut c = ArmController::new(p).unwrap();
    let (mut x, mut v) = (0.0f64, 0.0f64);
    for k in 0..400 {
        let cmd = c.step(&ArmFrame {
            seq: k,
            angle_rad: x as f32,
            velocity_radps: v as f32,
        });
        (x, v) = plant_step(&p, x, v, cmd.torque_nm as f64);
    }
    assert!(v.abs() > 0.5, "moving when the fault comes");
    let bad = c.step(&ArmFrame {
        seq: 400,
        angle_rad: f32::NAN,
        velocity_radps: 0.0,
    });
    assert_eq!((bad.mode, bad.fault), (Mode::Safe, Fault::NonFinite));
    (x, v) = plant_step(&p, x, v, bad.torque_nm as f64);
    for k in 401..800 {
        let cmd = c.step(&ArmFrame {
            seq: k,
            angle_rad: x as f32,
            velocity_radps: v as f32,
        });
        assert_eq!((cmd.mode, cmd.fault), (Mode::Safe, Fault::NonFinite));
        assert!(cmd.torque_nm.abs() <= p.limits.torque_max_nm);
        (x, v) = plant_step(&p, x, v, cmd.torque_nm as f64);
    }
    assert!(v.abs() < 0.05, "still moving at {v} rad/s");
}

#[test]
fn stale_input_and_a_large_tracking_error_fault() {
    let p = params();
    let mut c = ArmController::new(p).unwrap();
    let f = ArmFrame::default();
    for _ in 0..=p.stale_limit_steps {
        assert_eq!(c.step(&f).fault, Fault::None);
    }
    assert_eq!(c.step(&f).fault, Fault::Stale);
    let mut c = ArmController::new(p).unwrap();
    let far = ArmFrame {
        seq: 0,
        angle_rad: 0.5,
        velocity_radps: 0.0,
    };
    assert_eq!(c.step(&far).fault, Fault::OutOfRange);
    assert!((c.tracking_error_rad() + 0.5).abs() < 1e-6);
}

#[test]
fn invalid_params_are_named() {
    let named = |f: fn(&mut ArmParams), e: ParamError| {
        let mut p = params();
        f(&mut p);
        assert_eq!(ArmController::new(p).unwrap_err(), e);
    };
    named(
        |p| p.limits.accel_max_radps2 = 50.0,
        ParamError::OutOfRange("limits.accel_max_radps2"),
    );
    named(
        |p| p.limits.max_angle_rad = -2.0,
        ParamError::OutOfRange("limits.max_angle_rad"),
    );
    named(
        |p| p.limits.velocity_max_radps = 0.0,
        ParamError::NotPositive("limits.velocity_max_radps"),
    );
    named(
        |p| p.brake_accel_radps2 = 31.0,
        ParamError::OutOfRange("brake_accel_radps2"),
    );
    named(
        |p| p.brake_accel_radps2 = 0.3, // stops beyond the joint limit
        ParamError::OutOfRange("brake_accel_radps2"),
    );
    named(
        |p| p.trajectory.points_rad[4] = 1.0, // (1.0 + 0.3) / 0.15 = 8.7 rad/s > 8
        ParamError::OutOfRange("trajectory.points_rad"),
    );
    named(
        |p| p.trajectory.points_rad[0] = 3.0,
        ParamError::OutOfRange("trajectory.points_rad"),
    );
    named(
        |p| p.trajectory.count = MAX_KNOTS as u8 + 1,
        ParamError::OutOfRange("trajectory.count"),
    );
    named(
        |p| p.stale_limit_steps = 0,
        ParamError::NotPositive("stale_limit_steps"),
    );
}

#[test]
fn params_fit_the_wire_budget() {
    let p = ArmParams {
        trajectory: Knots::from_slice(&[0.25; MAX_KNOTS], 0.1).unwrap(),
        ..params()
    };
    let bytes = postcard::to_allocvec(&p).unwrap();
    assert!(bytes.len() <= 200, "{} bytes", bytes.len());
    let back: ArmParams = postcard::from_bytes(&bytes).unwrap();
    assert_eq!(back, p);
}

fn any_f32() -> impl Strategy<Value = f32> {
    prop_oneof![
        any::<u32>().prop_map(f32::from_bits),
        -3.0f32..3.0,
        Just(f32::NAN),
        Just(f32::INFINITY),
        Just(0.0f32),
    ]
}

proptest! {
    #[test]
    fn any_frames_give_a_bounded_command_or_the_safe_state(
        frames in prop::collection::vec((0u32..3, any_f32(), any_f32()), 1..200)
    ) {
        let p = params();
        let mut c = ArmController::new(p).unwrap();
        let mut seq = 0u32;
        for (ds, x, v) in frames {
            seq = seq.wrapping_add(ds);
            let cmd = c.step(&ArmFrame { seq, angle_rad: x, velocity_radps: v });
            prop_assert!(cmd.torque_nm.is_finite());
            prop_assert!(cmd.torque_nm.abs() <= p.limits.torque_max_nm);
            prop_assert!(cmd.accel_cmd_radps2.abs() <= p.limits.accel_max_radps2);
            prop_assert_eq!(cmd.mode == Mode::Safe, cmd.fault != Fault::None);
        }
    }
}
