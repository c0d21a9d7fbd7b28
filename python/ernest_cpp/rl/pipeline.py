"""``ernest train-default``: the default policy from scratch in one command (seed 004 §4.6).

Stages, each skipped when its output is complete, so that running the same command again after a
kill resumes where it stopped:

1. **specialists**: one ``ernest train`` process per scenario, ``parallel`` at a time (both cores
   are used by processes with one learner thread each, not by intra-op threads); a run with
   checkpoints continues with ``--resume``. Progress of every running specialist (transitions,
   transitions/s, updates/s, last evaluation) is printed every ``progress_every`` seconds from
   the runs' ``progress.json``.
2. **consolidate**: ``ernest consolidate`` over the specialists (Table 4's consolidation settings
   unless the pipeline file overrides them), once per seed in ``consolidate.seeds``, ``parallel``
   at a time, each keeping its agent every ``keep_every`` iterations (the ``set`` list).
3. **select**: every kept agent on validation episodes the reports never use
   (``ernest_cpp.rl.selection``); the best is the policy, and its table against every specialist
   on every scenario is written beside it. Without a ``select`` section: seed 0's final agent.
   With a ``refine`` section, the chosen agent is then continued on the same pool (``ernest
   consolidate`` with ``consolidate.init``, the consolidation's settings and then ``refine.set``,
   e.g. a relabelled lateral weight and a lower learning rate), its kept agents and the chosen one
   are judged on the validation episodes (the select section with ``refine.select``'s keys
   replaced), and the best of them is the policy (``out/refined``).
4. **export**: TorchScript export and weights checksum, written to the policy path atomically.
5. **evaluate**: ``ernest reproduce`` with the new policy over ``evaluate.seeds`` seeds.
6. **report**: learning curves against wall time (``curves.png``) and ``training.md``.

The pipeline file (YAML, default ``policies/default.yaml``) names the specialists and their
settings; see that file.
"""

from __future__ import annotations

import argparse
import ctypes
import json
import os
import signal
import subprocess
import sys
import time

import yaml

DEFAULT_FILE = os.path.join("policies", "default.yaml")
STAGES = ("specialists", "consolidate", "select", "export", "evaluate", "report")
_KEYS = {"out", "policy", "parallel", "progress_every", "preset", "specialists", "consolidate",
         "select", "refine", "evaluate"}


