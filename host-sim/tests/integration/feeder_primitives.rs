//! The 1JOC primitives, the goal-edge rule, the convergent turn, infeasibility reports,
//! and the four parts to ship as scenes (issue 16, items 2-4).

use crate::common;

use dexter_sim::model::feeder::execute::{
    execute, plan_and_execute, sweep, sweep_arrivals, Noise, SweepSpec,
};
use dexter_sim::model::feeder::geometry::{Pose, Vec2};
use dexter_sim::model::feeder::part::Part;
use dexter_sim::model::feeder::planner::detail::{arrive, jog, turn};
use dexter_sim::model::feeder::planner::goal::{goal_edge, has_parallel_pair};
use dexter_sim::model::feeder::planner::{plan, Feeder, PlanOptions};
use dexter_sim::model::feeder::primitives::{turn_landing_radius_m, Primitive};
use dexter_sim::model::feeder::FeederError;
use dexter_sim::systems::feeder::scene::FeederScene;

fn pts(v: &[(f64, f64)]) -> Vec<Vec2> {
    v.iter().map(|&(x, y)| Vec2::new(x, y)).collect()
}

/// A scene around `vertices` (m); the shapes below are the ones to ship.
fn scene(vertices: &str, extra: &str) -> String {
    format!(
        "[feeder.part]\nvertices_m = {vertices}\n[feeder.belt]\nspeed_mps = 0.05\nwidth_m = 1.0\n\
         [feeder.fence]\nlength_m = 0.5\nmu = 0.3\n[feeder.arrival]\nx_m = 0.2\ny_m = 0.1\nangle_deg = 30.0\n{extra}"
    )
}

const SQUARE: &str = "[[0.0, 0.0], [0.04, 0.0], [0.04, 0.04], [0.0, 0.04]]";
const TRIANGLE: &str = "[[0.0, 0.0], [0.05, 0.0], [0.015, 0.04]]";
const L_PART: &str =
    "[[0.0, 0.0], [0.06, 0.0], [0.06, 0.04], [0.025, 0.04], [0.025, 0.06], [0.0, 0.06]]";
/// Leaning parallelogram: base 40 mm, shift 10 mm, height 10 mm; its short edges are
/// unstable (s (w - s) = 300 mm^2 > h^2 = 100 mm^2), so its only stable edges are the two
/// parallel long ones.
const PARALLEL: &str = "[[0.0, 0.0], [0.04, 0.0], [0.05, 0.01], [0.01, 0.01]]";

fn built(vertices: &str) -> dexter_sim::systems::feeder::scene::Built {
    FeederScene::from_toml_str(&scene(vertices, ""))
        .unwrap()
        .build()
        .unwrap()
}

#[test]
fn the_four_scene_parts_plan_and_feed_from_random_arrivals() {
    for (name, v) in [
        ("square", SQUARE),
        ("triangle", TRIANGLE),
        ("L", L_PART),
        ("parallel", PARALLEL),
    ] {
        let b = built(v);
        let spec = SweepSpec {
            trials: 8,
            seed: 3,
            x_range_m: (0.1, 0.35),
            y_m: 0.1,
        };
        let r = sweep(&b.feeder, &b.options, &spec, None);
        assert_eq!(r.fed, 8, "{name}: {r:?}");
        assert!(r.worst_radius_error_m <= 1e-3, "{name}: {r:?}");
        let s = plan_and_execute(&b.feeder, b.arrival, &b.options, None).unwrap();
        assert!(s.reached_goal, "{name}");
        let json = serde_json::to_value(&s).unwrap();
        for key in common::feeder::SUMMARY_KEYS {
            assert!(json.get(key).is_some(), "{name}: summary lacks {key}");
        }
        assert!(
            !s.frames.is_empty()
                && s.frames
                    .iter()
                    .all(|f| f.part_m.len() == b.feeder.part.vertices.len())
        );
    }
}

#[test]
fn goal_edge_is_the_one_that_cannot_turn_counter_clockwise() {
    // Triangle (0,0), (10,0), (9,1): COM (19/3, 1/3). Edge 1 (10,0)->(9,1): the COM's foot
    // lies at parameter ((3.67, 0.33) . (-1, 1)) / 2 = 2 > 1, past its end: unstable.
    // Edges 0 and 2 are stable; the CCW rotation from edge 2 to edge 0 is
    // 186.3 deg >= 180, so no turn leaves edge 2: it is the goal.
    let p = Part::new(&pts(&[(0.0, 0.0), (10.0, 0.0), (9.0, 1.0)]), None).unwrap();
    assert_eq!(p.stable_edges(), vec![0, 2]);
    assert!((p.rotation_between(2, 0).to_degrees() - 186.34).abs() < 0.01);
    assert_eq!(goal_edge(&p), Some(2));
}

