#!/usr/bin/env python3
"""The tables of BENCHMARKS.md, "Speed": run by scripts/speed-table.sh (which builds the
release `dexter` first). Each table prints as markdown on stdout.

  ratio  dexter's CLI (`run ... --json`) against scripts/reference_bounce.py on the passive
         bounce (e = 1) and the ideal mirror juggler, interleaved in the same run: simulated
         seconds per wall second of the whole process (start-up included, for both), the
         median of REPEATS runs each, and their ratio.
  rss    Peak resident memory (`/usr/bin/time -v`, "Maximum resident set size") and speed
         of the passive bounce through the CLI from 1e5 to 1e8 impacts.
  sil    The realistic line juggler (scenes/line-juggler.toml: controller, sensor with
         noise/latency/quantization, second-order actuator) at 1 kHz, SIL, through the CLI.
  sweep  A 1000-point sweep serial (RAYON_NUM_THREADS=1) and on every core, interleaved:
         wall time and user + sys CPU time, median of REPEATS.

Usage: scripts/speed_table.py BIN [ratio|rss|sil|sweep ...]   (default: all four)
Environment: SPEED_REPEATS (default 3).
"""

import json
import os
import re
import statistics
import subprocess
import sys
import tempfile
import time

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
REPEATS = int(os.environ.get("SPEED_REPEATS", "3"))
REFERENCE = [sys.executable, os.path.join(ROOT, "scripts", "reference_bounce.py")]

PASSIVE = ["scenes/passive-bounce.toml", "--set", "physics.restitution=1.0"]
MIRROR = ["scenes/line-juggler-ideal.toml"]
# The realistic scene with controller and sensor at 1 kHz (the shipped one runs at 500 Hz).
SIL_1KHZ = ["scenes/line-juggler.toml", "--set", "control.rate_hz=1000.0",
            "--set", "sensor.rate_hz=1000.0", "--set", "stop.impacts=100000000"]
SWEEP = ["sweep", "scenes/line-juggler-ideal.toml",
         "--range", "control.kappa1_s2pm2=0.0:0.1:1000", "--set", "stop.impacts=50000",
         "--set", "stop.duration_s=1e9"]


def measure(cmd, env=None):
    """Run `cmd` under /usr/bin/time -v: (wall s, user s, sys s, peak RSS KiB, stdout)."""
    with tempfile.NamedTemporaryFile("r", suffix=".time") as t:
        start = time.perf_counter()
        p = subprocess.run(["/usr/bin/time", "-v", "-o", t.name] + cmd, cwd=ROOT,
                           env=env, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                           text=True)
        wall = time.perf_counter() - start
        if p.returncode != 0:
            raise SystemExit(f"{' '.join(cmd)} failed ({p.returncode}):\n{p.stderr}")
        report = t.read()

    def field(name):
        return float(re.search(re.escape(name) + r":\s*([0-9.]+)", report).group(1))

    return (wall, field("User time (seconds)"), field("System time (seconds)"),
            int(field("Maximum resident set size (kbytes)")), p.stdout)


def fmt(x):
    """A number with 3 significant digits, e.g. 4.52e7 (1e8 for a power of ten)."""
    return f"{x:.2e}".replace("e+0", "e").replace("e+", "e").replace(".00e", "e")


def ratio_table(bin_):
    print("| scene | dexter impacts | dexter sim s / wall s | Python impacts "
          "| Python sim s / wall s | ratio |")
    print("| --- | --- | --- | --- | --- | --- |")
    scenes = [("passive bounce, e = 1", PASSIVE, "passive", 10**8, 2 * 10**6),
              ("ideal mirror juggler", MIRROR, "mirror", 10**8, 2 * 10**6)]
    for label, scene, ref, n_dexter, n_python in scenes:
        ours, theirs = [], []
        for _ in range(REPEATS):  # interleaved, so both see the same load
            wall, _, _, _, out = measure([bin_, "run"] + scene +
                                         ["--impacts", str(n_dexter), "--json"])
            ours.append(json.loads(out)["sim_time_s"] / wall)
            wall, _, _, _, out = measure(REFERENCE + [ref, str(n_python)])
            theirs.append(json.loads(out)["sim_time_s"] / wall)
        a, b = statistics.median(ours), statistics.median(theirs)
        print(f"| {label} | {fmt(n_dexter)} | {fmt(a)} | {fmt(n_python)} | {fmt(b)} "
              f"| {a / b:.0f} |")


