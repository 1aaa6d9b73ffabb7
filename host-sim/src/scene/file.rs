//! A scene file read once into a TOML table.

use super::{apply_set, SceneError};
use serde::de::DeserializeOwned;
use std::path::{Path, PathBuf};

/// A scene file, read once: its path, its stem (the default scene name) and its table.
#[derive(Clone, Debug, PartialEq)]
pub struct SceneFile {
    /// The path it was read from.
    pub path: PathBuf,
    /// The file stem (`line-juggler` for `scenes/line-juggler.toml`, `stdin` for
    /// `/dev/stdin`), or `scene` if the path has none.
    pub stem: String,
    /// The parsed TOML, before any `--set`.
    pub table: toml::Table,
}

impl SceneFile {
    /// Read `path` (once: a pipe or `/dev/stdin` works) and parse it.
    pub fn read(path: &Path) -> Result<Self, SceneError> {
        let text = std::fs::read_to_string(path)
            .map_err(|e| SceneError::whole(format!("cannot read {}: {e}", path.display())))?;
        Self::parse(path, &text)
    }

    /// Parse `text` as the content of `path`; a syntax error names the file, line and
    /// column.
    pub fn parse(path: &Path, text: &str) -> Result<Self, SceneError> {
        let table: toml::Table = text
            .parse()
            .map_err(|e: toml::de::Error| syntax_error(path, text, &e))?;
        let stem = path
            .file_stem()
            .and_then(|s| s.to_str())
            .unwrap_or("scene")
            .to_string();
        Ok(Self {
            path: path.to_path_buf(),
            stem,
            table,
        })
    }

    /// The table with `overrides` applied (`--set`, a sweep's value), not yet validated.
    pub fn table_with(
        &self,
        overrides: &[(String, toml::Value)],
    ) -> Result<toml::Table, SceneError> {
        let mut table = self.table.clone();
        for (key, value) in overrides {
            apply_set(&mut table, key, value.clone())?;
        }
        Ok(table)
    }
}

/// `path:line:column: not valid TOML: message` (line and column 1-based).
fn syntax_error(path: &Path, text: &str, e: &toml::de::Error) -> SceneError {
    let at = match e.span() {
        Some(span) => {
            let before = &text[..span.start.min(text.len())];
            let line = before.matches('\n').count() + 1;
            let column = before.rsplit('\n').next().map_or(0, |l| l.chars().count()) + 1;
            format!("{}:{line}:{column}", path.display())
        }
        None => path.display().to_string(),
    };
    SceneError::whole(format!("{at}: not valid TOML: {}", e.message().trim_end()))
}

/// Deserialize a scene table into `T`; an unknown key or a wrong type names its dotted path.
pub fn deserialize<T: DeserializeOwned>(table: toml::Table) -> Result<T, SceneError> {
    serde_path_to_error::deserialize(toml::Value::Table(table)).map_err(|e| {
        let path = e.path().to_string();
        let reason = e.into_inner().message().to_string();
        // serde_path_to_error already ends the path with an unknown key's name
        let key = if path == "." { String::new() } else { path };
        SceneError::new(key, reason)
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn syntax_errors_name_file_line_and_column() {
        let e = SceneFile::parse(Path::new("s.toml"), "[a]\nx = 1\ny = = 2\n").unwrap_err();
        assert!(e.reason.starts_with("s.toml:3:5: not valid TOML"), "{e}");
        let e = SceneFile::parse(Path::new("t.toml"), "[physics\n").unwrap_err();
        assert!(e.reason.starts_with("t.toml:1:"), "{e}");
        assert_eq!(e.key, "");
    }

    #[test]
    fn the_stem_names_the_scene_and_overrides_apply_to_a_copy() {
        let f = SceneFile::parse(Path::new("dir/fig.toml"), "[a]\nx = 1\n").unwrap();
        assert_eq!(f.stem, "fig");
        let t = f
            .table_with(&[("a.x".into(), toml::Value::Integer(2))])
            .unwrap();
        assert_eq!(t["a"]["x"].as_integer(), Some(2));
        assert_eq!(f.table["a"]["x"].as_integer(), Some(1));
        assert_eq!(SceneFile::parse(Path::new("/"), "").unwrap().stem, "scene");
    }

    #[test]
    fn deserialize_names_the_key_path() {
        #[derive(serde::Deserialize, Debug)]
        #[serde(deny_unknown_fields)]
        struct Inner {
            #[allow(dead_code)]
            x: f64,
        }
        #[derive(serde::Deserialize, Debug)]
        #[serde(deny_unknown_fields)]
        struct Outer {
            #[allow(dead_code)]
            a: Inner,
        }
        let t: toml::Table = "[a]\nx = \"no\"\n".parse().unwrap();
        assert_eq!(deserialize::<Outer>(t).unwrap_err().key, "a.x");
        let t: toml::Table = "[a]\nx = 1.0\ny = 2\n".parse().unwrap();
        assert_eq!(deserialize::<Outer>(t).unwrap_err().key, "a.y");
    }
}
