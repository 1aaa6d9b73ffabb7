//! `dexter basin`, for every system that classifies its runs ([`Basins`], issue 24 item 3):
//! every point of a two-key grid (usually initial conditions) is run to its end and
//! classified; the points are evaluated on every core and written in serial order (the
//! shards of a larger map are the sub-grids given by `--range`/`--range2`).
//!
//! CSV (`--csv FILE`, else stdout): `KEY1,KEY2,class,certified`, one row per point
//! (`certified` is `true`, `false` or empty when the system has no certificate for the
//! scene). The summary (stdout with `--csv`, else stderr; one JSON object with `--json`)
//! counts each class, the fraction that converged to the target, and that fraction inside
//! the certified region. `--plot DIR` writes `{scene}-basin` (SVG + PNG): one colour per
//! class, the certified points ringed.

use crate::grid::{map_ordered, Grid, Range};
use crate::output::{AtomicFile, Sig17};
use crate::plot::{key_label, Chart, Style};
use crate::progress;
use crate::scene::{parse_sets, SceneFile};
use crate::system::basin::{BasinClass, Basins};
use crate::system::{Failure, Setup};
use clap::Args;
use serde_json::json;
use std::collections::BTreeMap;
use std::io::Write;
use std::path::PathBuf;

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
}

/// One classified point.
struct Point {
    class: BasinClass,
    certified: Option<bool>,
}

/// `dexter basin` on a scene of system `S`.
pub fn basin<S: Basins>(file: &SceneFile, req: &BasinRequest) -> Result<(), Failure> {
    let x = Range::parse(&req.range)?;
    let y = Range::parse(&req.range2)?;
    let (kx, ky) = (x.key.clone(), y.key.clone());
    let grid = Grid::new(x, Some(y))?;
    let base = parse_sets(&req.sets)?;
    // the base scene once, so that a bad file fails before the map starts
    let name = {
        let cfg = S::parse(file, file.table_with(&base)?)?;
        let _ = cfg;
        file.stem.clone()
    };
    let bar = progress::bar(grid.len() as u64, "points", !req.json);
    let mut rows: Vec<(f64, f64, Point)> = Vec::with_capacity(grid.len());
    let done = map_ordered(
        grid.len(),
        &bar,
        |i| {
            let (vx, vy) = grid.point(i);
            let vy = vy.unwrap_or(f64::NAN);
            let mut sets = base.clone();
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
        },
        |i, p| {
            let (vx, vy) = grid.point(i);
            rows.push((vx, vy.unwrap_or(f64::NAN), p));
            Ok(())
        },
    );
    bar.finish_and_clear();
    done?;

    let mut csv = format!("{kx},{ky},class,certified\n");
    for (vx, vy, p) in &rows {
        let c = p.certified.map_or(String::new(), |c| c.to_string());
        csv += &format!("{},{},{},{c}\n", Sig17(*vx), Sig17(*vy), p.class.name());
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
    for (_, _, p) in &rows {
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
        let mut chart = Chart::new(format!("basin of {name}"), key_label(&kx), key_label(&ky));
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
