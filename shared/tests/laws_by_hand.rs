//! Law behaviours that `scripts/mutants.sh` found unpinned in the planar and hopper modules,
//! each checked against a value worked out by hand from the paper's equation (not from the
//! code under test).

use dexter_core::hop::{energy_fixed_point, EnergyServoThrust};
use dexter_core::planar::{quadratic_roots, ModifiedPlanarLaw, PlanarBall, PlanarMirrorLaw};
use dexter_core::tilt::{
    restitution_compensation, tilt_eigenvalues, BodyState, EnergyFeedback, TiltLaw,
};
use std::f64::consts::{FRAC_PI_3, FRAC_PI_4};

/// Planar mirror gain, eq. 5/12: k(w) = kappa0 + kappa1 (eta* - eta) with
/// eta = |b'|^2/2 + gamma b_z. By hand: gamma = 2, h* = 3 -> eta* = 6; the ball
/// (b_z = 1, b' = (1, 2)) has eta = (1 + 4)/2 + 2 = 4.5; kappa0 = 0.1, kappa1 = 0.2:
/// k = 0.1 + 0.2 * 1.5 = 0.4.
#[test]
fn planar_gain_by_hand() {
    let law = PlanarMirrorLaw::new(0.1f64, 0.2, 3.0, 0.0, 0.0, 1.0, 2.0).unwrap();
    assert!((law.target_energy_jpkg() - 6.0).abs() < 1e-12);
    let ball = PlanarBall::new(0.7, 1.0, 1.0, 2.0);
    assert!((law.gain(&ball) - 0.4).abs() < 1e-12, "{}", law.gain(&ball));
    // above the target energy the gain drops: eta = 8 -> k = 0.1 - 0.4 = -0.3
    let fast = PlanarBall::new(0.7, 1.0, 0.0, 12f64.sqrt());
    assert!((law.gain(&fast) + 0.3).abs() < 1e-12);
}

/// The energy servo's target, as given (J/kg).
#[test]
fn energy_servo_keeps_its_target() {
    let servo = EnergyServoThrust::new(10.0f64, 2.0, 7.5, 40.0, 0.1).unwrap();
    assert_eq!(servo.target_energy_jpkg(), 7.5);
}

/// Eq. 19's interior fixed point E* = ln(alpha) exists only for alpha > 1 (Lemma 1): at
/// alpha = 1 it would be E* = 0, the trivial fixed point, which is not interior.
#[test]
fn energy_fixed_point_needs_alpha_above_one() {
    assert_eq!(energy_fixed_point(1.0f64), None);
    assert_eq!(energy_fixed_point(0.5f64), None);
    let e = energy_fixed_point(std::f64::consts::E).unwrap();
    assert!((e - 1.0).abs() < 1e-15);
}

/// The modified law's gain is eq. 5's, as for the planar law above (same numbers).
#[test]
fn modified_planar_gain_by_hand() {
    let law = ModifiedPlanarLaw::new(0.1f64, 0.2, 3.0, 0.0, 0.0, 1.0, 2.0).unwrap();
    let ball = PlanarBall::new(0.7, 1.0, 1.0, 2.0);
    assert!((law.gain(&ball) - 0.4).abs() < 1e-12, "{}", law.gain(&ball));
}

/// theta_l = atan2(kappa10 (x - x*) + kappa11 x', x) at the apex (eq. 15): kappa10 = 0.3,
/// kappa11 = 0.4 s, x* = 1.5, apex x = 2, x' = 0.5: atan2(0.15 + 0.2, 2).
#[test]
fn modified_planar_target_angle_by_hand() {
    let law = ModifiedPlanarLaw::new(0.1f64, 0.2, 3.0, 0.3, 0.4, 1.5, 2.0).unwrap();
    let apex = PlanarBall::new(2.0, 1.0, 0.5, 0.0);
    assert!((law.target_angle_rad(&apex) - 0.35f64.atan2(2.0)).abs() < 1e-15);
}

