#!/usr/bin/env bash
# HIL lock-step on an idle and on a busy host (issue 26): the line juggler's HIL smoke
# (`dexter run scenes/line-juggler.toml --hil --duration 40 --json`, 20 000 control steps of
# the release firmware in QEMU) under each of the host's wait policies (host-sim/src/hil/
# link.rs, WaitPolicy: block, spin, adaptive, picked by DEXTER_HIL_WAIT), each run once
# without and once with a CPU-bound process pinned to CPU 0 beside it, interleaved, RUNS
# times. Prints the median steps per wall second of each, and the busy/idle ratio.
# Usage: scripts/hil-load.sh [RUNS]   (default 5; needs qemu-system-arm and taskset)
set -euo pipefail
cd "$(dirname "$0")/.."
runs=${1:-5}
command -v taskset >/dev/null || { echo "needs taskset (util-linux)" >&2; exit 1; }
cargo build --release -q -p dexter-sim
cargo build --release -q -p dexter-mps2-an386 --target thumbv7em-none-eabihf
rate() {  # one HIL smoke under policy $1: its steps per wall second
  DEXTER_HIL_WAIT=$1 target/release/dexter run scenes/line-juggler.toml --hil --duration 40 --json \
    | python3 -c 'import json,sys; d=json.load(sys.stdin); assert d["sil_mismatches"]==0, "SIL mismatch"; print(round(d["steps_per_wall_second"]))'
}
hog=
stop_hog() { if [ -n "$hog" ]; then kill "$hog" 2>/dev/null || true; wait "$hog" 2>/dev/null || true; hog=; fi; }
trap stop_hog EXIT
median() { python3 -c 'import statistics,sys; print(round(statistics.median(map(float,sys.argv[1:]))))' "$@"; }
echo "load average before: $(cut -d' ' -f1-3 /proc/loadavg), $(nproc) CPUs"
declare -A idle busy
for i in $(seq "$runs"); do
  for p in block spin adaptive; do
    idle[$p]="${idle[$p]:-} $(rate "$p")"
    taskset -c 0 sh -c 'while :; do :; done' & hog=$!
    busy[$p]="${busy[$p]:-} $(rate "$p")"
    stop_hog
  done
done
echo "load average after: $(cut -d' ' -f1-3 /proc/loadavg)"
echo "| wait policy | idle, steps/s (runs) | CPU 0 busy, steps/s (runs) | median busy / idle |"
echo "| --- | --- | --- | --- |"
for p in block spin adaptive; do
  # shellcheck disable=SC2086
  a=$(median ${idle[$p]}); b=$(median ${busy[$p]})
  echo "| $p | $a (${idle[$p]# }) | $b (${busy[$p]# }) | $(python3 -c "print(f'{$b/$a:.2f}')") |"
done
