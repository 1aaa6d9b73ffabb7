//! The framing, the kinds and the partial decode of a firmware image, together.

use super::*;
use crate::fixed_rate::FixedRate;

fn frame() -> SensorFrame {
    SensorFrame {
        seq: 7,
        ball_height_m: 0.5,
        paddle_height_m: -0.02,
        paddle_velocity_mps: 0.25,
    }
}

fn sensor() -> HostMessage {
    HostMessage::Sensor(Frame::Line(frame()))
}

#[test]
fn max_frame_len_covers_the_largest_payload_with_crc_cobs_and_delimiter() {
    // COBS adds one byte per started 254-byte block: 260 bytes need 2, plus the 0x00.
    assert_eq!(MAX_FRAME_LEN, MAX_PAYLOAD_LEN + CRC_LEN + 2 + 1);
}

#[test]
fn round_trip_through_stream_decoder() {
    let msg = sensor();
    let mut out = [0u8; MAX_FRAME_LEN];
    let n = encode(&msg, &mut out).unwrap();
    assert_eq!(out[n - 1], 0);
    assert!(out[..n - 1].iter().all(|&b| b != 0));
    let mut dec = FrameDecoder::<MAX_FRAME_LEN>::new();
    let mut got = None;
    for &b in &out[..n] {
        if let Some(r) = dec.push::<HostMessage>(b) {
            got = Some(r);
        }
    }
    assert_eq!(got, Some(Ok(msg)));
    assert_eq!(dec.stats().frames_ok, 1);
}

#[test]
fn flipped_bit_is_rejected_and_next_frame_resyncs() {
    let msg = sensor();
    let mut out = [0u8; MAX_FRAME_LEN];
    let n = encode(&msg, &mut out).unwrap();
    let mut bad = out;
    bad[3] ^= 0x10;
    let mut dec = FrameDecoder::<MAX_FRAME_LEN>::new();
    let mut results = heapless::Vec::<_, 4>::new();
    for &b in bad[..n].iter().chain(out[..n].iter()) {
        if let Some(r) = dec.push::<HostMessage>(b) {
            results.push(r).unwrap();
        }
    }
    assert_eq!(results.len(), 2);
    assert!(results[0].is_err());
    assert_eq!(results[1], Ok(msg));
    assert_eq!(dec.stats().errors(), 1);
}

#[test]
fn overlong_garbage_is_counted_once_then_decoding_resumes() {
    let mut dec = FrameDecoder::<16>::new();
    for _ in 0..40 {
        assert!(dec.push::<HostMessage>(0x55).is_none());
    }
    assert_eq!(dec.push::<HostMessage>(0), Some(Err(DecodeError::Overlong)));
    let mut out = [0u8; MAX_FRAME_LEN];
    let n = encode(&HostMessage::Stop, &mut out).unwrap();
    let mut last = None;
    for &b in &out[..n] {
        last = dec.push::<HostMessage>(b).or(last);
    }
    assert_eq!(last, Some(Ok(HostMessage::Stop)));
    assert_eq!(dec.stats().overlong, 1);
}

#[test]
fn a_frame_of_exactly_n_encoded_bytes_is_accepted_and_n_plus_one_is_overlong() {
    let mut out = [0u8; MAX_FRAME_LEN];
    let n = encode(&sensor(), &mut out).unwrap();
    let body = n - 1; // encoded bytes without the delimiter
    let mut exact = FrameDecoder::<64>::new();
    assert!(body < 64);
    let feed = |dec: &mut FrameDecoder<64>, bytes: &[u8]| {
        bytes
            .iter()
            .fold(None, |last, &b| dec.push::<HostMessage>(b).or(last))
    };
    assert_eq!(feed(&mut exact, &out[..n]), Some(Ok(sensor())));
    // the same frame into a decoder one byte too small
    let mut small = FrameDecoder::<8>::new();
    let r = out[..n]
        .iter()
        .fold(None, |last, &b| small.push::<HostMessage>(b).or(last));
    assert_eq!(r, Some(Err(DecodeError::Overlong)));
}

