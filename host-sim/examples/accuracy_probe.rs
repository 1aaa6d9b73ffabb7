//! The measurements behind `docs/figures/` (BENCHMARKS.md, "What accuracy costs, at a
//! glance"): each probe does one knob's work and prints what it measured as one line of
//! `key=value` fields, which `scripts/accuracy_figures.py` reads (and fails on if a field is
//! missing).
//!
//! ```text
//! accuracy_probe sin BACKEND CALLS        # BACKEND: libm, micromath, poly, none
//! accuracy_probe return-map PREC ITERS    # PREC: f32, f64, none
//! accuracy_probe mirror PREC EVALS        # PREC: f32, f64, none
//! accuracy_probe integrator MIN_SECONDS
//! accuracy_probe tilt CAP SEEDS
//! accuracy_probe defmt ELF LOG            # the firmware's defmt log, decoded
//! ```
//!
//! `sin`, `return-map` and `mirror` print their error and then do the work CALLS (ITERS,
//! EVALS) times: the script runs each under callgrind at two counts, so the difference is
//! the marginal instructions per call, and subtracts the same loop around nothing (`none`).
//! `integrator` prints, for each case of `benches/common/integration_cases.rs`, its error
//! and the median wall time of one 200-impact run (repeated for at least MIN_SECONDS, at
//! least 3 runs). `tilt` prints the controller's planning periods for the Newton cap and the
//! impact-time prediction errors of `tests/support/tilt_accuracy.rs`. `defmt` decodes the log
//! a firmware image wrote over semihosting (the bench image's per-call costs of the math
//! kernels on the Cortex-M4F in QEMU) with that image's defmt table.

use std::hint::black_box;
use std::process::ExitCode;
use std::time::Instant;

use dexter_core::math::sin_poly_f32;
use dexter_core::mirror::MirrorLaw;
use dexter_core::state::BallState;
use dexter_core::tilt_control::sincos::PolySinCos;
use dexter_sim::model::planar::real_table::RealTable;
use micromath::F32Ext;

#[path = "../benches/common/integration_cases.rs"]
mod integration_cases;
#[path = "../tests/support/tilt_accuracy.rs"]
mod tilt_accuracy;

/// Points of the argument grid the work loops over.
const GRID: usize = 1024;
/// Restitution of the return map (BENCHMARKS.md's f32 vs f64 row).
const ALPHA: f64 = 0.8;
/// Iterations of the return map before its error is read.
const MAP_ITERATIONS: usize = 1000;

fn main() -> ExitCode {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let args: Vec<&str> = args.iter().map(String::as_str).collect();
    match probe(&args) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("accuracy_probe: {e}");
            ExitCode::from(2)
        }
    }
}

fn probe(args: &[&str]) -> Result<(), String> {
    match args {
        ["sin", backend, n] => sin(backend, count(n)?),
        ["return-map", precision, n] => return_map(precision, count(n)?),
        ["mirror", precision, n] => mirror(precision, count(n)?),
        ["integrator", seconds] => {
            integrator(
                seconds
                    .parse()
                    .map_err(|_| format!("bad seconds {seconds:?}"))?,
            );
            Ok(())
        }
        ["defmt", elf, log] => {
            let bytes = std::fs::read(log).map_err(|e| format!("{log}: {e}"))?;
            let text = dexter_sim::hil::decode_defmt_log(elf.as_ref(), &bytes)
                .map_err(|e| format!("{log}: {e}"))?;
            print!("{text}");
            Ok(())
        }
        ["tilt", cap, seeds] => {
            let cap: u8 = cap.parse().map_err(|_| format!("bad cap {cap:?}"))?;
            tilt(cap, count(seeds)? as u64);
            Ok(())
        }
        _ => Err(format!(
            "unknown arguments {args:?} (see the example's docs)"
        )),
    }
}

