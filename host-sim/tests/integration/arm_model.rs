//! The arm model's contact laws against independent computations: hand-derived grasp cases,
//! the roll against Newton-Euler in maximal coordinates with the contact force solved as a
//! linear system, flight against its closed form, the torque against statics.

use dexter_sim::model::arm::contact::{ArmInertia, BodyState, Joint, Placement, Rig};
use dexter_sim::model::arm::geometry::{Polygon, Surface, V2};
use std::f64::consts::FRAC_PI_4;

const G: f64 = 9.81;

/// A 0.1 m square on a link surface whose line lies `surface_y` above the link's axis.
fn rig(surface_y: f64) -> Rig {
    Rig {
        body: Polygon::square(0.1, None).unwrap(),
        surface: Surface {
            origin: V2::new(0.0, surface_y),
            beta_rad: 0.0,
            length_m: 1.22,
        },
        gravity_mps2: G,
    }
}

/// Edge 0 (the bottom) flat, its first vertex at sigma = 0.85 m (centre at 0.9 m).
const AT: Placement = Placement {
    edge: 0,
    sigma_m: 0.85,
};

fn joint(angle: f64, vel: f64, acc: f64) -> Joint {
    Joint {
        angle_rad: angle,
        velocity_radps: vel,
        accel_radps2: acc,
    }
}

#[test]
fn horizontal_surface_accelerating_up_needs_g_plus_a_and_no_friction() {
    // surface 5 cm below the axis: the centre of mass is on the axis, at x = 0.9 m, so
    // with theta = 0, theta' = 0 it accelerates straight up at a = 0.9 theta''
    let r = rig(-0.05);
    for alpha in [0.0, 5.0, 20.0] {
        let g = r.grasp(&AT, &joint(0.0, 0.0, alpha));
        let a = 0.9 * alpha;
        assert!((g.force.normal - (G + a)).abs() < 1e-12);
        assert!(g.force.tangential.abs() < 1e-12);
        assert_eq!(g.force.friction_ratio(), 0.0);
        // the centre of pressure shifts forward by rho^2 theta'' / f_n: the contact must
        // also spin the body up with the arm
        let rho2 = 0.01 / 6.0;
        assert!((g.cop_m - (0.05 + rho2 * alpha / (G + a))).abs() < 1e-12);
    }
}

#[test]
fn tilted_surface_at_rest_needs_tan_tilt_and_tips_at_45_degrees() {
    let r = rig(0.05);
    for b in [0.1f64, 0.5, -0.5, FRAC_PI_4] {
        let g = r.grasp(&AT, &joint(b, 0.0, 0.0));
        assert!((g.force.normal - G * b.cos()).abs() < 1e-12);
        assert!((g.force.tangential - G * b.sin()).abs() < 1e-12);
        assert!((g.force.friction_ratio() - b.tan().abs()).abs() < 1e-12);
        assert!(g.force.in_cone(b.tan().abs() * 1.001));
        assert!(!g.force.in_cone(b.tan().abs() * 0.999), "tilt {b}");
        // centre of pressure (a/2)(1 - tan b): on the lower vertex at 45 degrees
        assert!((g.cop_m - 0.05 * (1.0 - b.tan())).abs() < 1e-12);
    }
}

#[test]
fn a_surface_pulled_away_faster_than_gravity_loses_the_object() {
    let r = rig(-0.05);
    let g = r.grasp(&AT, &joint(0.0, 0.0, -12.0)); // 0.9 * 12 > g downward
    assert!(g.force.normal < 0.0);
    assert!(!g.force.in_cone(10.0));
    assert_eq!(g.force.friction_ratio(), f64::INFINITY);
}

