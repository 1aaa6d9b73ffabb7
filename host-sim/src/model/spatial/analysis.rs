//! Linearized stability of the spatial juggler's apex-to-apex map (Rizzi & Koditschek
//! sec. 4.2, eq. 17–21, carried to three dimensions), numerically, since eq. 13 has no
//! closed-form flight time.
//!
//! # The map and its fixed point
//!
//! Apex coordinates (eq. 17): `z = (b_x, b_y, b_z, b_x', b_y')` at the top of a flight
//! (b_z' = 0). One step is one bat and the rise to the next apex ([`apex_map`]). The fixed
//! point is `(rho* cos phi*, rho* sin phi*, h_fp, 0, 0)`, h_fp = v*^2 / (2 gamma) with v*
//! the line juggler's period-1 impact speed (`dexter_core::mirror`, eq. 8): on it the bar
//! meets the ball horizontally at the pivot's height, as in the planar juggler.
//! The Jacobian and its eigenvalues are the engine's ([`crate::engine::linearize`]).
//!
//! # What the eigenvalues are compared with
//!
//! The plane through the base at phi* is invariant and mirror-symmetric, so to first order the
//! map splits into three blocks: vertical (b_z), radial (rho, rho') and lateral (d, d').
//!
//! - **vertical**: eq. 8's slope `1 - (1 + alpha) kappa1 v*^2` (both laws).
//! - **lateral**: the roll q3 = l2 tilts the normal by q3 across the plane, so an impact
//!   adds `2 v* q3` to d' (the impulse's size at the fixed point is 2 v*); tau = t_a =
//!   v*/gamma after and before the apexes; `c0 = 2 v* kappa20`, `c1 = 2 v* kappa21`.
//!   Under eq. 13, l2 is read at the impact, and in impact coordinates the block is
//!   `[[1 + c0 T, T (1 + c1)], [c0, 1 + c1]]`, T = 2 v*/gamma: trace `2 + c0 T + c1`,
//!   determinant `1 + c1`. Under the modified law l2 is read at the apex (`w_bar`): the
//!   double integrator of eq. 21 below with (p, d) = (c0, c1).
//! - **radial, modified law**: eq. 21, the PD-compensated double integrator, in this law's
//!   terms: the bar meets the ball on the plane at elevation e_l ~ l/rho*, whose normal
//!   pushes the ball by `-2 v* e_l`, so `xi = -2 v*/rho*` (the paper's xi_2 = (1 + alpha)
//!   (1 + k) theta_b' at the fixed point), and
//!   `[rho, rho'](k+1) = [[1, 2 t_a], [0, 1]] [rho, rho'](k) + xi [t_a, 1] l`,
//!   `l = kappa10 (rho - rho*) + kappa11 rho'`. With (p, d) = (xi kappa10, xi kappa11): trace
//!   `2 + t_a p + d`, determinant `1 + d - t_a p`.
//! - **radial, eq. 13**: no closed form; the tests compare it with the planar juggler's map
//!   (eq. 12, independent code) linearized the same way.
//!
//! # Measured decay
//!
//! Independently of the Jacobian, [`measured`] runs the juggler from a small offset in each
//! block alone and fits its apex sequence: a ratio for the vertical block, and for the 2-D
//! blocks the two-term recurrence `s(n+2) = tr s(n+1) - det s(n)` that every coordinate of
//! a linear 2-D map obeys (Cayley–Hamilton), by least squares over [`FIT_BATS`] bats. Its
//! roots are the decay the simulation shows.

use super::{Law, SpatialJuggler, SpatialParams};
use crate::engine::linearize::{self, match_max_diff, Eigenvalue, Verdict, STEP_REL};
use dexter_core::mirror::MirrorLaw;
use dexter_core::spatial::SpatialBall;
use serde::Serialize;

/// Bats fitted by [`measured`].
pub const FIT_BATS: usize = 24;
/// Relative offset of each block's start in [`measured`] (of rho* for the horizontal blocks,
/// of h_fp for the vertical).
pub const FIT_OFFSET: f64 = 1e-5;

