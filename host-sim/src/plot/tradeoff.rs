//! What accuracy costs, as a picture: one knob's settings as labelled points, error against
//! cost (BENCHMARKS.md, "What accuracy costs, at a glance"; `scripts/accuracy-figures.sh`
//! measures the data, `examples/tradeoff_figure.rs` draws it).
//!
//! # The CSV
//!
//! One header line, exactly [`HEADER`], then one point per line, six comma-separated fields
//! (no quoting: a field holds no comma):
//!
//! | field | meaning |
//! | --- | --- |
//! | `series` | the group the point belongs to (one colour and legend entry each) |
//! | `label` | the setting, written beside the point |
//! | `cost` | what the setting costs, > 0 |
//! | `cost_unit` | the cost's unit and how it was measured: the x axis's title, the same on every line |
//! | `error` | the error the setting leaves, >= 0 |
//! | `error_unit` | the error's unit and against what: the y axis's title, the same on every line |
//!
//! Blank lines are skipped. Anything else that does not fit is an error naming its line
//! ([`CsvError`]); nothing is dropped or guessed.
//!
//! # The figure
//!
//! An axis is logarithmic when its positive values span at least a decade
//! ([`LOG_AXIS_SPAN`]), linear otherwise. On a logarithmic error axis an error of exactly 0
//! (an exact method) cannot be placed: such a point is drawn as a triangle on the axis floor
//! and its label ends in " (error 0)", and a note under the plot says so. A dashed line in a
//! series' colour joins its best trades, the points no other point of the series beats on
//! both cost and error ([`best_trades`]).

use std::fmt;
use std::path::Path;

use plotters::coord::ranged1d::{DefaultFormatting, KeyPointHint, Ranged};
use plotters::coord::types::RangedCoordf64;
use plotters::coord::Shift;
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};

use super::{ensure_fonts, fmt_num, span, PlotError, FONT, PLOT_SIZE, TITLE_SIZE};

/// The header line every trade-off CSV starts with.
pub const HEADER: &str = "series,label,cost,cost_unit,error,error_unit";

/// An axis whose largest positive value is at least this many times its smallest is drawn
/// logarithmic.
pub const LOG_AXIS_SPAN: f64 = 10.0;

const FIELDS: usize = 6;
const LABEL_SIZE: u32 = 16;
const AXIS_SIZE: u32 = 20;
const TICK_SIZE: u32 = 16;
const NOTE_SIZE: u32 = 15;
const MARKER_RADIUS: i32 = 5;

/// One measured setting of a knob.
#[derive(Clone, Debug, PartialEq)]
pub struct Point {
    /// The group it belongs to (colour, legend).
    pub series: String,
    /// The setting, written beside the point.
    pub label: String,
    /// What it costs (> 0, in [`Tradeoff::cost_unit`]).
    pub cost: f64,
    /// The error it leaves (>= 0, in [`Tradeoff::error_unit`]).
    pub error: f64,
}

/// One knob's measured points, as read from its CSV ([`parse_csv`]).
#[derive(Clone, Debug, PartialEq)]
pub struct Tradeoff {
    /// The cost's unit and measurement: the x axis's title.
    pub cost_unit: String,
    /// The error's unit and reference: the y axis's title.
    pub error_unit: String,
    /// The points, in file order (at least one).
    pub points: Vec<Point>,
}

/// Why a trade-off CSV could not be read. Every variant but [`CsvError::Header`] and
/// [`CsvError::NoPoints`] names the 1-based line it is about.
#[derive(Clone, Debug, PartialEq)]
pub enum CsvError {
    /// The first line is not [`HEADER`] (`None`: the file is empty).
    Header {
        /// The first line as found.
        found: Option<String>,
    },
    /// A line has another number of fields than six.
    Fields {
        /// The line number.
        line: usize,
        /// How many comma-separated fields it has.
        found: usize,
    },
    /// A field that must not be empty is.
    Empty {
        /// The line number.
        line: usize,
        /// The column's name.
        column: &'static str,
    },
    /// A number field is not a finite number, or out of its range.
    Number {
        /// The line number.
        line: usize,
        /// The column's name.
        column: &'static str,
        /// The field as written.
        text: String,
        /// What it must be.
        expected: &'static str,
    },
    /// A unit differs from the first point's: one figure has one unit per axis.
    Unit {
        /// The line number.
        line: usize,
        /// The column's name.
        column: &'static str,
        /// The unit of the first point.
        expected: String,
        /// The unit on this line.
        found: String,
    },
    /// The file has a header but no point.
    NoPoints,
}

