//! Hardware in the loop for the kappa-tilt table (issue 11): the real-table plant of the
//! simulator (`run_real_table`: drives with limits, a camera with noise, latency and
//! quantization) closed through the firmware in QEMU (`LockStep::<TiltController>`), checked
//! against the same run with the core linked in (SIL), command by command and impact by
//! impact.
//!
//! These tests never skip: without `qemu-system-arm` or the `thumbv7em-none-eabihf` target
//! they fail and say what to install. The firmware is built once per test binary.
//!
//! The figures of BENCHMARKS.md ("Tilt controller on the MCU": instructions per step for
//! each sine/cosine source and contact-solver iteration cap, with the accuracy each buys)
//! come from the ignored `bench_tilt_figures`, run by `scripts/hil-bench.sh`.

use dexter_core::fixed_rate::FixedRate;
use dexter_core::protocol::RunSummary;
use dexter_core::protocol::Wire;
use dexter_core::tilt_control::sincos::{BackendSinCos, SinCos};
use dexter_core::tilt_control::{TiltController, TiltControllerWith};
use dexter_sim::controller::{HilReport, Sil};
use dexter_sim::hil::{self, HilOptions, LinkKind, LockStep, StepBudget};
use dexter_sim::model::planar::real_table::{
    controller_params_for, run_real_table, RealTable, TableRunConfig,
};
use dexter_sim::model::planar::table_run::TableRun;
use dexter_sim::model::planar::PlanarParams;
use dexter_sim::model::planar::RunEnd;
use dexter_tests::{firmware, static_worst_case};
use std::path::{Path, PathBuf};
use std::time::Duration;

/// The tilt controller's own budget (600 instructions).
const TILT_BUDGET: u32 = <TiltController as FixedRate>::STEP_INSTRUCTION_BUDGET;

fn options(elf: &Path, budget: StepBudget) -> HilOptions {
    HilOptions {
        firmware_elf: elf.to_path_buf(),
        link: LinkKind::Semihosting,
        instruction_budget: budget,
        timeout: Duration::from_secs(20),
        ..HilOptions::default()
    }
}

/// The sec. 2.3 triangle: rho 9.428 cm, l = 2/3 of 20 cm, e 0.5, kappa 1.1, kappa_E 0.165,
/// 25 cm apex, dropped from 20 cm at theta 0.3; tips at atan 4.
fn triangle() -> PlanarParams {
    PlanarParams {
        kappa_e_s2pm2: 0.165,
        target_apex_m: Some(0.25),
        impacts: 300,
        tip_angle_rad: 4f64.atan(),
        ..PlanarParams::default()
    }
}

/// The triangle on `table` with the controller's law and body from the model, `iterations`
/// Newton steps per plan.
fn setup(mut table: RealTable, iterations: u8, impacts: usize) -> (TableRunConfig, RealTable) {
    let p = triangle();
    let model = p.build().unwrap();
    table.controller =
        controller_params_for(&model, &table.controller, table.camera.as_ref()).unwrap();
    table.controller.contact_iterations = iterations;
    table.validate(&model).unwrap();
    let cfg = TableRunConfig {
        model,
        start: p.start().unwrap(),
        impacts,
        record: vec![],
    };
    (cfg, table)
}

/// The run with the core linked in.
fn sil<T: SinCos>(cfg: &TableRunConfig, table: &RealTable) -> TableRun
where
    TiltControllerWith<T>: FixedRate<Params = dexter_core::tilt_control::TiltParams>,
{
    let mut sil = Sil::<TiltControllerWith<T>>::new(table.controller).unwrap();
    run_real_table(cfg, table, &mut sil).unwrap()
}

/// The same run with the firmware `elf` in the loop: the run, the HIL report and what the
/// firmware says at its end (stack high-water), and the first disagreement with the
/// shadow core, if any.
fn hil_run<T: SinCos>(
    elf: &Path,
    budget: StepBudget,
    cfg: &TableRunConfig,
    table: &RealTable,
) -> (TableRun, HilReport, RunSummary, Option<String>)
where
    TiltControllerWith<T>: Wire<Params = dexter_core::tilt_control::TiltParams>,
{
    let mut lock = LockStep::<TiltControllerWith<T>>::start(table.controller, options(elf, budget))
        .expect("QEMU starts with the tilt controller");
    let run = run_real_table(cfg, table, &mut lock).unwrap_or_else(|e| panic!("HIL run: {e}"));
    let mismatch = lock.first_mismatch().map(str::to_string);
    let (report, summary) = lock.finish_with_summary().expect("firmware ends cleanly");
    (run, report, summary, mismatch)
}

