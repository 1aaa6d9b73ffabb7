//! The fixed-rate tilt controller (`dexter_core::tilt_control`): the table arrives where the
//! laws say at the predicted impact, the safe state, parameter validation, wire sizes, and
//! for any input a finite command within the limits or the safe state.

use dexter_core::fixed_rate::FixedRate;
use dexter_core::fixed_rate::{Fault, Mode};
use dexter_core::params::ParamError;
use dexter_core::tilt::{BodyState, EnergyFeedback};
use dexter_core::tilt_control::{PlanStatus, TiltCommand, TiltController, TiltFrame, TiltParams};
use proptest::prelude::*;

mod common;
use common::tilt::{flight, frame_at, table_after, true_contact, G};

/// Perfect camera (no latency), exact table axes (double integrators under the held
/// commands, f64): step the controller until its plan is committed and the predicted impact
/// time has passed; return the table (angle, rate, height, velocity) at the predicted time,
/// that time, and the commands seen.
fn run_to_predicted_impact(params: TiltParams, s0: [f64; 6]) -> ([f64; 4], f64, Vec<TiltCommand>) {
    let mut c = TiltController::new(params).unwrap();
    let dt = f64::from(params.dt_s);
    let mut table = [0.0f64; 4]; // alpha, alpha', h, h'
    let mut cmds = Vec::new();
    let mut predicted: Option<f64> = None;
    for k in 0..400u32 {
        let t = f64::from(k) * dt;
        let b = flight(s0, t);
        let frame = frame_at(k, b, table);
        let cmd = c.step(&frame);
        cmds.push(cmd);
        if cmd.plan == PlanStatus::Committed {
            predicted = Some(t + f64::from(cmd.impact_in_s));
        }
        // the table at the predicted time, if it falls in this period
        if let Some(tp) = predicted {
            if tp >= t && tp < t + dt {
                let s = tp - t;
                let at = table_after(table, &cmd, s);
                return (at, tp, cmds);
            }
        }
        table = table_after(table, &cmd, dt);
    }
    panic!("no committed plan came due");
}

#[test]
fn the_table_arrives_where_kappa_tilt_and_eq25_say_at_the_predicted_impact() {
    for (kappa_rate, s0) in [
        (0.0, [0.0, 0.25, 0.2, 0.3, 0.4, -1.2]),
        (0.0, [0.1, 0.30, -0.25, -0.4, 0.0, 0.9]),
        (0.01, [0.0, 0.22, 0.1, 0.0, 0.8, 1.4]),
    ] {
        let params = TiltParams {
            kappa_rate_s: kappa_rate,
            estimator: dexter_core::tilt_control::flight::FlightTuning {
                latency_s: 0.0,
                ..TiltParams::default().estimator
            },
            ..TiltParams::default()
        };
        let (table, tp, cmds) = run_to_predicted_impact(params, s0);
        let l = f64::from(params.l_m);
        // measured: time 8e-8 s, alpha 5e-6 rad, rate 1.4e-4 rad/s, height 1.1e-6 m,
        // stroke velocity 5.5e-5 m/s (f32 control, 2 ms periods)
        // the predicted time is eq. 7's root of the true flight
        let tc = true_contact(s0, l, 0.0);
        assert!((tp - tc).abs() < 1e-6, "predicted {tp} vs true {tc}");
        // independent targets from the true state at the contact, f64, with the core's
        // f64 eq. 25
        let b = flight(s0, tc);
        let alpha = f64::from(params.kappa) * b[2] + f64::from(kappa_rate) * b[5];
        let fb = EnergyFeedback::new(0.5f64, 0.165, G * 0.25, G, l).unwrap();
        let vt = fb.table_velocity(&BodyState::new(b[2], b[3], b[4], b[5]));
        let (sa, ca) = alpha.sin_cos();
        let vn = -sa * vt[0] + ca * vt[1];
        // the pivot under the centre of mass: the line through the contact point at y = 0
        let h = -alpha.tan() * l * b[2].sin();
        let hd = (vn + sa * b[3]) / ca;
        assert!(
            (table[0] - alpha).abs() < 2e-4,
            "alpha {} vs {alpha}",
            table[0]
        );
        assert!(table[1].abs() < 2e-3, "tilt rate at impact {}", table[1]);
        assert!((table[2] - h).abs() < 2e-5, "height {} vs {h}", table[2]);
        assert!(
            (table[3] - hd).abs() < 2e-3,
            "stroke velocity {} vs {hd}",
            table[3]
        );
        // within the limits all the way, never limited with these generous ones
        let p = &params;
        for c in &cmds {
            assert!(c.tilt_accel_radps2.abs() <= p.tilt.accel_max_radps2);
            assert!(c.stroke_accel_mps2.abs() <= p.stroke.accel_max_mps2);
            assert_ne!(c.plan, PlanStatus::Limited, "{c:?}");
            assert_ne!(c.mode, Mode::Safe);
        }
    }
}

