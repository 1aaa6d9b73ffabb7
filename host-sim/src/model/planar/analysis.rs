//! Linearized stability of the impact-to-impact map (Zumel & Erdmann sec. 2.1.2, 2.2.1) and
//! the stability map over initial angle x kappa (sec. 2.3).
//!
//! # The map and its fixed point
//!
//! The state just before an impact, with the contact point on the impact line y = 0, is
//! `z = (rho theta, x', y', rho theta')` (the paper's coordinates; the point mass uses
//! `(x', y')`). One step applies the tilt law and eq. 25, the impact, the flight and the exact
//! contact of eq. 7 (no timing noise). Its fixed point is `(0, 0, y*, 0)` with
//! `y* = -sqrt(2 (eta* - G l))` (eq. 8 / eq. 25's target); [`analyze`] checks the residual.
//!
//! # Finite differences with steps chosen for accuracy
//!
//! Column j of the Jacobian is the central difference `D(h) = (F(z + h e_j) - F(z - h e_j))/2h`
//! (error `O(h^2)` from truncation, `O(eps/h)` from rounding), Richardson-extrapolated twice:
//! `R(h) = (4 D(h/2) - D(h))/3` (error `O(h^4)`). With `h = STEP_REL * scale_j`, scale_j the
//! coordinate's natural size (rho for rho theta, |y*| for the velocities), truncation and
//! rounding are both near 1e-12; the reported error estimate is `max |R(h/2) - R(h)|` over
//! the entries (an upper estimate of the coarser level's error).
//!
//! # Closed forms for comparison
//!
//! eq. 11 (re-derived in the core, [`tilt_eigenvalues`]), eq. 16 (`kappa_crit` at e = 1) and
//! eq. 26 (as printed), the energy eigenvalue `1 - (1+e) kappa_E y*^2` and kappa_Emax (core,
//! re-derived and as printed). The linearization shows that with the compensation of eq. 25
//! the tilt block is eq. 11 for every e: the type change happens at eq. 16's kappa_crit, not
//! eq. 26's (see `docs/planar.md`).

use super::{Body, PlanarError, PlanarModel, PlanarParams, PlanarState, RunEnd};
use dexter_core::tilt::{
    energy_eigenvalue, kappa_crit, kappa_e_max, kappa_e_max_as_printed, tilt_eigenvalues,
};
use serde::Serialize;

/// Relative finite-difference step (before the two halvings of Richardson extrapolation).
pub const STEP_REL: f64 = 2e-3;

/// The parameters the analysis used.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct ResolvedParams {
    /// rho, m (0 for a point mass).
    pub rho_m: f64,
    /// l, m (0 for a point mass).
    pub l_m: f64,
    /// y*, the fixed point's impact velocity, m/s (negative: downward).
    pub impact_velocity_mps: f64,
    /// kappa, dimensionless.
    pub kappa: f64,
    /// kappa_E, s^2/m^2.
    pub kappa_e_s2pm2: f64,
    /// e, dimensionless.
    pub restitution: f64,
    /// G, m/s^2.
    pub gravity_mps2: f64,
    /// eta*, J/kg.
    pub target_energy_jpkg: f64,
}

/// One eigenvalue.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Eigenvalue {
    /// Real part.
    pub re: f64,
    /// Imaginary part.
    pub im: f64,
    /// |lambda|.
    pub modulus: f64,
}

impl Eigenvalue {
    fn from_pair((re, im): (f64, f64)) -> Self {
        Self {
            re,
            im,
            modulus: re.hypot(im),
        }
    }
}

/// The linearization's verdict.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Verdict {
    /// Some |lambda| > 1 (beyond the tolerance): the fixed point is unstable.
    Unstable,
    /// All |lambda| <= 1, some = 1 within the tolerance: neutrally stable to first order
    /// (the linearization cannot decide; the x' eigenvalue 1 is always there: horizontal
    /// drift, sec. 2.1.2).
    Marginal,
    /// All |lambda| < 1.
    AsymptoticallyStable,
}

