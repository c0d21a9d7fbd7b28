"""``ernest perception``: the stereo elevation-mapping pipeline of seed 004 §2.4 on a generated
scenario, frame by frame, with the views of Fig. 11. The rover is placed along its path (0.4 m
between frames: 0.2 m/s at the paper's 0.5 Hz fusion rate); at each frame the two masthead cameras
are ray-cast, matched with OpenCV StereoBM, back-projected and fused into the robot-centric map.
For each frame it writes the left image, the disparity, the fused map beside the ground truth, the
error map, the coverage and the 12 elevation samples of §4.2 (Fig. 11's arrows), and a CSV of RMS
error, normalised-error variance and coverage over the cells within 3 m of the cameras.
"""

from __future__ import annotations

import argparse
import csv
import math
import os

import numpy as np

from ._csv import header
from . import _args
from . import dynamics as D
from . import perception as P
from . import sensing as S
from ._core import envs as _envs

CHASSIS_HEIGHT = 0.17  # chassis origin above the ground (wheel-axle height) [m]
SOURCE_MARKERS = {0: ("o", "measured"), 1: ("s", "interpolated"), 2: (">", "extrapolated"),
                  3: ("x", "unknown")}


def scene(scenario: str, seed: int):
    """(scenario, HeightMap, [BoxObstacle]) of a generated trial."""
    opts = _envs.ScenarioOptions()
    opts.kind = scenario
    sc = _envs.generate_scenario(opts, seed)
    ox, oy = sc.origin
    terrain = D.HeightMap(sc.heights, sc.spacing, ox, oy)
    boxes = [D.BoxObstacle(r[0:3], r[3:6], r[6], r[7], r[8]) for r in np.asarray(sc.obstacles)]
    return sc, terrain, boxes


def chassis_pose(sc, k: int, step: float = 0.4):
    """Chassis position and rotation (heading only) at frame k along the start heading."""
    h = sc.start_heading
    x = sc.start_x + k * step * math.cos(h)
    y = sc.start_y + k * step * math.sin(h)
    rot = np.array([[math.cos(h), -math.sin(h), 0.0], [math.sin(h), math.cos(h), 0.0], [0, 0, 1.0]])
    return np.array([x, y, sc.height(x, y) + CHASSIS_HEIGHT]), rot


#: Units of summary.csv's columns (its header reads ``name [unit]``).
SUMMARY_UNITS = {"frame": "-", "points": "-", "cells": "-", "rms": "m", "normalised_variance": "-",
                 "coverage": "-"}


def frame_metrics(mapper: "P.StereoMapper", radius: float = 3.0) -> dict[str, float]:
    """RMS error, normalised-error variance and coverage over cells within `radius` of the camera."""
    m = mapper.map
    h, v = m.heights, m.variances
    n = m.cells
    xs = m.origin_x + np.arange(n) * m.resolution
    ys = m.origin_y + np.arange(n) * m.resolution
    cam = mapper.last_frame.left_pose[:3, 3]
    ii = np.where(np.abs(xs - cam[0]) <= radius)[0]
    jj = np.where(np.abs(ys - cam[1]) <= radius)[0]
    X, Y = np.meshgrid(xs[ii], ys[jj], indexing="ij")
    inside = np.hypot(X - cam[0], Y - cam[1]) <= radius
    hh, vv = h[np.ix_(ii, jj)], v[np.ix_(ii, jj)]
    known = inside & np.isfinite(hh)
    truth = mapper.raycaster.surface_heights(X, Y)
    err = (hh - truth)[known]
    nz = err / np.sqrt(vv[known])
    return {"cells": int(known.sum()), "rms": float(np.sqrt(np.mean(err**2))) if err.size else math.nan,
            "normalised_variance": float(np.mean(nz**2)) if nz.size else math.nan,
            "coverage": float(known.sum() / max(inside.sum(), 1))}