def load_pipeline(path: str) -> dict:
    """The pipeline settings, validated (unknown keys and bad values are errors)."""
    try:
        with open(path) as fh:
            cfg = yaml.safe_load(fh) or {}
    except OSError as exc:
        raise ValueError(f"pipeline file {path}: {exc.strerror or exc}") from None
    if not isinstance(cfg, dict):
        raise ValueError(f"pipeline file {path}: expected a mapping")
    unknown = sorted(set(cfg) - _KEYS)
    if unknown:
        raise ValueError(f"pipeline file {path}: unknown key(s) {', '.join(unknown)}; known: "
                         f"{', '.join(sorted(_KEYS))}")
    out = {"out": "runs/default", "policy": "policies/ernest_default.pt", "parallel": 2,
           "progress_every": 60, "preset": "quick", "consolidate": {"set": []},
           "evaluate": {"seeds": 10, "sections": "table6,obstacles"}}
    out.update(cfg)
    for key in ("parallel", "progress_every"):
        v = out[key]
        if isinstance(v, bool) or not isinstance(v, int) or v < 1:
            raise ValueError(f"pipeline {key} = {v!r} must be a whole number >= 1")
    sp = out.get("specialists")
    if not isinstance(sp, dict) or not sp:
        raise ValueError("pipeline specialists: give at least one, name: {scenario, steps, set}")
    for name, s in sp.items():
        if not isinstance(s, dict) or "scenario" not in s or "steps" not in s:
            raise ValueError(f"pipeline specialist {name!r} needs scenario and steps")
        if isinstance(s["steps"], bool) or not isinstance(s["steps"], int) or s["steps"] < 1:
            raise ValueError(f"pipeline specialist {name!r}: steps = {s['steps']!r} must be >= 1")
        extra = sorted(set(s) - {"scenario", "steps", "set"})
        if extra:
            raise ValueError(f"pipeline specialist {name!r}: unknown key(s) {', '.join(extra)}")
        s.setdefault("set", [])
    c = out["consolidate"]
    extra = sorted(set(c) - {"set", "seeds"})
    if extra:
        raise ValueError(f"pipeline consolidate: unknown key(s) {', '.join(extra)}; known: seeds, set")
    seeds = c.setdefault("seeds", [0])
    if (not isinstance(seeds, list) or not seeds or len(set(seeds)) != len(seeds)
            or not all(isinstance(v, int) and not isinstance(v, bool) and v >= 0 for v in seeds)):
        raise ValueError(f"pipeline consolidate.seeds = {seeds!r} must list distinct whole "
                         f"numbers >= 0")
    c.setdefault("set", [])
    if "select" in out:
        from .selection import check_select

        out["select"] = check_select(out["select"] or {})
    if "refine" in out:
        r = out["refine"]
        if "select" not in out:
            raise ValueError("pipeline refine needs a select section (it refines the chosen agent)")
        if (not isinstance(r, dict) or set(r) - {"set", "select"}
                or not isinstance(r.get("set", []), list)
                or not isinstance(r.get("select", {}), dict)):
            raise ValueError(f"pipeline refine = {r!r}: give {{set: [consolidate.key=value, ...], "
                             f"select: {{select.key: value, ...}}}}")
        r.setdefault("set", [])
        # the refined agents are chosen on the select section with these keys replaced
        r["select"] = check_select({**out["select"], **(r.get("select") or {})})
    return out


def _checkpoint_step(run_dir: str) -> int | None:
    """Step of a run's newest intact checkpoint (None: no checkpoint yet). A lost or garbled
    ``LATEST`` falls back to the newest intact ``step-N`` (``checkpoints.find_checkpoint``); step-N
    folders none of which is intact are an error, not a fresh start."""
    from .checkpoints import STEP_DIR, find_checkpoint
    from .storage import CorruptFileError

    root = os.path.join(run_dir, "checkpoints")
    if not os.path.isdir(root):
        return None
    try:
        name = os.path.basename(find_checkpoint(run_dir))
    except CorruptFileError as exc:
        if any(STEP_DIR.match(d) for d in os.listdir(root)):
            raise RuntimeError(f"specialist {run_dir}: {exc}") from None
        return None
    return int(name[5:]) if STEP_DIR.match(name) else None


def _die_with_parent() -> None:
    """Child processes end when the pipeline does, even on SIGKILL (Linux prctl), so that a
    resumed pipeline never races an orphaned specialist for its run folder."""
    try:
        ctypes.CDLL("libc.so.6", use_errno=True).prctl(1, signal.SIGTERM)  # PR_SET_PDEATHSIG
    except OSError:
        pass


def _ernest(args: list[str], log_path: str | None = None) -> subprocess.Popen:
    cmd = [sys.executable, "-m", "ernest_cpp.cli", *args]
    out = open(log_path, "a") if log_path else None
    try:
        env = dict(os.environ, PYTHONUNBUFFERED="1")  # the logs show progress as it happens
        return subprocess.Popen(cmd, stdout=out, stderr=subprocess.STDOUT if out else None,
                                env=env, preexec_fn=_die_with_parent)
    finally:
        if out:
            out.close()


def _run(args: list[str], what: str, log_path: str | None = None) -> None:
    p = _ernest(args, log_path)
    rc = p.wait()
    if rc != 0:
        where = f" (log: {log_path})" if log_path else ""
        raise RuntimeError(f"{what} failed with exit code {rc}{where}")