def rss_table(bin_):
    print("| impacts | simulated s | wall s | sim s / wall s | peak RSS (KiB) |")
    print("| --- | --- | --- | --- | --- |")
    for n in [10**5, 10**6, 10**7, 10**8]:
        wall, _, _, rss, out = measure([bin_, "run"] + PASSIVE +
                                       ["--impacts", str(n), "--json"])
        sim = json.loads(out)["sim_time_s"]
        print(f"| {fmt(n)} | {fmt(sim)} | {wall:.3f} | {fmt(sim / wall)} | {rss} |")


def sil_table(bin_):
    print("| run | control steps | simulated s | wall s | sim s / wall s "
          "| safe steps | peak RSS (KiB) |")
    print("| --- | --- | --- | --- | --- | --- | --- |")
    for duration in [2000, 20000]:
        rates = []
        for _ in range(REPEATS):
            wall, _, _, rss, out = measure([bin_, "run"] + SIL_1KHZ +
                                           ["--duration", str(duration), "--json"])
            s = json.loads(out)
            rates.append((s["sim_time_s"] / wall, wall))
        rate, wall = sorted(rates)[len(rates) // 2]
        print(f"| {duration} s, median of {REPEATS} | {s['control_steps']} "
              f"| {fmt(s['sim_time_s'])} | {wall:.3f} | {fmt(rate)} | {s['safe_steps']} "
              f"| {rss} |")


def sweep_table(bin_):
    print("| threads | wall s (median) | user + sys s (median) | wall / serial wall |")
    print("| --- | --- | --- | --- |")
    runs = {1: [], None: []}
    with tempfile.TemporaryDirectory() as d:
        csv = os.path.join(d, "sweep.csv")
        for _ in range(REPEATS):
            for threads in runs:
                env = dict(os.environ)
                env.pop("RAYON_NUM_THREADS", None)
                if threads:
                    env["RAYON_NUM_THREADS"] = str(threads)
                wall, user, sys_, _, _ = measure([bin_] + SWEEP + ["--csv", csv], env)
                runs[threads].append((wall, user + sys_))
    serial = statistics.median(w for w, _ in runs[1])
    for threads, label in [(1, "1 (`RAYON_NUM_THREADS=1`)"),
                           (None, f"{os.cpu_count()} (every core)")]:
        wall = statistics.median(w for w, _ in runs[threads])
        cpu = statistics.median(c for _, c in runs[threads])
        walls = " / ".join(f"{w:.2f}" for w, _ in runs[threads])
        print(f"| {label} | {wall:.2f} ({walls}) | {cpu:.2f} | {wall / serial:.2f} |")


def main(argv):
    if len(argv) < 2:
        raise SystemExit("usage: speed_table.py BIN [ratio|rss|sil|sweep ...]")
    tables = {"ratio": ratio_table, "rss": rss_table, "sil": sil_table,
              "sweep": sweep_table}
    chosen = argv[2:] or list(tables)
    for name in chosen:
        if name not in tables:
            raise SystemExit(f"unknown table {name!r}: one of {', '.join(tables)}")
    print(f"load average before: {open('/proc/loadavg').read().strip()}")
    for name in chosen:
        print(f"\n{name}:\n")
        tables[name](os.path.abspath(argv[1]))
    print(f"\nload average after: {open('/proc/loadavg').read().strip()}")


if __name__ == "__main__":
    main(sys.argv)
