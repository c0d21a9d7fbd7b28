"""FootFall from Python: the stability map of one SDM-B leg (2 cm cells, full reach)
through the binding and its numpy view, and a sag-compensated step (map + sag + SBL + smoothing),
medians of repeats; the C++ figures (SBL vs RRT-Connect, smoother vs OMPL's simplifier) are
benchmarks/bench_footfall.cpp, which `./run bench footfall` runs first. Then the terrain from
perception: 8 stereo views fused into the elevation map (once), its conversion to the planner's
DEM (median), and the same step planned on it, against the step on the ground truth."""

import statistics
import time

from ernest_cpp import footfall as F
from ernest_cpp import footfall_terrain as FT
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

    t0 = time.perf_counter()
    mapper = FT.stereo_map(terrain, body)
    t_fuse = time.perf_counter() - t0
    t_conv = median_s(lambda: F.terrain_from_map(mapper.map))
    dem = F.terrain_from_map(mapper.map)
    plans = []
    t_stereo = median_s(lambda: plans.append(F.plan_step(model, dem.terrain, body, q, 0, feet[0, 0] + 0.35,
                                                         feet[1, 0], so)))
    n = dem.observed + dem.filled + dem.unknown
    print(f"terrain from stereo: 8 views rendered, matched and fused in {t_fuse:.1f} s (once); "
          f"elevation map -> planner DEM {1e3 * t_conv:.0f} ms median ({100 * dem.unknown / n:.1f} % of the "
          f"vertices unknown); plan_step on it {1e3 * t_stereo:.0f} ms median, "
          f"{'solved' if plans[-1].solved else plans[-1].reason}; ratio to the ground-truth step "
          f"{t_stereo / t_step:.2f}")


if __name__ == "__main__":
    main()
