//! The tilt controller's parameter checks at their edges and its command's `Reply` view,
//! each against what its documentation states (a mutation pass over `tilt_control` found
//! these unpinned by the core's own tests).

use dexter_core::fixed_rate::{Fault, Mode, Reply};
use dexter_core::params::ParamError;
use dexter_core::tilt_control::{PlanStatus, TiltCommand, TiltParams};

fn refused(p: &TiltParams, key: &'static str) {
    assert_eq!(p.validate(), Err(ParamError::OutOfRange(key)), "{key}");
}

#[test]
fn the_defaults_are_valid() {
    assert_eq!(TiltParams::default().validate(), Ok(()));
}

#[test]
fn an_axis_whose_travel_is_empty_is_refused_by_name() {
    let d = TiltParams::default();
    let mut p = d;
    p.tilt.max_rad = p.tilt.min_rad;
    p.tilt.home_rad = p.tilt.min_rad;
    refused(&p, "tilt.max_rad");
    let mut p = d;
    p.stroke.max_m = p.stroke.min_m;
    p.impact_height_m = p.stroke.min_m;
    refused(&p, "stroke.max_m");
}

#[test]
fn a_stroke_that_cannot_move_is_refused_by_name() {
    let mut p = TiltParams::default();
    p.stroke.velocity_max_mps = 0.0;
    assert_eq!(
        p.validate(),
        Err(ParamError::NotPositive("stroke.velocity_max_mps"))
    );
    let mut p = TiltParams::default();
    p.stroke.accel_max_mps2 = -1.0;
    assert_eq!(
        p.validate(),
        Err(ParamError::NotPositive("stroke.accel_max_mps2"))
    );
}

#[test]
fn the_apex_must_be_above_the_half_length_and_the_window_not_empty() {
    let d = TiltParams::default();
    let mut p = d;
    p.target_apex_m = p.l_m;
    refused(&p, "target_apex_m");
    let mut p = d;
    p.y_max_m = p.y_min_m;
    refused(&p, "y_max_m");
}

#[test]
fn the_commit_must_come_after_a_latency_a_planning_cycle_and_a_period() {
    let d = TiltParams::default();
    // the documented due time: latency + (contact_iterations + 7) periods + one period
    let cycle_s = f32::from(d.contact_iterations + 7) * d.dt_s;
    let due_s = d.estimator.latency_s + cycle_s + d.dt_s;
    assert!(
        due_s + d.dt_s <= 0.2,
        "the test's commit stays within its own range"
    );
    for (commit_s, ok) in [
        (due_s, false),
        (due_s - 0.5 * d.dt_s, false),
        (due_s + d.dt_s, true),
    ] {
        let p = TiltParams { commit_s, ..d };
        if ok {
            assert_eq!(p.validate(), Ok(()), "commit {commit_s} after due {due_s}");
        } else {
            refused(&p, "commit_s");
        }
    }
}

fn command() -> TiltCommand {
    TiltCommand {
        seq: 7,
        tilt_accel_radps2: 1.5,
        stroke_accel_mps2: -2.5,
        tilt_ref_rad: 0.125,
        stroke_ref_m: 0.0625,
        impact_in_s: 0.25,
        mode: Mode::Track,
        fault: Fault::None,
        plan: PlanStatus::Planned,
    }
}

#[test]
fn the_reply_view_reads_the_commands_own_fields() {
    let c = TiltCommand {
        mode: Mode::Safe,
        fault: Fault::Stale,
        ..command()
    };
    assert_eq!(
        (c.seq(), c.mode(), c.fault()),
        (7, Mode::Safe, Fault::Stale)
    );
}

#[test]
fn bit_identical_tells_every_field_apart_to_the_bit() {
    let a = command();
    assert!(a.bit_identical(&a));
    let zero = TiltCommand {
        impact_in_s: 0.0,
        ..a
    };
    let variants = [
        TiltCommand { seq: 8, ..a },
        TiltCommand {
            tilt_accel_radps2: 1.5000001,
            ..a
        },
        TiltCommand {
            stroke_accel_mps2: -2.4999998,
            ..a
        },
        TiltCommand {
            tilt_ref_rad: 0.12500001,
            ..a
        },
        TiltCommand {
            stroke_ref_m: 0.06250001,
            ..a
        },
        TiltCommand {
            impact_in_s: 0.25000003,
            ..a
        },
        TiltCommand {
            mode: Mode::Hold,
            ..a
        },
        TiltCommand {
            fault: Fault::NonFinite,
            ..a
        },
        TiltCommand {
            plan: PlanStatus::Committed,
            ..a
        },
    ];
    for (i, v) in variants.iter().enumerate() {
        assert!(!a.bit_identical(v), "field {i} differs");
        assert!(!v.bit_identical(&a), "field {i} differs");
    }
    // to the bit: -0.0 is not 0.0, although they compare equal
    let negative_zero = TiltCommand {
        impact_in_s: -0.0,
        ..a
    };
    assert!(!zero.bit_identical(&negative_zero));
}

#[test]
fn non_finite_travel_ends_and_a_zero_stale_limit_are_refused_by_name() {
    let d = TiltParams::default();
    let mut p = d;
    p.stroke.min_m = f32::NAN;
    assert_eq!(p.validate(), Err(ParamError::NotFinite("stroke.min_m")));
    let mut p = d;
    p.stroke.max_m = f32::INFINITY;
    assert_eq!(p.validate(), Err(ParamError::NotFinite("stroke.max_m")));
    let mut p = d;
    p.y_min_m = f32::NEG_INFINITY;
    assert_eq!(p.validate(), Err(ParamError::NotFinite("y_min_m")));
    let p = TiltParams {
        stale_limit_steps: 0,
        ..d
    };
    assert_eq!(
        p.validate(),
        Err(ParamError::NotPositive("stale_limit_steps"))
    );
}
