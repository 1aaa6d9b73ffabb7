//! The flat-tuple serde form of the large parameter sets (`dexter_core`'s `fields` module, used by
//! `TiltParams`, `TiltFrame`, `HopParams`, `HopFrame`) read from a self-describing sequence
//! (serde's own `SeqDeserializer`, the shape a JSON or TOML array has): a short sequence's
//! error says how many values it had and how many the set needs, and of several bad values
//! the first is reported. Postcard (the wire) never produces a short sequence, so the
//! core's own tests did not reach these paths; a mutation pass over `tilt_control` found them.

use dexter_core::tilt_control::TiltParams;
use serde::de::value::{Error, SeqDeserializer};
use serde::Deserialize;

/// `TiltParams` from a sequence of integers (each field, f32, u8 or u16, takes an integer
/// that fits it).
fn read(values: &[u32]) -> Result<TiltParams, Error> {
    TiltParams::deserialize(SeqDeserializer::<_, Error>::new(values.iter().copied()))
}

/// The number of fields: the length of the shortest sequence of ones that reads.
fn field_count() -> usize {
    (1..200)
        .find(|&n| read(&vec![1; n]).is_ok())
        .expect("some length reads")
}

#[test]
fn a_short_sequence_says_how_many_values_it_had_and_how_many_are_needed() {
    let n = field_count();
    assert!(n > 10, "{n}");
    for len in [0, 1, 5, n - 1] {
        let e = read(&vec![1; len]).expect_err("too short").to_string();
        assert_eq!(
            e,
            format!("invalid length {len}, expected the {n} fields of TiltParams in order")
        );
    }
}

#[test]
fn of_several_bad_values_the_first_is_reported() {
    // distinct values, each too large for an u8 or u16 field (every f32 field takes them):
    // the error names the value of the first field that cannot hold it, found as the
    // shortest prefix whose error is not "invalid length"
    let n = field_count();
    let values: Vec<u32> = (0..n as u32).map(|i| 70_000 + i).collect();
    let first_bad = (1..=n)
        .find(|&k| {
            !read(&values[..k])
                .unwrap_err()
                .to_string()
                .starts_with("invalid length")
        })
        .expect("some field rejects 70 000");
    assert!(first_bad < n, "the last field is not the only small one");
    let first = read(&values[..first_bad]).unwrap_err().to_string();
    assert!(
        first.contains(&format!("`{}`", values[first_bad - 1])),
        "{first}"
    );
    // the whole sequence (more bad values after the first) and a short one after the first
    // bad value both report that first error
    assert_eq!(read(&values).unwrap_err().to_string(), first);
    assert_eq!(read(&values[..n - 1]).unwrap_err().to_string(), first);
}