def _progress_line(name: str, run_dir: str, total: int) -> str:
    try:
        with open(os.path.join(run_dir, "progress.json")) as fh:
            p = json.load(fh)
    except (OSError, ValueError):
        return f"{name}: starting"
    ev = p.get("last_eval") or {}
    prog = f", eval progress {ev['path_progress']:.2f} m" if "path_progress" in ev else ""
    return (f"{name}: {p['step']}/{total} transitions ({100 * p['step'] / total:.0f} %), "
            f"{p['transitions_per_s']:.1f} transitions/s, {p['updates_per_s']:.1f} updates/s, "
            f"{p['elapsed_s'] / 60:.1f} min{prog}")


def _in_parallel(jobs: list, parallel: int, what: str, log=print, progress=None,
                 every: float = 0.0) -> None:
    """Runs ``jobs`` ``[(name, start, finished)]``, at most ``parallel`` at a time: ``start()``
    returns ``(process, log path)``, or None when there is nothing left to do; ``finished()`` is
    called when the process exits cleanly. A failure stops the others and raises. ``progress(name)``
    returns a line logged for every running job each ``every`` seconds."""
    todo, running, t_last = list(jobs), {}, 0.0
    while todo or running:
        while todo and len(running) < parallel:
            name, start, finished = todo.pop(0)  # started now, not when the pipeline started
            started = start()
            if started is not None:
                running[name] = (*started, finished)
        time.sleep(1.0)
        for name in list(running):
            proc, log_path, finished = running[name]
            rc = proc.poll()
            if rc is None:
                continue
            del running[name]
            if rc != 0:
                for p, _, _ in running.values():
                    p.terminate()
                raise RuntimeError(f"{what} {name} failed with exit code {rc} (log: {log_path})")
            finished()
        if progress is not None and running and time.monotonic() - t_last >= every:
            t_last = time.monotonic()
            for name in running:
                log("  " + progress(name))


def run_specialists(cfg: dict, log=print) -> list[str]:
    out, preset = cfg["out"], cfg["preset"]
    specs = {name: (s, os.path.join(out, name)) for name, s in cfg["specialists"].items()}

    def start(name):
        s, run_dir = specs[name]
        done_step = _checkpoint_step(run_dir)
        if done_step is not None and done_step >= s["steps"]:
            log(f"specialist {name}: done ({done_step} transitions)")
            return None
        # A resumed run keeps its saved settings (the preset is not read again).
        args = ["train", "--scenario", s["scenario"], "--steps", str(s["steps"]),
                "--run-dir", run_dir, "--set", "log.progress_bar=false"]
        args += ["--resume"] if done_step is not None else ["--preset", preset]
        for a in s["set"]:
            args += ["--set", str(a)]
        log(f"specialist {name}: {'resuming at ' + str(done_step) if done_step else 'start'}"
            f" ({s['steps']} transitions, log {run_dir}.log)")
        os.makedirs(out, exist_ok=True)
        return _ernest(args, run_dir + ".log"), run_dir + ".log"

    def progress(name):
        s, run_dir = specs[name]
        return _progress_line(name, run_dir, s["steps"])

    jobs = [(name, lambda n=name: start(n),
             lambda n=name: log(f"specialist {n}: done; {progress(n)}")) for name in specs]
    _in_parallel(jobs, cfg["parallel"], "specialist", log, progress, cfg["progress_every"])
    return [run_dir for _, run_dir in specs.values()]


def consolidation_dirs(cfg: dict) -> list[str]:
    """One consolidation folder per seed: ``consolidated`` for seed 0, ``consolidated-sN``."""
    return [os.path.join(cfg["out"], "consolidated" if v == 0 else f"consolidated-s{v}")
            for v in cfg["consolidate"]["seeds"]]


