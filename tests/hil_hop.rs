//! Hardware in the loop for the hopper's thrust controller (issue 12): the sampled hopper of
//! the simulator (`run_sampled`: the valve-driven plant, exact between control steps)
//! closed through the firmware in QEMU (`LockStep::<HopController>`), checked against the
//! same run with the core linked in (SIL), command by command and cycle by cycle.
//!
//! These tests never skip: without `qemu-system-arm` or the `thumbv7em-none-eabihf` target
//! they fail and say what to install. The firmware is built once per test binary.
//!
//! The rate table of BENCHMARKS.md ("Hopper controller on the MCU": control rate vs
//! fixed-point error vs instructions per second of hopping) comes from the ignored
//! `bench_hop_rate_table`, run by `scripts/hil-bench.sh`.

use dexter_core::fixed_rate::FixedRate;
use dexter_core::hop::{EnergyServoThrust, RaibertThrust};
use dexter_core::hop_control::HopController;
use dexter_core::protocol::RunSummary;
use dexter_sim::controller::HilReport;
use dexter_sim::hil::{HilOptions, LinkKind, LockStep, StepBudget};
use dexter_sim::model::hopper::sampled::{
    run_sampled, run_sil, DetectorOptions, SampledConfig, SampledEnd, SampledRun, SensorConfig,
    TimelineWindow,
};
use dexter_sim::model::hopper::valve::ValveModel;
use dexter_sim::model::hopper::{LinearSpring, ThrustLaw};
use dexter_tests::{firmware, static_worst_case};
use std::path::{Path, PathBuf};
use std::time::Duration;

const G: f64 = 9.81;
/// The hopper controller's own budget (300 instructions).
const HOP_BUDGET: u32 = <HopController as FixedRate>::STEP_INSTRUCTION_BUDGET;

/// Tuned linear model (eq. 16 in eq. 10's coordinates): Table 1's eta1 and gamma (figs.
/// 8, 10), touchdown at 0.5 m.
fn linear() -> ValveModel {
    ValveModel::Linear(LinearSpring::new(0.5, 46.5, 2.33, 0.5 + G / 46.5, 0.0, G).unwrap())
}

fn raibert(tau: f64, delta: f64) -> ThrustLaw {
    ThrustLaw::Raibert(RaibertThrust::new(tau, delta).unwrap())
}

fn config(law: &ThrustLaw, rate_hz: f64, sensor: SensorConfig, cycles: usize) -> SampledConfig {
    let det = DetectorOptions::default();
    SampledConfig::new(linear(), law, rate_hz, &det, sensor, 1.0, cycles).unwrap()
}

/// `cfg` with the firmware `elf` in the loop: the run, the HIL report, what the firmware
/// says at its end, and the first disagreement with the shadow core, if any.
fn hil_run(
    elf: &Path,
    budget: StepBudget,
    cfg: &SampledConfig,
) -> (SampledRun, HilReport, RunSummary, Option<String>) {
    let opts = HilOptions {
        firmware_elf: elf.to_path_buf(),
        link: LinkKind::Semihosting,
        instruction_budget: budget,
        timeout: Duration::from_secs(20),
        ..HilOptions::default()
    };
    let mut lock = LockStep::<HopController>::start(cfg.control, opts)
        .expect("QEMU starts with the hopper controller");
    let run = run_sampled(cfg, &mut lock).unwrap_or_else(|e| panic!("HIL run: {e}"));
    let mismatch = lock.first_mismatch().map(str::to_string);
    let (report, summary) = lock.finish_with_summary().expect("firmware ends cleanly");
    (run, report, summary, mismatch)
}

/// Everything a run computed apart from its HIL figures (every cycle's exact event times
/// and apexes, the timeline of control steps, the statistics), as text with every f64 in
/// its shortest exact form: equal text is equal bits.
fn trajectory(run: &SampledRun) -> String {
    format!("{run:?}")
}

/// Raibert's fixed thrust (Table 1: tau 41.86 m/s^2 for 50 ms) on the tuned linear model at
/// 1 kHz with the firmware in the loop: settles to period 1 within 1 % of eq. 17's fixed
/// point, every command bit-identical to the core's (so every cycle of the whole run and
/// the timeline of its first hops equal the SIL run's, bit for bit), no link error, every
/// step within the 300-instruction budget, the stack within three quarters of its region.
#[test]
fn raibert_hopper_in_hil_settles_to_period_1_and_equals_sil_bit_for_bit() {
    let mut cfg = config(&raibert(41.86, 0.05), 1000.0, SensorConfig::default(), 300);
    cfg.record_cycles = true;
    cfg.timeline = Some(TimelineWindow {
        first_cycle: 0,
        cycles: 3,
    });
    let sil = run_sil(&cfg).unwrap();
    let (hil, report, summary, mismatch) = hil_run(&firmware(), StepBudget::OfController, &cfg);
    eprintln!(
        "hop HIL: {report:?}; stack {} of {} B; fixed-point error {:?}",
        summary.stack_used_bytes, summary.stack_size_bytes, hil.fixed_point_error
    );
    assert_eq!(mismatch, None, "firmware and SIL disagree");
    assert_eq!(report.sil_mismatches, 0);
    assert_eq!(report.link_errors, 0);
    assert_eq!(report.over_budget_steps, 0);
    assert!(report.step_instructions_max <= HOP_BUDGET, "{report:?}");
    assert_eq!(hil.end, SampledEnd::Completed);
    assert_eq!(hil.cycles, 300);
    assert_eq!(hil.period(), Some(1), "{:?}", hil.settle);
    let fpe = hil.fixed_point_error.unwrap();
    assert!(fpe < 0.01, "fixed-point error {fpe}");
    assert_eq!((hil.safe.safe_steps, hil.invalid_commands), (0, 0));
    assert_eq!(hil.records.len(), 300);
    assert!(!hil.timeline.is_empty());
    assert_eq!(
        trajectory(&hil),
        trajectory(&sil),
        "HIL and SIL runs differ"
    );
    assert!(
        summary.stack_used_bytes > 0
            && summary.stack_used_bytes * 4 <= summary.stack_size_bytes * 3,
        "{summary:?}"
    );
}

