//! A rejected frame's reason, as a host prints it: each [`DecodeError`] reads as its own
//! cause (the HIL reports and the serial link's errors quote these texts).

use dexter_core::protocol::DecodeError;

#[test]
fn each_decode_error_names_its_cause_in_words() {
    let cases = [
        (DecodeError::Overlong, "longer"),
        (DecodeError::Cobs, "COBS"),
        (DecodeError::TooShort, "shorter"),
        (DecodeError::Crc, "CRC mismatch"),
        (DecodeError::Payload, "not a valid message"),
    ];
    for (error, word) in cases {
        let text = error.to_string();
        assert!(
            text.contains(word),
            "{error:?} reads {text:?}, not naming {word:?}"
        );
    }
}

/// Feeds `bytes` to a decoder of `N` encoded bytes and returns the last frame's result.
fn last_frame<const N: usize>(bytes: &[u8]) -> Option<Result<u8, DecodeError>> {
    let mut decoder = dexter_core::protocol::FrameDecoder::<N>::new();
    bytes.iter().filter_map(|b| decoder.push::<u8>(*b)).last()
}

#[test]
fn a_frame_of_exactly_the_decoders_length_is_accepted_and_one_byte_more_is_overlong() {
    // a u8 message is 1 postcard byte + 4 CRC bytes; COBS of 5 bytes (< 254) is 6 bytes,
    // whatever their values: 6 encoded bytes, then the delimiter
    let mut frame = [0u8; 16];
    let len = dexter_core::protocol::encode(&200u8, &mut frame).unwrap();
    assert_eq!(len, 7, "6 encoded bytes and the delimiter");
    let bytes = &frame[..len];
    assert_eq!(last_frame::<6>(bytes), Some(Ok(200)));
    assert_eq!(last_frame::<5>(bytes), Some(Err(DecodeError::Overlong)));
}
