//! `Reply::bit_identical` of every command kind: a change to any one field, an `f32`'s sign
//! of zero or NaN payload included, makes two commands differ; and every kind's largest
//! encoding fits the stack buffer it is encoded into (`MAX_COMMAND_LEN`), so no command is
//! refused for its length.
//!
//! The field lists below are written from the structs' definitions; the struct literals
//! name every field, so a field added to a command fails to compile here until it is
//! flipped too.

use dexter_core::arm_control::ArmCommand;
use dexter_core::control::ActuatorCommand;
use dexter_core::echo::EchoCommand;
use dexter_core::fixed_rate::{Fault, Mode, Reply, MAX_COMMAND_LEN};
use dexter_core::hop::StancePhase;
use dexter_core::hop_control::HopCommand;
use dexter_core::tilt_control::{PlanStatus, TiltCommand};

/// A NaN with a payload other than the default quiet NaN's.
const NAN_PAYLOAD: f32 = f32::from_bits(0x7fc0_0001);

/// `base` is identical to itself, and each of `changed` differs from it both ways.
fn each_change_differs<R: Reply + core::fmt::Debug>(base: R, changed: &[R]) {
    assert!(base.bit_identical(&base));
    for (i, c) in changed.iter().enumerate() {
        assert!(c.bit_identical(c), "change {i} against itself");
        assert!(!base.bit_identical(c), "change {i}: {c:?}");
        assert!(!c.bit_identical(&base), "change {i}: {c:?}");
    }
}

/// Every `f32` field of `base` (through `set`) at -0.0 and at a NaN of another payload
/// differs from it at +0.0 and at the default NaN.
fn zero_and_nan_by_bits<R: Reply + core::fmt::Debug>(base: R, set: impl Fn(&mut R, f32)) {
    for (a, b) in [(0.0, -0.0), (f32::NAN, NAN_PAYLOAD)] {
        let (mut x, mut y) = (base, base);
        set(&mut x, a);
        set(&mut y, b);
        assert!(!x.bit_identical(&y), "{a:?} vs {b:?} ({:#x})", b.to_bits());
    }
}

/// The postcard length of `command`, which must fit [`MAX_COMMAND_LEN`].
fn encoded_len<R: Reply>(command: &R) -> usize {
    let mut buf = [0u8; MAX_COMMAND_LEN];
    postcard::to_slice(command, &mut buf)
        .expect("fits MAX_COMMAND_LEN")
        .len()
}

/// The worst-case postcard length of a command of `f32s` floats, a `u32` sequence number
/// and `bytes` one-byte fields (bools, small enums): a varint `u32` takes up to 5 bytes.
fn worst_len(f32s: usize, bytes: usize) -> usize {
    5 + 4 * f32s + bytes
}

fn line() -> ActuatorCommand {
    ActuatorCommand {
        seq: 7,
        paddle_accel_mps2: 1.5,
        paddle_height_ref_m: 0.25,
        paddle_velocity_ref_mps: -0.5,
        mode: Mode::Track,
        fault: Fault::None,
    }
}

#[test]
fn line_commands_differ_in_every_field() {
    let b = line();
    each_change_differs(
        b,
        &[
            ActuatorCommand { seq: 8, ..b },
            ActuatorCommand {
                paddle_accel_mps2: 1.25,
                ..b
            },
            ActuatorCommand {
                paddle_height_ref_m: 0.5,
                ..b
            },
            ActuatorCommand {
                paddle_velocity_ref_mps: 0.5,
                ..b
            },
            ActuatorCommand {
                mode: Mode::Safe,
                ..b
            },
            ActuatorCommand {
                fault: Fault::Stale,
                ..b
            },
        ],
    );
    zero_and_nan_by_bits(b, |c, v| c.paddle_accel_mps2 = v);
    zero_and_nan_by_bits(b, |c, v| c.paddle_height_ref_m = v);
    zero_and_nan_by_bits(b, |c, v| c.paddle_velocity_ref_mps = v);
    let worst = ActuatorCommand {
        seq: u32::MAX,
        fault: Fault::Overrun,
        ..b
    };
    assert_eq!(encoded_len(&worst), worst_len(3, 2));
}

#[test]
fn echo_commands_differ_in_every_field() {
    let b = EchoCommand {
        seq: 3,
        value: 2.5,
        mode: Mode::Track,
        fault: Fault::None,
    };
    each_change_differs(
        b,
        &[
            EchoCommand { seq: 4, ..b },
            EchoCommand { value: -2.5, ..b },
            EchoCommand {
                mode: Mode::Hold,
                ..b
            },
            EchoCommand {
                fault: Fault::NonFinite,
                ..b
            },
        ],
    );
    zero_and_nan_by_bits(b, |c, v| c.value = v);
    let worst = EchoCommand { seq: u32::MAX, ..b };
    assert_eq!(encoded_len(&worst), worst_len(1, 2));
}

