//! The planar bouncing body (issue 5) against the closed forms of Zumel & Erdmann from
//! `dexter_core::tilt` and against computations written here from the paper's equations
//! (the reflection of eq. 1 in the table frame, a brute-force search of the eq. 7 gap, the
//! impulse-momentum balance of a frictional impact). No expected value is copied from the
//! simulator's own output.

use dexter_core::params::ParamError;
use dexter_core::planar::PlanarBall;
use dexter_core::tilt::{
    energy_eigenvalue, impact as core_impact, impact_normal, kappa_crit, point_mass_angle_after,
    tilt_eigenvalues,
};
use dexter_sim::engine::eigen::eigenvalues;
use dexter_sim::model::planar::analysis::{analyze, Verdict};
use dexter_sim::model::planar::contact::{first_contact, Gap};
use dexter_sim::model::planar::impact::{coulomb, FrictionMode, ImpactGeometry};
use dexter_sim::model::planar::juggler::JugglerParams;
use dexter_sim::model::planar::stats::{classify, stability_map, CellClass};
use dexter_sim::model::planar::{PlanarError, PlanarParams, RunEnd};

const G: f64 = 9.81;
/// The triangle's rho "as stated" and l = 2/3 of its 20 cm height (sec. 2.3).
const RHO: f64 = 0.094_28;
const L: f64 = 0.133_333_333_333;

fn scene(name: &str) -> PlanarParams {
    let path = format!(
        "{}/../scenes/planar-{name}.toml",
        env!("CARGO_MANIFEST_DIR")
    );
    PlanarParams::from_toml_str(&std::fs::read_to_string(path).unwrap()).unwrap()
}

/// A small deterministic generator for test inputs (64-bit LCG, top 53 bits).
struct Lcg(u64);
impl Lcg {
    fn next(&mut self) -> f64 {
        self.0 = self
            .0
            .wrapping_mul(6_364_136_223_846_793_005)
            .wrapping_add(1_442_695_040_888_963_407);
        (self.0 >> 11) as f64 / (1u64 << 53) as f64
    }
    fn range(&mut self, lo: f64, hi: f64) -> f64 {
        lo + (hi - lo) * self.next()
    }
}

// ---------------------------------------------------------------- point mass, eq. 3–4

#[test]
fn point_mass_lossless_angle_follows_eq4() {
    // theta_n = (1 - 2 kappa)^n theta_0, theta = angle of the incoming velocity to the vertical
    let mut worst = 0.0f64;
    for &kappa in &[0.1, 0.3, 0.45, 0.8] {
        let mut p = scene("point-mass");
        p.kappa = kappa;
        let run = p.simulate().unwrap();
        assert_eq!(run.end, RunEnd::Completed);
        let angle = |r: &dexter_sim::model::planar::ImpactRecord| {
            r.before.x_dot_mps.atan2(-r.before.y_dot_mps)
        };
        let theta0 = angle(&run.impacts[0]);
        // independent: the drop from 0.5 m with x' = 0.4 hits at atan(0.4 / sqrt(2 G 0.5))
        assert!((theta0 - (0.4f64 / (2.0 * G * 0.5).sqrt()).atan()).abs() < 1e-15);
        for r in &run.impacts {
            let expected = point_mass_angle_after(theta0, kappa, r.index as u32);
            let d = (angle(r) - expected).abs();
            worst = worst.max(d);
            assert!(d <= 1e-12, "kappa {kappa} n {}: {d:e}", r.index);
        }
    }
    println!("point mass eq. 4: max |theta_n - (1-2k)^n theta_0| = {worst:e}");
}

// ------------------------------------------------------------- analyze vs eq. 11/16/26

/// The lossless scene's y*: drop from y0 = 0.25 m, eta* = G y0, y*^2 = 2 G (y0 - l) (eq. 8).
fn lossless_y_star() -> f64 {
    -(2.0 * G * (0.25 - L)).sqrt()
}

fn lossless(kappa: f64) -> dexter_sim::model::planar::PlanarModel {
    let mut p = scene("lossless");
    p.kappa = kappa;
    p.build().unwrap()
}

/// Distance from each closed-form eigenvalue to the nearest numerical one.
fn nearest(report: &[dexter_sim::model::planar::analysis::Eigenvalue], z: (f64, f64)) -> f64 {
    report
        .iter()
        .map(|e| (e.re - z.0).hypot(e.im - z.1))
        .fold(f64::INFINITY, f64::min)
}

