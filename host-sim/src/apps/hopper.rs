//! CLI front end of the hopper scenes (`[hopper]` table): run, sweep, analyze.

use super::{AppAnalyze, AppError, AppRun, AppSweep};

/// `dexter run` on a hopper scene.
pub fn run(_args: &AppRun) -> Result<(), AppError> {
    Err(AppError::Scene(
        "hopper scenes cannot be run from the CLI yet".into(),
    ))
}

/// `dexter sweep` on a hopper scene.
pub fn sweep(_args: &AppSweep) -> Result<(), AppError> {
    Err(AppError::Scene(
        "hopper scenes cannot be swept from the CLI yet".into(),
    ))
}

/// `dexter analyze` on a hopper scene.
pub fn analyze(_args: &AppAnalyze) -> Result<(), AppError> {
    Err(AppError::Scene(
        "hopper scenes cannot be analyzed from the CLI yet".into(),
    ))
}
