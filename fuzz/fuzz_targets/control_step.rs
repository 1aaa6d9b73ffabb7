//! Any sequence of sensor frames gives a finite command within the paddle's acceleration
//! limit, or the safe state with a fault code; never a panic.
#![no_main]

use dexter_core::control::{Controller, ControllerParams};
use dexter_core::fixed_rate::FixedRate;
use dexter_core::fixed_rate::{Fault, Mode};
use dexter_core::protocol::SensorFrame;
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let params = ControllerParams::default();
    let mut c = Controller::new(params).expect("default params are valid");
    for chunk in data.chunks_exact(16) {
        let word =
            |i: usize| u32::from_le_bytes([chunk[i], chunk[i + 1], chunk[i + 2], chunk[i + 3]]);
        let frame = SensorFrame {
            seq: word(0),
            ball_height_m: f32::from_bits(word(4)),
            paddle_height_m: f32::from_bits(word(8)),
            paddle_velocity_mps: f32::from_bits(word(12)),
        };
        let cmd = c.step(&frame);
        assert!(cmd.paddle_accel_mps2.is_finite());
        assert!(cmd.paddle_accel_mps2.abs() <= params.limits.accel_max_mps2);
        assert_eq!(cmd.mode == Mode::Safe, cmd.fault != Fault::None);
    }
});
