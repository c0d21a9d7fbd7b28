"""Self-imaging of the wheel-on-leg walker (seed 003 §4.3, §5.2). With a leg raised mid-step, the
hazard camera facing it sees the leg; the C++ renderer ray-casts the terrain and the walker's links
(capsules) and wheels (cylinders) together into one depth map, and the watershed segmentation of
that depth map (OpenCV ``cv::watershed``) removes the segment of the right size, closest to the
camera and not connected to the ground before the map is fused. :func:`demo` runs several legs
and poses, scores the removed mask against the rendered leg mask (intersection over union), fuses
the frame with and without the removal and writes one figure; ``ernest footfall`` calls it.
"""

from __future__ import annotations

import argparse
import json
import os
import time

import numpy as np

from . import _args
from . import perception as P
from . import walker as W

#: (leg, lift [m], reach [m]): different legs, low to high mid-step lifts, in and out
POSES = ((0, 0.4, 0.1), (1, 0.25, 0.0), (3, 0.55, 0.2), (4, 0.3, -0.15), (5, 0.45, 0.25))
#: a map cell counts as a false obstacle when it stands this far above the true surface [m]
TOLERANCE = 0.05


def render_pose(model, scene, caster, camera, leg: int, lift: float, reach: float,
                sigma: float = 0.3):
    """(image, depth, labels, camera pose) of `leg` raised by `lift`, moved out by `reach`."""
    q = np.array(scene.q)
    q[:, leg] = P.raised_leg(model, leg, lift, reach)
    pose = P.hazcam_pose(model, scene.body, leg, camera)
    ro = P.SelfRenderOptions()
    ro.disparity_sigma = sigma
    image, depth, labels = P.render_with_robot(caster, P.walker_solids(model, scene.body, q), pose,
                                               camera, ro, leg)
    return image, depth, labels, pose


def fused_map(depth, camera, pose, body, removed=None, max_depth: float = 6.0) -> "P.ElevationMap":
    """An 8 m, 2 cm elevation map centred on the body holding the frame (minus `removed`)."""
    mo = P.ElevationMapOptions()
    mo.length, mo.resolution = 8.0, 0.02
    m = P.ElevationMap(mo)
    m.move_to(body[0, 3], body[1, 3])
    mask = np.zeros((0, 0), np.uint8) if removed is None else removed
    points, _ = P.depth_to_points(depth, camera, mask, max_depth)
    m.fuse_cloud(points, pose, camera)
    return m


def map_error(m, caster):
    """(height - true surface height) per cell (NaN in holes) and the cell centres' x, y axes."""
    n = m.cells
    xs = m.origin_x + np.arange(n) * m.resolution
    ys = m.origin_y + np.arange(n) * m.resolution
    X, Y = np.meshgrid(xs, ys, indexing="ij")
    truth = caster.surface_heights(X, Y)
    return m.heights - truth, xs, ys


def under_leg(depth, leg_mask, camera, pose, shape, xs, ys):
    """Boolean grid of the map cells holding a point of a (rendered) leg pixel."""
    points, _ = P.depth_to_points(depth, camera, (~leg_mask).astype(np.uint8), 6.0)
    world = points @ pose[:3, :3].T + pose[:3, 3]
    res = xs[1] - xs[0]
    i = np.rint((world[:, 0] - xs[0]) / res).astype(int)
    j = np.rint((world[:, 1] - ys[0]) / res).astype(int)
    ok = (i >= 0) & (j >= 0) & (i < shape[0]) & (j < shape[1])
    grid = np.zeros(shape, bool)
    grid[i[ok], j[ok]] = True
    return grid


