"""Statics from Python, against the same computations in numpy/scipy in the same run (medians of
repeats, microseconds per call, six contacts):

* SSM + NESM + CPS: ours (one binding call) vs scipy.spatial.ConvexHull for the seven hulls, a
  numpy half-plane clip for the CPS and numpy distances and NESM (Hirose's formula as in
  cpp/statics/stability.hpp); the answers are compared too.
* zero-interaction distribution: ours vs numpy.linalg.pinv of the explicit 6 x 18 matrix.
* one sag solve: ours vs the same residuals (eqs 4–8, the contact set ours ended with) in numpy,
  solved by scipy.optimize.least_squares(method="lm"), i.e. MINPACK's LM with a forward-difference
  Jacobian.

    ./run bench statics      (runs the C++ benchmark, then this script; scipy: pip install '.[bench]')
"""

import platform

import numpy as np

from ernest_cpp import statics as S
from bench_util import median_us

try:
    import scipy.optimize
    import scipy.spatial
except ImportError:  # benchmark-only extra
    scipy = None

G = np.array([0.0, 0.0, -9.81])


def stances(n, seed=7):
    rng = np.random.default_rng(seed)
    out = []
    for _ in range(n):
        t = np.arange(6) * np.pi / 3 + 0.2 * rng.uniform(-0.3, 0.3, 6)
        feet = np.vstack([2.5 * np.cos(t) + rng.uniform(-0.3, 0.3, 6),
                          2.5 * np.sin(t) + rng.uniform(-0.3, 0.3, 6),
                          0.3 * rng.uniform(-0.3, 0.3, 6)])
        out.append((feet, np.array([rng.uniform(-0.3, 0.3), rng.uniform(-0.3, 0.3), 1.75])))
    return out


# ---- numpy/scipy reference of the margins ----
def cross2(a, b):
    return a[0] * b[1] - a[1] * b[0]


def hull(points2, idx):
    h = scipy.spatial.ConvexHull(points2[idx])  # counter-clockwise in 2-D
    return [idx[v] for v in h.vertices]


def clip(poly, a, b, lab):
    """Keep the part of poly (list of (vertex, edge label)) left of a -> b."""
    d = b - a
    out = []
    for k, (p, plab) in enumerate(poly):
        q = poly[(k + 1) % len(poly)][0]
        dp, dq = cross2(d, p - a), cross2(d, q - a)
        if dp >= 0:
            out.append((p, plab))
        if (dp >= 0) != (dq >= 0):
            out.append((p + dp / (dp - dq) * (q - p), lab if dp >= 0 else plab))
    return out


def signed_distance_and_nesm(poly, feet, cg):
    c2 = cg[:2]
    n = len(poly)
    ssm_in, dist_out, inside, nesm = np.inf, np.inf, True, np.inf
    for k, (p, (i, j)) in enumerate(poly):
        q = poly[(k + 1) % n][0]
        e = q - p
        s = cross2(e, c2 - p) / np.linalg.norm(e)
        inside &= s >= 0
        ssm_in = min(ssm_in, s)
        t = np.clip(np.dot(c2 - p, e) / np.dot(e, e), 0, 1)
        dist_out = min(dist_out, np.linalg.norm(p + t * e - c2))
        ax = feet[:, j] - feet[:, i]
        ax /= np.linalg.norm(ax)
        dv = cg - feet[:, i]
        R = dv - dv.dot(ax) * ax
        h = max(0.0, np.linalg.norm(R) * np.sqrt(1 - ax[2] ** 2) - R[2])
        nesm = min(nesm, h if s >= 0 else -h)
    return (ssm_in if inside else -dist_out), nesm


def margins_reference(feet, cg):
    p2 = feet[:2].T
    h = hull(p2, np.arange(6))
    support = [(p2[h[k]], (h[k], h[(k + 1) % len(h)])) for k in range(len(h))]
    cps = None
    for removed in range(6):
        sub = hull(p2, np.array([i for i in range(6) if i != removed]))
        if cps is None:
            cps = [(p2[sub[k]], (sub[k], sub[(k + 1) % len(sub)])) for k in range(len(sub))]
            continue
        for k in range(len(sub)):
            cps = clip(cps, p2[sub[k]], p2[sub[(k + 1) % len(sub)]], (sub[k], sub[(k + 1) % len(sub)]))
    ssm, nesm = signed_distance_and_nesm(support, feet, cg)
    ssm_cps, nesm_cps = signed_distance_and_nesm(cps, feet, cg)
    return ssm, nesm, ssm_cps, nesm_cps


