#!/usr/bin/env python3
"""What accuracy costs, one figure per knob: measures each knob's settings (error and cost)
into docs/figures/data/<knob>.csv and draws docs/figures/<knob>.svg from it.

    scripts/accuracy-figures.sh [KNOB ...]     # builds the binaries, then runs this

Run directly only with the binaries built (`--target-dir DIR`, default target/; the bench
firmware image in DIR/accuracy-figures-fw, so the default image stays as it was). Every
figure is measured here, by the probes of host-sim/examples/accuracy_probe.rs and by the
`dexter` CLI; nothing is copied from BENCHMARKS.md. Instruction counts are callgrind's
(exact and repeatable): each is the difference of two run lengths, so start-up cancels
out; on the Cortex-M4F they are QEMU's (icount), from the firmware's bench image. The error
of a sin is computed on the host: the same f32 code runs on both. Any output that does not parse stops the script with the command and what was
missing (exit status 1).

The knobs: math-backend, precision, integrator, control-rate, tilt-newton-cap, hopper-rate.
"""

import csv
import io
import json
import math
import os
import re
import subprocess
import sys
import tempfile
import time

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
HEADER = ["series", "label", "cost", "cost_unit", "error", "error_unit"]


class Failure(Exception):
    """A measurement that failed or whose output could not be read."""


class Tools:
    """The built binaries."""

    def __init__(self, target_dir, scratch):
        self.scratch = scratch
        release = os.path.join(target_dir, "release")
        self.dexter = os.path.join(release, "dexter")
        self.probe = os.path.join(release, "examples", "accuracy_probe")
        self.figure = os.path.join(release, "examples", "tradeoff_figure")
        self.bench_elf = os.path.join(target_dir, "accuracy-figures-fw", "thumbv7em-none-eabihf", "release",
                                      "dexter-mps2-an386")
        for path in (self.dexter, self.probe, self.figure, self.bench_elf):
            if not os.access(path, os.X_OK):
                raise Failure(f"{path} is not built: run scripts/accuracy-figures.sh")


# ---- running and reading ----------------------------------------------------------------------


def run(cmd):
    """Runs cmd from the workspace root; returns (stdout, stderr). A failure raises."""
    p = subprocess.run(cmd, cwd=ROOT, capture_output=True, text=True)
    if p.returncode != 0:
        raise Failure(f"{' '.join(cmd)} exited {p.returncode}:\n{p.stderr.strip()}")
    return p.stdout, p.stderr


def record(text, kind, cmd):
    """The `key=value` fields of the one line of text that starts with `kind `."""
    lines = [l for l in text.splitlines() if l.startswith(kind + " ")]
    if len(lines) != 1:
        raise Failure(f"{' '.join(cmd)}: expected one '{kind}' line, found {len(lines)} in:\n{text}")
    return parse_fields(lines[0], cmd)


def parse_fields(line, cmd):
    """`kind a=1 b=x` as {'a': '1', 'b': 'x'}; a token without '=' raises."""
    fields = {}
    for token in line.split()[1:]:
        key, eq, value = token.partition("=")
        if not eq:
            raise Failure(f"{' '.join(cmd)}: field {token!r} is not key=value in {line!r}")
        fields[key] = value
    return fields


def number(fields, key, cmd):
    """fields[key] as a finite float; a missing or bad field raises."""
    if key not in fields:
        raise Failure(f"{' '.join(cmd)}: no field {key!r} in {fields}")
    try:
        v = float(fields[key])
    except ValueError:
        raise Failure(f"{' '.join(cmd)}: {key}={fields[key]!r} is not a number") from None
    if not math.isfinite(v):
        raise Failure(f"{' '.join(cmd)}: {key}={fields[key]!r} is not finite")
    return v


def json_number(summary, key, cmd):
    """summary[key] as a finite float (a JSON null or a missing key raises)."""
    v = summary.get(key)
    if not isinstance(v, (int, float)) or isinstance(v, bool) or not math.isfinite(v):
        raise Failure(f"{' '.join(cmd)}: {key!r} is {v!r}, not a finite number")
    return float(v)


def dexter_json(tools, args):
    """`dexter run ARGS --json`, its summary as a dict."""
    cmd = [tools.dexter, "run", *args, "--json"]
    out, _ = run(cmd)
    try:
        return json.loads(out), cmd
    except json.JSONDecodeError as e:
        raise Failure(f"{' '.join(cmd)}: the summary is not JSON ({e}):\n{out[:500]}") from None


def instructions(cmd):
    """Instructions callgrind counts for one run of cmd (and that run's stdout)."""
    full = ["valgrind", "--tool=callgrind", "--callgrind-out-file=/dev/null", *cmd]
    out, err = run(full)
    m = re.search(r"Collected : (\d+)", err)
    if not m:
        raise Failure(f"{' '.join(full)}: no 'Collected :' count in callgrind's output:\n{err}")
    return int(m.group(1)), out