/// The apex-to-apex map (module docs): `None` if the bat fails.
pub fn apex_map(juggler: &SpatialJuggler, z: &[f64]) -> Option<Vec<f64>> {
    let start = SpatialBall::new([z[0], z[1], z[2]], [z[3], z[4], 0.0]);
    let bat = *juggler.run(start, 1).bats.first()?;
    let [x, y, h] = bat.apex_m;
    Some(vec![x, y, h, bat.after[3], bat.after[4]])
}

/// The fixed point's impact speed v* (eq. 8, `dexter_core::mirror`), m/s.
fn impact_speed_mps(p: &SpatialParams) -> Result<f64, &'static str> {
    let l = &p.law;
    MirrorLaw::new(l.kappa0, l.kappa1_s2pm2, l.target_apex_m, l.gravity_mps2)
        .ok()
        .and_then(|m| m.fixed_point_speed_mps(p.restitution))
        .ok_or("eq. 8 has no positive period-1 orbit for these gains")
}

/// The eigenvalues of a 2 x 2 block from its trace and determinant, (re, im).
pub fn pair(trace: f64, det: f64) -> [(f64, f64); 2] {
    let (m, disc) = (0.5 * trace, 0.25 * trace * trace - det);
    if disc >= 0.0 {
        [(m + disc.sqrt(), 0.0), (m - disc.sqrt(), 0.0)]
    } else {
        [(m, (-disc).sqrt()), (m, -(-disc).sqrt())]
    }
}

/// The double integrator kicked at each impact by `p x + d x'` of the apex before it
/// (eq. 21): `[x, x'](k+1) = [[1, 2 t_a], [0, 1]] [x, x'](k) + [t_a, 1] (p x + d x')`, trace
/// `2 + t_a p + d`, determinant `1 + d - t_a p`.
fn apex_pd_pair(t_a: f64, p: f64, d: f64) -> [(f64, f64); 2] {
    pair(2.0 + t_a * p + d, 1.0 + d - t_a * p)
}

/// The closed forms of the module docs.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct ClosedForms {
    /// v*, m/s.
    pub impact_speed_mps: f64,
    /// eq. 8's slope, the vertical eigenvalue.
    pub vertical: f64,
    /// The lateral pair, (re, im).
    pub lateral: [(f64, f64); 2],
    /// The radial pair of the modified law (eq. 21), (re, im); `None` for eq. 13.
    pub radial_modified: Option<[(f64, f64); 2]>,
}

impl ClosedForms {
    /// The closed forms for `p` under `law`.
    pub fn of(p: &SpatialParams, law: Law) -> Result<Self, &'static str> {
        let l = &p.law;
        let v = impact_speed_mps(p)?;
        let g = l.gravity_mps2;
        let (t_a, period) = (v / g, 2.0 * v / g);
        let (c0, c1) = (2.0 * v * l.kappa20_radpm, 2.0 * v * l.kappa21_radspm);
        let xi = -2.0 * v / l.target_radius_m;
        Ok(Self {
            impact_speed_mps: v,
            vertical: 1.0 - (1.0 + p.restitution) * l.kappa1_s2pm2 * v * v,
            lateral: match law {
                Law::Mirror => pair(2.0 + c0 * period + c1, 1.0 + c1),
                Law::Modified => apex_pd_pair(t_a, c0, c1),
            },
            radial_modified: (law == Law::Modified)
                .then(|| apex_pd_pair(t_a, xi * l.kappa10, xi * l.kappa11)),
        })
    }

    /// Every predicted eigenvalue.
    fn predicted(&self) -> Vec<(f64, f64)> {
        let mut v = vec![(self.vertical, 0.0)];
        v.extend(self.lateral);
        v.extend(self.radial_modified.into_iter().flatten());
        v
    }
}

/// The decay measured in simulation, block by block (module docs).
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Measured {
    /// The vertical block's ratio.
    pub vertical: f64,
    /// The radial pair, (re, im).
    pub radial: [(f64, f64); 2],
    /// The lateral pair, (re, im).
    pub lateral: [(f64, f64); 2],
}

