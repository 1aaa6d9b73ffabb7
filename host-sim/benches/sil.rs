//! Throughput of the simulator: control steps and impacts per second for the SIL line
//! juggler with effects off and on, and impacts per second of the event-driven scenes.
//! Each switchable effect is measured alone so "off costs nothing" is visible: an effect
//! that is off is a different (smaller) type, not a branch.

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion, Throughput};
use dexter_sim::scene::parse_set;
use dexter_sim::systems::line::run::{run_scene, RunOptions};
use dexter_sim::systems::line::scene::Scene;
use std::hint::black_box;
use std::path::PathBuf;
use std::time::Duration;

fn scene(name: &str, sets: &[&str]) -> Scene {
    let path = PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../scenes")
        .join(format!("{name}.toml"));
    let o: Vec<_> = sets.iter().map(|s| parse_set(s).unwrap()).collect();
    Scene::load(&path, &o).unwrap()
}

fn sil(c: &mut Criterion) {
    let steps = 5000u64; // 10 s at 500 Hz
    let dur = format!("stop.duration_s={}", steps as f64 / 500.0);
    let mut g = c.benchmark_group("sil_line_juggler_steps");
    g.throughput(Throughput::Elements(steps));
    // (name, keep the scene's [sensor] table, overrides); "off" = ideal actuator, the true
    // ball height every step, no jitter, no drag
    let variants: Vec<(&str, bool, Vec<String>)> = vec![
        ("effects_off", false, vec!["actuator.kind=ideal".into()]),
        ("actuator_second_order", false, vec![]),
        (
            "sensor_noise_latency",
            true,
            vec!["actuator.kind=ideal".into()],
        ),
        (
            "sensor_on_zero_noise_latency",
            true,
            vec![
                "actuator.kind=ideal".into(),
                "sensor.noise_sigma_m=0".into(),
                "sensor.latency_s=0".into(),
                "sensor.quantization_m=0".into(),
                "control.estimator.latency_s=0".into(),
            ],
        ),
        (
            "jitter_10ms",
            false,
            vec!["actuator.kind=ideal".into(), "jitter.sigma_s=0.01".into()],
        ),
        (
            "drag_rk4_1ms",
            false,
            vec![
                "actuator.kind=ideal".into(),
                "drag.coefficient_per_m=0.01".into(),
            ],
        ),
        (
            "all_on",
            true,
            vec![
                "jitter.sigma_s=0.01".into(),
                "drag.coefficient_per_m=0.01".into(),
            ],
        ),
    ];
    for (name, keep_sensor, sets) in &variants {
        let mut all: Vec<&str> = vec![dur.as_str(), "stop.impacts=1000000"];
        // the sensor table is in the file: "off" variants remove it below
        all.extend(sets.iter().map(String::as_str));
        let mut s = scene("line-juggler", &all);
        if !keep_sensor {
            s.sensor = None;
            s.control.estimator.latency_s = Some(0.0);
        }
        let out = run_scene(&s, &RunOptions::default(), None).unwrap();
        eprintln!(
            "{name}: {} control steps, {} impacts per run",
            out.control_steps, out.impacts
        );
        g.bench_function(BenchmarkId::from_parameter(name), |b| {
            b.iter(|| {
                black_box(
                    run_scene(black_box(&s), &RunOptions::default(), None)
                        .unwrap()
                        .control_steps,
                )
            })
        });
    }
    g.finish();
}

fn event_driven(c: &mut Criterion) {
    let mut g = c.benchmark_group("event_driven_impacts");
    let n = 100_000u64;
    g.throughput(Throughput::Elements(n));
    let imp = format!("stop.impacts={n}");
    for (name, s) in [
        (
            "passive_e1",
            scene(
                "passive-bounce",
                &["physics.restitution=1", &imp, "stop.duration_s=1e9"],
            ),
        ),
        (
            "passive_e1_jitter_sigma0",
            scene(
                "passive-bounce",
                &[
                    "physics.restitution=1",
                    &imp,
                    "stop.duration_s=1e9",
                    "jitter.sigma_s=0",
                ],
            ),
        ),
        (
            "ideal_mirror",
            scene("line-juggler-ideal", &[&imp, "stop.duration_s=1e9"]),
        ),
        (
            "ideal_mirror_jitter_sigma0",
            scene(
                "line-juggler-ideal",
                &[&imp, "stop.duration_s=1e9", "jitter.sigma_s=0"],
            ),
        ),
        (
            "ideal_mirror_jitter_10ms",
            scene(
                "line-juggler-ideal",
                &[&imp, "stop.duration_s=1e9", "jitter.sigma_s=0.01"],
            ),
        ),
        (
            "ideal_mirror_drag0_rk45",
            scene(
                "line-juggler-ideal",
                &[
                    &imp,
                    "stop.duration_s=1e9",
                    "drag.coefficient_per_m=0",
                    "drag.integrator=rk45",
                ],
            ),
        ),
    ] {
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
    targets = sil, event_driven
}
criterion_main!(benches);
