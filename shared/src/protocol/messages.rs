//! The messages of the link, one set for every controller kind.
//!
//! The host sends [`HostMessage::Configure`] with a [`Config`] (which controller, with what
//! parameters), then one [`HostMessage::Sensor`] [`Frame`] per control period, each answered
//! by [`DeviceMessage::Output`] with a [`Command`] and controller-neutral [`Telemetry`]. A
//! frame of another kind than the configured controller's is answered with
//! [`DeviceMessage::Rejected`] ([`Rejection::WrongKind`]), never a panic. A firmware image
//! decodes only the parameters and frames of the kinds it hosts ([`Partial`]).

use super::framing::{DecodeError, EncodeError, MAX_PAYLOAD_LEN};
use super::kinds::{Command, Config, Frame, Kind};
use crate::fixed_rate::Telemetry;
use serde::{Deserialize, Serialize};

/// A message from the plant side (host) to the controller (firmware).
pub type HostMessage = HostMessageOf<Config, Frame>;

/// [`HostMessage`] with the types `Configure` and `Sensor` carry as parameters. The wire
/// form is the same for any `C`, `F` whose postcard forms are [`Config`]'s and [`Frame`]'s:
/// a firmware image decodes `HostMessageOf<Partial<P>, Partial<F>>`, which decodes the
/// parameters and frames of the kinds it hosts only ([`Partial`]), so a kind it leaves out
/// costs it no decoder.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub enum HostMessageOf<C, F> {
    /// (Re)configure the controller; answered with [`DeviceMessage::Configured`].
    Configure(C),
    /// A sensor sample; answered with [`DeviceMessage::Output`] (or
    /// [`DeviceMessage::Rejected`] if no controller of its kind is configured).
    Sensor(F),
    /// Ask the firmware to end the run: it answers [`DeviceMessage::Stopped`] and exits the
    /// emulator with success.
    Stop,
}

/// Which message a [`HostMessageOf`] payload holds: its variant, as postcard writes it
/// (a varint index, in declaration order).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum HostVariant {
    /// [`HostMessageOf::Configure`].
    Configure,
    /// [`HostMessageOf::Sensor`].
    Sensor,
    /// [`HostMessageOf::Stop`].
    Stop,
}

impl HostVariant {
    /// Split a host message's payload (a frame's, CRC checked: [`FrameDecoder::feed`])
    /// into its variant and the postcard bytes of the variant's value, read as the derived
    /// decoder of [`HostMessageOf`] reads them: decoding that value with [`decode_exact`]
    /// (nothing for `Stop`: its bytes must be empty) accepts and rejects exactly the
    /// payloads `decode_exact::<HostMessageOf<C, F>>` does. A firmware thus decodes each
    /// message straight into the place it keeps it, and never moves a whole message.
    ///
    /// [`FrameDecoder::feed`]: super::FrameDecoder::feed
    /// [`decode_exact`]: super::decode_exact
    pub fn split(payload: &[u8]) -> Result<(HostVariant, &[u8]), DecodeError> {
        let (index, body) =
            postcard::take_from_bytes::<u32>(payload).map_err(|_| DecodeError::Payload)?;
        let variant = match index {
            0 => HostVariant::Configure,
            1 => HostVariant::Sensor,
            2 => HostVariant::Stop,
            _ => return Err(DecodeError::Payload),
        };
        Ok((variant, body))
    }
}

impl Frame {
    /// Decode a [`Frame`] from all of `bytes` ([`decode_exact`](super::decode_exact)) into
    /// `self`, left as it was on an error. Compiled once, here, with the core's
    /// speed-optimised profile (Cargo.toml), for the firmware's hot path.
    #[inline(never)]
    pub fn decode_from(&mut self, bytes: &[u8]) -> Result<(), DecodeError> {
        *self = super::decode_exact(bytes)?;
        Ok(())
    }
}

/// The hosted part of a kind-indexed enum ([`Config`] or [`Frame`]) of a firmware image:
/// one variant per kind it hosts, in any order, decoded by [`Partial`].
pub trait HostedKinds: Sized {
    /// The kind of this value.
    fn kind(&self) -> Kind;
    /// If `kind` is hosted, its value decoded from `body` (`Ok(Ok(..))`, or the decoder's
    /// error); else `body` handed back undecoded (`Ok(Err(body))`).
    fn decode<'de, A: serde::de::VariantAccess<'de>>(
        kind: Kind,
        body: A,
    ) -> Result<Result<Self, A>, A::Error>;
}

/// A [`Config`] or [`Frame`] as an image that hosts the kinds of `T` decodes it: the value
/// of a hosted kind, or only the kind of one it does not host (the rest of the message
/// skipped undecoded, so the image holds no decoder for it).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Partial<T> {
    /// A hosted kind's value.
    Hosted(T),
    /// A kind this image does not host.
    NotHosted(Kind),
}

