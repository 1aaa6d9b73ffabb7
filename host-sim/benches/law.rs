//! The mirror law in f32 (what the MCU runs) and f64 (the simulator's reference):
//! reference evaluations (r, r' and r'' all consumed) and closed-form return-map steps per
//! second.

use criterion::{criterion_group, criterion_main, Criterion, Throughput};
use dexter_core::mirror::MirrorLaw;
use dexter_core::state::BallState;
use std::hint::black_box;
use std::time::Duration;

const N: usize = 1024;

fn law(c: &mut Criterion) {
    let l32 = MirrorLaw::<f32>::new(1.0 / 9.0, 0.02, 1.0, 9.81).unwrap();
    let l64 = MirrorLaw::<f64>::new(1.0 / 9.0, 0.02, 1.0, 9.81).unwrap();
    let b64: Vec<BallState<f64>> = (0..N)
        .map(|i| BallState::new(0.001 * i as f64, 4.0 - 0.008 * i as f64))
        .collect();
    let b32: Vec<BallState<f32>> = b64
        .iter()
        .map(|b| BallState::new(b.height_m as f32, b.velocity_mps as f32))
        .collect();
    let mut g = c.benchmark_group("mirror_law_reference");
    g.throughput(Throughput::Elements(N as u64));
    // every evaluation's r, r' and r'' are consumed (black_box), so none is optimised away
    g.bench_function("f32", |b| {
        b.iter(|| {
            for s in black_box(&b32) {
                black_box(l32.reference(s));
            }
        })
    });
    g.bench_function("f64", |b| {
        b.iter(|| {
            for s in black_box(&b64) {
                black_box(l64.reference(s));
            }
        })
    });
    g.finish();
    let mut g = c.benchmark_group("return_map_iterations");
    g.throughput(Throughput::Elements(N as u64));
    g.bench_function("f32", |b| {
        b.iter(|| {
            let mut v = black_box(3.0f32);
            for _ in 0..N {
                v = l32.impact_speed_map(v, 0.8);
            }
            v
        })
    });
    g.bench_function("f64", |b| {
        b.iter(|| {
            let mut v = black_box(3.0f64);
            for _ in 0..N {
                v = l64.impact_speed_map(v, 0.8);
            }
            v
        })
    });
    g.finish();
}

criterion_group! {
    name = benches;
    config = Criterion::default().sample_size(20).measurement_time(Duration::from_secs(1)).warm_up_time(Duration::from_millis(300));
    targets = law
}
criterion_main!(benches);
