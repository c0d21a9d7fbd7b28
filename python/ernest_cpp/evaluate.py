"""``ernest evaluate``: the passive bogie and the scripted crawling gait (and optionally an
exported policy) over the evaluation courses of seed 004 §5: Bickler trap, 20 deg slope on dry M90
and on wet sand (Table 6), wheel-high step and a mixed course. Writes a markdown report with a
metrics table, PNG plots and a short animation.
"""

from __future__ import annotations

import argparse
import math
import os
import time

import gymnasium as gym
import numpy as np

from . import _args
from . import envs as E
from .scenarios import SCENARIOS, scenario_name
from .envs.baselines import CrawlingGaitController, PassiveController

COURSES = [  # (label, env id, kwargs); --scenario picks them by the env's short name
    ("Bickler trap (dry sand)", "ernest/BicklerTrap-v0", {"soil": "dry_sand"}),
    ("20 deg slope, dry M90", "ernest/SlopeEval-v0", {"soil": "m90"}),
    ("20 deg slope, wet sand", "ernest/SlopeEval-v0", {"soil": "wet_sand"}),
    ("Wheel-high step (M90)", "ernest/WheelStep-v0", {}),
    ("Mixed course (M90)", "ernest/Course-v0", {}),
]


#: The names ``ernest evaluate`` (and ``ernest reproduce``) give the controllers it compares.
PASSIVE, CRAWLING, LEARNED = "passive bogie", "crawling gait", "learned policy"


def controllers(policy_file: str | None):
    """{name: (policy(obs, env) -> action, passive)}: the passive bogie, the crawling gait of
    seed 004 §5.5 (``envs.baselines.CrawlingGaitController``, its defaults) and, with a policy
    file, the exported learned policy."""
    out = {PASSIVE: (PassiveController(), True),
           CRAWLING: (CrawlingGaitController(), False)}
    if policy_file:
        from .rl.export import load_policy  # TorchScript actor with its scaling

        import torch

        from . import sensing

        from .rl.layout import check_policy_layout

        from .rl.policy_file import check_runtime

        # the metadata checks of ernest_runtime: both refuse the same files
        module, meta = load_policy(policy_file, check=check_runtime)
        scale = np.asarray(sensing.ObservationScales().divisors())
        check_policy_sizes(module, meta, policy_file)
        check_policy_layout(meta, policy_file)  # the module divides by its own table: same one

        def learned(obs, env=None):
            # the exported module takes physical observations and returns (Vx, yaw rate, roll rate)
            with torch.no_grad():
                cmd = module(torch.as_tensor(obs * scale, dtype=torch.float32)).numpy()
            if not np.all(np.isfinite(cmd)):
                raise ValueError(f"{policy_file}: the policy returned a non-finite command "
                                 f"{cmd.tolist()} for a finite observation")
            return sensing.command_to_action(cmd.astype(np.float64))

        out[LEARNED] = (learned, False)
    return out


def check_policy_sizes(module, meta: dict, path: str) -> None:
    """Refuse, before any episode runs, a policy whose metadata or module does not map the
    environments' observation (sensing.OBSERVATION_SIZE values) to one command
    (sensing.ACTION_SIZE values). Raises ValueError naming the file and the sizes."""
    import torch

    from . import sensing

    n_obs, n_act = sensing.OBSERVATION_SIZE, sensing.ACTION_SIZE
    if meta.get("obs_dim") != n_obs or meta.get("act_dim") != n_act:
        raise ValueError(f"{path}: the policy maps {meta.get('obs_dim')} observation values to "
                         f"{meta.get('act_dim')} commands, the environments need {n_obs} -> {n_act}")
    try:
        with torch.no_grad():
            out = module(torch.zeros(n_obs, dtype=torch.float32))
    except Exception as exc:  # TorchScript raises RuntimeError/torch.jit.Error for shape errors
        msg = str(exc).strip().splitlines()[-1] if str(exc).strip() else type(exc).__name__
        raise ValueError(f"{path}: the module does not accept a {n_obs}-value observation "
                         f"({msg})") from None
    if not isinstance(out, torch.Tensor) or out.numel() != n_act:
        got = out.numel() if isinstance(out, torch.Tensor) else type(out).__name__
        raise ValueError(f"{path}: the module returns {got} values for one observation, "
                         f"expected {n_act} (Vx, yaw rate, roll rate)")
    if not bool(torch.isfinite(out).all()):
        raise ValueError(f"{path}: the policy returned a non-finite command for the zero "
                         "observation")


