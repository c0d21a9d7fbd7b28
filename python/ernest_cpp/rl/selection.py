"""Choosing the consolidated policy on validation episodes (``ernest train-default``'s select stage).

Consolidation trains a fresh actor–critic on the pooled experience alone (seed 004 §4.6). On our
pool (about 2e5 transitions, the paper's is 4e6) the offline training swings: the policy a
thousand iterations earlier or later, or with another seed, may climb the step in none of ten
seeds instead of seven (``policies/TRAINING.md``). The pipeline therefore keeps the agent every
``consolidate.keep_every`` iterations of each consolidation seed and picks one here, on episodes
the reported evaluation never runs: the wheel-high step and the Bickler trap at seeds
``select.seeds`` (the reports use 0-9) and the slope course at the angles ``select.slopes_deg``
on dry M90 and wet sand, at seeds ``select.slope_seeds``, each seed drawing its angle within
``select.slope_spread_deg`` of the nominal one (as the reports' 20 ± 0.5° ensembles do). With
held-out slope seeds (10 or above) the validation may use the reported 20° ensemble's
distribution; with seeds below 10 it must use other angles.

Ranking: first the number of the controller's four targets a candidate meets on these
episodes (all four wheels up the step in at least ``select.min_crossed`` of the episodes; across
the trap in as many; a lower travel reduction than the crawling gait's on every validation slope;
tracked within ``select.max_lateral`` metres on every one), then the obstacle crossings (the
paper's headline: the fractions of step and trap episodes crossed, summed), then the lower mean
slope travel reduction.

Each candidate's results are saved in its checkpoint folder (``validation.json``, with the courses
they were run on), so a killed selection, or one over more consolidation seeds, evaluates only
the candidates it has not seen.
"""

from __future__ import annotations

import csv
import json
import os
import time
from concurrent.futures import ProcessPoolExecutor
import multiprocessing as mp

import numpy as np

from .._csv import header

SOILS = ("m90", "wet_sand")


def validation_courses(sel: dict) -> list[tuple[str, str, dict, str | None, list[int]]]:
    """(label, env id, kwargs, obstacle kind, seeds) of every validation course."""
    lo, hi = sel["seeds"]
    seeds = list(range(int(lo), int(hi)))
    out = [("step", "ernest/WheelStep-v0", {}, "step", seeds),
           ("trap", "ernest/BicklerTrap-v0", {}, "bickler", seeds)]
    slope_seeds = list(range(*(int(v) for v in sel["slope_seeds"])))
    for deg in sel["slopes_deg"]:
        rand = {"eval_slope_deg": float(deg)}
        if sel["slope_spread_deg"] > 0:
            rand["eval_slope_spread_deg"] = float(sel["slope_spread_deg"])
        for soil in SOILS:
            out.append((f"slope {deg:g} {soil}", "ernest/SlopeEval-v0",
                        {"soil": soil, "randomisation": dict(rand)}, None, slope_seeds))
    return out


def _seed_range(out: dict, key: str) -> list[int]:
    s = out[key]
    if (not isinstance(s, list) or len(s) != 2 or not all(isinstance(v, int) for v in s)
            or not 0 <= s[0] < s[1]):
        raise ValueError(f"pipeline select.{key} = {s!r} must be [first, end) with 0 <= first < end")
    return s


def check_select(sel: dict) -> dict:
    """The ``select`` section with its defaults, validated."""
    out = {"seeds": [100, 120], "slopes_deg": [18.0, 22.0], "slope_seeds": [0, 1],
           "slope_spread_deg": 0.0, "max_lateral": 0.3, "min_crossed": 0.8, "workers": 2}
    unknown = sorted(set(sel) - set(out))
    if unknown:
        raise ValueError(f"pipeline select: unknown key(s) {', '.join(unknown)}; known: "
                         f"{', '.join(sorted(out))}")
    out.update(sel)
    s = _seed_range(out, "seeds")
    if not 10 <= s[0]:
        raise ValueError(f"pipeline select.seeds = {s!r} must not overlap the reported seeds "
                         f"0-9: start at 10 or above")
    held_out = _seed_range(out, "slope_seeds")[0] >= 10
    d = out["slopes_deg"]
    if not isinstance(d, list) or not d or not all(
            isinstance(v, (int, float)) and 0 < v <= 45 and (held_out or v != 20) for v in d):
        raise ValueError(f"pipeline select.slopes_deg = {d!r} must list angles in (0, 45]"
                         + ("" if held_out else " other than the reported 20 (or use "
                            "select.slope_seeds of 10 or above)"))
    sp = out["slope_spread_deg"]
    if isinstance(sp, bool) or not isinstance(sp, (int, float)) or not 0 <= sp <= 5:
        raise ValueError(f"pipeline select.slope_spread_deg = {sp!r} must be in [0, 5] [deg]")
    if not (isinstance(out["max_lateral"], (int, float)) and out["max_lateral"] > 0):
        raise ValueError(f"pipeline select.max_lateral = {out['max_lateral']!r} must be > 0 [m]")
    if not (isinstance(out["min_crossed"], (int, float)) and 0 < out["min_crossed"] <= 1):
        raise ValueError(f"pipeline select.min_crossed = {out['min_crossed']!r} must be in (0, 1]")
    w = out["workers"]
    if isinstance(w, bool) or not isinstance(w, int) or w < 1:
        raise ValueError(f"pipeline select.workers = {w!r} must be a whole number >= 1")
    return out


