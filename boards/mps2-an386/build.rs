//! Puts `boards/mps2-an386/memory.x` on the linker search path (cortex-m-rt's `link.x` includes
//! it), through a copy in `OUT_DIR`. (It is not at the workspace root: rustc links with the
//! workspace root as its working directory, where the linker would find it first.)
//!
//! The search path is a link argument of this package's binary only
//! (`rustc-link-arg-bins`): each board crate brings its own `memory.x`.
//!
//! `memory.x` cuts flash to the product's 32 KiB budget, so the linker refuses an image
//! that does not fit. The `bench` feature builds a measurement tool, not the product (it
//! links the math kernels under test, libm's `sinf` among them, ~36 KiB): for it alone the
//! copy gets 64 KiB of flash. The RAM split (stack and statics) is the same for both.
//!
//! It also writes the `device.x` that cortex-m-rt's `device` feature links: the binary
//! brings its own interrupt table (`__INTERRUPTS` in `src/main.rs`).
use std::path::PathBuf;

/// The linker script cortex-m-rt's `device` feature includes: nothing to alias, because
/// `src/main.rs` builds the interrupt table from `DefaultHandler` directly.
const DEVICE_X: &str = "/* mps2-an386: every interrupt goes to DefaultHandler (src/main.rs) */\n";

fn main() {
    let manifest = PathBuf::from(std::env::var("CARGO_MANIFEST_DIR").expect("set by cargo"));
    let source = manifest.join("memory.x");
    let mut memory = std::fs::read_to_string(&source).expect("boards/mps2-an386/memory.x");
    if std::env::var_os("CARGO_FEATURE_BENCH").is_some() {
        let product = "FLASH : ORIGIN = 0x00000000, LENGTH = 32K";
        assert!(
            memory.contains(product),
            "memory.x: no `{product}` line to widen for bench"
        );
        memory = memory.replace(product, "FLASH : ORIGIN = 0x00000000, LENGTH = 64K");
    }
    let out = PathBuf::from(std::env::var("OUT_DIR").expect("set by cargo"));
    std::fs::write(out.join("memory.x"), memory).expect("write memory.x to OUT_DIR");
    // cortex-m-rt's `device` feature includes a `device.x` naming each interrupt handler;
    // the binary's `__INTERRUPTS` points every entry at `DefaultHandler` itself.
    std::fs::write(out.join("device.x"), DEVICE_X).expect("write device.x to OUT_DIR");
    println!("cargo:rustc-link-arg-bins=-L{}", out.display());
    println!("cargo:rerun-if-changed={}", source.display());
    println!("cargo:rerun-if-changed=build.rs");
}
