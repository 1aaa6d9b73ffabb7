//! What a system that analyzes declares ([`Analyzes`]): `dexter analyze` parses the scene,
//! asks the system for its [`Report`] and prints it as text or JSON.

use super::{Failure, System};
use crate::scene::SceneFile;

/// An analysis as the CLI prints it.
pub trait Report {
    /// The human report.
    fn text(&self) -> String;
    /// One JSON object.
    fn json(&self) -> Result<String, String>;
    /// Draw the analysis' pictures into `dir` (`--plot`); refused (exit 2) by default.
    fn plot(&self, dir: &std::path::Path) -> Result<Vec<std::path::PathBuf>, Failure> {
        let _ = dir;
        Err(Failure::usage("--plot: this analysis has no pictures"))
    }
}

/// A system with an analysis of its own (linearization, closed forms).
pub trait Analyzes: System {
    /// Analyze the scene `cfg` (parsed from `file` with `--set` applied).
    fn analyze<'a>(
        file: &'a SceneFile,
        cfg: &'a Self::Config,
    ) -> Result<Box<dyn Report + 'a>, Failure>;
}