def _episode(policy, env_id: str, kwargs: dict, kind: str | None, seed: int,
             passive: bool = False) -> tuple[float, float, bool]:
    """(travel reduction, largest |lateral deviation| [m], all four wheels over)."""
    from .. import evaluate as ev
    from ..reproduce import wheels_over

    m, hist, env, _ = ev.run_episode(env_id, kwargs, policy, passive, seed)
    over = bool(kind) and wheels_over(kind, env) == 4
    return float(m["travel_reduction"]), ev.max_lateral(env, hist), over


def course_results(policy, courses) -> dict:
    """{label: {"crossed": fraction or None, "tr": mean travel reduction, "lat": largest
    lateral deviation}} of ``policy(obs, env)`` (reset before each episode if it has ``reset``)
    on every course."""
    out = {}
    for label, env_id, kwargs, kind, seeds in courses:
        runs = [_episode(policy, env_id, kwargs, kind, s) for s in seeds]
        out[label] = {"crossed": float(np.mean([r[2] for r in runs])) if kind else None,
                      "tr": float(np.mean([r[0] for r in runs])),
                      "lat": float(max(r[1] for r in runs))}
    return out


def score(res: dict, crawling: dict, sel: dict) -> dict:
    """The ranking's terms: targets met (0-4), obstacle crossings (0-2), mean slope travel
    reduction."""
    slopes = [k for k in res if res[k]["crossed"] is None]
    met = (int(res["step"]["crossed"] >= sel["min_crossed"])
           + int(res["trap"]["crossed"] >= sel["min_crossed"])
           + int(all(res[k]["tr"] < crawling[k]["tr"] for k in slopes))
           + int(all(res[k]["lat"] <= sel["max_lateral"] for k in slopes)))
    return {"targets met": met, "crossings": float(res["step"]["crossed"] + res["trap"]["crossed"]),
            "slope TR mean": float(np.mean([res[k]["tr"] for k in slopes]))}


def selection_units(keys) -> dict[str, str]:
    """The unit of each ``selection.csv`` column (its header names it: ``step crossed [-]``,
    ``slope 18 m90 lateral [m]``): the largest lateral deviation in metres, every other column a
    pure number (fractions crossed, travel reductions, counts, names)."""
    return {k: "m" if k.endswith(" lateral") else "-" for k in keys}


def rank_key(row: dict) -> tuple:
    """Larger is better: targets met, then crossings, then the lower slope travel reduction."""
    return (row["targets met"], row["crossings"], -row["slope TR mean"])


VALIDATION_FILE = "validation.json"  # a candidate's results, kept in its checkpoint folder


def _courses_key(courses) -> list:
    """The validation courses as JSON (a cached result counts only for the same courses)."""
    return json.loads(json.dumps([list(c) for c in courses]))


def _cached(path: str, courses) -> dict | None:
    """The results saved by an earlier selection over the same courses, else None (a file that
    cannot be read is ignored: the candidate is evaluated again and the file rewritten)."""
    try:
        with open(os.path.join(path, VALIDATION_FILE)) as fh:
            saved = json.load(fh)
        if saved["courses"] == _courses_key(courses):
            return saved["results"]
    except (OSError, ValueError, KeyError, TypeError):
        pass
    return None


