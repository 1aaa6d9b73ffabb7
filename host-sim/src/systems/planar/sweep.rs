//! `dexter sweep` on a planar scene: the stability map (sec. 2.3). Every cell is the scene
//! with the swept value(s) set, run for `planar.impacts` and classified by
//! [`crate::model::planar::stats::classify`]. CSV: the swept key(s), `class`, `impacts`, `end`,
//! `max_abs_theta_rad`, `late_mean_energy_jpkg`, rows range2-major; with `--csv` a letter
//! grid and the count of cells upright for all impacts are printed; `--plot` draws
//! `{stem}-stability`. A scene with a `[real_table]` runs each cell on the real table (SIL),
//! so `--range planar.seed=1:20:20` counts the camera seeds that stay upright.

use super::summary::{class_name, class_words, kappa_crit_of, summarize};
use super::{config_of, PlanarSystem};
use crate::model::planar::stats::CellClass;
use crate::model::planar::stats::RunStats;
use crate::model::planar::{PlanarParams, RunEnd};
use crate::output::Sig17;
use crate::plot::{key_label, Chart};
use crate::scene::SceneError;
use crate::stream::Decimator;
use crate::system::{Failure, Setup, SweepBase, SweepReport, Sweeps};
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

/// One cell of a planar sweep.
#[derive(Clone, Debug)]
pub struct SweepCell {
    class: CellClass,
    impacts: usize,
    end: RunEnd,
    max_abs_theta_rad: f64,
    late_mean_energy_jpkg: f64,
}

/// The classes in the plot's order (one dotted series each).
const CLASSES: [CellClass; 4] = [
    CellClass::Converges,
    CellClass::Drifts,
    CellClass::TipsOver,
    CellClass::Diverges,
];

/// The TOML value of a swept number: integer keys (impacts, seed) keep an integer.
fn swept_value(key: &str, v: f64) -> toml::Value {
    let integer = key == "planar.impacts" || key == "planar.seed";
    if integer && v.fract() == 0.0 && v.abs() < 9.0e15 {
        toml::Value::Integer(v as i64)
    } else {
        toml::Value::Float(v)
    }
}

/// Every run end, for reading a name back.
const RUN_ENDS: [RunEnd; 8] = [
    RunEnd::Completed,
    RunEnd::TippedOver,
    RunEnd::NoSeparation,
    RunEnd::NoContact,
    RunEnd::SearchCap,
    RunEnd::Jam,
    RunEnd::NonFinite,
    RunEnd::TimeLimit,
];

/// A run end's name in the CSV (its JSON name).
fn end_name(e: RunEnd) -> String {
    serde_json::to_value(e)
        .ok()
        .and_then(|v| v.as_str().map(str::to_string))
        .unwrap_or_default()
}

fn class_letter(c: CellClass) -> char {
    match c {
        CellClass::Converges => 'C',
        CellClass::Drifts => 'D',
        CellClass::TipsOver => 'T',
        CellClass::Diverges => 'X',
    }
}

/// The axis label of a key: without `planar.`, with its unit.
fn axis_label(key: &str) -> String {
    key_label(key.strip_prefix("planar.").unwrap_or(key))
}

/// What the summary (letter grid) and the stability plot keep.
pub struct PlanarSweepReport {
    name: String,
    x_key: String,
    y_key: Option<String>,
    xs: Vec<f64>,
    cells: Vec<(f64, Option<f64>, CellClass, f64)>,
    impacts: usize,
    kappa_crit: f64,
    /// Cells that completed every impact upright.
    upright: usize,
}

impl Sweeps for PlanarSystem {
    type Point = SweepCell;
    type Report = PlanarSweepReport;
    const TWO_AXES: bool = true;
    const KEEPS: bool = false;

    fn check_key(key: &str) -> Result<(), SceneError> {
        // the key must exist in the [planar] table (checked again by deserialization)
        let probe = serde_json::to_value(PlanarParams::default()).ok();
        let known = key
            .strip_prefix("planar.")
            .is_some_and(|k| probe.as_ref().is_some_and(|p| p.get(k).is_some()));
        match known {
            true => Ok(()),
            false => Err(SceneError::new(
                key,
                "unknown sweep key (use a [planar] key such as planar.kappa or planar.initial_theta_rad)",
            )),
        }
    }

