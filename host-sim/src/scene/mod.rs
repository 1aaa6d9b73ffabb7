//! Scenes: TOML files that describe a model, its initial state, and which effects are on.
//!
//! Parsing goes `text -> toml::Table -> (--set overrides) -> Scene` with unknown keys
//! rejected (`deny_unknown_fields`) and every error carrying the dotted key path; then
//! [`Scene::validate`] checks ranges and cross-field rules. Every key, its unit and its
//! default are documented in `docs/scenes.md`.

mod schema;
mod set;
mod validate;

pub use schema::*;
pub use set::{apply_set, parse_set};
pub use validate::param_error;

use std::fmt;
use std::path::Path;

/// Why a scene was rejected: the dotted key path and the reason.
#[derive(Clone, Debug, PartialEq)]
pub struct SceneError {
    /// Dotted key path of the offending key (e.g. `physics.restitution`), or `""` for the
    /// whole file (unreadable, not TOML).
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

impl Scene {
    /// Parse and validate a scene from TOML text, after applying `overrides`
    /// (`key.path=value` pairs, see [`parse_set`]).
    pub fn from_toml_str(
        text: &str,
        overrides: &[(String, toml::Value)],
    ) -> Result<Self, SceneError> {
        let mut table: toml::Table = text.parse().map_err(|e: toml::de::Error| {
            SceneError::new("", format!("not valid TOML: {}", e.message()))
        })?;
        for (key, value) in overrides {
            apply_set(&mut table, key, value.clone())?;
        }
        Self::from_table(table)
    }

    /// Deserialize and validate a scene from an already parsed table.
    pub fn from_table(table: toml::Table) -> Result<Self, SceneError> {
        let value = toml::Value::Table(table);
        let scene: Scene = serde_path_to_error::deserialize(value).map_err(|e| {
            let path = e.path().to_string();
            let inner = e.into_inner();
            let msg = inner.message().to_string();
            // serde_path_to_error already ends the path with an unknown key's name
            let key = if path == "." { String::new() } else { path };
            SceneError::new(key, msg)
        })?;
        scene.validate()?;
        Ok(scene)
    }

    /// Read, parse and validate a scene file; overrides as in [`Scene::from_toml_str`].
    pub fn load(path: &Path, overrides: &[(String, toml::Value)]) -> Result<Self, SceneError> {
        let text = std::fs::read_to_string(path)
            .map_err(|e| SceneError::new("", format!("cannot read {}: {e}", path.display())))?;
        Self::from_toml_str(&text, overrides)
    }
}

/// Read a scene file as a TOML table with `overrides` applied (not yet validated: see
/// [`Scene::from_table`]); for sweeps, which re-apply one key per run.
pub fn load_table(
    path: &Path,
    overrides: &[(String, toml::Value)],
) -> Result<toml::Table, SceneError> {
    let text = std::fs::read_to_string(path)
        .map_err(|e| SceneError::new("", format!("cannot read {}: {e}", path.display())))?;
    let mut table: toml::Table = text.parse().map_err(|e: toml::de::Error| {
        SceneError::new(
            "",
            format!("{}: not valid TOML: {}", path.display(), e.message()),
        )
    })?;
    for (key, value) in overrides {
        apply_set(&mut table, key, value.clone())?;
    }
    Ok(table)
}
