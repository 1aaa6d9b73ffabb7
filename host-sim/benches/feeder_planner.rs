//! The 1JOC planner's wall-clock time and the planned feed's duration for parts of
//! growing complexity (issue 16). Each part starts from the same arrival pose.
//!
//! `cargo bench -p dexter-sim --bench feeder_planner` prints, before criterion's
//! timings, one line per part with its hull size, stable edges, the plan's primitives and
//! the planned feed duration (simulated seconds, deterministic).

use criterion::{criterion_group, criterion_main, Criterion};
use dexter_sim::model::feeder::geometry::{Pose, Vec2};
use dexter_sim::model::feeder::part::Part;
use dexter_sim::model::feeder::planner::{plan, Feeder, PlanOptions};
use dexter_sim::model::feeder::primitives::Drive;
use dexter_sim::model::feeder::quasistatic::Medium;
use dexter_sim::model::feeder::sim::Setup;
use std::hint::black_box;

fn cell(v: &[(f64, f64)]) -> Feeder {
    let pts: Vec<Vec2> = v.iter().map(|&(x, y)| Vec2::new(x, y)).collect();
    Feeder {
        part: Part::new(&pts, None).expect("valid part"),
        setup: Setup {
            medium: Medium {
                belt_speed_mps: 0.05,
                fence_mu: 0.3,
            },
            fence_length_m: 0.6,
            belt_edge_m: 0.6,
        },
        drive: Drive {
            push_rate_radps: 2.0,
            max_rate_radps: 6.0,
            max_angle_rad: 80f64.to_radians(),
            jog_tilt_rad: 0.3f64.atan() + 15f64.to_radians(),
        },
    }
}

fn regular(n: usize, r: f64) -> Vec<(f64, f64)> {
    (0..n)
        .map(|i| {
            let t = std::f64::consts::TAU * i as f64 / n as f64 + 0.1;
            (r * t.cos(), r * t.sin())
        })
        .collect()
}

fn parts() -> Vec<(&'static str, Vec<(f64, f64)>)> {
    vec![
        ("triangle", vec![(0.0, 0.0), (0.05, 0.0), (0.015, 0.04)]),
        (
            "square",
            vec![(0.0, 0.0), (0.04, 0.0), (0.04, 0.04), (0.0, 0.04)],
        ),
        (
            "parallelogram",
            vec![(0.0, 0.0), (0.04, 0.0), (0.05, 0.01), (0.01, 0.01)],
        ),
        (
            "L",
            vec![
                (0.0, 0.0),
                (0.06, 0.0),
                (0.06, 0.04),
                (0.025, 0.04),
                (0.025, 0.06),
                (0.0, 0.06),
            ],
        ),
        ("hexagon", regular(6, 0.025)),
        ("octagon", regular(8, 0.025)),
    ]
}

fn bench(c: &mut Criterion) {
    let arrival = Pose {
        com_m: Vec2::new(0.2, 0.12),
        angle_rad: 2.3,
    };
    let opts = PlanOptions::default();
    let mut g = c.benchmark_group("feeder_planner");
    g.sample_size(10);
    for (name, v) in parts() {
        let f = cell(&v);
        match plan(&f, arrival, &opts) {
            Ok(p) => {
                let kinds: Vec<&str> = p.steps.iter().map(|s| s.name()).collect();
                println!(
                    "{name}: hull {} stable {} steps [{}] plan duration {:.1} s",
                    f.part.hull.len(),
                    f.part.stable_edges().len(),
                    kinds.join(", "),
                    p.duration_s
                );
            }
            Err(e) => println!("{name}: {e}"),
        }
        g.bench_function(name, |b| {
            b.iter(|| plan(black_box(&f), black_box(arrival), &opts))
        });
    }
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
