"""Walker IK from Python (target: IK of one leg <= 20 us): the C++ single-start solve
(LegIk.solve_from, binding overhead included) against the same solve in numpy + scipy in the same
run: the same residual (wheel centre and w * (R - R*), 12 rows), the same analytic Jacobian, the
same q = c + h sin(u) limit transform, the same MINPACK Levenberg-Marquardt (scipy's
least_squares(method="lm")), the same targets and seed (scipy stops on its relative tests, 1e-10; the C++ solver also stops once
|r| < 1e-9). Medians of repeats.

    ./run bench walker      (runs the C++ benchmark, then this script)
    needs scipy (pip install 'ernest-cpp[bench]')
"""

import math
import platform

import numpy as np
from scipy.optimize import least_squares

from ernest_cpp import walker as W
from functools import partial

import bench_util

median_us = partial(bench_util.median_us, repeats=7)


class NumpyLeg:
    """Forward kinematics and the IK residual of one leg in numpy (the reference)."""

    def __init__(self, model, leg):
        p = model.params
        self.mount = model.hip_mount(leg)
        self.offsets = [np.array(j.offset) for j in p.joints]
        self.axes = [np.array(j.axis) for j in p.joints]
        self.foot_offset = np.array(p.foot_offset)
        self.foot_rotation = np.array(p.foot_rotation)
        lo, hi = model.lower_limits, model.upper_limits
        self.c, self.h = 0.5 * (lo + hi), 0.5 * (hi - lo)
        self.w = W.IkOptions().orientation_weight

    def frames(self, q):
        r, p = self.mount[:3, :3].copy(), self.mount[:3, 3].copy()
        pos, axes = [], []
        for off, a, qi in zip(self.offsets, self.axes, q):
            p = p + r @ off
            pos.append(p)
            axes.append(r @ a)
            k = np.array([[0, -a[2], a[1]], [a[2], 0, -a[0]], [-a[1], a[0], 0]])
            r = r @ (np.eye(3) + math.sin(qi) * k + (1 - math.cos(qi)) * (k @ k))
        return p + r @ self.foot_offset, r @ self.foot_rotation, pos, axes

    def residual(self, u, target):
        centre, rot, _, _ = self.frames(self.c + self.h * np.sin(u))
        return np.concatenate([centre - target[:3, 3], self.w * (rot - target[:3, :3]).T.ravel()])

    def jacobian(self, u, target):
        centre, rot, pos, axes = self.frames(self.c + self.h * np.sin(u))
        a, s = np.array(axes), self.h * np.cos(u)  # (n, 3) joint axes, dq/du
        J = np.empty((12, len(u)))
        J[:3] = np.cross(a, centre - np.array(pos)).T * s
        for k in range(3):
            J[3 + 3 * k: 6 + 3 * k] = np.cross(a, rot[:, k]).T * (s * self.w)
        return J

    def solve(self, target, seed):
        u0 = np.arcsin(np.clip((seed - self.c) / self.h, -0.99, 0.99))
        r = least_squares(self.residual, u0, jac=self.jacobian, method="lm", args=(target,),
                          xtol=1e-10, ftol=1e-10, gtol=1e-15, max_nfev=150)
        return self.c + self.h * np.sin(r.x)


def main():
    print(f"machine: {platform.processor() or platform.machine()}, python {platform.python_version()}")
    model = W.WalkerModel(W.sdm_b_parameters())
    seed = model.standard_configuration[:, 0].copy()
    rng = np.random.default_rng(42)
    targets = []
    for _ in range(100):
        q = np.clip(seed + rng.uniform(-0.3, 0.3, seed.size), model.lower_limits, model.upper_limits)
        targets.append(model.foot_pose(0, q))
    ik = W.LegIk(model)
    ref = NumpyLeg(model, 0)

    ok_cpp = sum(ik.solve_from(0, t, seed)[0] for t in targets)
    errs = []
    for t in targets:
        q = ref.solve(t, seed)
        errs.append(np.abs(model.foot_pose(0, q) - t).max())
    ok_ref = sum(e < 1e-6 for e in errs)
    cpp = median_us(lambda: [ik.solve_from(0, t, seed) for t in targets], len(targets), 15)
    sub = targets[:20]
    numpy_us = median_us(lambda: [ref.solve(t, seed) for t in sub], len(sub), 5)
    print(f"SDM-B leg IK, {len(targets)} targets within ±0.3 rad of the standard stance (median us per solve)")
    print(f"  C++ LegIk.solve_from from Python: {cpp:9.2f} us  ({ok_cpp}/{len(targets)} converged)")
    print(f"  numpy + scipy least_squares(lm):  {numpy_us:9.2f} us  ({ok_ref}/{len(targets)} converged)")
    print(f"  ratio: C++ is {numpy_us / cpp:.0f}x faster")


if __name__ == "__main__":
    main()
