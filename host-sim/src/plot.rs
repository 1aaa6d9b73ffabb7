//! Plots (plotters, SVG and PNG).
//!
//! Every plot function writes two files, `{dir}/{stem}.svg` and `{dir}/{stem}.png`, each
//! [`PLOT_SIZE`] pixels, creating `dir` if it is missing, and returns both paths (SVG first).
//!
//! The functions never panic on their input: non-finite points (NaN, ±inf) are skipped, input
//! that is empty or has no finite point gives a [`PlotError`], and a degenerate range (all
//! points equal) is widened so the axes still have a span.
//!
//! # Fonts
//!
//! plotters' bitmap backend needs a real font to draw text. Instead of the `ttf` feature
//! (which needs the system's fontconfig and freetype), plotters is built with its `ab_glyph`
//! feature and DejaVu Sans, embedded from the `dejavu` crate, is registered for the
//! `sans-serif`, `serif` and `monospace` families the first time a plot is drawn. So the PNGs
//! get readable text on a machine with no font packages at all. DejaVu fonts are under the
//! Bitstream Vera licence (DejaVu changes are in the public domain), which allows embedding
//! and redistribution.

use std::fmt;
use std::path::{Path, PathBuf};
use std::sync::OnceLock;

use plotters::coord::types::RangedCoordf64;
use plotters::coord::Shift;
use plotters::prelude::*;
use plotters::style::{register_font, FontStyle};

pub mod tradeoff;

/// Width and height, in pixels, of every plot (the PNG's size and the SVG's view box).
pub const PLOT_SIZE: (u32, u32) = (1024, 768);

pub(crate) const FONT: &str = "sans-serif";
pub(crate) const TITLE_SIZE: u32 = 30;
const AXIS_DESC_SIZE: u32 = 22;
pub(crate) const TICK_LABEL_SIZE: u32 = 17;
pub(crate) const LEGEND_SIZE: u32 = 18;

/// What went wrong while making a plot.
#[derive(Debug)]
pub enum PlotError {
    /// The input had nothing to plot (no points, or too few for this kind of plot).
    EmptyInput {
        /// Which plot's input, and what was missing.
        what: &'static str,
    },
    /// The input had points, but none of them was finite (all NaN or infinite).
    NoFiniteData {
        /// Which plot's input.
        what: &'static str,
        /// How many points the input had.
        points: usize,
    },
    /// An argument could not be used (an empty file stem, a range too wide to draw, ...).
    InvalidArgument {
        /// Which argument.
        what: &'static str,
        /// Why it could not be used.
        reason: String,
    },
    /// Creating the directory or writing a file failed.
    Io {
        /// The directory or file concerned.
        path: PathBuf,
        /// The underlying error.
        source: std::io::Error,
    },
    /// The plotting backend (or its font) reported an error while drawing or saving.
    Backend {
        /// The file being drawn.
        path: PathBuf,
        /// The backend's message.
        message: String,
    },
}

impl fmt::Display for PlotError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            PlotError::EmptyInput { what } => write!(f, "nothing to plot: {what}"),
            PlotError::NoFiniteData { what, points } => write!(
                f,
                "nothing to plot: {what}: none of the {points} points is finite (all NaN or infinite)"
            ),
            PlotError::InvalidArgument { what, reason } => {
                write!(f, "cannot plot: invalid {what}: {reason}")
            }
            PlotError::Io { path, source } => {
                write!(f, "plot I/O error on {}: {source}", path.display())
            }
            PlotError::Backend { path, message } => {
                write!(f, "plotting backend error for {}: {message}", path.display())
            }
        }
    }
}

impl std::error::Error for PlotError {
    fn source(&self) -> Option<&(dyn std::error::Error + 'static)> {
        match self {
            PlotError::Io { source, .. } => Some(source),
            _ => None,
        }
    }
}

/// How one series of a [`series`] plot is drawn.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Style {
    /// A line through the points in order (broken at non-finite points).
    Line,
    /// A dot at each point.
    Dots,
}