#[test]
fn wire_maps_each_kind_to_its_own_variants_only() {
    use crate::control::Controller;
    use crate::echo::{Echo, EchoFrame};
    let line = <Controller as Wire>::frame(frame());
    assert_eq!(line.kind(), Kind::Line);
    assert_eq!(<Controller as Wire>::frame_of(&line), Some(&frame()));
    assert_eq!(<Echo as Wire>::frame_of(&line), None);
    let echo = <Echo as Wire>::frame(EchoFrame { seq: 1, value: 2.0 });
    assert_eq!(echo.kind(), Kind::Echo);
    assert_eq!(<Controller as Wire>::frame_of(&echo), None);
    let cmd = Command::default_for(Kind::Echo).unwrap();
    assert_eq!(<Controller as Wire>::command_of(&cmd), None);
    assert!(<Echo as Wire>::command_of(&cmd).is_some());
    let config = Config::default_for(Kind::Line).unwrap();
    assert!(<Controller as Wire>::params_of(&config).is_some());
    assert!(<Echo as Wire>::params_of(&config).is_none());
    assert_eq!(
        Kind::ALL,
        &[
            Kind::Line,
            Kind::Echo,
            Kind::Tilt,
            Kind::Hop,
            Kind::Arm,
            Kind::Spatial
        ]
    );
}

/// An image that hosts the line juggler and the arm only (as a firmware image's
/// `HostedKinds` would be generated).
#[derive(Debug, PartialEq)]
enum LineAndArm {
    Line(<crate::control::Controller as FixedRate>::Params),
    Arm(<crate::arm_control::ArmController as FixedRate>::Params),
}

impl HostedKinds for LineAndArm {
    fn kind(&self) -> Kind {
        match self {
            LineAndArm::Line(_) => Kind::Line,
            LineAndArm::Arm(_) => Kind::Arm,
        }
    }
    fn decode<'de, A: serde::de::VariantAccess<'de>>(
        kind: Kind,
        body: A,
    ) -> Result<Result<Self, A>, A::Error> {
        Ok(match kind {
            Kind::Line => Ok(LineAndArm::Line(body.newtype_variant()?)),
            Kind::Arm => Ok(LineAndArm::Arm(body.newtype_variant()?)),
            _ => Err(body),
        })
    }
}

/// A host message as the line-and-arm image decodes it.
type Decoded = HostMessageOf<Partial<LineAndArm>, Partial<EchoOnly>>;

/// Frames of an image that hosts the link check only.
#[derive(Debug, PartialEq)]
struct EchoOnly(crate::echo::EchoFrame);

impl HostedKinds for EchoOnly {
    fn kind(&self) -> Kind {
        Kind::Echo
    }
    fn decode<'de, A: serde::de::VariantAccess<'de>>(
        kind: Kind,
        body: A,
    ) -> Result<Result<Self, A>, A::Error> {
        Ok(match kind {
            Kind::Echo => Ok(EchoOnly(body.newtype_variant()?)),
            _ => Err(body),
        })
    }
}

/// Every host message through the encoder and a partial image's decoder.
fn partial(message: &HostMessage) -> Result<Decoded, DecodeError> {
    let mut out = [0u8; MAX_FRAME_LEN];
    let n = encode(message, &mut out).unwrap();
    let mut dec = FrameDecoder::<MAX_FRAME_LEN>::new();
    out[..n]
        .iter()
        .fold(None, |last, &b| dec.push(b).or(last))
        .expect("one frame")
}