# ---- numpy/scipy reference of the sag solve (eqs 4–8 with a fixed contact set) ----
def sag_reference(p, active):
    n = p.feet.shape[1]
    feet, cg, k, W = p.feet, p.cg, p.stiffness, p.mass * p.gravity
    lift = p.lift if len(p.lift) else np.zeros(n)
    pairs = sorted({tuple(sorted((i, (i + s) % n))) for s in (1, 2) for i in range(n)})
    d0 = np.array([np.linalg.norm(feet[:, i] - feet[:, j]) for i, j in pairs])
    c0 = np.linalg.norm(cg[:, None] - feet, axis=0)
    Wn, L, delta = np.linalg.norm(W), c0.max(), np.linalg.norm(W) / k[2].sum()

    def residual(x):
        dr = x[:3 * n].reshape(n, 3).T
        rf, cgf = feet + dr, cg + x[3 * n:]
        f = np.where(active, np.vstack([-k[0] * dr[0], -k[1] * dr[1], -k[2] * (dr[2] + lift)]), 0)
        r1 = (f.sum(axis=1) + W) / Wn
        r2 = (np.cross((rf - cg[:, None]).T, f.T).sum(axis=0) + np.cross(cgf - cg, W)) / (Wn * L)
        r3 = [(d0[m] - np.linalg.norm(rf[:, i] - rf[:, j])) / delta for m, (i, j) in enumerate(pairs)]
        r4 = (c0 - np.linalg.norm(cgf[:, None] - rf, axis=0)) / delta
        return np.concatenate([r1, r2, r3, r4])

    x0 = np.tile([0, 0, -Wn / k[2].sum()], n + 1)
    sol = scipy.optimize.least_squares(residual, x0, method="lm", xtol=1e-14, ftol=1e-14)
    dr = sol.x[:3 * n].reshape(n, 3).T
    return np.where(active, np.vstack([-k[0] * dr[0], -k[1] * dr[1], -k[2] * (dr[2] + lift)]), 0)


def main():
    print(f"machine: {platform.processor() or platform.machine()}, python {platform.python_version()}")
    cases = stances(64)
    ours = median_us(lambda: [S.stability_margins(f, c, G) for f, c in cases], len(cases), 21)
    print(f"SSM + NESM + CPS, six contacts, from Python: {ours:9.2f} us/call")
    if scipy is not None:
        ref = median_us(lambda: [margins_reference(f, c) for f, c in cases], len(cases), 3)
        err = 0.0
        for f, c in cases:
            m = S.stability_margins(f, c, G)
            err = max(err, np.max(np.abs(np.array([m.ssm, m.nesm, m.ssm_cps, m.nesm_cps])
                                         - margins_reference(f, c))))
        print(f"  numpy/scipy reference:                    {ref:9.2f} us/call  ({ref / ours:.0f}x)"
              f"   max |difference| {err:.1e} m")

    ours = median_us(lambda: [S.zero_interaction_forces(f, c, 850.0, G) for f, c in cases],
                     len(cases), 21)

    def numpy_pinv(f, c):
        A = np.zeros((6, 18))
        for i, p in enumerate(f.T):
            A[:3, 3 * i:3 * i + 3] = np.eye(3)
            A[3:, 3 * i:3 * i + 3] = [[0, -p[2], p[1]], [p[2], 0, -p[0]], [-p[1], p[0], 0]]
        return np.linalg.pinv(A) @ np.concatenate([-850.0 * G, -np.cross(c, 850.0 * G)])

    ref = median_us(lambda: [numpy_pinv(f, c) for f, c in cases], len(cases), 9)
    err = max(np.max(np.abs(S.zero_interaction_forces(f, c, 850.0, G)[0].T.reshape(-1)
                            - numpy_pinv(f, c))) for f, c in cases)
    print(f"zero-interaction distribution, from Python: {ours:9.2f} us/call")
    print(f"  numpy.linalg.pinv reference:              {ref:9.2f} us/call  ({ref / ours:.0f}x)"
          f"   max |difference| {err:.1e} N")

    problems = []
    for n, (f, c) in enumerate(cases[:24]):
        p = S.sag_problem(f, c, 850.0, [2e5, 2e5, 1e5])
        if n % 3 == 0:
            p = S.lift_foot(p, n % 6, 0.05)
        problems.append(p)
    ours = median_us(lambda: [S.solve_sag(p) for p in problems], len(problems), 9)
    print(f"sag solve, six feet, from Python:           {ours:9.1f} us/solve")
    if scipy is not None:
        results = [S.solve_sag(p) for p in problems]
        active = [r.compression > 0 for r in results]
        ref = median_us(lambda: [sag_reference(p, a) for p, a in zip(problems, active)],
                        len(problems), 3)
        err = max(np.max(np.abs(sag_reference(p, a) - r.forces)) / (850 * 9.81)
                  for p, a, r in zip(problems, active, results))
        print(f"  scipy least_squares(lm) reference:        {ref:9.1f} us/solve ({ref / ours:.0f}x)"
              f"   max |force difference| {err:.1e} of the weight")
    else:
        print("  (scipy missing: pip install '.[bench]' for the numpy/scipy references)")


if __name__ == "__main__":
    main()
