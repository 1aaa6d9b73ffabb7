//! The throw and catch (`scenes/arm-throw-catch.toml`) in the loop: `ArmController` in
//! the firmware (QEMU `mps2-an386`) tracks the throw, its bang-bang move to the catch and the hold at
//! the catching angle; the whole tracked trajectory equals SIL's bit for bit, every step
//! within the controller's instruction budget, and so the verification of the tracked
//! catch is the same. (Whether that tracked catch succeeds is not asserted here: at the
//! plan's own mu it slips, docs/arm.md "Limits".)

use dexter_core::arm_control::ArmController;
use dexter_core::fixed_rate::FixedRate;
use dexter_sim::controller::StepController;
use dexter_sim::hil::{HilOptions, LinkKind, LockStep};
use dexter_sim::model::arm::closed_loop::{track, track_sil, TrackedMotion};
use dexter_sim::model::arm::params::ArmConfig;
use dexter_sim::model::arm::planner::plan;
use dexter_sim::systems::arm::examples;
use std::time::Duration;

const BUDGET: u32 = <ArmController as FixedRate>::STEP_INSTRUCTION_BUDGET;

fn bits(m: &TrackedMotion) -> (Vec<(u64, u64)>, Vec<u64>) {
    let s = m.states.iter().map(|(x, v)| (x.to_bits(), v.to_bits()));
    (
        s.collect(),
        m.torques_nm.iter().map(|t| t.to_bits()).collect(),
    )
}

#[test]
fn the_throw_and_catch_tracked_on_the_target_equals_sil_bit_for_bit_within_budget() {
    let elf = dexter_tests::hosted_image("arm");
    let scene = ArmConfig::from_toml_str(examples::THROW_CATCH)
        .and_then(|c| c.validate())
        .expect("the shipped scene");
    let p = plan(&scene).expect("the shipped scene plans");
    let params = scene.controller_params(&p.points_rad, p.segment_s).unwrap();
    let opts = HilOptions {
        firmware_elf: elf,
        link: LinkKind::Semihosting,
        corrupt_rate: 0.0,
        timeout: Duration::from_secs(20),
        ..HilOptions::default()
    };
    let mut lock = LockStep::<ArmController>::start(params, opts).expect("QEMU");
    let (hil_motion, hil) =
        track(&scene, &mut lock as &mut dyn StepController<_>, &p).expect("HIL tracking");
    let (report, stopped) = lock.finish_with_summary().expect("firmware stops");
    let (sil_motion, sil) = track_sil(&scene, &p).expect("SIL tracking");
    assert_eq!(report.sil_mismatches, 0, "{report:?}");
    assert_eq!(report.link_errors, 0);
    assert_eq!(report.over_budget_steps, 0);
    assert!(report.step_instructions_max <= BUDGET, "{report:?}");
    assert_eq!(bits(&hil_motion), bits(&sil_motion), "trajectories");
    assert_eq!(hil, sil, "the verification of the tracked motion");
    assert_eq!(hil.fault, None);
    assert_eq!(u64::from(stopped.steps), hil.steps as u64);
}
