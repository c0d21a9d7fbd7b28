"""The report of a ``ernest train-default`` run: each specialist's learning curve against wall time
(``curves.png``) and ``training.md`` with the curves' tables, the consolidated policy against every
specialist (``consolidated/evaluation.csv``) and the reproduce findings of the exported policy."""

from __future__ import annotations

import csv
import os

from .._csv import bare


def _selection_section(out: str, top: int = 10) -> list[str]:
    """The select stage's best candidates (``selection.csv``; the last row is the crawling gait's
    reference) with the chosen one marked."""
    rows = _rows(os.path.join(out, "selection.csv"), bare_names=True)
    if len(rows) < 2:
        return []
    ref, rows = rows[-1], rows[:-1]
    slopes = [k[:-3] for k in rows[0] if k.endswith(" TR") and k != "slope TR mean"]
    rows.sort(key=lambda r: (-r["targets met"], -r["crossings"], r["slope TR mean"]))
    md = ["## Choosing the policy on validation episodes", "",
          f"{len(rows)} kept consolidation agents, best {min(top, len(rows))} "
          f"(`ernest_cpp.rl.selection`: targets met, then step and trap crossings, then slope "
          f"travel reduction; the first row is the policy). Step and trap: fraction of "
          f"episodes crossed; slopes: travel reduction / largest lateral deviation [m]; "
          f"crawling gait: "
          + ", ".join(f"{k} {_fmt(ref[k + ' TR'])} / {_fmt(ref[k + ' lateral'])}"
                      for k in slopes) + ".", "",
          "| candidate | targets met | step | trap | " + " | ".join(slopes) + " |",
          "|---|---|---|---|" + "---|" * len(slopes)]
    for r in rows[:top]:
        md.append(f"| {r['candidate']} | {int(r['targets met'])} | {_fmt(r['step crossed'])} | "
                  f"{_fmt(r['trap crossed'])} | " + " | ".join(
                      f"{_fmt(r[k + ' TR'])} / {_fmt(r[k + ' lateral'])}" for k in slopes)
                  + " |")
    return md + [""]


def _rows(path: str, bare_names: bool = False) -> list[dict]:
    """The rows of a CSV file, keyed by its headers or (``bare_names``) by the headers without
    their units (eval.csv: 'return [-]' -> 'return'; files written before the units were named
    read the same)."""
    key = bare if bare_names else str
    try:
        with open(path, newline="") as fh:
            return [{key(k): _num(v) for k, v in r.items()} for r in csv.DictReader(fh)]
    except OSError:
        return []


def _num(v):
    try:
        return float(v)
    except (TypeError, ValueError):
        return v


def _fmt(v, digits=2) -> str:
    return f"{v:.{digits}f}" if isinstance(v, float) else str(v)


def plot_curves(curves: dict, path: str) -> str | None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    if not any(curves.values()):
        return None
    fig, axes = plt.subplots(1, 2, figsize=(11, 4))
    for name, rows in curves.items():
        rows = [r for r in rows if isinstance(r.get("elapsed_s"), float)]
        if not rows:
            continue
        t = [r["elapsed_s"] / 60.0 for r in rows]
        axes[0].plot(t, [r.get("path_progress", float("nan")) for r in rows], "o-", label=name)
        axes[1].plot(t, [r.get("return", float("nan")) for r in rows], "o-", label=name)
    axes[0].set_ylabel("evaluation progress along the path [m]")
    axes[1].set_ylabel("evaluation return")
    for ax in axes:
        ax.set_xlabel("wall time [min]")
        ax.grid(alpha=0.3)
        ax.legend()
    fig.suptitle("Specialists' learning curves (deterministic policy, evaluation seeds)")
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path


def write_report(cfg: dict, out: str) -> str:
    curves = {name: _rows(os.path.join(out, name, "eval.csv"), bare_names=True)
              for name in cfg["specialists"]}
    png = plot_curves(curves, os.path.join(out, "curves.png"))
    md = ["# Default policy training", "", f"Pipeline: `ernest train-default` ({out}).", ""]
    if png:
        md += ["![learning curves](curves.png)", ""]
    for name, rows in curves.items():
        md += [f"## Specialist {name} ({cfg['specialists'][name]['scenario']})", "",
               "| transitions | wall time [min] | return | progress [m] | travel reduction |",
               "|---|---|---|---|---|"]
        for r in rows:
            md.append(f"| {int(r['step'])} | {_fmt(r.get('elapsed_s', 0.0) / 60.0, 1)} | "
                      f"{_fmt(r.get('return'), 1)} | {_fmt(r.get('path_progress'))} | "
                      f"{_fmt(r.get('episode_metrics.travel_reduction'))} |")
        md.append("")
    table = _rows(os.path.join(out, "evaluation.csv"), bare_names=True)  # the selected agent's
    if not table:
        table = _rows(os.path.join(out, "consolidated", "evaluation.csv"), bare_names=True)
    if table:
        md += ["## Consolidated policy against every specialist", "",
               "| environment | policy | return | progress [m] | travel reduction |",
               "|---|---|---|---|---|"]
        for r in sorted(table, key=lambda r: (r["env"], r["policy"] != "consolidated")):
            md.append(f"| {r['env']} | {r['policy']} | {_fmt(r.get('return'), 1)} | "
                      f"{_fmt(r.get('path_progress'))} | "
                      f"{_fmt(r.get('episode_metrics.travel_reduction'))} |")
        md.append("")
    md += _selection_section(out)
    rep = os.path.join(out, "reproduce", "report.md")
    if os.path.exists(rep):
        md += ["## Evaluation of the exported policy", "", f"See `{rep}`.", ""]
    path = os.path.join(out, "training.md")
    with open(path + ".tmp", "w") as fh:
        fh.write("\n".join(md))
    os.replace(path + ".tmp", path)
    return path
