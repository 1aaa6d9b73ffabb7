//! The four shipped tasks as scene text: the files `scenes/arm-*.toml` themselves,
//! included at build time, so tests, benches and the CLI read the same text.
//!
//! - [`SNATCH`]: lift a 10 cm square off a table on the link (flush at 0 rad) to rest at
//!   0.3 rad within half a second.
//! - [`THROW`]: carry it on the link and throw it up and back to a goal 0.5 m behind the
//!   joint, 0.8 m up, turned 2.2 rad.
//! - [`ROLL`]: fig. 2: roll a square wooden frame over its vertex nearer the joint, nine
//!   knots, minimizing mu plus the squared landing speed, with the joint's travel and
//!   end angle limited (as the paper limited the arm's end angle).
//! - [`ROLLING_THROW`]: start it rolling outward and throw it back over the joint.

/// `scenes/arm-snatch.toml`.
pub const SNATCH: &str = include_str!("../../../../scenes/arm-snatch.toml");
/// `scenes/arm-throw.toml`.
pub const THROW: &str = include_str!("../../../../scenes/arm-throw.toml");
/// `scenes/arm-roll.toml`.
pub const ROLL: &str = include_str!("../../../../scenes/arm-roll.toml");
/// `scenes/arm-rolling-throw.toml`.
pub const ROLLING_THROW: &str = include_str!("../../../../scenes/arm-rolling-throw.toml");

/// `scenes/arm-throw-catch.toml` (not in [`ALL`]: its tracked catch slips at the plan's own mu).
pub const THROW_CATCH: &str = include_str!("../../../../scenes/arm-throw-catch.toml");

/// All four, with their names.
pub const ALL: [(&str, &str); 4] = [
    ("snatch", SNATCH),
    ("throw", THROW),
    ("roll", ROLL),
    ("rolling_throw", ROLLING_THROW),
];

/// `scenes/arm-juggle.toml`: ten throw-catch cycles in a row, each from where the last
/// catch left the square.
pub const JUGGLE: &str = include_str!("../../../../scenes/arm-juggle.toml");
