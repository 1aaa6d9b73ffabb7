//! The juggle (`scenes/arm-juggle.toml`) in the loop: every cycle is planned from where
//! the last tracked catch left the square, sent to the firmware (QEMU `mps2-an386`) as a
//! new `Configure`, and tracked by its `ArmController`. The chain of cycles, every
//! tracked trajectory bit for bit and every verdict, equals the same chain closed in SIL,
//! every step within the controller's instruction budget, and every cycle is caught.

use dexter_core::arm_control::ArmController;
use dexter_core::fixed_rate::FixedRate;
use dexter_sim::controller::{Sil, StepController};
use dexter_sim::hil::{HilOptions, LinkKind, LockStep};
use dexter_sim::model::arm::closed_loop::TrackedMotion;
use dexter_sim::model::arm::juggle::juggle;
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
fn the_juggle_tracked_on_the_target_equals_sil_cycle_by_cycle_bit_for_bit() {
    let elf = dexter_tests::hosted_image("arm");
    let cfg = ArmConfig::from_toml_str(examples::JUGGLE).expect("the shipped scene");
    let scene = cfg.validate().expect("the shipped scene");
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
    let (hil_chain, hil_motions) =
        juggle(&cfg, Some(&mut lock as &mut dyn StepController<_>)).expect("HIL juggle");
    let (report, _) = lock.finish_with_summary().expect("firmware stops");
    let mut sil = Sil::<ArmController>::new(params).unwrap();
    let (sil_chain, sil_motions) = juggle(&cfg, Some(&mut sil)).expect("SIL juggle");
    assert_eq!(report.sil_mismatches, 0, "{report:?}");
    assert_eq!(report.link_errors, 0);
    assert_eq!(report.over_budget_steps, 0);
    assert!(report.step_instructions_max <= BUDGET, "{report:?}");
    assert_eq!(hil_chain, sil_chain, "the chains of cycles");
    assert_eq!(hil_motions.len(), sil_motions.len());
    for (k, (a, b)) in hil_motions.iter().zip(&sil_motions).enumerate() {
        assert_eq!(bits(a), bits(b), "cycle {k}'s tracked trajectory");
    }
    assert_eq!(
        sil_chain.completed,
        scene.task.cycles,
        "every cycle caught: {:?}",
        sil_chain.cycles.last()
    );
}
