//! Linearization of a return map at its fixed point: a finite-difference Jacobian with the
//! step chosen for accuracy, its eigenvalues ([`super::eigen`]), their uncertainty and the
//! verdict it allows. One implementation for every system's `analyze` (the tilt table,
//! `model::planar::analysis`; the spatial juggler, `model::spatial::analysis`).
//!
//! # Finite differences with steps chosen for accuracy
//!
//! Column j of the Jacobian is the central difference `D(h) = (F(z + h e_j) - F(z - h e_j))/2h`
//! (error `O(h^2)` from truncation, `O(eps/h)` from rounding), Richardson-extrapolated:
//! `R(h) = (4 D(h/2) - D(h))/3` (error `O(h^4)`). No one step suits every map: a steep map
//! needs a small one. So each column tries `h = step_rel * scale_j / 2^i` for i up to
//! [`STEP_HALVINGS`] (scale_j the coordinate's natural size) and keeps the step where
//! neighbouring Richardson values `R(h)`, `R(h/2)` differ least: past it truncation, before
//! it rounding, makes them differ more. That difference is the reported error estimate.
//!
//! # The verdict
//!
//! The eigenvalues of the Jacobian and of its twin at twice each column's step are matched
//! one to one; their largest distance (with the square root of the Jacobian's error, by
//! which a double eigenvalue moves, how far the eigenvalues move under an entry error of
//! that size, and [`VERDICT_FLOOR`]) is the uncertainty `tol` of every eigenvalue. Unstable
//! if some |lambda| > 1 + tol, asymptotically stable if every |lambda| < 1 - tol, marginal
//! if the largest is within tol of 1 and tol <= [`MARGINAL_MAX_TOL`], else "unreliable":
//! the linearization cannot decide.

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
    /// The eigenvalue re + i im.
    pub fn from_pair((re, im): (f64, f64)) -> Self {
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
    /// (the linearization cannot decide; e.g. the tilt table's x' eigenvalue 1, horizontal
    /// drift, Zumel & Erdmann sec. 2.1.2).
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

fn central<F>(map: &F, z: &[f64], j: usize, h: f64) -> Option<Vec<f64>>
where
    F: Fn(&[f64]) -> Option<Vec<f64>>,
{
    let mut zp = z.to_vec();
    let mut zm = z.to_vec();
    zp[j] += h;
    zm[j] -= h;
    let fp = map(&zp)?;
    let fm = map(&zm)?;
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
/// are skipped.
fn column<F>(map: &F, z: &[f64], j: usize, h0: f64, f_scale: f64) -> Option<Column>
where
    F: Fn(&[f64]) -> Option<Vec<f64>>,
{
    let mut h = h0;
    let mut d_prev = central(map, z, j, h);
    let mut r_prev: Option<Vec<f64>> = None;
    let mut best: Option<Column> = None;
    for _ in 0..STEP_HALVINGS {
        h *= 0.5;
        let d = central(map, z, j, h);
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

/// The Jacobian of a map at `z` by central differences, Richardson-extrapolated,
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

/// [`Jacobian`] of `map` at `z`: column j's first step is `step_rel * scales[j]`; `map`
/// returns `None` where it is undefined (such steps are skipped).
pub fn jacobian<F>(
    map: F,
    z: &[f64],
    scales: &[f64],
    step_rel: f64,
) -> Result<Jacobian, &'static str>
where
    F: Fn(&[f64]) -> Option<Vec<f64>>,
{
    let n = z.len();
    let v = z.iter().fold(0.0f64, |m, x| m.max(x.abs())).max(1e-3);
    let f_scale = map(z)
        .ok_or("the map failed at the fixed point")?
        .iter()
        .fold(v, |m, x| m.max(x.abs()));
    let mut out = Jacobian {
        matrix: vec![vec![0.0; n]; n],
        coarse: vec![vec![0.0; n]; n],
        error: 0.0,
    };
    for (j, scale) in scales.iter().enumerate() {
        let (fine, coarse, err) = column(&map, z, j, step_rel * scale, f_scale)
            .ok_or("the map failed near the fixed point at every step")?;
        for i in 0..n {
            out.matrix[i][j] = fine[i];
            out.coarse[i][j] = coarse[i];
        }
        out.error = out.error.max(err);
    }
    Ok(out)
}

/// Match `predicted` one to one with `numeric` greedily by distance; the largest distance.
pub fn match_max_diff(predicted: &[(f64, f64)], numeric: &[Eigenvalue]) -> f64 {
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
pub fn sensitivity(m: &[Vec<f64>], eig: &[Eigenvalue], delta: f64) -> Result<f64, &'static str> {
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

/// The eigenvalues of `m` as (re, im) pairs ([`super::eigen::eigenvalues`]).
pub fn eigenvalues_of(m: &[Vec<f64>]) -> Result<Vec<(f64, f64)>, &'static str> {
    super::eigen::eigenvalues(m).ok_or("eigenvalue iteration did not converge")
}

/// The uncertainty of the eigenvalues `eig` of `jac` (module docs, "The verdict").
pub fn uncertainty(jac: &Jacobian, eig: &[Eigenvalue]) -> Result<f64, &'static str> {
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

/// The eigenvalues of `jac`, decreasing modulus, with their uncertainty (module docs).
pub fn spectrum(jac: &Jacobian) -> Result<(Vec<Eigenvalue>, f64), &'static str> {
    let mut eig: Vec<Eigenvalue> = eigenvalues_of(&jac.matrix)?
        .into_iter()
        .map(Eigenvalue::from_pair)
        .collect();
    eig.sort_by(|a, b| b.modulus.total_cmp(&a.modulus));
    let tol = uncertainty(jac, &eig)?;
    Ok((eig, tol))
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