def run_consolidations(cfg: dict, dirs: list[str], cons_dirs: list[str], log=print) -> None:
    """``ernest consolidate`` once per seed, ``parallel`` processes at a time; a seed whose
    folder holds its final agent is skipped (a killed one starts again: it has no checkpoints
    to resume from, and takes minutes)."""

    def start(seed, d):
        if os.path.exists(os.path.join(d, "checkpoints", "LATEST")):
            log(f"  consolidation seed {seed}: done")
            return None
        args = _consolidate_args(cfg, dirs, d, [f"seed={seed}", *cfg["consolidate"]["set"]])
        log(f"  consolidation seed {seed}: start (log {d}.log)")
        return _ernest(args, d + ".log"), d + ".log"

    jobs = [(f"seed {seed}", lambda v=seed, d=d: start(v, d),
             lambda v=seed: log(f"  consolidation seed {v}: done"))
            for seed, d in zip(cfg["consolidate"]["seeds"], cons_dirs)]
    _in_parallel(jobs, cfg["parallel"], "consolidation", log)


def _consolidate_args(cfg: dict, dirs: list[str], out_dir: str, settings: list) -> list[str]:
    """``ernest consolidate`` over the specialists ``dirs`` into ``out_dir``, with ``settings``
    (``key=value``, later ones win)."""
    args = ["consolidate", *dirs, "--out", out_dir, "--preset", cfg["preset"],
            "--set", "log.progress_bar=false"]
    if "select" in cfg:
        args.append("--no-eval")  # the chosen agent's table is written by the select stage
    for a in settings:
        args += ["--set", str(a)]
    return args


def _chosen_table(cfg: dict, chosen: str, log=print) -> None:
    """The chosen agent against every specialist on every scenario (``out/evaluation.csv``)."""
    from .checkpoints import agent_from_checkpoint, load_checkpoint
    from .consolidate import evaluation_table

    out = cfg["out"]
    specialists = [load_checkpoint(os.path.join(out, n), with_buffer=False)
                   for n in cfg["specialists"]]
    ck = load_checkpoint(chosen, with_buffer=False)
    evaluation_table(agent_from_checkpoint(ck), specialists, ck["state"]["config"], out, log)


def _select_stage(cfg: dict, log=print) -> None:
    """Choose among the kept agents (``out/selected.json``, ``out/selection.csv``) and write the
    chosen one's table against every specialist on every scenario (``out/evaluation.csv``)."""
    from .selection import select_policy

    _chosen_table(cfg, select_policy(consolidation_dirs(cfg), cfg["select"], cfg["out"], log), log)


def _refine_stage(cfg: dict, dirs: list[str], chosen: str, log=print) -> None:
    """Continues the chosen agent on the pool (``refine.set``), then chooses among its kept agents
    and the chosen one on the validation episodes (``out/refined/selected.json``)."""
    from .selection import select_policy

    d = os.path.join(cfg["out"], "refined")
    if not os.path.exists(os.path.join(d, "checkpoints", "LATEST")):
        settings = [f"consolidate.init={chosen}", *cfg["consolidate"]["set"],
                    *cfg["refine"]["set"]]  # refine's settings win
        log(f"      refine {chosen} ({', '.join(cfg['refine']['set'])}; log {d}.log)")
        _run(_consolidate_args(cfg, dirs, d, settings), "refine", d + ".log")
    _chosen_table(cfg, select_policy([d], cfg["refine"]["select"], d, log, extra=[chosen]), log)


def _export(cfg: dict, consolidated: str) -> None:
    from .export import ExportError, check_replaceable

    policy = cfg["policy"]
    try:
        check_replaceable(policy)  # the final rename below must not replace a device or folder
    except ExportError as exc:
        raise RuntimeError(f"policy = {policy}: {exc}") from None
    tmp = policy + ".tmp.pt"
    _run(["export", consolidated, "--out", tmp], "export")
    _run(["stamp-policy", tmp], "stamp-policy")
    os.replace(tmp, policy)


