//! The one-joint arm in the loop: `ArmController` in the firmware (QEMU `mps2-an386`)
//! tracks each shipped task's planned B-spline on the simulated joint, in lock-step.
//!
//! For every task: every command equals the core's bit for bit (the driver's shadow), the
//! whole tracked trajectory (joint state and torque at every control step) equals the same
//! loop closed in SIL bit for bit, so the verification of the tracked motion (how tracking
//! error changes the outcome) is the same; every step is within `ArmController`'s
//! instruction budget. A corrupted frame puts the controller in its latched safe state,
//! answered identically by the firmware and the shadow, and the run reports the fault.
//!
//! These tests never skip: without `qemu-system-arm` or the `thumbv7em-none-eabihf` target
//! they fail saying what to install. Run with `--nocapture` to see each task's figures.

use dexter_core::arm_control::ArmController;
use dexter_core::fixed_rate::FixedRate;
use dexter_sim::controller::StepController;
use dexter_sim::hil::{self, HilOptions, LinkKind, LockStep};
use dexter_sim::model::arm::closed_loop::{track, track_sil, TrackedMotion};
use dexter_sim::model::arm::params::ArmConfig;
use dexter_sim::model::arm::planner::{plan, Plan};
use dexter_sim::model::arm::simulate::Executed;
use dexter_sim::model::arm::ArmScene;
use dexter_sim::systems::arm::examples;
use std::path::PathBuf;
use std::time::Duration;

/// The arm controller's own budget.
const BUDGET: u32 = <ArmController as FixedRate>::STEP_INSTRUCTION_BUDGET;

/// The arm image (`--no-default-features --features arm`: line, echo and arm; the default
/// image hosts the tilt table and the hopper instead, firmware/README.md, "Images").
fn firmware() -> PathBuf {
    dexter_tests::hosted_image("arm")
}

fn options(corrupt_rate: f64) -> HilOptions {
    HilOptions {
        firmware_elf: firmware(),
        link: LinkKind::Semihosting,
        corrupt_rate,
        timeout: Duration::from_secs(20),
        ..HilOptions::default()
    }
}

fn planned(text: &str) -> (ArmScene, Plan) {
    let scene = ArmConfig::from_toml_str(text)
        .and_then(|c| c.validate())
        .expect("a shipped scene");
    let p = plan(&scene).expect("the shipped scene plans");
    (scene, p)
}

/// Joint states and torques, bit for bit.
fn bits(m: &TrackedMotion) -> (Vec<(u64, u64)>, Vec<u64>) {
    let s = m.states.iter().map(|(x, v)| (x.to_bits(), v.to_bits()));
    (
        s.collect(),
        m.torques_nm.iter().map(|t| t.to_bits()).collect(),
    )
}

#[test]
fn every_task_tracked_on_the_target_equals_sil_bit_for_bit_within_budget() {
    for (name, text) in examples::ALL {
        let (scene, p) = planned(text);
        let params = scene.controller_params(&p.points_rad, p.segment_s).unwrap();
        let mut lock = LockStep::<ArmController>::start(params, options(0.0)).expect("QEMU");
        let (hil_motion, hil) =
            track(&scene, &mut lock as &mut dyn StepController<_>, &p).expect("HIL tracking");
        let (report, stopped) = lock.finish_with_summary().expect("firmware stops");
        let (sil_motion, sil) = track_sil(&scene, &p).expect("SIL tracking");
        eprintln!(
            "{name}: {} steps, instructions min/mean/max {}/{:.1}/{}, stack {} of {} B, tracked {:?}, max error {:.3e} rad",
            hil.steps,
            report.step_instructions_min,
            report.step_instructions_mean,
            report.step_instructions_max,
            stopped.stack_used_bytes,
            stopped.stack_size_bytes,
            hil.executed,
            hil.max_tracking_error_rad
        );
        assert_eq!(report.sil_mismatches, 0, "{name}: {report:?}");
        assert_eq!(report.link_errors, 0, "{name}");
        assert_eq!(report.over_budget_steps, 0, "{name}");
        assert!(report.step_instructions_max <= BUDGET, "{name}: {report:?}");
        assert!(report.step_instructions_min > 0);
        assert_eq!(bits(&hil_motion), bits(&sil_motion), "{name}: trajectories");
        assert_eq!(hil, sil, "{name}: the verification of the tracked motion");
        assert_eq!(hil.fault, None, "{name}");
        assert_eq!(hil.executed, Executed::Ok, "{name}: {}", hil.reason);
        assert_eq!(u64::from(stopped.steps), hil.steps as u64);
        assert!(stopped.stack_used_bytes < stopped.stack_size_bytes);
    }
}

#[test]
fn a_corrupted_frame_latches_the_safe_state_on_target_and_shadow_alike() {
    let (scene, p) = planned(examples::THROW);
    let params = scene.controller_params(&p.points_rad, p.segment_s).unwrap();
    let mut lock = LockStep::<ArmController>::start(params, options(0.002)).expect("QEMU");
    let (_, hil) =
        track(&scene, &mut lock as &mut dyn StepController<_>, &p).expect("HIL tracking");
    let counts = lock.link_counts();
    let report = lock.finish().expect("firmware stops");
    assert!(report.link_errors > 0, "no frame was corrupted: {report:?}");
    assert_eq!(report.sil_mismatches, 0, "{report:?} {counts:?}");
    let fault = hil.fault.expect("the controller went to its safe state");
    assert!(fault.starts_with("LinkTimeout"), "{fault}");
    assert!(hil.max_torque_nm <= scene.bounds.torque_max_nm);
}

/// The default image (line, echo, tilt, hop) leaves the arm's parameters undecoded and
/// names the kind it does not host; the arm image does the same for the tilt table.
#[test]
fn each_image_refuses_a_kind_it_does_not_host_naming_it() {
    let (scene, p) = planned(examples::THROW);
    let params = scene.controller_params(&p.points_rad, p.segment_s).unwrap();
    // The arm image first: building it overwrites the default image's path (cargo has one
    // output path for both), and a struct update's base is evaluated after its fields, so
    // `..options(0.0)` here could replace the default ELF just built before QEMU boots it.
    let arm = options(0.0);
    let default = HilOptions {
        firmware_elf: hil::build_firmware().expect("the default image builds"),
        ..arm
    };
    let err = LockStep::<ArmController>::start(params, default)
        .err()
        .expect("the default image does not host the arm")
        .to_string();
    assert!(err.contains("does not host the Arm controller"), "{err}");
    let tilt = dexter_core::tilt_control::TiltParams::default();
    let err = LockStep::<dexter_core::tilt_control::TiltController>::start(tilt, options(0.0))
        .err()
        .expect("the arm image does not host the tilt table")
        .to_string();
    assert!(err.contains("does not host the Tilt controller"), "{err}");
}