def plot_frame(path: str, mapper, sampler, position, rotation, k: int, window: float = 6.0) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fr, m = mapper.last_frame, mapper.map
    n = m.cells
    xs = m.origin_x + np.arange(n) * m.resolution
    ys = m.origin_y + np.arange(n) * m.resolution
    # a window ahead of the rover (world-aligned): 1 m behind to window - 1 m ahead
    ii = np.where((xs >= position[0] - 1.0) & (xs <= position[0] + window - 1.0))[0]
    jj = np.where(np.abs(ys - position[1]) <= window / 2)[0]
    X, Y = np.meshgrid(xs[ii], ys[jj], indexing="ij")
    fused = m.heights[np.ix_(ii, jj)]
    truth = mapper.raycaster.surface_heights(X, Y)
    # imshow extent: column j (y) left to right, row i (x) bottom to top; the y axis is then
    # reversed (y to the left, x up, as Fig. 11)
    extent = (ys[jj[0]], ys[jj[-1]], xs[ii[0]], xs[ii[-1]])
    lo, hi = np.nanpercentile(truth, 1), np.nanpercentile(truth, 99.5)

    fig, ax = plt.subplots(2, 3, figsize=(15, 9.5))
    ax[0, 0].imshow(fr.left, cmap="gray", vmin=0, vmax=255)
    ax[0, 0].set_title(f"left image, frame {k}")
    disp = ax[0, 1].imshow(fr.disparity, cmap="viridis")
    ax[0, 1].set_title(f"StereoBM disparity [px] ({fr.points.shape[0]} points)")
    fig.colorbar(disp, ax=ax[0, 1], shrink=0.7)
    cov = ax[0, 2].imshow(np.isfinite(fused).astype(float), cmap="Greys", vmin=0, vmax=1,
                          extent=extent, origin="lower")
    ax[0, 2].set_title("coverage (black = seen)")
    for a, data, title in ((ax[1, 0], fused, "fused elevation map [m]"),
                           (ax[1, 1], truth, "ground truth [m]")):
        im = a.imshow(data, cmap="terrain", vmin=lo, vmax=hi, extent=extent, origin="lower")
        a.set_title(title)
        fig.colorbar(im, ax=a, shrink=0.7)
    err = ax[1, 2].imshow(fused - truth, cmap="RdBu_r", vmin=-0.1, vmax=0.1, extent=extent,
                          origin="lower")
    ax[1, 2].set_title("error: map - truth [m]")
    fig.colorbar(err, ax=ax[1, 2], shrink=0.7)
    # the 12 elevation samples of §4.2 (chassis frame -> world), marked by how they were obtained
    values, sources = sampler.sample(position, rotation, m)
    pts = np.array([rotation[:2, :2] @ np.asarray(sampler.point(i)) + position[:2] for i in range(12)])
    for a in (ax[1, 0], ax[0, 2]):
        for src, (marker, label) in SOURCE_MARKERS.items():
            sel = np.asarray(sources) == src
            if sel.any():
                a.scatter(pts[sel, 1], pts[sel, 0], marker=marker, c="tab:blue", s=30, label=label)
        a.legend(loc="lower right", fontsize=7)
    for a in (ax[0, 2], ax[1, 0], ax[1, 1], ax[1, 2]):
        a.set_xlim(extent[1], extent[0])  # y increasing to the left
        a.set_xlabel("y [m]")
        a.set_ylabel("x [m]")
    fig.tight_layout()
    fig.savefig(path, dpi=80)
    plt.close(fig)


def run(scenario: str, out: str, frames: int = 4, seed: int = 0,
        algorithm: str = "bm") -> list[dict[str, float]]:
    if frames < 1:
        raise ValueError(f"frames must be >= 1, got {frames}")
    if algorithm not in ("bm", "sgbm"):
        raise ValueError(f"algorithm must be 'bm' or 'sgbm', got {algorithm!r}")
    os.makedirs(out, exist_ok=True)
    sc, terrain, boxes = scene(scenario, seed)
    opts = P.StereoMapperOptions()
    if algorithm == "sgbm":
        opts.matcher.algorithm = P.StereoAlgorithm.SemiGlobal
        opts.matcher.block_size = 5
    mapper = P.StereoMapper(terrain, boxes, opts)
    sampler_opts = S.ElevationSamplingOptions()
    sampler_opts.ground_z = -CHASSIS_HEIGHT
    sampler = S.ElevationSampler(sampler_opts)
    rows = []
    for k in range(frames):
        position, rotation = chassis_pose(sc, k)
        mapper.update(2.0 * k, position, rotation)  # 0.5 Hz: one fusion per call
        row = {"frame": k, "points": int(mapper.last_frame.stats.fused_points),
               **frame_metrics(mapper)}
        rows.append(row)
        plot_frame(os.path.join(out, f"frame_{k}.png"), mapper, sampler, position, rotation, k)
        print(f"frame {k}: {row['points']} points, {row['cells']} cells within 3 m, "
              f"RMS {row['rms'] * 100:.2f} cm, normalised variance {row['normalised_variance']:.2f}, "
              f"coverage {row['coverage'] * 100:.0f} %")
    with open(os.path.join(out, "summary.csv"), "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(header(rows[0], SUMMARY_UNITS))
        w.writerows([r[k] for k in rows[0]] for r in rows)
    print(f"wrote {frames} frame views and summary.csv to {out}")
    return rows


def add_parser(subparsers) -> None:
    p = subparsers.add_parser("perception", help="stereo cameras -> StereoBM -> elevation map, "
                              "with Fig. 11's views (seed 004 §2.4)", description=__doc__)
    p.add_argument("--scenario", default="rockfield", help="scenario name (default rockfield)")
    p.add_argument("--out", default="out/perception", help="output folder (default out/perception)")
    p.add_argument("--frames", type=int, default=4, help="frames to fuse (default 4)")
    p.add_argument("--seed", type=_args.seed, default=0, help="scenario seed (default 0)")
    p.add_argument("--algorithm", default="bm", help="bm (StereoBM, default) or sgbm")
    p.set_defaults(func=main_args)


def main_args(args: argparse.Namespace) -> int:
    run(args.scenario, args.out, args.frames, args.seed, args.algorithm)
    return 0


def main(**options) -> int:
    """``ernest perception`` from Python: one keyword per option, named as on the command line with
    underscores (``ernest perception --help``), checked as there (``cli.run``), e.g.
    ``main(scenario="rockfield", out="out/perception")``. Returns the exit status; errors raise."""
    from .cli import run

    return run("perception", **options)