/// One named series of a [`series`] plot.
#[derive(Clone, Debug, PartialEq)]
pub struct Series {
    /// Legend label (empty: no legend entry).
    pub label: String,
    /// The points, (x, y) in the axes' units.
    pub points: Vec<(f64, f64)>,
    /// Line or dots.
    pub style: Style,
}

/// A general x–y plot of several named series (lines or dots), each in its own colour, with a
/// title and axis labels (put the units in the labels). Used for the planar and hopper
/// pictures: phase portraits, projections, return maps against their closed forms, stability
/// maps (one dotted series per class). Non-finite points are skipped.
pub fn series(
    title: &str,
    x_label: &str,
    y_label: &str,
    series: &[Series],
    dir: &Path,
    stem: &str,
) -> Result<Vec<PathBuf>, PlotError> {
    const WHAT: &str = "series";
    let total: usize = series.iter().map(|s| s.points.len()).sum();
    if total == 0 {
        return Err(PlotError::EmptyInput { what: WHAT });
    }
    let finite = || {
        series
            .iter()
            .flat_map(|s| s.points.iter())
            .filter(|p| p.0.is_finite() && p.1.is_finite())
    };
    if finite().next().is_none() {
        return Err(PlotError::NoFiniteData {
            what: WHAT,
            points: total,
        });
    }
    let x_range = span(finite().map(|p| p.0), "x range")?;
    let y_range = span(finite().map(|p| p.1), "y range")?;
    let fig = SeriesFigure {
        title: title.to_string(),
        x_label: x_label.to_string(),
        y_label: y_label.to_string(),
        series: series.to_vec(),
        x_range,
        y_range,
    };
    render(&fig, dir, stem)
}

/// A [`series`] plot being put together: a title, axis labels (with units) and named
/// series, each in the palette's next colour.
#[derive(Clone, Debug, PartialEq)]
pub struct Chart {
    title: String,
    x_label: String,
    y_label: String,
    series: Vec<Series>,
}

impl Chart {
    /// An empty chart.
    pub fn new(
        title: impl Into<String>,
        x_label: impl Into<String>,
        y_label: impl Into<String>,
    ) -> Self {
        Self {
            title: title.into(),
            x_label: x_label.into(),
            y_label: y_label.into(),
            series: Vec::new(),
        }
    }

    /// Add a series drawn as a dot per point.
    pub fn dots(self, label: impl Into<String>, points: Vec<(f64, f64)>) -> Self {
        self.with(label, points, Style::Dots)
    }

    /// Add a series drawn as a line through its points.
    pub fn line(self, label: impl Into<String>, points: Vec<(f64, f64)>) -> Self {
        self.with(label, points, Style::Line)
    }

    fn with(mut self, label: impl Into<String>, points: Vec<(f64, f64)>, style: Style) -> Self {
        self.push(label, points, style);
        self
    }

    /// Add a series.
    pub fn push(&mut self, label: impl Into<String>, points: Vec<(f64, f64)>, style: Style) {
        self.series.push(Series {
            label: label.into(),
            points,
            style,
        });
    }

    /// Add a line series as series number `slot` (its colour is the palette's `slot`-th),
    /// after empty unlabelled ones if fewer are there.
    pub fn line_at(
        mut self,
        slot: usize,
        label: impl Into<String>,
        points: Vec<(f64, f64)>,
    ) -> Self {
        while self.series.len() < slot {
            self.push("", Vec::new(), Style::Line);
        }
        self.line(label, points)
    }

    /// The series so far.
    pub fn series(&self) -> &[Series] {
        &self.series
    }

    /// Draw it into `{dir}/{stem}.svg` and `.png` ([`series`]).
    pub fn draw(&self, dir: &Path, stem: &str) -> Result<Vec<PathBuf>, PlotError> {
        series(
            &self.title,
            &self.x_label,
            &self.y_label,
            &self.series,
            dir,
            stem,
        )
    }
}