def marginal(make_cmd, n1, n2):
    """Instructions per unit: (count at n2 - count at n1) / (n2 - n1), and the n1 run's
    stdout. make_cmd(n) gives the command for n units."""
    a, out = instructions(make_cmd(n1))
    b, _ = instructions(make_cmd(n2))
    if b <= a:
        raise Failure(f"{' '.join(make_cmd(n2))}: {b} instructions, not more than {a} at {n1}")
    return (b - a) / (n2 - n1), out


# ---- the knobs --------------------------------------------------------------------------------

SIN_CALLS = (200_000, 400_000)


def probe_marginal(tools, probe, variant, kind, counts=SIN_CALLS):
    """A probe's marginal instructions per unit less its `none` loop, and its record."""
    cmd = lambda v: lambda n: [tools.probe, probe, v, str(n)]
    per, out = marginal(cmd(variant), *counts)
    loop, _ = marginal(cmd("none"), *counts)
    if per <= loop:
        raise Failure(f"{probe} {variant}: {per:.1f} instructions per unit, no more than the empty loop's {loop:.1f}")
    return per - loop, record(out, kind, cmd(variant)(counts[0]))


SIN_BACKENDS = [
    ("libm", "libm::sinf", "libm::sinf (default)"),
    ("micromath", "micromath sin", "micromath sin (fast-math)"),
    ("poly", "dexter_core::math::sin_poly_f32", "sin_poly_f32 (own polynomial)"),
]
MCU_IDENTITY = "identity (the indirect call itself)"


def mcu_sin_costs(tools):
    """Mean instructions per call of each sin on the Cortex-M4F (the bench image in QEMU,
    boot word `bench`), the indirect call's own cost subtracted: {kernel name: count}."""
    log = os.path.join(tools.scratch, "bench.log")
    cmd = ["qemu-system-arm", "-machine", "mps2-an386", "-nographic", "-monitor", "none",
           "-serial", "null", "-icount", "shift=10", "-semihosting-config", "enable=on,target=native",
           "-kernel", tools.bench_elf, "-append", "bench"]
    with open(log, "wb") as f:
        p = subprocess.run(cmd, cwd=ROOT, stdout=f, stderr=subprocess.PIPE, stdin=subprocess.DEVNULL, timeout=120)
    if p.returncode != 0:
        raise Failure(f"{' '.join(cmd)} exited {p.returncode}:\n{p.stderr.decode(errors='replace')}")
    text, _ = run([tools.probe, "defmt", tools.bench_elf, log])
    means = {}
    for m in re.finditer(r"bench (.+?): instructions per call min \d+ mean (\d+) max \d+;", text):
        means[m.group(1)] = int(m.group(2))
    for name in [MCU_IDENTITY] + [k for _, k, _ in SIN_BACKENDS]:
        if name not in means:
            raise Failure(f"the bench image's log has no per-call count for {name!r}:\n{text}")
    return {k: means[k] - means[MCU_IDENTITY] for k in means}


def math_backend(tools):
    """sin in f32: worst abs error on [-pi, pi] against instructions per call, on the host
    (callgrind) and on the Cortex-M4F (QEMU)."""
    unit = "instructions per call of sin alone"
    error_unit = "worst abs. error of sin over -pi..pi (vs f64)"
    host, mcu = [], []
    mcu_costs = mcu_sin_costs(tools)
    for backend, kernel, label in SIN_BACKENDS:
        cost, rec = probe_marginal(tools, "sin", backend, "sin")
        error = number(rec, "worst_abs_error", ["accuracy_probe", "sin", backend])
        host.append(("x86-64 host (callgrind; empty loop subtracted)", label, cost, unit, error, error_unit))
        if mcu_costs[kernel] <= 0:
            raise Failure(f"{kernel}: {mcu_costs[kernel]} instructions per call on the M4F after the call's own")
        mcu.append(("Cortex-M4F in QEMU (mean of 8 arguments; the call's own subtracted)", label,
                    float(mcu_costs[kernel]), unit, error, error_unit))
    return host + mcu


def precision(tools):
    """f32 vs f64: the eq. 8 return map and the mirror law, relative error against instructions."""
    unit = "instructions per evaluation on the x86-64 host (callgrind; empty loop subtracted)"
    rows = []
    for probe, series in [
        ("return-map", "eq. 8 return map: fixed point after 1000 iterations vs its closed form"),
        ("mirror", "mirror law r r' r'': worst vs f64 over 1024 states"),
    ]:
        for prec in ["f32", "f64"]:
            cost, rec = probe_marginal(tools, probe, prec, probe)
            error = number(rec, "relative_error", ["accuracy_probe", probe, prec])
            label = "f64 (the reference)" if probe == "mirror" and prec == "f64" else prec
            rows.append((series, label, cost, unit, error, "relative error"))
    return rows


