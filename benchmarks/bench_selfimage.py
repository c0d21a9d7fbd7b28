"""Self-imaging benchmark, Python half (seed 003 §5.2): per leg pose of the walker
scene, the watershed segmentation of the 640 x 480 hazcam depth map through the bindings against
the stereo matching of the same camera's pair (StereoBM with the left-right check, our default) as
the reference, medians, one OpenCV thread; and a figure of both time distributions with the IoU.

    ./run bench selfimage            # writes out/bench/selfimage_timing.png
"""

from __future__ import annotations

import os
import statistics
import sys
import time

import numpy as np

from ernest_cpp import perception as P
from ernest_cpp import perception_selfimage as SI
from ernest_cpp import walker as W


def times_ms(fn, repeats: int) -> list[float]:
    out = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        fn()
        out.append(1e3 * (time.perf_counter() - t0))
    return out


def main(out_dir: str = "out/bench") -> None:
    P.set_opencv_threads(1)
    model = W.WalkerModel(W.sdm_b_parameters())
    scene = P.self_image_scene(model, 3)
    caster = P.Raycaster(scene.terrain, list(scene.rocks))
    camera = P.walker_hazcam()
    seg, bm = P.SelfImageSegmenter(), P.StereoMatcher()
    rows = []
    for leg, lift, reach in SI.POSES:
        image, depth, labels, pose = SI.render_pose(model, scene, caster, camera, leg, lift, reach)
        q = np.array(scene.q)
        q[:, leg] = P.raised_leg(model, leg, lift, reach)
        right_pose = pose.copy()
        right_pose[:3, 3] += camera.baseline * pose[:3, 0]
        right, _, _ = P.render_with_robot(caster, P.walker_solids(model, scene.body, q), right_pose,
                                          camera, P.SelfRenderOptions(), 1)
        t_seg = times_ms(lambda: seg.segment(depth, camera), 9)
        t_bm = times_ms(lambda: bm.compute(image, right), 9)
        iou = P.mask_iou(seg.segment(depth, camera).removed, (labels == leg + 1).astype(np.uint8))
        rows.append((leg, lift, reach, iou, t_seg, t_bm))
    print("| leg | lift [m] | reach [m] | IoU | segmentation median [ms] | StereoBM median [ms] |")
    print("|---|---|---|---|---|---|")
    for leg, lift, reach, iou, t_seg, t_bm in rows:
        print(f"| {leg} | {lift:.2f} | {reach:.2f} | {iou:.3f} | {statistics.median(t_seg):.2f} | "
              f"{statistics.median(t_bm):.2f} |")
    all_seg = [t for r in rows for t in r[4]]
    all_bm = [t for r in rows for t in r[5]]
    ms, mb = statistics.median(all_seg), statistics.median(all_bm)
    print(f"\nall poses: segmentation {ms:.2f} ms, StereoBM {mb:.2f} ms (reference), ratio {ms / mb:.2f}")

    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(8, 4.5))
    x = np.arange(len(rows))
    ax.boxplot([r[5] for r in rows], positions=x - 0.18, widths=0.3, patch_artist=True,
               boxprops={"facecolor": "0.8"})
    ax.boxplot([r[4] for r in rows], positions=x + 0.18, widths=0.3, patch_artist=True,
               boxprops={"facecolor": "tab:green"})
    ax.set_xticks(x, [f"leg {r[0]}\nlift {r[1]:.2f} m\nIoU {r[3]:.3f}" for r in rows])
    ax.set_ylabel("time per 640 x 480 frame [ms], 1 thread")
    ax.set_ylim(0, 1.4 * max(max(r[5]) for r in rows))
    ax.legend([plt.Rectangle((0, 0), 1, 1, fc="0.8"), plt.Rectangle((0, 0), 1, 1, fc="tab:green")],
              [f"StereoBM + LR check (reference), median {mb:.1f} ms",
               f"watershed self-image removal, median {ms:.1f} ms"], loc="upper center")
    ax.set_title("Self-image segmentation vs the stereo matching it follows (seed 003 §5.2)")
    fig.tight_layout()
    os.makedirs(out_dir, exist_ok=True)
    path = os.path.join(out_dir, "selfimage_timing.png")
    fig.savefig(path, dpi=90)
    print(f"figure: {path}")


if __name__ == "__main__":
    main(*sys.argv[1:2])