#[test]
fn an_image_decodes_the_parameters_of_its_kinds_and_only_the_kind_of_the_others() {
    let mut arm = <crate::arm_control::ArmController as FixedRate>::Params::default();
    arm.trajectory.points_rad[3] = -0.25;
    let line = <crate::control::Controller as FixedRate>::Params::default();
    for kind in Kind::ALL.iter().copied() {
        let config = match kind {
            Kind::Arm => Config::Arm(arm),
            _ => Config::default_for(kind).unwrap(),
        };
        let expected = match config {
            Config::Line(p) => Partial::Hosted(LineAndArm::Line(p)),
            Config::Arm(p) => Partial::Hosted(LineAndArm::Arm(p)),
            _ => Partial::NotHosted(kind),
        };
        let got = partial(&HostMessage::Configure(config));
        assert_eq!(got, Ok(HostMessageOf::Configure(expected)), "{kind:?}");
    }
    assert!(matches!(
        partial(&HostMessage::Configure(Config::Line(line))),
        Ok(HostMessageOf::Configure(Partial::Hosted(LineAndArm::Line(p)))) if p == line
    ));
    assert_eq!(
        partial(&sensor()),
        Ok(HostMessageOf::Sensor(Partial::NotHosted(Kind::Line)))
    );
    let echo = crate::echo::EchoFrame {
        seq: 3,
        value: -1.5,
    };
    assert_eq!(
        partial(&HostMessage::Sensor(Frame::Echo(echo))),
        Ok(HostMessageOf::Sensor(Partial::Hosted(EchoOnly(echo))))
    );
    assert_eq!(partial(&HostMessage::Stop), Ok(HostMessageOf::Stop));
}

#[test]
fn a_kind_index_past_the_list_is_a_payload_error() {
    // Configure (0), kind index = the number of kinds, no parameters; CRC appended.
    let payload = [0u8, Kind::ALL.len() as u8];
    let mut raw = [0u8; 6];
    raw[..2].copy_from_slice(&payload);
    raw[2..].copy_from_slice(&framing::CRC32C.checksum(&payload).to_le_bytes());
    let mut out = [0u8; 16];
    let n = cobs::try_encode(&raw, &mut out).unwrap();
    assert_eq!(decode::<Decoded>(&mut out[..n]), Err(DecodeError::Payload));
}

// The hand-written CRC, COBS encoder and streaming COBS decoder of the framing, against
// independent implementations: the `crc` crate's CRC-32C and the `cobs` crate's encoder
// and decoder, over random bytes biased to zeros and to long runs without one (the COBS
// corner cases: a block of 254 non-zero bytes, frames ending inside a block).
mod hand_written {
    use super::framing::{self, cobs_encode_in_place, crc32c, CRC32C};
    use super::*;
    use proptest::prelude::*;

    /// Random bytes: mostly zeros, mostly non-zero, or uniform, with long non-zero runs.
    fn bytes(max: usize) -> impl Strategy<Value = Vec<u8>> {
        prop_oneof![
            prop::collection::vec(any::<u8>(), 0..=max),
            prop::collection::vec(prop_oneof![Just(0u8), any::<u8>()], 0..=max),
            prop::collection::vec(1u8..=255, 0..=max),
            (0..=max, 200usize..=300, any::<u8>()).prop_map(move |(zero_at, len, fill)| {
                let mut v = vec![fill | 1; len.min(max)];
                if let Some(b) = v.get_mut(zero_at) {
                    *b = 0;
                }
                v
            }),
        ]
    }

    /// The reference frame: `cobs` crate's encoding of `payload ++ crc` and the delimiter.
    fn reference_frame(payload: &[u8]) -> Vec<u8> {
        let mut raw = payload.to_vec();
        raw.extend_from_slice(&CRC32C.checksum(payload).to_le_bytes());
        let mut frame = cobs::encode_vec(&raw);
        frame.push(0);
        frame
    }

