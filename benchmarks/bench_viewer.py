"""The 3D viewer's library, viser or rerun-sdk, on the same scene: a 200 x 200 height map, 40
boxes and the rover (six bodies, four load arrows, four time series), 121 frames (a 60 s episode
at the environments' 2 Hz).

    python benchmarks/bench_viewer.py --lib viser [--browser]
    python benchmarks/bench_viewer.py --lib rerun [--browser]   # in an environment with rerun-sdk

Prints: start-up (import, server up, scene sent) [s], frame updates the server side sends per
second, the recording of the 60 s episode [MB] and, with --browser, headless Chromium's time to a
drawn scene [s] and its frame rate while the rover moves [frames/s] (software WebGL, 800 x 500).
benchmarks/RESULTS.md ("3D viewer") has the figures and the choice.
"""

from __future__ import annotations

import argparse
import math
import os
import sys
import tempfile
import time

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(HERE, "..", "python"))

N_FRAMES = 121
GRID = 200
SPACING = 0.05
GEOMETRY = {"wheelbase": 0.86, "track": 0.8, "wheel_radius": 0.17, "wheel_width": 0.13,
            "gimbal_point": [0.43, 0.0, 0.25], "chassis_com": [-0.12, 0.0, 0.33]}


def scene_data(seed: int = 0) -> dict:
    rng = np.random.default_rng(seed)
    x = np.arange(GRID) * SPACING
    X, Y = np.meshgrid(x, x, indexing="ij")
    heights = (0.05 * np.sin(X * 1.3) * np.cos(Y * 0.9) + 0.02 * rng.standard_normal((GRID, GRID))
               ).astype(np.float32)
    boxes = np.zeros((40, 9), np.float32)
    boxes[:, 0:2] = rng.uniform(0.5, 9.5, (40, 2))
    boxes[:, 3:6] = rng.uniform(0.1, 0.3, (40, 3))
    boxes[:, 2] = boxes[:, 5] / 2
    boxes[:, 6] = rng.uniform(-math.pi, math.pi, 40)
    t = np.arange(N_FRAMES) * 0.5
    pos = np.stack([1.0 + 0.12 * t, 5.0 + 0.1 * np.sin(t / 5), 0.17 + 0.02 * np.sin(t)], 1)
    quat = np.tile([1.0, 0.0, 0.0, 0.0], (N_FRAMES, 1))
    gimbal = np.stack([0.3 * np.sin(t / 3), 0.15 * np.cos(t / 3)], 1)
    offs = np.array([[0.43, 0.4, 0.0], [0.43, -0.4, 0.0], [-0.43, 0.4, 0.0], [-0.43, -0.4, 0.0]])
    wheels = pos[:, None, :] + offs[None, :, :]
    loads = 184.0 + 40.0 * np.sin(t[:, None] + np.arange(4)[None, :])
    frames = {"time": t, "position": pos, "quaternion": quat, "gimbal": gimbal,
              "wheel_position": wheels, "wheel_load": loads,
              "action": np.stack([np.full_like(t, 0.8), np.sin(t / 3), np.cos(t / 3)], 1),
              "power": np.abs(rng.standard_normal((N_FRAMES, 6))) * 20, "energy": np.cumsum(t)}
    return {"heights": heights, "obstacles": boxes, "frames": frames}


def bench_viser(data: dict, browser: bool) -> dict:
    t0 = time.perf_counter()
    from ernest_cpp.viewer.app import Player
    from ernest_cpp.viewer.recording import Recording, save_recording

    frames = {k: np.asarray(v, np.float64 if k == "time" else np.float32)
              for k, v in data["frames"].items()}
    rec = Recording(meta={"kind": "rover", "scenario": "synthetic", "geometry": GEOMETRY},
                    heights=data["heights"], spacing=SPACING, origin=(0.0, 0.0),
                    obstacles=data["obstacles"], path=(0.0, 5.0, 0.0), frames=frames)
    player = Player(rec, port=0)
    startup = time.perf_counter() - t0
    n = 0
    t1 = time.perf_counter()
    while time.perf_counter() - t1 < 3.0:
        player._show(n % N_FRAMES)
        n += 1
    rate = n / (time.perf_counter() - t1)
    with tempfile.TemporaryDirectory() as tmp:
        path = save_recording(rec, os.path.join(tmp, "episode.npz"))
        size = os.path.getsize(path) / 1e6
    out = {"startup_s": startup, "server_updates_per_s": rate, "recording_MB": size}
    if browser:
        out.update(browser_figures(player.url, lambda k: player._show(k % N_FRAMES)))
    player.close()
    return out


