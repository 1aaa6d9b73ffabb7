//! The one-joint arm's tracker (`arm_control`) against hand computations: the torque of the
//! rigid arm's inverse dynamics `J u + tau_g cos(theta + phi_g)` (exact `cos` in f64, a
//! nonzero phase) and its clamp, the braking tail after a trajectory that ends moving down
//! (closed form, exactly representable numbers so the boundaries are hit exactly), the
//! safe state's dead-reckoned braking to rest, the edges of the frame and parameter checks,
//! and the `Reply` view. A mutation pass over `arm_control.rs` found these unpinned by the
//! core's own tests.

use dexter_core::arm_control::{ArmCommand, ArmController, ArmFrame, ArmParams};
use dexter_core::bspline::Knots;
use dexter_core::fixed_rate::{Fault, FixedRate, Mode, Reply};
use dexter_core::params::ParamError;

/// Default arm (J = 2.2 kg m^2, tau_g = 25 N m, 100 N m, 30 rad/s^2, 8 rad/s, +-1.6 rad),
/// with the trajectory `points` of segment `h` s.
fn arm(points: &[f32], h: f32) -> ArmParams {
    ArmParams {
        trajectory: Knots::from_slice(points, h).unwrap(),
        ..ArmParams::default()
    }
}

fn frame(seq: u32, angle_rad: f32, velocity_radps: f32) -> ArmFrame {
    ArmFrame {
        seq,
        angle_rad,
        velocity_radps,
    }
}

fn close(got: f32, expect: f64, tol: f64) -> bool {
    (got as f64 - expect).abs() <= tol
}

/// `tau = J u + tau_g cos(theta + phi_g)`, clamped to +-tau_max, by hand in f64.
#[test]
fn the_torque_is_the_inverse_dynamics_with_the_gravity_phase_and_is_clamped() {
    let p = ArmParams {
        gravity_phase_rad: 0.4,
        ..arm(&[0.0; 4], 0.1)
    };
    let c = ArmController::new(p).unwrap();
    for &(u, th) in &[
        (0.0, 0.0),
        (10.0, 0.5),
        (-20.0, -1.2),
        (30.0, -0.4),
        (-30.0, 1.5),
        (5.0, 2.0),
    ] {
        let expect = 2.2 * u as f64 + 25.0 * (th as f64 + 0.4).cos();
        let got = c.torque_for(u, th);
        assert!(
            close(got, expect, 1e-4),
            "u {u} theta {th}: {got} vs {expect}"
        );
    }
    // beyond the motor: exactly the limit, with the sign of the demand
    assert_eq!(c.torque_for(100.0, 0.0), 100.0);
    assert_eq!(c.torque_for(-100.0, 0.0), -100.0);
    // just inside: 2.2 * 34 + 25 cos(0.6) = 95.43 N m, not clamped
    assert!(close(
        c.torque_for(34.0, 0.2),
        74.8 + 25.0 * 0.6f64.cos(),
        1e-4
    ));
}

/// A trajectory that ends moving down: P = [1/2, 1/2, 1/2, 1/4, 0], h = 1/8 s, so at
/// T = 1/4 s theta = (P2 + 4 P3 + P4)/6 = 1/4 rad, theta' = (P4 - P2)/(2h) = -2 rad/s,
/// theta'' = (P2 - 2 P3 + P4)/h^2 = 0; braking at a = 16 rad/s^2 stops it in |w|/a = 1/8 s
/// at 1/4 - 4/32 = 1/8 rad. Every number is a short binary fraction, so f32 hits the
/// boundaries t = T and t = T + 1/8 exactly.
#[test]
fn the_braking_tail_of_a_downward_end_by_hand() {
    let p = ArmParams {
        brake_accel_radps2: 16.0,
        ..arm(&[0.5, 0.5, 0.5, 0.25, 0.0], 0.125)
    };
    let c = ArmController::new(p).unwrap();
    let at = |t: f32| {
        let r = c.reference(t);
        (r.angle_rad, r.velocity_radps, r.accel_radps2)
    };
    // at T still the spline (its acceleration 0, not the brake's)
    assert_eq!(at(0.25), (0.25, -2.0, 0.0));
    // half-way: 1/4 - 2/16 + 16/2/256, -2 + 16/16, +16
    assert_eq!(at(0.3125), (0.15625, -1.0, 16.0));
    // at the stop instant exactly: at rest, no more braking
    assert_eq!(at(0.375), (0.125, 0.0, 0.0));
    assert_eq!(at(1.25), (0.125, 0.0, 0.0));
    // the mirror image ends moving up and brakes downward
    let up = ArmParams {
        brake_accel_radps2: 16.0,
        ..arm(&[-0.5, -0.5, -0.5, -0.25, 0.0], 0.125)
    };
    let c = ArmController::new(up).unwrap();
    let r = c.reference(0.3125);
    assert_eq!(
        (r.angle_rad, r.velocity_radps, r.accel_radps2),
        (-0.15625, 1.0, -16.0)
    );
    assert_eq!(c.reference(0.375).angle_rad, -0.125);
}

