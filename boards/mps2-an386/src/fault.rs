//! The stack's guard, and the HardFault handler that reports what it caught.
//!
//! `memory.x` puts the stack at the bottom of RAM, below the statics (flip-link's layout),
//! so that a stack that runs past its bottom leaves RAM instead of overwriting `.bss`. On a
//! part whose memory below RAM is unmapped, that first access is a bus fault. QEMU's
//! `mps2-an386` is not such a part: `0x0101_0000..0x2000_0000` is an unimplemented-device
//! region ("RESERVED 2" in the monitor's `info mtree`), where writes are ignored and reads
//! return 0, without a fault. A stack overflow there ran on: a function that saved its
//! return address read back 0 and faulted on the jump to it, but a recursion that never
//! returns (the `fault-stack-overflow` hook's) walked down through 500 MB of ignored
//! writes into the alias of SSRAM1 at `0x0040_0000`, the memory the code runs from, and
//! overwrote the program: it hung, spinning in a `memset` overwritten by its own fill.
//! (Compiler-builtins' `memset` kept its return address on the stack, so the hook used
//! to fault by that accident; the word-at-a-time `memset` of `mem.rs` keeps nothing there.)
//!
//! So [`guard_stack`] has the MPU forbid every access to the 256 MiB below RAM
//! ([`GUARD_BASE`]`..`[`GUARD_END`], where nothing of this board lives): the first
//! access past the stack's bottom is a MemManage fault, whatever the frame sizes (a guard
//! inside the stack region can be stepped over by a frame that does not touch all of
//! it). MemManage is not enabled on its own, so it is taken as a HardFault, whose
//! exception frame cannot be stacked either (MemManage `MSTKERR`). The MPU is off in
//! the HardFault (`HFNMIENA` = 0), so the handler could run on that stack, but its
//! accesses would land in the ignored region again: [`HardFault`] first moves the stack
//! pointer back to the top of the stack when it is below the stack's bottom (or too close
//! to it to run the handler), then [`report`] logs what happened and ends the run with a
//! failure status. `tests/hil.rs::a_stack_overflow_faults_instead_of_corrupting_the_statics`
//! checks the log line.

/// The lowest address the MPU guard forbids.
pub const GUARD_BASE: u32 = 0x1000_0000;
/// One past the highest address the guard forbids: the bottom of RAM, where memory.x puts
/// the bottom of the stack (`_stack_end`; `tests/hil.rs` checks that they agree).
pub const GUARD_END: u32 = 0x2000_0000;
/// Bytes the HardFault handler needs below a valid exception frame: a frame closer than
/// this to the stack's bottom gets a fresh stack at the top (the frame stays readable).
const HANDLER_STACK_BYTES: u32 = 512;

extern "C" {
    /// Top of the stack (the initial stack pointer), from memory.x.
    static _stack_start: u32;
    /// Bottom of the stack region, from memory.x.
    static _stack_end: u32;
}

/// Region 0 of the MPU: no access at all to [`GUARD_BASE`]`..`[`GUARD_END`]; the default
/// memory map stays in force elsewhere (`PRIVDEFENA`; the firmware runs privileged), and
/// the MPU is off in HardFault and NMI (`HFNMIENA` = 0).
pub fn guard_stack(mpu: &cortex_m::peripheral::MPU) {
    const SIZE_FIELD: u32 = (GUARD_END - GUARD_BASE).trailing_zeros() - 1; // 2^(SIZE+1) B
    const VALID_REGION_0: u32 = 1 << 4;
    const ENABLE: u32 = 1;
    const AP_NO_ACCESS: u32 = 0b000 << 24;
    const XN: u32 = 1 << 28;
    const PRIVDEFENA: u32 = 1 << 2;
    // Safety: the region covers no memory the firmware uses (nothing is mapped there
    // but QEMU's unimplemented-device region); the barriers make it take effect before the
    // next access.
    unsafe {
        mpu.rbar.write(GUARD_BASE | VALID_REGION_0);
        mpu.rasr
            .write(XN | AP_NO_ACCESS | (SIZE_FIELD << 1) | ENABLE);
        mpu.ctrl.write(PRIVDEFENA | ENABLE);
    }
    cortex_m::asm::dsb();
    cortex_m::asm::isb();
}

/// The HardFault vector. It runs before any code that uses the stack: with the main stack
/// pointer below `_stack_end + HANDLER_STACK_BYTES` (a stack overflow, whose frame could
/// not be stacked, or a frame too close to the bottom to run the handler under it) it
/// restarts the stack at `_stack_start` (the old contents are not needed again: the run
/// ends), then passes the old stack pointer to [`report`]. (This replaces cortex-m-rt's
/// trampoline, which would hand the frame straight to a Rust function.)
///
/// # Safety
/// Only the hardware calls it, as the HardFault handler.
#[unsafe(naked)]
#[unsafe(no_mangle)]
pub unsafe extern "C" fn HardFault() -> ! {
    core::arch::naked_asm!(
        "mrs r0, msp",
        "ldr r1, ={bottom}+{handler}",
        "cmp r0, r1",
        "bhs 1f",
        "ldr r1, ={top}",
        "msr msp, r1",
        "1:",
        "b {report}",
        ".ltorg",
        bottom = sym _stack_end,
        handler = const HANDLER_STACK_BYTES,
        top = sym _stack_start,
        report = sym report,
    )
}

/// What the HardFault was, from the MemManage status (`CFSR`'s low byte, `MMFAR`): a stack
/// overflow if the exception frame could not be stacked (`MSTKERR`) or an access hit the
/// guard (`DACCVIOL` with a valid `MMFAR` in it), logged as such; any other fault logs the
/// stacked `pc`. Either way the run ends with a failure status.
extern "C" fn report(sp: u32) -> ! {
    const CFSR: *const u32 = 0xE000_ED28 as *const u32;
    const MMFAR: *const u32 = 0xE000_ED34 as *const u32;
    const DACCVIOL: u32 = 1 << 1;
    const MSTKERR: u32 = 1 << 4;
    const MMARVALID: u32 = 1 << 7;
    // Safety: volatile reads of two System Control Block registers (always mapped).
    let (cfsr, mmfar) = unsafe { (CFSR.read_volatile(), MMFAR.read_volatile()) };
    let hit = cfsr & (DACCVIOL | MMARVALID) == DACCVIOL | MMARVALID
        && (GUARD_BASE..GUARD_END).contains(&mmfar);
    if cfsr & MSTKERR != 0 || hit {
        defmt::error!(
            "HardFault: stack overflow (sp={=u32:#010x}, access at {=u32:#010x}): the MPU guard below the stack stopped it",
            sp,
            if hit { mmfar } else { sp }
        );
    } else {
        // Safety: without MSTKERR the frame was stacked at `sp`, in the stack region, and
        // the handler left it alone (its own stack is below `sp`, or a fresh one at the
        // top); the frame's seventh word is the faulting `pc`.
        let pc = unsafe { (sp as *const u32).add(6).read_volatile() };
        defmt::error!("HardFault at pc={=u32:#010x}", pc);
    }
    crate::exit(false)
}
