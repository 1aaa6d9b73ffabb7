//! The line juggler's `--plot` pictures: apex per impact (with the target), the return map
//! of impact speeds, and the phase portrait; each keeps at most
//! [`crate::stream::PLOT_MAX_POINTS`] points however long the run.

use super::scene::Scene;
use super::trace::ImpactRow;
use super::{LineOutcome, LineSystem};
use crate::plot;
use crate::stream::Decimator;
use crate::system::Failure;
use crate::system::Plots;
use std::path::{Path, PathBuf};

/// Flights of a run without a controller drawn in its phase portrait.
pub const PHASE_FLIGHTS: usize = 4000;
/// Points per flight in that portrait.
const PER_FLIGHT: usize = 24;

/// What the line plots keep of a run.
pub struct LinePlots {
    apexes: Decimator<ImpactRow>,
    speeds: Decimator<(f64, f64)>,
    previous_speed: Option<f64>,
    first_rows: Vec<ImpactRow>,
    target_m: f64,
    stem: String,
}

impl Plots<LineSystem> for LinePlots {
    fn new(cfg: &Scene) -> Self {
        Self {
            apexes: Decimator::default(),
            speeds: Decimator::default(),
            previous_speed: None,
            first_rows: Vec::new(),
            target_m: cfg.control.target_apex_m.unwrap_or(f64::NAN),
            stem: cfg.name().to_string(),
        }
    }

    fn push(&mut self, row: &ImpactRow) {
        self.apexes.push(*row);
        let speed = -row.ball_velocity_before_mps;
        if let Some(p) = self.previous_speed.replace(speed) {
            self.speeds.push((p, speed));
        }
        if self.first_rows.len() <= PHASE_FLIGHTS {
            self.first_rows.push(*row);
        }
    }

    fn write(self, _: &Scene, outcome: &LineOutcome, dir: &Path) -> Result<Vec<PathBuf>, Failure> {
        let stem = &self.stem;
        let mut written = Vec::new();
        if !self.apexes.values().is_empty() {
            let apex_stem = format!("{stem}-apex");
            written.extend(plot::apex_per_impact(
                self.apexes.values(),
                self.target_m,
                dir,
                &apex_stem,
            )?);
            if !self.speeds.values().is_empty() {
                let map_stem = format!("{stem}-return-map");
                written.extend(plot::return_map_points(
                    self.speeds.into_values(),
                    dir,
                    &map_stem,
                )?);
            }
        }
        let phase = match outcome.phase.is_empty() {
            true => phase_from_rows(&self.first_rows, outcome.gravity_mps2),
            false => outcome.phase.clone(),
        };
        if !phase.is_empty() {
            written.extend(plot::phase_portrait(&phase, dir, &format!("{stem}-phase"))?);
        }
        Ok(written)
    }
}

/// (b, b') along the ballistic flights between the first recorded impacts (for runs
/// without a controller, whose plant is not sampled per step).
fn phase_from_rows(rows: &[ImpactRow], g: f64) -> Vec<(f64, f64)> {
    let mut pts = Vec::new();
    for w in rows.windows(2).take(PHASE_FLIGHTS) {
        let (a, b) = (&w[0], &w[1]);
        let dt = b.time_s - a.time_s;
        for i in 0..=PER_FLIGHT {
            let t = dt * i as f64 / PER_FLIGHT as f64;
            pts.push((
                a.ball_height_m + a.ball_velocity_after_mps * t - 0.5 * g * t * t,
                a.ball_velocity_after_mps - g * t,
            ));
        }
    }
    pts
}
