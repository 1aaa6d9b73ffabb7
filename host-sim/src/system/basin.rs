//! What a system that draws basin maps declares ([`Basins`]): how one run's
//! outcome is classified, and whether a point lies in a certified region.

use super::System;

/// The class of one basin-map point (one run to its end).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum BasinClass {
    /// Converged to the target orbit.
    Target,
    /// Settled on another periodic orbit (its period; 1 = a fixed point off the target).
    OtherPeriod(u32),
    /// Neither converged nor settled by the run's end (diverging, chaotic or slow).
    NotSettled,
    /// Came to rest (the ball on the paddle, a hopper that stopped) or tipped over.
    Rest,
    /// The controller spent most of the run in its safe state.
    Safe,
    /// The run failed (a run error other than a bad scene).
    Failed,
}

impl BasinClass {
    /// The CSV and legend name.
    pub fn name(&self) -> String {
        match self {
            BasinClass::Target => "target".into(),
            BasinClass::OtherPeriod(p) => format!("period_{p}"),
            BasinClass::NotSettled => "not_settled".into(),
            BasinClass::Rest => "rest".into(),
            BasinClass::Safe => "safe_state".into(),
            BasinClass::Failed => "failed".into(),
        }
    }
}

/// A system whose runs `dexter basin` classifies.
pub trait Basins: System {
    /// The class of a finished run of `cfg`.
    fn classify(cfg: &Self::Config, outcome: &Self::Outcome) -> BasinClass;

    /// True if the point `cfg` lies in the region a certificate covers (e.g. the
    /// Singer–Guckenheimer certificate of `dexter analyze`), false if not, `None` if the
    /// system has no certificate for this scene.
    fn certified(cfg: &Self::Config) -> Option<bool> {
        let _ = cfg;
        None
    }

    /// The estimated cost of a run with `key` = `value`, relative to other values of the
    /// same key (a point's is the product over its two axes): what the shards of a map
    /// balance ([`crate::shard::partition`]). 1 unless the key sets the run's length.
    fn cost(key: &str, value: f64) -> f64 {
        let _ = (key, value);
        1.0
    }
}