    /// What the old decoder (the `cobs` crate's, a frame at a time) says of the bytes
    /// between two delimiters: the payload, or why the frame is rejected.
    fn reference_decode(segment: &[u8], capacity: usize) -> Result<Vec<u8>, DecodeError> {
        if segment.len() > capacity {
            return Err(DecodeError::Overlong);
        }
        let mut copy = segment.to_vec();
        let n = cobs::decode_in_place(&mut copy).map_err(|_| DecodeError::Cobs)?;
        if n < CRC_LEN {
            return Err(DecodeError::TooShort);
        }
        let (payload, trailer) = copy[..n].split_at(n - CRC_LEN);
        if CRC32C.checksum(payload).to_le_bytes() != trailer {
            return Err(DecodeError::Crc);
        }
        Ok(payload.to_vec())
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(2000))]

        #[test]
        fn crc32c_is_the_crc_crates(data in bytes(300)) {
            prop_assert_eq!(crc32c(&data), CRC32C.checksum(&data));
        }

        #[test]
        fn cobs_in_place_is_the_cobs_crates_encoding_or_declines(raw in bytes(MAX_PAYLOAD_LEN + CRC_LEN)) {
            let mut out = [0u8; MAX_FRAME_LEN];
            out[1..=raw.len()].copy_from_slice(&raw);
            let mut expected = cobs::encode_vec(&raw);
            expected.push(0);
            let longest_run = raw.split(|&b| b == 0).map(<[u8]>::len).max().unwrap_or(0);
            match cobs_encode_in_place(&mut out, raw.len()) {
                Some(n) => prop_assert_eq!(&out[..n], &expected[..]),
                // only a block of 254 non-zero bytes needs the crate's encoder
                None => prop_assert!(longest_run >= 254, "declined a run of {}", longest_run),
            }
        }

        #[test]
        fn encode_is_cobs_of_postcard_and_crc(payload in bytes(MAX_PAYLOAD_LEN)) {
            // any postcard payload: a length and the bytes
            let value: &[u8] = &payload;
            let mut out = [0u8; MAX_FRAME_LEN];
            let mut payload_bytes = [0u8; MAX_PAYLOAD_LEN + 8];
            let postcard_bytes = postcard::to_slice(&value, &mut payload_bytes);
            let result = encode(&value, &mut out);
            match postcard_bytes {
                Ok(p) if p.len() <= MAX_PAYLOAD_LEN => {
                    let n = result.unwrap();
                    prop_assert_eq!(&out[..n], &reference_frame(p)[..]);
                }
                _ => prop_assert_eq!(result, Err(EncodeError::BufferTooSmall)),
            }
        }

        #[test]
        fn the_streaming_decoder_agrees_with_the_cobs_crate_frame_by_frame(
            payloads in prop::collection::vec(bytes(80), 0..6),
            garbage in prop::collection::vec(bytes(90), 0..6),
            chunk in 1usize..70,
        ) {
            const N: usize = 64;
            // valid frames and garbage, interleaved
            let mut stream = Vec::new();
            for i in 0..payloads.len().max(garbage.len()) {
                if let Some(p) = payloads.get(i) {
                    stream.extend(reference_frame(p));
                }
                if let Some(g) = garbage.get(i) {
                    stream.extend(g);
                }
            }
            stream.push(0);
            let expected: Vec<_> = stream
                .split(|&b| b == 0)
                .filter(|segment| !segment.is_empty())
                .map(|segment| reference_decode(segment, N))
                .collect();
            let mut dec = FrameDecoder::<N>::new();
            let mut got = Vec::new();
            for piece in stream.chunks(chunk) {
                let mut rest = piece;
                while !rest.is_empty() {
                    let (used, result) = dec.feed(rest, |payload| Ok(payload.to_vec()));
                    prop_assert!(used > 0 && used <= rest.len());
                    rest = &rest[used..];
                    got.extend(result);
                }
            }
            prop_assert_eq!(&got, &expected);
            let stats = dec.stats();
            prop_assert_eq!(stats.frames_ok as usize, expected.iter().filter(|r| r.is_ok()).count());
            prop_assert_eq!(stats.errors() as usize, expected.iter().filter(|r| r.is_err()).count());
        }
    }

    #[test]
    fn the_nibble_table_is_the_crc_crates_byte_table_at_multiples_of_16() {
        // and so the first 16 bits of CRC-32C: a spot check beside the property
        assert_eq!(crc32c(b"123456789"), 0xE306_9283);
        assert_eq!(framing::crc32c(&[]), CRC32C.checksum(&[]));
    }
}