fn count(text: &str) -> Result<usize, String> {
    text.parse().map_err(|_| format!("bad count {text:?}"))
}

/// The arguments in [-pi, pi] the work loops over.
fn grid() -> Vec<f32> {
    let pi = std::f32::consts::PI;
    (0..GRID)
        .map(|i| -pi + 2.0 * pi * i as f32 / (GRID - 1) as f32)
        .collect()
}

// ---- math backend ----------------------------------------------------------------------------

fn sin(backend: &str, calls: usize) -> Result<(), String> {
    match backend {
        "libm" => sin_with(backend, libm::sinf, calls),
        "micromath" => sin_with(backend, F32Ext::sin, calls),
        "poly" => sin_with(backend, sin_poly_f32, calls),
        "none" => sin_with(backend, |x| x, calls),
        _ => return Err(format!("unknown sin backend {backend:?}")),
    }
    Ok(())
}

/// Prints `f`'s worst absolute error on [-pi, pi] (100 001 points, against f64's sin of the
/// same f32 argument; 0 for `none`), then calls it `calls` times over the grid.
fn sin_with(name: &str, f: impl Fn(f32) -> f32, calls: usize) {
    let error = if name == "none" {
        0.0
    } else {
        (0..=100_000)
            .map(|i| -std::f64::consts::PI + 2.0 * std::f64::consts::PI * i as f64 / 100_000.0)
            .map(|x| (f64::from(f(x as f32)) - (x as f32 as f64).sin()).abs())
            .fold(0.0, f64::max)
    };
    println!("sin backend={name} worst_abs_error={error:e} calls={calls}");
    let xs = grid();
    let mut sum = 0.0f32;
    for i in 0..calls {
        sum += f(black_box(xs[i % GRID]));
    }
    black_box(sum);
}

// ---- precision -------------------------------------------------------------------------------

fn laws() -> (MirrorLaw<f32>, MirrorLaw<f64>) {
    (
        MirrorLaw::<f32>::new(0.111, 0.02, 1.0, 9.81).unwrap(),
        MirrorLaw::<f64>::new(0.111, 0.02, 1.0, 9.81).unwrap(),
    )
}

/// Prints the relative error of the eq. 8 return map's value after [`MAP_ITERATIONS`]
/// iterations from 3 m/s against its closed-form fixed point (f64), then iterates it `n`
/// times as a dependent chain.
fn return_map(precision: &str, n: usize) -> Result<(), String> {
    let (l32, l64) = laws();
    let exact = l64.fixed_point_speed_mps(ALPHA).unwrap();
    let rel = |v: f64| ((v - exact) / exact).abs();
    let error = match precision {
        "f32" => rel(f64::from(
            (0..MAP_ITERATIONS).fold(3.0f32, |v, _| l32.impact_speed_map(v, ALPHA as f32)),
        )),
        "f64" => rel((0..MAP_ITERATIONS).fold(3.0, |v, _| l64.impact_speed_map(v, ALPHA))),
        "none" => 0.0,
        _ => return Err(format!("unknown precision {precision:?}")),
    };
    println!("return-map precision={precision} relative_error={error:e} iterations={n}");
    match precision {
        "f32" => {
            black_box((0..n).fold(3.0f32, |v, _| {
                l32.impact_speed_map(black_box(v), ALPHA as f32)
            }));
        }
        "f64" => {
            black_box((0..n).fold(3.0f64, |v, _| l64.impact_speed_map(black_box(v), ALPHA)));
        }
        _ => {
            black_box((0..n).fold(3.0f64, |v, _| black_box(v)));
        }
    }
    Ok(())
}

/// Ball states over the grid (height |x|, velocity x), as the core's bench.
fn states() -> Vec<BallState<f64>> {
    grid()
        .iter()
        .map(|&x| BallState::new(f64::from(x.abs()), f64::from(x)))
        .collect()
}

