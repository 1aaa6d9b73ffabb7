//! Property tests of the wire protocol: decode(encode(x)) == x for every message of every
//! controller kind, any byte string decodes to a value or an error, never a panic;
//! corruption is detected; the streaming decoder agrees with cobs' own in-place decoder;
//! and every message of every kind fits the frame buffers, worst case over all values.

use dexter_core::control::ControllerParams;
use dexter_core::echo::{EchoCommand, EchoFrame, EchoParams};
use dexter_core::fixed_rate::{Fault, Mode, Telemetry, ESTIMATE_LEN};
use dexter_core::protocol::{
    decode, encode, ActuatorCommand, Command, Config, DecodeError, DeviceMessage, Frame,
    FrameDecoder, HostMessage, Kind, Rejection, RunSummary, SensorFrame, MAX_FRAME_LEN,
    MAX_PAYLOAD_LEN,
};
use proptest::prelude::*;

fn f() -> impl Strategy<Value = f32> {
    any::<u32>().prop_map(f32::from_bits)
}

fn mode() -> impl Strategy<Value = Mode> {
    prop_oneof![Just(Mode::Hold), Just(Mode::Track), Just(Mode::Safe)]
}

fn fault() -> impl Strategy<Value = Fault> {
    prop_oneof![
        Just(Fault::None),
        Just(Fault::NonFinite),
        Just(Fault::OutOfRange),
        Just(Fault::Stale),
        Just(Fault::LinkTimeout),
        Just(Fault::Overrun)
    ]
}

fn frame() -> impl Strategy<Value = Frame> {
    prop_oneof![
        (any::<u32>(), f(), f(), f()).prop_map(|(seq, b, r, v)| Frame::Line(SensorFrame {
            seq,
            ball_height_m: b,
            paddle_height_m: r,
            paddle_velocity_mps: v,
        })),
        (any::<u32>(), f()).prop_map(|(seq, value)| Frame::Echo(EchoFrame { seq, value })),
    ]
}

fn command() -> impl Strategy<Value = Command> {
    prop_oneof![
        (any::<u32>(), f(), f(), f(), mode(), fault()).prop_map(|(seq, a, h, v, mode, fault)| {
            Command::Line(ActuatorCommand {
                seq,
                paddle_accel_mps2: a,
                paddle_height_ref_m: h,
                paddle_velocity_ref_mps: v,
                mode,
                fault,
            })
        }),
        (any::<u32>(), f(), mode(), fault()).prop_map(|(seq, value, mode, fault)| {
            Command::Echo(EchoCommand {
                seq,
                value,
                mode,
                fault,
            })
        }),
    ]
}

fn telemetry() -> impl Strategy<Value = Telemetry> {
    (
        any::<[u32; 3]>(),
        any::<[u32; ESTIMATE_LEN]>(),
        any::<bool>(),
    )
        .prop_map(|(n, e, valid)| Telemetry {
            step_instructions: n[0],
            link_errors: n[1],
            frames_ok: n[2],
            estimate: e.map(f32::from_bits),
            estimate_valid: valid,
        })
}

fn kind() -> impl Strategy<Value = Kind> {
    prop::sample::select(Kind::ALL)
}

fn device() -> impl Strategy<Value = DeviceMessage> {
    prop_oneof![
        (kind(), any::<bool>()).prop_map(|(kind, ok)| DeviceMessage::Configured { kind, ok }),
        (command(), telemetry())
            .prop_map(|(command, telemetry)| DeviceMessage::Output { command, telemetry }),
        (kind(), kind()).prop_map(|(configured, received)| DeviceMessage::Rejected(
            Rejection::WrongKind {
                configured,
                received
            }
        )),
        Just(DeviceMessage::Rejected(Rejection::NotConfigured)),
        any::<[u32; 4]>().prop_map(|n| DeviceMessage::Stopped(RunSummary {
            steps: n[0],
            link_timeouts: n[1],
            stack_used_bytes: n[2],
            stack_size_bytes: n[3],
        })),
    ]
}

fn host() -> impl Strategy<Value = HostMessage> {
    prop_oneof![
        frame().prop_map(HostMessage::Sensor),
        Just(HostMessage::Stop),
        (f(), f(), f()).prop_map(|(dt, k1, apex)| HostMessage::Configure(Config::Line(
            ControllerParams {
                dt_s: dt,
                kappa1_s2pm2: k1,
                target_apex_m: apex,
                ..ControllerParams::default()
            }
        ))),
        f().prop_map(|gain| HostMessage::Configure(Config::Echo(EchoParams { gain }))),
    ]
}

