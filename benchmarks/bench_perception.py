"""Perception benchmark, Python half, each against a reference in the same run (medians):

1. StereoBM on one 640x480 pair of the rock field: ours (Debian OpenCV through the C++ core) vs the
   same call through cv2 (opencv-python-headless), both on one thread.
2. Fusing one frame's point cloud into the 10 m x 10 m, 1 cm map: ours (C++, target <= 10 ms on
   one core) vs a straightforward numpy implementation of the same update (same noise model,
   per-cell averaging, innovation gate, Kalman update of [17]); the two maps are compared.
3. Policy steps per second of a terrain_source="stereo" env against the ground-truth env.

    ./run bench perception
"""

from __future__ import annotations

import statistics
import time

import cv2
import numpy as np

import ernest_cpp.envs as E
from ernest_cpp import perception as P
from ernest_cpp.perception_demo import chassis_pose, scene


def median_ms(fn, repeats: int) -> float:
    times = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        fn()
        times.append(1e3 * (time.perf_counter() - t0))
    return statistics.median(times)


class NumpyMap:
    """The same update as ElevationMap.fuse_cloud, in numpy (window fixed: no move)."""

    def __init__(self, o: P.ElevationMapOptions, centre_x: float, centre_y: float):
        self.o = o
        self.n = int(round(o.length / o.resolution))
        self.gi0 = int(np.floor(centre_x / o.resolution)) - self.n // 2
        self.gj0 = int(np.floor(centre_y / o.resolution)) - self.n // 2
        self.h = np.full(self.n * self.n, np.nan)
        self.v = np.full(self.n * self.n, np.inf)

    def fuse_cloud(self, pts: np.ndarray, pose: np.ndarray, cam: P.StereoCameraParameters):
        o, n = self.o, self.n
        r, t = pose[:3, :3], pose[:3, 3]
        ok = np.isfinite(pts).all(axis=1) & (pts[:, 2] > 0)
        p = pts[ok]
        w = p @ r.T + t
        k = o.disparity_sigma / (cam.focal() * cam.baseline)
        var = ((p @ r[2]) * p[:, 2] * k) ** 2 + o.pose_variance
        i = np.floor(w[:, 0] / o.resolution).astype(np.int64) - self.gi0
        j = np.floor(w[:, 1] / o.resolution).astype(np.int64) - self.gj0
        inside = (i >= 0) & (i < n) & (j >= 0) & (j < n)
        cell = (i * n + j)[inside]
        cnt = np.bincount(cell, minlength=n * n)
        touched = np.nonzero(cnt)[0]
        meas = np.bincount(cell, w[inside, 2], n * n)[touched] / cnt[touched]
        mvar = np.maximum(np.bincount(cell, var[inside], n * n)[touched] / cnt[touched],
                          o.min_variance)
        h, v = self.h[touched], self.v[touched]
        new = ~np.isfinite(h)
        innov, s = meas - h, v + mvar
        gated = ~new & (innov**2 > o.mahalanobis_threshold**2 * s)
        upd = ~new & ~gated
        h_out, v_out = h.copy(), v.copy()
        h_out[new], v_out[new] = meas[new], mvar[new]
        v_out[gated] = v[gated] + o.multi_height_noise
        h_out[upd] = h[upd] + v[upd] / s[upd] * innov[upd]
        v_out[upd] = np.maximum(v[upd] * mvar[upd] / s[upd], o.min_variance)
        self.h[touched], self.v[touched] = h_out, v_out


def env_rate(terrain_source: str, steps: int, stereo=None) -> float:
    env = E.ErnestEnv("rockfield", terrain_source=terrain_source, stereo=stereo)
    env.reset(seed=0)
    t0 = time.perf_counter()
    for _ in range(steps):
        _, _, term, trunc, _ = env.step(np.array([1.0, 0.0, 0.0], np.float32))
        if term or trunc:
            env.reset()
    return steps / (time.perf_counter() - t0)


