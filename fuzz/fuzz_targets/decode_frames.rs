//! Any byte stream fed to the frame decoders yields messages or typed errors, never a panic,
//! and every completed frame is counted exactly once.
#![no_main]

use dexter_core::protocol::{decode, DeviceMessage, FrameDecoder, HostMessage, MAX_FRAME_LEN};
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let mut host = FrameDecoder::<MAX_FRAME_LEN>::new();
    let mut device = FrameDecoder::<32>::new();
    let mut completed = 0u32;
    for &b in data {
        if host.push::<HostMessage>(b).is_some() {
            completed += 1;
        }
        let _ = device.push::<DeviceMessage>(b);
    }
    let s = host.stats();
    assert_eq!(s.frames_ok + s.errors(), completed);
    let mut copy = data.to_vec();
    let _ = decode::<HostMessage>(&mut copy);
});
