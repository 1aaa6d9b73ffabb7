//! `dexter basin`, for every system that classifies its runs ([`Basins`]):
//! every point of a two-key grid (usually initial conditions) is run to its end and
//! classified; the points are evaluated on every core and written in serial order. A
//! larger map runs in shards (`--shard K/N`, [`crate::shard`]) merged by `dexter merge`
//! ([`merge`]) into the same CSV, summary and plot.
//!
//! CSV (`--csv FILE`, else stdout): `KEY1,KEY2,class,certified`, one row per point
//! (`certified` is `true`, `false` or empty when the system has no certificate for the
//! scene). The summary (stdout with `--csv`, else stderr; one JSON object with `--json`)
//! counts each class, the fraction that converged to the target, and that fraction inside
//! the certified region. `--plot DIR` writes `{scene}-basin` (SVG + PNG): one colour per
//! class, the certified points ringed.

use super::merge::{MergeRequest, ShardSet};
use super::shard::{self, ShardRun};
use crate::grid::{map_ordered, Grid, Range};
use crate::output::{AtomicFile, Sig17};
use crate::plot::{key_label, Chart, Style};
use crate::progress;
use crate::scene::{parse_sets, SceneFile};
use crate::shard::SweepId;
use crate::system::basin::{BasinClass, Basins};
use crate::system::{Failure, Setup};
use clap::Args;
use serde_json::json;
use std::collections::BTreeMap;
use std::io::Write;
use std::path::{Path, PathBuf};

/// `dexter basin SCENE ...` as parsed from the command line.
#[derive(Args, Clone, Debug, Default, PartialEq)]
pub struct BasinRequest {
    /// The scene file (TOML).
    pub scene: PathBuf,
    /// The first grid key and its values: key.path=FROM:TO:N.
    #[arg(long, value_name = "KEY=FROM:TO:N")]
    pub range: String,
    /// The second grid key and its values: key.path=FROM:TO:N.
    #[arg(long, value_name = "KEY=FROM:TO:N")]
    pub range2: String,
    /// Override a scene key: key.path=value (repeatable).
    #[arg(long = "set", value_name = "KEY=VALUE")]
    pub sets: Vec<String>,
    /// Write the points as CSV (else on stdout).
    #[arg(long, value_name = "FILE.csv")]
    pub csv: Option<PathBuf>,
    /// Write the basin map into this directory.
    #[arg(long, value_name = "DIR")]
    pub plot: Option<PathBuf>,
    /// Print the summary as one JSON object.
    #[arg(long)]
    pub json: bool,
    /// Run only the K-th of N shards of the grid (1 <= K <= N) into --csv FILE, for
    /// `dexter merge`; a complete shard already there is kept.
    #[arg(long, value_name = "K/N")]
    pub shard: Option<String>,
}

/// One classified point.
struct Point {
    class: BasinClass,
    certified: Option<bool>,
}

/// Every class `dexter basin` writes but the other periods, for reading a name back.
const CLASSES: [BasinClass; 5] = [
    BasinClass::Target,
    BasinClass::NotSettled,
    BasinClass::Rest,
    BasinClass::Safe,
    BasinClass::Failed,
];

impl Point {
    /// Its CSV row `KEY1,KEY2,class,certified` (with the newline).
    fn row(&self, vx: f64, vy: f64) -> String {
        let c = self.certified.map_or(String::new(), |c| c.to_string());
        format!("{},{},{},{c}\n", Sig17(vx), Sig17(vy), self.class.name())
    }

    /// The point of a row [`Point::row`] wrote (without the newline).
    fn read(row: &str) -> Result<(f64, f64, Point), String> {
        let cells: Vec<&str> = row.split(',').collect();
        let [x, y, class, certified] = cells[..] else {
            return Err(format!("`{row}` has not the basin map's 4 columns"));
        };
        let num = |s: &str| s.parse::<f64>().map_err(|_| format!("bad number `{s}`"));
        let period = class.strip_prefix("period_").and_then(|p| p.parse().ok());
        let class = match period {
            Some(p) => BasinClass::OtherPeriod(p),
            None => *CLASSES
                .iter()
                .find(|c| c.name() == class)
                .ok_or_else(|| format!("unknown class `{class}`"))?,
        };
        let certified = match certified {
            "" => None,
            c => Some(c.parse().map_err(|_| format!("bad certified `{c}`"))?),
        };
        Ok((num(x)?, num(y)?, Point { class, certified }))
    }
}