#[test]
fn analyze_matches_eq11_in_all_three_regimes() {
    let y = lossless_y_star();
    let kc = kappa_crit(G, RHO, L, y, 1.0);
    assert!(kc > 1.2, "kappa_crit {kc}");
    for (kappa, regime) in [
        (0.8, "below 1"),
        (0.5 * (1.0 + kc), "between"),
        (kc + 0.2, "above"),
    ] {
        let r = analyze(&lossless(kappa)).unwrap();
        assert!((r.params.impact_velocity_mps - y).abs() < 1e-14);
        assert!(r.fixed_point_residual < 1e-14);
        let [a, b] = tilt_eigenvalues(kappa, G, RHO, L, y);
        let diff = nearest(&r.eigenvalues, a).max(nearest(&r.eigenvalues, b));
        println!(
            "analyze vs eq. 11, kappa = {kappa:.4} ({regime}): max |diff| = {diff:.2e}, jacobian error {:.1e}",
            r.jacobian_error
        );
        assert!(diff <= 1e-6, "{regime}: {diff:e}");
        assert!(r.closed_form_max_abs_diff <= 1e-6);
        // the other two: 1 (x') and 1 (y', lossless)
        assert!(nearest(&r.eigenvalues, (1.0, 0.0)) < 1e-6);
        let pair: Vec<_> = r
            .eigenvalues
            .iter()
            .filter(|e| (e.re - 1.0).hypot(e.im) > 1e-3)
            .collect();
        assert_eq!(pair.len(), 2, "{regime}");
        match regime {
            "below 1" => {
                assert!(pair.iter().all(|e| e.im == 0.0));
                assert!(pair[0].modulus > 1.0 && pair[1].modulus < 1.0);
                assert_eq!(r.verdict, Verdict::Unstable);
            }
            "between" => {
                assert!(pair
                    .iter()
                    .all(|e| e.im != 0.0 && (e.modulus - 1.0).abs() < 1e-6));
                assert_eq!(r.verdict, Verdict::Marginal);
            }
            _ => {
                assert!(pair.iter().all(|e| e.im == 0.0 && e.re < 0.0));
                assert!(pair[0].modulus > 1.0);
                assert_eq!(r.verdict, Verdict::Unstable);
            }
        }
    }
}

/// The verdict in every regime of eq. 11 / 16, to very large gains (the issue: at
/// kappa = 100 the tolerance grew with the Jacobian's error and an eigenvalue of -1384 was
/// called "marginal"): the verdict is the closed form's, and every closed-form eigenvalue
/// lies within the reported uncertainty of a numerical one (the uncertainty is honest).
#[test]
fn verdict_is_the_closed_forms_in_every_regime_and_at_large_gains() {
    let y = lossless_y_star();
    let kc = kappa_crit(G, RHO, L, y, 1.0);
    let cases = [
        (0.3, Verdict::Unstable),
        (0.9, Verdict::Unstable),
        (1.05, Verdict::Marginal),
        (0.5 * (1.0 + kc), Verdict::Marginal),
        (kc + 0.01, Verdict::Unstable),
        (2.0, Verdict::Unstable),
        (10.0, Verdict::Unstable),
        (100.0, Verdict::Unstable),
        (1e4, Verdict::Unstable),
        (1e6, Verdict::Unstable),
    ];
    for (kappa, want) in cases {
        let r = analyze(&lossless(kappa)).unwrap();
        let [a, b] = tilt_eigenvalues(kappa, G, RHO, L, y);
        // closed form: the modulus of the tilt pair decides (the other two are 1)
        let closed = a.0.hypot(a.1).max(b.0.hypot(b.1));
        let tol = r.verdict_tolerance;
        println!(
            "kappa {kappa:e}: closed-form max |lambda| {closed:.10}, verdict {:?}, uncertainty {tol:.1e}",
            r.verdict
        );
        assert_eq!(r.verdict, want, "kappa {kappa}");
        for z in [a, b, (1.0, 0.0)] {
            let d = nearest(&r.eigenvalues, z);
            assert!(
                d <= tol,
                "kappa {kappa}: {z:?} is {d:e} from the nearest, uncertainty {tol:e}"
            );
        }
        // the dominant eigenvalue itself to 1e-8 relative
        let big = if a.0.hypot(a.1) >= b.0.hypot(b.1) {
            a
        } else {
            b
        };
        assert!(
            nearest(&r.eigenvalues, big) <= 1e-8 * big.0.hypot(big.1),
            "kappa {kappa}"
        );
    }
    // exactly at kappa = 1 the eigenvalue 1 is 4-fold and defective: no verdict is claimed
    // that the linearization cannot support
    let r = analyze(&lossless(1.0)).unwrap();
    assert_ne!(r.verdict, Verdict::AsymptoticallyStable);
    assert!(r.verdict_tolerance >= 1e-4, "{}", r.verdict_tolerance);
}

#[test]
fn eigenvalues_change_type_at_kappa_one_and_kappa_crit() {
    let y = lossless_y_star();
    let kc = kappa_crit(G, RHO, L, y, 1.0);
    let pair = |kappa: f64| {
        let r = analyze(&lossless(kappa)).unwrap();
        let [a, b] = tilt_eigenvalues(kappa, G, RHO, L, y);
        (r, a, b)
    };
    let d = 1e-3;
    // just below / above 1: real (one outside) -> complex on the unit circle
    let (r, a, _) = pair(1.0 - d);
    assert!(a.1 == 0.0 && a.0 > 1.0 && nearest(&r.eigenvalues, a) < 1e-6);
    assert_eq!(r.verdict, Verdict::Unstable);
    let (r, a, _) = pair(1.0 + d);
    assert!(a.1 > 0.0 && nearest(&r.eigenvalues, a) < 1e-6);
    assert_eq!(r.verdict, Verdict::Marginal);
    // just below / above kappa_crit: complex -> real, one below -1
    let (r, a, _) = pair(kc - d);
    assert!(a.1 > 0.0 && nearest(&r.eigenvalues, a) < 1e-6);
    let (r, a, _) = pair(kc + d);
    assert!(a.1 == 0.0 && a.0 < -1.0 && nearest(&r.eigenvalues, a) < 1e-6);
    assert_eq!(r.verdict, Verdict::Unstable);
    // exactly at 1 and kappa_crit: the eigenvalue 1 is 4-fold at kappa = 1 and -1 double at
    // kappa_crit, both defective: a Jacobian error eps moves them by ~eps^(1/4) resp.
    // eps^(1/2) (eps ~ 3e-11 here: 2e-3 resp. 6e-6)
    let (r, _, _) = pair(1.0);
    assert!(r
        .eigenvalues
        .iter()
        .all(|e| (e.re - 1.0).hypot(e.im) < 2e-3));
    let (r, _, _) = pair(kc);
    let minus: Vec<_> = r
        .eigenvalues
        .iter()
        .filter(|e| (e.re + 1.0).hypot(e.im) < 1e-4)
        .collect();
    assert_eq!(minus.len(), 2, "{:?}", r.eigenvalues);
}

