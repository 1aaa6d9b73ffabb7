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
                psi_rad,
            } => {
                assert_eq!(psi_rad, 0.0, "a rock off the edge lying flat");
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

/// A solid square (side a, `rho^2 = a^2/6`) on a level arm at rest, tilted by `psi` from
/// lying on edge 0, its centre of mass at `w + R(psi) (a/2, a/2)` with `w` the lower end:
/// vertex 0 if `psi > 0` (tilted counterclockwise, vertex 1 up by `a sin psi`), vertex 1 if
/// `psi < 0` (then `r - w = R(psi) (-a/2, a/2)`).
fn tilted_square(psi: f64, w_sigma: f64) -> (Rig, V2) {
    let rig = level(Polygon::square(A, None).unwrap());
    let h = A / 2.0;
    let w = rig.surface.point(w_sigma);
    let rw = if psi >= 0.0 {
        V2::new(h, h)
    } else {
        V2::new(-h, h)
    };
    (rig, w.plus(rw.rotate(psi)))
}

/// The tilted pose is the roll's pose at `psi`: `Rig::tilted` names the placement of the
/// edge turned flat about its lower end and the pivot over that end, and the roll over it
/// at `psi` (the catch continues from there) puts the object exactly where it struck.
#[test]
fn a_tilted_strike_continues_as_the_roll_from_that_tilt() {
    use dexter_sim::model::arm::contact::Joint;
    for psi in [0.3, 0.05, -0.05, -0.3] {
        let (rig, com) = tilted_square(psi, 0.6);
        let (p, pv) = rig.tilted(0, psi, com);
        let (vertex, dir, sigma) = if psi > 0.0 {
            (0, 1.0, 0.6)
        } else {
            (1, -1.0, 0.6 - A)
        };
        assert_eq!((pv.vertex, pv.dir, p.edge), (vertex, dir, 0), "psi {psi}");
        assert!((pv.sigma_m - 0.6).abs() < 1e-15 && (p.sigma_m - sigma).abs() < 1e-15);
        assert!(dir * psi > 0.0 && psi.abs() < pv.gamma_rad);
        // the other end of the edge is up by a |sin psi|
        let other = rig.body.vertex(if psi > 0.0 { 1 } else { 0 });
        let up = rig
            .surface
            .height_m(com.plus(other.rotate(rig.alpha_rad(0) + psi)));
        assert!((up - A * psi.abs().sin()).abs() < 1e-15, "{up}");
        // at any arm angle the roll's pose at psi is the struck pose
        let j = Joint {
            angle_rad: 0.2,
            velocity_radps: 0.0,
            accel_radps2: 0.0,
        };
        let s = rig.rolling_state(&pv, psi, 0.0, &j);
        assert!(s.com.minus(com.rotate(0.2)).norm() < 1e-15, "psi {psi}");
        assert!((s.angle_rad - (0.2 + rig.alpha_rad(0) + psi)).abs() < 1e-15);
    }
}

/// The solid square of `tilted_square` dropped straight at speed u, without rotation
/// (`v = (0, -u)`, `omega = 0`), onto its lower corner `w`. The impulse acts at `w` alone,
/// plastic and sticking; angular momentum about `w` is conserved:
///
/// - `psi > 0`: `r - w = (a/2) (c - s, s + c)` (`c = cos psi`, `s = sin psi`), so
///   `(r - w) x v = -(u a/2) (c - s)`, `|r - w|^2 = a^2/2` and
///   `omega+ = -(u a/2) (c - s) / (a^2/6 + a^2/2) = -(3u / 4a) (c - s)`: clockwise,
///   back toward flat (the roll's `dir` is +1, psi falls to 0).
/// - after, `v+ = omega+ J (r - w) = omega+ (a/2) (-(s + c), c - s)`, so with
///   `Pi = v+ - v`: `Pi_t = (3u/8) (c - s)(c + s) = (3u/8) cos 2 psi` and
///   `Pi_n = u - (3u/8) (c - s)^2 = u (5/8 + (3/8) sin 2 psi)` (> 0: it pushes). As
///   psi -> 0 the impulse is `(3u/8, 5u/8)`: it needs friction 3/5.
/// - the corner's approach speed is u; a stop outright (`Pi = -v`, no rate to take) would
///   act under the centre of mass, `(a/2) (c - s)` from `w` along the edge.
/// - `psi < 0`, with `phi = -psi`, is the mirror image: `w` is vertex 1 (at `L` along the
///   edge), `omega+ = +(3u / 4a) (cos phi - sin phi)` (counterclockwise, toward flat),
///   `Pi_t = -(3u/8) cos 2 phi`, the same `Pi_n`, the stop at `L - (a/2) (cos phi - sin phi)`.
/// - at psi -> 0 the edge then falls back onto the surface about `w` at `omega+` (a
///   fraction of a millisecond later): the roll's end of the first test, which rocks
///   onto the other end of the edge at `k omega+`, `k = rho^2 / (rho^2 + a^2/2) = 1/4`;
///   the edge striking as a whole would stop the square outright (its stop acts under the
///   centre of mass, on the edge). The two orders of nearly simultaneous impacts differ:
///   below `FLAT_TOL_RAD` the verifier takes the whole edge.
#[test]
fn a_square_dropped_on_its_corner_turns_back_toward_flat() {
    let u = 2.0;
    let v = V2::new(0.0, -u);
    for psi in [0.1f64, 0.3, 1e-6, -0.1, -0.3, -1e-6] {
        let (rig, com) = tilted_square(psi, 0.6);
        assert!((rig.body.rho_m.powi(2) - A * A / 6.0).abs() < 1e-15);
        let (p, pv) = rig.tilted(0, psi, com);
        let imp = rig.vertex_impact(&pv, &p, psi, v, 0.0);
        let phi = psi.abs();
        let (c, s) = (phi.cos(), phi.sin());
        let sign = psi.signum();
        let omega = -sign * 3.0 * u / (4.0 * A) * (c - s);
        let pt = sign * 3.0 * u / 8.0 * (2.0 * phi).cos();
        let pn = u * (5.0 / 8.0 + 3.0 / 8.0 * (2.0 * phi).sin());
        let tol = 1e-12;
        match imp.outcome {
            Outcome::Rock {
                vertex,
                dir,
                rate_radps,
                psi_rad,
            } => {
                assert_eq!((vertex, dir, psi_rad), (pv.vertex, sign, psi));
                assert!((rate_radps - omega).abs() < tol, "psi {psi}: {imp:?}");
                assert!(rate_radps * dir < 0.0, "it turns back toward flat");
            }
            other => panic!("expected a rock from the tilt, got {other:?}"),
        }
        assert!((imp.rate_after_radps - omega).abs() < tol);
        assert_eq!(imp.rate_before_radps, 0.0);
        assert!(
            (imp.impulse_tangential_mps - pt).abs() < tol,
            "psi {psi}: {imp:?}"
        );
        assert!(
            (imp.impulse_normal_mps - pn).abs() < tol,
            "psi {psi}: {imp:?}"
        );
        assert!((imp.speed_mps - u).abs() < tol);
        let under = A / 2.0 * (c - s);
        let (cop, stop) = if psi > 0.0 {
            (0.0, under)
        } else {
            (A, A - under)
        };
        assert!((imp.cop_m - cop).abs() < 1e-15 && (imp.stop_cop_m - stop).abs() < tol);
        // judged against mu like every impact
        let need = pt.abs() / pn;
        assert!((imp.friction_ratio() - need).abs() < tol);
        assert!(imp.judged(need + 1e-9).is_ok() && imp.judged(need - 1e-9).is_err());
        if phi < 1e-3 {
            assert!((need - 0.6).abs() < 1e-5, "3/5 at a corner: {need}");
            // the edge falls back about w at omega+ and rocks onto its other end
            let back = rig.roll_impact(&pv, &p, omega);
            let other = if psi > 0.0 { 1 } else { 0 };
            match back.outcome {
                Outcome::Rock {
                    vertex,
                    dir,
                    rate_radps,
                    psi_rad,
                } => {
                    assert_eq!((vertex, dir, psi_rad), (other, -sign, 0.0));
                    assert!((rate_radps - omega / 4.0).abs() < tol, "{back:?}");
                }
                o => panic!("expected a rock onto the other end, got {o:?}"),
            }
            // while the whole edge would stop it outright, under the centre of mass
            let whole = rig.edge_impact(&p, v, 0.0);
            assert_eq!(whole.outcome, Outcome::Grasp);
            assert!((whole.cop_m - A / 2.0).abs() < 1e-5);
        }
    }
}

/// A tilted catch state (the one an earlier SIL run of `scenes/arm-throw-catch.toml` met
/// at t = 1.0257 s against a frozen arm, copied here; today's run comes down flat): the
/// square comes down
/// with edge 3 tilted 0.0288 rad from flat, beyond `FLAT_TOL_RAD`, so vertex 3 strikes
/// alone. Recomputed here from the world state without the code under test: relative to
/// the arm and in its frame, `r = R(-theta) r_w`, `v = R(-theta) (v_w - theta' J r_w)`,
/// `omega = omega_w - theta'`; the lowest vertex `w = r + R(phi - theta) b`; then
/// `omega+ = (rho^2 omega + (r - w) x v) / (rho^2 + |r - w|^2)`, `Pi = omega+ J (r - w) - v`,
/// on the link's surface `t = x`, `n = y`. The corner's sticking impulse needs friction
/// 0.737, beyond the plan's mu (0.3993): the tracked catch slips at its impact.
#[test]
fn the_tracked_catch_strikes_vertex_first_and_needs_more_friction_than_the_plan_has() {
    use dexter_sim::model::arm::geometry::wrap_pi;
    let rig = level(Polygon::square(A, None).unwrap());
    let (th, thd) = (0.2078930924928505, -0.011089917498166688);
    let r_w = V2::new(0.6542020609567085, 0.24164665954044384);
    let v_w = V2::new(-0.4392676093491595, -2.499305428734416);
    let (phi, omega_w) = (1.8074464229256868, 3.2204431199892194);
    let r = r_w.rotate(-th);
    let v = v_w.minus(r_w.perp().scale(thd)).rotate(-th);
    let omega = omega_w - thd;
    // by hand: the lowest vertex and the impulse at it
    let low = (0..4)
        .map(|i| r.plus(rig.body.vertex(i).rotate(phi - th)))
        .min_by(|a, b| a.y.total_cmp(&b.y))
        .unwrap();
    assert!((low.y - 0.05).abs() < 1e-12, "on the surface");
    let rw = r.minus(low);
    let rho2 = A * A / 6.0;
    let after = (rho2 * omega + (rw.x * v.y - rw.y * v.x)) / (rho2 + rw.x * rw.x + rw.y * rw.y);
    let (pt, pn) = (-after * rw.y - v.x, after * rw.x - v.y);
    // the code: the edge nearest flat, its tilt, the pivot and the impact
    let off = wrap_pi(phi - th - rig.alpha_rad(3));
    assert!((off - 0.028757).abs() < 1e-6, "{off}");
    let (p, pv) = rig.tilted(3, off, r);
    assert_eq!((pv.vertex, pv.dir), (3, 1.0));
    let imp = rig.vertex_impact(&pv, &p, off, v, omega);
    assert!((imp.rate_after_radps - after).abs() < 1e-9, "{imp:?}");
    assert!(after < 0.0, "it turns back toward flat");
    assert!((imp.impulse_normal_mps - pn).abs() < 1e-9);
    assert!((imp.impulse_tangential_mps - pt).abs() < 1e-9);
    assert!(
        (imp.friction_ratio() - 0.7370).abs() < 5e-5,
        "{}",
        imp.friction_ratio()
    );
    assert!(imp.judged(0.3993).is_err());
}

/// The arm drops away under the resting square and stops tilted, so that the square
/// falls level onto it corner first: a whole catch through the verifier.
///
/// The arm (link surface 0.05 m above the joint) accelerates clockwise at `A = 80 rad/s^2`
/// for `t1 = 25 ms` and back for `t1`, stopping at `theta_c = -A t1^2 = -0.05 rad` at
/// 50 ms. At the square (0.9 m out) the surface falls at `80 * 0.9 = 72 m/s^2 > g`: the
/// grasp separates at once (the throw's release, at `release_s = 0`), and the square
/// falls level without rotation. Relative to the stopped arm edge 0 is tilted by
/// `+0.05 rad` > `FLAT_TOL_RAD`: its left end, vertex 0, strikes first, at `u` straight
/// down (world). The object is level in the world, so `r - w = (a/2, a/2)` (world) and
/// `(r - w) x v = -u a/2`: `omega+ = -(u a/2) / (a^2/6 + a^2/2) = -3u / 4a`, whatever the
/// tilt, and `Pi = v+ - v = (3u/8, 5u/8)` (world), i.e. along the arm's `t = (cos,
/// sin)(theta_c)` and `n = (-sin, cos)(theta_c)`: `Pi_t = u (3/8 cos 0.05 - 5/8 sin
/// 0.05)`, `Pi_n = u (3/8 sin 0.05 + 5/8 cos 0.05)`; the corner's normal approach speed is
/// `u cos 0.05`. It turns back toward flat, the edge falls back (a `roll_back`), and the
/// square rocks onto vertex 1 at 1/4 of the rate, and so on (`k = 1/4`, each rock's
/// impulse needing friction `(1 - k) / (1 + k) = 3/5`) until it settles: at mu = 2 it is
/// caught on edge 0 and held, through the phases `gfg`; at mu = 0.5 the corner's impulse
/// slips.
#[test]
fn a_square_caught_on_a_corner_falls_back_rocks_and_is_held() {
    use dexter_sim::model::arm::contact::Joint;
    use dexter_sim::model::arm::motion::ArmMotion;
    use dexter_sim::model::arm::params::ArmConfig;
    use dexter_sim::model::arm::simulate::{execute, Executed};
    use dexter_sim::systems::arm::examples;

    struct DropAway;
    const ACC: f64 = 80.0;
    const T1: f64 = 0.025;
    impl ArmMotion for DropAway {
        fn joint(&self, t: f64) -> Joint {
            let (angle, vel, acc) = if t < T1 {
                (-0.5 * ACC * t * t, -ACC * t, -ACC)
            } else if t < 2.0 * T1 {
                let s = 2.0 * T1 - t;
                (-ACC * T1 * T1 + 0.5 * ACC * s * s, -ACC * s, ACC)
            } else {
                (-ACC * T1 * T1, 0.0, 0.0)
            };
            Joint {
                angle_rad: angle,
                velocity_radps: vel,
                accel_radps2: acc,
            }
        }
        fn settled_s(&self) -> f64 {
            2.0 * T1
        }
        fn release_s(&self) -> f64 {
            0.0
        }
        fn breaks_s(&self) -> Vec<f64> {
            vec![T1, 2.0 * T1]
        }
    }

    let text = examples::THROW_CATCH.replace("catch_edge = 3", "catch_edge = 0");
    let sys = ArmConfig::from_toml_str(&text).unwrap().validate().unwrap();
    assert_eq!(sys.start.edge, 0);
    assert!((sys.rig.body.rho_m.powi(2) - A * A / 6.0).abs() < 1e-15);
    let tilt = ACC * T1 * T1;
    assert!((DropAway.joint(1.0).angle_rad + tilt).abs() < 1e-15);

    let e = execute(&sys, &DropAway, 2.0);
    assert_eq!(e.executed, Executed::Ok, "{}: {:?}", e.reason, e.events);
    assert_eq!(e.phases, "gfg");
    assert_eq!(e.catch_index, Some(0));
    let off = e.catch_flat_error_rad.unwrap();
    assert!(
        (off - tilt).abs() < 1e-12,
        "tilted by the arm's stop: {off}"
    );
    let first = &e.impacts[0];
    assert_eq!(first.edge, 0);
    let imp = first.impact;
    let u = imp.speed_mps / tilt.cos();
    assert!(u > 0.5, "a real fall: {u}");
    match imp.outcome {
        Outcome::Rock {
            vertex,
            dir,
            psi_rad,
            ..
        } => assert_eq!((vertex, dir, psi_rad), (0, 1.0, off)),
        o => panic!("expected the corner strike, got {o:?}"),
    }
    assert_eq!(imp.cop_m, 0.0);
    let tol = 1e-9;
    assert!(imp.rate_before_radps.abs() < tol, "{imp:?}");
    assert!(
        (imp.rate_after_radps + 3.0 * u / (4.0 * A)).abs() < tol,
        "{imp:?}"
    );
    let (c, s) = (tilt.cos(), tilt.sin());
    assert!((imp.impulse_tangential_mps - u * (0.375 * c - 0.625 * s)).abs() < tol);
    assert!((imp.impulse_normal_mps - u * (0.375 * s + 0.625 * c)).abs() < tol);
    // then the edge falls back and rocks, each rock a quarter of the last, and settles
    let kinds: Vec<&str> = e.events.iter().map(|ev| ev.kind).collect();
    assert_eq!(
        &kinds[..4],
        ["release", "catch", "rock_ccw", "roll_back"],
        "{kinds:?}"
    );
    assert!(e.impacts.len() >= 3, "{:?}", e.impacts);
    let rates: Vec<f64> = e
        .impacts
        .iter()
        .map(|i| i.impact.rate_after_radps)
        .collect();
    let rock = e.impacts[1].impact;
    assert!(
        matches!(rock.outcome, Outcome::Rock { vertex: 1, dir, psi_rad, .. } if dir == -1.0 && psi_rad == 0.0)
    );
    assert!((rock.friction_ratio() - 0.6).abs() < 0.01, "{rock:?}");
    assert!(
        (rates[1] / rock.rate_before_radps - 0.25).abs() < 1e-9,
        "{rates:?}"
    );
    assert_eq!(e.impacts.last().unwrap().impact.outcome, Outcome::Grasp);

    // the corner's impulse needs more than 0.5
    assert!(imp.friction_ratio() > 0.5);
    let low = execute(&sys, &DropAway, 0.5);
    assert_eq!(low.executed, Executed::Slipped, "{}", low.reason);
    assert!(low.reason.contains("impact"), "{}", low.reason);
    assert_eq!(low.catch_index, Some(0));
}
