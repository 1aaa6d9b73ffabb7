//! The one-sided plastic impact of an edge (`model::arm::impact`) against hand-derived
//! post-impact states: a square that cannot be stopped outright rocks onto its striking
//! vertex; a long plank can be stopped, with the impulse's centre of pressure on the edge.

use dexter_sim::model::arm::contact::{Placement, Rig};
use dexter_sim::model::arm::geometry::{Polygon, Surface, V2};
use dexter_sim::model::arm::impact::Outcome;

const A: f64 = 0.1;

fn level(body: Polygon) -> Rig {
    Rig {
        body,
        surface: Surface {
            origin: V2::new(0.0, 0.05),
            beta_rad: 0.0,
            length_m: 1.22,
        },
        gravity_mps2: 9.81,
    }
}

/// A square of side a rolling counterclockwise over vertex 0 (at sigma = 0.85) lands on
/// edge 3 (vertex 3 at 0.75 to vertex 0 at 0.85) at rate omega > 0, the arm at rest
/// (everything is relative to the arm, so the arm's own motion does not enter).
///
/// Hand derivation, with the pivot P at the origin, the surface along +x, the striking
/// vertex w at (-a, 0) and the centre of mass at r = (-a/2, a/2):
///
/// - before, the object turns about P: `v = omega J r = omega (-a/2, -a/2)`; w moves
///   down at `omega a` (the impact speed).
/// - a stop outright needs `Pi = -v` with `rho^2 (0 - omega) = (c - r) x Pi`; for
///   `c = (x_c, 0)` this gives `x_c = -(a + 2 rho^2 / a)`: beyond w (at -a) by
///   `2 rho^2 / a`, so from vertex 3 the stop's centre of pressure is at `-2 rho^2 / a`:
///   off the edge, it would pull.
/// - so the impulse acts at w alone; angular momentum about w is conserved:
///   `rho^2 omega + (r - w) x v = (rho^2 + |r - w|^2) omega+`, with `r - w = (a/2, a/2)`,
///   `(r - w) x v = omega (-a^2/4 + a^2/4) = 0`, `|r - w|^2 = a^2/2`:
///   `omega+ = k omega`, `k = rho^2 / (rho^2 + a^2 / 2)` (2/5 for a thin frame,
///   `rho^2 = a^2/3`).
/// - after, `v+ = omega+ J (r - w) = k omega (-a/2, a/2)`, so
///   `Pi = v+ - v = (a omega / 2) (1 - k, 1 + k)`: normal `a omega (1 + k) / 2`,
///   tangential `a omega (1 - k) / 2`, friction ratio `(1 - k) / (1 + k)` (3/7).
/// - the old pivot P then rises at `omega+ J (P - w) = k omega (0, a)`: it lifts off.
#[test]
fn a_square_striking_a_resting_arm_rocks_onto_its_striking_vertex() {
    for rho2 in [A * A / 3.0, A * A / 6.0] {
        let rig = level(Polygon::square(A, Some(rho2.sqrt())).unwrap());
        let start = Placement {
            edge: 0,
            sigma_m: 0.85,
        };
        let pv = rig.pivot(&start, 1.0);
        let onto = rig.landed(&pv);
        assert_eq!(
            onto,
            Placement {
                edge: 3,
                sigma_m: 0.75
            }
        );
        let omega = 6.3;
        let imp = rig.roll_impact(&pv, &onto, omega);
        let k = rho2 / (rho2 + A * A / 2.0);
        let tol = 1e-12;
        assert!((imp.speed_mps - omega * A).abs() < tol, "{imp:?}");
        assert!((imp.stop_cop_m + 2.0 * rho2 / A).abs() < tol, "{imp:?}");
        match imp.outcome {
            Outcome::Rock {
                vertex,
                dir,
                rate_radps,
            } => {
                assert_eq!((vertex, dir), (3, 1.0));
                assert!((rate_radps - k * omega).abs() < tol, "{imp:?}");
            }
            other => panic!("expected a rock, got {other:?}"),
        }
        assert!((imp.impulse_normal_mps - 0.5 * A * omega * (1.0 + k)).abs() < tol);
        assert!((imp.impulse_tangential_mps - 0.5 * A * omega * (1.0 - k)).abs() < tol);
        assert!((imp.friction_ratio() - (1.0 - k) / (1.0 + k)).abs() < tol);
        // the impulse acts at the striking vertex, the near end of the edge
        assert_eq!(imp.cop_m, 0.0);
        assert!(imp.cop_margin_m() >= 0.0);
        // friction just below what the impulse needs is not enough: the verifier's verdict
        let need = (1.0 - k) / (1.0 + k);
        assert!(imp.in_cone(need + 1e-9) && !imp.in_cone(need - 1e-9));
        assert!(imp.judged(need + 1e-9).is_ok());
        assert!(
            imp.judged(need - 1e-9).is_err(),
            "the impulse's friction is checked"
        );
    }
    // the thin frame of scenes/arm-roll.toml: 2/5 of the rate, 3/7 of friction
    let rig = level(Polygon::square(A, Some((A * A / 3.0).sqrt())).unwrap());
    let start = Placement {
        edge: 0,
        sigma_m: 0.85,
    };
    let pv = rig.pivot(&start, 1.0);
    let imp = rig.roll_impact(&pv, &rig.landed(&pv), 6.3);
    assert!((imp.rate_after_radps - 0.4 * 6.3).abs() < 1e-12);
    assert!((imp.friction_ratio() - 3.0 / 7.0).abs() < 1e-12);
}

