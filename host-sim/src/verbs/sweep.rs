//! `dexter sweep`, for every system that sweeps ([`Sweeps`]).
//!
//! The base scene (`--set` applied) is validated once, so a bad file fails before the sweep
//! starts. The points of the grid are evaluated on every core and consumed in serial order
//! ([`crate::grid::map_ordered`]): each point's CSV rows are streamed (to `--csv FILE`,
//! committed whole at the end, else to stdout) and the system's report keeps what its
//! summary and plot need. Then the summary is printed (to stdout with `--csv`, else to
//! stderr, after the CSV), and the plot drawn.

use super::shard::{self, ShardRun};
use super::SweepRequest;
use crate::grid::{map_ordered, Grid, Range};
use crate::output::{self, note, print_stderr, print_stdout, AtomicFile, Batch};
use crate::progress;
use crate::scene::{check_key, parse_sets, SceneFile};
use crate::shard::SweepId;
use crate::system::{unsupported, Failure, SweepBase, SweepReport, Sweeps};
use std::io::Write;
use std::path::Path;

/// Most late values a sweep keeps per point (`--keep`).
pub const MAX_KEEP: usize = 100_000;

/// The grid of `req`'s ranges, checked against what `S` sweeps.
fn grid<S: Sweeps>(req: &SweepRequest) -> Result<Grid, Failure> {
    let x = Range::parse(&req.range)?;
    check_key(&x.key)?;
    S::check_key(&x.key)?;
    let y = match &req.range2 {
        None => None,
        Some(_) if !S::TWO_AXES => return Err(unsupported::<S>("--range2")),
        Some(r) => {
            let y = Range::parse(r)?;
            check_key(&y.key)?;
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
    if let Some(spec) = &req.shard {
        return sweep_shard(&base, req, spec);
    }
    let mut report = S::report(&base);
    // `--csv -` (or /dev/stdout) is the CSV on stdout, as without `--csv`
    let csv_file = req.csv.as_deref().filter(|p| !output::is_stdout(p));
    let mut csv = AtomicFile::create(csv_file.unwrap_or(Path::new("-")))?;
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
    finish::<S>(&report, csv, csv_file, req.plot.as_deref())
}

/// The estimated cost of every point of `base`'s grid ([`Sweeps::cost`]).
pub fn costs<S: Sweeps>(base: &SweepBase<S>) -> Vec<f64> {
    shard::costs(&base.grid, S::cost)
}

/// `dexter sweep --shard K/N`: the shard's points, in a shard CSV ([`crate::shard`]).
fn sweep_shard<S: Sweeps>(
    base: &SweepBase<S>,
    req: &SweepRequest,
    spec: &str,
) -> Result<(), Failure> {
    if !S::SHARDS {
        return Err(unsupported::<S>("--shard"));
    }
    let report = S::report(base);
    let id = SweepId {
        verb: "sweep".into(),
        scene: base.file.stem.clone(),
        table: base.table.clone(),
        range: base.grid.x.clone(),
        range2: base.grid.y.clone(),
        keep: req.keep,
    };
    let run = ShardRun {
        id,
        spec,
        csv: req.csv.as_deref(),
        plot: req.plot.is_some(),
        columns: report.csv_header(),
        costs: costs(base),
    };
    let eval = |i| {
        let (x, y) = base.grid.point(i);
        S::point(base, x, y)
    };
    shard::run(run, eval, |i, p| {
        let (x, y) = base.grid.point(i);
        let mut rows = Vec::new();
        report
            .write_csv(x, y, &p, &mut rows)
            .map_err(Failure::run)?;
        Ok(rows)
    })
}

/// The end of a sweep whose rows are all in `csv` (from the points, or merged from its
/// shards): commit it, print the summary and draw the plot, all or nothing.
pub(super) fn finish<S: Sweeps>(
    report: &S::Report,
    csv: AtomicFile,
    csv_file: Option<&Path>,
    plot: Option<&Path>,
) -> Result<(), Failure> {
    // the CSV file and the plot appear together, and only if the whole sweep succeeds
    let batch = Batch::begin();
    csv.commit()?;
    let summary = report.summary(csv_file)?;
    let written = match plot {
        Some(dir) => report.plot(dir)?,
        None => Vec::new(),
    };
    // the summary before the renames: a sweep whose summary cannot be printed fails, and
    // writes nothing
    match csv_file {
        Some(_) => print_stdout(&summary)?,
        None => print_stderr(&summary),
    }
    batch.commit()?;
    for f in written {
        note(format_args!("wrote {}", f.display()));
    }
    Ok(())
}