/// With `dt = 2^-10` s and `h = 1/8` s the trajectory's end `T = 3/8` s is step 384
/// exactly: the command is `Track` up to and including it, `Hold` after (the reference at
/// rest past the end). The measurement is the reference itself (perfect tracking).
#[test]
fn the_mode_turns_to_hold_only_after_the_end_of_a_trajectory_that_ends_at_rest() {
    let p = ArmParams {
        dt_s: 1.0 / 1024.0,
        ..arm(&[0.0, 0.0, 0.0, 0.5, 0.5, 0.5], 0.125)
    };
    let mut c = ArmController::new(p).unwrap();
    let probe = ArmController::new(p).unwrap();
    for k in 0..=400u32 {
        let r = probe.reference(k as f32 / 1024.0);
        let cmd = c.step(&frame(k, r.angle_rad, r.velocity_radps));
        let expect = if k <= 384 { Mode::Track } else { Mode::Hold };
        assert_eq!(cmd.mode, expect, "step {k}");
        assert_eq!(cmd.fault, Fault::None);
    }
}

/// A measurement is plausible within 5 % of the joint's range beyond either limit (here
/// +-1.6 rad: 0.16 rad) and at up to twice the speed limit (16 rad/s), else the controller
/// faults `OutOfRange`. The trajectory rests at the limit, so the tracking error (< 0.2 rad)
/// is not what faults.
#[test]
fn implausible_frames_fault_at_the_documented_margins() {
    let fault_at = |rest: f32, angle: f32, velocity: f32| {
        let mut c = ArmController::new(arm(&[rest; 4], 0.1)).unwrap();
        c.step(&frame(0, angle, velocity)).fault
    };
    assert_eq!(fault_at(1.6, 1.75, 0.0), Fault::None);
    assert_eq!(fault_at(1.6, 1.77, 0.0), Fault::OutOfRange);
    assert_eq!(fault_at(-1.6, -1.75, 0.0), Fault::None);
    assert_eq!(fault_at(-1.6, -1.77, 0.0), Fault::OutOfRange);
    for v in [12.0, 16.0, -16.0] {
        assert_eq!(fault_at(0.0, 0.0, v), Fault::None, "{v} rad/s");
    }
    for v in [16.01, -16.01] {
        assert_eq!(fault_at(0.0, 0.0, v), Fault::OutOfRange, "{v} rad/s");
    }
}

/// A tracking error of exactly `max_tracking_error_rad` is tolerated, a larger one faults.
#[test]
fn the_tracking_error_faults_only_beyond_its_limit() {
    let step = |angle: f32| {
        let mut c = ArmController::new(arm(&[0.0; 4], 0.1)).unwrap();
        let cmd = c.step(&frame(0, angle, 0.0));
        (cmd.fault, c.tracking_error_rad())
    };
    assert_eq!(step(-0.2), (Fault::None, 0.2));
    assert_eq!(step(0.2), (Fault::None, -0.2));
    let (fault, err) = step(-0.2001);
    assert_eq!(fault, Fault::OutOfRange);
    assert!(close(err, 0.2001, 1e-6));
}

/// A sequence number half the counter's range ahead (or more) is an old frame: it keeps
/// the trajectory's time and counts as a repeat; one less is new and moves the time.
#[test]
fn a_frame_half_the_counter_ahead_is_old_not_new() {
    let p = arm(&[0.0, 0.0, 0.0, 0.1, 0.2, 0.3], 0.1);
    let mut c = ArmController::new(p).unwrap();
    assert_eq!(c.step(&frame(10, 0.0, 0.0)).angle_ref_rad, 0.0);
    let half = 10u32.wrapping_add(u32::MAX / 2);
    for _ in 0..p.stale_limit_steps {
        let cmd = c.step(&frame(half, 0.0, 0.0));
        assert_eq!((cmd.fault, cmd.angle_ref_rad), (Fault::None, 0.0));
    }
    assert_eq!(c.step(&frame(half, 0.0, 0.0)).fault, Fault::Stale);
    // one period ahead is new: time 1 ms
    let mut c = ArmController::new(p).unwrap();
    c.step(&frame(10, 0.0, 0.0));
    let cmd = c.step(&frame(11, 0.0, 0.0));
    assert_eq!(cmd.angle_ref_rad, c.reference(0.001).angle_rad);
    assert!(cmd.angle_ref_rad > 0.0);
}