def run_episode(env_id: str, kwargs: dict, policy, passive: bool, seed: int,
                record: str | None = None):
    """One episode of ``policy`` (its ``reset()`` called first, if it has one); returns
    (metrics, history, unwrapped env, last info). ``kwargs`` go to ``gym.make`` (e.g. ``soil``,
    ``episode_length``). ``record``: a file for the 3D viewer's recording (``ernest view``)."""
    env = gym.make(env_id, passive=passive, **kwargs)
    if record:
        from .viewer import RecordEpisode

        env = RecordEpisode(env, record)
    if hasattr(policy, "reset"):
        policy.reset()
    obs, _ = env.reset(seed=seed)
    while True:
        obs, _, term, trunc, info = env.step(policy(obs, env))
        if term or trunc:
            break
    u = env.unwrapped
    return u.metrics, u.history, u, info


def max_lateral(env, history) -> float:
    """The largest |lateral deviation| from the desired path (eq 37) over an episode's
    ``history`` (``run_episode``'s), in metres."""
    path = env.scenario.path
    return float(max(abs(path.lateral_deviation(h["position"][0], h["position"][1]))
                     for h in history))


def courses(scenarios=None) -> list[tuple[str, str, dict]]:
    """The (label, env id, kwargs) rows to run: all of ``COURSES`` without ``scenarios``, else
    those of the given short names (``scenarios.SCENARIOS``) in that order; a scenario that is not
    one of the courses runs on its own env's defaults."""
    if not scenarios:
        return list(COURSES)
    out = []
    for name in scenarios:
        env_id = SCENARIOS.get(name)
        if env_id is None:
            raise ValueError(f"scenario {name!r}: choose one of {', '.join(SCENARIOS)}")
        rows = [c for c in COURSES if c[1] == env_id] or [(f"{name} ({env_id})", env_id, {})]
        out += [c for c in rows if c not in out]
    return out


def video_course(runs: list[tuple[str, str, dict]]) -> tuple[str, str, dict]:
    """The (label, env id, kwargs) the animation records: the mixed course when every course runs
    (``runs`` is ``COURSES``), else the first of the chosen scenarios' courses, with its kwargs
    (e.g. the wet-sand slope's soil). The GIF is named after its scenario (``course.gif``,
    ``bickler.gif``)."""
    if runs == COURSES:
        return next(c for c in COURSES if c[1] == "ernest/Course-v0")
    return runs[0]


def _plots(results, out_dir: str) -> list[str]:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    paths = []
    labels = list(results)  # the courses run, in order
    # 1. paths over each course
    fig, axes = plt.subplots(len(labels), 1, figsize=(9, 2.3 * len(labels)), squeeze=False)
    axes = axes[:, 0]
    for ax, label in zip(axes, labels):
        for name, r in results[label].items():
            xy = np.array([h["position"][:2] for h in r["history"]])
            ax.plot(xy[:, 0], xy[:, 1], label=f"{name}: {r['metrics']['progress']:.2f} m")
        env = next(iter(results[label].values()))["env"]
        for o in np.asarray(env.scenario.obstacles):
            if o[3] < 10:
                ax.add_patch(plt.Rectangle((o[0] - o[3] / 2, o[1] - o[4] / 2), o[3], o[4],
                                           color="0.6"))
        ax.set_title(label, fontsize=9)
        ax.set_xlim(-1, 14 if "course" not in label.lower() else 24)
        ax.set_ylim(-2, 2)
        ax.set_aspect("equal")
        ax.legend(fontsize=7, loc="upper right")
    axes[-1].set_xlabel("x [m]")
    fig.tight_layout()
    paths.append(_save(fig, out_dir, "paths.png"))
    # 2. gait on the dry slope, like seed 004 Fig. 24: joints, roll torque, wheel loads
    label = "20 deg slope, dry M90"
    if label in results:
        paths.append(_slope_gait(results[label], out_dir, plt))
    # 3. bar chart of travel reduction and cost of transport
    fig, (a1, a2) = plt.subplots(1, 2, figsize=(11, 3.6))
    names = list(next(iter(results.values())).keys())
    x = np.arange(len(labels))
    for k, name in enumerate(names):
        tr = [100 * results[c][name]["metrics"]["travel_reduction"] for c in labels]
        cot = [min(results[c][name]["metrics"]["cost_of_transport"], 50) for c in labels]
        a1.bar(x + 0.8 * k / len(names), tr, 0.8 / len(names), label=name)
        a2.bar(x + 0.8 * k / len(names), cot, 0.8 / len(names), label=name)
    for a, yl in ((a1, "travel reduction [%]"), (a2, "cost of transport [-] (capped at 50)")):
        a.set_xticks(x + 0.4 - 0.4 / len(names))
        a.set_xticklabels([c.split(" (")[0] for c in labels], rotation=20, fontsize=7)
        a.set_ylabel(yl)
        a.legend(fontsize=7)
    fig.tight_layout()
    paths.append(_save(fig, out_dir, "metrics.png"))
    return paths