#[test]
fn static_torque_is_the_weights_moments() {
    let r = rig(0.05);
    let arm = ArmInertia {
        inertia_kgm2: 2.2,
        gravity_torque_nm: 25.0,
        gravity_phase_rad: 0.0,
    };
    let j = joint(0.3, 0.0, 0.0);
    let s = r.grasped_state(&AT, &j);
    let f = V2::new(0.0, G);
    let tau = arm.torque_nm(&j) + ArmInertia::load_torque_nm(0.2, 0.04, s.com, f, 0.0);
    let expect = 25.0 * 0.3f64.cos() + 0.2 * G * s.com.x;
    assert!((tau - expect).abs() < 1e-12);
    // the centre of mass: 0.9 m along the link, 0.1 m above its axis
    let c = V2::new(0.9, 0.1).rotate(0.3);
    assert!((s.com.x - c.x).abs() < 1e-12 && (s.com.y - c.y).abs() < 1e-12);
}

#[test]
fn roll_starts_exactly_when_the_centre_of_pressure_reaches_the_vertex() {
    // the grasp's s = 0 and the roll's psi'' = 0 at psi = psi' = 0 are the same condition
    let r = rig(0.05);
    let pv = r.pivot(&AT, 1.0);
    let (theta, w) = (0.6, 1.5);
    let s_of = |acc: f64| r.grasp(&AT, &joint(theta, w, acc)).cop_m;
    // bisect theta'' for s = 0 (s decreases as the arm decelerates)
    let (mut lo, mut hi) = (-8.0, 8.0);
    assert!(s_of(lo) < 0.0 && s_of(hi) > 0.0);
    for _ in 0..200 {
        let mid = 0.5 * (lo + hi);
        if s_of(mid) < 0.0 {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    let roll = r.roll(&pv, 0.0, 0.0, &joint(theta, w, lo));
    assert!(
        roll.psi_accel_radps2.abs() < 1e-9,
        "{}",
        roll.psi_accel_radps2
    );
    // beyond it the roll accelerates the right way, short of it the wrong way
    assert!(
        r.roll(&pv, 0.0, 0.0, &joint(theta, w, lo - 1.0))
            .psi_accel_radps2
            > 0.0
    );
    assert!(
        r.roll(&pv, 0.0, 0.0, &joint(theta, w, hi + 1.0))
            .psi_accel_radps2
            < 0.0
    );
    // and the grasp force equals the roll force there
    let g = r.grasp(&AT, &joint(theta, w, lo));
    assert!((g.force.normal - roll.force.normal).abs() < 1e-8);
    assert!((g.force.tangential - roll.force.tangential).abs() < 1e-8);
}

#[test]
fn roll_hand_cases_square_tipping_off_a_still_level_arm() {
    // A square of side a = 0.1 m on a still, level arm, rho^2 = a^2 / 6. About a bottom
    // vertex the centre of mass sits at d = (+-a/2, a/2); by hand (moments about the
    // pivot): (rho^2 + |d|^2) phi'' = -d_x g, so phi'' = -+3 g / (4 a), the centre of mass
    // accelerates phi'' J d = (+-3 g / 8, -3 g / 8), and the pivot pushes with
    // f = (+-3 g / 8, 5 g / 8): to start the tip without slipping needs mu >= 3/5.
    let r = rig(0.05);
    let still = joint(0.0, 0.0, 0.0);
    let a = 0.1;
    for (dir, d_x) in [(1.0, 0.05f64), (-1.0, -0.05)] {
        let pv = r.pivot(&AT, dir);
        let roll = r.roll(&pv, 0.0, 0.0, &still);
        let sign = d_x.signum();
        assert!((roll.phi_accel_radps2 + sign * 3.0 * G / (4.0 * a)).abs() < 1e-9);
        assert!((roll.psi_accel_radps2 - roll.phi_accel_radps2).abs() < 1e-12);
        assert!(
            (roll.force.tangential - sign * 3.0 * G / 8.0).abs() < 1e-9,
            "dir {dir}"
        );
        assert!((roll.force.normal - 5.0 * G / 8.0).abs() < 1e-9);
        assert!((roll.force.friction_ratio() - 0.6).abs() < 1e-9);
        assert!(roll.force.in_cone(0.601) && !roll.force.in_cone(0.599));
        // balanced on the vertex (psi = dir pi/4, centre of mass straight above it at
        // a / sqrt 2) and spinning at w: no torque, f = g - w^2 a / sqrt 2 along the normal
        for w in [0.0, 5.0, 20.0] {
            let top = r.roll(&pv, dir * FRAC_PI_4, w, &still);
            let h = a / 2f64.sqrt();
            assert!(top.phi_accel_radps2.abs() < 1e-9);
            assert!((top.force.normal - (G - w * w * h)).abs() < 1e-9, "w {w}");
            assert!(top.force.tangential.abs() < 1e-9);
        }
        // spun fast enough the vertex would have to pull: no cone holds it
        let fast = r.roll(&pv, dir * FRAC_PI_4, 20.0, &still);
        assert!(!fast.force.in_cone(100.0));
    }
}

/// A prescribed arm motion with analytic derivatives.
fn arm(t: f64) -> Joint {
    // tilted past 45 degrees and swinging down: the square tips back over its lower vertex
    let (a, w) = (0.15, 6.0);
    joint(
        0.95 - a * (1.0 - (w * t).cos()),
        -a * w * (w * t).sin(),
        -a * w * w * (w * t).cos(),
    )
}

/// Solve a small dense linear system by Gaussian elimination with partial pivoting.
fn solve<const N: usize>(mut a: [[f64; N]; N], mut b: [f64; N]) -> [f64; N] {
    for c in 0..N {
        let p = (c..N)
            .max_by(|&i, &j| a[i][c].abs().total_cmp(&a[j][c].abs()))
            .unwrap();
        a.swap(c, p);
        b.swap(c, p);
        let pivot = a[c];
        for r in c + 1..N {
            let f = a[r][c] / pivot[c];
            for (x, p) in a[r].iter_mut().zip(pivot).skip(c) {
                *x -= f * p;
            }
            b[r] -= f * b[c];
        }
    }
    let mut x = [0.0; N];
    for r in (0..N).rev() {
        let s: f64 = (r + 1..N).map(|k| a[r][k] * x[k]).sum();
        x[r] = (b[r] - s) / a[r][r];
    }
    x
}

/// Newton-Euler in maximal coordinates: unknowns (a_x, a_y, phi'', F_x, F_y) with the
/// pivot's body point accelerating with the arm's point. State (x, y, phi, x', y', phi').
fn newton_euler(r: &Rig, pivot_arm: V2, pivot_body: V2, t: f64, s: [f64; 6]) -> ([f64; 6], V2) {
    let j = arm(t);
    let u = pivot_body.rotate(s[2]); // centre of mass to pivot, world
    let w = s[5];
    let a_p = j.point_accel(pivot_arm);
    let rho2 = r.body.rho_m.powi(2);
    let m = [
        [1.0, 0.0, 0.0, -1.0, 0.0],
        [0.0, 1.0, 0.0, 0.0, -1.0],
        [0.0, 0.0, rho2, u.y, -u.x],
        [1.0, 0.0, -u.y, 0.0, 0.0],
        [0.0, 1.0, u.x, 0.0, 0.0],
    ];
    let b = [0.0, -G, 0.0, a_p.x + w * w * u.x, a_p.y + w * w * u.y];
    let x = solve(m, b);
    ([s[3], s[4], s[5], x[0], x[1], x[2]], V2::new(x[3], x[4]))
}

fn rk4<const N: usize>(
    s: [f64; N],
    t: f64,
    h: f64,
    f: impl Fn(f64, [f64; N]) -> [f64; N],
) -> [f64; N] {
    let add = |a: [f64; N], b: [f64; N], k: f64| {
        let mut c = a;
        for i in 0..N {
            c[i] += k * b[i];
        }
        c
    };
    let k1 = f(t, s);
    let k2 = f(t + h / 2.0, add(s, k1, h / 2.0));
    let k3 = f(t + h / 2.0, add(s, k2, h / 2.0));
    let k4 = f(t + h, add(s, k3, h));
    let mut out = s;
    for i in 0..N {
        out[i] += h / 6.0 * (k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i]);
    }
    out
}

#[test]
fn roll_matches_newton_euler_in_maximal_coordinates() {
    let r = rig(0.05);
    let pv = r.pivot(&AT, 1.0);
    let pivot_arm = r.surface.point(pv.sigma_m);
    let pivot_body = r.body.vertex(pv.vertex);
    let st = r.rolling_state(&pv, 0.0, 0.0, &arm(0.0));
    let mut full = [
        st.com.x,
        st.com.y,
        st.angle_rad,
        st.velocity.x,
        st.velocity.y,
        st.angular_velocity_radps,
    ];
    let mut red = [0.0f64, 0.0];
    let h = 1e-4;
    let mut t = 0.0;
    let mut max_psi: f64 = 0.0;
    for _ in 0..2500 {
        full = rk4(full, t, h, |t, s| {
            newton_euler(&r, pivot_arm, pivot_body, t, s).0
        });
        red = rk4(red, t, h, |t, s| {
            [s[1], r.roll(&pv, s[0], s[1], &arm(t)).psi_accel_radps2]
        });
        t += h;
        let j = arm(t);
        let psi_full = full[2] - j.angle_rad - pv.alpha0_rad;
        assert!(
            (psi_full - red[0]).abs() < 1e-9,
            "t {t}: {psi_full} vs {}",
            red[0]
        );
        let (_, f_full) = newton_euler(&r, pivot_arm, pivot_body, t, full);
        let f_red = r.roll(&pv, red[0], red[1], &j).force;
        let n = r.surface.normal().rotate(j.angle_rad);
        assert!((f_full.dot(n) - f_red.normal).abs() < 1e-7);
        let tt = r.surface.tangent().rotate(j.angle_rad);
        assert!((f_full.dot(tt) - f_red.tangential).abs() < 1e-7);
        max_psi = max_psi.max(red[0]);
        if red[0] >= pv.gamma_rad || red[0] < 0.0 {
            break;
        }
    }
    assert!(
        max_psi > 0.3,
        "the test rolls the square a good way: {max_psi}"
    );
}

#[test]
fn flight_is_the_closed_form_parabola() {
    let s = BodyState {
        com: V2::new(0.5, 0.2),
        velocity: V2::new(-1.0, 3.0),
        angle_rad: 0.3,
        angular_velocity_radps: 4.0,
    };
    let apex = s.flown(3.0 / G, G);
    assert!((apex.com.y - (0.2 + 9.0 / (2.0 * G))).abs() < 1e-12);
    assert!(apex.velocity.y.abs() < 1e-12);
    assert!((apex.com.x - (0.5 - 3.0 / G)).abs() < 1e-12);
    let two = s.flown(0.13, G).flown(0.29, G);
    let one = s.flown(0.42, G);
    assert!((two.com.y - one.com.y).abs() < 1e-12 && (two.angle_rad - one.angle_rad).abs() < 1e-12);
    assert!((one.angle_rad - (0.3 + 4.0 * 0.42)).abs() < 1e-12);
}

#[test]
fn a_roll_lands_on_the_next_edge_where_the_geometry_says() {
    let r = rig(0.05);
    for dir in [1.0, -1.0] {
        let pv = r.pivot(&AT, dir);
        let land = r.landed(&pv);
        let j = joint(0.2, 0.0, 0.0);
        // the rolled body at psi = dir * gamma equals the grasped body on the new edge
        let rolled = r.rolling_state(&pv, dir * pv.gamma_rad, 0.0, &j);
        let grasped = r.grasped_state(&land, &j);
        assert!(rolled.com.minus(grasped.com).norm() < 1e-12, "dir {dir}");
        let da = rolled.angle_rad - grasped.angle_rad;
        assert!((da - std::f64::consts::TAU * (da / std::f64::consts::TAU).round()).abs() < 1e-12);
        assert!((r.impact_speed_mps(&pv, -2.0) - 0.2).abs() < 1e-12);
    }
}