#[test]
fn tilt_commands_differ_in_every_field() {
    let b = TiltCommand {
        seq: 11,
        tilt_accel_radps2: 0.5,
        stroke_accel_mps2: -1.0,
        tilt_ref_rad: 0.125,
        stroke_ref_m: 0.01,
        impact_in_s: 0.3,
        mode: Mode::Track,
        fault: Fault::None,
        plan: PlanStatus::Planned,
    };
    each_change_differs(
        b,
        &[
            TiltCommand { seq: 12, ..b },
            TiltCommand {
                tilt_accel_radps2: 0.25,
                ..b
            },
            TiltCommand {
                stroke_accel_mps2: 1.0,
                ..b
            },
            TiltCommand {
                tilt_ref_rad: -0.125,
                ..b
            },
            TiltCommand {
                stroke_ref_m: 0.02,
                ..b
            },
            TiltCommand {
                impact_in_s: 0.6,
                ..b
            },
            TiltCommand {
                mode: Mode::Hold,
                ..b
            },
            TiltCommand {
                fault: Fault::OutOfRange,
                ..b
            },
            TiltCommand {
                plan: PlanStatus::Committed,
                ..b
            },
        ],
    );
    zero_and_nan_by_bits(b, |c, v| c.tilt_accel_radps2 = v);
    zero_and_nan_by_bits(b, |c, v| c.stroke_accel_mps2 = v);
    zero_and_nan_by_bits(b, |c, v| c.tilt_ref_rad = v);
    zero_and_nan_by_bits(b, |c, v| c.stroke_ref_m = v);
    zero_and_nan_by_bits(b, |c, v| c.impact_in_s = v);
    let worst = TiltCommand {
        seq: u32::MAX,
        plan: PlanStatus::Unreachable,
        ..b
    };
    assert_eq!(encoded_len(&worst), worst_len(5, 3));
}

#[test]
fn hop_commands_differ_in_every_field() {
    let b = HopCommand {
        seq: 5,
        valve_open: true,
        thrust_mps2: 30.0,
        phase: StancePhase::Thrust,
        mode: Mode::Track,
        fault: Fault::None,
    };
    each_change_differs(
        b,
        &[
            HopCommand { seq: 6, ..b },
            HopCommand {
                valve_open: false,
                ..b
            },
            HopCommand {
                thrust_mps2: 29.5,
                ..b
            },
            HopCommand {
                phase: StancePhase::Decompression,
                ..b
            },
            HopCommand {
                mode: Mode::Hold,
                ..b
            },
            HopCommand {
                fault: Fault::LinkTimeout,
                ..b
            },
        ],
    );
    zero_and_nan_by_bits(b, |c, v| c.thrust_mps2 = v);
    let worst = HopCommand { seq: u32::MAX, ..b };
    assert_eq!(encoded_len(&worst), worst_len(1, 4));
}

#[test]
fn arm_commands_differ_in_every_field() {
    let b = ArmCommand {
        seq: 9,
        torque_nm: 0.75,
        accel_cmd_radps2: 3.0,
        angle_ref_rad: 0.5,
        velocity_ref_radps: 1.0,
        mode: Mode::Track,
        fault: Fault::None,
    };
    each_change_differs(
        b,
        &[
            ArmCommand { seq: 10, ..b },
            ArmCommand {
                torque_nm: -0.75,
                ..b
            },
            ArmCommand {
                accel_cmd_radps2: 2.0,
                ..b
            },
            ArmCommand {
                angle_ref_rad: 0.25,
                ..b
            },
            ArmCommand {
                velocity_ref_radps: 0.5,
                ..b
            },
            ArmCommand {
                mode: Mode::Safe,
                ..b
            },
            ArmCommand {
                fault: Fault::Stale,
                ..b
            },
        ],
    );
    zero_and_nan_by_bits(b, |c, v| c.torque_nm = v);
    zero_and_nan_by_bits(b, |c, v| c.accel_cmd_radps2 = v);
    zero_and_nan_by_bits(b, |c, v| c.angle_ref_rad = v);
    zero_and_nan_by_bits(b, |c, v| c.velocity_ref_radps = v);
    let worst = ArmCommand { seq: u32::MAX, ..b };
    assert_eq!(encoded_len(&worst), worst_len(4, 2));
}