impl fmt::Display for CsvError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            CsvError::Header { found: None } => {
                write!(
                    f,
                    "line 1: the file is empty, expected the header {HEADER:?}"
                )
            }
            CsvError::Header { found: Some(h) } => {
                write!(f, "line 1: expected the header {HEADER:?}, found {h:?}")
            }
            CsvError::Fields { line, found } => write!(
                f,
                "line {line}: expected {FIELDS} comma-separated fields ({HEADER}), found {found}"
            ),
            CsvError::Empty { line, column } => write!(f, "line {line}: {column} is empty"),
            CsvError::Number {
                line,
                column,
                text,
                expected,
            } => write!(f, "line {line}: {column} {text:?} is not {expected}"),
            CsvError::Unit {
                line,
                column,
                expected,
                found,
            } => write!(
                f,
                "line {line}: {column} {found:?} differs from the first point's {expected:?} \
                 (one figure, one unit per axis)"
            ),
            CsvError::NoPoints => write!(f, "no point after the header"),
        }
    }
}

impl std::error::Error for CsvError {}

/// Reads a trade-off CSV (module docs): the header, then at least one point.
pub fn parse_csv(text: &str) -> Result<Tradeoff, CsvError> {
    let mut lines = text.lines().enumerate().map(|(i, l)| (i + 1, l));
    match lines.next() {
        Some((_, h)) if h.trim_end() == HEADER => {}
        first => {
            return Err(CsvError::Header {
                found: first.map(|(_, h)| h.to_string()),
            })
        }
    }
    let mut fig: Option<Tradeoff> = None;
    for (line, text) in lines.filter(|(_, l)| !l.trim().is_empty()) {
        let row = parse_row(line, text)?;
        match &mut fig {
            None => {
                fig = Some(Tradeoff {
                    cost_unit: row.cost_unit,
                    error_unit: row.error_unit,
                    points: vec![row.point],
                })
            }
            Some(f) => {
                same_unit(line, "cost_unit", &f.cost_unit, row.cost_unit)?;
                same_unit(line, "error_unit", &f.error_unit, row.error_unit)?;
                f.points.push(row.point);
            }
        }
    }
    fig.ok_or(CsvError::NoPoints)
}

/// One line of the CSV, its units not yet checked against the first line's.
struct Row {
    point: Point,
    cost_unit: String,
    error_unit: String,
}

fn parse_row(line: usize, text: &str) -> Result<Row, CsvError> {
    let fields: Vec<&str> = text.trim_end().split(',').map(str::trim).collect();
    if fields.len() != FIELDS {
        return Err(CsvError::Fields {
            line,
            found: fields.len(),
        });
    }
    let names = [
        "series",
        "label",
        "cost",
        "cost_unit",
        "error",
        "error_unit",
    ];
    if let Some(i) = fields.iter().position(|f| f.is_empty()) {
        return Err(CsvError::Empty {
            line,
            column: names[i],
        });
    }
    let cost = number(line, "cost", fields[2], |v| v > 0.0, "a finite number > 0")?;
    let error = number(
        line,
        "error",
        fields[4],
        |v| v >= 0.0,
        "a finite number >= 0",
    )?;
    Ok(Row {
        point: Point {
            series: fields[0].to_string(),
            label: fields[1].to_string(),
            cost,
            error,
        },
        cost_unit: fields[3].to_string(),
        error_unit: fields[5].to_string(),
    })
}

fn number(
    line: usize,
    column: &'static str,
    text: &str,
    ok: impl Fn(f64) -> bool,
    expected: &'static str,
) -> Result<f64, CsvError> {
    match text.parse::<f64>() {
        Ok(v) if v.is_finite() && ok(v) => Ok(v),
        _ => Err(CsvError::Number {
            line,
            column,
            text: text.to_string(),
            expected,
        }),
    }
}

fn same_unit(
    line: usize,
    column: &'static str,
    expected: &str,
    found: String,
) -> Result<(), CsvError> {
    if found == expected {
        Ok(())
    } else {
        Err(CsvError::Unit {
            line,
            column,
            expected: expected.to_string(),
            found,
        })
    }
}