impl<T: HostedKinds> Partial<T> {
    /// The kind named on the wire, hosted or not.
    pub fn kind(&self) -> Kind {
        match self {
            Partial::Hosted(t) => t.kind(),
            Partial::NotHosted(kind) => *kind,
        }
    }
}

impl<'de, T: HostedKinds> Deserialize<'de> for Partial<T> {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        d.deserialize_enum("Partial", &[], PartialVisitor(core::marker::PhantomData))
    }
}

struct PartialVisitor<T>(core::marker::PhantomData<T>);

impl<'de, T: HostedKinds> serde::de::Visitor<'de> for PartialVisitor<T> {
    type Value = Partial<T>;

    fn expecting(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.write_str("a controller kind and its value")
    }

    fn visit_enum<A: serde::de::EnumAccess<'de>>(self, data: A) -> Result<Self::Value, A::Error> {
        use serde::de::{Error, Unexpected, VariantAccess};
        let (index, body) = data.variant::<u32>()?;
        let kind = Kind::ALL
            .get(index as usize)
            .copied()
            .ok_or_else(|| A::Error::invalid_value(Unexpected::Unsigned(index.into()), &self))?;
        match T::decode(kind, body)? {
            Ok(value) => Ok(Partial::Hosted(value)),
            Err(body) => body
                .newtype_variant_seed(SkipRest)
                .map(|()| Partial::NotHosted(kind)),
        }
    }
}

/// Consumes the rest of a postcard message as single bytes (the undecoded parameters of
/// a kind not hosted are the message's last field: `Configure`'s or `Sensor`'s), so the decode ends at its end.
struct SkipRest;

impl<'de> serde::de::DeserializeSeed<'de> for SkipRest {
    type Value = ();
    fn deserialize<D: serde::Deserializer<'de>>(self, d: D) -> Result<(), D::Error> {
        d.deserialize_tuple(MAX_PAYLOAD_LEN, SkipRest)
    }
}

impl<'de> serde::de::Visitor<'de> for SkipRest {
    type Value = ();

    fn expecting(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.write_str("the rest of the message")
    }

    fn visit_seq<A: serde::de::SeqAccess<'de>>(self, mut seq: A) -> Result<(), A::Error> {
        // postcard reads a byte per element and reports the end of the input as an error
        // without moving: the loop stops there, with every byte consumed.
        while let Ok(Some(_)) = seq.next_element::<u8>() {}
        Ok(())
    }
}

/// Why the firmware refused to step a frame (a protocol error of the host, or a firmware
/// that does not host the kind).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Rejection {
    /// A sensor frame arrived before any accepted `Configure`.
    NotConfigured,
    /// A sensor frame's kind is not the configured controller's.
    WrongKind {
        /// The configured controller's kind.
        configured: Kind,
        /// The frame's kind.
        received: Kind,
    },
    /// `Configure` named a kind this firmware image does not host.
    NotHosted(Kind),
    /// A frame was rejected by the link while no controller was configured (so there is no
    /// safe command to answer with), e.g. a `Configure` this firmware cannot decode.
    Undecodable(DecodeError),
}

/// What the firmware reports when the host stops the run.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct RunSummary {
    /// Control steps run (saturating).
    pub steps: u32,
    /// Safe commands sent because of a link timeout (saturating).
    pub link_timeouts: u32,
    /// Stack high-water mark since reset, bytes (painted stack, see `firmware/src/stack.rs`).
    pub stack_used_bytes: u32,
    /// Stack reserved in memory.x, bytes.
    pub stack_size_bytes: u32,
}

/// A message from the controller (firmware) to the plant side (host).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub enum DeviceMessage {
    /// Answer to `Configure`.
    Configured {
        /// The kind that was configured (or rejected).
        kind: Kind,
        /// True if the parameters were accepted.
        ok: bool,
    },
    /// The command for one sensor frame, with telemetry.
    Output {
        /// The controller's command.
        command: Command,
        /// Status of the firmware.
        telemetry: Telemetry,
    },
    /// The frame was not stepped; see [`Rejection`].
    Rejected(Rejection),
    /// Answer to `Stop`, sent just before the firmware ends the run.
    Stopped(RunSummary),
}

impl DeviceMessage {
    /// [`encode`](super::encode) this message as one delimited frame into `out`: the bytes
    /// written. Compiled once, here, with the core's speed-optimised profile (Cargo.toml),
    /// for the firmware's hot path (its answer to every control period).
    #[inline(never)]
    pub fn encode(&self, out: &mut [u8]) -> Result<usize, EncodeError> {
        super::encode(self, out)
    }
}
