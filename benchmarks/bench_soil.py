"""Soil from Python: microseconds per wheel for one evaluate() call per wheel (binding overhead
included) and for evaluate_batch() over many wheels (one call, GIL released), medians of repeats.
Reference in the same run: the C++ cost is what evaluate_batch approaches as the batch grows.

    ./run bench soil      (runs the C++ benchmark, then this script)
"""

import platform

import numpy as np

from ernest_cpp import soil as S
from functools import partial

import bench_util

median_us = partial(bench_util.median_us, repeats=15)


def main():
    print(f"machine: {platform.processor() or platform.machine()}, python {platform.python_version()}")
    m = S.BekkerWongModel(S.soil_preset("m90"), S.ernest_wheel())
    rng = np.random.default_rng(42)
    n = 4096
    states = np.column_stack([rng.uniform(2e-3, 0.08, n), rng.uniform(-0.3, 0.3, (n, 4))])
    objs = [S.ContactState(*row) for row in states[:512]]

    single = median_us(lambda: [m.evaluate(s) for s in objs], len(objs))
    print(f"default quadrature ({S.DEFAULT_POINTS_PER_PANEL} points per panel), M90")
    print(f"  evaluate() per wheel from Python:         {single:8.3f} us")
    for batch in (4, 64, 4096):
        sub = np.ascontiguousarray(states[:batch])
        us = median_us(lambda: m.evaluate_batch(sub), batch, repeats=31)
        print(f"  evaluate_batch() of {batch:5d} wheels, per wheel: {us:8.3f} us  "
              f"({single / us:5.1f}x faster than per-wheel calls)")


if __name__ == "__main__":
    main()
