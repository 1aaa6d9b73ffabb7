//! `--shard K/N` for `sweep` and `basin`: run the points of one shard ([`crate::shard`])
//! and write its CSV, or do nothing if a complete shard of the same sweep is already there.

use crate::grid::{map_ordered, Grid};
use crate::output::{self, note};
use crate::progress;
use crate::shard::{incomplete, partition, points_of, Shard, ShardWriter, SweepId};
use crate::system::Failure;
use std::path::Path;

/// The estimated cost of every point of `grid`: the product of `cost(key, value)` over its
/// axes.
pub fn costs(grid: &Grid, cost: impl Fn(&str, f64) -> f64) -> Vec<f64> {
    (0..grid.len())
        .map(|i| {
            let (x, y) = grid.point(i);
            let cy = match (&grid.y, y) {
                (Some(r), Some(y)) => cost(&r.key, y),
                _ => 1.0,
            };
            cost(&grid.x.key, x) * cy
        })
        .collect()
}

/// One shard to run: which, where, and what its rows are.
pub struct ShardRun<'a> {
    /// The sweep.
    pub id: SweepId,
    /// `--shard`, as given.
    pub spec: &'a str,
    /// `--csv`.
    pub csv: Option<&'a Path>,
    /// True if `--plot` was given (refused: the merge draws the plots).
    pub plot: bool,
    /// The unsharded CSV header.
    pub columns: String,
    /// Every point's estimated cost ([`costs`]).
    pub costs: Vec<f64>,
}

/// Run the shard: `eval(i)` evaluates point `i` (on every core), `rows(i, p)` is its CSV
/// rows as the unsharded command writes them (in order).
pub fn run<T: Send>(
    s: ShardRun<'_>,
    eval: impl Fn(usize) -> Result<T, Failure> + Sync,
    rows: impl Fn(usize, T) -> Result<Vec<u8>, Failure>,
) -> Result<(), Failure> {
    let shard = Shard::parse(s.spec, s.costs.len()).map_err(Failure::usage)?;
    let Some(path) = s.csv.filter(|p| !output::is_stdout(p)) else {
        return Err(Failure::usage(format!(
            "--shard {shard} needs --csv FILE: a shard is a file that `dexter merge` reads and a re-run finds complete"
        )));
    };
    if s.plot {
        return Err(Failure::usage(format!(
            "--plot with --shard {shard}: a shard draws no plot; give --plot to `dexter merge`"
        )));
    }
    let json = s.id.json().map_err(Failure::run)?;
    let mine = points_of(&partition(&s.costs, shard.n), shard);
    match incomplete(path, &json, shard, &mine, &s.columns) {
        None => {
            note(format_args!(
                "{}: shard {shard} of this {} is already complete: nothing to do",
                path.display(),
                s.id.verb
            ));
            return Ok(());
        }
        Some(why) if path.exists() => note(format_args!("{why}: running shard {shard} again")),
        Some(_) => {}
    }
    let total = s.costs.len();
    let mut w = ShardWriter::create(path, &s.id, &json, shard, (mine.len(), total), &s.columns)?;
    let bar = progress::bar(mine.len() as u64, "points", true);
    let done = map_ordered(
        mine.len(),
        &bar,
        |j| eval(mine[j]),
        |j, p| Ok(w.push(mine[j], &rows(mine[j], p)?)?),
    );
    bar.finish_and_clear();
    done?;
    w.commit()?;
    note(format_args!(
        "wrote {} (shard {shard}: {} of {total} points)",
        path.display(),
        mine.len()
    ));
    Ok(())
}