/// An axis label for a scene key: the key with the unit its suffix names (`_mps2`: m/s^2,
/// `_rad`: rad, ...).
pub fn key_label(key: &str) -> String {
    const UNITS: [(&str, &str); 12] = [
        ("_s2pm2", "s^2/m^2"),
        ("_mps2", "m/s^2"),
        ("_radps", "rad/s"),
        ("_rad", "rad"),
        ("_mps", "m/s"),
        ("_hz", "Hz"),
        ("_per_s2", "1/s^2"),
        ("_per_s", "1/s"),
        ("_per_m", "1/m"),
        ("_jpkg", "J/kg"),
        ("_m", "m"),
        ("_s", "s"),
    ];
    match UNITS.iter().find(|(suffix, _)| key.ends_with(suffix)) {
        Some((_, unit)) => format!("{key} ({unit})"),
        None => key.to_string(),
    }
}

// ---------------------------------------------------------------------------------------------
// Figures

pub(crate) type DrawResult<DB> =
    Result<(), DrawingAreaErrorKind<<DB as DrawingBackend>::ErrorType>>;

/// Something that can draw itself on any plotters backend (SVG and bitmap).
pub(crate) trait Figure {
    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> DrawResult<DB>;
}

struct SeriesFigure {
    title: String,
    x_label: String,
    y_label: String,
    series: Vec<Series>,
    x_range: (f64, f64),
    y_range: (f64, f64),
}

impl Figure for SeriesFigure {
    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> DrawResult<DB> {
        let mut chart = chart(root, &self.title, self.x_range, self.y_range)?;
        mesh(&mut chart, &self.x_label, &self.y_label)?;
        let mut labelled = false;
        for (i, s) in self.series.iter().enumerate() {
            let colour = Palette99::pick(i).to_rgba();
            match s.style {
                Style::Line => {
                    let style = colour.stroke_width(2);
                    let mut first = true;
                    for run in finite_segments(s.points.iter().copied()) {
                        let drawn = chart.draw_series(LineSeries::new(run, style))?;
                        if first && !s.label.is_empty() {
                            drawn.label(s.label.clone()).legend(move |(x, y)| {
                                PathElement::new(vec![(x, y), (x + 24, y)], style)
                            });
                            labelled = true;
                        }
                        first = false;
                    }
                }
                Style::Dots => {
                    let radius = if s.points.len() > 2000 { 1 } else { 3 };
                    let fill = colour.filled();
                    let drawn = chart.draw_series(
                        s.points
                            .iter()
                            .filter(|p| p.0.is_finite() && p.1.is_finite())
                            .map(|&p| Circle::new(p, radius, fill)),
                    )?;
                    if !s.label.is_empty() {
                        drawn
                            .label(s.label.clone())
                            .legend(move |(x, y)| Circle::new((x + 12, y), 4, fill));
                        labelled = true;
                    }
                }
            }
        }
        if labelled {
            legend(&mut chart, SeriesLabelPosition::UpperRight)?;
        }
        Ok(())
    }
}

// ---------------------------------------------------------------------------------------------
// Shared drawing helpers

pub(crate) type Ctx<'a, DB> = ChartContext<'a, DB, Cartesian2d<RangedCoordf64, RangedCoordf64>>;

pub(crate) fn chart<'a, DB: DrawingBackend>(
    root: &'a DrawingArea<DB, Shift>,
    title: &str,
    (x0, x1): (f64, f64),
    (y0, y1): (f64, f64),
) -> Result<Ctx<'a, DB>, DrawingAreaErrorKind<DB::ErrorType>> {
    root.fill(&WHITE)?;
    ChartBuilder::on(root)
        .caption(title, (FONT, TITLE_SIZE))
        .margin(24)
        .x_label_area_size(70)
        .y_label_area_size(100)
        .build_cartesian_2d(x0..x1, y0..y1)
}