#[test]
fn triangle_linearization_energy_eigenvalue_and_eq26() {
    // e = 0.5, kappa_E = 0.165, eta* = G 0.25: y*^2 = 2 G (0.25 - l)
    let m = scene("triangle").build().unwrap();
    let r = analyze(&m).unwrap();
    let y = -(2.0 * G * (0.25 - L)).sqrt();
    assert!((r.params.impact_velocity_mps - y).abs() < 1e-14);
    let [a, b] = tilt_eigenvalues(1.1, G, RHO, L, y);
    let le = energy_eigenvalue(0.165, 0.5, y);
    let diff = [a, b, (le, 0.0), (1.0, 0.0)]
        .iter()
        .map(|&z| nearest(&r.eigenvalues, z))
        .fold(0.0, f64::max);
    println!("triangle (e = 0.5): max |diff| vs eq. 11 + energy eigenvalue = {diff:.2e}");
    assert!(diff < 1e-6);
    // eq. 26 vs eq. 16: with the compensation of eq. 25 the tilt pair is eq. 11 for any e, so
    // it turns real at eq. 16's kappa_crit. Midway between the two the map is unstable
    // although eq. 26 would call it stable.
    let k16 = kappa_crit(G, RHO, L, y, 1.0);
    let k26 = kappa_crit(G, RHO, L, y, 0.5);
    assert!(k26 > k16 + 0.05);
    let mut p = scene("triangle");
    p.kappa = 0.5 * (k16 + k26);
    let r = analyze(&p.build().unwrap()).unwrap();
    assert_eq!(r.verdict, Verdict::Unstable);
    assert!(r.eigenvalues.iter().any(|e| e.re < -1.0 && e.im == 0.0));
}

#[test]
fn analyze_report_json_has_parameters_and_eigen_pairs() {
    let r = analyze(&scene("triangle").build().unwrap()).unwrap();
    let v = serde_json::to_value(&r).unwrap();
    for key in [
        "rho_m",
        "l_m",
        "impact_velocity_mps",
        "kappa",
        "kappa_e_s2pm2",
        "restitution",
        "gravity_mps2",
    ] {
        assert!(v["params"][key].is_number(), "{key}");
    }
    assert_eq!(v["eigenvalues"].as_array().unwrap().len(), 4);
    assert!(v["eigenvalues"][0]["re"].is_number() && v["eigenvalues"][0]["im"].is_number());
    assert_eq!(v["verdict"], "marginal");
}

#[test]
fn eigen_solver_on_known_matrices() {
    // block diag(rotation by 0.7 scaled by 1.5, 3, -0.25): 1.5 e^{±0.7 i}, 3, -0.25
    let (c, s) = (1.5 * 0.7f64.cos(), 1.5 * 0.7f64.sin());
    let m = [
        [c, -s, 0.0, 0.0],
        [s, c, 0.0, 0.0],
        [0.0, 0.0, 3.0, 0.0],
        [0.0, 0.0, 0.0, -0.25],
    ];
    // similarity by an upper-triangular T (T^-1 by hand) so the matrix is not block diagonal
    let t = [
        [1.0, 2.0, 0.0, 1.0],
        [0.0, 1.0, 3.0, 0.0],
        [0.0, 0.0, 1.0, -1.0],
        [0.0, 0.0, 0.0, 1.0],
    ];
    let ti = [
        [1.0, -2.0, 6.0, 5.0],
        [0.0, 1.0, -3.0, -3.0],
        [0.0, 0.0, 1.0, 1.0],
        [0.0, 0.0, 0.0, 1.0],
    ];
    let mut a = vec![vec![0.0; 4]; 4];
    for i in 0..4 {
        for j in 0..4 {
            for p in 0..4 {
                for q in 0..4 {
                    a[i][j] += t[i][p] * m[p][q] * ti[q][j];
                }
            }
        }
    }
    let ev = eigenvalues(&a).unwrap();
    let want = [(3.0, 0.0), (c, s), (c, -s), (-0.25, 0.0)];
    for (got, w) in ev.iter().zip(want) {
        assert!(
            (got.0 - w.0).abs() < 1e-12 && (got.1 - w.1).abs() < 1e-12,
            "{ev:?}"
        );
    }
}

// ------------------------------------------------------------------ the triangle, fig. 4–5