/// The clockwise mirror image: over vertex 1 (at 0.95) onto edge 1, at omega < 0, rocking
/// onto vertex 2 at the far end of edge 1 (sigma 1.05), clockwise.
#[test]
fn the_mirror_image_rocks_clockwise_onto_the_far_vertex() {
    let rho2 = A * A / 3.0;
    let rig = level(Polygon::square(A, Some(rho2.sqrt())).unwrap());
    let start = Placement {
        edge: 0,
        sigma_m: 0.85,
    };
    let pv = rig.pivot(&start, -1.0);
    let onto = rig.landed(&pv);
    assert_eq!(onto.edge, 1);
    let imp = rig.roll_impact(&pv, &onto, -6.3);
    let k = rho2 / (rho2 + A * A / 2.0);
    assert!(matches!(imp.outcome, Outcome::Rock { vertex: 2, dir, .. } if dir == -1.0));
    assert!((imp.rate_after_radps + k * 6.3).abs() < 1e-12);
    assert!((imp.cop_m - A).abs() < 1e-15);
    // mirrored: the tangential impulse points the other way
    assert!((imp.impulse_tangential_mps + 0.5 * A * 6.3 * (1.0 - k)).abs() < 1e-12);
    assert!((imp.stop_cop_m - (A + 2.0 * rho2 / A)).abs() < 1e-12);
}

/// A plank (length L = 0.4 m, thickness 2h = 0.02 m, a uniform plate) tipping over its
/// corner onto its long edge. With P at the origin, w at (-L, 0), r = (-L/2, h), rotating
/// at omega about P: `v = omega J r = omega (-h, -L/2)`, and the stop outright
/// `Pi = -v = omega (h, L/2)` acts at `x_c = -(L/2 + (h^2 + rho^2) / (L/2))`
/// (as for the square above), `rho^2 = (L^2 + 4 h^2) / 12`: 0.2673 m from P, on the
/// 0.4 m edge. It is stopped outright and grasped.
#[test]
fn a_long_plank_is_stopped_outright_with_its_centre_of_pressure_on_the_edge() {
    let (l, h) = (0.4, 0.01);
    let body = Polygon::new(
        &[
            V2::new(0.0, 0.0),
            V2::new(l, 0.0),
            V2::new(l, 2.0 * h),
            V2::new(0.0, 2.0 * h),
        ],
        None,
    )
    .unwrap();
    let rho2 = (l * l + 4.0 * h * h) / 12.0;
    assert!((body.rho_m.powi(2) - rho2).abs() < 1e-15);
    let rig = level(body);
    // stood on its short edge 3 (vertex 3 to 0) at sigma 0.5: roll ccw over vertex 3
    let stood = Placement {
        edge: 3,
        sigma_m: 0.5,
    };
    let pv = rig.pivot(&stood, 1.0);
    let onto = rig.landed(&pv);
    assert_eq!(onto.edge, 2);
    assert!((onto.sigma_m - (0.5 - l)).abs() < 1e-12);
    let omega = 3.0;
    let imp = rig.roll_impact(&pv, &onto, omega);
    assert_eq!(imp.outcome, Outcome::Grasp);
    let x_c = l / 2.0 + (h * h + rho2) / (l / 2.0);
    // from vertex 2 (the far end, at P - L) the centre of pressure is at L - x_c
    assert!((imp.cop_m - (l - x_c)).abs() < 1e-12, "{imp:?}");
    assert_eq!(imp.cop_m, imp.stop_cop_m);
    assert!(imp.cop_margin_m() > 0.1);
    assert!((imp.impulse_normal_mps - omega * l / 2.0).abs() < 1e-12);
    assert!((imp.impulse_tangential_mps - omega * h).abs() < 1e-12);
    assert_eq!(imp.rate_after_radps, 0.0);
}