pub(crate) fn mesh<DB: DrawingBackend>(
    chart: &mut Ctx<'_, DB>,
    x_desc: &str,
    y_desc: &str,
) -> DrawResult<DB> {
    chart
        .configure_mesh()
        .x_desc(x_desc)
        .y_desc(y_desc)
        .axis_desc_style((FONT, AXIS_DESC_SIZE))
        .label_style((FONT, TICK_LABEL_SIZE))
        .x_label_formatter(&|v| fmt_num(*v))
        .y_label_formatter(&|v| fmt_num(*v))
        .light_line_style(BLACK.mix(0.05))
        .bold_line_style(BLACK.mix(0.15))
        .draw()
}

pub(crate) fn legend<'a, DB: DrawingBackend + 'a>(
    chart: &mut Ctx<'a, DB>,
    position: SeriesLabelPosition,
) -> DrawResult<DB> {
    chart
        .configure_series_labels()
        .position(position)
        .label_font((FONT, LEGEND_SIZE))
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK.mix(0.5))
        .draw()
}

/// Splits points into runs of finite points; a non-finite point ends a run and is dropped.
pub(crate) fn finite_segments(
    points: impl IntoIterator<Item = (f64, f64)>,
) -> Vec<Vec<(f64, f64)>> {
    let mut segments = Vec::new();
    let mut current = Vec::new();
    for (x, y) in points {
        if x.is_finite() && y.is_finite() {
            current.push((x, y));
        } else if !current.is_empty() {
            segments.push(std::mem::take(&mut current));
        }
    }
    if !current.is_empty() {
        segments.push(current);
    }
    segments
}

/// A short, readable number: up to 4 significant digits, no trailing zeros, scientific
/// notation for very large or very small magnitudes.
pub(crate) fn fmt_num(v: f64) -> String {
    if v == 0.0 || !v.is_finite() {
        return if v == 0.0 { "0".into() } else { format!("{v}") };
    }
    let mag = v.abs();
    if !(1e-3..1e5).contains(&mag) {
        let s = format!("{v:.3e}");
        return match s.split_once('e') {
            Some((mantissa, exp)) if mantissa.contains('.') => {
                let mantissa = mantissa.trim_end_matches('0').trim_end_matches('.');
                format!("{mantissa}e{exp}")
            }
            _ => s,
        };
    }
    let decimals = (3 - mag.log10().floor() as i32).clamp(0, 6) as usize;
    let s = format!("{v:.decimals$}");
    let s = if s.contains('.') {
        s.trim_end_matches('0').trim_end_matches('.').to_string()
    } else {
        s
    };
    if s == "-0" {
        "0".into()
    } else {
        s
    }
}

/// The (min, max) of finite values, padded by 5 % of the span; a zero span is widened by 10 %
/// of the magnitude (or by 1 around zero) so the axis keeps a width.
pub(crate) fn span(
    values: impl IntoIterator<Item = f64>,
    what: &'static str,
) -> Result<(f64, f64), PlotError> {
    let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
    for v in values.into_iter().filter(|v| v.is_finite()) {
        lo = lo.min(v);
        hi = hi.max(v);
    }
    if lo > hi {
        return Err(PlotError::InvalidArgument {
            what,
            reason: "no finite value".into(),
        });
    }
    let width = hi - lo;
    let scale = lo.abs().max(hi.abs());
    let (lo, hi) = if width <= scale * 1e-9 {
        let pad = if scale > 0.0 { scale * 0.1 } else { 1.0 };
        (lo - pad, hi + pad)
    } else {
        (lo - width * 0.05, hi + width * 0.05)
    };
    if !(lo.is_finite() && hi.is_finite() && (hi - lo).is_finite()) {
        return Err(PlotError::InvalidArgument {
            what,
            reason: format!("values span too wide a range to draw ({lo:e} to {hi:e})"),
        });
    }
    Ok((lo, hi))
}

// ---------------------------------------------------------------------------------------------
// Output