impl Measured {
    /// All five, (re, im).
    pub fn all(&self) -> Vec<(f64, f64)> {
        let mut v = vec![(self.vertical, 0.0)];
        v.extend(self.radial);
        v.extend(self.lateral);
        v
    }

    /// The largest modulus.
    pub fn spectral_radius(&self) -> f64 {
        self.all()
            .iter()
            .fold(0.0, |m, (re, im)| m.max(re.hypot(*im)))
    }
}

/// Least-squares fit of `s(n+2) = tr s(n+1) - det s(n)`: (tr, det).
fn fit_recurrence(s: &[f64]) -> (f64, f64) {
    let (mut a11, mut a12, mut a22, mut b1, mut b2) = (0.0, 0.0, 0.0, 0.0, 0.0);
    for w in s.windows(3) {
        let (x1, x2, y) = (w[1], -w[0], w[2]);
        a11 += x1 * x1;
        a12 += x1 * x2;
        a22 += x2 * x2;
        b1 += x1 * y;
        b2 += x2 * y;
    }
    let det = a11 * a22 - a12 * a12;
    ((b1 * a22 - b2 * a12) / det, (a11 * b2 - a12 * b1) / det)
}

/// Run from `start` (an apex) and return each apex's offset along `probe`.
fn sequence(
    juggler: &SpatialJuggler,
    start: &[f64],
    probe: impl Fn(&[f64]) -> f64,
) -> Result<Vec<f64>, &'static str> {
    let ball = SpatialBall::new([start[0], start[1], start[2]], [start[3], start[4], 0.0]);
    let run = juggler.run(ball, FIT_BATS);
    if run.bats.len() < FIT_BATS {
        return Err("the measured run ended early");
    }
    let mut s = vec![probe(start)];
    s.extend(run.bats.iter().map(|b| {
        let [x, y, z] = b.apex_m;
        probe(&[x, y, z, b.after[3], b.after[4]])
    }));
    Ok(s)
}

/// The decay of each block measured from runs offset from the fixed point `fp` (module docs).
pub fn measured(
    juggler: &SpatialJuggler,
    p: &SpatialParams,
    fp: &[f64],
) -> Result<Measured, &'static str> {
    let l = &p.law;
    let (s, c) = l.target_azimuth_rad.sin_cos();
    let offset = FIT_OFFSET * l.target_radius_m;
    let shifted = |dx: f64, dy: f64, dz: f64| {
        let mut z = fp.to_vec();
        (z[0], z[1], z[2]) = (z[0] + dx, z[1] + dy, z[2] + dz);
        z
    };
    let rho = |z: &[f64]| z[0] * c + z[1] * s - l.target_radius_m;
    let d = |z: &[f64]| z[1] * c - z[0] * s;
    let h = |z: &[f64]| z[2] - fp[2];
    let radial = sequence(juggler, &shifted(offset * c, offset * s, 0.0), rho)?;
    let lateral = sequence(juggler, &shifted(-offset * s, offset * c, 0.0), d)?;
    let vertical = sequence(juggler, &shifted(0.0, 0.0, FIT_OFFSET * fp[2]), h)?;
    let ratio = vertical.windows(2).map(|w| w[0] * w[1]).sum::<f64>()
        / vertical[..FIT_BATS].iter().map(|x| x * x).sum::<f64>();
    let (rt, rd) = fit_recurrence(&radial);
    let (lt, ld) = fit_recurrence(&lateral);
    Ok(Measured {
        vertical: ratio,
        radial: pair(rt, rd),
        lateral: pair(lt, ld),
    })
}