/// The closed forms the numerical eigenvalues are compared with.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct ClosedForms {
    /// The eigenvalues the closed forms predict, (re, im): rigid body: 1 (x'), the energy
    /// eigenvalue (y'), eq. 11's pair; point mass: 1 - 2 kappa (eq. 3) and the energy
    /// eigenvalue.
    pub predicted: [(f64, f64); 4],
    /// How many entries of `predicted` are used (4 rigid, 2 point mass).
    pub count: usize,
    /// eq. 16: 1 + G rho^2/(y*^2 l) (NaN for a point mass).
    pub kappa_crit_eq16: f64,
    /// eq. 26 as printed: 1 + 2 G rho^2/((1+e) y*^2 l) (NaN for a point mass).
    pub kappa_crit_eq26: f64,
    /// Energy eigenvalue 1 - (1+e) kappa_E y*^2 (core re-derivation).
    pub energy_eigenvalue: f64,
    /// kappa_Emax re-derived, 2/((1+e) y*^2), s^2/m^2.
    pub kappa_e_max: f64,
    /// kappa_Emax as printed, 4/((1+e) y*^2), s^2/m^2.
    pub kappa_e_max_as_printed: f64,
}

/// The result of [`analyze`].
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct AnalysisReport {
    /// The parameters used.
    pub params: ResolvedParams,
    /// The fixed point z* (rho theta m, x' m/s, y' m/s, rho theta' m/s; point mass x', y').
    pub fixed_point: Vec<f64>,
    /// max |F(z*) - z*|, m/s.
    pub fixed_point_residual: f64,
    /// The Jacobian dF/dz at z*, rows.
    pub jacobian: Vec<Vec<f64>>,
    /// Estimated max abs error of the Jacobian's entries.
    pub jacobian_error: f64,
    /// Eigenvalues, decreasing modulus.
    pub eigenvalues: Vec<Eigenvalue>,
    /// Verdict from the moduli.
    pub verdict: Verdict,
    /// Tolerance on |lambda| = 1 used for the verdict.
    pub verdict_tolerance: f64,
    /// Closed forms.
    pub closed_form: ClosedForms,
    /// max over closed-form eigenvalues of the distance to the nearest numerical one
    /// (matched one to one).
    pub closed_form_max_abs_diff: f64,
}

/// The fixed point's impact velocity y* = -sqrt(2 (eta* - G l)), m/s.
pub fn fixed_point_velocity_mps(model: &PlanarModel) -> Result<f64, PlanarError> {
    let v2 = 2.0 * (model.feedback.target_energy_jpkg() - model.gravity_mps2 * model.l_m());
    if v2.is_nan() || v2 <= 0.0 {
        return Err(PlanarError::Analysis(
            "target energy below G l: no flight at the fixed point",
        ));
    }
    Ok(-v2.sqrt())
}

/// The pre-impact state of map coordinates `z`.
fn state_of(model: &PlanarModel, z: &[f64]) -> PlanarState {
    match model.body {
        Body::PointMass => PlanarState {
            x_dot_mps: z[0],
            y_dot_mps: z[1],
            ..PlanarState::default()
        },
        Body::Rigid { rho_m, l_m } => {
            let theta = z[0] / rho_m;
            PlanarState {
                x_m: 0.0,
                y_m: l_m * theta.cos(),
                theta_rad: theta,
                x_dot_mps: z[1],
                y_dot_mps: z[2],
                theta_dot_radps: z[3] / rho_m,
            }
        }
    }
}

fn coords_of(model: &PlanarModel, s: &PlanarState) -> Vec<f64> {
    match model.body {
        Body::PointMass => vec![s.x_dot_mps, s.y_dot_mps],
        Body::Rigid { rho_m, .. } => vec![
            rho_m * s.theta_rad,
            s.x_dot_mps,
            s.y_dot_mps,
            rho_m * s.theta_dot_radps,
        ],
    }
}

/// The exact impact-to-impact map F(z) (module docs): impact with the commanded table,
/// flight, contact of eq. 7. `Err` if the body does not separate or no contact is found.
pub fn impact_map(model: &PlanarModel, z: &[f64]) -> Result<Vec<f64>, RunEnd> {
    let s = state_of(model, z);
    let cmd = model.command(&s);
    let (after, _) = model.collide(&s, &cmd).map_err(|_| RunEnd::Jam)?;
    let (t, _, _) = model.ideal_contact_time_s(&after)?;
    Ok(coords_of(model, &after.flown(t, model.gravity_mps2)))
}