// ---------------------------------------------------------------------------------------------
// Axes

/// How one axis is drawn: its range and whether it is logarithmic.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Axis {
    /// A linear axis over (low, high).
    Linear(f64, f64),
    /// A logarithmic axis over (low, high), both > 0; a value of 0 is drawn just above `low`.
    Log(f64, f64),
}

impl Axis {
    /// The axis for these values (each >= 0): logarithmic when the positive ones span at
    /// least [`LOG_AXIS_SPAN`], padded so no point sits on the frame.
    pub fn for_values(values: &[f64]) -> Result<Axis, PlotError> {
        let positive = values.iter().copied().filter(|v| *v > 0.0);
        let lo = positive.clone().fold(f64::INFINITY, f64::min);
        let hi = positive.fold(0.0, f64::max);
        if hi > 0.0 && hi / lo >= LOG_AXIS_SPAN {
            let pad = (0.08 * (hi / lo).log10()).max(0.15);
            let floor = if values.contains(&0.0) {
                pad + 0.3
            } else {
                pad
            };
            return Ok(Axis::Log(lo / 10f64.powf(floor), hi * 10f64.powf(pad)));
        }
        let (a, b) = span(values.iter().copied(), "axis")?;
        Ok(Axis::Linear(a, b))
    }

    /// The same axis, its top raised by `fraction` of its span (room for the legend).
    pub fn with_headroom(self, fraction: f64) -> Axis {
        match self {
            Axis::Linear(a, b) => Axis::Linear(a, b + fraction * (b - a)),
            Axis::Log(a, b) => Axis::Log(a, b * (b / a).powf(fraction)),
        }
    }

    /// Where `v` is drawn: `v` itself, or the floor for 0 on a logarithmic axis.
    fn place(&self, v: f64) -> f64 {
        match *self {
            Axis::Log(lo, _) if v <= 0.0 => lo * 10f64.powf(0.12),
            _ => v,
        }
    }

    fn is_log(&self) -> bool {
        matches!(self, Axis::Log(..))
    }

    /// Ticks of a logarithmic axis: the densest of 10^k, {1, 2, 5} x 10^k and
    /// {1, ..., 9} x 10^k within (lo, hi) that has at most `max` ticks (the sparsest if none
    /// has).
    fn log_ticks(lo: f64, hi: f64, max: usize) -> Vec<f64> {
        let ladders: [&[f64]; 3] = [
            &[1.0],
            &[1.0, 2.0, 5.0],
            &[1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0, 8.0, 9.0],
        ];
        let mut chosen = Vec::new();
        for ladder in ladders {
            let ticks = Self::ladder_ticks(lo, hi, ladder);
            if chosen.is_empty() || ticks.len() <= max {
                chosen = ticks;
            }
        }
        chosen
    }

    fn ladder_ticks(lo: f64, hi: f64, ladder: &[f64]) -> Vec<f64> {
        let first = lo.log10().floor() as i32;
        let last = hi.log10().ceil() as i32;
        (first..=last)
            .flat_map(|k| ladder.iter().map(move |m| m * 10f64.powi(k)))
            .filter(|v| (lo..=hi).contains(v))
            .collect()
    }
}

/// The axis as plotters' coordinate: linear as [`RangedCoordf64`], logarithmic mapped by
/// log10 with ticks at 1, 2, 5 (or 1 to 9) times powers of ten, whole decades included.
impl Ranged for Axis {
    type FormatOption = DefaultFormatting;
    type ValueType = f64;

    fn map(&self, value: &f64, limit: (i32, i32)) -> i32 {
        match *self {
            Axis::Linear(a, b) => RangedCoordf64::from(a..b).map(value, limit),
            Axis::Log(a, b) => {
                RangedCoordf64::from(a.log10()..b.log10()).map(&value.log10(), limit)
            }
        }
    }

    fn key_points<Hint: KeyPointHint>(&self, hint: Hint) -> Vec<f64> {
        match *self {
            Axis::Linear(a, b) => RangedCoordf64::from(a..b).key_points(hint),
            Axis::Log(a, b) => Self::log_ticks(a, b, hint.max_num_points()),
        }
    }

    fn range(&self) -> std::ops::Range<f64> {
        match *self {
            Axis::Linear(a, b) | Axis::Log(a, b) => a..b,
        }
    }
}

