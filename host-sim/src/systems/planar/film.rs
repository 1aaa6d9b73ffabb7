//! The real table's `--plot` filmstrip (`{stem}-filmstrip`): the body and the table at the
//! apex of a flight and at the impact that ends it, for the first impacts and the last ones,
//! so a reader sees the balance, not only its numbers. Kept in bounded memory while the run
//! streams ([`FilmKeeper`], a [`TableSink`]).
//!
//! Every panel is drawn in the body's horizontal frame (x relative to the centre of mass:
//! the law lets the body wander metres sideways), so all panels share one window. The body
//! is drawn as the sec. 2.3 triangle scaled to its contact distance l (apex at the contact
//! point, base 1.5 l from it, 0.75 l wide); the table as a 0.4 m line through its pivot
//! (apex panels) or through the contact point (impact panels) at its angle.

use crate::filmstrip::{filmstrip, Frame, Ink, Shape, MAX_FRAMES};
use crate::model::planar::real_table::TableSink;
use crate::model::planar::table_run::{StepSample, TableImpact};
use std::collections::VecDeque;
use std::path::{Path, PathBuf};

/// Impacts shown at the start and at the end (two panels each: apex, impact).
const SHOWN: usize = MAX_FRAMES / 4;
/// Most control steps kept of the first flights.
const MAX_FIRST_STEPS: usize = 16_384;
/// Control steps kept of the last flights (4 flights of the sec. 2.3 triangle at 1 kHz).
const TAIL_STEPS: usize = 4_096;
/// Half the drawn length of the table, m.
const TABLE_HALF_M: f64 = 0.2;

/// What the filmstrip keeps of a streamed run.
#[derive(Clone, Debug, Default)]
pub struct FilmKeeper {
    first_impacts: Vec<TableImpact>,
    first_steps: Vec<StepSample>,
    last_impacts: VecDeque<TableImpact>,
    last_steps: VecDeque<StepSample>,
}

impl TableSink for FilmKeeper {
    fn impact(&mut self, r: &TableImpact) {
        if self.first_impacts.len() < SHOWN {
            self.first_impacts.push(*r);
        }
        if self.last_impacts.len() == SHOWN {
            self.last_impacts.pop_front();
        }
        self.last_impacts.push_back(*r);
    }

    fn step(&mut self, s: &StepSample) {
        if self.first_impacts.len() < SHOWN && self.first_steps.len() < MAX_FIRST_STEPS {
            self.first_steps.push(*s);
        }
        if self.last_steps.len() == TAIL_STEPS {
            self.last_steps.pop_front();
        }
        self.last_steps.push_back(*s);
    }
}

/// The body (triangle), its centre of mass and the table line for a pose (x m, y m, theta
/// rad) drawn at horizontal offset 0, with the table line through (`tx`, `ty`) at `alpha`.
fn shapes(pose: [f64; 3], l_m: f64, (tx, ty): (f64, f64), alpha: f64) -> Vec<Shape> {
    let (_, y, th) = (pose[0], pose[1], pose[2]);
    // the contact point is l below the centre of mass along the body's axis
    let down = (th.sin(), -th.cos());
    let apex = (l_m * down.0, y + l_m * down.1);
    let base = (-0.5 * l_m * down.0, y - 0.5 * l_m * down.1);
    let w = 0.375 * l_m;
    let side = (-down.1 * w, down.0 * w);
    let body = vec![
        apex,
        (base.0 + side.0, base.1 + side.1),
        (base.0 - side.0, base.1 - side.1),
    ];
    let (c, s) = (alpha.cos(), alpha.sin());
    let table = vec![
        (tx - TABLE_HALF_M * c, ty - TABLE_HALF_M * s),
        (tx + TABLE_HALF_M * c, ty + TABLE_HALF_M * s),
    ];
    vec![
        Shape::new(table, Ink::Surface, 1),
        Shape::new(body, Ink::Body, 0),
        Shape::new(vec![(0.0, y)], Ink::Dots, 2),
    ]
}

/// The panel at the highest point of the flight that ends at `r` (from `steps`).
fn apex_frame(steps: &[&StepSample], r: &TableImpact, after_s: f64, l_m: f64) -> Option<Frame> {
    let s = steps
        .iter()
        .filter(|s| s.time_s > after_s && s.time_s < r.time_s)
        .max_by(|a, b| a.body[1].total_cmp(&b.body[1]))?;
    Some(Frame {
        label: match r.index {
            0 => format!("drop, t {:.3} s", s.time_s),
            _ => format!("apex, t {:.3} s", s.time_s),
        },
        shapes: shapes(s.body, l_m, (0.0, s.table_height_m), s.table_angle_rad),
    })
}

/// The panel at impact `r`.
fn impact_frame(r: &TableImpact, l_m: f64) -> Frame {
    let b = &r.before;
    let pose = [b.x_m, b.y_m, b.theta_rad];
    let contact = b.contact_point(l_m);
    Frame {
        label: format!("impact {}, t {:.3} s", r.index, r.time_s),
        shapes: shapes(
            pose,
            l_m,
            (contact[0] - b.x_m, contact[1]),
            r.table_angle_rad,
        ),
    }
}

/// Apex and impact panels for `impacts` (the flight before each from `steps`; a flight
/// whose start is not in `steps` gets only its impact panel).
fn frames_of<'a>(
    impacts: impl Iterator<Item = &'a TableImpact>,
    steps: &[&StepSample],
    l_m: f64,
) -> Vec<Frame> {
    let first_step = steps.first().map_or(f64::INFINITY, |s| s.time_s);
    let mut prev: Option<f64> = None;
    let mut out = Vec::new();
    for r in impacts {
        let after = prev.unwrap_or(0.0);
        if prev.is_some() || first_step <= 0.0 {
            if let Some(f) = apex_frame(steps, r, after, l_m) {
                out.push(f);
            }
        }
        out.push(impact_frame(r, l_m));
        prev = Some(r.time_s);
    }
    out
}

impl FilmKeeper {
    /// The panels: the first `SHOWN` impacts, then the last ones not among them.
    pub fn frames(&self, l_m: f64) -> Vec<Frame> {
        let first: Vec<&StepSample> = self.first_steps.iter().collect();
        let mut out = frames_of(self.first_impacts.iter(), &first, l_m);
        let shown = self.first_impacts.last().map_or(0, |r| r.index + 1);
        let late: Vec<&StepSample> = self.last_steps.iter().collect();
        let lasts = self.last_impacts.iter().skip_while(|r| r.index < shown);
        out.extend(frames_of(lasts, &late, l_m));
        out.truncate(MAX_FRAMES);
        out
    }

    /// Draw the filmstrip `{dir}/{stem}-filmstrip` (SVG and PNG).
    pub fn write(
        &self,
        title: &str,
        l_m: f64,
        dir: &Path,
        stem: &str,
    ) -> Result<Vec<PathBuf>, String> {
        let frames = self.frames(l_m);
        filmstrip(title, &frames, dir, &format!("{stem}-filmstrip")).map_err(|e| e.to_string())
    }
}
