"""FootFall from Python (issue 16): the stability map of one SDM-B leg (2 cm cells, full reach)
through the binding and its numpy view, and a sag-compensated step (map + sag + SBL + smoothing),
medians of repeats; the C++ figures (SBL vs RRT-Connect, smoother vs OMPL's simplifier) are
benchmarks/bench_footfall.cpp, which `./run bench footfall` runs first."""

import statistics
import time

from ernest_cpp import footfall as F
from ernest_cpp import walker as W


def median_s(fn, repeats=5):
    t = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        fn()
        t.append(time.perf_counter() - t0)
    return statistics.median(t)


def main() -> None:
    model = W.WalkerModel(W.sdm_b_parameters())
    body, q = model.standard_body_pose(), model.standard_configuration
    feet = model.contact_points(body, q)
    terrain = F.rock_field(F.RockFieldOptions(), feet[:2])
    t_map = median_s(lambda: F.stability_map(model, terrain, body, q, 0))
    print(f"stability map from Python (2 cm, numpy arrays): {t_map:.3f} s median (target <= 0.5 s)")
    so = F.StepOptions()
    steps = []
    t_step = median_s(lambda: steps.append(F.plan_step(model, terrain, body, q, 0, feet[0, 0] + 0.35,
                                                       feet[1, 0], so)))
    s = steps[-1]
    print(f"plan_step (goal check, sag, waypoints, SBL, smoothing): {1e3 * t_step:.0f} ms median; "
          f"SBL {1e3 * s.plan.seconds:.1f} ms, smoothing {1e3 * s.smoothing.seconds:.1f} ms, "
          f"length {s.plan.length:.2f} -> {s.smoothing.length:.2f} rad, "
          f"swing-hip sag {100 * -s.sag.hip_displacement[2]:.1f} cm")


if __name__ == "__main__":
    main()
