//! Puts this board's `memory.x` on the linker search path of its binary (cortex-m-rt's
//! `link.x` includes it), through a copy in `OUT_DIR` (not the workspace root, where the
//! linker runs and would find another `memory.x` first). The PAC's `device.x` (interrupt
//! vectors) comes from `stm32f4`'s own build script.
//!
//! It also copies the scene's `Configure` frame that the stand-alone loop runs
//! (`DEXTER_BOARD_CONFIGURE`, a file `dexter board SCENE --write FILE` writes; by default
//! `scene.configure`, the line juggler's) to `OUT_DIR/scene.configure`, which `main.rs`
//! includes: the board decodes it at reset with the same decoder as a host's `Configure`.
use std::path::PathBuf;

fn main() {
    let manifest = PathBuf::from(std::env::var("CARGO_MANIFEST_DIR").expect("set by cargo"));
    let source = manifest.join("memory.x");
    let out = PathBuf::from(std::env::var("OUT_DIR").expect("set by cargo"));
    std::fs::copy(&source, out.join("memory.x")).expect("copy memory.x to OUT_DIR");
    println!("cargo:rustc-link-arg-bins=-L{}", out.display());
    println!("cargo:rerun-if-changed={}", source.display());
    println!("cargo:rerun-if-changed=build.rs");

    println!("cargo:rerun-if-env-changed=DEXTER_BOARD_CONFIGURE");
    let scene = std::env::var_os("DEXTER_BOARD_CONFIGURE")
        .map(PathBuf::from)
        .unwrap_or_else(|| manifest.join("scene.configure"));
    if let Err(e) = std::fs::copy(&scene, out.join("scene.configure")) {
        panic!(
            "DEXTER_BOARD_CONFIGURE: cannot read the scene's Configure frame {}: {e} \
             (write one with `dexter board SCENE --write FILE`)",
            scene.display()
        );
    }
    println!("cargo:rerun-if-changed={}", scene.display());
}
