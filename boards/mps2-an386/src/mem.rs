//! `memcpy` a word at a time, and a small `memset`, for this image, in place of
//! compiler-builtins' ones.
//!
//! The lock-step server's hot path copies short runs: a link chunk into the frame
//! decoder, a sensor frame out of its slot, postcard's varint bytes. compiler-builtins'
//! `memcpy` (a weak symbol, so this strong one replaces it at link time) spends some
//! thirty instructions on setting up before it copies a byte and then copies an unaligned
//! source byte by byte: in QEMU it was a fifth of the guest instructions of a control
//! period (BENCHMARKS.md, "HIL guest instructions"). This one copies four bytes per
//! `ldr`/`str` pair, aligned or not (the Cortex-M4 allows unaligned word accesses to
//! normal memory, and the firmware never sets `CCR.UNALIGN_TRP`), then the last 0 to 3
//! bytes one at a time: about one instruction per byte, three to set up. It is written
//! in assembly so that the compiler cannot turn its loop back into a call to `memcpy`.
//!
//! The AEABI entry points the compiler also calls (`__aeabi_memcpy`, `…4`, `…8`: the same
//! arguments, no result) branch to it. `memset` and its AEABI entry points (`memclr`:
//! zeroing) are replaced for flash: together compiler-builtins' are over 500 bytes, this
//! `memset` 40. `memmove` stays compiler-builtins' (nothing in the image calls it). `tests/hil.rs` runs every HIL scene on this image, bit for
//! bit against SIL, so a wrong copy shows there.

/// `memcpy(dest, src, n)`: copies `n` bytes from `src` to `dest` (not overlapping),
/// returns `dest`.
///
/// # Safety
/// The C contract: `src` readable and `dest` writable for `n` bytes, not overlapping.
#[unsafe(naked)]
#[unsafe(no_mangle)]
pub unsafe extern "C" fn memcpy(dest: *mut u8, src: *const u8, n: usize) -> *mut u8 {
    core::arch::naked_asm!(
        "mov r12, r0",
        "subs r2, r2, #4",
        "blo 2f",
        "1:",
        "ldr r3, [r1], #4",
        "str r3, [r12], #4",
        "subs r2, r2, #4",
        "bhs 1b",
        "2:",
        "adds r2, r2, #4",
        "beq 4f",
        "3:",
        "ldrb r3, [r1], #1",
        "strb r3, [r12], #1",
        "subs r2, r2, #1",
        "bne 3b",
        "4:",
        "bx lr",
    )
}

/// `__aeabi_memcpy(dest, src, n)`: [`memcpy`] without its result.
///
/// # Safety
/// As [`memcpy`].
#[unsafe(naked)]
#[unsafe(no_mangle)]
pub unsafe extern "C" fn __aeabi_memcpy(dest: *mut u8, src: *const u8, n: usize) {
    core::arch::naked_asm!("b {memcpy}", memcpy = sym memcpy)
}

/// `__aeabi_memcpy4`: [`memcpy`] of word-aligned `dest` and `src`.
///
/// # Safety
/// As [`memcpy`].
#[unsafe(naked)]
#[unsafe(no_mangle)]
pub unsafe extern "C" fn __aeabi_memcpy4(dest: *mut u8, src: *const u8, n: usize) {
    core::arch::naked_asm!("b {memcpy}", memcpy = sym memcpy)
}

/// `__aeabi_memcpy8`: [`memcpy`] of doubleword-aligned `dest` and `src`.
///
/// # Safety
/// As [`memcpy`].
#[unsafe(naked)]
#[unsafe(no_mangle)]
pub unsafe extern "C" fn __aeabi_memcpy8(dest: *mut u8, src: *const u8, n: usize) {
    core::arch::naked_asm!("b {memcpy}", memcpy = sym memcpy)
}

/// `memset(dest, c, n)`: fills `n` bytes at `dest` with the low byte of `c`, returns
/// `dest`: a word at a time, then the last 0 to 3 bytes. Here for flash, not speed: it is
/// 40 bytes, compiler-builtins' `memset` and its AEABI entry points over 500.
///
/// # Safety
/// The C contract: `dest` writable for `n` bytes.
#[unsafe(naked)]
#[unsafe(no_mangle)]
pub unsafe extern "C" fn memset(dest: *mut u8, c: i32, n: usize) -> *mut u8 {
    core::arch::naked_asm!(
        "mov r12, r0",
        "and r1, r1, #0xff",
        "orr r1, r1, r1, lsl #8",
        "orr r1, r1, r1, lsl #16",
        "subs r2, r2, #4",
        "blo 2f",
        "1:",
        "str r1, [r12], #4",
        "subs r2, r2, #4",
        "bhs 1b",
        "2:",
        "adds r2, r2, #4",
        "beq 4f",
        "3:",
        "strb r1, [r12], #1",
        "subs r2, r2, #1",
        "bne 3b",
        "4:",
        "bx lr",
    )
}

/// `__aeabi_memset(dest, n, c)` (the AEABI order): [`memset`] without its result.
///
/// # Safety
/// As [`memset`].
#[unsafe(naked)]
#[unsafe(no_mangle)]
pub unsafe extern "C" fn __aeabi_memset(dest: *mut u8, n: usize, c: i32) {
    core::arch::naked_asm!("mov r3, r1", "mov r1, r2", "mov r2, r3", "b {memset}", memset = sym memset)
}

/// `__aeabi_memset4`: [`__aeabi_memset`] of a word-aligned `dest`.
///
/// # Safety
/// As [`memset`].
#[unsafe(naked)]
#[unsafe(no_mangle)]
pub unsafe extern "C" fn __aeabi_memset4(dest: *mut u8, n: usize, c: i32) {
    core::arch::naked_asm!("b {f}", f = sym __aeabi_memset)
}

/// `__aeabi_memset8`: [`__aeabi_memset`] of a doubleword-aligned `dest`.
///
/// # Safety
/// As [`memset`].
#[unsafe(naked)]
#[unsafe(no_mangle)]
pub unsafe extern "C" fn __aeabi_memset8(dest: *mut u8, n: usize, c: i32) {
    core::arch::naked_asm!("b {f}", f = sym __aeabi_memset)
}

/// `__aeabi_memclr(dest, n)`: [`memset`] with zero.
///
/// # Safety
/// As [`memset`].
#[unsafe(naked)]
#[unsafe(no_mangle)]
pub unsafe extern "C" fn __aeabi_memclr(dest: *mut u8, n: usize) {
    core::arch::naked_asm!("mov r2, r1", "movs r1, #0", "b {memset}", memset = sym memset)
}

/// `__aeabi_memclr4`: [`__aeabi_memclr`] of a word-aligned `dest`.
///
/// # Safety
/// As [`memset`].
#[unsafe(naked)]
#[unsafe(no_mangle)]
pub unsafe extern "C" fn __aeabi_memclr4(dest: *mut u8, n: usize) {
    core::arch::naked_asm!("b {f}", f = sym __aeabi_memclr)
}

/// `__aeabi_memclr8`: [`__aeabi_memclr`] of a doubleword-aligned `dest`.
///
/// # Safety
/// As [`memset`].
#[unsafe(naked)]
#[unsafe(no_mangle)]
pub unsafe extern "C" fn __aeabi_memclr8(dest: *mut u8, n: usize) {
    core::arch::naked_asm!("b {f}", f = sym __aeabi_memclr)
}