INTEGRATOR_LABELS = {"rk4": "RK4 step {} s", "rk45": "RK45 tol {} m"}


def integrator_label(case):
    """`drag0.1_rk45_1e-9` -> ('drag 0.1 1/m', 'RK45 tol 1e-9 m')."""
    if case == "exact":
        return "drag 0 (exact physics)", "exact events (closed form)"
    m = re.fullmatch(r"drag([0-9.]+)_(rk4|rk45)_(.+)", case)
    if not m:
        raise Failure(f"accuracy_probe integrator: unknown case name {case!r}")
    drag, method, value = m.groups()
    series = "drag 0 (exact physics)" if float(drag) == 0 else f"drag {drag} 1/m"
    return series, INTEGRATOR_LABELS[method].format(value)


def integrator(tools):
    """Exact events vs RK4 / RK45: worst landing-speed error against time per 200 impacts."""
    cmd = [tools.probe, "integrator", "0.3"]
    out, _ = run(cmd)
    lines = [l for l in out.splitlines() if l.startswith("integrator ")]
    if len(lines) != 13:
        raise Failure(f"{' '.join(cmd)}: expected 13 'integrator' lines, found {len(lines)}:\n{out}")
    rows = []
    for line in lines:
        f = parse_fields(line, cmd)
        series, label = integrator_label(f.get("case", "?"))
        rows.append((
            series,
            label,
            number(f, "us_per_run", cmd),
            "µs per 200 impacts on the host (median wall time)",
            number(f, "worst_landing_speed_error", cmd),
            "worst landing-speed relative error",
        ))
    return rows


LINE_RATES = [100, 200, 250, 500, 1000, 2000, 4000]
LINE_IMPACTS = 200


