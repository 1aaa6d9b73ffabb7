//! An arm scene's text, parsed into the model's tables ([`ArmConfig`]); errors name the
//! key path (the CLI reads the same tables through `crate::scene`).
use crate::model::arm::params::ArmConfig;
use crate::model::arm::ArmError;

impl ArmConfig {
    /// Parse a scene's text; unknown keys and wrong types are errors naming the key path.
    pub fn from_toml_str(text: &str) -> Result<Self, ArmError> {
        let de = toml::Deserializer::parse(text).map_err(|e| ArmError::Toml(e.to_string()))?;
        serde_path_to_error::deserialize(de)
            .map_err(|e| ArmError::Toml(format!("{}: {}", e.path(), e.inner())))
    }
}
