//! Host benchmarks of the core: what each accuracy knob costs in time.
//!
//! - math backend: `libm` vs `micromath` vs the core's own f32 polynomial (sin), and their
//!   worst-case error over [-pi, pi] printed once before timing;
//! - f32 vs f64: the mirror-law reference and the eq. 8 return map in each precision;
//! - the whole control step (validate, estimate, mirror law, track, limit).
//!
//! Run: `cargo bench -p dexter-core --bench core`. Instruction counts on the Cortex-M4F are
//! measured in QEMU by the firmware (see BENCHMARKS.md).

use criterion::{criterion_group, criterion_main, Criterion};
use dexter_core::control::{Controller, ControllerParams};
use dexter_core::math::{cos_poly_f32, sin_poly_f32};
use dexter_core::mirror::MirrorLaw;
use dexter_core::protocol::SensorFrame;
use dexter_core::state::BallState;
use micromath::F32Ext;
use std::hint::black_box;

const N: usize = 1024;

fn grid() -> Vec<f32> {
    (0..N)
        .map(|i| -std::f32::consts::PI + 2.0 * std::f32::consts::PI * i as f32 / (N - 1) as f32)
        .collect()
}

fn worst_error(f: impl Fn(f32) -> f32, exact: impl Fn(f64) -> f64) -> f64 {
    (0..=100_000)
        .map(|i| -std::f64::consts::PI + 2.0 * std::f64::consts::PI * i as f64 / 100_000.0)
        .map(|x| (f(x as f32) as f64 - exact(x as f32 as f64)).abs())
        .fold(0.0, f64::max)
}

fn math_backends(c: &mut Criterion) {
    println!(
        "worst |error| over [-pi, pi]: sin libm {:.1e}, micromath {:.1e}, poly {:.1e}; cos poly {:.1e}",
        worst_error(libm::sinf, f64::sin),
        worst_error(F32Ext::sin, f64::sin),
        worst_error(sin_poly_f32, f64::sin),
        worst_error(cos_poly_f32, f64::cos),
    );
    let xs = grid();
    let mut g = c.benchmark_group("sin_1024_calls");
    g.bench_function("libm_sinf", |b| {
        b.iter(|| xs.iter().map(|&x| libm::sinf(black_box(x))).sum::<f32>())
    });
    g.bench_function("micromath_sin", |b| {
        b.iter(|| xs.iter().map(|&x| F32Ext::sin(black_box(x))).sum::<f32>())
    });
    g.bench_function("poly_sin_f32", |b| {
        b.iter(|| xs.iter().map(|&x| sin_poly_f32(black_box(x))).sum::<f32>())
    });
    g.finish();
}

fn precision(c: &mut Criterion) {
    let l32 = MirrorLaw::<f32>::new(0.111, 0.02, 1.0, 9.81).unwrap();
    let l64 = MirrorLaw::<f64>::new(0.111, 0.02, 1.0, 9.81).unwrap();
    let mut g = c.benchmark_group("mirror_reference_1024_states");
    let s32: Vec<BallState<f32>> = grid().iter().map(|&x| BallState::new(x.abs(), x)).collect();
    let s64: Vec<BallState<f64>> = s32
        .iter()
        .map(|s| BallState::new(s.height_m as f64, s.velocity_mps as f64))
        .collect();
    g.bench_function("f32", |b| {
        b.iter(|| {
            s32.iter()
                .map(|s| l32.reference(black_box(s)).height_m)
                .sum::<f32>()
        })
    });
    g.bench_function("f64", |b| {
        b.iter(|| {
            s64.iter()
                .map(|s| l64.reference(black_box(s)).height_m)
                .sum::<f64>()
        })
    });
    g.finish();
    // the return map iterated: where f32's rounding shows, next to its cost
    let v0 = 3.0f64;
    let (mut v32, mut v64) = (v0 as f32, v0);
    for _ in 0..1000 {
        v32 = l32.impact_speed_map(v32, 0.8);
        v64 = l64.impact_speed_map(v64, 0.8);
    }
    println!(
        "eq. 8 iterated 1000 times from v = 3 m/s: f32 {v32:.9}, f64 {v64:.9} (fixed point {:.9})",
        l64.fixed_point_speed_mps(0.8).unwrap()
    );
    let mut g = c.benchmark_group("return_map_1000_iterations");
    g.bench_function("f32", |b| {
        b.iter(|| (0..1000).fold(black_box(3.0f32), |v, _| l32.impact_speed_map(v, 0.8)))
    });
    g.bench_function("f64", |b| {
        b.iter(|| (0..1000).fold(black_box(3.0f64), |v, _| l64.impact_speed_map(v, 0.8)))
    });
    g.finish();
}

fn control_step(c: &mut Criterion) {
    let params = ControllerParams::default();
    let mut ctl = Controller::new(params).unwrap();
    let g = 9.81f32;
    let frames: Vec<SensorFrame> = (0..2000u32)
        .map(|k| {
            let t = (k as f32 * params.dt_s) % 0.9;
            SensorFrame {
                seq: k,
                ball_height_m: 1.0 - 0.5 * g * t * t + 0.4,
                paddle_height_m: -0.01,
                paddle_velocity_mps: 0.1,
            }
        })
        .collect();
    let mut i = 0usize;
    c.bench_function("controller_step", |b| {
        b.iter(|| {
            i = (i + 1) % frames.len();
            ctl.step(black_box(&frames[i]))
        })
    });
}

criterion_group!(benches, math_backends, precision, control_step);
criterion_main!(benches);
