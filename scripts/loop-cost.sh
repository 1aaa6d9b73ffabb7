#!/usr/bin/env bash
# Instructions per unit of simulation through the CLI (valgrind/callgrind: exact and
# repeatable, unlike wall time on a shared machine): per impact of the passive bounce
# (e = 1) and of the ideal mirror juggler, and per control step of the realistic line
# juggler in SIL at 1 kHz (controller and sensor at 1 kHz). Each runs twice with different
# lengths; the difference is the marginal cost, so start-up and parsing cancel out. The
# passive bounce is set beside the floor under it, host-sim/examples/bounce_floor.rs (the
# bare closed-form loop), counted the same way in the same run.
# Usage: scripts/loop-cost.sh [--check] [DEXTER_BINARY]
#   default: builds and uses the release CLI; pass another build, e.g. of an older commit,
#   to compare. --check: exit 1 if a figure is over its ceiling (scripts/test.sh runs this).
set -euo pipefail
cd "$(dirname "$0")/.."
command -v valgrind >/dev/null || { echo "needs valgrind (apt-get install valgrind)" >&2; exit 1; }
check=0
if [ "${1:-}" = --check ]; then check=1; shift; fi
# The floor uses std alone: rustc builds it in a second, where `cargo build --example` would
# link it with fat LTO against every dependency of dexter-sim (about 90 s of a fresh
# scripts/test.sh on 2 cores, BENCHMARKS.md "Building").
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
floor_bin=$work/bounce_floor
rustc --edition 2021 -C opt-level=3 -C codegen-units=1 -o "$floor_bin" host-sim/examples/bounce_floor.rs
if [ $# -ge 1 ]; then bin=$1; else cargo build --release -q -p dexter-sim; bin=target/release/dexter; fi

# Ceilings, instructions (issue 26): the passive bounce's and the SIL step's goals; the
# mirror juggler at its figure plus a small margin, so a change that costs more fails until
# it is justified here. SIL: 396 since the quiet periods in closed form and the stepped
# sensor (573 before; BENCHMARKS.md, "Realistic line juggler, SIL at 1 kHz", says where
# the 396 go).
MAX_PASSIVE=100
MAX_MIRROR=200
MAX_SIL=400

ir() { valgrind --tool=callgrind --callgrind-out-file=/dev/null "$@" 2>&1 >/dev/null \
  | sed -n 's/.*Collected : \([0-9]*\).*/\1/p'; }
cli() { ir "$bin" run "$@" --json; }
marginal() {  # runner, n1, n2, args (with @N@ for the length)
  local run=$1 n1=$2 n2=$3; shift 3
  local a b
  a=$($run "${@//@N@/$n1}")
  b=$($run "${@//@N@/$n2}")
  [ -n "$a" ] && [ -n "$b" ] || { echo "could not read callgrind's count for: $*" >&2; exit 1; }
  echo $(( (b - a) / (n2 - n1) ))
}
passive=$(marginal cli 100000 200000 scenes/passive-bounce.toml --set physics.restitution=1.0 --impacts @N@)
floor=$(marginal ir 100000 200000 "$floor_bin" @N@)
mirror=$(marginal cli 100000 200000 scenes/line-juggler-ideal.toml --impacts @N@)
sil=(scenes/line-juggler.toml --set control.rate_hz=1000.0 --set sensor.rate_hz=1000.0 --set stop.impacts=100000000)
sil=$(marginal cli 20000 40000 "${sil[@]}" --duration @N@e-3)
ratio=$(python3 -c "print(f'{$passive / $floor:.1f}')")

echo "| loop | marginal instructions | ceiling |"
echo "| --- | --- | --- |"
echo "| passive bounce, e = 1 | $passive per impact ($ratio x the floor) | $MAX_PASSIVE |"
echo "| the floor: bare closed-form bounce (examples/bounce_floor.rs) | $floor per impact | |"
echo "| ideal mirror juggler | $mirror per impact | $MAX_MIRROR |"
echo "| realistic line juggler, SIL at 1 kHz | $sil per control step | $MAX_SIL |"

if [ "$check" = 1 ]; then
  over=0
  for f in "passive $passive $MAX_PASSIVE" "mirror $mirror $MAX_MIRROR" "sil $sil $MAX_SIL"; do
    set -- $f
    if [ "$2" -gt "$3" ]; then echo "error: $1 costs $2 instructions, over its ceiling of $3" >&2; over=1; fi
  done
  exit "$over"
fi