/// The CSV header.
fn header(kx: &str, ky: &str) -> String {
    format!("{kx},{ky},class,certified")
}

/// Run the scene `file` with `base` overrides and `kx` = `vx`, `ky` = `vy` to its end and
/// classify it.
fn evaluate<S: Basins>(
    file: &SceneFile,
    base: &[(String, toml::Value)],
    (kx, vx): (&str, f64),
    (ky, vy): (&str, f64),
) -> Result<Point, Failure> {
    let mut sets = base.to_vec();
    sets.extend(parse_sets(&[
        format!("{kx}={}", Sig17(vx)),
        format!("{ky}={}", Sig17(vy)),
    ])?);
    let cfg = S::parse(file, file.table_with(&sets)?)?;
    let setup = Setup {
        plot: false,
        progress: false,
    };
    let class = match S::run(&cfg, None, &setup, &mut |_| {}) {
        Ok(out) => S::classify(&cfg, &out),
        Err(f) if f.code == crate::system::EXIT_SCENE => return Err(f),
        Err(_) => BasinClass::Failed,
    };
    Ok(Point {
        class,
        certified: S::certified(&cfg),
    })
}

/// `dexter basin` on a scene of system `S`.
pub fn basin<S: Basins>(file: &SceneFile, req: &BasinRequest) -> Result<(), Failure> {
    let x = Range::parse(&req.range)?;
    let y = Range::parse(&req.range2)?;
    let (kx, ky) = (x.key.clone(), y.key.clone());
    let grid = Grid::new(x, Some(y))?;
    let base = parse_sets(&req.sets)?;
    // the base scene once, so that a bad file fails before the map starts
    let table = file.table_with(&base)?;
    S::parse(file, table.clone())?;
    let point = |i: usize| {
        let (vx, vy) = grid.point(i);
        let vy = vy.unwrap_or(f64::NAN);
        Ok::<_, Failure>((vx, vy, evaluate::<S>(file, &base, (&kx, vx), (&ky, vy))?))
    };
    if let Some(spec) = &req.shard {
        let id = SweepId {
            verb: "basin".into(),
            scene: file.stem.clone(),
            table,
            range: grid.x.clone(),
            range2: grid.y.clone(),
            keep: 0,
        };
        let run = ShardRun {
            id,
            spec,
            csv: req.csv.as_deref(),
            plot: req.plot.is_some(),
            columns: header(&kx, &ky),
            costs: shard::costs(&grid, S::cost),
        };
        return shard::run(run, point, |_, (vx, vy, p)| Ok(p.row(vx, vy).into_bytes()));
    }
    let bar = progress::bar(grid.len() as u64, "points", !req.json);
    let mut rows: Vec<(f64, f64, Point)> = Vec::with_capacity(grid.len());
    let done = map_ordered(grid.len(), &bar, point, |_, p| {
        rows.push(p);
        Ok(())
    });
    bar.finish_and_clear();
    done?;
    let out = Output {
        csv: req.csv.as_deref(),
        plot: req.plot.as_deref(),
        json: req.json,
    };
    output(&file.stem, (&kx, &ky), &rows, out)
}

/// `dexter merge` of a basin map's shards: the map's CSV, summary and plot, as `dexter
/// basin` writes them.
pub fn merge<S: Basins>(mut set: ShardSet, req: &MergeRequest) -> Result<(), Failure> {
    let grid = Grid::new(set.id.range.clone(), set.id.range2.clone())?;
    let Some(ry) = &grid.y else {
        return Err(Failure::usage("a basin map's shards name two ranges"));
    };
    let (kx, ky) = (grid.x.key.clone(), ry.key.clone());
    S::parse(&set.file, set.file.table.clone())?;
    set.check_columns(&header(&kx, &ky))?;
    let owner = set.owners(&shard::costs(&grid, S::cost));
    let mut rows = Vec::with_capacity(grid.len());
    for (i, &k) in owner.iter().enumerate() {
        let (vx, vy) = grid.point(i);
        let vy = vy.unwrap_or(f64::NAN);
        let (lines, name) = set.rows(k, i)?;
        let bad = |why: String| Failure::usage(format!("{name}: point {i}: {why}"));
        let [line] = &lines[..] else {
            return Err(bad(format!("{} rows, not one", lines.len())));
        };
        let (_, _, p) = Point::read(line).map_err(bad)?;
        if p.row(vx, vy) != format!("{line}\n") {
            return Err(bad(format!(
                "`{line}` is not the row `dexter basin` writes at {kx} = {vx}, {ky} = {vy}"
            )));
        }
        rows.push((vx, vy, p));
    }
    let name = set.id.scene.clone();
    set.finish()?;
    let out = Output {
        csv: Some(&req.out),
        plot: req.plot.as_deref(),
        json: req.json,
    };
    output(&name, (&kx, &ky), &rows, out)
}