def _slope_gait(runs: dict, out_dir: str, plt) -> str:
    fig, axes = plt.subplots(3, len(runs), figsize=(11, 7), sharex=True, squeeze=False)
    for col, (name, r) in enumerate(runs.items()):
        h = r["history"]
        t = np.array([x["time"] for x in h])
        axes[0, col].plot(t, np.degrees([x["gimbal_yaw"] for x in h]), label="yaw")
        axes[0, col].plot(t, np.degrees([x["gimbal_roll"] for x in h]), label="roll")
        axes[0, col].set_ylabel("joint [deg]")
        axes[0, col].set_title(name, fontsize=9)
        axes[0, col].legend(fontsize=7)
        axes[1, col].plot(t, [x["roll_torque"] for x in h], color="tab:red")
        axes[1, col].set_ylabel("roll torque [N m]")
        loads = np.array([x["wheel_load"] for x in h])
        for i, w in enumerate(["FL", "FR", "RL", "RR"]):
            axes[2, col].plot(t, loads[:, i], label=w)
        axes[2, col].set_ylabel("wheel load [N]")
        axes[2, col].set_xlabel("time [s]")
        axes[2, col].legend(fontsize=7, ncol=4)
    fig.suptitle("Gait on a 20 deg M90 slope (compare seed 004 Figs 23-24)", fontsize=10)
    fig.tight_layout()
    return _save(fig, out_dir, "slope_gait.png")


def _save(fig, out_dir, name):
    import matplotlib.pyplot as plt

    path = os.path.join(out_dir, name)
    fig.savefig(path + ".tmp.png", dpi=100)
    os.replace(path + ".tmp.png", path)
    plt.close(fig)
    return path


def course_episode(env_id: str, kwargs: dict, name: str, policy_file: str | None, seed: int):
    """One (course, controller) episode in a fresh process (a Ray task of ``--backend ray``):
    (metrics, history, a stand-in env with the scenario's obstacles, last info, seconds)."""
    from types import SimpleNamespace

    policy, passive = controllers(policy_file)[name]
    t0 = time.perf_counter()
    metrics, history, env, info = run_episode(env_id, kwargs, policy, passive, seed)
    scen = SimpleNamespace(obstacles=np.asarray(env.scenario.obstacles).copy())
    return metrics, history, SimpleNamespace(scenario=scen), info, time.perf_counter() - t0


def record_path(args: argparse.Namespace, label: str, controller: str) -> str | None:
    """With ``--record``: OUT/recordings/<course>_<controller>.npz for ``ernest view``."""
    if not getattr(args, "record", False):
        return None
    slug = "".join(c if c.isalnum() else "_" for c in f"{label}_{controller}".lower())
    return os.path.join(args.out, "recordings", "_".join(filter(None, slug.split("_"))) + ".npz")


