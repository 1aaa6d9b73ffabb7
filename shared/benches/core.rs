//! Host benchmarks of the core: what each accuracy knob costs in time.
//!
//! - math backend: `libm` vs `micromath` vs the core's own f32 polynomial (sin), and their
//!   worst-case error over [-pi, pi] printed once before timing;
//! - f32 vs f64: the mirror-law reference and the eq. 8 return map in each precision;
//! - the whole control step (validate, estimate, mirror law, track, limit), its Track path
//!   (a recorded closed-loop juggle) and its safe state timed separately.
//!
//! Run: `cargo bench -p dexter-core --bench core`. Instruction counts on the Cortex-M4F are
//! measured in QEMU by the firmware (see BENCHMARKS.md).

use criterion::{criterion_group, criterion_main, BatchSize, Criterion, Throughput};
use dexter_core::control::{Controller, ControllerParams};
use dexter_core::fixed_rate::FixedRate;
use dexter_core::fixed_rate::Mode;
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
    // every evaluation's r, r' and r'' are consumed (black_box), so none is optimised away
    g.bench_function("f32", |b| {
        b.iter(|| {
            for s in &s32 {
                black_box(l32.reference(black_box(s)));
            }
        })
    });
    g.bench_function("f64", |b| {
        b.iter(|| {
            for s in &s64 {
                black_box(l64.reference(black_box(s)));
            }
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

/// Frames of a real closed-loop juggle: the default controller drives a paddle (commanded
/// acceleration held over each period, as the firmware's HIL plant) under a ball with
/// restitution 0.8. Returns the controller as it was before the first recorded frame, and
/// the frames; replaying them from that state reproduces the same (Track-mode) steps.
fn juggle_frames(params: ControllerParams, warm_up: u32, n: u32) -> (Controller, Vec<SensorFrame>) {
    let mut ctl = Controller::new(params).unwrap();
    let (dt, g) = (params.dt_s, params.gravity_mps2);
    let e = params.estimator.restitution;
    let (mut b, mut vb, mut p, mut vp) = (1.2f32, 0.0f32, params.home_height_m, 0.0f32);
    let mut start = ctl.clone();
    let mut frames = Vec::with_capacity(n as usize);
    for seq in 0..warm_up + n {
        if seq == warm_up {
            start = ctl.clone();
        }
        let frame = SensorFrame {
            seq,
            ball_height_m: b,
            paddle_height_m: p,
            paddle_velocity_mps: vp,
        };
        let cmd = ctl.step(&frame);
        if seq >= warm_up {
            assert_eq!(
                cmd.mode,
                Mode::Track,
                "frame {seq} is not a Track step: {cmd:?}"
            );
            frames.push(frame);
        }
        let u = cmd.paddle_accel_mps2;
        b += vb * dt - 0.5 * g * dt * dt;
        vb -= g * dt;
        p += vp * dt + 0.5 * u * dt * dt;
        vp += u * dt;
        if b <= p && vb < vp {
            vb = vp + e * (vp - vb);
            b = p;
        }
    }
    (start, frames)
}

/// The control step, each path timed on its own: Track (a closed-loop juggle replayed from
/// the controller state it was recorded with: every step estimates, runs the mirror law and
/// tracks, impacts included), and the safe state for a non-finite and for an out-of-range
/// measurement.
fn control_step(c: &mut Criterion) {
    let params = ControllerParams::default();
    let (start, frames) = juggle_frames(params, 1000, 2000);
    let mut g = c.benchmark_group("controller_step");
    g.throughput(Throughput::Elements(frames.len() as u64));
    g.bench_function("track_2000_steps", |b| {
        b.iter_batched_ref(
            || start.clone(),
            |ctl| {
                for f in &frames {
                    black_box(ctl.step(black_box(f)));
                }
            },
            BatchSize::SmallInput,
        )
    });
    let mut ctl = start.clone();
    let mut seq = frames.len() as u32;
    for (name, ball_m) in [("safe_non_finite", f32::NAN), ("safe_out_of_range", 1e6)] {
        let frame = SensorFrame {
            ball_height_m: ball_m,
            ..frames[0]
        };
        assert_eq!(ctl.step(&frame).mode, Mode::Safe);
        g.throughput(Throughput::Elements(1));
        g.bench_function(name, |b| {
            b.iter(|| {
                seq = seq.wrapping_add(1);
                ctl.step(black_box(&SensorFrame { seq, ..frame }))
            })
        });
    }
    g.finish();
}

criterion_group!(benches, math_backends, precision, control_step);
criterion_main!(benches);
