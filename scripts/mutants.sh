#!/usr/bin/env bash
# Mutation testing of the control core (`dexter-core`, shared/) with cargo-mutants: every
# mutant (a flipped operator, a dropped term, a function returning a constant) must make a
# test of the core fail. A mutant that survives is a behaviour no test pins down.
#
#   cargo install cargo-mutants --locked      # once (crates.io)
#   scripts/mutants.sh                        # every file of shared/src (~1100 mutants: 1.5 h on 2 busy cores)
#   scripts/mutants.sh shared/src/estimate.rs shared/src/mirror.rs   # some files
#   MUTANTS_JOBS=1 scripts/mutants.sh ...     # on a busy machine
#
# Results go to target/mutants/mutants.out/ (caught.txt, missed.txt, timeout.txt,
# unviable.txt, outcomes.json); the script prints the survivors (missed.txt) at the end and
# exits non-zero if there are any, like cargo-mutants itself.
#
# How it runs, and why:
# - cargo-mutants' normal copy mode (not --in-place), so the work tree is never touched;
#   each job builds in its own copy of the workspace (the first build of a copy compiles the
#   dependencies: a few minutes).
# - only dexter-core's own tests run for a mutant of dexter-core (cargo-mutants' default):
#   the unit tests, shared/tests/*.rs (closed loop, properties) and the doc tests. The
#   simulator's and HIL tests would also catch some, but they take minutes per mutant.
# - `-- --lib --tests`: the unit and integration tests, not the doc tests (dexter-core has
#   none; building rustdoc for every mutant would cost seconds each for nothing).
# - --timeout 60: a mutant that makes a loop endless (a step cap turned off) is stopped and
#   counted as "timeout" (caught), not left running.
# - exclusions (--exclude-re), each for a reason:
#   * `math::fpu::sqrt_f32`, the hard-float ARM square root: its body is compiled only for
#     thumbv7em-none-eabihf, so on the host its mutants are never built and always
#     "survive"; it is checked on the target by the HIL tests, which compare the firmware's
#     commands with the host core's bit for bit.
#   * the `fast-math` backend: compiled only with that feature; a second pass below runs
#     cargo-mutants on it with `--features fast-math`.
set -euo pipefail
cd "$(dirname "$0")/.."
if ! command -v cargo-mutants >/dev/null; then
    echo "cargo-mutants is not installed: cargo install cargo-mutants --locked" >&2
    exit 2
fi
jobs="${MUTANTS_JOBS:-2}"
out="${MUTANTS_OUT:-target/mutants}"
files=("$@")
if [ ${#files[@]} -eq 0 ]; then
    files=(shared/src/*.rs)
fi
file_args=()
for f in "${files[@]}"; do
    file_args+=(--file "$f")
done
# the ARM-only square root (module `math::fpu`) and the fast-math backend (module
# `math::micromath_backend`), see above
excludes=(--exclude-re 'fpu::|micromath_backend::')
status=0
cargo mutants --package dexter-core --jobs "$jobs" --timeout 60 --output "$out" \
    "${file_args[@]}" "${excludes[@]}" -- --lib --tests || status=$?
echo "== survivors (missed) =="
cat "$out/mutants.out/missed.txt" 2>/dev/null || true
# second pass: the fast-math backend, with its feature on
if printf '%s\n' "${files[@]}" | grep -q 'math\.rs$'; then
    cargo mutants --package dexter-core --features fast-math --jobs "$jobs" --timeout 60 \
        --output "$out/fast-math" --file shared/src/math.rs --re 'micromath_backend::' \
        -- --lib --tests || status=$?
    echo "== survivors (missed), fast-math backend =="
    cat "$out/fast-math/mutants.out/missed.txt" 2>/dev/null || true
fi
exit "$status"
