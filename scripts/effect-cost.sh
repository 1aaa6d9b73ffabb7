#!/usr/bin/env bash
# What each effect costs, in instructions (valgrind/callgrind: exact and repeatable, unlike
# wall time on a shared machine). For every variant it runs `dexter` twice with different
# run lengths and reports the marginal instructions per impact (event-driven scenes) or per
# control step (SIL), so start-up and scene parsing cancel out.
# Usage: scripts/effect-cost.sh [DEXTER_BINARY]   (needs valgrind; prints a markdown table;
#   default: builds and uses the release CLI; pass another build, e.g. of an older commit)
set -euo pipefail
cd "$(dirname "$0")/.."
command -v valgrind >/dev/null || { echo "needs valgrind (apt-get install valgrind)" >&2; exit 1; }
if [ $# -ge 1 ]; then bin=$1; else cargo build --release -q -p dexter-sim; bin=target/release/dexter; fi
tmp=$(mktemp -d); trap 'rm -rf "$tmp"' EXIT

ir() { valgrind --tool=callgrind --callgrind-out-file=/dev/null "$bin" run "$@" --json 2>&1 >/dev/null \
  | sed -n 's/.*Collected : \([0-9]*\).*/\1/p'; }

# The realistic scene with every effect removed; each variant adds one back.
python3 - "$tmp" <<'PY'
import sys, re
src = open("scenes/line-juggler.toml").read()
def drop(text, table):
    return re.sub(r"(?ms)^\[" + re.escape(table) + r"\]\n.*?(?=^\[|\Z)", "", text)
off = drop(drop(src, "sensor"), "actuator") + '\n[actuator]\nkind = "ideal"\ninitial_height_m = 0.0\n'
open(sys.argv[1] + "/off.toml", "w").write(off)
PY

echo "| loop | variant | marginal instructions |"
echo "| --- | --- | --- |"
per_impact() {  # label, extra args...
  local label=$1; shift
  local a b
  a=$(ir scenes/passive-bounce.toml --set physics.restitution=1.0 "$@" --impacts 100000)
  b=$(ir scenes/passive-bounce.toml --set physics.restitution=1.0 "$@" --impacts 200000)
  echo "| event-driven, passive bounce e = 1 | $label | $(( (b - a) / 100000 )) per impact |"
}
per_step() {  # label, scene, extra args...
  local label=$1 scene=$2; shift 2
  local a b
  a=$(ir "$scene" "$@" --duration 20)
  b=$(ir "$scene" "$@" --duration 40)
  echo "| SIL line juggler, 500 Hz | $label | $(( (b - a) / 10000 )) per control step |"
}
per_impact "jitter off (absent)"
per_impact "jitter on, sigma 0" --set jitter.sigma_s=0.0
per_impact "jitter on, sigma 10 ms" --set jitter.sigma_s=0.01
per_step "every effect off" "$tmp/off.toml"
per_step "sensor on, noise/latency/quantization 0" "$tmp/off.toml" --set sensor.noise_sigma_m=0.0 --set sensor.latency_s=0.0 --set sensor.quantization_m=0.0
per_step "sensor on, 0.5 mm noise, 4 ms latency, 0.1 mm quantization" "$tmp/off.toml" --set sensor.noise_sigma_m=0.0005 --set sensor.latency_s=0.004 --set sensor.quantization_m=0.0001
per_step "jitter on, sigma 0" "$tmp/off.toml" --set jitter.sigma_s=0.0
per_step "second-order actuator with limits" "$tmp/off.toml" --set actuator.kind=second_order --set actuator.accel_max_mps2=250.0 --set actuator.velocity_max_mps=4.0 --set actuator.min_height_m=-0.35 --set actuator.max_height_m=0.15
per_step "drag 0 (flight integrated, RK45)" "$tmp/off.toml" --set drag.coefficient_per_m=0.0
per_step "the shipped scene (sensor + actuator)" scenes/line-juggler.toml
