//! Puts this board's `memory.x` on the linker search path of its binary (cortex-m-rt's
//! `link.x` includes it), through a copy in `OUT_DIR` (not the workspace root, where the
//! linker runs and would find another `memory.x` first). The PAC's `device.x` (interrupt
//! vectors) comes from `stm32f4`'s own build script.
use std::path::PathBuf;

fn main() {
    let manifest = PathBuf::from(std::env::var("CARGO_MANIFEST_DIR").expect("set by cargo"));
    let source = manifest.join("memory.x");
    let out = PathBuf::from(std::env::var("OUT_DIR").expect("set by cargo"));
    std::fs::copy(&source, out.join("memory.x")).expect("copy memory.x to OUT_DIR");
    println!("cargo:rustc-link-arg-bins=-L{}", out.display());
    println!("cargo:rerun-if-changed={}", source.display());
    println!("cargo:rerun-if-changed=build.rs");
}
