use dexter_sim::model::feeder::geometry::{Pose, Vec2};
use dexter_sim::model::feeder::part::Part;
use dexter_sim::model::feeder::planner::{plan, Feeder, PlanOptions};
use dexter_sim::model::feeder::primitives::Drive;
use dexter_sim::model::feeder::quasistatic::Medium;
use dexter_sim::model::feeder::sim::Setup;

fn feeder(v: &[(f64, f64)]) -> Feeder {
    let pts: Vec<Vec2> = v.iter().map(|&(x, y)| Vec2::new(x, y)).collect();
    Feeder {
        part: Part::new(&pts, None).unwrap(),
        setup: Setup {
            medium: Medium {
                belt_speed_mps: 0.05,
                fence_mu: 0.3,
            },
            fence_length_m: 0.4,
            belt_edge_m: 0.4,
        },
        drive: Drive {
            push_rate_radps: 0.5,
            max_rate_radps: 3.0,
            max_angle_rad: 80f64.to_radians(),
            jog_tilt_rad: (0.3f64.atan() + 15f64.to_radians()),
        },
    }
}

#[test]
fn smoke() {
    for (name, v) in [
        (
            "square",
            vec![(0.0, 0.0), (0.04, 0.0), (0.04, 0.04), (0.0, 0.04)],
        ),
        ("triangle", vec![(0.0, 0.0), (0.05, 0.0), (0.015, 0.04)]),
        (
            "L",
            vec![
                (0.0, 0.0),
                (0.06, 0.0),
                (0.06, 0.02),
                (0.02, 0.02),
                (0.02, 0.05),
                (0.0, 0.05),
            ],
        ),
        (
            "para",
            vec![(0.0, 0.0), (0.04, 0.0), (0.05, 0.01), (0.01, 0.01)],
        ),
    ] {
        let f = feeder(&v);
        println!(
            "{name}: stable {:?} rho {}",
            f.part.stable_edges(),
            f.part.rho_m
        );
        for k in 0..6 {
            let arr = Pose {
                com_m: Vec2::new(0.1 + 0.02 * k as f64, 0.1),
                angle_rad: 0.9 * k as f64 + 0.3,
            };
            let t0 = std::time::Instant::now();
            match plan(&f, arr, &PlanOptions::default()) {
                Ok(p) => {
                    println!(
                        "  ok start {} goal {} r {:.4} pred {:.5} dur {:.1}s plan {:.3}s steps {}",
                        p.start_edge,
                        p.goal_edge,
                        p.goal_radius_m,
                        p.predicted_radius_m,
                        p.duration_s,
                        t0.elapsed().as_secs_f64(),
                        p.steps.len()
                    );
                    for s in &p.steps {
                        println!("     {}", serde_json::to_string(s).unwrap());
                    }
                }
                Err(e) => println!("  ERR {e}"),
            }
        }
    }
}

#[test]
fn dbg_triangle() {
    use dexter_sim::model::feeder::planner::detail;
    use dexter_sim::model::feeder::planner::goal::sequences;
    use dexter_sim::model::feeder::planner::optimize::{solve, RadiusTable};
    let f = feeder(&[(0.0, 0.0), (0.05, 0.0), (0.015, 0.04)]);
    let arr = Pose {
        com_m: Vec2::new(0.1, 0.1),
        angle_rad: 0.3,
    };
    let (st, _, _) = detail::arrive(&f, arr, 100.0).unwrap();
    let t = RadiusTable::new(&f);
    println!("st {:?}", st);
    for e in &f.part.edges {
        println!("edge {:?} b {}", e, e.b_m());
    }
    for seq in sequences(&f.part, st.edge, 1, true, 64) {
        let sol = solve(&f, &t, &seq, st.r_m, 0.2261);
        println!("{:?} {:?}", seq, sol);
        if let Some(sol) = sol {
            let mut cur = st;
            for (k, c) in sol.turns.iter().enumerate() {
                let j = detail::jog(&f, &cur, c.r_before_m);
                println!(" jog {:?}", j.as_ref().map(|p| (p.0, p.1.clone())));
                cur = j.unwrap().0;
                let tr = detail::turn(
                    &f,
                    &cur,
                    seq.edges[k + 1],
                    seq.edges[k + 1],
                    c.theta_minus_rad,
                    false,
                );
                println!(" turn {:?}", tr.as_ref().map(|p| (p.0, p.1.clone())));
                if tr.is_err() {
                    break;
                }
                cur = tr.unwrap().0;
            }
        }
    }
}