#[test]
fn turn_lands_at_the_closed_form_radius() {
    // The square turned from edge 0 to edge 3 (Psi = 90 deg) with theta- = -40 deg: the
    // simulated landing radius equals r' = r cos Psi - h sin Psi - D sin theta- with
    // D = (r sin Psi + h cos Psi - h') / cos theta- (primitives module doc; hand: r = 0.3,
    // h = h' = 0.02: D = 0.28 / cos 40 = 0.36552, r' = -0.02 + 0.36552 sin 40 = 0.21495).
    let b = built(SQUARE);
    let f = &b.feeder;
    let (st, _, _) = arrive(
        f,
        Pose {
            com_m: Vec2::new(0.3, 0.1),
            angle_rad: 0.0,
        },
        60.0,
    )
    .unwrap();
    assert_eq!(st.edge, 0);
    assert!((st.r_m - 0.3).abs() < 1e-9);
    let tm = -40f64.to_radians();
    let (end, prim, _) = turn(f, &st, 3, 3, tm, false).unwrap();
    let want = -0.02 + 0.28 / tm.cos() * 40f64.to_radians().sin();
    assert!((want - 0.21495).abs() < 1e-5);
    let e = &f.part.edges;
    assert!(
        (turn_landing_radius_m(&e[0], &e[3], 0.3, std::f64::consts::FRAC_PI_2, tm) - want).abs()
            < 1e-12
    );
    assert!((end.r_m - want).abs() < 2e-5, "{} vs {want}", end.r_m);
    assert!(matches!(prim, Primitive::Turn { to_edge: 3, .. }));
}

#[test]
fn jogs_move_the_part_in_and_out_without_turning_it() {
    let b = built(SQUARE);
    let f = &b.feeder;
    let (st, _, _) = arrive(
        f,
        Pose {
            com_m: Vec2::new(0.25, 0.1),
            angle_rad: 0.0,
        },
        60.0,
    )
    .unwrap();
    for target in [0.32, 0.2, 0.2504] {
        let (end, prim, _) = jog(f, &st, target).unwrap();
        assert_eq!(end.edge, st.edge);
        assert!((end.r_m - target).abs() < 1e-4, "{target}: {}", end.r_m);
        assert!((end.pose.angle_rad - st.pose.angle_rad).abs() < 1e-6);
        let Primitive::Jog { tilt_rad, .. } = prim else {
            panic!()
        };
        assert_eq!(
            tilt_rad < 0.0,
            target > st.r_m,
            "outward jogs tilt the fence down"
        );
    }
}

fn parallelograms() -> Vec<Part> {
    // Base w, shift s, height h with s (w - s) > h^2: exactly two parallel stable edges.
    [
        (0.04, 0.01, 0.01),
        (0.05, 0.02, 0.015),
        (0.045, 0.03, 0.012),
    ]
    .iter()
    .map(|&(w, s, h)| Part::new(&pts(&[(0.0, 0.0), (w, 0.0), (w + s, h), (s, h)]), None).unwrap())
    .collect()
}

#[test]
fn convergent_turn_is_used_exactly_for_parallel_two_stable_edge_parts() {
    let others = [
        SQUARE,
        TRIANGLE,
        L_PART,
        "[[0.0, 0.0], [0.05, 0.0], [0.05, 0.02], [0.0, 0.02]]",
    ];
    let spec = SweepSpec {
        trials: 8,
        seed: 5,
        x_range_m: (0.1, 0.35),
        y_m: 0.1,
    };
    let base = built(SQUARE).feeder;
    let mut convergent_seen = 0;
    let parts = parallelograms()
        .into_iter()
        .map(|p| (true, p))
        .chain(others.iter().map(|v| (false, built(v).feeder.part)));
    for (parallel, part) in parts {
        assert_eq!(has_parallel_pair(&part), parallel);
        let f = Feeder {
            part,
            ..base.clone()
        };
        for a in sweep_arrivals(&spec) {
            let p = plan(&f, a, &PlanOptions::default())
                .unwrap_or_else(|e| panic!("{:?} from {a:?}: {e}", f.part.hull));
            let conv = p
                .steps
                .iter()
                .filter(|s| matches!(s, Primitive::ConvergentTurn { .. }))
                .count();
            assert_eq!(
                conv,
                usize::from(parallel && p.start_edge != p.goal_edge),
                "{:?}",
                p.steps
            );
            convergent_seen += conv;
            assert!(execute(&f, &p, a, None).reached_goal);
        }
    }
    assert!(convergent_seen > 0);
}