/// Everything the two runs computed, apart from the HIL figures, as text with every f64 in
/// its shortest exact form: equal text is equal bits.
fn trajectory(run: &TableRun) -> String {
    format!("{:?}\n{:?}\n{:?}", run.summary, run.impacts, run.samples)
}

/// The sec. 2.3 triangle on the realistic table and camera (500 Hz, 1 mm and 5 mrad noise,
/// 4 ms latency) with the firmware in the loop: upright for 300 impacts with the late
/// energy within 2 % of eta*, every command bit-identical to the core's (so every impact
/// of the whole trajectory equals the SIL run's, bit for bit), no link error, every step
/// within the 600-instruction budget, and the stack within three quarters of its region.
#[test]
fn realistic_triangle_in_hil_stays_upright_and_equals_sil_bit_for_bit() {
    let (mut cfg, table) = setup(RealTable::realistic(1), 2, 300);
    cfg.record = vec![(0.0, 1.0), (100.0, 101.0)];
    let sil = sil::<dexter_core::tilt_control::sincos::PolySinCos>(&cfg, &table);
    let (hil, report, summary, mismatch) = hil_run::<dexter_core::tilt_control::sincos::PolySinCos>(
        &firmware(),
        StepBudget::OfController,
        &cfg,
        &table,
    );
    eprintln!(
        "tilt HIL: {report:?}; stack {} of {} B; {:?}",
        summary.stack_used_bytes, summary.stack_size_bytes, hil.summary
    );
    assert_eq!(mismatch, None, "firmware and SIL disagree");
    assert_eq!(report.sil_mismatches, 0);
    assert_eq!(report.link_errors, 0);
    assert_eq!(report.over_budget_steps, 0);
    assert!(report.step_instructions_max <= TILT_BUDGET, "{report:?}");
    let s = &hil.summary;
    assert_eq!(s.end, RunEnd::Completed, "{s:?}");
    assert!(!s.tipped_over && s.impacts == 300);
    assert!(s.late_energy_error.abs() < 0.02, "{}", s.late_energy_error);
    assert_eq!(s.safe.safe_steps, 0);
    assert!(!hil.samples.is_empty());
    assert_eq!(
        trajectory(&hil),
        trajectory(&sil),
        "HIL and SIL trajectories differ"
    );
    assert!(
        summary.stack_used_bytes > 0
            && summary.stack_used_bytes * 4 <= summary.stack_size_bytes * 3,
        "{summary:?}"
    );
}

// ---- the static bound -------------------------------------------------------------------

/// The tilt step's instruction budget holds for every accepted configuration: the longest
/// path through `TiltControllerWith<PolySinCos>::step` as compiled into the shipped image
/// (with its callees: the estimator's periods, the sine/cosine, the axis commands) is
/// within 600 less the 3 instructions the HIL measurement window adds around the call (the
/// line juggler's convention, scripts/test.sh), and so is the safe command.
#[test]
fn the_tilt_step_is_within_its_budget_on_every_path() {
    let elf = firmware();
    let (step, cycles) = static_worst_case(
        &elf,
        "dexter_core::tilt_control::TiltControllerWith<T>::step",
    );
    let (safe, _) = static_worst_case(
        &elf,
        "dexter_core::tilt_control::TiltControllerWith<T>::safe",
    );
    eprintln!("tilt step: static worst case {step} instructions, {cycles} cycles; safe {safe}");
    assert!(
        step + 3 <= TILT_BUDGET,
        "static worst case {step} + 3 > {TILT_BUDGET}"
    );
    assert!(safe + 3 <= TILT_BUDGET);
}

// ---- benchmark figures (BENCHMARKS.md, "Tilt controller on the MCU") ---------------------