// ---------------------------------------------------------------------------------------------
// Drawing

/// The points that no other of `points` beats on both cost and error (the best trades),
/// cheapest first.
pub fn best_trades(points: &[Point]) -> Vec<&Point> {
    let mut sorted: Vec<&Point> = points.iter().collect();
    sorted.sort_by(|a, b| a.cost.total_cmp(&b.cost).then(a.error.total_cmp(&b.error)));
    let mut best = Vec::new();
    let mut lowest = f64::INFINITY;
    for p in sorted {
        if p.error < lowest {
            lowest = p.error;
            best.push(p);
        }
    }
    best
}

/// The figure of `fig` as an SVG document ([`crate::plot::PLOT_SIZE`], module docs).
pub fn svg(fig: &Tradeoff, title: &str) -> Result<String, PlotError> {
    ensure_fonts().map_err(|m| backend(&m))?;
    let x = Axis::for_values(&fig.points.iter().map(|p| p.cost).collect::<Vec<_>>())?;
    let y = Axis::for_values(&fig.points.iter().map(|p| p.error).collect::<Vec<_>>())?
        .with_headroom(HEADROOM);
    let mut out = String::new();
    {
        let root = SVGBackend::with_string(&mut out, PLOT_SIZE).into_drawing_area();
        let drawn = draw(&root, fig, title, x, y);
        drawn.map_err(|e| backend(&e))?;
        root.present().map_err(|e| backend(&e))?;
    }
    Ok(out)
}

/// Reads the CSV at `csv`, draws it and writes the SVG to `out` (whole or not at all).
/// The error names the file, and for a CSV error its line.
pub fn csv_to_svg(csv: &Path, out: &Path, title: &str) -> Result<(), String> {
    let text = std::fs::read_to_string(csv).map_err(|e| format!("{}: {e}", csv.display()))?;
    let fig = parse_csv(&text).map_err(|e| format!("{}: {e}", csv.display()))?;
    let doc = svg(&fig, title).map_err(|e| format!("{}: {e}", out.display()))?;
    crate::output::write_atomic(out, doc.as_bytes()).map_err(|e| format!("{e}"))
}

fn backend(message: &dyn fmt::Display) -> PlotError {
    PlotError::Backend {
        path: "<trade-off SVG, in memory>".into(),
        message: message.to_string(),
    }
}

type Area<DB> = DrawingArea<DB, Shift>;
type Drawn<DB> = Result<(), DrawingAreaErrorKind<<DB as DrawingBackend>::ErrorType>>;

type Chart<'a, DB> = ChartContext<'a, DB, Cartesian2d<Axis, Axis>>;

fn draw<DB: DrawingBackend>(
    root: &Area<DB>,
    fig: &Tradeoff,
    title: &str,
    x: Axis,
    y: Axis,
) -> Drawn<DB> {
    let mut chart = chart_with_mesh(root, fig, title, x, y)?;
    let zero_floor = y.is_log() && fig.points.iter().any(|p| p.error == 0.0);
    let at = |p: &Point| (x.place(p.cost), y.place(p.error));
    let marks: Vec<(i32, i32)> = fig
        .points
        .iter()
        .map(|p| chart.backend_coord(&at(p)))
        .collect();
    let plot = chart.plotting_area().get_pixel_range();
    let entries = legend_entries(fig);
    let legend = legend_box(root, &entries, &marks, &plot)?;
    for (i, name) in series_names(fig).iter().enumerate() {
        let series = &members(fig, name);
        draw_series(root, &mut chart, (x, y), series, (name, i), zero_floor)?;
    }
    if entries.len() > series_names(fig).len() {
        let dash = BLACK.mix(0.45).stroke_width(2);
        chart
            .draw_series(std::iter::empty::<Circle<(f64, f64), i32>>())?
            .label(DASHED_LEGEND)
            .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 24, y)], dash));
    }
    label_points(root, fig, &marks, zero_floor, legend, &plot)?;
    chart
        .configure_series_labels()
        .position(SeriesLabelPosition::Coordinate(
            legend.0 - plot.0.start,
            legend.1 - plot.1.start,
        ))
        .margin(LEGEND_MARGIN)
        .legend_area_size(LEGEND_KEY)
        .label_font((FONT, LABEL_SIZE + 1))
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK.mix(0.5))
        .draw()?;
    if zero_floor {
        let (_, h) = root.dim_in_pixel();
        let style = (FONT, NOTE_SIZE).into_font().color(&BLACK.mix(0.7));
        root.draw(&Text::new(ZERO_NOTE, (24, h as i32 - 24), style))?;
    }
    Ok(())
}

