"""Export a policy to TorchScript and run it in the onboard C++ runtime, then check that Python
takes the same actions.

Shows: ``rl.export.export_actor`` (the actor with its observation scaling and metadata, verified
on reload; what ``ernest export`` does), the ``ernest_runtime`` executable (libtorch, no Python)
running one episode with ``--actions`` and ``--telemetry``, and the same episode in Python
(``envs.ErnestEnv`` with the exported file loaded by ``rl.export.load_policy``).

    python examples/export_and_run_cpp.py --out out/examples [--checkpoint RUN] [--scenario rockfield]

Without ``--checkpoint`` the actor is freshly initialised (untrained, so the rover's path means
nothing; the point is the pipeline); with it, the run or checkpoint folder of ``ernest train``.
The runtime is found through $ERNEST_RUNTIME_EXE, the PATH, or the build tree
(build*/cpp/cpp/runtime/ernest_runtime, built by ``./run test``). Writes OUT/policy.pt,
OUT/runtime_actions.csv and OUT/runtime_telemetry.csv. Takes ~10 s.
"""

from __future__ import annotations

import argparse
import glob
import os
import shutil
import subprocess
import sys

import numpy as np
import torch

from ernest_cpp import sensing
from ernest_cpp.envs import ErnestEnv
from ernest_cpp.rl.export import export_actor, load_policy
from ernest_cpp.rl.networks import Actor

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


def find_runtime() -> str | None:
    exe = os.environ.get("ERNEST_RUNTIME_EXE") or shutil.which("ernest_runtime")
    if exe:
        return exe
    built = glob.glob(os.path.join(ROOT, "build*", "cpp", "cpp", "runtime", "ernest_runtime"))
    return max(built, key=os.path.getmtime) if built else None


def actor_to_export(checkpoint: str | None):
    if checkpoint:
        from ernest_cpp.rl import layout as L
        from ernest_cpp.rl.checkpoints import agent_from_checkpoint, load_checkpoint

        ck = load_checkpoint(checkpoint, with_buffer=False)
        return agent_from_checkpoint(ck).actor, L.ObservationLayout.from_dict(ck["state"]["layout"])
    torch.manual_seed(0)
    return (Actor(sensing.OBSERVATION_SIZE, sensing.ACTION_SIZE, 512),
            ErnestEnv("flat").observation_layout)


def python_actions(policy, scenario: str, seed: int, duration: float) -> np.ndarray:
    """The episode in Python: physical observation -> exported policy -> physical command."""
    env = ErnestEnv(scenario, episode_length=duration)
    scale = np.asarray(env.options.scales.divisors())  # env observations are normalised
    obs, _ = env.reset(seed=seed)
    actions = []
    while True:
        with torch.no_grad():
            cmd = policy(torch.as_tensor(obs * scale, dtype=torch.float32)).numpy()
        action = np.asarray(sensing.command_to_action(cmd.astype(np.float64)))
        actions.append(action)
        obs, _, terminated, truncated, _ = env.step(action)
        if terminated or truncated:
            return np.array(actions)


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", default="out/examples", help="output folder")
    ap.add_argument("--checkpoint", help="run or checkpoint folder of `ernest train` to export")
    ap.add_argument("--scenario", default="rockfield", help="runtime scenario")
    ap.add_argument("--seed", type=int, default=3)
    ap.add_argument("--duration", type=float, default=10.0, help="episode length [s]")
    args = ap.parse_args()
    os.makedirs(args.out, exist_ok=True)
    torch.set_num_threads(1)  # as the runtime: identical float results

    actor, layout = actor_to_export(args.checkpoint)
    policy_path = os.path.join(args.out, "policy.pt")
    meta = export_actor(actor, layout, policy_path)
    print(f"exported {policy_path}: {meta['obs_dim']} -> {meta['act_dim']}, layout "
          f"{meta['layout_version']}, {meta['policy_rate_hz']} Hz")

    exe = find_runtime()
    if not exe:
        print("ernest_runtime not found: build it (./run test) or set ERNEST_RUNTIME_EXE",
              file=sys.stderr)
        return 1
    actions_csv = os.path.join(args.out, "runtime_actions.csv")
    telemetry_csv = os.path.join(args.out, "runtime_telemetry.csv")
    cmd = [exe, "--policy", policy_path, "--scenario", args.scenario, "--seed", str(args.seed),
           "--duration", str(args.duration), "--actions", actions_csv, "--telemetry", telemetry_csv]
    print("$ " + " ".join(cmd))
    r = subprocess.run(cmd, capture_output=True, text=True)
    print(r.stdout + r.stderr, end="")
    if r.returncode != 0:
        return r.returncode

    cpp = np.loadtxt(actions_csv, delimiter=",", skiprows=1)[:, 1:]  # time column dropped
    module, _ = load_policy(policy_path)
    py = python_actions(module, args.scenario, args.seed, args.duration)
    err = float(np.max(np.abs(cpp - py))) if cpp.shape == py.shape else float("inf")
    print(f"C++ runtime vs Python: {len(cpp)} policy steps, max action difference {err:.2g}")
    return 0 if err <= 1e-5 else 1


if __name__ == "__main__":
    sys.exit(main())
