//! Property tests of the control step: for any input, finite or not, the controller returns
//! a finite command within its limits, or the safe command with a fault code. It never panics.

use dexter_core::control::{Controller, ControllerParams};
use dexter_core::fixed_rate::FixedRate;
use dexter_core::fixed_rate::{Fault, Mode};
use dexter_core::protocol::SensorFrame;
use proptest::prelude::*;

/// Any f32 bit pattern: NaNs, infinities, subnormals, huge and tiny values.
fn any_f32() -> impl Strategy<Value = f32> {
    prop_oneof![
        any::<u32>().prop_map(f32::from_bits),
        -30.0f32..30.0,
        Just(f32::NAN),
        Just(f32::INFINITY),
        Just(f32::NEG_INFINITY),
        Just(0.0f32),
    ]
}

fn any_frame() -> impl Strategy<Value = SensorFrame> {
    (any::<u32>(), any_f32(), any_f32(), any_f32()).prop_map(|(seq, b, r, v)| SensorFrame {
        seq,
        ball_height_m: b,
        paddle_height_m: r,
        paddle_velocity_mps: v,
    })
}

/// Plausible frames with mostly increasing sequence numbers: exercises the tracking path.
fn plausible_frames() -> impl Strategy<Value = Vec<SensorFrame>> {
    prop::collection::vec(
        (0u32..3, -0.4f32..5.0, -0.35f32..0.15, -5.0f32..5.0),
        1..300,
    )
    .prop_map(|steps| {
        let mut seq = 0u32;
        steps
            .into_iter()
            .map(|(ds, b, r, v)| {
                seq = seq.wrapping_add(ds);
                SensorFrame {
                    seq,
                    ball_height_m: b,
                    paddle_height_m: r,
                    paddle_velocity_mps: v,
                }
            })
            .collect()
    })
}

fn check(cmd: &dexter_core::protocol::ActuatorCommand, params: &ControllerParams) {
    let a = params.limits.accel_max_mps2;
    assert!(
        cmd.paddle_accel_mps2.is_finite(),
        "non-finite command {cmd:?}"
    );
    assert!(
        cmd.paddle_accel_mps2.abs() <= a,
        "command beyond limit {cmd:?}"
    );
    assert!(cmd.paddle_height_ref_m.is_finite() && cmd.paddle_velocity_ref_mps.is_finite());
    match cmd.mode {
        Mode::Safe => assert_ne!(cmd.fault, Fault::None, "safe state without a fault code"),
        Mode::Track | Mode::Hold => assert_eq!(cmd.fault, Fault::None),
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(2000))]

    #[test]
    fn any_frame_sequence_gives_a_limited_command_or_the_safe_state(
        frames in prop::collection::vec(any_frame(), 1..60)
    ) {
        let params = ControllerParams::default();
        let mut c = Controller::new(params).unwrap();
        for f in &frames {
            let cmd = c.step(f);
            check(&cmd, &params);
            prop_assert_eq!(cmd.seq, f.seq);
            let finite = f.ball_height_m.is_finite()
                && f.paddle_height_m.is_finite()
                && f.paddle_velocity_mps.is_finite();
            if !finite {
                prop_assert_eq!((cmd.mode, cmd.fault), (Mode::Safe, Fault::NonFinite));
            }
        }
    }

    #[test]
    fn plausible_frames_track_or_hold_within_limits(frames in plausible_frames()) {
        let params = ControllerParams::default();
        let mut c = Controller::new(params).unwrap();
        for f in &frames {
            check(&c.step(f), &params);
        }
    }

    #[test]
    fn random_valid_params_never_break_the_step(
        dt in 1e-4f32..0.05,
        kappa1 in 0.0f32..1.0,
        apex in 0.01f32..100.0,
        kp in 0.0f32..1e5,
        kd in 0.0f32..1e3,
        frames in prop::collection::vec(any_frame(), 1..40),
    ) {
        let params = ControllerParams {
            dt_s: dt,
            kappa1_s2pm2: kappa1,
            target_apex_m: apex,
            kp_per_s2: kp,
            kd_per_s: kd,
            ..ControllerParams::default()
        };
        let mut c = Controller::new(params).unwrap();
        for f in &frames {
            check(&c.step(f), &params);
        }
    }
}
