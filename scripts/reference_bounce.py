#!/usr/bin/env python3
"""A plain Python event-driven reference for dexter's speed table (BENCHMARKS.md, "Speed").

It simulates the same two line scenes as dexter, the same way (closed-form ballistic flight,
contact time from the numerically stable quadratic formula, the restitution law at each
impact), in a plain loop that keeps only running figures (constant memory, like dexter's
CLI without --trace), and prints one JSON line with the simulated seconds per wall second.

Scenes (the physics of scenes/passive-bounce.toml and scenes/line-juggler-ideal.toml):

  passive  A ball dropped from rest at 1 m onto a fixed table at height 0, restitution
           e = 1 (`--set physics.restitution=1.0`): every flight lasts 2 sqrt(2 h / g).
  mirror   The ideal mirror juggler of Rizzi & Koditschek (1994) sec. 2.1: the paddle
           follows r = -k(eta) b exactly, k = kappa0 + kappa1 (eta* - eta),
           eta = b'^2/2 + g b (eq. 5). k is constant in flight (eta is), so paddle and ball
           meet at b = 0, where the paddle moves at r' = -k b'. Ball from rest at 0.3 m,
           e = 0.8, kappa0 = (1 - e)/(1 + e), kappa1 = 0.05 s^2/m^2, target apex 1 m.

The loop stops at the requested number of impacts. Neither scene reaches a Zeno cascade
(passive e = 1 keeps its energy; the mirror converges to a 1 m apex), so the reference
has no Zeno handling; it refuses a take-off speed that is not positive rather than run on.

Usage: scripts/reference_bounce.py {passive,mirror} IMPACTS
Output: {"scene", "impacts", "sim_time_s", "wall_time_s", "sim_s_per_wall_s",
         "last_apex_m"}; wall_time_s is the loop alone (process start-up excluded).
"""

import json
import math
import sys
import time

G_MPS2 = 9.81


def flight_time_s(height_m, velocity_mps, g):
    """Time until a ball at height_m > = 0 moving at velocity_mps reaches height 0 (the
    positive root of h + v t - g t^2 / 2, stable for either sign of v)."""
    s = math.sqrt(velocity_mps * velocity_mps + 2.0 * g * height_m)
    if velocity_mps >= 0.0:
        return (velocity_mps + s) / g
    return 2.0 * height_m / (s - velocity_mps)


def passive(impacts):
    """Passive bounce, e = 1, from rest at 1 m onto a table at 0 m."""
    g, e = G_MPS2, 1.0
    t, h, v = 0.0, 1.0, 0.0
    apex = h
    for _ in range(impacts):
        dt = flight_time_s(h, v, g)
        t += dt
        v_in = v - g * dt
        v = -e * v_in  # table at rest: restitution_velocity(v_in, 0, e)
        h = 0.0
        if v <= 0.0:
            raise SystemExit(f"the ball stopped bouncing at t = {t} s")
        apex = v * v / (2.0 * g)
    return t, apex


def mirror(impacts):
    """Ideal mirror juggler, e = 0.8, kappa0 matched, kappa1 = 0.05, target 1 m."""
    g, e = G_MPS2, 0.8
    kappa0 = (1.0 - e) / (1.0 + e)
    kappa1 = 0.05
    target_energy = g * 1.0
    t, h, v = 0.0, 0.3, 0.0
    apex = h
    for _ in range(impacts):
        dt = flight_time_s(h, v, g)
        t += dt
        v_in = v - g * dt
        k = kappa0 + kappa1 * (target_energy - 0.5 * v_in * v_in)  # eta at b = 0
        paddle_v = -k * v_in
        v = -e * v_in + (1.0 + e) * paddle_v
        h = 0.0
        if v <= paddle_v:
            raise SystemExit(f"the ball stays on the paddle at t = {t} s")
        apex = v * v / (2.0 * g)
    return t, apex


def main(argv):
    scenes = {"passive": passive, "mirror": mirror}
    if len(argv) != 3 or argv[1] not in scenes or not argv[2].isdigit():
        raise SystemExit("usage: reference_bounce.py {passive,mirror} IMPACTS")
    impacts = int(argv[2])
    start = time.perf_counter()
    sim_s, apex_m = scenes[argv[1]](impacts)
    wall_s = time.perf_counter() - start
    print(json.dumps({
        "scene": argv[1],
        "impacts": impacts,
        "sim_time_s": sim_s,
        "wall_time_s": wall_s,
        "sim_s_per_wall_s": sim_s / wall_s,
        "last_apex_m": apex_m,
    }))


if __name__ == "__main__":
    main(sys.argv)