fn central(model: &PlanarModel, z: &[f64], j: usize, h: f64) -> Result<Vec<f64>, PlanarError> {
    let mut zp = z.to_vec();
    let mut zm = z.to_vec();
    zp[j] += h;
    zm[j] -= h;
    let fail = |_| PlanarError::Analysis("impact map failed near the fixed point");
    let fp = impact_map(model, &zp).map_err(fail)?;
    let fm = impact_map(model, &zm).map_err(fail)?;
    Ok(fp
        .iter()
        .zip(&fm)
        .map(|(a, b)| (a - b) / (2.0 * h))
        .collect())
}

fn richardson(model: &PlanarModel, z: &[f64], j: usize, h: f64) -> Result<Vec<f64>, PlanarError> {
    let d1 = central(model, z, j, h)?;
    let d2 = central(model, z, j, 0.5 * h)?;
    Ok(d1
        .iter()
        .zip(&d2)
        .map(|(a, b)| (4.0 * b - a) / 3.0)
        .collect())
}

/// The Jacobian of [`impact_map`] at `z` by twice-Richardson central differences with
/// relative step `step_rel`, and its estimated max abs error.
pub fn jacobian(
    model: &PlanarModel,
    z: &[f64],
    step_rel: f64,
) -> Result<(Vec<Vec<f64>>, f64), PlanarError> {
    let n = z.len();
    let v = z.iter().fold(0.0f64, |m, x| m.max(x.abs())).max(1e-3);
    let scales: Vec<f64> = match model.body {
        Body::PointMass => vec![v, v],
        Body::Rigid { rho_m, .. } => vec![rho_m, v, v, v],
    };
    let mut jac = vec![vec![0.0; n]; n];
    let mut err = 0.0f64;
    for j in 0..n {
        let h = step_rel * scales[j];
        let coarse = richardson(model, z, j, h)?;
        let fine = richardson(model, z, j, 0.5 * h)?;
        for i in 0..n {
            jac[i][j] = fine[i];
            err = err.max((fine[i] - coarse[i]).abs());
        }
    }
    Ok((jac, err))
}

/// Match `predicted` one to one with `numeric` greedily by distance; the largest distance.
fn match_max_diff(predicted: &[(f64, f64)], numeric: &[Eigenvalue]) -> f64 {
    let mut used = vec![false; numeric.len()];
    let mut worst = 0.0f64;
    for p in predicted {
        let mut best: Option<(usize, f64)> = None;
        for (k, q) in numeric.iter().enumerate() {
            if used[k] {
                continue;
            }
            let d = (q.re - p.0).hypot(q.im - p.1);
            if best.is_none_or(|(_, bd)| d < bd) {
                best = Some((k, d));
            }
        }
        if let Some((k, d)) = best {
            used[k] = true;
            worst = worst.max(d);
        } else {
            worst = f64::INFINITY;
        }
    }
    worst
}