#[test]
fn triangle_stays_upright_and_converges_to_target_energy() {
    let p = scene("triangle");
    let m = p.build().unwrap();
    let run = p.simulate().unwrap();
    assert_eq!(run.end, RunEnd::Completed);
    assert_eq!(run.impacts.len(), 300);
    let eta_star = G * 0.25;
    assert!((m.feedback.target_energy_jpkg() - eta_star).abs() < 1e-14);
    let mean = |a: usize, b: usize| {
        run.impacts[a..b].iter().map(|r| r.energy_jpkg).sum::<f64>() / (b - a) as f64
    };
    let (m1, m2) = (mean(100, 200), mean(200, 300));
    println!(
        "triangle: first eta {:.4}, mean eta over impacts 100-199 {m1:.5}, 200-299 {m2:.5}, eta* {eta_star:.5}",
        run.impacts[0].energy_jpkg
    );
    // the first impact is at the drop energy G * 0.2, 20% below the target
    assert!((run.impacts[0].energy_jpkg - G * 0.2).abs() < 1e-12);
    assert!((m2 - eta_star).abs() < 0.01 * eta_star);
    assert!((m2 - m1).abs() < 1e-3 * eta_star);
    let max_theta = run
        .impacts
        .iter()
        .fold(0.0f64, |a, r| a.max(r.before.theta_rad.abs()));
    assert!(max_theta < 0.45, "{max_theta}");
    assert_eq!(classify(&m, &run), CellClass::Converges);
    // theta - theta' projection centred on the origin (fig. 4): mean theta near 0
    let mt = run.impacts.iter().map(|r| r.before.theta_rad).sum::<f64>() / 300.0;
    assert!(mt.abs() < 0.05);
}

#[test]
fn triangle_with_timing_noise_stays_upright() {
    let p = scene("triangle-noise");
    let m = p.build().unwrap();
    let run = p.simulate().unwrap();
    assert_eq!(run.end, RunEnd::Completed);
    let late = &run.impacts[200..];
    let mean = late.iter().map(|r| r.energy_jpkg).sum::<f64>() / late.len() as f64;
    let eta_star = m.feedback.target_energy_jpkg();
    assert!((mean - eta_star).abs() < 0.03 * eta_star, "{mean}");
    // the noise moves impacts off the line y = 0 (the paper: "as well as the y-height")
    let spread = run
        .impacts
        .iter()
        .map(|r| r.before.contact_point(L)[1].abs())
        .fold(0.0, f64::max);
    assert!(spread > 1e-3);
    // over seeds: most runs stay up for 300 impacts
    let survive = (1..=20u64)
        .filter(|&seed| {
            let mut q = p.clone();
            q.seed = seed;
            q.simulate().unwrap().end == RunEnd::Completed
        })
        .count();
    println!("triangle with 10 ms noise: {survive}/20 seeds upright for 300 impacts");
    assert!(survive >= 14);
}

// ----------------------------------------------------------------------------- friction

#[test]
fn friction_defeats_the_tilt_law() {
    // mu = 0: stays up; any tested mu > 0: loses the body within a few impacts
    let mut p = scene("friction");
    p.friction_mu = 0.0;
    assert_eq!(p.simulate().unwrap().end, RunEnd::Completed);
    for &mu in &[0.02, 0.05, 0.1, 0.3, 0.5, 1.0] {
        p.friction_mu = mu;
        let run = p.simulate().unwrap();
        println!(
            "friction mu = {mu}: {:?} after {} impacts",
            run.end,
            run.impacts.len()
        );
        assert!(
            matches!(run.end, RunEnd::TippedOver | RunEnd::NoSeparation),
            "mu {mu}: {:?}",
            run.end
        );
        assert!(run.impacts.len() < 20);
    }
    // the mechanism of eq. 27 at the first impact: beta = (1 - kappa) theta is small, so the
    // friction moment mu P_n l cos(beta) outweighs the normal moment P_n l sin(beta)
    let (theta, alpha) = (0.3f64, 1.1 * 0.3);
    let beta = theta - alpha;
    let v = [0.0, -(2.0 * G * (0.2 - L * theta.cos())).sqrt(), 0.0];
    let table = [0.0, -(1.0 / 3.0 + 0.165 * (G * 0.25 - G * 0.2)) * v[1]];
    let geo = ImpactGeometry { rho_m: RHO, l_m: L };
    let r = coulomb(geo, theta, v, alpha, table, 0.5, 0.1).unwrap();
    let normal_moment = r.normal_impulse_mps * L * beta.sin();
    let friction_moment = r.tangential_impulse_mps * L * beta.cos();
    assert!(friction_moment.abs() > normal_moment.abs());
}

