//! What accuracy costs in time: exact event location (closed-form flight, quadratic roots)
//! against numerical integration with event location (RK4 at several steps, adaptive
//! RK45 at several tolerances), on the ideal line juggler: the cases and their error measure
//! are in `common/integration_cases.rs`, shared with `examples/accuracy_probe.rs`.
//!
//! The error of each method is printed (ACCURACY lines) before it is timed.

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion, Throughput};
use std::hint::black_box;
use std::time::Duration;

#[path = "common/integration_cases.rs"]
mod integration_cases;
use integration_cases::{cases, flight_error, run_impacts, scene, IMPACTS};

fn exact_vs_integration(c: &mut Criterion) {
    let mut g = c.benchmark_group("exact_vs_integration_impacts");
    g.throughput(Throughput::Elements(IMPACTS));
    for case in cases() {
        let s = scene(&case.sets);
        eprintln!(
            "ACCURACY {}: worst landing-speed relative error over {IMPACTS} impacts = {:.2e}",
            case.name,
            flight_error(&s)
        );
        g.bench_function(BenchmarkId::from_parameter(&case.name), |b| {
            b.iter(|| black_box(run_impacts(black_box(&s))))
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
