//! The spatial juggler in the loop: `SpatialController` in its own firmware image (QEMU
//! `mps2-an386`, `--no-default-features --features spatial`) juggles the simulated ball of
//! `scenes/spatial-juggler-sil.toml` in lock-step.
//!
//! Every command equals the core's bit for bit (the driver's shadow), every bat (ball,
//! joints, apex) equals the same loop closed in SIL bit for bit, and every step is within
//! `SpatialController`'s instruction budget. A corrupted link puts the controller in its
//! safe state, answered identically by the firmware and the shadow.
//!
//! These tests never skip: without `qemu-system-arm` or the `thumbv7em-none-eabihf` target
//! they fail saying what to install. Run with `--nocapture` to see the figures.

use dexter_core::fixed_rate::FixedRate;
use dexter_core::spatial_control::SpatialController;
use dexter_sim::hil::{HilOptions, LinkKind, LockStep};
use dexter_sim::model::spatial::sil::{self, SilEnd};
use dexter_sim::model::spatial::SpatialBat;
use dexter_sim::systems::spatial_juggler::{SpatialConfig, SpatialTable};
use std::path::PathBuf;
use std::time::Duration;

/// The controller's own budget.
const BUDGET: u32 = <SpatialController as FixedRate>::STEP_INSTRUCTION_BUDGET;

/// The spatial image (line, echo and the spatial juggler).
fn firmware() -> PathBuf {
    dexter_tests::hosted_image("spatial")
}

fn options(corrupt_rate: f64) -> HilOptions {
    HilOptions {
        firmware_elf: firmware(),
        link: LinkKind::Semihosting,
        corrupt_rate,
        timeout: Duration::from_secs(30),
        ..HilOptions::default()
    }
}

/// The shipped closed-loop scene, `impacts` bats.
fn scene(impacts: usize) -> SpatialConfig {
    let path = dexter_tests::scenes_dir().join("spatial-juggler-sil.toml");
    let text = std::fs::read_to_string(&path).expect("the shipped scene");
    let mut file: toml::Table = toml::from_str(&text).expect("TOML");
    let table = file.remove("spatial_juggler").expect("[spatial_juggler]");
    let mut t: SpatialTable = table.try_into().expect("a valid table");
    t.impacts = impacts;
    t.config("spatial-juggler-sil").expect("a valid scene")
}

/// Every bat's numbers, bit for bit.
fn bits(bats: &[SpatialBat]) -> Vec<u64> {
    let each = |b: &SpatialBat| {
        let mut v: Vec<f64> = vec![b.time_s, b.energy_jpkg];
        v.extend(b.before.iter().chain(&b.after).chain(&b.joints_rad));
        v.extend(b.joint_rates_radps.iter().chain(&b.apex_m));
        v
    };
    bats.iter().flat_map(each).map(f64::to_bits).collect()
}

#[test]
fn the_juggle_on_the_target_equals_sil_bit_for_bit_within_budget() {
    let cfg = scene(15);
    let (params, plant) = cfg.sil.expect("a closed-loop scene");
    let apex = cfg.table.target_apex_m;
    let mut lock = LockStep::<SpatialController>::start(params, options(0.0)).expect("QEMU");
    let mut on_target = Vec::new();
    let hil_run =
        sil::run(&plant, apex, &mut lock, 15, &mut |b| on_target.push(*b)).expect("HIL run");
    let (report, stopped) = lock.finish_with_summary().expect("firmware stops");
    let mut sil_ctl = sil::sil_controller(params).unwrap();
    let mut in_sil = Vec::new();
    let sil_run = sil::run(&plant, apex, &mut sil_ctl, 15, &mut |b| in_sil.push(*b)).unwrap();
    eprintln!(
        "spatial: {} steps, {} bats, instructions min/mean/max {}/{:.1}/{} (budget {BUDGET}), stack {} of {} B, {:.0} steps/s",
        sil_run.safe.steps,
        in_sil.len(),
        report.step_instructions_min,
        report.step_instructions_mean,
        report.step_instructions_max,
        stopped.stack_used_bytes,
        stopped.stack_size_bytes,
        report.steps_per_wall_second
    );
    assert_eq!(hil_run.end, SilEnd::Completed, "{hil_run:?}");
    assert_eq!(hil_run, sil_run);
    assert_eq!(in_sil.len(), 15);
    assert_eq!(bits(&on_target), bits(&in_sil), "bats");
    assert_eq!(report.sil_mismatches, 0, "{report:?}");
    assert_eq!(report.link_errors, 0);
    assert_eq!(report.over_budget_steps, 0);
    assert!(report.step_instructions_max <= BUDGET, "{report:?}");
    assert!(report.step_instructions_min > 0);
    assert!(stopped.stack_used_bytes < stopped.stack_size_bytes);
}

#[test]
fn a_corrupted_link_is_the_safe_state_on_target_and_shadow_alike() {
    let cfg = scene(3);
    let (params, plant) = cfg.sil.expect("a closed-loop scene");
    let mut lock = LockStep::<SpatialController>::start(params, options(0.002)).expect("QEMU");
    let run = sil::run(&plant, cfg.table.target_apex_m, &mut lock, 3, &mut |_| {});
    let report = lock.finish().expect("firmware stops");
    let run = run.expect("the run goes on through the faults");
    assert!(report.link_errors > 0, "no frame was corrupted: {report:?}");
    assert_eq!(report.sil_mismatches, 0, "{report:?}");
    assert!(run.safe.safe_steps > 0, "{run:?}");
}
