#!/usr/bin/env bash
# Instructions per unit of simulation through the CLI (valgrind/callgrind: exact and
# repeatable, unlike wall time on a shared machine): per impact of the passive bounce
# (e = 1) and of the ideal mirror juggler, and per control step of the realistic line
# juggler in SIL at 1 kHz (controller and sensor at 1 kHz). Each runs twice with different
# lengths; the difference is the marginal cost, so start-up and parsing cancel out.
# Usage: scripts/loop-cost.sh [DEXTER_BINARY]   (default: builds and uses the release CLI;
# pass another build, e.g. of an older commit, to compare)
set -euo pipefail
cd "$(dirname "$0")/.."
command -v valgrind >/dev/null || { echo "needs valgrind (apt-get install valgrind)" >&2; exit 1; }
if [ $# -ge 1 ]; then bin=$1; else cargo build --release -q -p dexter-sim; bin=target/release/dexter; fi

ir() { valgrind --tool=callgrind --callgrind-out-file=/dev/null "$bin" run "$@" --json 2>&1 >/dev/null \
  | sed -n 's/.*Collected : \([0-9]*\).*/\1/p'; }
marginal() {  # per-unit label, n1, n2, args for n1 (with N), args for n2
  local label=$1 n1=$2 n2=$3; shift 3
  local a b
  a=$(ir "${@//@N@/$n1}")
  b=$(ir "${@//@N@/$n2}")
  echo "$(( (b - a) / (n2 - n1) )) $label"
}
echo "| loop | marginal instructions |"
echo "| --- | --- |"
echo "| passive bounce, e = 1 | $(marginal "per impact" 100000 200000 scenes/passive-bounce.toml --set physics.restitution=1.0 --impacts @N@) |"
echo "| ideal mirror juggler | $(marginal "per impact" 100000 200000 scenes/line-juggler-ideal.toml --impacts @N@) |"
sil=(scenes/line-juggler.toml --set control.rate_hz=1000.0 --set sensor.rate_hz=1000.0 --set stop.impacts=100000000)
echo "| realistic line juggler, SIL at 1 kHz | $(marginal "per control step" 20000 40000 "${sil[@]}" --duration @N@e-3) |"
