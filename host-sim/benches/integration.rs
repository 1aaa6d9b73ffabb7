//! What accuracy costs in time: exact event location (closed-form flight, quadratic roots)
//! against numerical integration with event location (RK4 at several steps, adaptive
//! RK45 at several tolerances), on the ideal line juggler.
//!
//! - drag 0: the same physics as the exact run (RK4 is exact on a quadratic, so this is the
//!   pure cost of integrating and locating events numerically);
//! - drag 0.1 1/m (a table-tennis ball): the error is measured against the closed form of a
//!   flight with quadratic drag from the impact plane back to it, v_in^2 = v_out^2 / (1 + c
//!   v_out^2 / g) (rise: apex ln(1 + c v^2/g)/(2c); fall from it: v^2 = (g/c)(1 - e^(-2 c H))).
//!
//! The error of each method is printed (ACCURACY lines) before it is timed.

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion, Throughput};
use dexter_sim::scene::parse_set;
use dexter_sim::systems::line::run::{run_scene, RunOptions};
use dexter_sim::systems::line::scene::Scene;
use std::hint::black_box;
use std::path::PathBuf;
use std::time::Duration;

const IMPACTS: u64 = 200;

fn scene(sets: &[String]) -> Scene {
    let path = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../scenes/line-juggler-ideal.toml");
    let mut all = vec![format!("stop.impacts={IMPACTS}")];
    all.extend(sets.iter().cloned());
    let o: Vec<_> = all.iter().map(|s| parse_set(s).unwrap()).collect();
    Scene::load(&path, &o).unwrap()
}

/// Worst relative error of each flight's landing speed against the closed form for its
/// take-off speed (drag coefficient c, 0 = ballistic).
fn flight_error(s: &Scene) -> f64 {
    let out = run_scene(
        s,
        &RunOptions {
            record_rows: true,
            ..RunOptions::default()
        },
        None,
    )
    .unwrap();
    let g = s.physics.gravity_mps2;
    let c = s.drag.as_ref().map_or(0.0, |d| d.coefficient_per_m);
    out.rows
        .windows(2)
        .map(|w| {
            let up = w[0].ball_velocity_after_mps;
            let exact = (up * up / (1.0 + c * up * up / g)).sqrt();
            ((-w[1].ball_velocity_before_mps - exact) / exact).abs()
        })
        .fold(0.0, f64::max)
}

fn exact_vs_integration(c: &mut Criterion) {
    let mut g = c.benchmark_group("exact_vs_integration_impacts");
    g.throughput(Throughput::Elements(IMPACTS));
    let mut cases: Vec<(String, Vec<String>)> = vec![("exact".into(), vec![])];
    for c in ["0", "0.1"] {
        let d = format!("drag.coefficient_per_m={c}");
        for step in ["1e-2", "1e-3", "1e-4"] {
            cases.push((
                format!("drag{c}_rk4_{step}"),
                vec![d.clone(), format!("drag.step_s={step}")],
            ));
        }
        for tol in ["1e-6", "1e-9", "1e-12"] {
            cases.push((
                format!("drag{c}_rk45_{tol}"),
                vec![
                    d.clone(),
                    "drag.integrator=rk45".into(),
                    format!("drag.tolerance={tol}"),
                ],
            ));
        }
    }
    for (name, sets) in &cases {
        let s = scene(sets);
        eprintln!(
            "ACCURACY {name}: worst landing-speed relative error over {IMPACTS} impacts = {:.2e}",
            flight_error(&s)
        );
        g.bench_function(BenchmarkId::from_parameter(name), |b| {
            b.iter(|| {
                black_box(
                    run_scene(black_box(&s), &RunOptions::default(), None)
                        .unwrap()
                        .impacts,
                )
            })
        });
    }
    g.finish();
}

criterion_group! {
    name = benches;
    config = Criterion::default().sample_size(10).measurement_time(Duration::from_secs(2)).warm_up_time(Duration::from_millis(300));
    targets = exact_vs_integration
}
criterion_main!(benches);
