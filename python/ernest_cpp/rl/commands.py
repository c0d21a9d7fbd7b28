"""Console subcommands ``ernest train``, ``ernest consolidate`` and ``ernest export``.

Heavy imports (torch, gymnasium) happen only when a command runs.
"""

from __future__ import annotations

import argparse
import json
import os
import re

from .. import _args
from ..scenarios import SCENARIOS


def _passive_openmp() -> None:
    """Idle OpenMP threads sleep instead of spinning (before torch loads its OpenMP runtime). On a
    machine whose cores are shared with other processes, spinning made 2-thread TD3 updates ~5×
    slower (benchmarks/RESULTS.md, consolidation); an explicit OMP_WAIT_POLICY is respected."""
    os.environ.setdefault("OMP_WAIT_POLICY", "PASSIVE")


def _positive_int(text: str) -> int:
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a whole number, got {text!r}") from None
    if value < 1:
        raise argparse.ArgumentTypeError(f"must be at least 1, got {value}")
    return value


def _settings_args(p: argparse.ArgumentParser) -> None:
    p.add_argument("--preset", default="quick", choices=("quick", "paper"),
                   help="base settings (python/ernest_cpp/rl/presets/<preset>.yaml)")
    p.add_argument("--config", metavar="YAML", help="YAML file overriding the preset")
    p.add_argument("--set", metavar="KEY=VALUE", action="append", default=[],
                   help="override one setting, e.g. --set td3.batch_size=256 (repeatable)")
    p.add_argument("--print-config", action="store_true",
                   help="print the settings this command would use (YAML) and exit")


def _print_config(cfg: dict) -> int:
    import yaml

    print(yaml.safe_dump(cfg, sort_keys=False), end="")
    return 0


def _build(args, extra: dict | None = None) -> dict:
    from .config import build_config, merge

    cfg = build_config(args.preset, args.config, args.set)
    return merge(cfg, extra) if extra else cfg


def _check_more_steps(total, done: int, args) -> None:
    """A resumed run must be given more transitions than it has done: fewer or as many would
    end at once without training."""
    if int(total) > done:
        return
    if args.steps is not None:
        where = f"--steps {args.steps}"
    elif any(o.strip().startswith("total_steps") for o in args.set):
        where = f"--set total_steps={total}"
    else:
        where = f"total_steps {total} (the run's saved settings)"
    raise ValueError(f"{where}: the run in {args.run_dir} has done {done} transitions already; "
                     f"give --steps above {done} to continue")


def _train(args) -> int:
    _passive_openmp()
    from .envs_util import resolve_env_id
    from .trainer import Trainer

    extra: dict = {}
    if args.env:
        extra["env"] = {"id": args.env, "scenario": None}
    if args.scenario:
        extra["env"] = {"id": args.env, "scenario": args.scenario}
    if args.seed is not None:
        extra["seed"] = args.seed
    if args.steps is not None:
        extra["total_steps"] = args.steps
    ray_extra = {k: v for k, v in (("address", args.ray_address), ("num_workers", args.num_workers),
                                   ("envs_per_worker", args.envs_per_worker),
                                   ("mode", args.ray_mode)) if v is not None}
    if ray_extra:
        if args.backend != "ray":
            raise ValueError("--ray-address, --num-workers, --envs-per-worker and --ray-mode "
                             "need --backend ray")
        extra["ray"] = ray_extra
    if args.resume:
        # The run's saved settings, changed only by what this command line gives explicitly.
        from .config import merge, parse_assignment
        from .checkpoints import load_checkpoint, saved_settings

        if not args.run_dir:
            raise ValueError("--resume needs --run-dir")
        if args.config:
            raise ValueError("--resume continues with the run's saved settings; use --set to "
                             "change one")
        ck = load_checkpoint(args.run_dir, with_buffer=False)
        state = ck["state"]
        # Settings newer than the run (ray, learner_device, demos) get the quick preset's values,
        # which --set may then change; a run from before learner_device learned on the CPU.
        cfg = saved_settings(state["config"])
        if extra:
            cfg = merge(cfg, extra)
        for o in args.set:
            cfg = merge(cfg, parse_assignment(o))
        _check_more_steps(cfg["total_steps"], state["step"], args)
    else:
        if args.override_config:
            raise ValueError("--override-config applies to --resume only")
        cfg = _build(args, extra)
    if args.backend == "ray":  # the simulations are the workers' (env.num_envs follows)
        from .config import merge

        cfg = merge(cfg, {"env": {"num_envs": cfg["ray"]["num_workers"] *
                                  cfg["ray"]["envs_per_worker"]}})
    if args.print_config:
        return _print_config(cfg)
    if args.resume:  # refused here, before any simulation starts (the trainer checks too)
        from .checkpoints import check_resume_config

        check_resume_config(state["config"], cfg, ck["path"], args.override_config)
    env_id = resolve_env_id(cfg["env"])
    run_dir = args.run_dir or os.path.join(
        "runs", f"{re.sub(r'[^A-Za-z0-9_.-]+', '_', env_id)}-seed{cfg['seed']}")
    if args.backend == "ray":
        from .ray_trainer import RayTrainer

        tr = RayTrainer(cfg, run_dir, resume=args.resume, override_config=args.override_config)
        where = (f"{tr.rc['num_workers']} Ray workers x {tr.rc['envs_per_worker']}, "
                 f"{tr.rc['mode']} mode, ")
    else:
        tr = Trainer(cfg, run_dir, resume=args.resume, override_config=args.override_config)
        where = ""
    print(f"training on {env_id} ({where}{tr.n} simulations, obs {tr.obs_dim}, act {tr.act_dim}, layout "
          f"{tr.layout.version}, FTS noise on {tr.buffer.noise_idx.size} components) -> {run_dir}")
    try:
        res = tr.train()
    finally:
        tr.close()
    print(json.dumps({k: v for k, v in res.items()}, indent=1))
    return 0