fn frame(seq: u32, y: f32) -> TiltFrame {
    TiltFrame {
        seq,
        body_x_m: 0.0,
        body_y_m: y,
        body_theta_rad: 0.1,
        ..TiltFrame::default()
    }
}

#[test]
fn nan_out_of_range_and_stale_input_give_the_safe_state_then_recover() {
    let mut c: TiltController = TiltController::new(TiltParams::default()).unwrap();
    assert_eq!(c.step(&frame(0, 0.3)).mode, Mode::Hold);
    let mut f = frame(1, 0.3);
    f.body_theta_rad = f32::NAN;
    let cmd = c.step(&f);
    assert_eq!(
        (cmd.mode, cmd.fault, cmd.plan),
        (Mode::Safe, Fault::NonFinite, PlanStatus::Idle)
    );
    let mut f = frame(2, 0.3);
    f.table_velocity_mps = f32::INFINITY;
    assert_eq!(c.step(&f).fault, Fault::NonFinite);
    let mut f = frame(3, 0.3);
    f.body_theta_rad = 1.5; // beyond theta_max_rad = 1.4
    assert_eq!(c.step(&f).fault, Fault::OutOfRange);
    let mut f = frame(4, 0.3);
    f.table_angle_rad = 0.8; // beyond the tilt travel 0.7 plus 5 % of 1.4
    assert_eq!(c.step(&f).fault, Fault::OutOfRange);
    let mut f = frame(5, 0.3);
    f.table_angle_rad = 0.76; // inside the 5 % margin
    assert_eq!(c.step(&f).fault, Fault::None);
    // the same sequence number: stale after stale_limit_steps (5) repeats
    for _ in 0..5 {
        assert_eq!(c.step(&frame(5, 0.3)).fault, Fault::None);
    }
    assert_eq!(c.step(&frame(5, 0.3)).fault, Fault::Stale);
    let cmd = c.step(&frame(6, 0.3));
    assert_eq!((cmd.mode, cmd.fault), (Mode::Hold, Fault::None));
}

#[test]
fn the_safe_state_brakes_both_axes_to_rest() {
    let p = TiltParams::default();
    let mut c: TiltController = TiltController::new(p).unwrap();
    let mut f = frame(0, 0.3);
    f.table_rate_radps = 3.0;
    f.table_velocity_mps = -1.5;
    c.step(&f);
    let (mut w, mut v) = (3.0f32, -1.5f32);
    for k in 0..40 {
        let cmd = c.step(&frame(1 + k, f32::NAN));
        assert_eq!(cmd.mode, Mode::Safe);
        assert!(cmd.tilt_accel_radps2.abs() <= p.tilt.accel_max_radps2);
        w += cmd.tilt_accel_radps2 * p.dt_s;
        v += cmd.stroke_accel_mps2 * p.dt_s;
    }
    // 3 rad/s at 300 rad/s^2 stops in 5 periods; 1.5 m/s at 60 m/s^2 in 13
    assert!(w.abs() < 1e-4 && v.abs() < 1e-4, "{w} {v}");
}

#[test]
fn invalid_parameters_are_named() {
    let d = TiltParams::default();
    let cases: [(TiltParams, ParamError); 9] = [
        (
            TiltParams { kappa: -1.0, ..d },
            ParamError::Negative("kappa"),
        ),
        (
            TiltParams {
                target_apex_m: 0.1,
                ..d
            },
            ParamError::OutOfRange("target_apex_m"),
        ),
        (
            TiltParams {
                contact_iterations: 5,
                ..d
            },
            ParamError::OutOfRange("contact_iterations"),
        ),
        (
            TiltParams {
                commit_s: 0.01,
                ..d
            },
            ParamError::OutOfRange("commit_s"),
        ),
        (
            TiltParams {
                kappa_rate_s: -0.01,
                ..d
            },
            ParamError::OutOfRange("kappa_rate_s"),
        ),
        (
            TiltParams {
                kappa_x_pm: -0.001,
                ..d
            },
            ParamError::OutOfRange("kappa_x_pm"),
        ),
        (
            TiltParams {
                kappa_xdot_spm: 1.001,
                ..d
            },
            ParamError::OutOfRange("kappa_xdot_spm"),
        ),
        (
            TiltParams {
                impact_height_m: 0.5,
                ..d
            },
            ParamError::OutOfRange("impact_height_m"),
        ),
        (
            TiltParams {
                tilt: dexter_core::tilt_control::TiltAxisParams {
                    max_rad: 1.3,
                    ..d.tilt
                },
                ..d
            },
            ParamError::OutOfRange("tilt.max_rad"),
        ),
    ];
    for (p, e) in cases {
        assert_eq!(TiltController::new(p).unwrap_err(), e);
    }
}