#[test]
fn coulomb_impact_limits_and_invariants() {
    let geo = ImpactGeometry { rho_m: RHO, l_m: L };
    let mut rng = Lcg(11);
    for _ in 0..500 {
        let theta = rng.range(-0.8, 0.8);
        let alpha = rng.range(-0.5, 0.5);
        let v = [
            rng.range(-2.0, 2.0),
            rng.range(-3.0, -0.5),
            rng.range(-5.0, 5.0),
        ];
        let e = rng.range(0.0, 1.0);
        // contact velocity along the table normal must be closing for a real impact
        let (st, ct) = theta.sin_cos();
        let vc = [v[0] + L * v[2] * ct, v[1] + L * v[2] * st];
        let un = -alpha.sin() * vc[0] + alpha.cos() * vc[1];
        if un >= 0.0 {
            continue;
        }
        // mu = 0 is eq. 21 (the core's impact, normal of eq. 2)
        let r0 = coulomb(geo, theta, v, alpha, [0.0, 0.0], e, 0.0).unwrap();
        let c = core_impact(
            [v[0], v[1], RHO * v[2]],
            [0.0, 0.0],
            impact_normal(alpha, theta, L, RHO),
            e,
        );
        assert!((r0.velocity[0] - c[0]).abs() < 1e-12);
        assert!((r0.velocity[1] - c[1]).abs() < 1e-12);
        assert!((RHO * r0.velocity[2] - c[2]).abs() < 1e-12);
        let ke = |w: [f64; 3]| 0.5 * (w[0] * w[0] + w[1] * w[1] + RHO * RHO * w[2] * w[2]);
        for &mu in &[0.05, 0.3, 1.0, 5.0] {
            let r = match coulomb(geo, theta, v, alpha, [0.0, 0.0], e, mu) {
                Ok(r) => r,
                Err(_) => continue, // Painlevé jam: reported, not an energy question
            };
            // never creates energy against a resting table
            assert!(ke(r.velocity) <= ke(v) * (1.0 + 1e-12), "mu {mu}");
            // within the friction cone
            assert!(r.tangential_impulse_mps.abs() <= mu * r.normal_impulse_mps * (1.0 + 1e-12));
            // impulse-momentum: the velocity change is the impulse; the spin change its moment
            let (sa, ca) = alpha.sin_cos();
            let p = [
                -sa * r.normal_impulse_mps + ca * r.tangential_impulse_mps,
                ca * r.normal_impulse_mps + sa * r.tangential_impulse_mps,
            ];
            assert!((r.velocity[0] - v[0] - p[0]).abs() < 1e-12);
            assert!((r.velocity[1] - v[1] - p[1]).abs() < 1e-12);
            let moment = (L * st) * p[1] - (-L * ct) * p[0];
            assert!((r.velocity[2] - v[2] - moment / (RHO * RHO)).abs() < 1e-9);
            // the contact point's relative tangential velocity after a sticking impact is 0
            let vc2 = [
                r.velocity[0] + L * r.velocity[2] * ct,
                r.velocity[1] + L * r.velocity[2] * st,
            ];
            let ut2 = ca * vc2[0] + sa * vc2[1];
            if r.mode == FrictionMode::Sticking {
                assert!(ut2.abs() < 1e-12, "{ut2}");
            }
            if r.mode == FrictionMode::Sliding {
                assert!((r.tangential_impulse_mps.abs() - mu * r.normal_impulse_mps).abs() < 1e-12);
                // sliding all through: Poisson's restitution is Newton's, u_n+ = -e u_n-
                let un2 = -sa * vc2[0] + ca * vc2[1];
                assert!((un2 + e * un).abs() < 1e-12);
            }
        }
    }
}

// ------------------------------------------------------------ the first contact, eq. 7

/// Brute force: the first grid time with g <= 0 over `n` samples of [0, horizon].
fn brute_first(gap: &Gap, horizon: f64, n: usize) -> Option<f64> {
    (1..=n)
        .map(|k| horizon * k as f64 / n as f64)
        .find(|&t| gap.value(t) <= 0.0)
}

#[test]
fn first_contact_is_never_missed() {
    let mut rng = Lcg(5);
    let n = 20_000;
    for case in 0..400 {
        // a rigid body just after an impact (gap 0, opening) or in flight, spinning fast in
        // some cases (l omega^2 > G: the gap wiggles and can graze)
        let l = rng.range(0.05, 0.3);
        let omega = if case % 2 == 0 {
            rng.range(-4.0, 4.0)
        } else {
            rng.range(-40.0, 40.0)
        };
        let theta = rng.range(-1.2, 1.2);
        let y = l * theta.cos()
            + if case % 3 == 0 {
                0.0
            } else {
                rng.range(0.0, 0.4)
            };
        let gap = Gap {
            c0: y,
            c1: rng.range(0.2, 3.0),
            c2: -0.5 * G,
            l_m: l,
            phi0_rad: theta,
            omega_radps: omega,
        };
        if gap.rate(0.0) <= 0.0 && gap.value(0.0) <= 1e-12 {
            continue;
        }
        let horizon = gap.horizon_s().unwrap();
        let found = first_contact(&gap)
            .unwrap()
            .expect("a contact before the horizon");
        let step = horizon / n as f64;
        // never later than the brute-force detection
        if let Some(b) = brute_first(&gap, horizon, n) {
            assert!(
                found.time_s <= b + 1e-12,
                "case {case}: {} > {b}",
                found.time_s
            );
        }
        // and a real contact: no grid point before it is below zero, and g ~ 0 there
        assert!(gap.value(found.time_s).abs() < 1e-12, "case {case}");
        let k_before = (found.time_s / step).floor() as usize;
        for k in 1..k_before {
            assert!(
                gap.value(k as f64 * step) > -1e-12,
                "case {case}: missed at grid {k}"
            );
        }
    }
}

