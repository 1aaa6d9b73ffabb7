#!/usr/bin/env bash
# The speed-up of a sharded sweep on a one-node SLURM, measured in one run (BENCHMARKS.md,
# "Sweeps on SLURM"): a 200-point SIL sweep of the line juggler as one serial process
# (RAYON_NUM_THREADS=1), as one process on every core (rayon), and as a 4-task job array of
# deploy/slurm/sweep.sbatch plus its dependent merge job, timed from the first sbatch to the
# merged CSV. The cluster is host-sim/tests/slurm.rs's (munged, slurmctld, slurmd in a
# temporary directory, stopped by PID); the three CSVs are checked equal byte for byte.
# Needs slurm-wlm and munge (scripts/test.sh installs them). Exits 1 if the array takes more
# than 0.6 of the serial time.
# Usage: scripts/slurm-bench.sh [SWEEP-ARGS]   (default: the sweep in host-sim/tests/slurm.rs)
set -euo pipefail
cd "$(dirname "$0")/.."
target=${CARGO_TARGET_DIR:-target}
cargo build --release -q -p dexter-sim --bin dexter
[ $# -gt 0 ] && export DEXTER_BENCH_SWEEP="$*"
DEXTER_BIN="$target/release/dexter" cargo test -q -p dexter-sim --test slurm -- \
  --ignored --nocapture --exact bench_a_job_array_against_one_serial_process
