"""Timing helper shared by the Python benchmarks: medians over repeats (these machines are noisy)."""

from __future__ import annotations

import statistics
import time


def median_us(fn, per, repeats=9):
    """Median over ``repeats`` calls of ``fn()``, in microseconds per unit (``fn`` does ``per``)."""
    times = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        fn()
        times.append((time.perf_counter() - t0) * 1e6 / per)
    return statistics.median(times)


def rolling_rover(obstacles=(), speed=0.15, substeps=None, guess_obstacles=True, slip_warm_start=True,
                  stepper=None, contact=None):
    """A rover on flat M90 (friction 0.8 on the rocks) with these box obstacles, started rolling at
    ``speed`` [m/s] with its wheels commanded to it (gimbal free): the driving runs of the
    dynamics benchmarks. ``substeps``: SimOptions.obstacle_substeps, ``stepper``:
    SimOptions.stepper, ``contact``: SimOptions.wheel_obstacle_contact (None: their defaults)."""
    from ernest_cpp import dynamics as D

    o = D.make_options("soil", friction=0.8)
    if substeps is not None:
        o.obstacle_substeps = substeps
    o.guess_obstacle_contacts = guess_obstacles
    o.slip_warm_start = slip_warm_start
    if stepper is not None:
        o.stepper = stepper
    if contact is not None:
        o.wheel_obstacle_contact = contact
    sim = D.make_sim(obstacles=list(obstacles), options=o)
    sim.reset(0.0, 0.0, 0.0, 0.0, 0.0, speed)
    c = D.Commands()
    c.wheel_speed = [speed / sim.parameters.wheel_radius] * 4
    sim.set_commands(c)
    return sim
