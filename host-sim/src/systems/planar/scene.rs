//! A planar scene's text: the document holding only `[planar]`, parsed into the model's
//! [`PlanarParams`] (the CLI reads the same table through `crate::scene`).
use crate::model::planar::{PlanarError, PlanarParams};
use serde::Deserialize;

/// A scene file for the planar body: only a `[planar]` table.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct PlanarScene {
    planar: PlanarParams,
}

impl PlanarParams {
    /// Parse a scene's text (a TOML document holding only `[planar]`); unknown keys are
    /// errors. Does not validate values: see [`PlanarParams::build`].
    pub fn from_toml_str(text: &str) -> Result<Self, PlanarError> {
        toml::from_str::<PlanarScene>(text)
            .map(|s| s.planar)
            .map_err(|e| PlanarError::Toml(e.to_string()))
    }
}
