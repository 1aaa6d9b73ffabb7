//! The paper's jog, "a sequence of small stable pushes interleaved with drift" (sec. 3.1),
//! as derived in `primitives.rs`: one step checked against the closed form by hand, jogs
//! both ways, and a part whose center-of-mass foot lies half a millimetre from the end
//! of the edge it arrives on, at a radius below the old fixed-floor minimum (the case of
//! part 44 of the feeding sweep), now planned and fed.

use crate::common;

use dexter_sim::model::feeder::execute::{execute, FEED_TOL_M};
use dexter_sim::model::feeder::geometry::{Pose, Vec2};
use dexter_sim::model::feeder::part::Part;
use dexter_sim::model::feeder::planner::detail::{
    arrive, drift_jog, drift_step, drift_step_limit_rad, jog, State,
};
use dexter_sim::model::feeder::planner::{plan, Feeder, PlanOptions};
use dexter_sim::model::feeder::primitives::{
    can_jog, drift_landing_limit_rad, drift_step_radius_m, landing_sticks, Primitive,
};

fn pts(v: &[(f64, f64)]) -> Vec<Vec2> {
    v.iter().map(|&(x, y)| Vec2::new(x, y)).collect()
}

use common::feeder::cell;

/// The 40 mm square, edge 0 (the bottom, a = b = h = 20 mm) flush at `r_m`.
fn square_at(mu: f64, r_m: f64) -> (Feeder, State) {
    let sq = pts(&[(0.0, 0.0), (0.04, 0.0), (0.04, 0.04), (0.0, 0.04)]);
    let f = cell(Part::new(&sq, None).unwrap(), mu);
    let arrival = Pose {
        com_m: Vec2::new(r_m, 0.1),
        angle_rad: 0.0,
    };
    let (st, _, _) = arrive(&f, arrival, 60.0).unwrap();
    assert_eq!(st.edge, 0);
    assert!((st.r_m - r_m).abs() < 1e-9);
    (f, st)
}

#[test]
fn one_push_and_drift_step_moves_the_start_vertex_by_the_cosine_ratio() {
    // Square of side 40 mm, edge 0 flush at r = 0.2 m, so its start vertex is at
    // u = r - a = 0.18 m. Drift keeps every x; a stable push keeps every fence
    // coordinate; the landing vertex sticks (hand: rho = 0.38260 * 0.04 = 15.30 mm,
    // rho^2 = 2.342e-4 m^2; at theta2 = 0, a h = 4.0e-4 <= mu (rho^2 + h^2) = 6.34e-4 with
    // mu = 1; at theta2 = -10 deg, F_t : F_n = (6.342e-4 (-0.17365) + 4e-4 (0.98481)) :
    // (4e-4 (-0.17365) + 6.342e-4 (0.98481)) = 2.838e-4 : 5.551e-4 = 0.51 <= 1). So:
    //   outward, fence dropped to -10 deg, part caught there, pushed back to 0:
    //     r' = a + u / cos 10 deg = 0.02 + 0.18 / 0.984808 = 0.202777 m;
    //   inward, pushed to +10 deg, fence dropped to 0, part caught there:
    //     r' = a + u cos 10 deg = 0.02 + 0.18 * 0.984808 = 0.197265 m.
    let (f, st) = square_at(1.0, 0.2);
    let e = &f.part.edges[0];
    let d = 10f64.to_radians();
    assert!(landing_sticks(e, f.part.rho_m, 1.0, 0.0) && landing_sticks(e, f.part.rho_m, 1.0, -d));
    for (angle, want) in [(-d, 0.202777), (d, 0.197265)] {
        assert!(
            (drift_step_radius_m(e, 0.2, angle.max(0.0), angle.min(0.0)) - want).abs() < 1e-6,
            "closed form at {angle}"
        );
        let (end, sched) = drift_step(&f, &st, angle).unwrap();
        assert_eq!(end.edge, 0);
        assert!(
            (end.r_m - want).abs() < 2e-5,
            "step at {:.1} deg: r = {:.6} m, hand {want}",
            angle.to_degrees(),
            end.r_m
        );
        // The part's angle is unchanged and the fence ends at 0.
        assert!(
            (end.pose.angle_rad - st.pose.angle_rad).abs() < 1e-6,
            "{} vs {}",
            end.pose.angle_rad,
            st.pose.angle_rad
        );
        assert_eq!(sched.end_angle(), 0.0);
        // The fence went the way the step says: below 0 for outward, above for inward.
        let extreme =
            sched
                .knots
                .iter()
                .map(|k| k.1)
                .fold(0.0f64, |m, a| if a.abs() > m.abs() { a } else { m });
        assert!((extreme - angle).abs() < 1e-12, "{extreme} vs {angle}");
    }
}