/// The chart on a white background: title, axes with their units, grid.
fn chart_with_mesh<'a, DB: DrawingBackend>(
    root: &'a Area<DB>,
    fig: &Tradeoff,
    title: &str,
    x: Axis,
    y: Axis,
) -> Result<Chart<'a, DB>, DrawingAreaErrorKind<DB::ErrorType>> {
    root.fill(&WHITE)?;
    let mut chart = ChartBuilder::on(root)
        .caption(title, (FONT, TITLE_SIZE))
        .margin(24)
        .margin_bottom(40)
        .x_label_area_size(64)
        .y_label_area_size(100)
        .build_cartesian_2d(x, y)?;
    chart
        .configure_mesh()
        .x_desc(fig.cost_unit.as_str())
        .y_desc(fig.error_unit.as_str())
        .axis_desc_style((FONT, AXIS_SIZE))
        .label_style((FONT, TICK_SIZE))
        .x_label_formatter(&|v| fmt_num(*v))
        .y_label_formatter(&|v| fmt_num(*v))
        .light_line_style(BLACK.mix(0.05))
        .bold_line_style(BLACK.mix(0.15))
        .draw()?;
    Ok(chart)
}

/// One series in the palette's `index`-th colour: the dashed line through its best trades,
/// a dot per point (a triangle on the floor for an error of 0 on a log axis), its legend
/// entry.
fn draw_series<DB: DrawingBackend>(
    root: &Area<DB>,
    chart: &mut Chart<'_, DB>,
    axes: (Axis, Axis),
    members: &[Point],
    (name, index): (&str, usize),
    zero_floor: bool,
) -> Drawn<DB> {
    let (x, y) = axes;
    let at = |p: &Point| (x.place(p.cost), y.place(p.error));
    let colour = Palette99::pick(index).to_rgba();
    let best: Vec<(f64, f64)> = best_trades(members).into_iter().map(at).collect();
    if best.len() > 1 {
        let style = colour.mix(0.6).stroke_width(2);
        chart.draw_series(DashedLineSeries::new(best, 8, 6, style))?;
    }
    let fill = colour.filled();
    let on_floor = |p: &&Point| zero_floor && p.error == 0.0;
    let dots = members
        .iter()
        .filter(|p| !on_floor(p))
        .map(|p| Circle::new(at(p), MARKER_RADIUS, fill));
    chart
        .draw_series(dots)?
        .label(name)
        .legend(move |(x, y)| Circle::new((x + 12, y), MARKER_RADIUS, fill));
    for p in members.iter().filter(on_floor) {
        let (px, py) = chart.backend_coord(&at(p));
        let corners = vec![(px - 7, py - 9), (px + 7, py - 9), (px, py + 3)];
        root.draw(&Polygon::new(corners, fill))?;
    }
    Ok(())
}

/// The points of one series, in file order.
fn members(fig: &Tradeoff, series: &str) -> Vec<Point> {
    fig.points
        .iter()
        .filter(|p| p.series == series)
        .cloned()
        .collect()
}

const DASHED_LEGEND: &str = "dashed: best trades in a series";
/// The share of the error axis kept free above the highest point, for the legend.
const HEADROOM: f64 = 0.2;
const ZERO_NOTE: &str = "triangle on the floor: error exactly 0 (no place on a log axis)";
const LEGEND_MARGIN: i32 = 10;
const LEGEND_KEY: i32 = 30;

/// The legend's lines: each series, then the dashed line's meaning if a series has one.
fn legend_entries(fig: &Tradeoff) -> Vec<String> {
    let names = series_names(fig);
    let dashed = names
        .iter()
        .any(|n| best_trades(&members(fig, n)).len() > 1);
    let mut entries = names;
    if dashed {
        entries.push(DASHED_LEGEND.to_string());
    }
    entries
}

