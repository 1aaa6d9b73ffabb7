//! What a system that sweeps declares ([`Sweeps`]): how one point of the grid is evaluated
//! and what its report keeps; the `sweep` verb runs the grid over it.

use super::{Failure, System};
use crate::grid::Grid;
use crate::scene::{SceneError, SceneFile};
use std::io::Write;
use std::path::{Path, PathBuf};

/// A system that sweeps: how one point is evaluated and reported.
pub trait Sweeps: System {
    /// What one point's evaluation produced.
    type Point: Send;
    /// What the summary and the plot keep of the points, in order.
    type Report: SweepReport<Self>;
    /// True if a second axis (`--range2`) is accepted.
    const TWO_AXES: bool = false;
    /// True if `--keep` is used (else it is ignored, as documented).
    const KEEPS: bool = true;

    /// Refuse a key this system cannot sweep (the error names it).
    fn check_key(key: &str) -> Result<(), SceneError> {
        let _ = key;
        Ok(())
    }

    /// Evaluate the scene with the swept value(s) set.
    fn point(base: &SweepBase<Self>, x: f64, y: Option<f64>) -> Result<Self::Point, Failure>;

    /// A report for this sweep.
    fn report(base: &SweepBase<Self>) -> Self::Report;

    /// True if the sweep can be sharded (`--shard K/N`, `dexter merge`): its CSV rows hold
    /// all that its report keeps of a point, so [`Sweeps::read_point`] reads them back.
    const SHARDS: bool = false;

    /// The estimated cost of a run with `key` = `value`, relative to other values of the
    /// same key (a point's cost is the product over its axes): what the shards balance
    /// ([`crate::shard::partition`]). 1 unless the key sets the run's length.
    fn cost(key: &str, value: f64) -> f64 {
        let _ = (key, value);
        1.0
    }

    /// The point whose CSV rows (as [`SweepReport::write_csv`] wrote them at `x`, `y`) are
    /// `rows`: the inverse of `write_csv`, for `dexter merge` (only if [`Sweeps::SHARDS`]).
    fn read_point(x: f64, y: Option<f64>, rows: &[String]) -> Result<Self::Point, String> {
        let _ = (x, y, rows);
        Err(format!(
            "a {} sweep cannot be read back from its CSV",
            Self::NAME
        ))
    }
}

/// What every point of a sweep starts from.
pub struct SweepBase<'a, S: System> {
    /// The scene file.
    pub file: &'a SceneFile,
    /// Its table with `--set` applied.
    pub table: toml::Table,
    /// The base scene, validated.
    pub config: S::Config,
    /// The points.
    pub grid: Grid,
    /// `--keep`.
    pub keep: usize,
}

impl<S: System> SweepBase<'_, S> {
    /// The base table with `key` set to `value`.
    pub fn table_with(&self, key: &str, value: toml::Value) -> Result<toml::Table, Failure> {
        let mut t = self.table.clone();
        crate::scene::apply_set(&mut t, key, value)?;
        Ok(t)
    }
}

/// A sweep's output besides the CSV rows: its summary and its plot.
pub trait SweepReport<S: Sweeps> {
    /// The CSV header.
    fn csv_header(&self) -> String;
    /// One point's CSV rows.
    fn write_csv(
        &self,
        x: f64,
        y: Option<f64>,
        p: &S::Point,
        w: &mut dyn Write,
    ) -> std::io::Result<()>;
    /// Keep what the summary and the plot need of a point (bounded).
    fn add(&mut self, x: f64, y: Option<f64>, p: S::Point);
    /// The summary (may be empty); `csv` is the file the CSV went to, if any.
    fn summary(&self, csv: Option<&Path>) -> Result<String, Failure>;
    /// Draw the plot into `dir`; the files written.
    fn plot(&self, dir: &Path) -> Result<Vec<PathBuf>, Failure>;
}