/// Bitwise equality (NaN payloads must survive the round trip too).
fn same<T: serde::Serialize>(a: &T, b: &T) -> bool {
    postcard::to_allocvec(a).unwrap() == postcard::to_allocvec(b).unwrap()
}

/// Feed `bytes` to a fresh decoder; every completed frame's result.
fn stream<const N: usize>(bytes: &[u8]) -> Vec<Result<HostMessage, DecodeError>> {
    let mut dec = FrameDecoder::<N>::new();
    bytes
        .iter()
        .filter_map(|&b| dec.push::<HostMessage>(b))
        .collect()
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
    fn any_bytes_decode_to_a_value_or_an_error(bytes in prop::collection::vec(any::<u8>(), 0..700)) {
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

    /// The streaming decoder (COBS undone byte by byte) against cobs' in-place decoder behind
    /// `decode`, on arbitrary frame bodies: the same message, or an error for the same frames
    /// (the in-place decoder does not know the buffer limit, so overlong is checked apart).
    #[test]
    fn the_streaming_decoder_agrees_with_the_in_place_decoder(
        body in prop::collection::vec(1u8..=255, 1..80),
        valid in any::<bool>(),
        msg in host(),
    ) {
        let mut bytes = body.clone();
        if valid {
            let mut buf = [0u8; MAX_FRAME_LEN];
            let n = encode(&msg, &mut buf).unwrap();
            bytes = buf[..n - 1].to_vec();
        }
        let mut copy = bytes.clone();
        let oracle = decode::<HostMessage>(&mut copy);
        let mut framed = bytes.clone();
        framed.push(0);
        let got = stream::<MAX_FRAME_LEN>(&framed);
        prop_assert_eq!(got.len(), 1);
        match (&got[0], &oracle) {
            (Ok(a), Ok(b)) => prop_assert!(same(a, b)),
            (Err(_), Err(_)) => {}
            (a, b) => prop_assert!(false, "stream {:?} vs in-place {:?}", a, b),
        }
        let small = stream::<8>(&framed);
        if bytes.len() > 8 {
            prop_assert_eq!(&small, &vec![Err(DecodeError::Overlong)]);
        }
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

#[test]
fn a_message_longer_than_the_payload_limit_is_an_encode_error_not_a_panic() {
    // 3 x 32 f32 = 384 bytes of payload, over the 256-byte limit
    let too_long = [[1.5f32; 32]; 3];
    const { assert!(3 * 32 * 4 > MAX_PAYLOAD_LEN) };
    let mut buf = [0u8; 2 * MAX_FRAME_LEN];
    assert!(encode(&too_long, &mut buf).is_err());
    let mut small = [0u8; 4];
    assert!(encode(&HostMessage::Stop, &mut small).is_err());
}

// ---- worst-case message sizes ---------------------------------------------------------------

mod worst_case {
    //! A serde serializer that charges every value the most bytes postcard can spend on its
    //! type (a u32 varint 5 bytes, an f32 4), whatever the value, and refuses the types whose
    //! size depends on the value (options, sequences, strings, maps). For the fixed-shape
    //! wire types the protocol allows, the count is therefore the largest encoding over every
    //! value of the given variants: a static bound, not one sample.
    use serde::ser::{self, Impossible, Serialize};

    #[derive(Debug)]
    pub struct VariableShape(pub String);

    impl std::fmt::Display for VariableShape {
        fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
            write!(f, "not a fixed-shape wire type: {}", self.0)
        }
    }
    impl std::error::Error for VariableShape {}
    impl ser::Error for VariableShape {
        fn custom<T: std::fmt::Display>(msg: T) -> Self {
            VariableShape(msg.to_string())
        }
    }

    pub fn size<T: Serialize>(value: &T) -> Result<usize, VariableShape> {
        let mut counter = Counter(0);
        value.serialize(&mut counter)?;
        Ok(counter.0)
    }

    pub struct Counter(usize);
    type R = Result<(), VariableShape>;

    impl Counter {
        fn add(&mut self, n: usize) -> R {
            self.0 += n;
            Ok(())
        }
        /// An enum tag: a varint of the variant index, 1 byte below 128 variants.
        fn tag(&mut self, index: u32) -> R {
            if index >= 128 {
                return Err(VariableShape(format!("variant index {index}")));
            }
            self.add(1)
        }
    }

    fn refuse<T>(what: &str) -> Result<T, VariableShape> {
        Err(VariableShape(what.into()))
    }

    impl ser::Serializer for &mut Counter {
        type Ok = ();
        type Error = VariableShape;
        type SerializeSeq = Impossible<(), VariableShape>;
        type SerializeTuple = Self;
        type SerializeTupleStruct = Self;
        type SerializeTupleVariant = Self;
        type SerializeMap = Impossible<(), VariableShape>;
        type SerializeStruct = Self;
        type SerializeStructVariant = Self;

        fn serialize_bool(self, _: bool) -> R {
            self.add(1)
        }
        fn serialize_i8(self, _: i8) -> R {
            self.add(1)
        }
        fn serialize_u8(self, _: u8) -> R {
            self.add(1)
        }
        fn serialize_i16(self, _: i16) -> R {
            self.add(3)
        }
        fn serialize_u16(self, _: u16) -> R {
            self.add(3)
        }
        fn serialize_i32(self, _: i32) -> R {
            self.add(5)
        }
        fn serialize_u32(self, _: u32) -> R {
            self.add(5)
        }
        fn serialize_i64(self, _: i64) -> R {
            self.add(10)
        }
        fn serialize_u64(self, _: u64) -> R {
            self.add(10)
        }
        fn serialize_f32(self, _: f32) -> R {
            self.add(4)
        }
        fn serialize_f64(self, _: f64) -> R {
            self.add(8)
        }
        fn serialize_char(self, _: char) -> R {
            refuse("char")
        }
        fn serialize_str(self, _: &str) -> R {
            refuse("str")
        }
        fn serialize_bytes(self, _: &[u8]) -> R {
            refuse("bytes")
        }
        fn serialize_none(self) -> R {
            refuse("Option")
        }
        fn serialize_some<T: ?Sized + Serialize>(self, _: &T) -> R {
            refuse("Option")
        }
        fn serialize_unit(self) -> R {
            Ok(())
        }
        fn serialize_unit_struct(self, _: &'static str) -> R {
            Ok(())
        }
        fn serialize_unit_variant(self, _: &'static str, i: u32, _: &'static str) -> R {
            self.tag(i)
        }
        fn serialize_newtype_struct<T: ?Sized + Serialize>(self, _: &'static str, v: &T) -> R {
            v.serialize(self)
        }
        fn serialize_newtype_variant<T: ?Sized + Serialize>(
            self,
            _: &'static str,
            i: u32,
            _: &'static str,
            v: &T,
        ) -> R {
            self.tag(i)?;
            v.serialize(self)
        }
        fn serialize_seq(self, _: Option<usize>) -> Result<Self::SerializeSeq, VariableShape> {
            refuse("sequence")
        }
        fn serialize_tuple(self, _: usize) -> Result<Self, VariableShape> {
            Ok(self)
        }
        fn serialize_tuple_struct(self, _: &'static str, _: usize) -> Result<Self, VariableShape> {
            Ok(self)
        }
        fn serialize_tuple_variant(
            self,
            _: &'static str,
            i: u32,
            _: &'static str,
            _: usize,
        ) -> Result<Self, VariableShape> {
            self.tag(i)?;
            Ok(self)
        }
        fn serialize_map(self, _: Option<usize>) -> Result<Self::SerializeMap, VariableShape> {
            refuse("map")
        }
        fn serialize_struct(self, _: &'static str, _: usize) -> Result<Self, VariableShape> {
            Ok(self)
        }
        fn serialize_struct_variant(
            self,
            _: &'static str,
            i: u32,
            _: &'static str,
            _: usize,
        ) -> Result<Self, VariableShape> {
            self.tag(i)?;
            Ok(self)
        }
        fn is_human_readable(&self) -> bool {
            false
        }
    }

    macro_rules! compound {
        ($($trait:ident :: $method:ident),+) => {$(
            impl ser::$trait for &mut Counter {
                type Ok = ();
                type Error = VariableShape;
                fn $method<T: ?Sized + Serialize>(&mut self, v: &T) -> R {
                    v.serialize(&mut **self)
                }
                fn end(self) -> R {
                    Ok(())
                }
            }
        )+};
    }
    compound!(
        SerializeTuple::serialize_element,
        SerializeTupleStruct::serialize_field,
        SerializeTupleVariant::serialize_field
    );

    macro_rules! named_compound {
        ($($trait:ident),+) => {$(
            impl ser::$trait for &mut Counter {
                type Ok = ();
                type Error = VariableShape;
                fn serialize_field<T: ?Sized + Serialize>(&mut self, _: &'static str, v: &T) -> R {
                    v.serialize(&mut **self)
                }
                fn end(self) -> R {
                    Ok(())
                }
            }
        )+};
    }
    named_compound!(SerializeStruct, SerializeStructVariant);
}

/// Every message the protocol can carry, one per variant and kind.
fn every_message_shape() -> (Vec<HostMessage>, Vec<DeviceMessage>) {
    let mut host = vec![HostMessage::Stop];
    let mut device = vec![DeviceMessage::Rejected(Rejection::NotConfigured)];
    for &kind in Kind::ALL {
        host.push(HostMessage::Configure(
            Config::default_for(kind).expect("every kind is on the host's wire"),
        ));
        host.push(HostMessage::Sensor(
            Frame::default_for(kind).expect("every kind is on the host's wire"),
        ));
        device.push(DeviceMessage::Configured { kind, ok: true });
        device.push(DeviceMessage::Output {
            command: Command::default_for(kind).expect("every kind is on the host's wire"),
            telemetry: Telemetry::default(),
        });
        device.push(DeviceMessage::Rejected(Rejection::NotHosted(kind)));
        device.push(DeviceMessage::Rejected(Rejection::WrongKind {
            configured: kind,
            received: kind,
        }));
    }
    device.push(DeviceMessage::Rejected(Rejection::Undecodable(
        DecodeError::Payload,
    )));
    device.push(DeviceMessage::Stopped(RunSummary::default()));
    (host, device)
}

/// The static argument behind `MAX_PAYLOAD_LEN`: the worst case over every value of every
/// message of every kind fits, and so every frame fits `MAX_FRAME_LEN`. A controller kind
/// whose wire types have a value-dependent size (Option, Vec, str) fails here by name.
#[test]
fn every_message_of_every_kind_fits_the_frame_worst_case_over_all_values() {
    let (host, device) = every_message_shape();
    let mut largest = (0, String::new());
    let mut check = |what: String, size: Result<usize, worst_case::VariableShape>| {
        let size = size.unwrap_or_else(|e| panic!("{what}: {e}"));
        assert!(
            size <= MAX_PAYLOAD_LEN,
            "{what}: worst case {size} bytes > MAX_PAYLOAD_LEN {MAX_PAYLOAD_LEN}"
        );
        if size > largest.0 {
            largest = (size, what);
        }
    };
    for m in &host {
        check(format!("{m:?}"), worst_case::size(m));
        let mut buf = [0u8; MAX_FRAME_LEN];
        encode(m, &mut buf).expect("encodes");
    }
    for m in &device {
        check(format!("{m:?}"), worst_case::size(m));
    }
    eprintln!(
        "largest message, worst case: {} bytes: {}",
        largest.0, largest.1
    );
}

/// The counter itself, against postcard on values that take the most bytes: u32::MAX is a
/// 5-byte varint, so a line-juggler Output at its extremes is exactly the worst case.
#[test]
fn the_worst_case_counter_matches_postcard_at_the_extremes() {
    let extreme = DeviceMessage::Output {
        command: Command::Line(ActuatorCommand {
            seq: u32::MAX,
            ..ActuatorCommand::default()
        }),
        telemetry: Telemetry {
            step_instructions: u32::MAX,
            link_errors: u32::MAX,
            frames_ok: u32::MAX,
            ..Telemetry::default()
        },
    };
    let actual = postcard::to_allocvec(&extreme).unwrap().len();
    assert_eq!(worst_case::size(&extreme).unwrap(), actual);
    let small = postcard::to_allocvec(
        &Command::default_for(Kind::Line).expect("every kind is on the host's wire"),
    )
    .unwrap()
    .len();
    assert!(
        worst_case::size(
            &Command::default_for(Kind::Line).expect("every kind is on the host's wire")
        )
        .unwrap()
            > small
    );
    assert!(worst_case::size(&Some(1u8)).is_err());
}