/// A gap with a tangency (double root) at `t_g`, shifted up by `m` (m): g(t_g) = m,
/// g'(t_g) = 0, g''(t_g) = -G + l omega^2 > 0.
fn grazing_gap(m: f64) -> (Gap, f64) {
    let (l, omega, t_g) = (L, 15.0, 0.05);
    let c2 = -0.5 * G;
    // phi(t_g) = 0: the contact point at its lowest relative to the body
    let phi0 = -omega * t_g;
    let c1 = -2.0 * c2 * t_g;
    let c0 = -c1 * t_g - c2 * t_g * t_g + l + m;
    (
        Gap {
            c0,
            c1,
            c2,
            l_m: l,
            phi0_rad: phi0,
            omega_radps: omega,
        },
        t_g,
    )
}

#[test]
fn grazing_contacts_of_the_rotating_body() {
    let (g0, t_g) = grazing_gap(0.0);
    // the gap has a local minimum there: g'' = -G + l omega^2 > 0
    let curv = -G + g0.l_m * g0.omega_radps * g0.omega_radps;
    assert!(curv > 0.0);
    // separated before the tangency (brute force)
    for k in 0..1000 {
        assert!(g0.value(t_g * k as f64 / 1000.0) > 0.0);
    }
    // exact tangency: found there, flagged grazing
    let c = first_contact(&g0).unwrap().unwrap();
    assert!((c.time_s - t_g).abs() < 1e-6, "{}", c.time_s);
    assert!(c.grazing);
    // penetrating by 1 nm: found before the tangency, where g = 0,
    // t_g - sqrt(2 * 1e-9 / g'') (closing, not grazing)
    let (gm, _) = grazing_gap(-1e-9);
    let c = first_contact(&gm).unwrap().unwrap();
    let expect = t_g - (2.0 * 1e-9 / curv).sqrt();
    assert!((c.time_s - expect).abs() < 1e-7, "{} vs {expect}", c.time_s);
    assert!(!c.grazing);
    // missing by 1 nm: no contact at the tangency; the next contact is later
    let (gp, _) = grazing_gap(1e-9);
    let c = first_contact(&gp).unwrap().unwrap();
    assert!(c.time_s > t_g + 1e-3, "{}", c.time_s);
    assert!(brute_first(&gp, c.time_s * 0.999, 200_000).is_none());
}

// ------------------------------------------------------------------------- hard cases

#[test]
fn kappa_exactly_one_and_kappa_crit_run_cleanly() {
    let y = lossless_y_star();
    let kc = kappa_crit(G, RHO, L, y, 1.0);
    let run_at = |kappa: f64| {
        let mut p = scene("lossless");
        p.kappa = kappa;
        p.initial_theta_rad = 0.05;
        p.simulate().unwrap()
    };
    // kappa = 1: beta = theta - alpha = 0, so the impulse has no moment (eq. 27) and theta
    // never changes, while the tilted table turns vertical into horizontal speed until the
    // body no longer flies: "the kappa = 1 case is always unstable" (sec. 2.3)
    let run = run_at(1.0);
    assert_eq!(run.end, RunEnd::NoSeparation);
    for r in &run.impacts {
        assert_eq!(r.before.theta_rad, 0.05);
        assert_eq!(r.after.theta_dot_radps, 0.0);
    }
    // kappa = kappa_crit: "can be stable" (sec. 2.3): it completes, upright
    let run = run_at(kc);
    assert_eq!(run.end, RunEnd::Completed);
    // lossless: total energy conserved from impact to impact
    let e0 = run.impacts[0].before.total_energy_jpkg(RHO, G);
    for r in &run.impacts {
        assert!((r.after.total_energy_jpkg(RHO, G) - e0).abs() < 1e-9 * e0);
    }
}

#[test]
fn initial_angle_at_the_tip_over_angle() {
    let tip = 4.0f64.atan();
    let mut p = scene("triangle");
    p.tip_angle_rad = tip;
    p.initial_height_m = 0.1; // contact point above the line: 0.1 > l cos(tip) = 0.0323
    p.initial_theta_rad = tip + 1e-9;
    let run = p.simulate().unwrap();
    assert_eq!(run.end, RunEnd::TippedOver);
    assert!(run.impacts.is_empty());
    p.initial_theta_rad = tip - 1e-9;
    let run = p.simulate().unwrap();
    assert!(!run.impacts.is_empty());
    // the first impact happens at theta0 (no spin), at the eq. 7 height l cos(theta0)
    let r = &run.impacts[0];
    assert!((r.before.theta_rad - (tip - 1e-9)).abs() < 1e-15);
    assert!((r.before.y_m - L * (tip - 1e-9).cos()).abs() < 1e-15);
}

