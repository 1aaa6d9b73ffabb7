//! A hopper scene's text: the document holding only `[hopper]`, parsed into the model's
//! [`HopperParams`] (the CLI reads the same table through `crate::scene`).
use crate::model::hopper::params::HopperParams;
use crate::model::hopper::HopperError;
use serde::Deserialize;

/// A scene file for the hopper: only a `[hopper]` table.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct HopperScene {
    hopper: HopperParams,
}

impl HopperParams {
    /// Parse a scene's text (a TOML document holding only `[hopper]`); unknown keys are
    /// errors. Does not validate values: see [`HopperParams::build`].
    pub fn from_toml_str(text: &str) -> Result<Self, HopperError> {
        toml::from_str::<HopperScene>(text)
            .map(|s| s.hopper)
            .map_err(|e| HopperError::Toml(e.to_string()))
    }
}
