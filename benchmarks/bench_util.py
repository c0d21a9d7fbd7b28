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
