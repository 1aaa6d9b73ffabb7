//! Wire protocol between the plant (simulator, or a real sensor/actuator front end) and the
//! controller (firmware, or the core linked into the simulator), for every controller kind.
//!
//! | module | what it holds | imports |
//! | --- | --- | --- |
//! | [`framing`] | `COBS(postcard ++ CRC-32C) ++ 0x00` frames: [`encode`], [`decode`], [`FrameDecoder`], [`LinkStats`], the typed errors | no message, no controller |
//! | [`messages`] | [`HostMessage`], [`DeviceMessage`], [`Rejection`], [`RunSummary`], the partial decode of a firmware image ([`Partial`]) | the kinds, the framing's errors |
//! | [`kinds`] | [`Kind`], [`Config`], [`Frame`], [`Command`] and every [`Wire`] impl: the one file that names every controller kind | the controllers |
//!
//! The layers are one-way: a controller imports [`crate::fixed_rate`] (its [`FixedRate`]
//! shape, [`Mode`], [`Fault`], [`Telemetry`]) and nothing of the protocol; the kinds import
//! the controllers; the messages import the kinds. Every item of the three is re-exported
//! here, so `protocol::X` names it.
//!
//! ## Adding a controller kind
//! 1. Implement [`FixedRate`] for it (its params, frame and command types derive
//!    `Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize`, and hold only
//!    fixed-size fields: numbers, bools, fieldless enums, arrays and structs of them — no
//!    `Option`, slices or strings, so every message has one worst-case size), and
//!    [`Reply`](crate::fixed_rate::Reply) for its command (`seq`, `mode`, `fault`).
//! 2. In [`kinds`] (`kinds.rs`), append a variant named for it at the **end** of [`Kind`],
//!    [`Kind::ALL`], [`Config`], [`Frame`] and [`Command`] (the position is the wire tag:
//!    append only), an arm to each `match` there (the compiler lists the ones missing), and
//!    a line `wire!(path::Controller => Name);` for its [`Wire`] impl.
//! 3. Append `Name(path::Controller) if feature = "name"` to [`for_each_kind!`](crate::for_each_kind)
//!    in the same file, and the feature `name` to `firmware/Cargo.toml`: the firmware's
//!    hosted controllers (`firmware/src/hosted.rs`) are generated from that list.
//!
//! `shared/tests/protocol_props.rs` then checks that every message of the new kind fits
//! [`MAX_PAYLOAD_LEN`] (worst case over every value) and round-trips; the HIL driver
//! (`dexter_sim::hil::LockStep::<path::Controller>`) runs it in QEMU unchanged.
//!
//! [`FixedRate`]: crate::fixed_rate::FixedRate
//! [`Mode`]: crate::fixed_rate::Mode
//! [`Fault`]: crate::fixed_rate::Fault
//! [`Telemetry`]: crate::fixed_rate::Telemetry

pub mod framing;
pub mod kinds;
pub mod messages;

pub use framing::*;
pub use kinds::*;
pub use messages::*;

#[cfg(test)]
mod tests;
