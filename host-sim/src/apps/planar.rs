//! CLI front end of the planar scenes (`[planar]` table): run, sweep, analyze.

use super::{AppAnalyze, AppError, AppRun, AppSweep};

/// `dexter run` on a planar scene.
pub fn run(_args: &AppRun) -> Result<(), AppError> {
    Err(AppError::Scene(
        "planar scenes cannot be run from the CLI yet".into(),
    ))
}

/// `dexter sweep` on a planar scene.
pub fn sweep(_args: &AppSweep) -> Result<(), AppError> {
    Err(AppError::Scene(
        "planar scenes cannot be swept from the CLI yet".into(),
    ))
}

/// `dexter analyze` on a planar scene.
pub fn analyze(_args: &AppAnalyze) -> Result<(), AppError> {
    Err(AppError::Scene(
        "planar scenes cannot be analyzed from the CLI yet".into(),
    ))
}
