#!/usr/bin/env bash
# Firmware figures for BENCHMARKS.md ("## Firmware"): builds three firmware variants
# (libm, fast-math, bench), copies them to target/hil-bench/, runs the lock-step juggle in
# QEMU over each link and the per-call math kernel benchmark, then rebuilds the default
# firmware (the ELF path the HIL tests use).
set -euo pipefail
cd "$(dirname "$0")/.."
out=target/hil-bench
mkdir -p "$out"
elf=target/thumbv7em-none-eabihf/release/dexter-firmware
build() { cargo build -q -p dexter-firmware --release --target thumbv7em-none-eabihf "$@"; }
build --features fast-math && cp "$elf" "$out/fast-math.elf"
build --features bench && cp "$elf" "$out/bench.elf"
build && cp "$elf" "$out/libm.elf"
DEXTER_BENCH_DIR="$PWD/$out" cargo test -q -p dexter-tests --test hil -- --ignored --nocapture --test-threads 1 bench_figures