def run(args: argparse.Namespace) -> int:
    os.makedirs(args.out, exist_ok=True)
    ctrls = controllers(args.policy)
    runs = courses(getattr(args, "scenario", None))
    results: dict[str, dict] = {}
    total = len(runs) * len(ctrls)
    k = 0
    t_start = time.perf_counter()
    remote = None
    if getattr(args, "backend", "local") == "ray":  # all episodes at once on the cluster
        from .rl.ray_backend import fan_out

        policy_file = os.path.abspath(args.policy) if args.policy else None  # read on the nodes
        keys = [(c, name) for c in range(len(runs)) for name in ctrls]
        jobs = [(runs[c][1], runs[c][2], name, policy_file, args.seed) for c, name in keys]
        remote = dict(zip(keys, fan_out(course_episode, jobs, args.ray_address)))
    elif getattr(args, "ray_address", None):
        raise ValueError("--ray-address needs --backend ray")
    if getattr(args, "record", False) and remote is not None:
        raise ValueError("--record runs the episodes here: use it without --backend ray")
    for c, (label, env_id, kwargs) in enumerate(runs):
        results[label] = {}
        for name, (policy, passive) in ctrls.items():
            k += 1
            t0 = time.perf_counter()
            if remote is not None:
                metrics, history, env, info, secs = remote[(c, name)]
                t0 -= secs
            else:
                metrics, history, env, info = run_episode(env_id, kwargs, policy, passive,
                                                          args.seed, record_path(args, label, name))
            results[label][name] = {"metrics": metrics, "history": history, "env": env}
            print(f"[{k:2d}/{total}] {label:24s} {name:16s} progress {metrics['progress']:5.2f} m "
                  f"travel reduction {100 * metrics['travel_reduction']:5.1f} % "
                  f"CoT {metrics['cost_of_transport']:7.3f}  ({info['message']}, "
                  f"{time.perf_counter() - t0:.1f} s)", flush=True)
    if getattr(args, "record", False):
        print(f"wrote {total} recordings to {os.path.join(args.out, 'recordings')} "
              "(ernest view FILE)", flush=True)
    lines = ["# ERNEST evaluation report", "",
             f"Seed {args.seed}. Travel reduction = 1 - progress / no-slip travel (seed 004 Table 6); "
             "cost of transport = electrical energy of all six actuators (eq 40) / (m g progress).", "",
             "| course | scenario | controller | progress [m] | travel reduction [%] | "
             "cost of transport [-] | energy [kJ] | time [s] |", "|---|---|---|---|---|---|---|---|"]
    for label, env_id, _ in runs:
        for name, r in results[label].items():
            m = r["metrics"]
            cot = m["cost_of_transport"]
            lines.append(f"| {label} | {scenario_name(env_id)} | {name} | {m['progress']:.2f} | {100 * m['travel_reduction']:.1f} | "
                         f"{'inf' if not math.isfinite(cot) else f'{cot:.3f}'} | {m['energy'] / 1e3:.2f} | "
                         f"{m['time']:.0f} |")
    pngs = _plots(results, args.out)
    lines += ["", *[f"![{os.path.basename(p)}]({os.path.basename(p)})" for p in pngs]]
    if not args.no_video:
        from .envs.render import record_episode

        name = LEARNED if LEARNED in ctrls else CRAWLING
        policy, passive = ctrls[name]
        label, env_id, kwargs = video_course(runs)
        env = gym.make(env_id, passive=passive, render_mode="rgb_array", **kwargs)
        video = os.path.join(args.out, f"{scenario_name(env_id)}.gif")
        print(f"recording {name} on {label} -> {video}", flush=True)
        record_episode(env.unwrapped, policy, video, seed=args.seed, every=3, max_steps=160)
        lines += ["", f"Animation: [{os.path.basename(video)}]({os.path.basename(video)})"]
    report = os.path.join(args.out, "report.md")
    with open(report + ".tmp", "w") as fh:
        fh.write("\n".join(lines) + "\n")
    os.replace(report + ".tmp", report)
    print("\n".join(lines[4:4 + total + 2]))
    print(f"wrote {report} ({time.perf_counter() - t_start:.0f} s)")
    return 0


def add_parser(sub) -> None:
    p = sub.add_parser("evaluate", help="passive bogie vs crawling gait (vs learned policy) on the "
                       "evaluation courses",
                       description=__doc__)
    p.add_argument("--out", default="out/report", help="output folder (default: out/report)")
    p.add_argument("--seed", type=_args.seed, default=0)
    p.add_argument("--policy", default=None, help="exported TorchScript policy to evaluate too")
    p.add_argument("--scenario", action="append", choices=tuple(SCENARIOS),
                   help="run only this scenario's courses (its short name, docs/envs.md; "
                   "repeatable; default: all evaluation courses)")
    p.add_argument("--no-video", action="store_true", help="skip the animation")
    p.add_argument("--record", action="store_true",
                   help="write each episode's 3D recording to OUT/recordings/ (ernest view FILE)")
    from .rl.commands import backend_args

    backend_args(p)  # --backend ray: the episodes as tasks on a Ray cluster
    p.set_defaults(func=run)


def main(**options) -> int:
    """``ernest evaluate`` from Python: one keyword per option, named as on the command line with
    underscores (``ernest evaluate --help``), checked as there (``cli.run``), e.g.
    ``main(out="out/report", scenario=["bickler"], no_video=True)``. Returns the exit status; errors raise."""
    from .cli import run

    return run("evaluate", **options)
