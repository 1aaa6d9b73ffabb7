use super::*;
use crate::model::planar::juggler::{JuggleEnd, JugglerParams};
use dexter_core::planar::PlanarBall;

const G: f64 = 9.81;

/// The planar juggler's parameters that the spatial defaults reduce to in the plane through
/// the base (radial gains negated back).
pub(super) fn planar_twin(p: &SpatialParams) -> JugglerParams {
    JugglerParams {
        restitution: p.restitution,
        gravity_mps2: p.law.gravity_mps2,
        kappa0: p.law.kappa0,
        kappa1_s2pm2: p.law.kappa1_s2pm2,
        target_apex_m: p.law.target_apex_m,
        kappa10: -p.law.kappa10,
        kappa11: -p.law.kappa11,
        target_x_m: p.law.target_radius_m,
    }
}

fn close(a: f64, b: f64, tol: f64) -> bool {
    (a - b).abs() <= tol * (1.0 + b.abs())
}

/// A ball at rest at `apex` (its apex).
fn dropped(apex: [f64; 3]) -> SpatialBall<f64> {
    SpatialBall::new(apex, [0.0; 3])
}

/// With the ball in the vertical plane through the base, the spatial juggler is the planar
/// juggler (independent code, eq. 12 and 15): the same impacts, bat by bat, to rounding.
#[test]
fn in_the_plane_through_the_base_it_is_the_planar_juggler() {
    let p = SpatialParams::default();
    let twin = planar_twin(&p);
    for (x, z, u) in [(1.1, 0.6, 0.0), (0.9, 0.45, 0.05), (1.05, 0.55, -0.04)] {
        for modified in [false, true] {
            let (spatial, planar) = if modified {
                let p = SpatialParams {
                    law: SpatialLawParams {
                        kappa10: 0.12,
                        kappa11: 0.08,
                        ..p.law
                    },
                    ..p
                };
                let t = JugglerParams {
                    kappa10: 0.12,
                    kappa11: 0.08,
                    ..twin
                };
                (p.modified().unwrap(), t.modified().unwrap())
            } else {
                (p.mirror().unwrap(), twin.mirror().unwrap())
            };
            let s = spatial.run(SpatialBall::new([x, 0.0, z], [u, 0.0, 0.0]), 30);
            let q = planar.run(PlanarBall::new(x, z, u, 0.0), 30);
            assert_eq!(
                (s.end, q.end),
                (SpatialEnd::Completed, JuggleEnd::Completed)
            );
            for (a, b) in s.bats.iter().zip(&q.bats) {
                assert!(close(a.time_s, b.time_s, 1e-9), "{} {}", a.time_s, b.time_s);
                let spatial_state = [a.after[0], a.after[2], a.after[3], a.after[5]];
                for (v, w) in spatial_state.iter().zip(b.after) {
                    assert!(close(*v, w, 1e-9), "bat {}: {v} {w}", a.index);
                }
                assert_eq!((a.after[1], a.after[4], a.joints_rad[2]), (0.0, 0.0, 0.0));
                assert!(close(
                    a.joints_rad[1] + core::f64::consts::FRAC_PI_2,
                    b.bar_angle_rad,
                    1e-9
                ));
            }
        }
    }
}

/// Issue 28's convergence: from an apex 10 cm off the set point horizontally and 20 % above
/// it, the horizontal apex error is below 1 mm and the height error below 0.1 % within 30
/// impacts, for both laws.
#[test]
fn from_ten_centimetres_and_twenty_percent_off_both_laws_converge_within_thirty_impacts() {
    let p = SpatialParams::default();
    let h = p.law.target_apex_m;
    let modified = SpatialParams {
        law: SpatialLawParams {
            kappa10: 0.12,
            kappa11: 0.08,
            ..p.law
        },
        ..p
    };
    // 10 cm off: 6 cm radially, 8 cm laterally
    let start = dropped([1.06, 0.08, 1.2 * h]);
    for (name, juggler) in [
        ("eq. 13", p.mirror().unwrap()),
        ("modified", modified.modified().unwrap()),
    ] {
        let run = juggler.run(start, 30);
        assert_eq!(run.end, SpatialEnd::Completed, "{name}");
        let last = run.bats.last().unwrap();
        let [x, y, z] = last.apex_m;
        let horizontal = (x - 1.0).hypot(y);
        assert!(
            horizontal < 1e-3,
            "{name}: horizontal apex error {horizontal} m"
        );
        assert!(((z - h) / h).abs() < 1e-3, "{name}: apex height {z} m");
    }
}

