//! Calibration mode (feature `calibrate`: `cargo board-calibrate`): the image that reads the
//! rig's sensors raw, for the figures of `rig.rs`, with the motor never driven (parked at
//! duty 0 from reset, as after a watchdog reset). Each control period it samples the
//! encoder and the camera; five times a second it logs what it read, raw and through
//! `rig.rs`'s figures, and it keeps the newest reading in [`DEXTER_CALIBRATION`] for a
//! debugger (and the emulator test, `host-sim/tests/board_hil.rs`). How to use it:
//! firmware/README.md, "From the box to a juggling paddle", step 4.
//!
//! - metres per encoder count: move the paddle by hand over a measured distance `d` and
//!   read the counts before and after: `M_PER_COUNT = d / (counts after - counts before)`
//!   (negative if the count falls as the paddle rises);
//! - the camera: hold the ball at two measured heights `h1 < h2` and read the rows `r1`,
//!   `r2`: `M_PER_PX = (h2 - h1) / (r1 - r2)`, `ROW_AT_ZERO_PX = r1 + h1 / M_PER_PX`.
//!
//! The host link stays open: a host's `Configure` starts HIL as in the product image.

use crate::rig::{BoardRig, M_PER_COUNT, M_PER_PX, PADDLE_HEIGHT_AT_RESET_M, ROW_AT_ZERO_PX};
use core::sync::atomic::{AtomicI32, AtomicU32, Ordering};
use dexter_rig::rig::Rig;

/// The newest raw reading, word by word (`xp` in QEMU's monitor, a debugger's memory view).
#[repr(C)]
pub struct Readout {
    /// The encoder's position, counts from reset.
    pub counts: AtomicI32,
    /// Camera frames parsed since reset.
    pub frames: AtomicU32,
    /// The newest image's row, 1/16 px (the frame's own resolution).
    pub row_px16: AtomicU32,
    /// The newest image's column, 1/16 px.
    pub column_px16: AtomicU32,
    /// 1 if the newest image found the ball.
    pub found: AtomicU32,
}

/// See [`Readout`].
#[no_mangle]
pub static DEXTER_CALIBRATION: Readout = Readout {
    counts: AtomicI32::new(0),
    frames: AtomicU32::new(0),
    row_px16: AtomicU32::new(0),
    column_px16: AtomicU32::new(0),
    found: AtomicU32::new(0),
};

/// Control periods between two log lines (5 Hz at 500 Hz).
const LOG_EVERY_PERIODS: u32 = 100;

static PERIODS: AtomicU32 = AtomicU32::new(0);

/// One period of calibration: sample the sensors, publish, log now and then.
pub fn sample(rig: &mut BoardRig) {
    let _ = rig.sense();
    let counts = rig.paddle_counts();
    let image = rig.last_image().unwrap_or_default();
    let r = &DEXTER_CALIBRATION;
    r.counts.store(counts as i32, Ordering::Relaxed);
    r.frames.store(rig.camera_stats().frames, Ordering::Relaxed);
    r.row_px16
        .store((image.y_px * 16.0) as u32, Ordering::Relaxed);
    r.column_px16
        .store((image.x_px * 16.0) as u32, Ordering::Relaxed);
    r.found.store(u32::from(image.found), Ordering::Relaxed);
    let period = PERIODS.fetch_add(1, Ordering::Relaxed);
    if period.is_multiple_of(LOG_EVERY_PERIODS) {
        defmt::info!(
            "calibrate: encoder {=i64} counts (= {=f32} m at M_PER_COUNT); camera frames {=u32}, image {=u8}: found {=bool}, row {=f32} px, column {=f32} px (= {=f32} m at ROW_AT_ZERO_PX, M_PER_PX)",
            counts,
            PADDLE_HEIGHT_AT_RESET_M + counts as f32 * M_PER_COUNT,
            rig.camera_stats().frames,
            image.seq,
            image.found,
            image.y_px,
            image.x_px,
            (ROW_AT_ZERO_PX - image.y_px) * M_PER_PX
        );
    }
}