/// Registers the embedded DejaVu Sans for the font families plotters asks for (once per
/// process). Both backends need it: the bitmap backend to draw glyphs, the SVG backend to
/// measure text for the layout.
pub(crate) fn ensure_fonts() -> Result<(), String> {
    static REGISTERED: OnceLock<Result<(), String>> = OnceLock::new();
    REGISTERED
        .get_or_init(|| {
            let regular = dejavu::sans::regular();
            let bold = dejavu::sans::bold();
            let fonts: [(&str, FontStyle, &'static [u8]); 4] = [
                ("sans-serif", FontStyle::Normal, regular),
                ("sans-serif", FontStyle::Bold, bold),
                ("serif", FontStyle::Normal, regular),
                ("monospace", FontStyle::Normal, regular),
            ];
            for (family, style, bytes) in fonts {
                register_font(family, style, bytes).map_err(|_| {
                    format!("the embedded DejaVu Sans font could not be loaded for {family}")
                })?;
            }
            Ok(())
        })
        .clone()
}

fn backend_error(path: &Path, message: impl fmt::Display) -> PlotError {
    PlotError::Backend {
        path: path.to_path_buf(),
        message: message.to_string(),
    }
}

/// Encodes a `w` x `h` 8-bit RGB buffer as PNG into `out`, with the settings
/// `image::codecs::png::PngEncoder::new` used (fast compression, adaptive filtering
/// starting from Sub), so the files are byte for byte the ones written before `image` was
/// dropped.
fn write_png(
    out: impl std::io::Write,
    rgb: &[u8],
    w: u32,
    h: u32,
) -> Result<(), png::EncodingError> {
    let mut encoder = png::Encoder::new(out, w, h);
    encoder.set_color(png::ColorType::Rgb);
    encoder.set_depth(png::BitDepth::Eight);
    encoder.set_compression(png::Compression::Fast);
    encoder.set_filter(png::FilterType::Sub);
    encoder.set_adaptive_filter(png::AdaptiveFilterType::Adaptive);
    encoder.write_header()?.write_image_data(rgb)
}

/// Draws `fig` into `{dir}/{stem}.svg` and `{dir}/{stem}.png`, each written whole or not at
/// all ([`crate::output::AtomicFile`]).
pub(crate) fn render(fig: &impl Figure, dir: &Path, stem: &str) -> Result<Vec<PathBuf>, PlotError> {
    if stem.is_empty() || stem.contains(['/', '\\']) || stem == "." || stem == ".." {
        return Err(PlotError::InvalidArgument {
            what: "file stem",
            reason: format!("{stem:?} must be a non-empty file name without a directory"),
        });
    }
    let svg_path = dir.join(format!("{stem}.svg"));
    let png_path = dir.join(format!("{stem}.png"));
    ensure_fonts().map_err(|m| backend_error(&png_path, m))?;
    std::fs::create_dir_all(dir).map_err(|source| PlotError::Io {
        path: dir.to_path_buf(),
        source,
    })?;
    let io = |e: crate::output::OutputError| PlotError::Io {
        path: e.path,
        source: e.source,
    };
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, PLOT_SIZE).into_drawing_area();
        fig.draw(&root).map_err(|e| backend_error(&svg_path, e))?;
        root.present().map_err(|e| backend_error(&svg_path, e))?;
    }
    let (w, h) = PLOT_SIZE;
    let mut rgb = vec![0u8; w as usize * h as usize * 3];
    {
        let root = BitMapBackend::with_buffer(&mut rgb, PLOT_SIZE).into_drawing_area();
        fig.draw(&root).map_err(|e| backend_error(&png_path, e))?;
        root.present().map_err(|e| backend_error(&png_path, e))?;
    }
    crate::output::write_atomic(&svg_path, svg.as_bytes()).map_err(io)?;
    let mut png = crate::output::AtomicFile::create(&png_path).map_err(io)?;
    write_png(png.writer(), &rgb, w, h).map_err(|e| backend_error(&png_path, e))?;
    png.commit().map_err(io)?;
    Ok(vec![svg_path, png_path])
}