    fn point(base: &SweepBase<Self>, x: f64, y: Option<f64>) -> Result<SweepCell, Failure> {
        let mut table = base.table_with(&base.grid.x.key, swept_value(&base.grid.x.key, x))?;
        if let (Some(r), Some(y)) = (&base.grid.y, y) {
            crate::scene::apply_set(&mut table, &r.key, swept_value(&r.key, y))?;
        }
        let cfg = config_of(&base.config.name, table)?;
        if let Some(t) = &cfg.real {
            let out = super::closed_loop::run_real(&cfg, t, None, &Setup::default(), &mut |_| {})?;
            let s = out.summary;
            return Ok(SweepCell {
                class: s.class,
                impacts: s.impacts,
                end: s.end,
                max_abs_theta_rad: s.max_abs_theta_rad,
                late_mean_energy_jpkg: s.late_mean_energy_jpkg,
            });
        }
        let p = &cfg.params;
        let mut stats = RunStats::new(&cfg.model, p.impacts);
        let done = cfg
            .model
            .run_streaming(cfg.start, p.impacts, p.seed, &mut |r| stats.push(r));
        let s = summarize(&cfg.name, p, &cfg.model, &stats, &done, 0.0);
        Ok(SweepCell {
            class: s.class,
            impacts: done.impacts,
            end: done.end,
            max_abs_theta_rad: s.max_abs_theta_rad,
            late_mean_energy_jpkg: s.late_mean_energy_jpkg,
        })
    }

    const SHARDS: bool = true;

    fn cost(key: &str, value: f64) -> f64 {
        match key {
            "planar.impacts" => value,
            _ => 1.0,
        }
    }

    /// The one row `KEY[,KEY2],class,impacts,end,max_abs_theta_rad,late_mean_energy_jpkg`.
    fn read_point(_: f64, y: Option<f64>, rows: &[String]) -> Result<SweepCell, String> {
        let [row] = rows else {
            return Err(format!("{} rows for one cell", rows.len()));
        };
        let cells: Vec<&str> = row.split(',').skip(1 + usize::from(y.is_some())).collect();
        let [class, impacts, end, theta, energy] = cells[..] else {
            return Err(format!("`{row}` has not the planar sweep's columns"));
        };
        let num = |s: &str| s.parse::<f64>().map_err(|_| format!("bad number `{s}`"));
        Ok(SweepCell {
            class: *CLASSES
                .iter()
                .find(|c| class_name(**c) == class)
                .ok_or_else(|| format!("unknown class `{class}`"))?,
            impacts: impacts
                .parse()
                .map_err(|_| format!("bad impacts `{impacts}`"))?,
            end: *RUN_ENDS
                .iter()
                .find(|e| end_name(**e) == end)
                .ok_or_else(|| format!("unknown end `{end}`"))?,
            max_abs_theta_rad: num(theta)?,
            late_mean_energy_jpkg: num(energy)?,
        })
    }

    fn report(base: &SweepBase<Self>) -> PlanarSweepReport {
        PlanarSweepReport {
            name: base.file.stem.clone(),
            x_key: base.grid.x.key.clone(),
            y_key: base.grid.y.as_ref().map(|r| r.key.clone()),
            xs: base.grid.x.values(),
            cells: Vec::new(),
            impacts: base.config.params.impacts,
            kappa_crit: kappa_crit_of(&base.config.model),
            upright: 0,
        }
    }
}

impl SweepReport<PlanarSystem> for PlanarSweepReport {
    fn csv_header(&self) -> String {
        let y = self
            .y_key
            .as_ref()
            .map_or(String::new(), |k| format!(",{k}"));
        format!(
            "{}{y},class,impacts,end,max_abs_theta_rad,late_mean_energy_jpkg",
            self.x_key
        )
    }