/// Linearize the model's impact-to-impact map at its fixed point (module docs) and compare
/// with the closed forms of eq. 11, 16, 26.
pub fn analyze(model: &PlanarModel) -> Result<AnalysisReport, PlanarError> {
    let y_star = fixed_point_velocity_mps(model)?;
    let z: Vec<f64> = match model.body {
        Body::PointMass => vec![0.0, y_star],
        Body::Rigid { .. } => vec![0.0, 0.0, y_star, 0.0],
    };
    let fz = impact_map(model, &z)
        .map_err(|_| PlanarError::Analysis("impact map failed at the fixed point"))?;
    let residual = fz
        .iter()
        .zip(&z)
        .fold(0.0f64, |m, (a, b)| m.max((a - b).abs()));
    let (jac, jac_err) = jacobian(model, &z, STEP_REL)?;
    let eig = super::eigen::eigenvalues(&jac).ok_or(PlanarError::Analysis(
        "eigenvalue iteration did not converge",
    ))?;
    let eigenvalues: Vec<Eigenvalue> = eig.into_iter().map(Eigenvalue::from_pair).collect();
    let g = model.gravity_mps2;
    let e = model.feedback.e();
    let ke = model.feedback.kappa_e_s2pm2();
    let kappa = model.tilt.kappa();
    let (rho, l) = (model.rho_m(), model.l_m());
    let energy = energy_eigenvalue(ke, e, y_star);
    let (predicted, count, kc16, kc26) = match model.body {
        Body::PointMass => (
            [
                (1.0 - 2.0 * kappa, 0.0),
                (energy, 0.0),
                (f64::NAN, 0.0),
                (f64::NAN, 0.0),
            ],
            2,
            f64::NAN,
            f64::NAN,
        ),
        Body::Rigid { .. } => {
            let [a, b] = tilt_eigenvalues(kappa, g, rho, l, y_star);
            (
                [(1.0, 0.0), (energy, 0.0), a, b],
                4,
                kappa_crit(g, rho, l, y_star, 1.0),
                kappa_crit(g, rho, l, y_star, e),
            )
        }
    };
    let diff = match_max_diff(&predicted[..count], &eigenvalues);
    let tol = 1e-6f64.max(100.0 * jac_err).max(jac_err.sqrt());
    let max_mod = eigenvalues.iter().fold(0.0f64, |m, x| m.max(x.modulus));
    let verdict = if max_mod > 1.0 + tol {
        Verdict::Unstable
    } else if max_mod >= 1.0 - tol {
        Verdict::Marginal
    } else {
        Verdict::AsymptoticallyStable
    };
    Ok(AnalysisReport {
        params: ResolvedParams {
            rho_m: rho,
            l_m: l,
            impact_velocity_mps: y_star,
            kappa,
            kappa_e_s2pm2: ke,
            restitution: e,
            gravity_mps2: g,
            target_energy_jpkg: model.feedback.target_energy_jpkg(),
        },
        fixed_point: z,
        fixed_point_residual: residual,
        jacobian: jac,
        jacobian_error: jac_err,
        eigenvalues,
        verdict,
        verdict_tolerance: tol,
        closed_form: ClosedForms {
            predicted,
            count,
            kappa_crit_eq16: kc16,
            kappa_crit_eq26: kc26,
            energy_eigenvalue: energy,
            kappa_e_max: kappa_e_max(e, y_star),
            kappa_e_max_as_printed: kappa_e_max_as_printed(e, y_star),
        },
        closed_form_max_abs_diff: diff,
    })
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

/// Classify a run of `model` (see [`CellClass`]).
pub fn classify(model: &PlanarModel, run: &super::PlanarRun) -> CellClass {
    let eta_star = model.feedback.target_energy_jpkg();
    if run
        .impacts
        .iter()
        .any(|r| r.energy_jpkg.is_nan() || r.energy_jpkg > 100.0 * eta_star)
    {
        return CellClass::Diverges;
    }
    match run.end {
        RunEnd::TippedOver => return CellClass::TipsOver,
        RunEnd::Completed => {}
        _ => return CellClass::Diverges,
    }
    let n = run.impacts.len();
    if n < 4 {
        return CellClass::Drifts;
    }
    let q = n / 4;
    let late = &run.impacts[n - q..];
    let early = &run.impacts[..q];
    let mean = late.iter().map(|r| r.energy_jpkg).sum::<f64>() / late.len() as f64;
    let settled = (mean - eta_star).abs() <= ENERGY_TOL * eta_star;
    let amp = |rs: &[super::ImpactRecord]| {
        rs.iter()
            .fold(0.0f64, |m, r| m.max(r.before.theta_rad.abs()))
    };
    if settled && amp(late) <= GROWTH_TOL * amp(early) {
        CellClass::Converges
    } else {
        CellClass::Drifts
    }
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
            let run = model.run(p.start()?, impacts, p.seed);
            row.push(Cell {
                theta0_rad: theta0,
                kappa,
                class: classify(&model, &run),
                impacts: run.impacts.len(),
                max_abs_theta_rad: run
                    .impacts
                    .iter()
                    .fold(0.0f64, |m, r| m.max(r.before.theta_rad.abs())),
            });
        }
        rows.push(row);
    }
    Ok(rows)
}
