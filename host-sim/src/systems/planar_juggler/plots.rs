//! The planar juggler's `--plot` pictures (SVG + PNG, stem = the scene file's stem):
//! `-apex` (the apex after each bat in the plane, with the target), `-energy` (eta per bat
//! with eta* and the fixed point of eq. 8) and `-energy-map` (eta_{n+1} against eta_n with
//! eq. 8's map on the line b_x = b_x*, and the identity). Each series keeps at most
//! [`crate::stream::PLOT_MAX_POINTS`] points.

use super::summary::JugglerOutcome;
use super::trace::BatRow;
use super::{JugglerConfig, PlanarJugglerSystem};
use crate::model::planar::juggler::JugglerParams;
use crate::plot::Chart;
use crate::stream::Decimator;
use crate::system::Failure;
use crate::system::Plots;
use std::path::{Path, PathBuf};

/// Points drawn of eq. 8's map.
const CURVE_POINTS: usize = 400;

/// What the planar juggler's plots keep of a run.
#[derive(Default)]
pub struct JugglerPlots {
    apexes: Decimator<(f64, f64)>,
    energy: Decimator<(f64, f64)>,
    pairs: Decimator<(f64, f64)>,
    last_energy: Option<f64>,
}

/// Eq. 8 in energies: the energy after a bat from an impact with energy `eta` on the line
/// b_x = b_x* (impact at b_z = 0, so eta = v^2/2).
fn eq8_energy(p: &JugglerParams, eta: f64) -> f64 {
    let a = p.restitution;
    let k = p.kappa0 + p.kappa1_s2pm2 * (p.gravity_mps2 * p.target_apex_m - eta);
    let gain = a + (1.0 + a) * k;
    gain * gain * eta
}

impl Plots<PlanarJugglerSystem> for JugglerPlots {
    fn new(_: &JugglerConfig) -> Self {
        Self::default()
    }

    fn push(&mut self, row: &BatRow) {
        let b = &row.0;
        self.apexes.push((b.apex[0], b.apex[1]));
        self.energy.push((b.index as f64, b.energy_jpkg));
        if let Some(e) = self.last_energy.replace(b.energy_jpkg) {
            self.pairs.push((e, b.energy_jpkg));
        }
    }

    fn write(
        self,
        cfg: &JugglerConfig,
        out: &JugglerOutcome,
        dir: &Path,
    ) -> Result<Vec<PathBuf>, Failure> {
        let apexes = self.apexes.values().to_vec();
        let Some(&first) = apexes.first() else {
            return Err(Failure::run("plot: the run has no bats"));
        };
        let s = &out.summary;
        let cf = &s.closed_form;
        let (name, p) = (&cfg.name, &cfg.params);
        let law = format!("{} law, {}", cfg.table.law.name(), cfg.table.law.equation());
        let mut written = Vec::new();
        let mut chart = Chart::new(
            format!("{name}: apex after each bat ({law})"),
            "b_x (m)",
            "b_z (m)",
        )
        .dots("apex after bat n", apexes)
        .dots("first apex", vec![first])
        .dots("target (b_x*, h*)", vec![(p.target_x_m, p.target_apex_m)]);
        if let Some(h) = cf.fixed_point_apex_m {
            chart = chart.dots(
                "eq. 8 fixed point (b_x*, eta_fp / gamma)",
                vec![(p.target_x_m, h)],
            );
        }
        written.extend(chart.draw(dir, &format!("{name}-apex"))?);
        let last = (s.impacts.saturating_sub(1) as f64).max(1.0);
        let mut chart = Chart::new(
            format!("{name}: energy after each bat ({law})"),
            "bat n",
            "eta = |b'|^2/2 + gamma b_z (J/kg)",
        )
        .line("eta", self.energy.values().to_vec())
        .line(
            "eta* = gamma h*",
            vec![(0.0, cf.target_energy_jpkg), (last, cf.target_energy_jpkg)],
        );
        if let Some(e) = cf.fixed_point_energy_jpkg {
            chart = chart.line("eq. 8 fixed point", vec![(0.0, e), (last, e)]);
        }
        written.extend(chart.draw(dir, &format!("{name}-energy"))?);
        if let Some(chart) = energy_map(cfg, self.pairs.into_values()) {
            written.extend(chart.draw(dir, &format!("{name}-energy-map"))?);
        }
        Ok(written)
    }
}

/// eta_{n+1} against eta_n with eq. 8 on the line b_x = b_x* and the identity.
fn energy_map(cfg: &JugglerConfig, pairs: Vec<(f64, f64)>) -> Option<Chart> {
    let coords = pairs
        .iter()
        .flat_map(|q| [q.0, q.1])
        .filter(|v| v.is_finite());
    let (lo, hi) = coords.fold(None, |r: Option<(f64, f64)>, v| {
        Some(r.map_or((v, v), |(a, b)| (a.min(v), b.max(v))))
    })?;
    let pad = 0.1 * (hi - lo).max(1e-3 * hi.abs().max(1e-3));
    let (a, b) = ((lo - pad).max(0.0), hi + pad);
    let curve = (0..CURVE_POINTS)
        .map(|i| a + (b - a) * i as f64 / (CURVE_POINTS - 1) as f64)
        .map(|e| (e, eq8_energy(&cfg.params, e)))
        .collect();
    let title = format!("{}: energy return map", cfg.name);
    let chart = Chart::new(title, "eta(n) (J/kg)", "eta(n+1) (J/kg)")
        .dots("simulated (eta(n), eta(n+1))", pairs)
        .line("eq. 8 on the line b_x = b_x*", curve)
        .line("identity", vec![(a, a), (b, b)]);
    Some(chart)
}
