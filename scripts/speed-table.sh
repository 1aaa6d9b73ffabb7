#!/usr/bin/env bash
# The tables of BENCHMARKS.md, "Speed": dexter's CLI against the Python event-driven
# reference (scripts/reference_bounce.py) in one run, peak memory of a streaming run from
# 1e5 to 1e8 impacts, the realistic line juggler in SIL at 1 kHz, and a 1000-point sweep
# serial vs on every core. Builds the release `dexter` (as users run it), then runs
# scripts/speed_table.py, which prints markdown tables.
# Usage: scripts/speed-table.sh [ratio|rss|sil|sweep ...]   (default: all; needs /usr/bin/time)
# SPEED_REPEATS=N sets the repetitions per figure (default 3, the median is shown).
set -euo pipefail
cd "$(dirname "$0")/.."
[ -x /usr/bin/time ] || { echo "needs GNU time at /usr/bin/time (apt-get install time)" >&2; exit 1; }
cargo build --release -q -p dexter-sim
exec python3 scripts/speed_table.py target/release/dexter "$@"
