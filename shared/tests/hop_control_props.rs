//! Property tests of the hopper controller's step: for any input, finite or not, and any
//! accepted parameters, the command is a valid valve command or the safe state. It never
//! panics, and the valve is never open without a finite thrust within the law's limit.

use dexter_core::fixed_rate::FixedRate;
use dexter_core::fixed_rate::{Fault, Mode};
use dexter_core::hop_control::{HopCommand, HopController, HopFrame, HopParams, HopThrust};
use proptest::prelude::*;

/// Any f32 bit pattern: NaNs, infinities, subnormals, huge and tiny values.
fn any_f32() -> impl Strategy<Value = f32> {
    prop_oneof![
        any::<u32>().prop_map(f32::from_bits),
        -2.0f32..2.0,
        Just(f32::NAN),
        Just(f32::INFINITY),
        Just(f32::NEG_INFINITY),
        Just(0.0f32),
    ]
}

fn any_frame() -> impl Strategy<Value = HopFrame> {
    (
        any::<u32>(),
        any_f32(),
        any::<bool>(),
        prop::option::of(any_f32()),
    )
        .prop_map(|(seq, c, contact, h)| HopFrame {
            seq,
            leg_compression_m: c,
            contact,
            has_body_height: h.is_some(),
            body_height_m: h.unwrap_or(f32::NAN),
        })
}

/// Plausible hops: mostly increasing sequence numbers, compressions within range.
fn plausible_frames() -> impl Strategy<Value = Vec<HopFrame>> {
    prop::collection::vec(
        (
            0u32..3,
            -0.01f32..0.5,
            any::<bool>(),
            prop::option::of(0.0f32..3.0),
        ),
        1..400,
    )
    .prop_map(|steps| {
        let mut seq = 0u32;
        steps
            .into_iter()
            .map(|(ds, c, contact, h)| {
                seq = seq.wrapping_add(ds);
                HopFrame {
                    seq,
                    leg_compression_m: c,
                    contact,
                    has_body_height: h.is_some(),
                    body_height_m: h.unwrap_or(f32::NAN),
                }
            })
            .collect()
    })
}

fn check(cmd: &HopCommand, frame: &HopFrame, params: &HopParams) {
    assert_eq!(cmd.seq, frame.seq);
    match cmd.mode {
        Mode::Safe => {
            assert_ne!(cmd.fault, Fault::None, "safe state without a fault code");
            assert!(!cmd.valve_open && cmd.thrust_mps2 == 0.0, "{cmd:?}");
        }
        Mode::Track | Mode::Hold => assert_eq!(cmd.fault, Fault::None),
    }
    if cmd.valve_open {
        assert_eq!(
            cmd.mode,
            Mode::Track,
            "only an armed controller opens the valve"
        );
        let t = cmd.thrust_mps2;
        assert!(
            t.is_finite() && t >= 0.0 && t <= params.thrust.max_thrust_mps2(),
            "{cmd:?}"
        );
    } else {
        assert_eq!(cmd.thrust_mps2, 0.0);
    }
    let bad =
        !frame.leg_compression_m.is_finite() || frame.body_height().is_some_and(|h| !h.is_finite());
    if bad {
        assert_eq!((cmd.mode, cmd.fault), (Mode::Safe, Fault::NonFinite));
    }
}

fn servo() -> HopParams {
    HopParams {
        thrust: HopThrust {
            nominal_thrust_mps2: 40.0,
            gain_per_m: 5.0,
            target_energy_jpkg: 1.5,
            max_thrust_mps2: 60.0,
        },
        ..HopParams::default()
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(2000))]

    #[test]
    fn any_frame_sequence_gives_a_valid_valve_command_or_the_safe_state(
        frames in prop::collection::vec(any_frame(), 1..80),
        use_servo in any::<bool>(),
    ) {
        let params = if use_servo { servo() } else { HopParams::default() };
        let mut c = HopController::new(params).unwrap();
        for f in &frames {
            check(&c.step(f), f, &params);
        }
    }

    #[test]
    fn plausible_frames_never_break_the_step(frames in plausible_frames()) {
        let params = servo();
        let mut c = HopController::new(params).unwrap();
        for f in &frames {
            check(&c.step(f), f, &params);
        }
    }

    #[test]
    fn random_accepted_params_never_break_the_step(
        dt in 1e-5f32..0.05,
        delta in 0.0f32..0.5,
        on in 0.0f32..0.05,
        off_frac in -1.0f32..1.0,
        hyst in 0.0f32..0.05,
        debounce in 1u8..=64,
        predict in any::<bool>(),
        at_estimate in any::<bool>(),
        latency in 0.0f32..0.01,
        gain in 0.0f32..100.0,
        frames in prop::collection::vec(any_frame(), 1..60),
        plausible in plausible_frames(),
    ) {
        let params = HopParams {
            dt_s: dt,
            thrust_duration_s: delta,
            touchdown_compression_m: on,
            liftoff_compression_m: off_frac * on,
            bottom_hysteresis_m: hyst,
            debounce_samples: debounce,
            predict_bottom: predict,
            end_thrust_at_estimate: at_estimate,
            sensor_latency_s: latency,
            thrust: HopThrust {
                nominal_thrust_mps2: 40.0,
                gain_per_m: gain,
                target_energy_jpkg: 1.5,
                max_thrust_mps2: 60.0,
            },
            ..HopParams::default()
        };
        prop_assume!(params.validate().is_ok());
        let mut c = HopController::new(params).unwrap();
        for f in frames.iter().chain(plausible.iter()) {
            check(&c.step(f), f, &params);
        }
    }

    #[test]
    fn external_faults_always_close_the_valve(
        frames in plausible_frames(),
        at in 0usize..400,
    ) {
        let mut c = HopController::new(HopParams::default()).unwrap();
        for (i, f) in frames.iter().enumerate() {
            let cmd = if i == at { c.safe(f.seq, Fault::LinkTimeout) } else { c.step(f) };
            if i == at {
                prop_assert_eq!((cmd.mode, cmd.fault, cmd.valve_open), (Mode::Safe, Fault::LinkTimeout, false));
            }
        }
    }
}