/// Where a basin map goes.
struct Output<'a> {
    csv: Option<&'a Path>,
    plot: Option<&'a Path>,
    json: bool,
}

/// Write the map of `rows` (in grid order) of scene `name` over `kx` x `ky`: its CSV, its
/// summary and its plot.
fn output(
    name: &str,
    (kx, ky): (&str, &str),
    rows: &[(f64, f64, Point)],
    req: Output<'_>,
) -> Result<(), Failure> {
    let mut csv = header(kx, ky) + "\n";
    for (vx, vy, p) in rows {
        csv += &p.row(*vx, *vy);
    }
    match &req.csv {
        Some(path) => {
            let mut f = AtomicFile::create(path)?;
            f.writer()
                .write_all(csv.as_bytes())
                .map_err(|e| Failure::from(f.error(e)))?;
            f.commit()?;
        }
        None => print!("{csv}"),
    }

    let mut counts: BTreeMap<String, usize> = BTreeMap::new();
    for (_, _, p) in rows {
        *counts.entry(p.class.name()).or_default() += 1;
    }
    let n = rows.len();
    let target = |p: &Point| p.class == BasinClass::Target;
    let converged = rows.iter().filter(|r| target(&r.2)).count();
    let inside: Vec<&Point> = rows
        .iter()
        .map(|r| &r.2)
        .filter(|p| p.certified == Some(true))
        .collect();
    let inside_converged = inside.iter().filter(|p| target(p)).count();
    let frac = |a: usize, b: usize| (b > 0).then(|| a as f64 / b as f64);
    let summary = json!({
        "scene": name,
        "keys": [kx, ky],
        "points": n,
        "classes": counts,
        "converged": converged,
        "converged_fraction": frac(converged, n),
        "certified_points": inside.len(),
        "certified_converged_fraction": frac(inside_converged, inside.len()),
    });
    let text = format!(
        "basin of {name} over {kx} x {ky}: {n} points, {converged} converged to the target ({:.4} %); classes {}; certified region: {} points, {} converged{}\n",
        100.0 * frac(converged, n).unwrap_or(0.0),
        counts
            .iter()
            .map(|(k, v)| format!("{k} {v}"))
            .collect::<Vec<_>>()
            .join(", "),
        inside.len(),
        inside_converged,
        frac(inside_converged, inside.len())
            .map_or(String::new(), |f| format!(" ({:.4} %)", 100.0 * f))
    );
    let out = if req.json {
        format!("{summary}\n")
    } else {
        text
    };
    match req.csv {
        Some(_) => print!("{out}"),
        None => eprint!("{out}"),
    }

    if let Some(dir) = &req.plot {
        let mut chart = Chart::new(format!("basin of {name}"), key_label(kx), key_label(ky));
        // one series per class, split by the certificate (the certified region is the set
        // of points drawn in the "(certified region)" colours); every series keeps its slot,
        // empty or not, so that a class has the same colour in every map
        let mut classes: Vec<String> = ["target", "not_settled", "rest", "safe_state", "failed"]
            .iter()
            .map(|c| c.to_string())
            .collect();
        let extra: Vec<String> = counts
            .keys()
            .filter(|k| !classes.contains(k))
            .cloned()
            .collect();
        classes.extend(extra);
        for class in &classes {
            for cert in [Some(true), Some(false), None] {
                let pts: Vec<(f64, f64)> = rows
                    .iter()
                    .filter(|r| &r.2.class.name() == class && r.2.certified == cert)
                    .map(|r| (r.0, r.1))
                    .collect();
                let label = match (pts.is_empty(), cert) {
                    (true, _) => String::new(),
                    (false, Some(true)) => format!("{class} (certified region)"),
                    (false, Some(false)) => format!("{class} (outside the certified region)"),
                    (false, None) => class.clone(),
                };
                chart.push(label, pts, Style::Dots);
            }
        }
        for f in chart
            .draw(dir, &format!("{name}-basin"))
            .map_err(Failure::run)?
        {
            eprintln!("wrote {}", f.display());
        }
    }
    Ok(())
}