/// One row: a sine/cosine source on its firmware image and an iteration cap, over the
/// perfect table (the solver alone) and 20 camera seeds of the realistic table, all in HIL.
fn bench_row<T: SinCos>(elf: &Path, name: &str, iterations: u8)
where
    TiltControllerWith<T>: Wire<Params = dexter_core::tilt_control::TiltParams>,
{
    let mut perfect = RealTable::realistic(1);
    perfect.camera = None;
    perfect.tilt = None;
    perfect.stroke = None;
    perfect.controller.kappa_rate_s = 0.0;
    let (cfg, table) = setup(perfect, iterations, 300);
    let (run, mut worst, _, _) = hil_run::<T>(elf, StepBudget::Unchecked, &cfg, &table);
    let solver_rms = run.summary.impact_time_error_rms_s.unwrap_or(f64::NAN);
    let (mut up, mut energy, mut sq, mut count, mut mismatches) = (0, 0.0, 0.0, 0usize, 0);
    let (mut steps, mut sum, mut min) = (0u64, 0.0, u32::MAX);
    for seed in 1..=20 {
        let (cfg, table) = setup(RealTable::realistic(seed), iterations, 300);
        let (run, report, _, _) = hil_run::<T>(elf, StepBudget::Unchecked, &cfg, &table);
        let s = &run.summary;
        if s.stayed_up {
            up += 1;
            energy += s.late_energy_error.abs();
        }
        for r in &run.impacts {
            if let Some(p) = r.predicted_time_s {
                sq += (r.time_s - p).powi(2);
                count += 1;
            }
        }
        mismatches += report.sil_mismatches;
        steps += s.control_steps;
        sum += report.step_instructions_mean * s.control_steps as f64;
        min = min.min(report.step_instructions_min);
        worst.step_instructions_max = worst
            .step_instructions_max
            .max(report.step_instructions_max);
    }
    let max = worst.step_instructions_max;
    println!(
        "| {name} | {iterations} | {min} / {:.0} / {max} | {} | {:.1e} | {:.1e} | {:.2} % | {up} / 20 | {mismatches} |",
        sum / steps as f64,
        if max <= TILT_BUDGET { "yes" } else { "**no**" },
        solver_rms,
        (sq / count.max(1) as f64).sqrt(),
        100.0 * energy / f64::from(up.max(1)),
    );
}

/// The accuracy-costs-time table of issue 11, in HIL: for each sine/cosine source (the
/// polynomial on the shipped image; the math backend on the images built with
/// `tilt-backend-sincos`, libm, and with `fast-math` too, micromath) and each contact-solver
/// iteration cap, instructions per step (min / mean / max over the perfect table and 20
/// seeds), whether the max is within the 600 budget, the impact-time error of the solver
/// alone (perfect table) and on the realistic table, the late energy error and the seeds
/// upright for 300 impacts. `DEXTER_BENCH_DIR` holds the images (scripts/hil-bench.sh);
/// `DEXTER_TILT_SOURCES` picks the rows (`poly,backend`; the backend rows compare against
/// the host's backend, so run them once without and once with `--features
/// dexter-core/fast-math`, as the script does).
#[test]
#[ignore = "benchmark figures for BENCHMARKS.md: run scripts/hil-bench.sh (builds the variants)"]
fn bench_tilt_figures() {
    let dir = std::env::var_os("DEXTER_BENCH_DIR")
        .map(PathBuf::from)
        .unwrap_or_else(|| hil::workspace_root().join("target").join("hil-bench"));
    let sources = std::env::var("DEXTER_TILT_SOURCES").unwrap_or_else(|_| "poly,backend".into());
    for n in 1..=4u8 {
        for source in sources.split(',') {
            match source {
                "poly" => bench_row::<dexter_core::tilt_control::sincos::PolySinCos>(
                    &dir.join("libm.elf"),
                    "poly",
                    n,
                ),
                "backend" => {
                    let image = format!("tilt-{}.elf", BackendSinCos::NAME);
                    bench_row::<BackendSinCos>(&dir.join(image), BackendSinCos::NAME, n)
                }
                other => panic!("DEXTER_TILT_SOURCES: unknown source {other}"),
            }
        }
    }
}