/// After a fault the controller ignores the frames and brakes its last valid measurement
/// with `clamp(-v/dt, +-a_max)`, dead-reckoning `x + v dt + u dt^2/2`, `v + u dt`, and
/// commands the torque of that acceleration at the angle it believes (phase 0.3 rad).
/// By hand in f64 from (0.05 rad, 2 rad/s): 66 periods at -30 rad/s^2, then the rest in
/// one period, then gravity compensation alone at the stop angle, about
/// 0.05 + 2^2 / (2 * 30) rad.
#[test]
fn the_safe_state_dead_reckons_its_braking_to_rest_by_hand() {
    let p = ArmParams {
        gravity_phase_rad: 0.3,
        ..arm(&[0.0; 4], 0.1)
    };
    let mut c = ArmController::new(p).unwrap();
    assert_eq!(c.step(&frame(0, 0.05, 2.0)).fault, Fault::None);
    let (dt, a) = (0.001f64, 30.0f64);
    let (mut x, mut v) = (0.05f64, 2.0f64);
    for k in 1..120u32 {
        // the frames are ignored: a NaN first, then nonsense
        let f = if k == 1 {
            frame(k, f32::NAN, 0.0)
        } else {
            frame(k, -1.0, 5.0)
        };
        let cmd = c.step(&f);
        let u = (-v / dt).clamp(-a, a);
        let tau = 2.2 * u + 25.0 * (x + 0.3).cos();
        x += v * dt + 0.5 * u * dt * dt;
        v += u * dt;
        assert_eq!(
            (cmd.seq, cmd.mode, cmd.fault),
            (k, Mode::Safe, Fault::NonFinite)
        );
        // the f32 speed carries ~1e-6 rad/s of rounding, which -v/dt turns into ~1e-3
        let got_u = cmd.accel_cmd_radps2;
        assert!(close(got_u, u, 0.02), "step {k}: u {got_u} vs {u}");
        assert!(close(cmd.torque_nm, tau, 0.05), "step {k}: torque");
        assert!(close(cmd.angle_ref_rad, x, 1e-5), "step {k}: angle");
        assert_eq!(cmd.velocity_ref_radps, 0.0);
    }
    assert!(v.abs() < 1e-9, "the hand model is at rest");
    assert_eq!(c.fault(), Fault::NonFinite);
    // at rest: only gravity, at 0.05 + 2^2/60 = 0.1167 rad
    assert!((x - (0.05 + 4.0 / 60.0)).abs() < 1e-3);
}