#[test]
fn bad_scene_values_give_named_errors() {
    let bad = |f: &dyn Fn(&mut PlanarParams)| {
        let mut p = scene("triangle");
        f(&mut p);
        p.build().unwrap_err()
    };
    assert_eq!(
        bad(&|p| p.restitution = 1.5),
        PlanarError::Param(ParamError::OutOfRange("planar.restitution"))
    );
    assert_eq!(
        bad(&|p| p.radius_of_gyration_m = -0.1),
        PlanarError::Param(ParamError::NotPositive("planar.radius_of_gyration_m"))
    );
    assert_eq!(
        bad(&|p| p.kappa = f64::NAN),
        PlanarError::Param(ParamError::NotFinite("planar.kappa"))
    );
    assert_eq!(
        bad(&|p| p.friction_mu = -1.0),
        PlanarError::Param(ParamError::Negative("planar.friction_mu"))
    );
    assert_eq!(
        bad(&|p| p.tip_angle_rad = 2.0),
        PlanarError::Param(ParamError::OutOfRange("planar.tip_angle_rad"))
    );
    assert_eq!(
        bad(&|p| p.impacts = 0),
        PlanarError::Param(ParamError::OutOfRange("planar.impacts"))
    );
    assert!(matches!(
        bad(&|p| p.initial_height_m = 0.05),
        PlanarError::Relation {
            param: "planar.initial_height_m",
            ..
        }
    ));
    assert!(matches!(
        bad(&|p| p.target_apex_m = Some(0.1)),
        PlanarError::Relation {
            param: "planar.target_apex_m",
            ..
        }
    ));
    match PlanarParams::from_toml_str("[planar]\nkapa = 1.1\n").unwrap_err() {
        PlanarError::Toml(m) => assert!(m.contains("kapa"), "{m}"),
        e => panic!("{e:?}"),
    }
    assert!(PlanarParams::from_toml_str("[planar]\nbody = \"brick\"\n").is_err());
}

#[test]
fn scenes_load_and_hold_only_planar() {
    for name in [
        "triangle",
        "triangle-noise",
        "point-mass",
        "lossless",
        "friction",
    ] {
        let p = scene(name);
        p.build().unwrap();
    }
    assert_eq!(scene("triangle-noise").timing_noise_s, 0.01);
    assert_eq!(scene("friction").friction_mu, 0.3);
}

// ----------------------------------------------------------------------- stability map

#[test]
fn stability_map_classifies_the_regimes() {
    let base = scene("triangle");
    let thetas = [0.1, 0.3];
    let kappas = [0.8, 1.1, 1.6];
    let map = stability_map(&base, &thetas, &kappas, 120).unwrap();
    for row in &map {
        // kappa < 1: the tilt mode grows: not converging
        assert!(matches!(
            row[0].class,
            CellClass::TipsOver | CellClass::Diverges | CellClass::Drifts
        ));
        // 1 < kappa < kappa_crit (1.286 here): converges
        assert_eq!(row[1].class, CellClass::Converges, "{row:?}");
        // kappa > kappa_crit: not converging
        assert_ne!(row[2].class, CellClass::Converges);
    }
}

// ----------------------------------------------------------------- the planar juggler

#[test]
fn planar_juggler_converges_from_several_starts() {
    let jp = JugglerParams::default();
    let eta_star = jp.gravity_mps2 * jp.target_apex_m;
    let starts = [
        PlanarBall::new(0.7, 0.4, 0.2, 0.0),
        PlanarBall::new(1.3, 0.8, -0.3, 0.0),
        PlanarBall::new(1.1, 0.2, 0.0, 1.0),
        PlanarBall::new(0.9, 0.6, 0.4, -0.5),
    ];
    for (name, j) in [
        ("mirror eq. 12", jp.mirror().unwrap()),
        ("modified eq. 15", jp.modified().unwrap()),
    ] {
        for s in starts {
            let run = j.run(s, 80);
            assert_eq!(run.bats.len(), 80, "{name} from {s:?}: {:?}", run.end);
            let last = run.bats.last().unwrap();
            let ex = (last.apex[0] - jp.target_x_m).abs();
            let ee = (last.energy_jpkg - eta_star).abs() / eta_star;
            assert!(ex < 1e-4 && ee < 1e-6, "{name}: {ex:e} {ee:e}");
            // the first bat is far from the target (so convergence is shown)
            assert!(
                (run.bats[0].apex[0] - jp.target_x_m).abs() > 1e-2
                    || (run.bats[0].energy_jpkg - eta_star).abs() > 1e-2 * eta_star
            );
        }
    }
}

#[test]
fn juggler_impacts_satisfy_eq14_and_eq16() {
    let jp = JugglerParams::default();
    // eq. 12 / 14: at the impact (1 + k) theta_b = kappa10 (b_x - b_x*) + kappa11 b_x'
    let run = jp
        .mirror()
        .unwrap()
        .run(PlanarBall::new(0.8, 0.5, 0.3, 0.0), 10);
    for b in &run.bats {
        let [x, z, xd, zd] = b.before;
        let eta = 0.5 * (xd * xd + zd * zd) + jp.gravity_mps2 * z;
        let k = jp.kappa0 + jp.kappa1_s2pm2 * (jp.gravity_mps2 * jp.target_apex_m - eta);
        let lhs = (1.0 + k) * z.atan2(x);
        let rhs = jp.kappa10 * (x - jp.target_x_m) + jp.kappa11 * xd;
        assert!((lhs - rhs).abs() < 1e-12, "{lhs} {rhs}");
        assert!(zd < 0.0);
    }
    // eq. 15 / 16: the ball meets the bar on the ray theta_l fixed by its apex
    let run = jp
        .modified()
        .unwrap()
        .run(PlanarBall::new(1.2, 0.5, -0.2, 0.0), 10);
    let mut apex = [1.2, 0.5];
    let mut apex_xd = -0.2;
    for b in &run.bats {
        let h = jp.kappa10 * (apex[0] - jp.target_x_m) + jp.kappa11 * apex_xd;
        let theta_l = h.atan2(apex[0]);
        assert!((b.before[1].atan2(b.before[0]) - theta_l).abs() < 1e-12);
        apex = b.apex;
        apex_xd = b.after[2];
    }
}