def bench_rerun(data: dict, browser: bool) -> dict:
    t0 = time.perf_counter()
    import rerun as rr

    rr.init("ernest_viewer_bench")
    grpc = rr.serve_grpc()
    h = data["heights"]
    x = np.arange(GRID) * SPACING
    X, Y = np.meshgrid(x, x, indexing="ij")
    verts = np.stack([X.ravel(), Y.ravel(), h.ravel()], 1)
    idx = np.arange(GRID * GRID).reshape(GRID, GRID)
    a, b, c, d = idx[:-1, :-1].ravel(), idx[1:, :-1].ravel(), idx[1:, 1:].ravel(), idx[:-1, 1:].ravel()
    faces = np.concatenate([np.stack([a, b, c], 1), np.stack([a, c, d], 1)])
    u = (h.ravel() - h.min()) / (h.max() - h.min())
    colours = (np.stack([70 + 160 * u, 90 + 130 * u, 120 + 80 * u], 1)).astype(np.uint8)

    def log_static():
        rr.log("terrain", rr.Mesh3D(vertex_positions=verts, triangle_indices=faces,
                                    vertex_colors=colours), static=True)
        o = data["obstacles"]
        rr.log("obstacles", rr.Boxes3D(centers=o[:, :3], sizes=o[:, 3:6],
                                       colors=(120, 118, 112), fill_mode="solid"), static=True)
        rr.log("rover/chassis/body", rr.Boxes3D(centers=[(-0.04, 0, 0.33)], sizes=[(0.69, 0.44, 0.16)],
                                                colors=(225, 70, 25), fill_mode="solid"), static=True)
        rr.log("rover/bogie/axle", rr.Boxes3D(centers=[(0, 0, -0.19)], sizes=[(0.08, 0.67, 0.06)],
                                              colors=(40, 110, 225), fill_mode="solid"), static=True)

    f = data["frames"]

    def log_frame(k: int):
        rr.set_time("t", duration=float(f["time"][k]))
        rr.log("rover/chassis", rr.Transform3D(translation=f["position"][k],
                                               quaternion=rr.Quaternion(xyzw=np.roll(f["quaternion"][k], -1))))
        rr.log("rover/bogie", rr.Transform3D(translation=f["position"][k] + [0.43, 0, 0.25]))
        for w in range(4):
            rr.log(f"rover/wheel{w}", rr.Ellipsoids3D(centers=[f["wheel_position"][k][w]],
                                                      half_sizes=[(0.17, 0.065, 0.17)],
                                                      colors=(45, 45, 50), fill_mode="solid"))
        base = f["wheel_position"][k] - [0, 0, 0.17]
        rr.log("forces", rr.Arrows3D(origins=base, vectors=np.c_[np.zeros((4, 2)),
                                                                 f["wheel_load"][k] * 0.4 / 184]))
        for w in range(4):
            rr.log(f"plots/wheel_load/{w}", rr.Scalars(f["wheel_load"][k][w]))
        rr.log("plots/gimbal/yaw", rr.Scalars(f["gimbal"][k][0]))
        rr.log("plots/gimbal/roll", rr.Scalars(f["gimbal"][k][1]))
        rr.log("plots/power", rr.Scalars(float(np.sum(f["power"][k]))))

    log_static()
    startup = time.perf_counter() - t0
    n = 0
    t1 = time.perf_counter()
    while time.perf_counter() - t1 < 3.0:
        log_frame(n % N_FRAMES)
        n += 1
    rate = n / (time.perf_counter() - t1)
    with tempfile.TemporaryDirectory() as tmp:
        path = os.path.join(tmp, "episode.rrd")
        rec = rr.RecordingStream("ernest_viewer_bench_file")
        with rec:
            rr.save(path, recording=rec)
            log_static()
            for k in range(N_FRAMES):
                log_frame(k)
            rec.flush()
        rec.disconnect()
        size = os.path.getsize(path) / 1e6
    out = {"startup_s": startup, "server_updates_per_s": rate, "recording_MB": size}
    if browser:
        from urllib.parse import quote

        port = 9091
        rr.serve_web_viewer(web_port=port, open_browser=False, connect_to=grpc)
        out.update(browser_figures(f"http://localhost:{port}/?url={quote(grpc, safe='')}",
                                   log_frame, white_background=False))
    return out


def browser_figures(url: str, push, white_background: bool = True) -> dict:
    import importlib.util  # the module alone: no ernest_cpp needed where rerun is installed

    spec = importlib.util.spec_from_file_location(
        "viewer_browser", os.path.join(HERE, "..", "python", "ernest_cpp", "viewer", "browser.py"))
    B = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(B)

    driver = B.start_browser((800, 500))
    try:
        t0 = time.perf_counter()
        driver.get(url)
        first = None
        while time.perf_counter() - t0 < 90:
            img = B.grab(driver)
            if white_background and B.scene_drawn(img):
                first = time.perf_counter() - t0
                break
            if not white_background and float(np.std(img[: 400, : 500])) > 12:
                first = time.perf_counter() - t0
                break
            time.sleep(0.5)
        driver.set_script_timeout(60)
        # frame rate while the rover moves: updates pushed at 30 Hz from a thread
        import threading

        stop = threading.Event()

        def pusher():
            k = 0
            while not stop.wait(1 / 30):
                push(k)
                k += 1

        th = threading.Thread(target=pusher, daemon=True)
        th.start()
        fps = driver.execute_async_script(
            "const done = arguments[arguments.length - 1]; let n = 0; const t0 = performance.now();"
            "function f() { n++; if (performance.now() - t0 < 4000) requestAnimationFrame(f);"
            " else done(n / ((performance.now() - t0) / 1000)); } requestAnimationFrame(f);")
        stop.set()
        th.join()
        img = B.grab(driver)
        if os.environ.get("BENCH_VIEWER_SHOT"):  # the page as drawn, to look at
            from PIL import Image

            Image.fromarray(img).save(os.environ["BENCH_VIEWER_SHOT"])
        return {"browser_first_scene_s": first, "browser_fps_moving": fps}
    finally:
        driver.quit()


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--lib", choices=("viser", "rerun"), default="viser")
    ap.add_argument("--browser", action="store_true", help="also headless Chromium figures")
    args = ap.parse_args()
    data = scene_data()
    print(f"bench_viewer: {args.lib}, {GRID} x {GRID} height map, {N_FRAMES} frames", flush=True)
    out = (bench_viser if args.lib == "viser" else bench_rerun)(data, args.browser)
    for k, v in out.items():
        print(f"  {k:24s} {v if v is None else round(v, 3)}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