/// Prints the worst error of the f32 mirror-law reference (r, r', r'') over the grid
/// against f64's, each component relative to its largest magnitude (f64: 0, the
/// reference), then evaluates it `n` times over the grid.
fn mirror(precision: &str, n: usize) -> Result<(), String> {
    let (l32, l64) = laws();
    let s64 = states();
    let s32: Vec<BallState<f32>> = s64
        .iter()
        .map(|s| BallState::new(s.height_m as f32, s.velocity_mps as f32))
        .collect();
    let error = match precision {
        "f32" => mirror_error(&l32, &l64, &s32, &s64),
        "f64" | "none" => 0.0,
        _ => return Err(format!("unknown precision {precision:?}")),
    };
    println!("mirror precision={precision} relative_error={error:e} evaluations={n}");
    for i in 0..n {
        match precision {
            "f32" => {
                black_box(l32.reference(black_box(&s32[i % GRID])));
            }
            "f64" => {
                black_box(l64.reference(black_box(&s64[i % GRID])));
            }
            _ => {
                black_box(black_box(&s64[i % GRID]));
            }
        }
    }
    Ok(())
}

fn mirror_error(
    l32: &MirrorLaw<f32>,
    l64: &MirrorLaw<f64>,
    s32: &[BallState<f32>],
    s64: &[BallState<f64>],
) -> f64 {
    let r64: Vec<[f64; 3]> = s64
        .iter()
        .map(|s| {
            let r = l64.reference(s);
            [r.height_m, r.velocity_mps, r.accel_mps2]
        })
        .collect();
    let mut worst = 0.0f64;
    for k in 0..3 {
        let scale = r64.iter().map(|r| r[k].abs()).fold(0.0, f64::max);
        for (s, exact) in s32.iter().zip(&r64) {
            let r = l32.reference(s);
            let v = [r.height_m, r.velocity_mps, r.accel_mps2][k];
            worst = worst.max((f64::from(v) - exact[k]).abs() / scale);
        }
    }
    worst
}

// ---- integrator ------------------------------------------------------------------------------

fn integrator(min_seconds: f64) {
    use integration_cases::{cases, flight_error, run_impacts, scene, IMPACTS};
    for case in cases() {
        let s = scene(&case.sets);
        let error = flight_error(&s);
        black_box(run_impacts(&s)); // warm-up
        let mut times = Vec::new();
        let start = Instant::now();
        while times.len() < 3 || start.elapsed().as_secs_f64() < min_seconds {
            let t = Instant::now();
            black_box(run_impacts(black_box(&s)));
            times.push(t.elapsed().as_secs_f64());
        }
        times.sort_by(f64::total_cmp);
        let median = times[times.len() / 2];
        println!(
            "integrator case={} worst_landing_speed_error={error:e} us_per_run={:e} impacts={IMPACTS} runs={}",
            case.name,
            median * 1e6,
            times.len()
        );
    }
}

// ---- tilt Newton cap -------------------------------------------------------------------------

/// Prints, for the shipped sine/cosine and Newton cap `cap`: the control periods from one
/// plan to the next ([`dexter_core::tilt_control::TiltParams::cycle_periods`] of the
/// realistic table's controller: a cap of n makes a plan n + 7 periods old) and what
/// [`tilt_accuracy::accuracy`] measures.
fn tilt(cap: u8, seeds: u64) {
    let mut params = RealTable::realistic(1).controller;
    params.contact_iterations = cap;
    let a = tilt_accuracy::accuracy::<PolySinCos>(cap, seeds);
    println!(
        "tilt cap={cap} cycle_periods={} solver_rms_s={:e} realistic_rms_s={:e} realistic_worst_s={:e} \
         mean_late_energy_error={:e} upright={} seeds={seeds}",
        params.cycle_periods(),
        a.solver_rms_s,
        a.realistic_rms_s,
        a.realistic_worst_s,
        a.mean_late_energy_error,
        a.upright
    );
}
