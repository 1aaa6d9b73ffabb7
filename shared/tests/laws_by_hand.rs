//! Law behaviours that `scripts/mutants.sh` found unpinned in the planar and hopper modules,
//! each checked against a value worked out by hand from the paper's equation (not from the
//! code under test).

use dexter_core::hop::{energy_fixed_point, EnergyServoThrust};
use dexter_core::planar::{PlanarBall, PlanarMirrorLaw};

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