/// Eq. 16: when the falling ball crosses the ray at theta_l. By hand, gamma = 2:
/// - ray at 45 deg, apex (1, 3) moving at x' = 1: 3 - t^2 = 1 + t, t = 1;
/// - ray at 0 deg, apex (1, 2) at rest: 2 - t^2 = 0, t = sqrt(2);
/// - ray at 0 deg through the apex itself (1, 0): t = 0 (a root at 0 counts);
/// - a state past its apex, (1, 1) rising at 1 m/s: 1 + t - t^2 = 0, t = (1 + sqrt 5)/2;
/// - ray at -45 deg, (1, -0.5) with velocity (2, -1): 0.5 + t - t^2 = 0, roots
///   (1 -+ sqrt 3)/2: the negative one is in the past, the answer is (1 + sqrt 3)/2;
/// - ray at 60 deg, apex (-0.5, 1): the line z = sqrt(3) x is met at (-0.5, -0.87), on the
///   opposite ray: no impact; apex (0, 1): the line is met at the origin, not on the open
///   ray: no impact.
#[test]
fn modified_planar_impact_time_by_hand() {
    let law = ModifiedPlanarLaw::new(0.1f64, 0.0, 1.0, 0.0, 0.0, 1.0, 2.0).unwrap();
    let t = |x, z, xd, zd, theta| law.impact_time_s(&PlanarBall::new(x, z, xd, zd), theta);
    let close = |got: Option<f64>, want: f64| {
        assert!(
            got.is_some_and(|g| (g - want).abs() < 1e-12),
            "{got:?} vs {want}"
        )
    };
    close(t(1.0, 3.0, 1.0, 0.0, FRAC_PI_4), 1.0);
    close(t(1.0, 2.0, 0.0, 0.0, 0.0), 2f64.sqrt());
    close(t(1.0, 0.0, 0.0, 0.0, 0.0), 0.0);
    close(t(1.0, 1.0, 0.0, 1.0, 0.0), (1.0 + 5f64.sqrt()) / 2.0);
    close(
        t(1.0, -0.5, 2.0, -1.0, -FRAC_PI_4),
        (1.0 + 3f64.sqrt()) / 2.0,
    );
    assert_eq!(t(-0.5, 1.0, 0.0, 0.0, FRAC_PI_3), None);
    assert_eq!(t(0.0, 1.0, 0.0, 0.0, FRAC_PI_3), None);
}

/// Roots by hand, including the linear case (a = 0): 2 t - 4 = 0 -> t = 2 (twice).
#[test]
fn quadratic_roots_by_hand() {
    assert_eq!(quadratic_roots(0.0f64, 2.0, -4.0), Some([2.0, 2.0]));
    let [r1, r2] = quadratic_roots(1.0f64, -3.0, 2.0).unwrap();
    assert!(
        (r1 - 1.0).abs() < 1e-15 && (r2 - 2.0).abs() < 1e-15,
        "{r1} {r2}"
    );
    assert_eq!(quadratic_roots(1.0f64, 0.0, 1.0), None);
}

/// The tilt gain as given; eq. 22's compensation -(1-e)/(1+e) v- componentwise
/// (e = 0.5: -v/3).
#[test]
fn tilt_gain_and_restitution_compensation_by_hand() {
    assert_eq!(TiltLaw::new(1.7f64).unwrap().kappa(), 1.7);
    let c = restitution_compensation([3.0f64, -6.0, 1.5], 0.5);
    for (got, want) in c.iter().zip([-1.0, 2.0, -0.5]) {
        assert!((got - want).abs() < 1e-15, "{c:?}");
    }
}

/// Eq. 25's energy at impact, eta = G l cos(theta) + y'^2/2, and its parameters. By hand:
/// G = 10, l = 0.2, theta = 60 deg, y' = -2: eta = 1 + 2 = 3; eta* = 5, kappa_E = 0.1,
/// e = 0.5: gain = 1/3 + 0.1 * 2 = 0.5333.
#[test]
fn tilt_energy_feedback_by_hand() {
    let fb = EnergyFeedback::new(0.5f64, 0.1, 5.0, 10.0, 0.2).unwrap();
    assert_eq!(fb.kappa_e_s2pm2(), 0.1);
    assert_eq!(fb.target_energy_jpkg(), 5.0);
    assert!((fb.target_apex_m() - 0.5).abs() < 1e-15);
    let state = BodyState::new(FRAC_PI_3, 0.0, -2.0, 0.0);
    assert!((fb.energy_jpkg(&state) - 3.0).abs() < 1e-12);
    assert!((fb.gain(&state) - (1.0 / 3.0 + 0.2)).abs() < 1e-12);
}

/// Eigenvalues of the linearized tilt map (eq. 11): with u = y*^2 l (kappa - 1)/(G rho^2),
/// lambda = 1 - 2u +- 2 sqrt(u (u - 1)). By hand: y* = 2, l = 0.5, G = 4, rho = 1,
/// kappa = 2: u = 0.5, a complex pair 0 +- 1i; kappa = 3: u = 1, a double root -1;
/// kappa = 5: u = 2, lambda = -3 -+ 2 sqrt 2.
#[test]
fn tilt_eigenvalues_by_hand() {
    let [a, b] = tilt_eigenvalues(2.0f64, 4.0, 1.0, 0.5, 2.0);
    assert!(a.0.abs() < 1e-15 && (a.1 - 1.0).abs() < 1e-15, "{a:?}");
    assert!(b.0.abs() < 1e-15 && (b.1 + 1.0).abs() < 1e-15, "{b:?}");
    let [a, b] = tilt_eigenvalues(3.0f64, 4.0, 1.0, 0.5, 2.0);
    assert!((a.0 + 1.0).abs() < 1e-15 && (b.0 + 1.0).abs() < 1e-15);
    let [a, b] = tilt_eigenvalues(5.0f64, 4.0, 1.0, 0.5, 2.0);
    let r = 2.0 * 2f64.sqrt();
    assert!((a.0 - (-3.0 - r)).abs() < 1e-14 && (b.0 - (-3.0 + r)).abs() < 1e-14);
    assert_eq!((a.1, b.1), (0.0, 0.0));
}
