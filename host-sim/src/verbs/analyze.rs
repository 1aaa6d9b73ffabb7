//! `dexter analyze`, for every system that analyzes ([`Analyzes`]).

use super::{print_result, AnalyzeRequest};
use crate::scene::{parse_sets, SceneFile};
use crate::system::{Analyzes, Failure};

/// `dexter analyze` on a scene of system `S`: parse (with `--set`), analyze, print the
/// report as text or (`--json`) one JSON object.
pub fn analyze<S: Analyzes>(file: &SceneFile, req: &AnalyzeRequest) -> Result<(), Failure> {
    let table = file.table_with(&parse_sets(&req.sets)?)?;
    let cfg = S::parse(file, table)?;
    let report = S::analyze(file, &cfg)?;
    print_result(req.json, || report.text(), || report.json())?;
    if let Some(dir) = &req.plot {
        for f in report.plot(dir)? {
            eprintln!("wrote {}", f.display());
        }
    }
    Ok(())
}
