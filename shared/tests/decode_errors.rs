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
