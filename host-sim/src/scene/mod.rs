//! Scene files, the same for every system: read **once** (so `dexter run /dev/stdin` and
//! `<(...)` work), parsed as TOML with syntax errors that name the file, line and column,
//! `--set key.path=value` overrides applied to the table (so they pass the same checks as
//! the file), and deserialization into a system's schema with errors that name the dotted
//! key (unknown keys, wrong types). Which system runs a scene is decided from its top-level
//! tables (`crate::cli::registry::claim`); each system validates its own ranges.

mod file;
mod set;

pub use file::{deserialize, SceneFile};
pub use set::{apply_set, check_key, parse_set, parse_sets, MAX_KEY_DEPTH};

use std::fmt;

/// Why a scene was rejected: the dotted key path and the reason.
#[derive(Clone, Debug, PartialEq)]
pub struct SceneError {
    /// Dotted key path of the offending key (e.g. `physics.restitution`), or `""` for the
    /// whole file (unreadable, not TOML) or a rule between keys the reason names.
    pub key: String,
    /// What is wrong with it.
    pub reason: String,
}

impl SceneError {
    /// An error for `key` with `reason`.
    pub fn new(key: impl Into<String>, reason: impl Into<String>) -> Self {
        Self {
            key: key.into(),
            reason: reason.into(),
        }
    }

    /// An error about the scene as a whole (no single key), e.g. a model's own
    /// validation message that already names its key.
    pub fn whole(reason: impl fmt::Display) -> Self {
        Self::new("", reason.to_string())
    }

    /// A core parameter error under its scene key: `key` maps the core's parameter name to
    /// the key, `docs` is the page that gives the allowed ranges. An error without a
    /// parameter name is reported as a whole.
    pub fn of_param(
        e: dexter_core::params::ParamError,
        docs: &str,
        key: impl FnOnce(&'static str) -> String,
    ) -> Self {
        use dexter_core::params::ParamError as P;
        let (name, reason) = match e {
            P::NotFinite(n) => (n, "must be a finite number".to_string()),
            P::NotPositive(n) => (n, "must be > 0".into()),
            P::Negative(n) => (n, "must be >= 0".into()),
            P::OutOfRange(n) => (n, format!("is out of its allowed range ({docs})")),
            other => return Self::whole(other),
        };
        Self::new(key(name), reason)
    }
}

impl fmt::Display for SceneError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        if self.key.is_empty() {
            write!(f, "{}", self.reason)
        } else {
            write!(f, "`{}`: {}", self.key, self.reason)
        }
    }
}

impl std::error::Error for SceneError {}
