//! `dexter sweep`, for every system that sweeps ([`Sweeps`]).
//!
//! The base scene (`--set` applied) is validated once, so a bad file fails before the sweep
//! starts. The points of the grid are evaluated on every core and consumed in serial order
//! ([`crate::sweep::map_ordered`]): each point's CSV rows are streamed (to `--csv FILE`,
//! committed whole at the end, else to stdout) and the system's report keeps what its
//! summary and plot need. Then the summary is printed (to stdout with `--csv`, else to
//! stderr, after the CSV), and the plot drawn.

use super::{Failure, SweepRequest};
use crate::output::AtomicFile;
use crate::progress;
use crate::scene::{parse_sets, SceneError, SceneFile};
use crate::sweep::{map_ordered, Grid, Range};
use crate::systems::{unsupported, System};
use std::io::Write;
use std::path::{Path, PathBuf};

/// Most late values a sweep keeps per point (`--keep`).
pub const MAX_KEEP: usize = 100_000;

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

/// Where the CSV goes.
enum CsvOut {
    File(AtomicFile),
    Stdout(std::io::BufWriter<std::io::StdoutLock<'static>>),
}

impl CsvOut {
    fn open(path: Option<&Path>) -> Result<Self, Failure> {
        Ok(match path {
            Some(p) => CsvOut::File(AtomicFile::create(p)?),
            None => CsvOut::Stdout(std::io::BufWriter::new(std::io::stdout().lock())),
        })
    }
    fn writer(&mut self) -> &mut dyn Write {
        match self {
            CsvOut::File(f) => f.writer(),
            CsvOut::Stdout(w) => w,
        }
    }
    fn error(&self, e: std::io::Error) -> Failure {
        match self {
            CsvOut::File(f) => f.error(e).into(),
            CsvOut::Stdout(_) => Failure::run(format!("cannot write the CSV to stdout: {e}")),
        }
    }
    fn finish(self) -> Result<(), Failure> {
        match self {
            CsvOut::File(f) => Ok(f.commit()?),
            CsvOut::Stdout(mut w) => w
                .flush()
                .map_err(|e| Failure::run(format!("cannot write the CSV to stdout: {e}"))),
        }
    }
}

/// The grid of `req`'s ranges, checked against what `S` sweeps.
fn grid<S: Sweeps>(req: &SweepRequest) -> Result<Grid, Failure> {
    let x = Range::parse(&req.range)?;
    S::check_key(&x.key)?;
    let y = match &req.range2 {
        None => None,
        Some(_) if !S::TWO_AXES => return Err(unsupported::<S>("--range2")),
        Some(r) => {
            let y = Range::parse(r)?;
            S::check_key(&y.key)?;
            Some(y)
        }
    };
    if S::KEEPS && !(1..=MAX_KEEP).contains(&req.keep) {
        return Err(Failure::usage(format!(
            "--keep must be in 1..={MAX_KEEP}, got {}",
            req.keep
        )));
    }
    Ok(Grid::new(x, y)?)
}

/// `dexter sweep` on a scene of system `S`.
pub fn sweep<S: Sweeps>(file: &SceneFile, req: &SweepRequest) -> Result<(), Failure> {
    let grid = grid::<S>(req)?;
    let table = file.table_with(&parse_sets(&req.sets)?)?;
    // validate the base scene once so a bad file fails before the sweep starts
    let config = S::parse(file, table.clone())?;
    let base = SweepBase::<S> {
        file,
        table,
        config,
        grid,
        keep: req.keep,
    };
    let mut report = S::report(&base);
    let mut csv = CsvOut::open(req.csv.as_deref())?;
    let bar = progress::bar(base.grid.len() as u64, "points", true);
    let swept = map_ordered(
        base.grid.len(),
        &bar,
        |i| {
            let (x, y) = base.grid.point(i);
            S::point(&base, x, y)
        },
        |i, p| {
            let (x, y) = base.grid.point(i);
            let w = csv.writer();
            // the header with the first row: a sweep whose first point fails prints nothing
            let header = if i == 0 {
                writeln!(w, "{}", report.csv_header())
            } else {
                Ok(())
            };
            header
                .and_then(|_| report.write_csv(x, y, &p, w))
                .map_err(|e| csv.error(e))?;
            report.add(x, y, p);
            Ok(())
        },
    );
    bar.finish_and_clear();
    swept?;
    csv.finish()?;
    let summary = report.summary(req.csv.as_deref())?;
    match req.csv {
        Some(_) => print!("{summary}"),
        None => eprint!("{summary}"),
    }
    if let Some(dir) = &req.plot {
        for f in report.plot(dir)? {
            eprintln!("wrote {}", f.display());
        }
    }
    Ok(())
}