#[test]
fn a_sliding_landing_slips_toward_the_pivot() {
    // mu = 0.3: a h = 4.0e-4 > mu (rho^2 + h^2) = 1.9e-4, so the landing vertex slides,
    // toward the pivot (F_t > 0 at theta2 = 0): the inward step goes further in than the
    // sticking closed form, the outward one gains less than it.
    let (f, st) = square_at(0.3, 0.2);
    let e = &f.part.edges[0];
    let d = 10f64.to_radians();
    assert!(!landing_sticks(e, f.part.rho_m, 0.3, 0.0));
    let (inward, _) = drift_step(&f, &st, d).unwrap();
    assert!(
        inward.r_m < drift_step_radius_m(e, 0.2, d, 0.0) - 1e-4,
        "{}",
        inward.r_m
    );
    let (outward, _) = drift_step(&f, &st, -d).unwrap();
    assert!(
        outward.r_m < drift_step_radius_m(e, 0.2, 0.0, -d) - 1e-4,
        "{}",
        outward.r_m
    );
}

#[test]
fn push_and_drift_jogs_reach_their_radius_both_ways() {
    for (mu, target) in [(1.0, 0.23), (1.0, 0.17), (0.3, 0.17)] {
        let (f, st) = square_at(mu, 0.2);
        let (end, prim, sched) = drift_jog(&f, &st, target).unwrap();
        assert_eq!(end.edge, 0);
        assert!(
            (end.r_m - target).abs() < 1e-4,
            "mu {mu} to {target}: {}",
            end.r_m
        );
        assert!((end.pose.angle_rad - st.pose.angle_rad).abs() < 1e-6);
        let Primitive::DriftJog {
            step_angles_rad, ..
        } = &prim
        else {
            panic!("{prim:?}")
        };
        // Outward steps catch below 0, inward ones release above it.
        assert!(step_angles_rad
            .iter()
            .all(|a| (*a < 0.0) == (target > st.r_m)));
        // Its schedule, executed from the start, ends where the planner said.
        assert!((sched.end_s() - end.t_s).abs() < 1e-9);
    }
}

/// A hand-made part like part 44 of the feeding sweep: its bottom edge (hull edge 1) runs
/// from (-6, 0) to (0.5, 0) mm under the center of mass at (0, 30) mm, so the COM's foot
/// lies a = 6 mm from the start and b = 0.5 mm from the end, h = 30 mm above.
fn near_end_part() -> Part {
    let v = pts(&[
        (-0.006, 0.0),
        (0.0005, 0.0),
        (0.025, 0.02),
        (0.01, 0.055),
        (-0.02, 0.045),
        (-0.025, 0.015),
    ]);
    Part::new(&v, Some(Vec2::new(0.0, 0.03))).unwrap()
}