def main() -> None:
    sc, terrain, boxes = scene("rockfield", 0)
    opts = P.StereoMapperOptions()
    mapper = P.StereoMapper(terrain, boxes, opts)
    pos, rot = chassis_pose(sc, 0)
    mapper.capture(pos, rot)
    fr = mapper.last_frame
    left, right = np.ascontiguousarray(fr.left), np.ascontiguousarray(fr.right)

    # 1. StereoBM: ours vs cv2, one thread each
    mo = opts.matcher
    checked = P.StereoMatcher(mo)  # default: with the left-right check (a second, mirrored match)
    mo.max_lr_difference = None
    ours = P.StereoMatcher(mo)     # the same single StereoBM call as cv2's
    P.set_opencv_threads(1)
    cv2.setNumThreads(1)
    bm = cv2.StereoBM_create(numDisparities=mo.num_disparities, blockSize=mo.block_size)
    bm.setUniquenessRatio(mo.uniqueness_ratio)
    bm.setTextureThreshold(mo.texture_threshold)
    bm.setSpeckleWindowSize(mo.speckle_window)
    bm.setSpeckleRange(mo.speckle_range)
    bm.setPreFilterCap(mo.pre_filter_cap)
    t_ours = median_ms(lambda: ours.compute(left, right), 21)
    t_checked = median_ms(lambda: checked.compute(left, right), 21)
    t_cv2 = median_ms(lambda: bm.compute(left, right), 21)
    t_cv2_float = median_ms(lambda: bm.compute(left, right).astype(np.float32) / 16.0, 21)
    print(f"StereoBM 640x480, 1 thread: ours {t_ours:.2f} ms (incl. conversion to float px), "
          f"cv2 {t_cv2:.2f} ms raw / {t_cv2_float:.2f} ms with the same conversion "
          f"(ratio ours / cv2 {t_ours / t_cv2_float:.2f}); OpenCV C++ {cv2.__version__} wheel vs "
          f"Debian's; ours with the left-right check (default) {t_checked:.2f} ms")

    # 2. fusion: C++ vs numpy on the same cloud
    pts, pose = np.ascontiguousarray(fr.points), fr.left_pose
    cpp_map = P.ElevationMap(opts.map)
    cpp_map.move_to(pos[0], pos[1])
    np_map = NumpyMap(opts.map, pos[0], pos[1])
    cpp_map.fuse_cloud(pts, pose, opts.camera)
    np_map.fuse_cloud(pts, pose, opts.camera)
    for _ in range(2):  # exercise the Kalman branch in both
        cpp_map.fuse_cloud(pts, pose, opts.camera)
        np_map.fuse_cloud(pts, pose, opts.camera)
    hc = cpp_map.heights.ravel()
    hn = np_map.h.reshape(np_map.n, np_map.n).ravel()
    same_holes = np.array_equal(np.isnan(hc), np.isnan(hn))
    diff = np.nanmax(np.abs(hc - hn))
    t_cpp = median_ms(lambda: cpp_map.fuse_cloud(pts, pose, opts.camera), 21)
    t_np = median_ms(lambda: np_map.fuse_cloud(pts, pose, opts.camera), 7)
    print(f"fuse one frame ({pts.shape[0]} points) into the {np_map.n}x{np_map.n} map: "
          f"C++ {t_cpp:.2f} ms (target <= 10), numpy {t_np:.1f} ms, numpy / C++ "
          f"{t_np / t_cpp:.1f}x; maps agree: same holes {same_holes}, max |dh| {diff:.1e} m "
          f"(float32 cells)")

    # 3. env policy-step rate
    P.set_opencv_threads(0)
    r_truth = env_rate("truth", 40)
    r_stereo = env_rate("stereo", 40)
    small = P.StereoMapperOptions()
    small.camera.width, small.camera.height = 320, 240
    r_small = env_rate("stereo", 40, small)
    print(f"ErnestEnv rockfield, policy steps/s: ground truth {r_truth:.1f}, stereo 640x480 "
          f"{r_stereo:.1f} (stereo / truth {r_stereo / r_truth:.3f}), stereo 320x240 "
          f"{r_small:.1f} ({r_small / r_truth:.3f}); a frame every 4th step (0.5 Hz)")


if __name__ == "__main__":
    main()