/// The energy servo with a noisy, quantized, delayed sensor that also reports the body
/// height (the other branches of the step: hysteresis, debounce, the flight-time energy),
/// in HIL: bit-identical to SIL and within the budget.
#[test]
fn energy_servo_with_a_noisy_sensor_in_hil_equals_sil_bit_for_bit() {
    let law =
        ThrustLaw::EnergyServo(EnergyServoThrust::new(40.0, 5.0, G * 0.13, 80.0, 0.05).unwrap());
    let sensor = SensorConfig {
        compression_noise_m: 1e-4,
        height_noise_m: 1e-3,
        quantization_m: 1e-5,
        latency_s: 2e-3,
        body_height: true,
        seed: 5,
        ..SensorConfig::default()
    };
    let det = DetectorOptions {
        touchdown_compression_m: 1e-3,
        liftoff_compression_m: Some(5e-4),
        bottom_hysteresis_m: 5e-4,
        debounce_samples: 2,
        predict_bottom: false,
        end_thrust_at_estimate: false,
        ..DetectorOptions::default()
    };
    let mut cfg = SampledConfig::new(linear(), &law, 1000.0, &det, sensor, 1.0, 60).unwrap();
    cfg.record_cycles = true;
    let sil = run_sil(&cfg).unwrap();
    let (hil, report, _, mismatch) = hil_run(&firmware(), StepBudget::OfController, &cfg);
    eprintln!("hop servo HIL: {report:?}");
    assert_eq!(mismatch, None, "firmware and SIL disagree");
    assert_eq!((report.sil_mismatches, report.link_errors), (0, 0));
    assert!(report.step_instructions_max <= HOP_BUDGET, "{report:?}");
    assert_eq!(hil.cycles, 60);
    assert_eq!(
        trajectory(&hil),
        trajectory(&sil),
        "HIL and SIL runs differ"
    );
}

// ---- the static bound -------------------------------------------------------------------

/// The hopper step's budget holds for every accepted configuration: its compiled code has
/// no loop and no call, so its longest path (scripts/wcet.py) bounds every step; within
/// 300 less the 3 instructions of the HIL measurement window (scripts/test.sh's
/// convention), and so is the safe command.
#[test]
fn the_hopper_step_is_within_its_budget_on_every_path() {
    let elf = firmware();
    let (step, cycles) = static_worst_case(
        &elf,
        "<dexter_core::hop_control::HopController as dexter_core::fixed_rate::FixedRate>::step",
    );
    let (safe, _) = static_worst_case(
        &elf,
        "<dexter_core::hop_control::HopController as dexter_core::fixed_rate::FixedRate>::safe",
    );
    eprintln!("hopper step: static worst case {step} instructions, {cycles} cycles; safe {safe}");
    assert!(
        step + 3 <= HOP_BUDGET,
        "static worst case {step} + 3 > {HOP_BUDGET}"
    );
    assert!(safe + 3 <= HOP_BUDGET);
}

// ---- benchmark figures (BENCHMARKS.md, "Hopper controller on the MCU") -------------------

/// Issue 12's accuracy-costs-time table, in HIL: for each control rate, Raibert's thrust on
/// the tuned linear model (300 hops from five start heights), the largest and mean
/// fixed-point error against eq. 17, and the instructions per step (min / mean / max) and
/// per second of hopping (mean per step x rate) on the target. `DEXTER_BENCH_DIR/libm.elf`
/// (scripts/hil-bench.sh), or the default firmware.
#[test]
#[ignore = "benchmark figures for BENCHMARKS.md: run scripts/hil-bench.sh"]
fn bench_hop_rate_table() {
    let elf = std::env::var_os("DEXTER_BENCH_DIR")
        .map(|d| PathBuf::from(d).join("libm.elf"))
        .unwrap_or_else(firmware);
    let law = raibert(41.86, 0.05);
    println!(
        "| rate, Hz | fixed-point error, max / mean of 5 starts | instructions per step, min / mean / max | instructions per second of hopping | SIL mismatches |"
    );
    println!("| --- | --- | --- | --- | --- |");
    for rate in [250.0, 500.0, 1000.0, 2000.0, 5000.0] {
        let (mut errs, mut steps, mut sum, mut min, mut max, mut mism) =
            (Vec::new(), 0u64, 0.0, u32::MAX, 0, 0);
        for start in [0.8, 0.9, 1.0, 1.1, 1.2] {
            let mut cfg = config(&law, rate, SensorConfig::default(), 300);
            cfg.start_height_m = start;
            let (run, report, _, _) = hil_run(&elf, StepBudget::Unchecked, &cfg);
            errs.push(run.fixed_point_error.unwrap_or(f64::NAN));
            steps += run.control_steps;
            sum += report.step_instructions_mean * run.control_steps as f64;
            min = min.min(report.step_instructions_min);
            max = max.max(report.step_instructions_max);
            mism += report.sil_mismatches;
        }
        let worst = errs.iter().copied().fold(0.0, f64::max);
        let mean_err = errs.iter().sum::<f64>() / errs.len() as f64;
        let mean = sum / steps as f64;
        println!(
            "| {rate:.0} | {:.3} % / {:.3} % | {min} / {mean:.1} / {max} | {:.0} | {mism} |",
            100.0 * worst,
            100.0 * mean_err,
            mean * rate,
        );
    }
}
