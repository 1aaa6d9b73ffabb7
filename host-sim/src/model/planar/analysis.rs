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
//! # Linearization
//!
//! The Jacobian, its eigenvalues, their uncertainty and the verdict are the engine's
//! ([`crate::engine::linearize`]): central differences Richardson-extrapolated at the step
//! where neighbouring steps agree best, the first step [`STEP_REL`] times each coordinate's
//! natural size (rho for rho theta, |y*| for the velocities): at large kappa the map is so
//! steep that `STEP_REL` of rho in rho theta tilts the table by radians.
//!
//! # Closed forms for comparison
//!
//! eq. 11 (re-derived in the core, [`tilt_eigenvalues`]), eq. 16 (`kappa_crit` at e = 1) and
//! eq. 26 (as printed), the energy eigenvalue `1 - (1+e) kappa_E y*^2` and kappa_Emax (core,
//! re-derived and as printed). The linearization shows that with the compensation of eq. 25
//! the tilt block is eq. 11 for every e: the type change happens at eq. 16's kappa_crit, not
//! eq. 26's (see `docs/planar.md`).

use super::{Body, PlanarError, PlanarModel, PlanarState, RunEnd};
use crate::engine::linearize::{self, match_max_diff};
pub use crate::engine::linearize::{
    Eigenvalue, Jacobian, Verdict, MARGINAL_MAX_TOL, ROUNDING_ULPS, STEP_HALVINGS, STEP_REL,
    VERDICT_FLOOR,
};
use dexter_core::tilt::{
    energy_eigenvalue, kappa_crit, kappa_e_max, kappa_e_max_as_printed, tilt_eigenvalues,
};
use serde::Serialize;

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
    /// The eigenvalues' uncertainty used for the verdict: the largest of the distance
    /// between the eigenvalues of the Jacobian and of its coarser twin (matched one to one),
    /// the square root of the Jacobian's error (a double eigenvalue moves by that much) and
    /// [`VERDICT_FLOOR`].
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

/// [`Jacobian`] of [`impact_map`] at `z` ([`linearize::jacobian`]), the first step
/// `step_rel` times each coordinate's natural size.
pub fn jacobian(model: &PlanarModel, z: &[f64], step_rel: f64) -> Result<Jacobian, PlanarError> {
    let v = z.iter().fold(0.0f64, |m, x| m.max(x.abs())).max(1e-3);
    let scales: Vec<f64> = match model.body {
        Body::PointMass => vec![v, v],
        Body::Rigid { rho_m, .. } => vec![rho_m, v, v, v],
    };
    let map = |z: &[f64]| impact_map(model, z).ok();
    linearize::jacobian(map, z, &scales, step_rel).map_err(PlanarError::Analysis)
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
    let jac = jacobian(model, &z, STEP_REL)?;
    let eigenvalues: Vec<Eigenvalue> = linearize::eigenvalues_of(&jac.matrix)
        .map_err(PlanarError::Analysis)?
        .into_iter()
        .map(Eigenvalue::from_pair)
        .collect();
    let tol = linearize::uncertainty(&jac, &eigenvalues).map_err(PlanarError::Analysis)?;
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
    let max_mod = eigenvalues.iter().fold(0.0f64, |m, x| m.max(x.modulus));
    let verdict = Verdict::of(max_mod, tol);
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
        jacobian: jac.matrix,
        jacobian_error: jac.error,
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
