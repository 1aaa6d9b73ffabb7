//! `dexter merge OUT.csv SHARD...`: the shards of one sweep or basin map
//! ([`crate::shard`]) back into the CSV, summary and plot the unsharded command writes.
//!
//! The shards are checked first, and the merge refused (exit 2) naming the shard: one that
//! is not a shard or is incomplete, one of another sweep (another hash: scene, `--set`,
//! ranges or `--keep`), one given twice, one missing. Then the points are read in grid
//! order, each from the shard the deal gave it to, read back into the system's point
//! ([`crate::system::Sweeps::read_point`]) and written by the same code as the unsharded
//! sweep; a row that does not read back to the bytes it holds refuses the merge. The
//! output is written whole or not at all; memory holds one point of each shard at a time
//! (a sweep; a basin map holds its points, as `dexter basin` does).

use super::sweep::{costs, finish};
use crate::output::AtomicFile;
use crate::scene::SceneFile;
use crate::shard::{partition, ShardFile, SweepId};
use crate::system::{unsupported, Failure, SweepBase, SweepReport, Sweeps};
use clap::Args;
use std::io::Write;
use std::path::PathBuf;

/// `dexter merge OUT.csv SHARD...` as parsed from the command line.
#[derive(Args, Clone, Debug, Default, PartialEq)]
pub struct MergeRequest {
    /// The merged CSV (as the unsharded sweep's `--csv`).
    pub out: PathBuf,
    /// Every shard's CSV (`--shard K/N` outputs), each once, in any order.
    #[arg(required = true, num_args = 1..)]
    pub shards: Vec<PathBuf>,
    /// Draw the sweep's plot (or the basin map) into this directory.
    #[arg(long, value_name = "DIR")]
    pub plot: Option<PathBuf>,
    /// A basin map's summary as one JSON object (as `dexter basin --json`).
    #[arg(long)]
    pub json: bool,
}

/// The shards of one sweep, checked to cover it once, in shard order.
pub struct ShardSet {
    /// The sweep.
    pub id: SweepId,
    /// Its scene, rebuilt from the shards' `sweep` line (`--set` applied).
    pub file: SceneFile,
    shards: Vec<ShardFile>,
}

/// The shard files named `K/N` in messages: `path (shard K/N)`.
fn named(f: &ShardFile) -> String {
    format!("{} (shard {})", f.path.display(), f.shard)
}

impl ShardSet {
    /// Open every shard of `req` and check that they are the shards of one sweep, each
    /// once and none missing.
    pub fn open(req: &MergeRequest) -> Result<Self, Failure> {
        let mut files = Vec::with_capacity(req.shards.len());
        for p in &req.shards {
            files.push(ShardFile::open(p).map_err(Failure::usage)?);
        }
        let first = &files[0];
        for f in &files[1..] {
            if f.hash != first.hash {
                return Err(Failure::usage(format!(
                    "{} is a shard of another sweep than {}: sweep hash {}, not {} (a different scene, --set, range or --keep)",
                    named(f),
                    named(first),
                    f.hash,
                    first.hash
                )));
            }
            if f.shard.n != first.shard.n {
                return Err(Failure::usage(format!(
                    "{} is one of {} shards, {} one of {}",
                    named(f),
                    f.shard.n,
                    named(first),
                    first.shard.n
                )));
            }
        }
        let n = first.shard.n as usize;
        let mut slots: Vec<Option<ShardFile>> = (0..n).map(|_| None).collect();
        for f in files {
            let k = f.shard.k as usize;
            if let Some(other) = &slots[k - 1] {
                return Err(Failure::usage(format!(
                    "shard {} is given twice: {} and {}",
                    f.shard,
                    other.path.display(),
                    f.path.display()
                )));
            }
            slots[k - 1] = Some(f);
        }
        let missing: Vec<String> = (0..n)
            .filter(|&k| slots[k].is_none())
            .map(|k| format!("{}/{n}", k + 1))
            .collect();
        if !missing.is_empty() {
            return Err(Failure::usage(format!(
                "shard{} {} of this sweep {} missing (run `--shard K/N` for {}, or give {} file{})",
                if missing.len() > 1 { "s" } else { "" },
                missing.join(", "),
                if missing.len() > 1 { "are" } else { "is" },
                if missing.len() > 1 { "each" } else { "it" },
                if missing.len() > 1 { "their" } else { "its" },
                if missing.len() > 1 { "s" } else { "" },
            )));
        }
        let shards: Vec<ShardFile> = slots.into_iter().flatten().collect();
        let id = shards[0].id().map_err(Failure::usage)?;
        let file = SceneFile {
            path: PathBuf::from(format!("{}.toml", id.scene)),
            stem: id.scene.clone(),
            table: id.table.clone(),
        };
        Ok(Self { id, file, shards })
    }

