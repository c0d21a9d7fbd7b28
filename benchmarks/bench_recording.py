"""What recording an episode for the 3D viewer costs: a 60 s RockField episode run plain and run
under ``ernest_cpp.viewer.RecordEpisode`` (capture every step, write the file at the end),
alternated, several seeds. Prints the median times, the ratio of the extra time to the episode's
simulation time (target <= 10 %), the file's size (target < 20 MB) and the time to load it and
start the viewer's server on it (target < 5 s). benchmarks/RESULTS.md ("3D viewer") has the figures.

    python benchmarks/bench_recording.py [--episodes 5]
"""

from __future__ import annotations

import argparse
import os
import statistics
import sys
import tempfile
import time

import gymnasium as gym
import numpy as np

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "python"))

import ernest_cpp.envs  # noqa: E402,F401  (registers the ids)
from ernest_cpp.viewer import RecordEpisode  # noqa: E402

ACTION = np.array([-0.2, 0.05, 0.0])  # 0.08 m/s: the 60 s limit comes before the map's end


def episode(env, seed: int) -> tuple[float, int, float]:
    t0 = time.perf_counter()
    env.reset(seed=seed)
    n = 0
    while True:
        _, _, term, trunc, _ = env.step(ACTION)
        n += 1
        if term or trunc:
            break
    return time.perf_counter() - t0, n, env.unwrapped.core.state.time


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--episodes", type=int, default=5)
    args = ap.parse_args()
    if args.episodes < 1:
        raise SystemExit("--episodes must be >= 1")
    plain_env = gym.make("ernest/RockField-v0", episode_length=60.0)
    with tempfile.TemporaryDirectory() as tmp:
        path = os.path.join(tmp, "episode.npz")
        rec_env = RecordEpisode(gym.make("ernest/RockField-v0", episode_length=60.0), path)
        spent = [0.0]  # seconds inside the recorder itself: start, capture, save
        for name in ("start", "capture", "save"):
            fn = getattr(rec_env.recorder, name)

            def timed(*a, _fn=fn, **kw):
                t = time.perf_counter()
                try:
                    return _fn(*a, **kw)
                finally:
                    spent[0] += time.perf_counter() - t

            setattr(rec_env.recorder, name, timed)
        plain, recorded, ratios, inside = [], [], [], []
        for k in range(args.episodes):
            t_plain, n, t_sim = episode(plain_env, k)
            spent[0] = 0.0
            t_rec, _, _ = episode(rec_env, k)
            plain.append(t_plain)
            recorded.append(t_rec)
            ratios.append((t_rec - t_plain) / t_plain)
            inside.append(spent[0] / t_plain)
            print(f"[{k + 1}/{args.episodes}] seed {k}: {n} steps, {t_sim:.1f} s simulated; "
                  f"plain {t_plain * 1e3:.1f} ms, recorded {t_rec * 1e3:.1f} ms, in the "
                  f"recorder {spent[0] * 1e3:.2f} ms", flush=True)
        size = os.path.getsize(path) / 1e6
        t0 = time.perf_counter()
        from ernest_cpp.viewer import Player

        player = Player(path, port=0)
        opening = time.perf_counter() - t0
        player.close()
    p, r = statistics.median(plain), statistics.median(recorded)
    print(f"episode (median of {args.episodes}): plain {p * 1e3:.1f} ms, recorded {r * 1e3:.1f} ms")
    print(f"recording cost / simulation time: {100 * statistics.median(inside):.1f} % in the "
          f"recorder (max {100 * max(inside):.1f} %); run-time difference "
          f"{100 * statistics.median(ratios):.1f} % (median of seeds; target <= 10 %)")
    print(f"recording of a 60 s episode: {size:.2f} MB (target < 20 MB)")
    print(f"opening it (load + viewer server + scene): {opening:.2f} s (target < 5 s)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
