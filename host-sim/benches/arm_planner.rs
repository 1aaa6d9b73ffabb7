//! The arm planner's cost: B-spline knots vs solver iterations vs wall time vs the mu
//! found, for the four shipped tasks (snatch g, throw gf, the fig. 2 roll grg, rolling
//! throw grf). `-- --test` plans each configuration once and prints the table without
//! the timing runs. Before timing, each configuration
//! is planned once and its row is printed (knots, iterations, evaluations, mu, wall time),
//! so `cargo bench -p dexter-sim --bench arm_planner` prints the table as well.

use criterion::{criterion_group, criterion_main, Criterion};
use dexter_sim::model::arm::params::ArmConfig;
use dexter_sim::model::arm::planner::plan;
use dexter_sim::systems::arm::examples;
use std::hint::black_box;
use std::time::Duration;

/// The scene with `planner.knots` set (replaced, added to its `[planner]`, or a new one).
fn with_knots(text: &str, knots: usize) -> String {
    let line = format!("knots = {knots}");
    if text.contains("knots = 9") {
        text.replace("knots = 9", &line)
    } else if text.contains("[planner]\n") {
        text.replace("[planner]\n", &format!("[planner]\n{line}\n"))
    } else {
        format!("{text}\n[planner]\n{line}\n")
    }
}

fn planner(c: &mut Criterion) {
    let mut g = c.benchmark_group("arm_planner");
    g.sample_size(10);
    g.measurement_time(Duration::from_secs(20));
    g.warm_up_time(Duration::from_millis(100));
    eprintln!("task | knots | iterations | evaluations | mu | wall time (s)");
    for (task, text, knots) in [
        ("snatch", examples::SNATCH, &[7usize, 9, 12][..]),
        ("throw", examples::THROW, &[5usize, 7, 9, 12][..]),
        ("roll", examples::ROLL, &[7usize, 9, 11, 13][..]),
        (
            "rolling_throw",
            examples::ROLLING_THROW,
            &[7usize, 9, 12][..],
        ),
    ] {
        for &n in knots {
            let sys = ArmConfig::from_toml_str(&with_knots(text, n))
                .and_then(|c| c.validate())
                .expect("bench scene");
            match plan(&sys) {
                Ok(p) => eprintln!(
                    "{task} | {n} | {} | {} | {:.4} | {:.2}",
                    p.iterations, p.evaluations, p.mu, p.wall_time_s
                ),
                Err(e) => eprintln!("{task} | {n} | no plan: {e}"),
            }
            g.bench_function(format!("{task}/{n}_knots"), |b| {
                b.iter(|| plan(black_box(&sys)).map(|p| p.mu).unwrap_or(f64::NAN))
            });
        }
    }
    g.finish();
}

criterion_group!(benches, planner);
criterion_main!(benches);