/// The result of [`analyze`].
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct SpatialAnalysis {
    /// The fixed point (b_x, b_y, b_z, b_x', b_y'), m and m/s.
    pub fixed_point: Vec<f64>,
    /// max |F(z*) - z*|.
    pub fixed_point_residual: f64,
    /// dF/dz at z*, rows.
    pub jacobian: Vec<Vec<f64>>,
    /// Estimated max abs error of its entries.
    pub jacobian_error: f64,
    /// Eigenvalues, decreasing modulus.
    pub eigenvalues: Vec<Eigenvalue>,
    /// Their uncertainty ([`crate::engine::linearize`], "The verdict").
    pub eigenvalue_tolerance: f64,
    /// Verdict from the moduli.
    pub verdict: Verdict,
    /// The closed forms.
    pub closed_forms: ClosedForms,
    /// Largest distance from a closed-form eigenvalue to its numerical match.
    pub closed_form_max_abs_diff: f64,
    /// The decay measured in simulation.
    pub measured: Measured,
    /// Largest distance from a measured eigenvalue to its numerical match.
    pub measured_max_abs_diff: f64,
    /// |measured spectral radius / linearization's - 1|.
    pub spectral_radius_rel_diff: f64,
}

/// Linearize the apex map of the juggler of `p` under `law` at its fixed point, compare with
/// the closed forms and with the decay measured in simulation (module docs).
pub fn analyze(p: &SpatialParams, law: Law) -> Result<SpatialAnalysis, &'static str> {
    let juggler = p.juggler(law).map_err(|_| "invalid parameters")?;
    let cf = ClosedForms::of(p, law)?;
    let l = &p.law;
    let (s, c) = l.target_azimuth_rad.sin_cos();
    let h = cf.impact_speed_mps.powi(2) / (2.0 * l.gravity_mps2);
    let fp = vec![l.target_radius_m * c, l.target_radius_m * s, h, 0.0, 0.0];
    let map = |z: &[f64]| apex_map(&juggler, z);
    let fz = map(&fp).ok_or("the bat fails at the fixed point")?;
    let residual = fz
        .iter()
        .zip(&fp)
        .fold(0.0f64, |m, (a, b)| m.max((a - b).abs()));
    let v = cf.impact_speed_mps;
    let scales = [l.target_radius_m, l.target_radius_m, h, v, v];
    let jac = linearize::jacobian(map, &fp, &scales, STEP_REL)?;
    let (eigenvalues, tol) = linearize::spectrum(&jac)?;
    let max_mod = eigenvalues.first().map_or(0.0, |e| e.modulus);
    let measured = measured(&juggler, p, &fp)?;
    Ok(SpatialAnalysis {
        fixed_point_residual: residual,
        fixed_point: fp,
        jacobian: jac.matrix,
        jacobian_error: jac.error,
        closed_form_max_abs_diff: match_max_diff(&cf.predicted(), &eigenvalues),
        measured_max_abs_diff: match_max_diff(&measured.all(), &eigenvalues),
        spectral_radius_rel_diff: (measured.spectral_radius() / max_mod - 1.0).abs(),
        eigenvalues,
        eigenvalue_tolerance: tol,
        verdict: Verdict::of(max_mod, tol),
        closed_forms: cf,
        measured,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::planar::juggler::JugglerParams;
    use crate::model::spatial::tests::planar_twin;
    use dexter_core::planar::PlanarBall;
    use dexter_core::spatial::SpatialLawParams;

    fn modified_params() -> SpatialParams {
        let p = SpatialParams::default();
        SpatialParams {
            law: SpatialLawParams {
                kappa10: 0.12,
                kappa11: 0.08,
                ..p.law
            },
            ..p
        }
    }

    fn cases() -> [(Law, SpatialParams); 2] {
        [
            (Law::Mirror, SpatialParams::default()),
            (Law::Modified, modified_params()),
        ]
    }

    /// The planar juggler's apex map (x, z, x') linearized: independent code (eq. 12, 15).
    fn planar_eigenvalues(p: &JugglerParams, law: Law, h: f64) -> Vec<(f64, f64)> {
        let j = match law {
            Law::Mirror => p.mirror(),
            Law::Modified => p.modified(),
        }
        .unwrap();
        let map = |z: &[f64]| {
            let bat = *j
                .run(PlanarBall::new(z[0], z[1], z[2], 0.0), 1)
                .bats
                .first()?;
            Some(vec![bat.apex[0], bat.apex[1], bat.after[2]])
        };
        let fp = [p.target_x_m, h, 0.0];
        let jac = linearize::jacobian(map, &fp, &[1.0, h, 1.0], STEP_REL).unwrap();
        linearize::eigenvalues_of(&jac.matrix).unwrap()
    }

    /// The linearization's eigenvalues equal the closed forms (eq. 8's slope, the lateral
    /// double integrator, eq. 21 for the modified law), the planar juggler's own (the
    /// vertical and radial blocks are the planar juggler's map, independent code), and the
    /// decay measured in simulation: the spectral radius to 1 % (issue 28).
    #[test]
    fn eigenvalues_match_closed_forms_the_planar_juggler_and_the_measured_decay() {
        for (law, p) in cases() {
            let a = analyze(&p, law).unwrap();
            assert!(
                a.fixed_point_residual < 1e-12,
                "{law:?}: {}",
                a.fixed_point_residual
            );
            assert!(a.closed_form_max_abs_diff < 1e-6, "{law:?}: {a:#?}");
            // eq. 13's -l1 negates the radial gains against eq. 12; the modified laws agree
            let twin = match law {
                Law::Mirror => planar_twin(&p),
                Law::Modified => JugglerParams {
                    kappa10: p.law.kappa10,
                    kappa11: p.law.kappa11,
                    ..planar_twin(&p)
                },
            };
            let planar = planar_eigenvalues(&twin, law, a.fixed_point[2]);
            let d = match_max_diff(&planar, &a.eigenvalues);
            assert!(
                d < 1e-6,
                "{law:?}: planar {planar:?} vs {:?}",
                a.eigenvalues
            );
            assert!(a.spectral_radius_rel_diff < 0.01, "{law:?}: {a:#?}");
            assert!(a.measured_max_abs_diff < 0.01, "{law:?}: {a:#?}");
            assert_eq!(a.verdict, Verdict::AsymptoticallyStable, "{law:?}");
        }
    }

    /// The blocks by hand at the defaults: the lateral pair 0.5 +- 0.5i (half deadbeat:
    /// c1 = -1/2, c0 T = -1/2), the vertical slope 1/2 (kappa1 at half of 1/((1+alpha) v*^2)).
    #[test]
    fn default_blocks_by_hand() {
        let cf = ClosedForms::of(&SpatialParams::default(), Law::Mirror).unwrap();
        assert!((cf.vertical - 0.5).abs() < 1e-12);
        for ((re, im), want) in cf.lateral.iter().zip([0.5, -0.5]) {
            assert!(
                (re - 0.5).abs() < 1e-12 && (im - want).abs() < 1e-12,
                "{cf:?}"
            );
        }
    }

    /// Turning the set point about z changes no eigenvalue.
    #[test]
    fn the_set_point_azimuth_changes_no_eigenvalue() {
        let p = SpatialParams::default();
        let turned = SpatialParams {
            law: SpatialLawParams {
                target_azimuth_rad: 2.0,
                ..p.law
            },
            ..p
        };
        let (a, b) = (
            analyze(&p, Law::Mirror).unwrap(),
            analyze(&turned, Law::Mirror).unwrap(),
        );
        let pairs: Vec<(f64, f64)> = a.eigenvalues.iter().map(|e| (e.re, e.im)).collect();
        assert!(match_max_diff(&pairs, &b.eigenvalues) < 1e-6);
    }

    /// A flipped lateral or radial gain: the linearization says unstable.
    #[test]
    fn a_flipped_gain_is_unstable() {
        for (law, p) in cases() {
            for flip in [0, 1] {
                let mut q = p;
                if flip == 0 {
                    q.law.kappa21_radspm = -q.law.kappa21_radspm;
                } else {
                    q.law.kappa10 = -q.law.kappa10;
                    q.law.kappa11 = -q.law.kappa11;
                }
                let v = analyze(&q, law).map(|a| a.verdict);
                assert!(
                    v.is_err() || v == Ok(Verdict::Unstable),
                    "{law:?} {flip}: {v:?}"
                );
            }
        }
    }
}