def _consolidate(args) -> int:
    _passive_openmp()
    from .consolidate import consolidate_runs

    cfg = _build(args)
    if args.print_config:
        return _print_config(cfg)
    print(f"consolidating {len(args.runs)} runs -> {args.out}")
    ray = None
    if args.backend == "ray":
        ray = {"address": args.ray_address or cfg["ray"]["address"],
               "object_store_mb": cfg["ray"]["object_store_mb"]}
    elif args.ray_address:
        raise ValueError("--ray-address needs --backend ray")
    res = consolidate_runs(args.runs, cfg, args.out, evaluate_policies=not args.no_eval, ray=ray)
    print(f"checkpoint: {res['checkpoint']}")
    if res["table"]:
        print(f"evaluation table: {os.path.join(args.out, 'evaluation.csv')}")
    return 0


def _export(args) -> int:
    _passive_openmp()
    from . import layout as L
    from .export import export_actor
    from .checkpoints import agent_from_checkpoint, load_checkpoint

    if args.checkpoint.endswith(".zip") and os.path.isfile(args.checkpoint):
        # A Stable-Baselines3 TD3 model trained on an ernest env: its actor and the envs' layout.
        from ..envs.core import make_options, observation_layout
        from .export import actor_from_sb3

        actor = actor_from_sb3(args.checkpoint)
        lay = observation_layout(make_options())
        extra = {"source_checkpoint": os.path.abspath(args.checkpoint),
                 "source": "stable-baselines3 TD3"}
    else:
        ck = load_checkpoint(args.checkpoint, with_buffer=False)
        actor = agent_from_checkpoint(ck).actor
        lay = L.ObservationLayout.from_dict(ck["state"]["layout"])
        extra = {"source_checkpoint": os.path.abspath(ck["path"]), "env_id": ck["state"]["env_id"]}
    meta = export_actor(actor, lay, args.out, args.policy_rate, extra)
    print(f"wrote {args.out}: {meta['obs_dim']} -> {meta['act_dim']}, layout "
          f"{meta['layout_version']}, {meta['policy_rate_hz']} Hz, verified against the Python "
          f"actor (max abs error {meta['verified_max_abs_error']:.2g})")
    return 0


def _stamp(args) -> int:
    from .export import HASH_KEY, POLICY_KEY, stamp_policy

    meta = stamp_policy(args.policy)
    print(f"{args.policy}: {HASH_KEY} {meta[HASH_KEY]}, {POLICY_KEY} {meta[POLICY_KEY]}")
    return 0


def backend_args(p: argparse.ArgumentParser) -> None:
    p.add_argument("--backend", choices=("local", "ray"), default="local",
                   help="where simulations run: this process (local) or a Ray cluster (needs "
                   "the extra ernest-cpp[ray])")
    p.add_argument("--ray-address", metavar="ADDRESS", help="cluster to join (host:port of `ray "
                   "start --head`, or auto); default: start one on this machine")


