#!/usr/bin/env bash
# Firmware figures for BENCHMARKS.md ("## Firmware"): builds three firmware variants
# (libm, fast-math, bench), copies them to target/hil-bench/, runs the lock-step juggle in
# QEMU over each link, the link alone (the Echo controller), the per-call math kernels and
# the protocol's cost per frame, and the lock-step speed (median of 3 runs, with the CPU
# time per step of QEMU and of the host), then rebuilds the default firmware (the ELF path
# the HIL tests use). The host side is built in release, as the CLI is.
#
# Also the tilt table's and the hopper's figures ("Tilt controller on the MCU", "Hopper
# controller on the MCU"): two more variants host the tilt controller with the math
# backend's sine/cosine (tilt-libm: feature tilt-backend-sincos; tilt-micromath: with
# fast-math too; both measurement builds with 64 KiB of flash); the tilt table runs each
# sine/cosine source and contact-solver cap over 20 camera seeds in HIL (the micromath
# rows against a host core built with fast-math, so that HIL is compared bit for bit with
# the same source), the hopper its rate table; and the static worst cases of the three
# control steps of the shipped image (scripts/wcet.py). Everything after the line juggler's
# figures takes about 20 minutes on two cores.
set -euo pipefail
cd "$(dirname "$0")/.."
out=target/hil-bench
mkdir -p "$out"
elf=target/thumbv7em-none-eabihf/release/dexter-mps2-an386
build() { cargo build -q -p dexter-mps2-an386 --release --target thumbv7em-none-eabihf "$@"; }
build --features fast-math && cp "$elf" "$out/fast-math.elf"
build --features bench && cp "$elf" "$out/bench.elf"
build --features tilt-backend-sincos && cp "$elf" "$out/tilt-libm.elf"
build --features tilt-backend-sincos,fast-math && cp "$elf" "$out/tilt-micromath.elf"
build && cp "$elf" "$out/libm.elf"
echo "load average before: $(cat /proc/loadavg)"
DEXTER_BENCH_DIR="$PWD/$out" cargo test -q --release -p dexter-tests --test hil -- \
  --ignored --nocapture --test-threads 1 bench_figures lockstep_speed
echo "load average after: $(cat /proc/loadavg)"
echo "static worst cases of the shipped image's control steps (scripts/wcet.py):"
for sym in '<dexter_core::control::Controller as dexter_core::fixed_rate::FixedRate>::step' \
  'dexter_core::tilt_control::TiltControllerWith<T>::step' \
  'dexter_core::tilt_control::TiltControllerWith<T>::safe' \
  '<dexter_core::hop_control::HopController as dexter_core::fixed_rate::FixedRate>::step' '<dexter_core::hop_control::HopController as dexter_core::fixed_rate::FixedRate>::safe'; do
  python3 scripts/wcet.py "$out/libm.elf" "$sym"
done
DEXTER_BENCH_DIR="$PWD/$out" DEXTER_TILT_SOURCES=poly,backend cargo test -q --release \
  -p dexter-tests --test hil_tilt -- --ignored --nocapture --test-threads 1 bench_tilt_figures
DEXTER_BENCH_DIR="$PWD/$out" DEXTER_TILT_SOURCES=backend cargo test -q --release \
  -p dexter-tests --features dexter-core/fast-math --test hil_tilt -- \
  --ignored --nocapture --test-threads 1 bench_tilt_figures
DEXTER_BENCH_DIR="$PWD/$out" cargo test -q --release -p dexter-tests --test hil_hop -- \
  --ignored --nocapture --test-threads 1 bench_hop_rate_table
echo "load average at the end: $(cat /proc/loadavg)"