def run_pipeline(cfg: dict, stages=STAGES, log=print) -> None:
    out = cfg["out"]
    t0 = time.monotonic()
    dirs = [os.path.join(out, n) for n in cfg["specialists"]]
    if "specialists" in stages:
        log(f"[1/6] specialists: {', '.join(cfg['specialists'])}, {cfg['parallel']} at a time")
        dirs = run_specialists(cfg, log)
    cons_dirs = consolidation_dirs(cfg)
    if "consolidate" in stages:
        log(f"[2/6] consolidate (seed 004 §4.6, Table 4), seeds "
            f"{', '.join(str(v) for v in cfg['consolidate']['seeds'])}")
        run_consolidations(cfg, dirs, cons_dirs, log)
    chosen = os.path.join(cons_dirs[0], "checkpoints", "consolidated")
    if "select" in cfg:
        selected = os.path.join(out, "selected.json")
        if "select" in stages:
            if os.path.exists(selected):
                log("[3/6] select: done")
            else:
                log("[3/6] select: every kept agent on the validation episodes")
                _select_stage(cfg, log)
        if os.path.exists(selected):
            with open(selected) as fh:
                chosen = json.load(fh)["checkpoint"]
        refined = os.path.join(out, "refined", "selected.json")
        if "refine" in cfg and os.path.exists(selected):
            if "select" in stages:
                if os.path.exists(refined):
                    log("      refine: done")
                else:
                    log("      refine: the chosen agent continued on the pool")
                    _refine_stage(cfg, dirs, chosen, log)
            if os.path.exists(refined):
                with open(refined) as fh:
                    chosen = json.load(fh)["checkpoint"]
    if "export" in stages:
        log(f"[4/6] export {chosen} -> {cfg['policy']}")
        _export(cfg, chosen)
    if "evaluate" in stages:
        ev = cfg["evaluate"]
        log(f"[5/6] evaluate: ernest reproduce over {ev['seeds']} seeds -> {out}/reproduce")
        _run(["reproduce", "--policy", cfg["policy"], "--seeds", str(ev["seeds"]),
              "--sections", str(ev["sections"]), "--out", os.path.join(out, "reproduce")],
             "evaluation", os.path.join(out, "reproduce.log"))
    if "report" in stages:
        from .training_report import write_report

        path = write_report(cfg, out)
        log(f"[6/6] report -> {path}")
    log(f"train-default: finished in {(time.monotonic() - t0) / 60:.1f} min")


def _command(args) -> int:
    from .commands import _passive_openmp

    _passive_openmp()
    cfg = load_pipeline(args.config)
    if args.out:
        cfg["out"] = args.out
    if args.policy:
        cfg["policy"] = args.policy
    stages = STAGES
    if args.stages:
        stages = tuple(s.strip() for s in args.stages.split(","))
        bad = sorted(set(stages) - set(STAGES))
        if bad:
            raise ValueError(f"--stages: unknown {', '.join(bad)}; choose from {', '.join(STAGES)}")
    try:
        run_pipeline(cfg, stages)
    except RuntimeError as exc:
        print(f"ernest train-default: {exc}", file=sys.stderr)
        return 1
    return 0


def add_parser(sub) -> None:
    p = sub.add_parser("train-default", help="train the default policy from scratch: "
                       "specialists, consolidation, export, evaluation (resumable)",
                       description=__doc__.split("\n\n")[0] + " Run it again to resume.")
    p.add_argument("--config", default=DEFAULT_FILE, help=f"pipeline file (default {DEFAULT_FILE})")
    p.add_argument("--out", help="run folder (default: the pipeline file's out)")
    p.add_argument("--policy", help="where the exported policy goes (default: the file's policy)")
    p.add_argument("--stages", help=f"comma-separated subset of {','.join(STAGES)}")
    p.set_defaults(func=_command)


if __name__ == "__main__":
    parser = argparse.ArgumentParser(prog="ernest")
    add_parser(parser.add_subparsers(dest="command", required=True))
    a = parser.parse_args()
    sys.exit(a.func(a))


def train_default(**options) -> int:
    """``ernest train-default`` from Python: one keyword per option, named as on the command line with
    underscores (``ernest train-default --help``), checked as there (``cli.run``), e.g.
    ``train_default(stages="report")``. Returns the exit status; errors raise."""
    from ..cli import run

    return run("train-default", **options)
