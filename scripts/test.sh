#!/usr/bin/env bash
# All of dexter's tests, from a fresh machine: installs what it needs (the thumbv7em target
# via rustup, qemu-system-arm, slurm-wlm and munge from Debian) or stops saying exactly what to install.
# Usage: scripts/test.sh            (CI runs exactly this through .ci/run)
set -euo pipefail
cd "$(dirname "$0")/.."

TARGET=thumbv7em-none-eabihf
# Whole-crate builds: from an empty target directory, incremental compilation made the dev
# build of the dexter-sim library 109 s against 68-77 s without it (BENCHMARKS.md,
# "Building"). Set CARGO_INCREMENTAL=1 to share the artifacts of an incremental `cargo test`
# (switching rebuilds the workspace's own crates once).
export CARGO_INCREMENTAL="${CARGO_INCREMENTAL:-0}"
# Each step prints the seconds since the start, so a slow step shows in the log (BENCHMARKS.md,
# "Building", has a fresh clone's breakdown).
step() { printf '\n==> [%d s] %s\n' "$SECONDS" "$*"; }
die() { printf '\nerror: %s\n' "$*" >&2; exit 1; }

step "checking the toolchain"
command -v cargo >/dev/null || die "cargo not found: install Rust with rustup (https://rustup.rs)"
if ! rustup target list --installed 2>/dev/null | grep -qx "$TARGET"; then
  command -v rustup >/dev/null || die "the $TARGET target is missing and rustup is not available: install rustup, then run 'rustup target add $TARGET'"
  step "installing the $TARGET target (rustup target add $TARGET)"
  rustup target add "$TARGET" || die "could not install the target: run 'rustup target add $TARGET'"
fi
for comp in rustfmt clippy; do
  if ! cargo "${comp/rustfmt/fmt}" --version >/dev/null 2>&1; then
    rustup component add "$comp" || die "missing $comp: run 'rustup component add $comp'"
  fi
done
command -v python3 >/dev/null || die "python3 not found (the static worst-case tool scripts/wcet.py needs it): install Python 3"
if ! command -v llvm-objdump >/dev/null \
   && ! find "$(rustc --print sysroot)/lib/rustlib" -name llvm-objdump 2>/dev/null | grep -q .; then
  step "installing llvm-objdump for scripts/wcet.py (rustup component add llvm-tools, else Debian's llvm)"
  rustup component add llvm-tools 2>/dev/null \
    || { [ "$(id -u)" = 0 ] && command -v apt-get >/dev/null \
         && apt-get update -qq && DEBIAN_FRONTEND=noninteractive apt-get install -y -qq llvm >/dev/null; } \
    || { command -v sudo >/dev/null && command -v apt-get >/dev/null \
         && sudo apt-get update -qq && sudo DEBIAN_FRONTEND=noninteractive apt-get install -y -qq llvm >/dev/null; } \
    || die "llvm-objdump not found: run 'rustup component add llvm-tools' or 'sudo apt-get install llvm'"
fi

if ! command -v qemu-system-arm >/dev/null; then
  if command -v apt-get >/dev/null && [ "$(id -u)" = 0 ]; then
    step "installing qemu-system-arm from Debian (apt-get install qemu-system-arm)"
    (apt-get update -qq && DEBIAN_FRONTEND=noninteractive apt-get install -y -qq qemu-system-arm >/dev/null) \
      || die "could not install QEMU: run 'sudo apt-get install qemu-system-arm'"
  elif command -v apt-get >/dev/null && command -v sudo >/dev/null; then
    step "installing qemu-system-arm from Debian (sudo apt-get install qemu-system-arm)"
    (sudo apt-get update -qq && sudo DEBIAN_FRONTEND=noninteractive apt-get install -y -qq qemu-system-arm >/dev/null) \
      || die "could not install QEMU: run 'sudo apt-get install qemu-system-arm'"
  else
    die "qemu-system-arm (QEMU >= 7.2 with the mps2-an386 machine) is required for the hardware-in-the-loop tests: install it (Debian/Ubuntu: 'sudo apt-get install qemu-system-arm'; macOS: 'brew install qemu')"
  fi
