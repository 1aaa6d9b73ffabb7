//! Filmstrips: a motion shown as a grid of panels, one per moment, every panel drawn in the
//! same world window with equal units on both axes, so a reader sees bodies move, tilt and
//! land against fixed surroundings (the arm and its object, the fence and the part on the
//! belt, the table and the balanced body).
//!
//! A system builds [`Frame`]s from its own geometry (each a label and a few [`Shape`]s, in
//! metres) and calls [`filmstrip`]; this module owns the layout and the drawing. Written like
//! every plot: `{dir}/{stem}.svg` and `.png`, each whole or not at all.

use std::path::{Path, PathBuf};

use plotters::coord::Shift;
use plotters::prelude::*;

use crate::plot::{render, DrawResult, Figure, PlotError, FONT, TICK_LABEL_SIZE, TITLE_SIZE};

/// Most panels in one filmstrip (a 4 x 4 grid); a system picks which moments to show.
pub const MAX_FRAMES: usize = 16;

/// How a [`Shape`] is drawn.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Ink {
    /// A filled polygon (a body), outlined.
    Body,
    /// A thick line (a surface: table, paddle, arm link, fence).
    Surface,
    /// A thin line (a path, a belt edge, a reference).
    Trace,
    /// One dot per point (contact points, centres of mass).
    Dots,
}

/// One shape in one panel: a polyline or polygon in world coordinates (m).
#[derive(Clone, Debug, PartialEq)]
pub struct Shape {
    /// The vertices, m; a [`Ink::Body`] is closed automatically.
    pub points: Vec<(f64, f64)>,
    /// How it is drawn.
    pub ink: Ink,
    /// Colour index into the plot palette (the same index is the same colour in every panel).
    pub colour: usize,
}

impl Shape {
    /// A shape from its points, ink and colour index.
    pub fn new(points: Vec<(f64, f64)>, ink: Ink, colour: usize) -> Self {
        Self {
            points,
            ink,
            colour,
        }
    }
}

/// One panel: the moment's label (e.g. `t = 0.412 s, impact 3`) and what is drawn in it.
#[derive(Clone, Debug, PartialEq)]
pub struct Frame {
    /// Caption of the panel.
    pub label: String,
    /// The shapes, drawn in order (later on top).
    pub shapes: Vec<Shape>,
}

/// The world window every panel shares, m: the bounding box of every finite point, padded
/// by 5 % of its larger side (and at least 1 mm), so nothing touches a panel's edge.
pub fn world_window(frames: &[Frame]) -> Option<((f64, f64), (f64, f64))> {
    let pts = frames
        .iter()
        .flat_map(|f| f.shapes.iter())
        .flat_map(|s| s.points.iter())
        .filter(|p| p.0.is_finite() && p.1.is_finite());
    let (mut x0, mut x1, mut y0, mut y1) = (f64::MAX, f64::MIN, f64::MAX, f64::MIN);
    let mut any = false;
    for &(x, y) in pts {
        any = true;
        (x0, x1, y0, y1) = (x0.min(x), x1.max(x), y0.min(y), y1.max(y));
    }
    if !any {
        return None;
    }
    let pad = (0.05 * (x1 - x0).max(y1 - y0)).max(1e-3);
    Some(((x0 - pad, x1 + pad), (y0 - pad, y1 + pad)))
}

/// Rows and columns of the grid for `n` panels (at most 4 columns).
pub fn grid(n: usize) -> (usize, usize) {
    let cols = n.clamp(1, 4);
    (n.div_ceil(cols).max(1), cols)
}

/// Draw `frames` (1 to [`MAX_FRAMES`]) as a filmstrip titled `title` into `{dir}/{stem}`.
pub fn filmstrip(
    title: &str,
    frames: &[Frame],
    dir: &Path,
    stem: &str,
) -> Result<Vec<PathBuf>, PlotError> {
    if frames.is_empty() || frames.len() > MAX_FRAMES {
        return Err(PlotError::InvalidArgument {
            what: "filmstrip frames",
            reason: format!("{} frames; 1 to {MAX_FRAMES} are drawn", frames.len()),
        });
    }
    let (x, y) = world_window(frames).ok_or(PlotError::NoFiniteData {
        what: "filmstrip",
        points: 0,
    })?;
    let fig = FilmstripFigure {
        title: title.to_string(),
        frames: frames.to_vec(),
        window: (x, y),
    };
    render(&fig, dir, stem)
}

struct FilmstripFigure {
    title: String,
    frames: Vec<Frame>,
    window: ((f64, f64), (f64, f64)),
}

impl Figure for FilmstripFigure {
    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> DrawResult<DB> {
        root.fill(&WHITE)?;
        let body = root.titled(&self.title, (FONT, TITLE_SIZE))?;
        let (rows, cols) = grid(self.frames.len());
        for (panel, frame) in body.split_evenly((rows, cols)).iter().zip(&self.frames) {
            self.panel(panel, frame)?;
        }
        Ok(())
    }
}

impl FilmstripFigure {
    /// One panel: the shared window stretched to the panel's aspect, so one metre is as long
    /// across as it is up.
    fn panel<DB: DrawingBackend>(
        &self,
        area: &DrawingArea<DB, Shift>,
        frame: &Frame,
    ) -> DrawResult<DB> {
        let (w, h) = area.dim_in_pixel();
        let ((x0, x1), (y0, y1)) = equal_units(self.window, (f64::from(w), f64::from(h)));
        let mut chart = ChartBuilder::on(area)
            .caption(&frame.label, (FONT, TICK_LABEL_SIZE))
            .margin(4)
            .build_cartesian_2d(x0..x1, y0..y1)?;
        chart
            .configure_mesh()
            .disable_mesh()
            .x_labels(0)
            .y_labels(0)
            .draw()?;
        for shape in &frame.shapes {
            draw_shape(&mut chart, shape)?;
        }
        Ok(())
    }
}

