//! The spatial juggler's `--plot` pictures (SVG + PNG, stem = the scene file's stem):
//! `-apex-plane` (the apex after each bat in the horizontal plane, with the set point),
//! `-apex-height` (apex height per bat with h* and eq. 8's fixed point) and `-strikes-side`,
//! `-strikes-top` (a two-view filmstrip of the first [`STRIKES`] flights: the ball's path
//! and the bar at each impact, in the vertical plane of the bar (horizontal distance from
//! the base against height) and from above). Each series keeps at most
//! [`crate::stream::PLOT_MAX_POINTS`] points.

use super::summary::SpatialOutcome;
use super::trace::SpatialRow;
use super::{SpatialConfig, SpatialJugglerSystem};
use crate::model::spatial::SpatialBat;
use crate::plot::Chart;
use crate::stream::Decimator;
use crate::system::{Failure, Plots};
use std::path::{Path, PathBuf};

/// Flights drawn in the filmstrip.
pub const STRIKES: usize = 4;
/// Points per drawn flight.
const FLIGHT_POINTS: usize = 60;
/// The drawn bar's length, in units of the ball's distance from the base at the impact.
const BAR_LENGTH: f64 = 1.3;

/// What the spatial juggler's plots keep of a run.
#[derive(Default)]
pub struct SpatialPlots {
    plane: Decimator<(f64, f64)>,
    height: Decimator<(f64, f64)>,
    first: Vec<SpatialBat>,
}

impl Plots<SpatialJugglerSystem> for SpatialPlots {
    fn new(_: &SpatialConfig) -> Self {
        Self::default()
    }

    fn push(&mut self, row: &SpatialRow) {
        let b = &row.0;
        self.plane.push((b.apex_m[0], b.apex_m[1]));
        self.height.push((b.index as f64, b.apex_m[2]));
        if self.first.len() <= STRIKES {
            self.first.push(*b);
        }
    }

    fn write(
        self,
        cfg: &SpatialConfig,
        out: &SpatialOutcome,
        dir: &Path,
    ) -> Result<Vec<PathBuf>, Failure> {
        let plane = self.plane.values().to_vec();
        let Some(&first) = plane.first() else {
            return Err(Failure::run("plot: the run has no bats"));
        };
        let s = &out.summary;
        let [tx, ty, th] = s.target_m;
        let name = &cfg.name;
        let law = format!("{} law", cfg.table.law.name());
        let mut written = Vec::new();
        let chart = Chart::new(
            format!("{name}: apex after each bat, from above ({law})"),
            "b_x (m)",
            "b_y (m)",
        )
        .dots("apex after bat n", plane)
        .dots("first apex", vec![first])
        .dots("set point (rho* cos phi*, rho* sin phi*)", vec![(tx, ty)]);
        written.extend(chart.draw(dir, &format!("{name}-apex-plane"))?);
        let last = (s.impacts.saturating_sub(1) as f64).max(1.0);
        let mut chart = Chart::new(
            format!("{name}: apex height after each bat ({law})"),
            "bat n",
            "b_z at the apex (m)",
        )
        .line("apex height", self.height.values().to_vec())
        .line("h*", vec![(0.0, th), (last, th)]);
        if let Some(h) = s.closed_form.fixed_point_apex_m {
            chart = chart.line("eq. 8 fixed point", vec![(0.0, h), (last, h)]);
        }
        written.extend(chart.draw(dir, &format!("{name}-apex-height"))?);
        let g = cfg.params.law.gravity_mps2;
        for (side, stem, x, y) in [
            (
                true,
                "strikes-side",
                "distance from the base's axis (m)",
                "b_z (m)",
            ),
            (false, "strikes-top", "b_x (m)", "b_y (m)"),
        ] {
            let title = format!("{name}: the first flights and the bar at each impact ({law})");
            let chart = filmstrip(Chart::new(title, x, y), &self.first, g, side);
            written.extend(chart.draw(dir, &format!("{name}-{stem}"))?);
        }
        Ok(written)
    }
}

/// The ball's position `t` after the impact `b`.
fn flown(b: &SpatialBat, t: f64, g: f64) -> [f64; 3] {
    let (p, v) = (&b.before, &b.after);
    [
        p[0] + v[3] * t,
        p[1] + v[4] * t,
        p[2] + v[5] * t - 0.5 * g * t * t,
    ]
}

/// A point in the side view (distance from the base's axis, height) or the top view.
fn view(p: [f64; 3], side: bool) -> (f64, f64) {
    if side {
        (p[0].hypot(p[1]), p[2])
    } else {
        (p[0], p[1])
    }
}

/// Each flight between the first bats, and the bar at each of those impacts.
fn filmstrip(mut chart: Chart, bats: &[SpatialBat], g: f64, side: bool) -> Chart {
    for (i, pair) in bats.windows(2).enumerate() {
        let dt = pair[1].time_s - pair[0].time_s;
        let path = (0..FLIGHT_POINTS)
            .map(|k| dt * k as f64 / (FLIGHT_POINTS - 1) as f64)
            .map(|t| view(flown(&pair[0], t, g), side))
            .collect();
        chart = chart.line(format!("flight {}", i + 1), path);
    }
    for b in bats.iter().take(STRIKES) {
        let [q1, q2, _] = b.joints_rad;
        let e = q2 + core::f64::consts::FRAC_PI_2;
        let [x, y, z] = [b.before[0], b.before[1], b.before[2]];
        let length = BAR_LENGTH * (x * x + y * y + z * z).sqrt();
        let tip = [
            length * e.cos() * q1.cos(),
            length * e.cos() * q1.sin(),
            length * e.sin(),
        ];
        let bar = vec![view([0.0; 3], side), view(tip, side)];
        chart = chart.line(format!("bar at impact {}", b.index + 1), bar);
    }
    chart
}
