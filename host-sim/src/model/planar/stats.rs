//! What a planar run's summary and stability class need, gathered impact by impact in
//! constant memory ([`RunStats`]): a run of any length keeps the same few numbers.
//!
//! The windows are those of [`classify`] and the summary: the *early*
//! quarter (the first `requested / 4` impacts) and the *late* quarter (the last
//! `max(n / 4, 1)` of the `n` impacts simulated). For a run that completes, `n` is the
//! requested count, known before it starts, so both windows are accumulated exactly as the
//! impacts pass. A run that ends early (it tipped over, lost the body) has no class that
//! depends on them; its late window is taken from the last [`LATE_TAIL_MAX`] impacts kept:
//! exact up to `4 x LATE_TAIL_MAX` impacts, and never more than that many kept
//! (`late_window_impacts` says how many it used).

use super::{Body, ImpactRecord, PlanarError, PlanarModel, PlanarParams, PlanarRun, RunEnd};
use crate::stream::Tail;
use serde::Serialize;

/// Most impacts kept for the late window of a run that ends early.
pub const LATE_TAIL_MAX: usize = 1 << 16;

/// The late window's figures.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Late {
    /// Impacts in the window.
    pub impacts: usize,
    /// Mean eta over it, J/kg (NaN if empty).
    pub mean_energy_jpkg: f64,
    /// Max |angle of the tilt law| over it, rad (theta, or the point mass's velocity angle).
    pub max_abs_law_rad: f64,
    /// Max |theta| over it, rad (the class's amplitude).
    pub max_abs_theta_rad: f64,
}

/// Sums and maxima over a window.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
struct Window {
    impacts: usize,
    energy_sum: f64,
    max_abs_law: f64,
    max_abs_theta: f64,
}

impl Window {
    fn push(&mut self, (energy, law, theta): (f64, f64, f64)) {
        self.impacts += 1;
        self.energy_sum += energy;
        self.max_abs_law = self.max_abs_law.max(law.abs());
        self.max_abs_theta = self.max_abs_theta.max(theta.abs());
    }

    fn late(&self) -> Late {
        Late {
            impacts: self.impacts,
            mean_energy_jpkg: match self.impacts {
                0 => f64::NAN,
                n => self.energy_sum / n as f64,
            },
            max_abs_law_rad: self.max_abs_law,
            max_abs_theta_rad: self.max_abs_theta,
        }
    }
}

/// A run's figures in constant memory (module docs).
#[derive(Clone, Debug, PartialEq)]
pub struct RunStats {
    eta_star: f64,
    point_mass: bool,
    requested: usize,
    /// Impacts seen.
    pub impacts: usize,
    /// Some eta was NaN or above 100 eta* (the class: diverges).
    pub energy_blew_up: bool,
    /// eta at the first impact, J/kg (NaN before it).
    pub first_energy_jpkg: f64,
    /// Time of the last impact, s.
    pub end_time_s: f64,
    /// Max |law angle| over the run, rad.
    pub max_abs_law_rad: f64,
    law_sum: f64,
    early: Window,
    late: Window,
    tail: Tail<(f64, f64, f64)>,
}

impl RunStats {
    /// Before the first impact of a run of `model` asked for `requested` impacts.
    pub fn new(model: &PlanarModel, requested: usize) -> Self {
        Self {
            eta_star: model.feedback.target_energy_jpkg(),
            point_mass: matches!(model.body, Body::PointMass),
            requested,
            impacts: 0,
            energy_blew_up: false,
            first_energy_jpkg: f64::NAN,
            end_time_s: 0.0,
            max_abs_law_rad: 0.0,
            law_sum: 0.0,
            early: Window::default(),
            late: Window::default(),
            tail: Tail::new((requested / 4).clamp(1, LATE_TAIL_MAX)),
        }
    }

    /// One more impact.
    pub fn push(&mut self, r: &ImpactRecord) {
        let e = r.energy_jpkg;
        let law = match self.point_mass {
            true => r.before.x_dot_mps.atan2(-r.before.y_dot_mps),
            false => r.before.theta_rad,
        };
        let v = (e, law, r.before.theta_rad);
        if self.impacts == 0 {
            self.first_energy_jpkg = e;
        }
        self.energy_blew_up |= e.is_nan() || e > 100.0 * self.eta_star;
        self.end_time_s = r.time_s;
        self.max_abs_law_rad = self.max_abs_law_rad.max(law.abs());
        self.law_sum += law;
        if self.impacts < self.requested / 4 {
            self.early.push(v);
        }
        if self.impacts >= self.requested - (self.requested / 4).max(1).min(self.requested) {
            self.late.push(v);
        }
        self.tail.push(v);
        self.impacts += 1;
    }