/// Tests that can fail: with the lateral gain's sign flipped, or the mirror term dropped,
/// the same start does not converge.
#[test]
fn a_flipped_lateral_gain_or_no_mirror_term_does_not_converge() {
    let p = SpatialParams::default();
    let h = p.law.target_apex_m;
    let start = dropped([1.06, 0.08, 1.2 * h]);
    let converged = |q: SpatialParams| {
        let run = q.mirror().unwrap().run(start, 30);
        run.end == SpatialEnd::Completed && {
            let [x, y, z] = run.bats.last().unwrap().apex_m;
            (x - 1.0).hypot(y) < 1e-3 && ((z - h) / h).abs() < 1e-3
        }
    };
    assert!(converged(p));
    let flipped = SpatialLawParams {
        kappa20_radpm: -p.law.kappa20_radpm,
        ..p.law
    };
    assert!(!converged(SpatialParams { law: flipped, ..p }));
    let no_mirror = SpatialLawParams {
        kappa0: 0.0,
        kappa1_s2pm2: 0.0,
        ..p.law
    };
    assert!(!converged(SpatialParams {
        law: no_mirror,
        ..p
    }));
}

/// At each eq. 13 contact the bar's elevation equals the ball's (the contact condition), and
/// the ball leaves faster along the normal than the paddle, by alpha (restitution).
#[test]
fn impacts_meet_the_contact_condition_and_restitution() {
    let p = SpatialParams::default();
    let juggler = p.mirror().unwrap();
    let run = juggler.run(dropped([1.06, 0.08, 0.6]), 10);
    assert_eq!(run.end, SpatialEnd::Completed);
    for bat in &run.bats {
        let b = SpatialBall::new(
            [bat.before[0], bat.before[1], bat.before[2]],
            [bat.before[3], bat.before[4], bat.before[5]],
        );
        let e_bar = bat.joints_rad[1] + core::f64::consts::FRAC_PI_2;
        assert!(
            (e_bar - b.elevation_rad()).abs() < 1e-9,
            "{e_bar} {}",
            b.elevation_rad()
        );
        assert!(close(bat.joints_rad[0], b.azimuth_rad(), 1e-12));
    }
}

/// With every gain 0 the paddle lies still and horizontal (e_r = 0): a ball dropped onto it
/// meets it after the free fall's sqrt(2 z / gamma) and bounces back at alpha times its
/// impact speed, straight up.
#[test]
fn a_drop_on_a_still_horizontal_paddle_by_hand() {
    let law = SpatialLawParams {
        kappa0: 0.0,
        kappa1_s2pm2: 0.0,
        kappa10: 0.0,
        kappa11: 0.0,
        kappa20_radpm: 0.0,
        kappa21_radspm: 0.0,
        ..SpatialParams::default().law
    };
    let juggler = SpatialParams {
        restitution: 0.5,
        law,
    }
    .mirror()
    .unwrap();
    let run = juggler.run(dropped([0.8, 0.3, 0.45]), 1);
    let bat = run.bats[0];
    let t = (2.0 * 0.45 / G).sqrt();
    assert!(close(bat.time_s, t, 1e-12), "{}", bat.time_s);
    assert!(close(bat.after[5], 0.5 * G * t, 1e-12));
    assert!(bat.after[3].abs() < 1e-12 && bat.after[4].abs() < 1e-12);
}

#[test]
fn a_flight_over_the_base_is_reported() {
    let juggler = SpatialParams::default().mirror().unwrap();
    let run = juggler.run(SpatialBall::new([0.5, 0.0, 0.5], [-1.0, 0.0, 0.0]), 3);
    assert_eq!(run.end, SpatialEnd::OverBase);
}