fi
qemu-system-arm -machine help | grep -q mps2-an386 || die "this qemu-system-arm lacks the mps2-an386 machine: install QEMU >= 7.2"
qemu-system-arm -machine help | grep -q netduinoplus2 || die "this qemu-system-arm lacks the netduinoplus2 machine (the emulated NUCLEO-F446RE board): install QEMU >= 7.2"

# valgrind (scripts/loop-cost.sh counts the CLI's instructions per impact and per step)
if ! command -v valgrind >/dev/null; then
  if command -v apt-get >/dev/null && [ "$(id -u)" = 0 ]; then
    step "installing valgrind from Debian (apt-get install valgrind)"
    (apt-get update -qq && DEBIAN_FRONTEND=noninteractive apt-get install -y -qq valgrind >/dev/null) \
      || die "could not install valgrind: run 'sudo apt-get install valgrind'"
  elif command -v apt-get >/dev/null && command -v sudo >/dev/null; then
    step "installing valgrind from Debian (sudo apt-get install valgrind)"
    (sudo apt-get update -qq && sudo DEBIAN_FRONTEND=noninteractive apt-get install -y -qq valgrind >/dev/null) \
      || die "could not install valgrind: run 'sudo apt-get install valgrind'"
  else
    die "valgrind is required for the instruction ceilings of scripts/loop-cost.sh: install it (Debian/Ubuntu: 'sudo apt-get install valgrind'; macOS: not available, run on Linux)"
  fi
fi

# SLURM (host-sim/tests/slurm.rs starts a one-node cluster in a temporary directory)
have() { command -v "$1" >/dev/null || [ -x "/usr/sbin/$1" ]; }
if ! { have munged && have mungekey && have slurmctld && have slurmd && have sbatch; }; then
  if command -v apt-get >/dev/null && [ "$(id -u)" = 0 ]; then
    step "installing slurm-wlm and munge from Debian (apt-get install slurm-wlm munge)"
    (apt-get update -qq && DEBIAN_FRONTEND=noninteractive apt-get install -y -qq slurm-wlm munge >/dev/null) \
      || die "could not install SLURM: run 'sudo apt-get install slurm-wlm munge'"
  elif command -v apt-get >/dev/null && command -v sudo >/dev/null; then
    step "installing slurm-wlm and munge from Debian (sudo apt-get install slurm-wlm munge)"
    (sudo apt-get update -qq && sudo DEBIAN_FRONTEND=noninteractive apt-get install -y -qq slurm-wlm munge >/dev/null) \
      || die "could not install SLURM: run 'sudo apt-get install slurm-wlm munge'"
  else
    die "slurm-wlm and munge (munged, mungekey, slurmctld, slurmd, sbatch) are required for the SLURM test: install them (Debian/Ubuntu: 'sudo apt-get install slurm-wlm munge')"
  fi
fi

step "formatting (cargo fmt --check)"
cargo fmt --all -- --check

step "module layers: no import cycles, no layer imported upward (scripts/layers.py)"
python3 scripts/layers_test.py
python3 scripts/layers.py

# The release CLI (for the instruction ceilings below) builds in the background while the
# lints and the test build run: its fat-LTO link runs on one core for about a minute, and the
# two cargo runs do not wait for each other (different profiles, so different build
# directories). The thumbv7em release builds would wait for it (their build scripts build in
# the host's release directory), so they run after it. BENCHMARKS.md, "Building".
step "the release CLI builds in the background (cargo build --release -p dexter-sim)"
release_log=$(mktemp)
setsid cargo build --release -q -p dexter-sim > "$release_log" 2>&1 &
release_pid=$!
trap 'kill -- -"$release_pid" 2>/dev/null || true; rm -f "$release_log"' EXIT
trap 'exit 130' INT TERM HUP