#[test]
fn wire_types_are_compact() {
    let p = postcard::to_stdvec(&TiltParams::default()).unwrap();
    let f = postcard::to_stdvec(&TiltFrame {
        seq: u32::MAX,
        ..TiltFrame::default()
    })
    .unwrap();
    let c = postcard::to_stdvec(&TiltCommand {
        seq: u32::MAX,
        ..TiltCommand::default()
    })
    .unwrap();
    // 33 f32, two u16 and four u8 as varints: about 140 bytes
    assert!(p.len() <= 150, "params {} bytes", p.len());
    assert!(f.len() <= 33, "frame {} bytes", f.len());
    assert!(c.len() <= 28, "command {} bytes", c.len());
    let back: TiltParams = postcard::from_bytes(&p).unwrap();
    assert_eq!(back, TiltParams::default());
}

/// Any f32 bit pattern: NaNs, infinities, subnormals, huge and tiny values.
fn any_f32() -> impl Strategy<Value = f32> {
    prop_oneof![
        any::<u32>().prop_map(f32::from_bits),
        -3.0f32..3.0,
        Just(f32::NAN),
        Just(f32::INFINITY),
        Just(0.0f32),
    ]
}

fn any_frame() -> impl Strategy<Value = TiltFrame> {
    (
        any::<u32>(),
        [any_f32(), any_f32(), any_f32(), any_f32()],
        [any_f32(), any_f32(), any_f32()],
    )
        .prop_map(|(seq, [x, y, th, a], [w, h, v])| TiltFrame {
            seq,
            body_x_m: x,
            body_y_m: y,
            body_theta_rad: th,
            table_angle_rad: a,
            table_rate_radps: w,
            table_height_m: h,
            table_velocity_mps: v,
        })
}

/// Plausible frames with mostly advancing sequence numbers: the estimator, the pipeline
/// and the plans run on garbage flights.
fn plausible_frames() -> impl Strategy<Value = Vec<TiltFrame>> {
    prop::collection::vec(
        (
            0u32..3,
            [-2.0f32..2.0, -0.4f32..2.0, -1.3f32..1.3],
            [-0.7f32..0.7, -15.0f32..15.0, -0.1f32..0.1, -3.5f32..3.5],
        ),
        1..400,
    )
    .prop_map(|steps| {
        let mut seq = 0u32;
        steps
            .into_iter()
            .map(|(ds, [x, y, th], [a, w, h, v])| {
                seq = seq.wrapping_add(ds);
                TiltFrame {
                    seq,
                    body_x_m: x,
                    body_y_m: y,
                    body_theta_rad: th,
                    table_angle_rad: a,
                    table_rate_radps: w,
                    table_height_m: h,
                    table_velocity_mps: v,
                }
            })
            .collect()
    })
}

fn check(cmd: &TiltCommand, p: &TiltParams) {
    assert!(
        cmd.tilt_accel_radps2.is_finite() && cmd.stroke_accel_mps2.is_finite(),
        "{cmd:?}"
    );
    assert!(
        cmd.tilt_accel_radps2.abs() <= p.tilt.accel_max_radps2,
        "{cmd:?}"
    );
    assert!(
        cmd.stroke_accel_mps2.abs() <= p.stroke.accel_max_mps2,
        "{cmd:?}"
    );
    assert!(
        cmd.tilt_ref_rad.is_finite() && cmd.stroke_ref_m.is_finite() && cmd.impact_in_s.is_finite(),
        "{cmd:?}"
    );
    match cmd.mode {
        Mode::Safe => {
            assert_ne!(cmd.fault, Fault::None, "safe without a fault code");
            assert_eq!(cmd.plan, PlanStatus::Idle);
        }
        Mode::Track | Mode::Hold => assert_eq!(cmd.fault, Fault::None),
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(1000))]

    #[test]
    fn any_frame_sequence_gives_a_limited_command_or_the_safe_state(
        frames in prop::collection::vec(any_frame(), 1..60)
    ) {
        let p = TiltParams::default();
        let mut c: TiltController = TiltController::new(p).unwrap();
        for f in &frames {
            check(&c.step(f), &p);
        }
    }

    #[test]
    fn plausible_garbage_flights_keep_the_command_finite_and_limited(
        frames in plausible_frames(),
        iterations in 1u8..=4,
        kappa_rate in 0.0f32..0.1,
    ) {
        let p = TiltParams { contact_iterations: iterations, kappa_rate_s: kappa_rate, ..TiltParams::default() };
        let mut c: TiltController = TiltController::new(p).unwrap();
        for f in &frames {
            check(&c.step(f), &p);
        }
    }
}