    fn write_csv(
        &self,
        x: f64,
        y: Option<f64>,
        c: &SweepCell,
        w: &mut dyn std::io::Write,
    ) -> std::io::Result<()> {
        write!(w, "{}", Sig17(x))?;
        if let Some(y) = y {
            write!(w, ",{}", Sig17(y))?;
        }
        let end = end_name(c.end);
        writeln!(
            w,
            ",{},{},{end},{},{}",
            class_name(c.class),
            c.impacts,
            Sig17(c.max_abs_theta_rad),
            Sig17(c.late_mean_energy_jpkg)
        )
    }

    fn add(&mut self, x: f64, y: Option<f64>, c: SweepCell) {
        self.upright += usize::from(c.end == RunEnd::Completed);
        self.cells
            .push((x, y, c.class, y.unwrap_or(c.max_abs_theta_rad)));
    }

    /// The letter grid (rows range2, columns range), printed only with `--csv`.
    fn summary(&self, csv: Option<&Path>) -> Result<String, Failure> {
        if csv.is_none() {
            return Ok(String::new());
        }
        let axes = match &self.y_key {
            Some(k) => format!("rows {k}, columns {}", self.x_key),
            None => format!("columns {}", self.x_key),
        };
        let mut grid = format!(
            "planar sweep of {}: {axes} (C converges, D drifts, T tips over, X diverges)\n",
            self.name
        );
        let _ = write!(grid, "{:>12} |", "");
        for x in &self.xs {
            let _ = write!(grid, " {x:>7.4}");
        }
        grid.push('\n');
        for row in self.cells.chunks(self.xs.len()) {
            match row[0].1 {
                Some(y) => {
                    let _ = write!(grid, "{y:>12.4} |");
                }
                None => {
                    let _ = write!(grid, "{:>12} |", "");
                }
            }
            for c in row {
                let _ = write!(grid, " {:>7}", class_letter(c.2));
            }
            grid.push('\n');
        }
        let _ = writeln!(
            grid,
            "upright for all {} impacts: {} of {} cells",
            self.impacts,
            self.upright,
            self.cells.len()
        );
        Ok(grid)
    }

    fn plot(&self, dir: &Path) -> Result<Vec<PathBuf>, Failure> {
        let y_label = match &self.y_key {
            Some(k) => axis_label(k),
            None => "max |theta| at impacts (rad)".to_string(),
        };
        let title = format!(
            "{}: stability map, {} impacts per cell",
            self.name, self.impacts
        );
        let mut chart = Chart::new(title, axis_label(&self.x_key), y_label);
        for k in CLASSES {
            let mut pts = Decimator::default();
            for c in self.cells.iter().filter(|c| c.2 == k) {
                pts.push((c.0, c.3));
            }
            if !pts.values().is_empty() {
                chart = chart.dots(class_words(k), pts.into_values());
            }
        }
        chart = self.kappa_marks(chart);
        Ok(chart.draw(dir, &format!("{}-stability", self.name))?)
    }
}

impl PlanarSweepReport {
    /// kappa = 1 and kappa_crit (eq. 16) as lines across the other axis, when kappa is
    /// swept.
    fn kappa_marks(&self, mut chart: Chart) -> Chart {
        let finite = |v: &f64| v.is_finite();
        let (ylo, yhi) = self
            .cells
            .iter()
            .map(|c| c.3)
            .filter(finite)
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), v| {
                (a.min(v), b.max(v))
            });
        let xlo = self.xs.iter().copied().fold(f64::INFINITY, f64::min);
        let xhi = self.xs.iter().copied().fold(f64::NEG_INFINITY, f64::max);
        let kc = self.kappa_crit;
        let marks = [
            (1.0, "kappa = 1".to_string()),
            (kc, format!("kappa_crit = {kc:.4} (eq. 16)")),
        ];
        for (k, label) in marks.into_iter().filter(|m| m.0.is_finite()) {
            if self.x_key == "planar.kappa" && ylo.is_finite() {
                chart = chart.line(label, vec![(k, ylo), (k, yhi)]);
            } else if self.y_key.as_deref() == Some("planar.kappa") {
                chart = chart.line(label, vec![(xlo, k), (xhi, k)]);
            }
        }
        chart
    }
}
