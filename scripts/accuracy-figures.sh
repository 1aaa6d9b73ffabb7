#!/usr/bin/env bash
# What accuracy costs, at a glance (BENCHMARKS.md): measures every knob's settings, error
# and cost, into docs/figures/data/<knob>.csv and draws one figure per knob,
# docs/figures/<knob>.svg (scripts/accuracy_figures.py says how each is measured).
# Usage: scripts/accuracy-figures.sh [KNOB ...]   (default: all six; needs valgrind)
#   knobs: math-backend precision integrator control-rate tilt-newton-cap hopper-rate
# Builds the release CLI, the two examples and the firmware's bench image first
# (CARGO_TARGET_DIR is honoured; needs qemu-system-arm and the thumbv7em target). Fails
# (exit 1, naming the command) when a measurement fails or its output cannot be read.
set -euo pipefail
cd "$(dirname "$0")/.."
command -v valgrind >/dev/null || { echo "accuracy-figures: needs valgrind (apt-get install valgrind)" >&2; exit 1; }
command -v python3 >/dev/null || { echo "accuracy-figures: needs python3" >&2; exit 1; }
command -v qemu-system-arm >/dev/null || { echo "accuracy-figures: needs qemu-system-arm (scripts/test.sh installs it)" >&2; exit 1; }
rustup target list --installed 2>/dev/null | grep -x thumbv7em-none-eabihf >/dev/null \
  || { echo "accuracy-figures: needs the thumbv7em-none-eabihf target (rustup target add thumbv7em-none-eabihf)" >&2; exit 1; }
target=${CARGO_TARGET_DIR:-target}
cargo build --release -q -p dexter-sim --bin dexter --example accuracy_probe --example tradeoff_figure
# The bench firmware image (per-call costs of the math kernels on the Cortex-M4F), in a
# target directory of its own so the default image the HIL tests run is left alone.
CARGO_TARGET_DIR="$target/accuracy-figures-fw" \
  cargo build --release -q -p dexter-mps2-an386 --target thumbv7em-none-eabihf --features bench
python3 scripts/accuracy_figures.py --target-dir "$target" "$@"