def add_parser(subparsers) -> None:
    p = subparsers.add_parser("train", help="train a TD3 specialist (seed 004 §4.1, §4.4)",
                              description="Train a TD3 specialist on a Gymnasium environment.")
    p.add_argument("--env", help="any registered Gymnasium id with Box spaces, e.g. "
                   "ernest-toy/PointMass-v0")
    p.add_argument("--scenario", choices=tuple(SCENARIOS),
                   help="ERNEST scenario by its short name (docs/envs.md: rockfield, step, "
                   "ripples and slope are seed 004's training scenarios)")
    _settings_args(p)
    p.add_argument("--run-dir", help="output folder (default runs/<env>-seed<seed>)")
    p.add_argument("--resume", action="store_true", help="continue the run in --run-dir exactly, "
                   "with its saved settings (config.yaml); --steps, --set log.*, "
                   "checkpoint.keep, ray.address, ray.object_store_mb and consolidate.* may "
                   "differ, other changes are refused without --override-config. The checkpoint is the one checkpoints/LATEST names, or "
                   "the newest intact checkpoints/step-N when LATEST is missing or damaged")
    p.add_argument("--override-config", action="store_true",
                   help="with --resume: continue with the settings this command line gives "
                   "(e.g. another --seed) where they differ from the run's saved ones, and "
                   "rewrite config.yaml")
    p.add_argument("--steps", type=_positive_int,
                   help="total transitions to collect (total_steps, at least 1)")
    p.add_argument("--seed", type=_args.seed)
    backend_args(p)
    p.add_argument("--num-workers", type=_positive_int, help="Ray rollout workers (ray.num_workers)")
    p.add_argument("--envs-per-worker", type=_positive_int,
                   help="simulations per Ray worker (ray.envs_per_worker)")
    p.add_argument("--ray-mode", choices=("sync", "async"),
                   help="sync: bit-identical to --backend local with the same number of "
                   "simulations; async: throughput first (ray.mode)")
    p.set_defaults(func=_train)

    p = subparsers.add_parser("consolidate", help="pool specialists' experience and train one "
                              "policy (seed 004 §4.6)")
    p.add_argument("runs", nargs="+", metavar="RUN", help="specialist run or checkpoint folders")
    p.add_argument("--out", required=True, help="output folder")
    p.add_argument("--no-eval", action="store_true", help="skip the evaluation table")
    backend_args(p)
    _settings_args(p)
    p.set_defaults(func=_consolidate)

    p = subparsers.add_parser("export", help="export an actor to TorchScript with its scaling")
    p.add_argument("checkpoint", help="run, consolidation or checkpoint folder, or the .zip of a "
                   "Stable-Baselines3 TD3 model trained on an ernest env")
    p.add_argument("--out", required=True, help="output .pt file")
    p.add_argument("--policy-rate", type=_args.positive_finite, default=2.0,
                   help="policy rate in Hz, finite and > 0 (Table 5: 2)")
    p.set_defaults(func=_export)

    p = subparsers.add_parser("stamp-policy", help="add the checksums a policy lacks (in place)",
                              description="Add weights_sha256 (the weights) and policy_sha256 "
                              "(the whole archive: code, constants, weights, metadata) to the "
                              "metadata of a policy file written before they existed; the "
                              "rewritten file gives bit-identical actions. A file with both is "
                              "left as is; one whose weights or archive do not match a checksum "
                              "it has is refused.")
    p.add_argument("policy", help="exported .pt file")
    p.set_defaults(func=_stamp)


def train(**options) -> int:
    """``ernest train`` from Python: one keyword per option, named as on the command line with
    underscores (``ernest train --help``), checked as there (``cli.run``), e.g.
    ``train(scenario="slope", preset="quick", set=["td3.hidden=256"])``. Returns the exit status; errors raise."""
    from ..cli import run

    return run("train", **options)


def consolidate(**options) -> int:
    """``ernest consolidate`` from Python: one keyword per option, named as on the command line with
    underscores (``ernest consolidate --help``), checked as there (``cli.run``), e.g.
    ``consolidate(runs=["runs/slope", "runs/step"], out="runs/cons")``. Returns the exit status; errors raise."""
    from ..cli import run

    return run("consolidate", **options)


def export_policy(**options) -> int:
    """``ernest export`` from Python: one keyword per option, named as on the command line with
    underscores (``ernest export --help``), checked as there (``cli.run``), e.g.
    ``export_policy(checkpoint="runs/cons", out="policy.pt")``. Returns the exit status; errors raise."""
    from ..cli import run

    return run("export", **options)


def stamp(**options) -> int:
    """``ernest stamp-policy`` from Python: one keyword per option, named as on the command line with
    underscores (``ernest stamp-policy --help``), checked as there (``cli.run``), e.g.
    ``stamp(policy="old_policy.pt")``. Returns the exit status; errors raise."""
    from ..cli import run

    return run("stamp-policy", **options)