#[test]
fn a_part_whose_com_foot_is_half_a_millimetre_from_a_vertex_is_fed() {
    let p = near_end_part();
    // (the hull starts at the lowest-leftmost vertex: that edge is hull edge 1)
    let e = p.edges[1];
    assert!((e.a_m - 0.006).abs() < 1e-12 && (e.b_m() - 0.0005).abs() < 1e-12);
    assert!((e.h_m - 0.03).abs() < 1e-12);
    let f = cell(p, 0.3);
    // Arriving flush on edge 0 at r = 0.2 m. Before the edge's own rate floor, pushes ran
    // no slower than 2/64 rad/s, which holds the resultant before the end vertex at
    // theta = 0 only from r = (rho^2 + h^2)/(k b) - v_b / (2/64) on (hand, k = 0.9):
    let rho = f.part.rho_m;
    let old_min = (rho * rho + 0.03 * 0.03) / (0.9 * 0.0005) - 0.05 / (2.0 / 64.0);
    assert!(old_min > 0.9, "{old_min}");
    // and the slide jog cannot move it out (it would tip over the end vertex).
    assert!(!can_jog(&e, 0.3, true));
    let arrival = Pose {
        com_m: Vec2::new(0.2, 0.1),
        angle_rad: 0.0,
    };
    let (st, _, _) = arrive(&f, arrival, 60.0).unwrap();
    assert_eq!(st.edge, 1);
    let pl = plan(&f, arrival, &PlanOptions::default()).unwrap();
    let ex = execute(&f, &pl, arrival, None);
    assert!(ex.reached_goal, "{ex:?}\n{:?}", pl.steps);
    assert_eq!(ex.final_edge, Some(pl.goal_edge));
    assert!(ex.radius_error_m.abs() <= FEED_TOL_M);
    // The same part can also be jogged out on that edge, by push-and-drift only: the
    // steps rest the part at most atan(k b / h) = 0.86 deg below 0 (0.5 deg on the angle
    // grid), a gain of about u (1 / cos 0.5 deg - 1) = 7.4 um per step at u = 0.194 m,
    // so 0.6 mm takes about 81 steps.
    let (end, prim, _) = jog(&f, &st, st.r_m + 6e-4).unwrap();
    let Primitive::DriftJog {
        step_angles_rad, ..
    } = &prim
    else {
        panic!("{prim:?}")
    };
    let n = step_angles_rad.len();
    assert!((75..=90).contains(&n), "{n} steps");
    assert!(
        (end.r_m - st.r_m - 6e-4).abs() < 1e-4,
        "{}",
        end.r_m - st.r_m
    );
}

#[test]
fn an_inward_step_is_no_wider_than_the_landing_can_turn_back() {
    // Released at delta, the part lands on the edge's start vertex; the fence's force
    // acts there, so only the belt's drag through the COM turns the part about it:
    // back onto the edge iff the COM lies beyond the vertex in world x,
    // a cos delta - h sin delta > 0, tan delta < a / h. A regular 12-gon of circumradius
    // 30 mm (hand: side 2 R sin 15 deg = 15.529 mm, a = 7.765 mm, h = R cos 15 deg =
    // 28.978 mm, a / h = 0.26795 = tan 15 deg) with margin k = 0.9:
    // atan(0.9 * 0.26795) = 13.557 deg, 13.5 deg on the 0.5 deg grid. (Its exterior angle
    // bound, 0.8 * 30 = 24 deg, and with mu = 1 the jog tilt, 60 deg, are wider.)
    let v: Vec<Vec2> = (0..12)
        .map(|i| {
            let t = std::f64::consts::TAU * f64::from(i) / 12.0;
            Vec2::new(0.03 * t.cos(), 0.03 * t.sin())
        })
        .collect();
    let f = cell(Part::new(&v, None).unwrap(), 1.0);
    let (st, _, _) = arrive(
        &f,
        Pose {
            com_m: Vec2::new(0.3, 0.1),
            // an edge flat at the bottom (a vertex down would balance on it)
            angle_rad: std::f64::consts::PI / 12.0,
        },
        60.0,
    )
    .unwrap();
    let lim = drift_step_limit_rad(&f, st.edge, st.r_m, false);
    assert!(
        (lim.to_degrees() - 13.5).abs() < 1e-9,
        "{}",
        lim.to_degrees()
    );
    assert!((drift_landing_limit_rad(&f.part, st.edge).to_degrees() - 24.0).abs() < 1e-9);
    let (end, _) = drift_step(&f, &st, lim).unwrap();
    assert_eq!(end.edge, st.edge);
    // Past tan delta = a / h (15 deg), at 20 deg, the part turns onto the previous edge.
    let err = drift_step(&f, &st, 20f64.to_radians()).unwrap_err();
    assert!(err.contains("tipped"), "{err}");
}
