//! CLI front ends of the models that have their own scene tables: a scene file whose
//! top-level table is `[hopper]` or `[planar]` is run by [`hopper`] or [`planar`]; any
//! other scene is a line-model scene (`crate::scene::Scene`).

pub mod hopper;
pub mod planar;

use std::path::{Path, PathBuf};

/// Which model family a scene file describes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Kind {
    /// Ball and paddle on a vertical line (`crate::scene::Scene`).
    Line,
    /// The vertical hopper of Koditschek & Bühler (`[hopper]`).
    Hopper,
    /// Zumel & Erdmann's bouncing body or the planar juggler (`[planar]`).
    Planar,
}

/// `dexter run` for an app scene.
#[derive(Clone, Debug, Default)]
pub struct AppRun {
    /// The scene file.
    pub scene: PathBuf,
    /// `--set key.path=value` overrides, unparsed.
    pub sets: Vec<String>,
    /// `--impacts N` (hopper: cycles), if given.
    pub impacts: Option<u64>,
    /// Print one JSON object instead of the human summary.
    pub json: bool,
    /// Write plots (SVG and PNG) into this directory.
    pub plot: Option<PathBuf>,
    /// Write a per-impact (per-cycle) CSV trace to this file.
    pub trace: Option<PathBuf>,
}

/// `dexter sweep` for an app scene.
#[derive(Clone, Debug, Default)]
pub struct AppSweep {
    /// The scene file.
    pub scene: PathBuf,
    /// `--set key.path=value` overrides, unparsed.
    pub sets: Vec<String>,
    /// `--range key.path=FROM:TO:N`, unparsed.
    pub range: String,
    /// `--range2 key.path=FROM:TO:N`, unparsed: a second swept key (planar stability map).
    pub range2: Option<String>,
    /// Late values kept from each run.
    pub keep: usize,
    /// Write the points as CSV.
    pub csv: Option<PathBuf>,
    /// Write the plot into this directory.
    pub plot: Option<PathBuf>,
}

/// `dexter analyze` for an app scene.
#[derive(Clone, Debug, Default)]
pub struct AppAnalyze {
    /// The scene file.
    pub scene: PathBuf,
    /// `--set key.path=value` overrides, unparsed.
    pub sets: Vec<String>,
    /// Print one JSON object instead of the human report.
    pub json: bool,
}

/// Why an app command failed; the CLI maps it to an exit status.
#[derive(Debug, PartialEq)]
pub enum AppError {
    /// Bad scene or bad arguments (exit status 2); the message names the key.
    Scene(String),
    /// The run failed (exit status 1).
    Run(String),
}

impl std::fmt::Display for AppError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            AppError::Scene(m) | AppError::Run(m) => f.write_str(m),
        }
    }
}

/// The model family of the scene at `path`, from its top-level tables.
pub fn kind_of(path: &Path) -> Result<Kind, AppError> {
    let text = std::fs::read_to_string(path)
        .map_err(|e| AppError::Scene(format!("cannot read {}: {e}", path.display())))?;
    let table: toml::Table = text.parse().map_err(|e: toml::de::Error| {
        AppError::Scene(format!("not valid TOML: {}", e.message()))
    })?;
    Ok(if table.contains_key("hopper") {
        Kind::Hopper
    } else if table.contains_key("planar") {
        Kind::Planar
    } else {
        Kind::Line
    })
}