/// The torque budget `J a_max + tau_g <= tau_max` holds with equality (2.5 * 30 + 25 =
/// 100 N m) and fails just above; a control-point step of exactly `v_max h` (8 * 1/8 =
/// 1 rad) is allowed, a larger one not; equal joint limits are refused under the joint's
/// own name.
#[test]
fn parameter_checks_hold_at_their_edges() {
    let base = arm(&[0.0; 4], 0.1);
    let budget = ArmParams {
        inertia_kgm2: 2.5,
        ..base
    };
    assert_eq!(budget.validate(), Ok(()));
    let over = ArmParams {
        gravity_torque_nm: 25.01,
        ..budget
    };
    assert_eq!(
        over.validate(),
        Err(ParamError::OutOfRange("limits.accel_max_radps2"))
    );
    let step = arm(&[0.0, 0.0, 0.0, 1.0, 1.0, 1.0], 0.125);
    assert_eq!(step.validate(), Ok(()));
    let steeper = arm(&[0.0, 0.0, 0.0, 1.001, 1.001, 1.001], 0.125);
    assert_eq!(
        steeper.validate(),
        Err(ParamError::OutOfRange("trajectory.points_rad"))
    );
    let falling = arm(&[1.001, 1.001, 1.001, 0.0, 0.0, 0.0], 0.125);
    assert_eq!(
        falling.validate(),
        Err(ParamError::OutOfRange("trajectory.points_rad"))
    );
    let mut flat = base;
    flat.limits.min_angle_rad = 0.0;
    flat.limits.max_angle_rad = 0.0;
    assert_eq!(
        flat.validate(),
        Err(ParamError::OutOfRange("limits.max_angle_rad"))
    );
    let named = |f: fn(&mut ArmParams), e: ParamError| {
        let mut p = base;
        f(&mut p);
        assert_eq!(p.validate(), Err(e));
        assert_eq!(ArmController::new(p).unwrap_err(), e);
    };
    named(|p| p.dt_s = 0.0, ParamError::NotPositive("dt_s"));
    named(
        |p| p.limits.min_angle_rad = f32::NAN,
        ParamError::NotFinite("limits.min_angle_rad"),
    );
    named(
        |p| p.limits.max_angle_rad = f32::INFINITY,
        ParamError::NotFinite("limits.max_angle_rad"),
    );
    named(
        |p| p.limits.accel_max_radps2 = 0.0,
        ParamError::NotPositive("limits.accel_max_radps2"),
    );
    named(
        |p| p.limits.torque_max_nm = 0.0,
        ParamError::NotPositive("limits.torque_max_nm"),
    );
    named(
        |p| p.kp_per_s2 = -1.0,
        ParamError::Negative("tracking.kp_per_s2"),
    );
    named(
        |p| p.inertia_kgm2 = 0.0,
        ParamError::NotPositive("inertia_kgm2"),
    );
    named(
        |p| p.gravity_torque_nm = -1.0,
        ParamError::Negative("gravity_torque_nm"),
    );
    named(
        |p| p.gravity_phase_rad = f32::NAN,
        ParamError::NotFinite("gravity_phase_rad"),
    );
    named(
        |p| p.brake_accel_radps2 = 0.0,
        ParamError::NotPositive("brake_accel_radps2"),
    );
    named(
        |p| p.max_tracking_error_rad = 0.0,
        ParamError::NotPositive("max_tracking_error_rad"),
    );
    named(
        |p| p.trajectory.segment_s = 0.0,
        ParamError::NotPositive("trajectory.segment_s"),
    );
}

/// The trajectory `[P1, P1, P1, theta_T, P3]`, `P1,3 = theta_T -+ w h` (h = 1/8 s), ends at
/// `theta_T` moving at `w`; braking at `a` it stops at `theta_T + sgn(w) w^2 / (2 a)`
/// (closed form in f64), which the validator must accept exactly when it is within
/// +-1.6 rad.
#[test]
fn the_braking_stop_angle_is_checked_against_the_joint_limits_by_hand() {
    let h = 0.125f64;
    let mut checked = 0;
    for &end in &[-1.2f64, -0.2, 0.2, 1.2] {
        for &w in &[-2.0f64, 2.0] {
            for &a in &[0.5f64, 1.0, 1.25, 2.0, 2.5, 5.0, 30.0] {
                let (p1, p3) = ((end - w * h) as f32, (end + w * h) as f32);
                let p = ArmParams {
                    brake_accel_radps2: a as f32,
                    ..arm(&[p1, p1, p1, end as f32, p3], h as f32)
                };
                let stop = end + w.signum() * w * w / (2.0 * a);
                if (stop.abs() - 1.6).abs() < 1e-3 {
                    continue;
                }
                let expect = if stop.abs() <= 1.6 {
                    Ok(())
                } else {
                    Err(ParamError::OutOfRange("brake_accel_radps2"))
                };
                assert_eq!(p.validate(), expect, "end {end} w {w} a {a}: stop {stop}");
                checked += 1;
            }
        }
    }
    assert!(checked > 50);
}

/// `Reply`: the command's own seq, mode and fault; `bit_identical` compares every field's
/// bits (so -0.0 differs from 0.0 and a NaN equals the same NaN).
#[test]
fn the_reply_view_and_bit_identity_compare_every_field() {
    let cmd = ArmCommand {
        seq: 7,
        torque_nm: 1.5,
        accel_cmd_radps2: -2.0,
        angle_ref_rad: 0.25,
        velocity_ref_radps: f32::NAN,
        mode: Mode::Safe,
        fault: Fault::Stale,
    };
    assert_eq!(
        (cmd.seq(), cmd.mode(), cmd.fault()),
        (7, Mode::Safe, Fault::Stale)
    );
    assert!(cmd.bit_identical(&cmd));
    let changed: [fn(&mut ArmCommand); 7] = [
        |c| c.seq = 8,
        |c| c.torque_nm = 1.5000001,
        |c| c.accel_cmd_radps2 = -2.0000002,
        |c| c.angle_ref_rad = 0.2500001,
        |c| c.velocity_ref_radps = 0.0,
        |c| c.mode = Mode::Track,
        |c| c.fault = Fault::NonFinite,
    ];
    for (i, f) in changed.iter().enumerate() {
        let mut other = cmd;
        f(&mut other);
        assert!(!cmd.bit_identical(&other), "field {i}");
        assert!(!other.bit_identical(&cmd), "field {i}");
    }
    let zero = ArmCommand::default();
    let neg = ArmCommand {
        torque_nm: -0.0,
        ..zero
    };
    assert!(!zero.bit_identical(&neg));
}