    /// The verb that made the shards (`sweep` or `basin`).
    pub fn verb(&self) -> &str {
        &self.id.verb
    }

    /// Refuse shards whose CSV header is not `point,` + `columns`.
    pub fn check_columns(&self, columns: &str) -> Result<(), Failure> {
        match self.shards.iter().find(|f| f.columns != columns) {
            None => Ok(()),
            Some(f) => Err(Failure::usage(format!(
                "{}: its CSV header is `point,{}`, not `point,{columns}`",
                named(f),
                f.columns
            ))),
        }
    }

    /// The shard (0-based) of each point, for points of estimated costs `costs`.
    pub fn owners(&self, costs: &[f64]) -> Vec<u32> {
        partition(costs, self.shards.len() as u32)
    }

    /// The rows of point `i` from shard `k` (0-based), and the shard's name for messages.
    pub fn rows(&mut self, k: u32, i: usize) -> Result<(Vec<String>, String), Failure> {
        let f = &mut self.shards[k as usize];
        let rows = f.next_point(i).map_err(Failure::usage)?;
        Ok((rows, named(f)))
    }

    /// Check that every shard was read to its end, and only its points were in it.
    pub fn finish(self) -> Result<(), Failure> {
        for f in self.shards {
            f.finish().map_err(Failure::usage)?;
        }
        Ok(())
    }
}

/// `dexter merge` of a sweep of system `S`.
pub fn merge_sweep<S: Sweeps>(mut set: ShardSet, req: &MergeRequest) -> Result<(), Failure> {
    if !S::SHARDS {
        return Err(unsupported::<S>("--shard"));
    }
    let file = set.file.clone();
    let grid = crate::grid::Grid::new(set.id.range.clone(), set.id.range2.clone())?;
    let base = SweepBase::<S> {
        file: &file,
        table: file.table.clone(),
        config: S::parse(&file, file.table.clone())?,
        grid,
        keep: set.id.keep,
    };
    let mut report = S::report(&base);
    set.check_columns(&report.csv_header())?;
    let owner = set.owners(&costs(&base));
    let mut csv = AtomicFile::create(&req.out)?;
    writeln!(csv.writer(), "{}", report.csv_header()).map_err(|e| csv.error(e))?;
    for (i, &k) in owner.iter().enumerate() {
        let (x, y) = base.grid.point(i);
        let (lines, name) = set.rows(k, i)?;
        let bad = |why: String| Failure::usage(format!("{name}: point {i}: {why}"));
        let p = S::read_point(x, y, &lines).map_err(bad)?;
        let mut rows = Vec::new();
        report
            .write_csv(x, y, &p, &mut rows)
            .map_err(Failure::run)?;
        if !same_rows(&rows, &lines) {
            return Err(bad(
                "its rows do not read back to the rows `dexter sweep` writes for it".into(),
            ));
        }
        csv.writer().write_all(&rows).map_err(|e| csv.error(e))?;
        report.add(x, y, p);
    }
    set.finish()?;
    finish::<S>(&report, csv, Some(&req.out), req.plot.as_deref())
}

/// True if `rows` (lines ending in newlines) are `lines`.
fn same_rows(rows: &[u8], lines: &[String]) -> bool {
    let mut joined = Vec::with_capacity(rows.len());
    for l in lines {
        joined.extend_from_slice(l.as_bytes());
        joined.push(b'\n');
    }
    joined == rows
}
