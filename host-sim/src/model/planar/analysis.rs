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
//! (error `O(h^2)` from truncation, `O(eps/h)` from rounding), Richardson-extrapolated:
//! `R(h) = (4 D(h/2) - D(h))/3` (error `O(h^4)`). No one step suits every gain: at large
//! kappa the map is so steep that `STEP_REL` of rho in rho theta tilts the table by
//! radians. So each column tries `h = STEP_REL * scale_j / 2^i` for i up to
//! [`STEP_HALVINGS`] (scale_j the coordinate's natural size: rho for rho theta, |y*| for the
//! velocities) and keeps the step where neighbouring Richardson values `R(h)`, `R(h/2)`
//! differ least: past it truncation, before it rounding, makes them differ more. That
//! difference is the reported error estimate.
//!
//! # The verdict
//!
//! The eigenvalues of the Jacobian and of its twin at twice each column's step are matched
//! one to one; their largest distance (with the square root of the Jacobian's error, by
//! which a double eigenvalue can move, and [`VERDICT_FLOOR`]) is the uncertainty `tol` of
//! every eigenvalue. Unstable if some |lambda| > 1 + tol, asymptotically stable if every
//! |lambda| < 1 - tol, marginal if the largest is within tol of 1 and tol <=
//! [`MARGINAL_MAX_TOL`], else "unreliable": the linearization cannot decide.
//!
//! # Closed forms for comparison
//!
//! eq. 11 (re-derived in the core, [`tilt_eigenvalues`]), eq. 16 (`kappa_crit` at e = 1) and
//! eq. 26 (as printed), the energy eigenvalue `1 - (1+e) kappa_E y*^2` and kappa_Emax (core,
//! re-derived and as printed). The linearization shows that with the compensation of eq. 25
//! the tilt block is eq. 11 for every e: the type change happens at eq. 16's kappa_crit, not
//! eq. 26's (see `docs/planar.md`).

use super::{Body, PlanarError, PlanarModel, PlanarState, RunEnd};
use dexter_core::tilt::{
    energy_eigenvalue, kappa_crit, kappa_e_max, kappa_e_max_as_printed, tilt_eigenvalues,
};
use serde::Serialize;

/// Relative finite-difference step: the largest tried.
pub const STEP_REL: f64 = 2e-3;
/// Halvings of the step tried per column (down to `STEP_REL / 2^32`, 5e-13).
pub const STEP_HALVINGS: usize = 32;
/// Least uncertainty the verdict allows on |lambda| (rounding of a well-conditioned
/// Jacobian).
pub const VERDICT_FLOOR: f64 = 1e-9;
/// Rounding of one map evaluation, in ulps of its largest value (the contact time is
/// found to a few ulps; the state after it carries a few more).
pub const ROUNDING_ULPS: f64 = 64.0;
/// Trials of [`sensitivity`].
pub const PERTURBATIONS: usize = 8;
/// Largest uncertainty on |lambda| with which a modulus at 1 is still called marginal;
/// above it the linearization cannot decide ([`Verdict::Unreliable`]).
pub const MARGINAL_MAX_TOL: f64 = 1e-3;

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
    /// Some |lambda| is within the eigenvalues' uncertainty of 1 and that uncertainty
    /// exceeds [`MARGINAL_MAX_TOL`]: the linearization cannot decide.
    Unreliable,
}