/// Through the `FixedRate` trait: the same controller, its parameters back, no telemetry.
#[test]
fn the_fixed_rate_view_is_the_controller() {
    let p = ArmParams {
        gravity_phase_rad: 0.3,
        ..arm(&[0.0, 0.0, 0.0, 0.1, 0.2, 0.3], 0.1)
    };
    let mut c = <ArmController as FixedRate>::new(p).unwrap();
    assert_eq!(*FixedRate::params(&c), p);
    let mut d = ArmController::new(p).unwrap();
    for k in 0..50 {
        let f = frame(k, 0.001 * k as f32, 0.1);
        let a = FixedRate::step(&mut c, &f);
        assert!(a.bit_identical(&d.step(&f)));
    }
    let a = FixedRate::safe(&mut c, 50, Fault::Stale);
    assert!(a.bit_identical(&d.safe(50, Fault::Stale)));
    assert_eq!(a.fault, Fault::Stale);
    assert_eq!(FixedRate::telemetry(&c), Default::default());
}

/// The move to the catch, by hand: the spline 0, 0, 0, 0.1, 0.2, 0.3 of 0.1 s segments ends
/// (T = 0.3 s) at (0.1 + 4 * 0.2 + 0.3) / 6 = 0.2 rad moving at (0.3 - 0.1) / 0.2 = 1 rad/s.
/// To rest at -0.1 rad under a = 30: the brake alone would stop 1/60 rad on, so the move
/// brakes first (sigma = -1), peaks at w_1 = -sqrt(30 * 0.3 + 1/2) = -sqrt(9.5) rad/s after
/// (1 + sqrt(9.5)) / 30 s, and decelerates for sqrt(9.5) / 30 s to rest at -0.1 rad.
#[test]
fn the_move_to_the_catch_is_the_bang_bang_to_its_angle() {
    let p = ArmParams {
        catches: true,
        catch_angle_rad: -0.1,
        ..arm(&[0.0, 0.0, 0.0, 0.1, 0.2, 0.3], 0.1)
    };
    let c = ArmController::new(p).unwrap();
    let w1 = 9.5_f64.sqrt();
    let (t1, t2) = ((1.0 + w1) / 30.0, w1 / 30.0);
    let t = |s: f64| (0.3 + s) as f32;
    assert_eq!(c.reference(t(0.5 * t1)).accel_radps2, -30.0);
    assert_eq!(c.reference(t(t1 + 0.5 * t2)).accel_radps2, 30.0);
    let peak = c.reference(t(t1));
    assert!(close(peak.velocity_radps, -w1, 1e-4), "{peak:?}");
    let rest = c.reference(t(t1 + t2 + 0.01));
    assert!(close(rest.angle_rad, -0.1, 1e-5), "{rest:?}");
    assert_eq!(rest.velocity_radps, 0.0);
    // the braking stop, passed before the joint turns back: 0.2 + 1/60 rad
    let top = c.reference(t(1.0 / 30.0));
    assert!(close(top.angle_rad, 0.2 + 1.0 / 60.0, 1e-5), "{top:?}");
}

/// Without `catches` the same spline brakes to rest where that stops it: 0.2 + 1/60 rad.
#[test]
fn without_a_catch_the_move_is_the_brake() {
    let c = ArmController::new(arm(&[0.0, 0.0, 0.0, 0.1, 0.2, 0.3], 0.1)).unwrap();
    let rest = c.reference(0.3 + 0.1);
    assert!(close(rest.angle_rad, 0.2 + 1.0 / 60.0, 1e-5), "{rest:?}");
    assert_eq!(rest.velocity_radps, 0.0);
}

/// A catching angle outside the joint's range, or not finite, is refused by name.
#[test]
fn a_catch_angle_out_of_range_is_refused_by_name() {
    for bad in [2.0, f32::NAN] {
        let p = ArmParams {
            catches: true,
            catch_angle_rad: bad,
            ..arm(&[0.0; 4], 0.1)
        };
        let e = ArmController::new(p).unwrap_err();
        assert!(format!("{e:?}").contains("catch_angle_rad"), "{e:?}");
    }
}