def _candidate(path: str, courses) -> dict:
    """One candidate's validation results: from its folder's ``validation.json`` when an earlier
    selection ran the same courses (a killed selection resumes there), else by running them."""
    res = _cached(path, courses)
    if res is not None:
        return {"path": path, "results": res, "seconds": 0.0, "cached": True}
    import torch

    from .checkpoints import agent_from_checkpoint, load_checkpoint

    torch.set_num_threads(1)
    agent = agent_from_checkpoint(load_checkpoint(path, with_buffer=False))
    t0 = time.perf_counter()
    res = course_results(lambda obs, env=None: agent.act(obs), courses)
    tmp = os.path.join(path, VALIDATION_FILE + ".tmp")
    with open(tmp, "w") as fh:
        json.dump({"courses": _courses_key(courses), "results": res}, fh, indent=1)
    os.replace(tmp, os.path.join(path, VALIDATION_FILE))
    return {"path": path, "results": res, "seconds": time.perf_counter() - t0, "cached": False}


def candidates(dirs: list[str]) -> list[str]:
    """Every kept agent (``iteration-N``) and the final one of each consolidation folder."""
    out = []
    for d in dirs:
        root = os.path.join(d, "checkpoints")
        names = sorted(n for n in os.listdir(root) if n.startswith("iteration-"))
        out += [os.path.join(root, n) for n in names] + [os.path.join(root, "consolidated")]
    return out


def _iteration(path: str) -> int:
    with open(os.path.join(path, "state.json")) as fh:
        return int(json.load(fh)["consolidation"]["iterations"])


def select_policy(dirs: list[str], sel: dict, out: str, log=print,
                  extra: list[str] | None = None) -> str:
    """Evaluate every candidate of the consolidation folders ``dirs`` (and the checkpoints
    ``extra``); write ``out/selection.csv`` (all of them, each column's unit in its header:
    ``selection_units``; the last row is the crawling gait's reference) and ``out/selected.json``;
    return the chosen checkpoint."""
    from ..envs.baselines import CrawlingGaitController

    sel = check_select(sel)
    courses = validation_courses(sel)
    slopes = [c for c in courses if c[3] is None]
    crawling = course_results(CrawlingGaitController(), slopes)
    paths = list(extra or []) + candidates(dirs)
    log(f"  {len(paths)} candidates, {len(courses)} validation courses "
        f"(step and trap seeds {sel['seeds'][0]}-{sel['seeds'][1] - 1}), {sel['workers']} workers")
    rows, t0 = [], time.perf_counter()
    with ProcessPoolExecutor(sel["workers"], mp_context=mp.get_context("spawn")) as pool:
        for r in pool.map(_candidate, paths, [courses] * len(paths)):
            res = r["results"]
            row = {"candidate": os.path.relpath(r["path"], out), "iteration": _iteration(r["path"]),
                   **score(res, crawling, sel)}
            for label, v in res.items():
                if v["crossed"] is not None:
                    row[f"{label} crossed"] = v["crossed"]
                else:
                    row[f"{label} TR"] = v["tr"]
                    row[f"{label} lateral"] = v["lat"]
            rows.append(row)
            log(f"  {row['candidate']}: {row['targets met']} targets met, step "
                f"{res['step']['crossed']:.2f}, trap {res['trap']['crossed']:.2f}"
                f"{' (saved results)' if r['cached'] else ''}, "
                f"{len(rows)}/{len(paths)}, {time.perf_counter() - t0:.0f} s")
    best = max(rows, key=rank_key)
    crawl_row = {"candidate": "crawling gait (reference)"}
    for label, v in crawling.items():
        crawl_row[f"{label} TR"], crawl_row[f"{label} lateral"] = v["tr"], v["lat"]
    keys = list(rows[0])
    tmp = os.path.join(out, "selection.csv.tmp")
    with open(tmp, "w", newline="") as fh:
        w = csv.writer(fh)
        w.writerow(header(keys, selection_units(keys)))
        w.writerows([r.get(k, "") for k in keys] for r in rows + [crawl_row])
    os.replace(tmp, os.path.join(out, "selection.csv"))
    chosen = os.path.normpath(os.path.join(out, best["candidate"]))
    tmp = os.path.join(out, "selected.json.tmp")
    with open(tmp, "w") as fh:
        json.dump({"checkpoint": chosen, "targets met": best["targets met"],
                   "crossings": best["crossings"], "iteration": best["iteration"], "select": sel},
                  fh, indent=1)
    os.replace(tmp, os.path.join(out, "selected.json"))
    log(f"  chosen: {best['candidate']} ({best['targets met']} targets met, crossings "
        f"{best['crossings']:.2f})")
    return chosen


__all__ = ["select_policy", "check_select", "validation_courses", "course_results", "score",
           "rank_key", "candidates", "selection_units"]