impl Verdict {
    /// The verdict for eigenvalues of largest modulus `max_mod`, each uncertain by `tol`.
    pub fn of(max_mod: f64, tol: f64) -> Self {
        if max_mod - tol > 1.0 {
            Verdict::Unstable
        } else if max_mod + tol < 1.0 {
            Verdict::AsymptoticallyStable
        } else if tol <= MARGINAL_MAX_TOL {
            Verdict::Marginal
        } else {
            Verdict::Unreliable
        }
    }
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

fn central(model: &PlanarModel, z: &[f64], j: usize, h: f64) -> Option<Vec<f64>> {
    let mut zp = z.to_vec();
    let mut zm = z.to_vec();
    zp[j] += h;
    zm[j] -= h;
    let fp = impact_map(model, &zp).ok()?;
    let fm = impact_map(model, &zm).ok()?;
    let d: Vec<f64> = fp
        .iter()
        .zip(&fm)
        .map(|(a, b)| (a - b) / (2.0 * h))
        .collect();
    d.iter().all(|x| x.is_finite()).then_some(d)
}

/// A column of the Jacobian at its best step: the Richardson value there, the one of the
/// step twice as large, and their largest difference (the coarser value's error estimate).
type Column = (Vec<f64>, Vec<f64>, f64);

/// Column `j` of the Jacobian (module docs): central differences at `h0 / 2^i`,
/// i = 0 ..= [`STEP_HALVINGS`], Richardson-extrapolated between neighbours; the pair of
/// neighbouring Richardson values that differ least is kept. Steps at which the map fails
/// (the body does not separate, no contact) are skipped.
fn column(model: &PlanarModel, z: &[f64], j: usize, h0: f64, f_scale: f64) -> Option<Column> {
    let mut h = h0;
    let mut d_prev = central(model, z, j, h);
    let mut r_prev: Option<Vec<f64>> = None;
    let mut best: Option<Column> = None;
    for _ in 0..STEP_HALVINGS {
        h *= 0.5;
        let d = central(model, z, j, h);
        let r: Option<Vec<f64>> = match (&d_prev, &d) {
            (Some(a), Some(b)) => Some(a.iter().zip(b).map(|(a, b)| (4.0 * b - a) / 3.0).collect()),
            _ => None,
        };
        if let (Some(coarse), Some(fine)) = (&r_prev, &r) {
            // the rounding of F over a step h bounds the error from below (two neighbours
            // agreeing to the last bit at a step below the rounding are both wrong)
            let rounding = ROUNDING_ULPS * f64::EPSILON * f_scale / h;
            let err = coarse
                .iter()
                .zip(fine)
                .fold(rounding, |m, (a, b): (&f64, &f64)| m.max((a - b).abs()));
            if best.as_ref().is_none_or(|b| err < b.2) {
                best = Some((fine.clone(), coarse.clone(), err));
            }
        }
        (d_prev, r_prev) = (d, r);
    }
    best
}

/// The Jacobian of [`impact_map`] at `z` by central differences, Richardson-extrapolated,
/// with each column's step chosen where neighbouring steps agree best (module docs); the
/// step starts at `step_rel` times the coordinate's natural size.
#[derive(Clone, Debug, PartialEq)]
pub struct Jacobian {
    /// dF/dz, rows.
    pub matrix: Vec<Vec<f64>>,
    /// The same with every column at twice its step (to estimate the eigenvalues' error).
    pub coarse: Vec<Vec<f64>>,
    /// Estimated max abs error of the entries (of `coarse`; `matrix` is more accurate).
    pub error: f64,
}

/// [`Jacobian`] of [`impact_map`] at `z`.
pub fn jacobian(model: &PlanarModel, z: &[f64], step_rel: f64) -> Result<Jacobian, PlanarError> {
    let n = z.len();
    let v = z.iter().fold(0.0f64, |m, x| m.max(x.abs())).max(1e-3);
    let scales: Vec<f64> = match model.body {
        Body::PointMass => vec![v, v],
        Body::Rigid { rho_m, .. } => vec![rho_m, v, v, v],
    };
    let f_scale = impact_map(model, z)
        .map_err(|_| PlanarError::Analysis("impact map failed at the fixed point"))?
        .iter()
        .fold(v, |m, x| m.max(x.abs()));
    let mut out = Jacobian {
        matrix: vec![vec![0.0; n]; n],
        coarse: vec![vec![0.0; n]; n],
        error: 0.0,
    };
    for (j, scale) in scales.iter().enumerate() {
        let (fine, coarse, err) = column(model, z, j, step_rel * scale, f_scale).ok_or(
            PlanarError::Analysis("impact map failed near the fixed point at every step"),
        )?;
        for i in 0..n {
            out.matrix[i][j] = fine[i];
            out.coarse[i][j] = coarse[i];
        }
        out.error = out.error.max(err);
    }
    Ok(out)
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

/// How far the eigenvalues `eig` of `m` move when every entry of `m` moves by `delta`
/// (the Jacobian's uncertainty), the largest over [`PERTURBATIONS`] sign patterns: an
/// ill-conditioned eigenvalue (a small one beside a huge one at large kappa) moves far.
pub fn sensitivity(m: &[Vec<f64>], eig: &[Eigenvalue], delta: f64) -> Result<f64, PlanarError> {
    let mut state = 0x9E37_79B9_7F4A_7C15u64;
    let mut worst = 0.0f64;
    for _ in 0..PERTURBATIONS {
        let p: Vec<Vec<f64>> = m
            .iter()
            .map(|row| {
                row.iter()
                    .map(|x| {
                        // xorshift: a fixed, reproducible sign pattern
                        state ^= state << 13;
                        state ^= state >> 7;
                        state ^= state << 17;
                        x + if state & 1 == 0 { delta } else { -delta }
                    })
                    .collect()
            })
            .collect();
        let moved = eigenvalues_of(&p)?;
        worst = worst.max(match_max_diff(&moved, eig));
    }
    Ok(worst)
}

fn eigenvalues_of(m: &[Vec<f64>]) -> Result<Vec<(f64, f64)>, PlanarError> {
    super::eigen::eigenvalues(m).ok_or(PlanarError::Analysis(
        "eigenvalue iteration did not converge",
    ))
}

/// The uncertainty of the eigenvalues `eig` of `jac` (module docs, "The verdict").
fn uncertainty(jac: &Jacobian, eig: &[Eigenvalue]) -> Result<f64, PlanarError> {
    let coarse = eigenvalues_of(&jac.coarse)?;
    let scale = jac
        .matrix
        .iter()
        .flatten()
        .fold(0.0f64, |m, x| m.max(x.abs()));
    let delta = jac.error.max(ROUNDING_ULPS * f64::EPSILON * scale);
    Ok(match_max_diff(&coarse, eig)
        .max(sensitivity(&jac.matrix, eig, delta)?)
        .max(jac.error.sqrt())
        .max(VERDICT_FLOOR))
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
    let eigenvalues: Vec<Eigenvalue> = eigenvalues_of(&jac.matrix)?
        .into_iter()
        .map(Eigenvalue::from_pair)
        .collect();
    let tol = uncertainty(&jac, &eigenvalues)?;
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

#[cfg(test)]
mod tests {
    use super::*;

    /// An ill-conditioned Jacobian (a huge coupling beside a near-double eigenvalue) whose
    /// coarse twin agrees with it: the uncertainty must still cover how far its eigenvalues
    /// move under an entry error of the Jacobian's size (sqrt(1e-12 x 1e8) = 0.01 here).
    #[test]
    fn the_uncertainty_covers_ill_conditioned_eigenvalues() {
        let m = vec![vec![1.0, 1e8], vec![0.0, 1.0 + 1e-9]];
        let jac = Jacobian {
            matrix: m.clone(),
            coarse: m.clone(),
            error: 1e-12,
        };
        let eig: Vec<Eigenvalue> = eigenvalues_of(&m)
            .unwrap()
            .into_iter()
            .map(Eigenvalue::from_pair)
            .collect();
        let tol = uncertainty(&jac, &eig).unwrap();
        // the lower-left entry at 1e-12: eigenvalues 1 +- sqrt(1e-12 x 1e8) = 1 +- 0.01
        let mut moved = m.clone();
        moved[1][0] = 1e-12;
        let shifted = eigenvalues_of(&moved).unwrap();
        let d = match_max_diff(&shifted, &eig);
        assert!(d > 5e-3, "{d}");
        assert!(tol >= d, "uncertainty {tol} < movement {d}");
        assert!(Verdict::of(1.0, tol) == Verdict::Unreliable);
    }
}