/// Where the legend goes: the first corner of the plot (upper right, upper left, lower
/// right, lower left) whose box covers no point, else the one covering fewest.
fn legend_box<DB: DrawingBackend>(
    root: &Area<DB>,
    entries: &[String],
    marks: &[(i32, i32)],
    (xs, ys): &(std::ops::Range<i32>, std::ops::Range<i32>),
) -> Result<Box2, DrawingAreaErrorKind<DB::ErrorType>> {
    let style = TextStyle::from((FONT, LABEL_SIZE + 1).into_font());
    let mut w = 0;
    let mut h = 0;
    for e in entries {
        let (ew, eh) = root.estimate_text_size(e, &style)?;
        w = w.max(ew as i32);
        h += (eh as i32).max(((LABEL_SIZE + 1) as f64 * 1.25) as i32);
    }
    let (w, h) = (w + LEGEND_KEY + 2 * LEGEND_MARGIN, h + 2 * LEGEND_MARGIN);
    let (l, r, t, b) = (xs.start + 5, xs.end - 5 - w, ys.start + 5, ys.end - 5 - h);
    let corners = [(r, t), (l, t), (r, b), (l, b)];
    let covered = |&(x, y): &(i32, i32)| {
        let bx = (x, y, x + w, y + h);
        marks
            .iter()
            .filter(|&&(mx, my)| overlaps(bx, (mx - 12, my - 12, mx + 12, my + 12)))
            .count()
    };
    let best = corners
        .iter()
        .min_by_key(|c| covered(c))
        .copied()
        .unwrap_or((r, t));
    Ok((best.0, best.1, best.0 + w, best.1 + h))
}

/// The series in order of first appearance.
fn series_names(fig: &Tradeoff) -> Vec<String> {
    let mut names: Vec<String> = Vec::new();
    for p in &fig.points {
        if !names.contains(&p.series) {
            names.push(p.series.clone());
        }
    }
    names
}

/// A label's box in pixels: left, top, right, bottom.
type Box2 = (i32, i32, i32, i32);

fn overlaps(a: Box2, b: Box2) -> bool {
    a.0 < b.2 && b.0 < a.2 && a.1 < b.3 && b.1 < a.3
}

/// Writes each point's label beside it: the first of a few places (right, then left, then
/// further above or below) that stays inside the plot and clear of the labels and markers
/// placed so far; failing all, the first place.
fn label_points<DB: DrawingBackend>(
    root: &Area<DB>,
    fig: &Tradeoff,
    marks: &[(i32, i32)],
    zero_floor: bool,
    legend: Box2,
    (xs, ys): &(std::ops::Range<i32>, std::ops::Range<i32>),
) -> Drawn<DB> {
    let style = TextStyle::from((FONT, LABEL_SIZE).into_font());
    let r = MARKER_RADIUS + 1;
    let mut taken: Vec<Box2> = marks
        .iter()
        .map(|&(x, y)| (x - r, y - r, x + r, y + r))
        .chain([legend])
        .collect();
    for (p, &(x, y)) in fig.points.iter().zip(marks) {
        let text = if zero_floor && p.error == 0.0 {
            format!("{} (error 0)", p.label)
        } else {
            p.label.clone()
        };
        let (w, h) = root.estimate_text_size(&text, &style)?;
        let (w, h) = (w as i32, h as i32);
        let fits = |b: Box2| b.0 >= xs.start && b.2 <= xs.end && b.1 >= ys.start && b.3 <= ys.end;
        let candidates = label_candidates(x, y, w, h);
        let chosen = candidates
            .iter()
            .copied()
            .find(|&b| fits(b) && !taken.iter().any(|&t| overlaps(b, t)))
            .unwrap_or(candidates[0]);
        taken.push(chosen);
        let anchored = style.pos(Pos::new(HPos::Left, VPos::Top));
        root.draw(&Text::new(text, (chosen.0, chosen.1), anchored))?;
    }
    Ok(())
}

/// Boxes a label of `w` x `h` pixels may take around the point at (x, y), best first.
fn label_candidates(x: i32, y: i32, w: i32, h: i32) -> Vec<Box2> {
    let gap = MARKER_RADIUS + 4;
    let mut out = Vec::new();
    for k in [0, -1, 1, -2, 2, -3, 3] {
        let top = y - h / 2 + k * (h + 2);
        out.push((x + gap, top, x + gap + w, top + h));
        out.push((x - gap - w, top, x - gap, top + h));
    }
    out
}
