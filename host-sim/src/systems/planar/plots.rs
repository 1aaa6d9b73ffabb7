//! The planar run's `--plot` pictures (SVG + PNG, stem = the scene file's stem):
//! `-theta` (θ–θ̇ at impacts, rigid bodies), `-velocity` (ẋ–ẏ at impacts with the fixed
//! point), `-path` (the centre of mass over the first flights) and `-energy` (η per impact
//! with η* and the late mean), and on the real table `-filmstrip` ([`super::film`]). Series over all impacts keep at most
//! [`crate::stream::PLOT_MAX_POINTS`] points.

use super::trace::PlanarRow;
use super::{PlanarConfig, PlanarOutcome, PlanarSystem};
use crate::model::planar::{analysis, Body, ImpactRecord};
use crate::plot::Chart;
use crate::stream::Decimator;
use crate::system::Failure;
use crate::system::Plots;
use std::path::{Path, PathBuf};

/// Points per flight in the path plot.
const PATH_SAMPLES: usize = 24;
/// Flights drawn in the path plot (more is an unreadable tangle).
const PATH_FLIGHTS: usize = 12;

/// What the planar plots keep of a run.
pub struct PlanarPlots {
    first: Vec<ImpactRecord>,
    theta: Decimator<(f64, f64)>,
    velocity: Decimator<(f64, f64)>,
    energy: Decimator<(f64, f64)>,
    impacts: usize,
}

impl Plots<PlanarSystem> for PlanarPlots {
    fn new(_: &PlanarConfig) -> Self {
        Self {
            first: Vec::new(),
            theta: Decimator::default(),
            velocity: Decimator::default(),
            energy: Decimator::default(),
            impacts: 0,
        }
    }

    fn push(&mut self, row: &PlanarRow) {
        let r = &row.record;
        if self.first.len() <= PATH_FLIGHTS {
            self.first.push(*r);
        }
        self.theta
            .push((r.before.theta_rad, r.before.theta_dot_radps));
        self.velocity.push((r.before.x_dot_mps, r.before.y_dot_mps));
        self.energy.push((r.index as f64, r.energy_jpkg));
        self.impacts += 1;
    }

    fn write(
        self,
        cfg: &PlanarConfig,
        out: &PlanarOutcome,
        dir: &Path,
    ) -> Result<Vec<PathBuf>, Failure> {
        if self.first.is_empty() {
            return Err(Failure::run("plot: the run has no impacts"));
        }
        let m = &cfg.model;
        let name = &cfg.name;
        let sub = |title: &str| {
            format!(
                "{name}: {title} (kappa {}, e {}, {} impacts)",
                m.tilt.kappa(),
                m.feedback.e(),
                self.impacts
            )
        };
        let mut written = Vec::new();
        if let Some(film) = &out.film {
            let title = format!("{name}: body and table, first and last impacts");
            let files = film
                .write(&title, m.l_m(), dir, name)
                .map_err(|e| Failure::run(format!("plot: {e}")))?;
            written.extend(files);
        }
        // fig. 4-5, upper: the orbit in the theta - theta' plane at the impacts
        if !matches!(m.body, Body::PointMass) {
            let pts = self.theta.values().to_vec();
            let first = vec![pts[0]];
            let chart = Chart::new(
                sub("theta-theta' at impacts"),
                "theta just before impact (rad)",
                "theta' just before impact (rad/s)",
            );
            let chart = chart.dots("impacts", pts).dots("first impact", first);
            written.extend(chart.draw(dir, &format!("{name}-theta"))?);
        }
        written.extend(self.velocity_plot(cfg, &sub("x'-y' at impacts"), dir)?);
        written.extend(self.path_plot(cfg, dir)?);
        written.extend(self.energy_plot(cfg, out, &sub("energy per impact"), dir)?);
        Ok(written)
    }
}

impl PlanarPlots {
    /// Fig. 4-5, lower: the orbit in the x' - y' plane at the impacts (the paper's "xy"
    /// projection: "y is bounded in the neighborhood of y0, the y-velocity at first
    /// impact"), with the fixed point (0, y*).
    fn velocity_plot(
        &self,
        cfg: &PlanarConfig,
        title: &str,
        dir: &Path,
    ) -> Result<Vec<PathBuf>, Failure> {
        let vel = self.velocity.values().to_vec();
        let first = vec![vel[0]];
        let y_star = analysis::fixed_point_velocity_mps(&cfg.model).unwrap_or(f64::NAN);
        let mut chart = Chart::new(
            title,
            "x' just before impact (m/s)",
            "y' just before impact (m/s)",
        )
        .dots("impacts", vel)
        .dots("first impact", first);
        if y_star.is_finite() {
            chart = chart.dots("fixed point (0, y*)", vec![(0.0, y_star)]);
        }
        Ok(chart.draw(dir, &format!("{}-velocity", cfg.name))?)
    }

    /// The centre of mass's path in the x - y plane over the first flights.
    fn path_plot(&self, cfg: &PlanarConfig, dir: &Path) -> Result<Vec<PathBuf>, Failure> {
        let g = cfg.model.gravity_mps2;
        let mut path = Vec::new();
        for w in self.first.windows(2).take(PATH_FLIGHTS) {
            let dt = w[1].time_s - w[0].time_s;
            for i in 0..=PATH_SAMPLES {
                let s = w[0].after.flown(dt * i as f64 / PATH_SAMPLES as f64, g);
                path.push((s.x_m, s.y_m));
            }
        }
        let impacts_xy = self
            .first
            .iter()
            .map(|r| (r.before.x_m, r.before.y_m))
            .collect();
        let flights = PATH_FLIGHTS.min(self.impacts.saturating_sub(1));
        let title = format!("{}: centre-of-mass path, first {flights} flights", cfg.name);
        let mut chart = Chart::new(title, "x (m)", "y (m)");
        if !path.is_empty() {
            chart = chart.line("centre of mass in flight", path);
        }
        let chart = chart.dots("impacts", impacts_xy);
        Ok(chart.draw(dir, &format!("{}-path", cfg.name))?)
    }

    /// Energy per impact with eta* and the late mean.
    fn energy_plot(
        &self,
        cfg: &PlanarConfig,
        out: &PlanarOutcome,
        title: &str,
        dir: &Path,
    ) -> Result<Vec<PathBuf>, Failure> {
        let s = &out.summary;
        let eta_star = cfg.model.feedback.target_energy_jpkg();
        let last = (self.impacts.saturating_sub(1) as f64).max(1.0);
        let late_from = (self.impacts - s.late_window_impacts) as f64;
        let late_mean = s.late_mean_energy_jpkg;
        let chart = Chart::new(
            title,
            "impact n",
            "eta = G l cos(theta) + y'^2/2 before impact (J/kg)",
        )
        .line("eta", self.energy.values().to_vec())
        .line("eta* (target)", vec![(0.0, eta_star), (last, eta_star)])
        .line(
            format!("late mean eta (last {} impacts)", s.late_window_impacts),
            vec![(late_from, late_mean), (last, late_mean)],
        );
        Ok(chart.draw(dir, &format!("{}-energy", cfg.name))?)
    }
}