#[test]
fn accuracy_and_its_cost() {
    use dexter_sim::model::planar::analysis::jacobian;
    // the exact contact: gap evaluations per impact for machine-precision impact times
    let run = scene("triangle").simulate().unwrap();
    let per = run.gap_evaluations as f64 / run.impacts.len() as f64;
    println!("triangle: {per:.1} gap evaluations per impact (eq. 7 to adjacent floats)");
    assert!(per < 200.0);
    // the Jacobian: each column tries its step and 32 halvings of it and keeps the one
    // where neighbouring Richardson values agree best (4 columns x 33 steps x 2 sides = 264
    // map evaluations), so the accuracy no longer depends on the starting step; the error
    // estimate bounds the eigenvalue's actual error
    let m = scene("triangle").build().unwrap();
    let y = -(2.0 * G * (0.25 - L)).sqrt();
    let z = [0.0, 0.0, y, 0.0];
    let [a, _] = tilt_eigenvalues(1.1, G, RHO, L, y);
    for step in [2e-1, 2e-2, 2e-3] {
        let j = jacobian(&m, &z, step).unwrap();
        let ev = eigenvalues(&j.matrix).unwrap();
        let d = ev
            .iter()
            .map(|e| (e.0 - a.0).hypot(e.1 - a.1))
            .fold(f64::INFINITY, f64::min);
        println!(
            "step {step:e}: jacobian error estimate {:.1e}, eq. 11 eigenvalue error {d:.1e}",
            j.error
        );
        assert!(
            d < 1e-8 && j.error < 1e-8,
            "step {step:e}: {d:e}, {:e}",
            j.error
        );
        // two neighbouring steps that agree to the last bit below the map's rounding do not
        // make the Jacobian exact: the estimate keeps the rounding's floor
        assert!(
            j.error >= 1e-13,
            "step {step:e}: error estimate {:e}",
            j.error
        );
    }
}

/// The streamed run statistics (constant memory) equal the same figures computed on every
/// impact of the run, kept whole: the late quarter's mean energy and max angle, the early
/// quarter's amplitude through the class, for runs that complete and runs that end early.
#[test]
fn streamed_statistics_equal_the_whole_run() {
    use dexter_sim::model::planar::stats::RunStats;
    let cases: [(&str, f64, usize); 5] = [
        ("triangle", 1.1, 300),
        ("triangle", 1.1, 7),
        ("triangle", 5.0, 300), // no separation at once
        ("friction", 1.1, 300), // tips over early
        ("triangle-noise", 1.1, 301),
    ];
    for (name, kappa, impacts) in cases {
        let mut p = scene(name);
        p.kappa = kappa;
        p.impacts = impacts;
        let model = p.build().unwrap();
        let run = model.run(p.start().unwrap(), impacts, p.seed);
        let mut stats = RunStats::new(&model, impacts);
        let done = model.run_streaming(p.start().unwrap(), impacts, p.seed, &mut |r| stats.push(r));
        assert_eq!(
            (done.end, done.impacts),
            (run.end, run.impacts.len()),
            "{name}"
        );
        let n = run.impacts.len();
        let late = &run.impacts[n - (n / 4).max(1).min(n)..];
        let l = stats.late();
        assert_eq!(l.impacts, late.len(), "{name} {impacts}");
        if !late.is_empty() {
            let mean = late.iter().map(|r| r.energy_jpkg).sum::<f64>() / late.len() as f64;
            assert!(
                (l.mean_energy_jpkg - mean).abs() <= 1e-12 * mean.abs(),
                "{name}"
            );
            let max = late
                .iter()
                .fold(0.0f64, |m, r| m.max(r.before.theta_rad.abs()));
            assert_eq!(l.max_abs_theta_rad, max, "{name}");
        }
        // the class, written out from the paper's definition on the whole run
        let eta = model.feedback.target_energy_jpkg();
        let want = if run
            .impacts
            .iter()
            .any(|r| r.energy_jpkg.is_nan() || r.energy_jpkg > 100.0 * eta)
        {
            CellClass::Diverges
        } else if run.end == RunEnd::TippedOver {
            CellClass::TipsOver
        } else if run.end != RunEnd::Completed {
            CellClass::Diverges
        } else if n < 4 {
            CellClass::Drifts
        } else {
            let q = n / 4;
            let amp = |rs: &[dexter_sim::model::planar::ImpactRecord]| {
                rs.iter()
                    .fold(0.0f64, |m, r| m.max(r.before.theta_rad.abs()))
            };
            let mean = run.impacts[n - q..]
                .iter()
                .map(|r| r.energy_jpkg)
                .sum::<f64>()
                / q as f64;
            let settled = (mean - eta).abs() <= 0.02 * eta;
            if settled && amp(&run.impacts[n - q..]) <= 1.1 * amp(&run.impacts[..q]) {
                CellClass::Converges
            } else {
                CellClass::Drifts
            }
        };
        assert_eq!(stats.class(done.end), want, "{name} {impacts}");
        assert_eq!(classify(&model, &run), want, "{name} {impacts}");
    }
}