    /// Mean law angle over the run, rad (NaN without impacts).
    pub fn mean_law_rad(&self) -> f64 {
        match self.impacts {
            0 => f64::NAN,
            n => self.law_sum / n as f64,
        }
    }

    /// The late window: the last `max(n/4, 1)` impacts (module docs).
    pub fn late(&self) -> Late {
        if self.impacts == self.requested {
            return self.late.late();
        }
        let n = self.impacts;
        let k = (n / 4).max(1).min(n).min(self.tail.len());
        let mut w = Window::default();
        for &v in self.tail.iter().skip(self.tail.len() - k) {
            w.push(v);
        }
        w.late()
    }

    /// The stability-map class of the run, which ended for `end` (see
    /// [`CellClass`]): the same as [`classify`] on every impact.
    pub fn class(&self, end: RunEnd) -> CellClass {
        if self.energy_blew_up {
            return CellClass::Diverges;
        }
        match end {
            RunEnd::TippedOver => return CellClass::TipsOver,
            RunEnd::Completed => {}
            _ => return CellClass::Diverges,
        }
        if self.impacts < 4 || self.impacts != self.requested {
            return CellClass::Drifts;
        }
        let late = self.late.late();
        let settled = (late.mean_energy_jpkg - self.eta_star).abs() <= ENERGY_TOL * self.eta_star;
        if settled && late.max_abs_theta_rad <= GROWTH_TOL * self.early.max_abs_theta {
            CellClass::Converges
        } else {
            CellClass::Drifts
        }
    }
}

/// The class of one stability-map cell (sec. 2.3).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum CellClass {
    /// Stayed up for all impacts, the mean of eta over the last quarter of impacts lies within
    /// [`ENERGY_TOL`] of eta* (eta itself keeps oscillating with the tilt, whose eigenvalues
    /// sit on the unit circle), and the tilt amplitude did not grow (last quarter's max
    /// |theta| <= [`GROWTH_TOL`] x the first quarter's).
    Converges,
    /// Stayed up for all impacts but the energy did not settle or the tilt grew.
    Drifts,
    /// |theta| reached the tip angle.
    TipsOver,
    /// The run failed otherwise (no separation, no contact, jam, non-finite) or the energy
    /// exceeded 100 eta*.
    Diverges,
}

/// Relative tolerance on the late mean energy of [`CellClass::Converges`].
pub const ENERGY_TOL: f64 = 0.02;
/// Amplitude-growth tolerance of [`CellClass::Converges`].
pub const GROWTH_TOL: f64 = 1.1;

/// One cell of a stability map.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Cell {
    /// theta0, rad.
    pub theta0_rad: f64,
    /// kappa, dimensionless.
    pub kappa: f64,
    /// The class.
    pub class: CellClass,
    /// Impacts simulated before the run ended.
    pub impacts: usize,
    /// max |theta| at impacts, rad.
    pub max_abs_theta_rad: f64,
}

/// Classify a run of `model` (see [`CellClass`]): [`RunStats::class`] on
/// every impact of the run.
pub fn classify(model: &PlanarModel, run: &PlanarRun) -> CellClass {
    let mut stats = RunStats::new(model, run.impacts.len());
    for r in &run.impacts {
        stats.push(r);
    }
    stats.class(run.end)
}

/// A stability map over `thetas_rad` (rows) x `kappas` (columns): each cell is the scene
/// `base` with that initial angle and kappa, run for `impacts` impacts and classified.
pub fn stability_map(
    base: &PlanarParams,
    thetas_rad: &[f64],
    kappas: &[f64],
    impacts: usize,
) -> Result<Vec<Vec<Cell>>, PlanarError> {
    let mut rows = Vec::with_capacity(thetas_rad.len());
    for &theta0 in thetas_rad {
        let mut row = Vec::with_capacity(kappas.len());
        for &kappa in kappas {
            let p = PlanarParams {
                initial_theta_rad: theta0,
                kappa,
                impacts,
                ..base.clone()
            };
            let model = p.build()?;
            let mut stats = RunStats::new(&model, impacts);
            let mut max_theta = 0.0f64;
            let done = model.run_streaming(p.start()?, impacts, p.seed, &mut |r| {
                stats.push(r);
                max_theta = max_theta.max(r.before.theta_rad.abs());
            });
            row.push(Cell {
                theta0_rad: theta0,
                kappa,
                class: stats.class(done.end),
                impacts: done.impacts,
                max_abs_theta_rad: max_theta,
            });
        }
        rows.push(row);
    }
    Ok(rows)
}