step "lints (cargo clippy -D warnings), host crates and firmware"
cargo clippy --all-targets -- -D warnings
cargo clippy -p dexter-firmware -p dexter-mps2-an386 --target "$TARGET" -- -D warnings
cargo clippy -p dexter-firmware -p dexter-mps2-an386 --target "$TARGET" --no-default-features --features spatial -- -D warnings
cargo clippy -p dexter-nucleo-f446re --target "$TARGET" -- -D warnings
cargo clippy -p dexter-nucleo-f446re --target "$TARGET" --features qemu-hsi -- -D warnings
cargo clippy -p dexter-nucleo-f446re --target "$TARGET" --features qemu-hsi,calibrate -- -D warnings

step "the core builds for $TARGET with each math backend"
cargo build -p dexter-core --target "$TARGET"
cargo build -p dexter-core --target "$TARGET" --features fast-math

step "the unit, property, paper-reproduction, driver and HIL tests build (cargo test --no-run)"
cargo test --all-targets --no-run -q

step "waiting for the release CLI"
wait "$release_pid" || { cat "$release_log"; die "the release CLI did not build: cargo build --release -p dexter-sim"; }
cat "$release_log"
trap 'rm -f "$release_log"' EXIT

step "the firmware images build for $TARGET (release): the arm and spatial images, then the default one"
# Each image is a cargo feature selection of hosted kinds (firmware/README.md, "Images").
cargo build -p dexter-mps2-an386 --release --target "$TARGET" --no-default-features --features arm
FW="target/$TARGET/release/dexter-mps2-an386"
ARM_FW="target/$TARGET/release/dexter-mps2-an386-arm.elf"
cp "$FW" "$ARM_FW"
cargo build -p dexter-mps2-an386 --release --target "$TARGET" --no-default-features --features spatial
SPATIAL_FW="target/$TARGET/release/dexter-mps2-an386-spatial.elf"
cp "$FW" "$SPATIAL_FW"
cargo build -p dexter-mps2-an386 --release --target "$TARGET"

step "static worst-case control steps, from each image as flashed (scripts/wcet.py)"
python3 scripts/wcet_test.py
# 296 = the line juggler's 300-instruction goal less the HIL measurement window (3 or 4
# instructions around the call, as the compiler schedules it: 4 since 2026-11-29)
python3 scripts/wcet.py "$FW" '<dexter_core::control::Controller as dexter_core::fixed_rate::FixedRate>::step' --max-instructions 296
python3 scripts/wcet.py "$ARM_FW" '<dexter_core::control::Controller as dexter_core::fixed_rate::FixedRate>::step' --max-instructions 296
# 416 = ArmController's 424-instruction budget less the 8 its HIL measurement window adds
# (shared/src/arm_control.rs, STEP_INSTRUCTION_BUDGET)
python3 scripts/wcet.py "$ARM_FW" '<dexter_core::arm_control::ArmController as dexter_core::fixed_rate::FixedRate>::step' --max-instructions 416
# 1490 = SpatialController's 1500-instruction budget less its HIL measurement window
# (shared/src/spatial_control/mod.rs, STEP_INSTRUCTION_BUDGET)
python3 scripts/wcet.py "$SPATIAL_FW" '<dexter_core::spatial_control::SpatialController as dexter_core::fixed_rate::FixedRate>::step' --max-instructions 1490

step "instructions per impact and per control step through the release CLI, under their ceilings (scripts/loop-cost.sh --check)"
scripts/loop-cost.sh --check

step "guest instructions per HIL control period in QEMU, under their ceiling (scripts/hil-guest-count.sh --check)"
scripts/hil-guest-count.sh --check

step "the NUCLEO-F446RE image builds for $TARGET (release); its sizes are checked by tests/board.rs"
cargo build -p dexter-nucleo-f446re --release --target "$TARGET"

step "unit, property, paper-reproduction, driver (embedded-hal-mock), HIL, board-size and emulated-board HIL (netduinoplus2) tests run (cargo test)"
cargo test --all-targets

step "documentation builds without warnings"
RUSTDOCFLAGS="-D warnings" cargo doc --no-deps -q

echo
echo "all tests passed in $SECONDS s"
