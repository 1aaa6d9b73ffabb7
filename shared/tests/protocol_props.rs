//! Property tests of the wire protocol: decode(encode(x)) == x for every message, and any
//! byte string decodes to a value or an error, never a panic; corruption is detected.

use dexter_core::control::ControllerParams;
use dexter_core::protocol::{
    decode, encode, ActuatorCommand, DecodeError, DeviceMessage, Fault, FrameDecoder, HostMessage,
    Mode, SensorFrame, Telemetry, MAX_FRAME_LEN,
};
use proptest::prelude::*;

fn f() -> impl Strategy<Value = f32> {
    any::<u32>().prop_map(f32::from_bits)
}

fn sensor() -> impl Strategy<Value = SensorFrame> {
    (any::<u32>(), f(), f(), f()).prop_map(|(seq, b, r, v)| SensorFrame {
        seq,
        ball_height_m: b,
        paddle_height_m: r,
        paddle_velocity_mps: v,
    })
}

fn device() -> impl Strategy<Value = DeviceMessage> {
    let mode = prop_oneof![Just(Mode::Hold), Just(Mode::Track), Just(Mode::Safe)];
    let fault = prop_oneof![
        Just(Fault::None),
        Just(Fault::NonFinite),
        Just(Fault::OutOfRange),
        Just(Fault::Stale),
        Just(Fault::LinkTimeout)
    ];
    prop_oneof![
        any::<bool>().prop_map(|ok| DeviceMessage::Configured { ok }),
        (
            any::<u32>(),
            f(),
            f(),
            f(),
            mode,
            fault,
            any::<[u32; 3]>(),
            f(),
            f(),
            any::<bool>()
        )
            .prop_map(|(seq, a, h, v, mode, fault, n, bh, bv, valid)| {
                DeviceMessage::Output {
                    command: ActuatorCommand {
                        seq,
                        paddle_accel_mps2: a,
                        paddle_height_ref_m: h,
                        paddle_velocity_ref_mps: v,
                        mode,
                        fault,
                    },
                    telemetry: Telemetry {
                        step_instructions: n[0],
                        link_errors: n[1],
                        frames_ok: n[2],
                        ball_height_est_m: bh,
                        ball_velocity_est_mps: bv,
                        estimate_valid: valid,
                    },
                }
            }),
    ]
}

fn host() -> impl Strategy<Value = HostMessage> {
    prop_oneof![
        sensor().prop_map(HostMessage::Sensor),
        Just(HostMessage::Stop),
        (f(), f(), f()).prop_map(|(dt, k1, apex)| HostMessage::Configure(ControllerParams {
            dt_s: dt,
            kappa1_s2pm2: k1,
            target_apex_m: apex,
            ..ControllerParams::default()
        })),
    ]
}

/// Bitwise equality (NaN payloads must survive the round trip too).
fn same<T: serde::Serialize>(a: &T, b: &T) -> bool {
    postcard::to_allocvec(a).unwrap() == postcard::to_allocvec(b).unwrap()
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(3000))]

    #[test]
    fn host_messages_round_trip(msg in host()) {
        let mut buf = [0u8; MAX_FRAME_LEN];
        let n = encode(&msg, &mut buf).unwrap();
        prop_assert_eq!(buf[n - 1], 0);
        prop_assert!(buf[..n - 1].iter().all(|&b| b != 0));
        let back: HostMessage = decode(&mut buf[..n - 1]).unwrap();
        prop_assert!(same(&back, &msg));
    }

    #[test]
    fn device_messages_round_trip_through_the_stream_decoder(msgs in prop::collection::vec(device(), 1..10)) {
        let mut dec = FrameDecoder::<MAX_FRAME_LEN>::new();
        let mut got = Vec::new();
        for m in &msgs {
            let mut buf = [0u8; MAX_FRAME_LEN];
            let n = encode(m, &mut buf).unwrap();
            for &b in &buf[..n] {
                if let Some(r) = dec.push::<DeviceMessage>(b) {
                    got.push(r.unwrap());
                }
            }
        }
        prop_assert_eq!(got.len(), msgs.len());
        for (a, b) in got.iter().zip(&msgs) {
            prop_assert!(same(a, b));
        }
        prop_assert_eq!(dec.stats().frames_ok as usize, msgs.len());
    }

    #[test]
    fn any_bytes_decode_to_a_value_or_an_error(bytes in prop::collection::vec(any::<u8>(), 0..400)) {
        let mut dec = FrameDecoder::<MAX_FRAME_LEN>::new();
        let mut completed = 0u32;
        for &b in &bytes {
            if dec.push::<HostMessage>(b).is_some() {
                completed += 1;
            }
        }
        let s = dec.stats();
        prop_assert_eq!(s.frames_ok + s.errors(), completed);
        let mut copy = bytes.clone();
        let _ = decode::<DeviceMessage>(&mut copy);
    }

    #[test]
    fn a_corrupted_frame_is_never_accepted_as_a_different_message(
        msg in host(),
        flips in prop::collection::vec((any::<usize>(), 1u8..=255), 1..4),
    ) {
        let mut buf = [0u8; MAX_FRAME_LEN];
        let n = encode(&msg, &mut buf).unwrap();
        let mut bad = buf;
        for (pos, mask) in &flips {
            bad[pos % (n - 1)] ^= mask;
        }
        // corruption that produces a delimiter splits the frame; feed it as a stream
        let mut dec = FrameDecoder::<MAX_FRAME_LEN>::new();
        for &b in &bad[..n] {
            if let Some(Ok(m)) = dec.push::<HostMessage>(b) {
                // only possible if the flips cancelled out (same bytes as the original)
                prop_assert!(bad[..n] == buf[..n] && same(&m, &msg));
            }
        }
    }
}

#[test]
fn truncated_and_empty_frames_are_typed_errors() {
    let mut buf = [0u8; MAX_FRAME_LEN];
    let n = encode(&HostMessage::Stop, &mut buf).unwrap();
    assert!(decode::<HostMessage>(&mut buf[..2]).is_err());
    assert!(decode::<HostMessage>(&mut [][..]).is_err());
    // one valid COBS byte group holding fewer bytes than a CRC
    assert_eq!(
        decode::<HostMessage>(&mut [3, 1, 2][..]),
        Err(DecodeError::TooShort)
    );
    assert!(n > 5);
}
