//! The reserved stack and its high-water mark, measured by painting.
//!
//! `memory.x` reserves the stack as a region of its own at the bottom of RAM,
//! `[_stack_end, _stack_start)`, below the statics (flip-link's layout without the tool):
//! the stack grows down towards the start of RAM, so an overflow runs out of RAM and
//! faults (each board's MPU guard makes sure of it: `boards/*/src/fault.rs`) instead of
//! silently overwriting `.bss`. At reset cortex-m-rt (feature
//! `paint-stack`) fills the region with [`cortex_m_rt::STACK_PAINT_VALUE`]; [`usage`] finds
//! the lowest word that is no longer paint. The figure counts the words the code wrote, so
//! a frame that reserves a buffer it never touches is not counted; every buffer in this
//! firmware is initialised before use.

use cortex_m_rt::STACK_PAINT_VALUE;

extern "C" {
    /// Top of the stack (the initial stack pointer), from memory.x.
    static _stack_start: u32;
    /// Bottom of the stack region, from memory.x.
    static _stack_end: u32;
}

/// How much of the reserved stack a run has used.
#[derive(Clone, Copy, Debug, PartialEq, Eq, defmt::Format)]
pub struct StackUsage {
    /// Bytes between the top of the stack and the lowest word written since reset.
    pub used_bytes: u32,
    /// Bytes reserved for the stack in memory.x.
    pub size_bytes: u32,
}

/// The high-water mark of the stack since reset.
pub fn usage() -> StackUsage {
    // Taking the address of a linker symbol reads nothing.
    let top = core::ptr::addr_of!(_stack_start) as usize;
    let bottom = core::ptr::addr_of!(_stack_end) as usize;
    let mut lowest_used = top;
    let mut addr = bottom;
    while addr < top {
        // Safety: `addr` is word aligned (memory.x aligns both ends to 8) and inside the
        // stack region, which is RAM; a volatile read of a word there has no side effects.
        let word = unsafe { core::ptr::read_volatile(addr as *const u32) };
        if word != STACK_PAINT_VALUE {
            lowest_used = addr;
            break;
        }
        addr += 4;
    }
    StackUsage {
        used_bytes: (top - lowest_used) as u32,
        size_bytes: (top - bottom) as u32,
    }
}