def _figure(path, image, depth, labels, result, leg, before, after, xs, ys, iou):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    truth = labels == leg + 1
    removed = result.removed.astype(bool)
    fig, ax = plt.subplots(2, 3, figsize=(15, 9))
    shown = np.where(np.isfinite(depth), depth, np.nan)
    im = ax[0, 0].imshow(shown, cmap="viridis_r", vmax=np.nanpercentile(shown, 99))
    fig.colorbar(im, ax=ax[0, 0], label="depth z [m]")
    ax[0, 0].set_title(f"hazcam depth, leg {leg} raised (terrain + leg)")
    rng = np.random.default_rng(0)
    colours = rng.uniform(0.15, 1.0, size=(result.segment_count + 2, 3))
    colours[1] = 0.0
    ax[0, 1].imshow(colours[result.segments])
    ax[0, 1].contour(removed, levels=[0.5], colors="w", linewidths=1.0)
    ax[0, 1].set_title(f"watershed: {result.segment_count} segments, {result.object_count} objects "
                       "(white: removed)")
    overlay = np.zeros(truth.shape + (3,))
    overlay[truth & removed] = (0.1, 0.75, 0.1)
    overlay[removed & ~truth] = (0.9, 0.1, 0.1)
    overlay[truth & ~removed] = (0.1, 0.3, 0.95)
    ax[0, 2].imshow(image, cmap="gray")
    ax[0, 2].imshow(overlay, alpha=0.6)
    ax[0, 2].set_title(f"removed vs rendered leg: IoU {iou:.3f}\n(green both, red removed only, "
                       "blue leg missed)")
    # the map around the raised leg's wheel
    rows = np.where(np.isfinite(before).any(axis=1))[0]
    cols = np.where(np.isfinite(before).any(axis=0))[0]
    ext = (ys[cols[0]], ys[cols[-1]], xs[rows[0]], xs[rows[-1]])
    for a, err, title in ((ax[1, 0], before, "map error without removal"),
                          (ax[1, 1], after, "map error with the leg removed")):
        im = a.imshow(err[rows[0]:rows[-1] + 1, cols[0]:cols[-1] + 1], origin="lower", extent=ext,
                      cmap="RdBu_r", vmin=-0.5, vmax=0.5, aspect="equal")
        fig.colorbar(im, ax=a, label="height - true surface [m]")
        a.set_title(f"{title}: max {np.nanmax(err):.2f} m")
        a.set_xlabel("y [m]")
        a.set_ylabel("x [m]")
    fin = before[np.isfinite(before)]
    fia = after[np.isfinite(after)]
    ax[1, 2].hist([fin, fia], bins=60, range=(-0.2, 1.2), log=True,
                  label=["without removal", "with removal"])
    ax[1, 2].axvline(TOLERANCE, color="k", ls="--", lw=0.8, label=f"{TOLERANCE} m")
    ax[1, 2].set_xlabel("map height - true surface [m]")
    ax[1, 2].set_ylabel("cells")
    ax[1, 2].legend()
    ax[1, 2].set_title("cell errors")
    for a in ax[0]:
        a.set_xticks([])
        a.set_yticks([])
    fig.suptitle("Self-imaging (seed 003 §4.3, §5.2): the raised leg in the depth map, removed by "
                 "watershed segmentation before fusion")
    fig.tight_layout()
    fig.savefig(path, dpi=90)
    plt.close(fig)


def demo(out_dir: str, seed: int = 3, poses=POSES) -> dict:
    """Runs the self-imaging pipeline on `poses` of the SDM-B walker's scene; writes
    ``selfimage.png`` (first pose) and ``selfimage.json`` in `out_dir`; returns the IoU per pose,
    their minimum, and the worst map error above the true surface (the false obstacle) in the
    cells the leg covers, with and without the removal, for the first pose."""
    os.makedirs(out_dir, exist_ok=True)
    model = W.WalkerModel(W.sdm_b_parameters())
    scene = P.self_image_scene(model, seed)
    caster = P.Raycaster(scene.terrain, list(scene.rocks))
    camera = P.walker_hazcam()
    seg = P.SelfImageSegmenter()
    out: dict = {"poses": [], "figure": os.path.join(out_dir, "selfimage.png")}
    for k, (leg, lift, reach) in enumerate(poses):
        image, depth, labels, pose = render_pose(model, scene, caster, camera, leg, lift, reach)
        t0 = time.perf_counter()
        result = seg.segment(depth, camera)
        seconds = time.perf_counter() - t0
        iou = P.mask_iou(result.removed, (labels == leg + 1).astype(np.uint8))
        out["poses"].append({"leg": leg, "lift": lift, "reach": reach, "iou": iou,
                             "found": result.found(), "segments": result.segment_count,
                             "segment_ms": 1e3 * seconds})
        if k == 0:
            before, xs, ys = map_error(fused_map(depth, camera, pose, scene.body), caster)
            after, _, _ = map_error(fused_map(depth, camera, pose, scene.body, result.removed), caster)
            leg_cells = under_leg(depth, labels == leg + 1, camera, pose, before.shape, xs, ys)
            out["false_obstacle_before_m"] = float(np.nanmax(np.where(leg_cells, before, np.nan)))
            known = after[leg_cells & np.isfinite(after)]
            out["false_obstacle_after_m"] = float(known.max()) if known.size else 0.0
            out["leg_cells_known_after"] = int(known.size)
            out["leg_cells"] = int(leg_cells.sum())
            _figure(out["figure"], image, depth, labels, result, leg, before, after, xs, ys, iou)
    out["min_iou"] = min(p["iou"] for p in out["poses"])
    with open(os.path.join(out_dir, "selfimage.json"), "w") as f:
        json.dump(out, f, indent=2)
    return out


def main(argv=None) -> dict:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--out", default="out/selfimage")
    ap.add_argument("--seed", type=_args.seed, default=3)
    args = ap.parse_args(argv)
    res = demo(args.out, args.seed)
    print(json.dumps({k: v for k, v in res.items() if k != "poses"}, indent=2))
    for p in res["poses"]:
        print(f"leg {p['leg']} lift {p['lift']} reach {p['reach']}: IoU {p['iou']:.3f}")
    return res


if __name__ == "__main__":
    main()
