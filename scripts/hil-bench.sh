#!/usr/bin/env bash
# Firmware figures for BENCHMARKS.md ("## Firmware"): builds three firmware variants
# (libm, fast-math, bench), copies them to target/hil-bench/, runs the lock-step juggle in
# QEMU over each link, the link alone (the Echo controller), the per-call math kernels and
# the protocol's cost per frame, and the lock-step speed (median of 3 runs, with the CPU
# time per step of QEMU and of the host), then rebuilds the default firmware (the ELF path
# the HIL tests use). The host side is built in release, as the CLI is.
set -euo pipefail
cd "$(dirname "$0")/.."
out=target/hil-bench
mkdir -p "$out"
elf=target/thumbv7em-none-eabihf/release/dexter-firmware
build() { cargo build -q -p dexter-firmware --release --target thumbv7em-none-eabihf "$@"; }
build --features fast-math && cp "$elf" "$out/fast-math.elf"
build --features bench && cp "$elf" "$out/bench.elf"
build && cp "$elf" "$out/libm.elf"
echo "load average before: $(cat /proc/loadavg)"
DEXTER_BENCH_DIR="$PWD/$out" cargo test -q --release -p dexter-tests --test hil -- \
  --ignored --nocapture --test-threads 1 bench_figures lockstep_speed
echo "load average after: $(cat /proc/loadavg)"