type Ctx<'a, DB> = ChartContext<
    'a,
    DB,
    Cartesian2d<plotters::coord::types::RangedCoordf64, plotters::coord::types::RangedCoordf64>,
>;

fn draw_shape<DB: DrawingBackend>(chart: &mut Ctx<'_, DB>, shape: &Shape) -> DrawResult<DB> {
    let colour = Palette99::pick(shape.colour).to_rgba();
    let pts: Vec<(f64, f64)> = shape
        .points
        .iter()
        .copied()
        .filter(|p| p.0.is_finite() && p.1.is_finite())
        .collect();
    if pts.is_empty() {
        return Ok(());
    }
    match shape.ink {
        Ink::Body => {
            chart.draw_series(std::iter::once(Polygon::new(
                pts.clone(),
                colour.mix(0.35).filled(),
            )))?;
            let mut outline = pts;
            outline.push(outline[0]);
            chart.draw_series(std::iter::once(PathElement::new(
                outline,
                colour.stroke_width(2),
            )))?;
        }
        Ink::Surface => {
            chart.draw_series(std::iter::once(PathElement::new(
                pts,
                colour.stroke_width(4),
            )))?;
        }
        Ink::Trace => {
            chart.draw_series(std::iter::once(PathElement::new(
                pts,
                colour.stroke_width(1),
            )))?;
        }
        Ink::Dots => {
            chart.draw_series(pts.into_iter().map(|p| Circle::new(p, 3, colour.filled())))?;
        }
    }
    Ok(())
}

/// Widen the window along one axis so that it has the panel's aspect ratio (equal units).
pub fn equal_units(
    ((x0, x1), (y0, y1)): ((f64, f64), (f64, f64)),
    (w_px, h_px): (f64, f64),
) -> ((f64, f64), (f64, f64)) {
    let (wx, wy) = (x1 - x0, y1 - y0);
    if w_px <= 0.0 || h_px <= 0.0 || wx <= 0.0 || wy <= 0.0 {
        return ((x0, x1), (y0, y1));
    }
    let aspect = w_px / h_px;
    if wx / wy < aspect {
        let grow = 0.5 * (wy * aspect - wx);
        ((x0 - grow, x1 + grow), (y0, y1))
    } else {
        let grow = 0.5 * (wx / aspect - wy);
        ((x0, x1), (y0 - grow, y1 + grow))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn square(cx: f64) -> Shape {
        Shape::new(
            vec![(cx, 0.0), (cx + 1.0, 0.0), (cx + 1.0, 1.0), (cx, 1.0)],
            Ink::Body,
            0,
        )
    }

    #[test]
    fn the_window_holds_every_frame_with_a_margin() {
        let frames = vec![
            Frame {
                label: "a".into(),
                shapes: vec![square(0.0)],
            },
            Frame {
                label: "b".into(),
                shapes: vec![square(3.0), Shape::new(vec![(f64::NAN, 9.0)], Ink::Dots, 1)],
            },
        ];
        let ((x0, x1), (y0, y1)) = world_window(&frames).unwrap();
        // box [0, 4] x [0, 1], padded by 5 % of 4 = 0.2; the NaN point is ignored
        assert!((x0 + 0.2).abs() < 1e-12 && (x1 - 4.2).abs() < 1e-12);
        assert!((y0 + 0.2).abs() < 1e-12 && (y1 - 1.2).abs() < 1e-12);
        assert_eq!(world_window(&[]), None);
    }

    #[test]
    fn equal_units_keep_the_window_and_match_the_panel_aspect() {
        let ((x0, x1), (y0, y1)) = equal_units(((0.0, 4.0), (0.0, 1.0)), (200.0, 100.0));
        // 4:1 window in a 2:1 panel: y widens to span 2, centred
        assert_eq!((x0, x1), (0.0, 4.0));
        assert!((y0 + 0.5).abs() < 1e-12 && (y1 - 1.5).abs() < 1e-12);
        let ((x0, x1), _) = equal_units(((0.0, 1.0), (0.0, 1.0)), (300.0, 100.0));
        assert!((x0 + 1.0).abs() < 1e-12 && (x1 - 2.0).abs() < 1e-12);
    }

    #[test]
    fn the_grid_has_at_most_four_columns() {
        assert_eq!(grid(1), (1, 1));
        assert_eq!(grid(4), (1, 4));
        assert_eq!(grid(5), (2, 4));
        assert_eq!(grid(16), (4, 4));
    }

    #[test]
    fn a_filmstrip_is_written_and_bad_input_is_an_error() {
        let dir = std::env::temp_dir().join(format!("dexter-film-{}", std::process::id()));
        let frames: Vec<Frame> = (0..6)
            .map(|i| Frame {
                label: format!("frame {i}"),
                shapes: vec![
                    Shape::new(vec![(-1.0, 0.0), (6.0, 0.0)], Ink::Surface, 1),
                    square(f64::from(i)),
                ],
            })
            .collect();
        let files = filmstrip("test", &frames, &dir, "film").unwrap();
        assert_eq!(files.len(), 2);
        let svg = std::fs::read_to_string(&files[0]).unwrap();
        assert_eq!(svg.matches("frame ").count(), 6, "one caption per panel");
        assert!(filmstrip("test", &[], &dir, "none").is_err());
        let too_many = vec![frames[0].clone(); MAX_FRAMES + 1];
        assert!(filmstrip("test", &too_many, &dir, "none").is_err());
        let _ = std::fs::remove_dir_all(&dir);
    }
}