def apex_error(tools, sets):
    """RMS apex error over the last half of LINE_IMPACTS impacts, relative to the target,
    and the safe steps of the run."""
    trace = os.path.join(tools.scratch, "trace.csv")
    args = ["scenes/line-juggler.toml", "--impacts", str(LINE_IMPACTS), *sets, "--trace", trace]
    summary, cmd = dexter_json(tools, args)
    if summary.get("end") != "impacts" or summary.get("impacts") != LINE_IMPACTS:
        raise Failure(f"{' '.join(cmd)}: ended {summary.get('end')!r} after {summary.get('impacts')!r} impacts")
    target = json_number(summary, "target_apex_m", cmd)
    with open(trace) as f:
        apexes = [float(r["apex_height_m"]) for r in csv.DictReader(f)]
    if len(apexes) != LINE_IMPACTS:
        raise Failure(f"{trace}: {len(apexes)} rows, expected {LINE_IMPACTS}")
    late = apexes[LINE_IMPACTS // 2:]
    rms = math.sqrt(sum((a - target) ** 2 for a in late) / len(late)) / target
    return rms, int(json_number(summary, "safe_steps", cmd))


def control_rate(tools):
    """The SIL line juggler at several control rates: rms apex error against instructions
    per simulated second."""
    rows = []
    for series, extra in [
        ("shipped sensor (0.5 mm noise; 0.1 mm steps; 4 ms)", []),
        ("noise-free sensor (4 ms latency only)", ["--set", "sensor.noise_sigma_m=0", "--set", "sensor.quantization_m=0"]),
    ]:
        for rate in LINE_RATES:
            sets = ["--set", f"control.rate_hz={rate}", "--set", f"sensor.rate_hz={rate}", *extra]
            error, safe = apex_error(tools, sets)
            make = lambda s: [tools.dexter, "run", "scenes/line-juggler.toml", *sets, "--duration", str(s), "--json"]
            per_s, _ = marginal(make, 10, 20)
            label = f"{rate} Hz" + (f" ({safe} safe steps)" if safe else "")
            rows.append((
                series,
                label,
                per_s,
                "instructions per simulated second (x86-64 host SIL; callgrind)",
                error,
                "rms apex error / target (last 100 of 200 impacts)",
            ))
    return rows


TILT_SEEDS = 20


def tilt_newton_cap(tools):
    """The tilt controller's Newton cap 1-4: impact-time prediction error against the
    control periods a plan takes."""
    rows = []
    for cap in range(1, 5):
        cmd = [tools.probe, "tilt", str(cap), str(TILT_SEEDS)]
        out, _ = run(cmd)
        f = record(out, "tilt", cmd)
        periods = number(f, "cycle_periods", cmd)
        upright = int(number(f, "upright", cmd))
        label = f"cap {cap}" + (" (shipped)" if cap == 2 else "")
        unit = "control periods per plan (TiltParams::cycle_periods at 500 Hz)"
        err = "impact-time prediction error rms (s)"
        rows.append(("perfect sensing and the paper's law (the solver alone)", label, periods, unit,
                     number(f, "solver_rms_s", cmd), err))
        rows.append((f"realistic table ({TILT_SEEDS} camera seeds)", f"{label}: {upright}/{TILT_SEEDS} up", periods,
                     unit, number(f, "realistic_rms_s", cmd), err))
    return rows


HOPPER_SCENES = [
    ("Raibert thrust on the linear model (hopper-raibert-sil)", "scenes/hopper-raibert-sil.toml",
     [250, 500, 1000, 2000, 5000, 10000]),
    ("full model above the doubling (hopper-limp-sil)", "scenes/hopper-limp-sil.toml", [1000, 2000, 5000, 10000]),
]


def hopper_rate(tools):
    """The hopper's control rate in SIL: fixed-point error against control steps per
    second of hopping."""
    rows = []
    for series, scene, rates in HOPPER_SCENES:
        for rate in rates:
            summary, cmd = dexter_json(tools, [scene, "--set", f"hopper.control.rate_hz={rate}"])
            if summary.get("end") != "completed" or summary.get("safe_steps") != 0:
                raise Failure(f"{' '.join(cmd)}: ended {summary.get('end')!r} with {summary.get('safe_steps')!r} safe steps")
            steps = json_number(summary, "control_steps", cmd)
            per_s = steps / json_number(summary, "sim_time_s", cmd)
            rows.append((
                series,
                f"{rate} Hz (period {summary.get('period')})",
                per_s,
                "control steps per second of hopping (SIL)",
                json_number(summary, "fixed_point_error", cmd),
                "fixed_point_error (relative to the exact orbit's hop)",
            ))
    return rows


KNOBS = {
    "math-backend": (math_backend, "Math backend: sin in f32, error against instructions"),
    "precision": (precision, "Precision: f32 against f64"),
    "integrator": (integrator, "Flight: exact events against RK4 and RK45 (200 impacts)"),
    "control-rate": (control_rate, "Line juggler (SIL): control rate"),
    "tilt-newton-cap": (tilt_newton_cap, "Tilt controller: Newton steps per plan"),
    "hopper-rate": (hopper_rate, "Hopper (SIL): control rate"),
}


# ---- output -----------------------------------------------------------------------------------


def csv_text(rows):
    """The rows as the trade-off CSV (host-sim/src/plot/tradeoff.rs); a field with a comma
    or a newline raises (the format has no quoting)."""
    buf = io.StringIO()
    buf.write(",".join(HEADER) + "\n")
    for row in rows:
        fields = [f"{v:.6g}" if isinstance(v, float) else str(v) for v in row]
        for f in fields:
            if "," in f or "\n" in f or not f.strip():
                raise Failure(f"a CSV field would be unreadable: {f!r} in {row}")
        buf.write(",".join(fields) + "\n")
    return buf.getvalue()


def write(path, text):
    os.makedirs(os.path.dirname(path), exist_ok=True)
    tmp = path + ".tmp"
    with open(tmp, "w") as f:
        f.write(text)
    os.replace(tmp, path)


def make(tools, knob):
    measure, title = KNOBS[knob]
    start = time.monotonic()
    rows = measure(tools)
    data = os.path.join(ROOT, "docs", "figures", "data", f"{knob}.csv")
    write(data, csv_text(rows))
    svg = os.path.join(ROOT, "docs", "figures", f"{knob}.svg")
    run([tools.figure, data, svg, title])
    print(f"{knob}: {len(rows)} points, {time.monotonic() - start:.1f} s -> {os.path.relpath(svg, ROOT)}")


def main(argv):
    target_dir = os.path.join(ROOT, "target")
    if argv[:1] == ["--target-dir"] and len(argv) >= 2:
        target_dir, argv = argv[1], argv[2:]
    unknown = [k for k in argv if k not in KNOBS]
    if unknown:
        print(f"unknown knob(s) {unknown}; the knobs: {' '.join(KNOBS)}", file=sys.stderr)
        return 2
    try:
        with tempfile.TemporaryDirectory(prefix="accuracy-figures-") as scratch:
            return measure_all(Tools(target_dir, scratch), argv or list(KNOBS))
    except Failure as e:
        print(f"accuracy-figures: {e}", file=sys.stderr)
        return 1


def measure_all(tools, knobs):
    start = time.monotonic()
    for knob in knobs:
        make(tools, knob)
    print(f"measured and drawn in {time.monotonic() - start:.1f} s")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
