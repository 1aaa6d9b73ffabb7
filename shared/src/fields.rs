//! The serde form of the large parameter sets (the tilt controller's [`crate::tilt_control::TiltParams`],
//! the hopper's [`crate::hop_control::HopParams`]): their fields in declaration order as
//! one flat tuple, nested structs inline.
//!
//! For postcard (the wire) these are exactly the bytes `#[derive(Serialize)]` writes; the
//! difference is the code. The derived deserializer expands every field into its own read
//! and error path (about 25 bytes of Cortex-M code a field, some 1.9 KiB for the two sets);
//! here each field is one call of a shared reader ([`Fields::fields`] lists them once, for
//! both directions), which is what the firmware's 32 KiB flash budget needs. In a
//! self-describing format (JSON, TOML) the form is a flat array of the values in that order.

use core::fmt;
use core::marker::PhantomData;
use serde::de::{self, SeqAccess, Visitor};
use serde::ser::{SerializeTuple, Serializer};
use serde::{Deserialize, Deserializer, Serialize};

/// One field of a flat tuple, by type.
pub(crate) trait FieldVisit {
    /// An f32 field.
    fn f32(&mut self, value: &mut f32);
    /// A u8 field.
    fn u8(&mut self, value: &mut u8);
    /// A u16 field.
    fn u16(&mut self, value: &mut u16);
    /// A u32 field.
    fn u32(&mut self, value: &mut u32);
    /// A bool field.
    fn bool(&mut self, value: &mut bool);
}

/// A parameter set whose serde form is its fields as one flat tuple.
pub(crate) trait Fields: Sized {
    /// Fields in the flat tuple.
    const COUNT: usize;
    /// Type name for error messages.
    const NAME: &'static str;
    /// A value to overwrite field by field (every field is then read).
    fn blank() -> Self;
    /// Visit every field in declaration order, nested structs inline.
    fn fields<V: FieldVisit>(&mut self, v: &mut V);
}

/// Counts the fields a [`Fields::fields`] visits (checks [`Fields::COUNT`] in the tests).
#[cfg(test)]
pub(crate) struct Count(pub usize);

#[cfg(test)]
impl FieldVisit for Count {
    fn f32(&mut self, _: &mut f32) {
        self.0 += 1;
    }
    fn u8(&mut self, _: &mut u8) {
        self.0 += 1;
    }
    fn u16(&mut self, _: &mut u16) {
        self.0 += 1;
    }
    fn u32(&mut self, _: &mut u32) {
        self.0 += 1;
    }
    fn bool(&mut self, _: &mut bool) {
        self.0 += 1;
    }
}

/// Reads the fields from a sequence; after a short sequence or an error, skips the rest.
struct Reader<'a, 'de, A: SeqAccess<'de>> {
    seq: &'a mut A,
    read: usize,
    short: bool,
    error: Option<A::Error>,
    _de: PhantomData<&'de ()>,
}

impl<'de, A: SeqAccess<'de>> Reader<'_, 'de, A> {
    /// The next element into `into`. Not inlined: one copy per element type, one call
    /// per field.
    #[inline(never)]
    fn next<T: Deserialize<'de>>(&mut self, into: &mut T) {
        if self.short || self.error.is_some() {
            return;
        }
        match self.seq.next_element::<T>() {
            Ok(Some(v)) => {
                *into = v;
                self.read += 1;
            }
            Ok(None) => self.short = true,
            Err(e) => self.error = Some(e),
        }
    }
}

impl<'de, A: SeqAccess<'de>> FieldVisit for Reader<'_, 'de, A> {
    fn f32(&mut self, value: &mut f32) {
        self.next(value);
    }
    fn u8(&mut self, value: &mut u8) {
        self.next(value);
    }
    fn u16(&mut self, value: &mut u16) {
        self.next(value);
    }
    fn u32(&mut self, value: &mut u32) {
        self.next(value);
    }
    fn bool(&mut self, value: &mut bool) {
        self.next(value);
    }
}

struct FlatVisitor<P>(PhantomData<P>);

impl<'de, P: Fields> Visitor<'de> for FlatVisitor<P> {
    type Value = P;

    fn expecting(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "the {} fields of {} in order", P::COUNT, P::NAME)
    }

    fn visit_seq<A: SeqAccess<'de>>(self, mut seq: A) -> Result<P, A::Error> {
        let mut value = P::blank();
        let mut r = Reader {
            seq: &mut seq,
            read: 0,
            short: false,
            error: None,
            _de: PhantomData,
        };
        value.fields(&mut r);
        match (r.error, r.short) {
            (Some(e), _) => Err(e),
            (None, true) => Err(de::Error::invalid_length(r.read, &self)),
            (None, false) => Ok(value),
        }
    }
}

/// Deserialize `P` from its flat tuple form.
pub(crate) fn deserialize<'de, P: Fields, D: Deserializer<'de>>(d: D) -> Result<P, D::Error> {
    d.deserialize_tuple(P::COUNT, FlatVisitor(PhantomData))
}

/// Writes the fields into a tuple; keeps the first error.
struct Writer<T: SerializeTuple> {
    tuple: T,
    error: Option<T::Error>,
}

impl<T: SerializeTuple> Writer<T> {
    fn put<V: Serialize>(&mut self, value: &V) {
        if self.error.is_none() {
            if let Err(e) = self.tuple.serialize_element(value) {
                self.error = Some(e);
            }
        }
    }
}

impl<T: SerializeTuple> FieldVisit for Writer<T> {
    fn f32(&mut self, value: &mut f32) {
        self.put(value);
    }
    fn u8(&mut self, value: &mut u8) {
        self.put(value);
    }
    fn u16(&mut self, value: &mut u16) {
        self.put(value);
    }
    fn u32(&mut self, value: &mut u32) {
        self.put(value);
    }
    fn bool(&mut self, value: &mut bool) {
        self.put(value);
    }
}

/// Serialize `value` as its flat tuple form.
pub(crate) fn serialize<P: Fields + Copy, S: Serializer>(
    value: &P,
    s: S,
) -> Result<S::Ok, S::Error> {
    let mut w = Writer {
        tuple: s.serialize_tuple(P::COUNT)?,
        error: None,
    };
    let mut copy = *value;
    copy.fields(&mut w);
    match w.error {
        Some(e) => Err(e),
        None => w.tuple.end(),
    }
}
