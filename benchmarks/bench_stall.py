"""A stalled rover: the passive bogie driving its wheels at 0.2 m/s up a 20 deg M90
slope (the environments' eq 12/16 constants, rolling start), 10 s, with the slip of eq 12 solved
implicitly (default) and explicitly (``slip_force_tolerance = 1e9``), at dt,
dt/2 and dt/4. Prints the mean creep over the last 5 s, the wheel-load standard deviation after the
first second and the extra solves per step.

    ./run bench stall
"""

from __future__ import annotations

import math
import time

import numpy as np

from ernest_cpp import dynamics as D
from ernest_cpp import soil as S


def run(dt: float, tolerance: float, duration: float = 10.0):
    p = S.soil_preset("m90")
    p.eps_slip, p.eps_motion = 1e4, 0.01  # envs.EnvOptions defaults
    o = D.make_options("soil", soil=p, dt=dt)
    o.slip_force_tolerance = tolerance
    sim = D.make_sim(terrain=D.HeightMap.slope(math.radians(20), 24, 8, 0.25, -4, -4), options=o)
    sim.reset(0.0, 0.0, 0.0, 0.0, 0.0, 0.2)
    c = D.Commands()
    c.wheel_speed = [0.2 / sim.parameters.wheel_radius] * 4
    c.gimbal_enabled, c.clutch_engage = False, False
    sim.set_commands(c)
    n = int(round(duration / dt))
    loads, x = np.zeros((n, 4)), np.zeros(n)
    t0 = time.perf_counter()
    for k in range(n):
        sim.step()
        loads[k], x[k] = sim.state.wheel_load, sim.state.position[0]
    us = (time.perf_counter() - t0) / n * 1e6
    creep = (x[-1] - x[n // 2]) / (duration / 2)
    std = loads[int(round(1.0 / dt)):].std(axis=0).max()
    return creep, std, sim.solver_stats.slip_solves / n, us


def main() -> None:
    dt = D.SimOptions().dt
    print("| slip | dt [s] | creep [cm/s] | max wheel-load std [N] | extra solves/step | us/step |")
    print("|---|---|---|---|---|---|")
    for name, tol in (("explicit", 1e9), ("implicit", D.SimOptions().slip_force_tolerance)):
        for h in (dt, dt / 2, dt / 4):
            creep, std, extra, us = run(h, tol)
            print(f"| {name} | {h:g} | {100 * creep:+.3f} | {std:.3f} | {extra:.2f} | {us:.1f} |",
                  flush=True)


if __name__ == "__main__":
    main()