#[test]
fn parallel_parts_cannot_be_fed_without_the_convergent_turn() {
    let base = built(SQUARE).feeder;
    let spec = SweepSpec {
        trials: 12,
        seed: 5,
        x_range_m: (0.1, 0.35),
        y_m: 0.1,
    };
    let off = PlanOptions {
        allow_convergent: false,
        ..PlanOptions::default()
    };
    for part in parallelograms() {
        let f = Feeder {
            part,
            ..base.clone()
        };
        let with = sweep(&f, &PlanOptions::default(), &spec, None);
        let without = sweep(&f, &off, &spec, None);
        assert_eq!(with.fed, 12, "{with:?}");
        assert!(without.fed < 12 && without.unplanned > 0, "{without:?}");
        assert!(
            without.errors.iter().all(|e| e.contains("convergent turn")),
            "{:?}",
            without.errors
        );
    }
}

#[test]
fn infeasibility_names_the_fence_or_the_belt() {
    let short = scene(SQUARE, "")
        .replace("length_m = 0.5", "length_m = 0.12")
        .replace("x_m = 0.2", "x_m = 0.06");
    let b = FeederScene::from_toml_str(&short).unwrap().build().unwrap();
    let a = Pose {
        com_m: Vec2::new(0.06, 0.1),
        angle_rad: 2.0,
    };
    let e = plan(&b.feeder, a, &b.options).unwrap_err();
    assert!(matches!(e, FeederError::Infeasible(_)));
    assert!(
        e.to_string().contains("fence too short")
            && e.to_string().contains("feeder.fence.length_m"),
        "{e}"
    );
    let narrow = scene(SQUARE, "").replace("width_m = 1.0", "width_m = 0.3");
    let narrow = narrow.replace("x_m = 0.2", "x_m = 0.1");
    let b = FeederScene::from_toml_str(&narrow)
        .unwrap()
        .build()
        .unwrap();
    let e = plan(
        &b.feeder,
        Pose {
            com_m: Vec2::new(0.08, 0.1),
            angle_rad: 2.0,
        },
        &b.options,
    )
    .unwrap_err();
    assert!(
        e.to_string().contains("belt too narrow") && e.to_string().contains("feeder.belt.width_m"),
        "{e}"
    );
}

#[test]
fn scene_errors_name_the_dotted_key() {
    let cases = [
        (
            scene(SQUARE, "").replace("speed_mps = 0.05", "speed_mps = -0.05"),
            "feeder.belt.speed_mps",
        ),
        (
            scene(SQUARE, "").replace("mu = 0.3", "mu = -1.0"),
            "feeder.fence.mu",
        ),
        (
            scene(SQUARE, "").replace("length_m = 0.5", "length_m = 0.5\nlenght = 2"),
            "feeder.fence.lenght",
        ),
        (
            scene(SQUARE, "[feeder.goal]\ncontact_radius_m = -0.1\n"),
            "feeder.goal.contact_radius_m",
        ),
        (
            scene(SQUARE, "[feeder.noise]\nbelt_speed_rel = -0.1\n"),
            "feeder.noise.belt_speed_rel",
        ),
        (
            scene(SQUARE, "").replace("y_m = 0.1", "y_m = 0.01"),
            "feeder.arrival.y_m",
        ),
        (
            scene(SQUARE, "").replace("x_m = 0.2", "x_m = 0.49"),
            "feeder.arrival.x_m",
        ),
        (
            scene("[[0.0, 0.0], [0.04, 0.0]]", ""),
            "feeder.part.vertices_m",
        ),
        (scene(SQUARE, "[feeder.part2]\n"), "feeder.part2"),
        (
            scene(SQUARE, "").replace("mu = 0.3", "mu = 0.3\nmax_angle_deg = 95.0"),
            "feeder.fence.max_angle_deg",
        ),
    ];
    for (text, key) in cases {
        let e = FeederScene::from_toml_str(&text)
            .and_then(|s| s.build())
            .unwrap_err();
        assert!(e.to_string().contains(key), "{key}: {e}");
    }
    let com = scene(SQUARE, "").replace(
        "[feeder.belt]",
        "center_of_mass_m = [0.05, 0.02]\n[feeder.belt]",
    );
    let e = FeederScene::from_toml_str(&com)
        .unwrap()
        .build()
        .unwrap_err();
    assert!(
        e.to_string().contains("feeder.part.center_of_mass_m"),
        "{e}"
    );
}

#[test]
fn noisy_sweeps_are_seeded_and_report_a_fraction() {
    let b = built(TRIANGLE);
    let spec = SweepSpec {
        trials: 6,
        seed: 2,
        x_range_m: (0.1, 0.35),
        y_m: 0.1,
    };
    let noise = Noise {
        seed: 9,
        belt_speed_rel: 0.05,
        fence_mu_rel: 0.2,
        arrival_xy_m: 0.005,
        arrival_angle_rad: 0.05,
    };
    let r1 = sweep(&b.feeder, &b.options, &spec, Some(&noise));
    let r2 = sweep(&b.feeder, &b.options, &spec, Some(&noise));
    assert_eq!(r1, r2);
    assert!(
        (0.0..=1.0).contains(&r1.fraction_fed)
            && r1.fed == (r1.fraction_fed * 6.0).round() as usize
    );
}
