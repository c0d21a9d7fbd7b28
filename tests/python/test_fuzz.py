"""Property-based fuzzing of every bound module's public functions, classes (constructors and
methods) and option structs, and of the Gymnasium environments (fuzz_child.py draws the inputs
with hypothesis). One subprocess per module and seed, so that an abort or a segfault is counted;
a call still running a few seconds after its interrupt signal is counted as a hang.

Must hold: no crash, no hang, no NaN or inf returned for finite inputs (where NaN is not a
documented "no value"), and every error a ValueError/TypeError/RuntimeError (IndexError,
OverflowError, KeyError) naming what was wrong. A call that runs past ERNEST_FUZZ_CALL_SECONDS is
sent SIGALRM, whose handler raises like Ctrl-C's: it must stop within ERNEST_FUZZ_GRACE_SECONDS.

The normal run (pytest) uses a fixed seed (0) and 20 examples per target: about 5000 inputs in
35-40 s on two cores. The longer campaign (benchmarks/RESULTS.md, "Robustness"):

    ERNEST_FUZZ_EXAMPLES=60 ERNEST_FUZZ_SEEDS=0-6 ERNEST_FUZZ_JOBS=2 \\
        PYTHONPATH=python .venv/bin/python tests/python/test_fuzz.py

prints the counts (inputs, crashes, hangs, non-finite outputs, unclear errors, skipped targets)
as JSON.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
import time
from concurrent.futures import ThreadPoolExecutor

HERE = os.path.dirname(os.path.abspath(__file__))
# "envs_gym": the Gymnasium environments (ernest_cpp.envs); the others are ernest_cpp._core's.
MODULES = ("soil", "dynamics", "envs", "opt", "sensing", "statics", "walker", "perception",
           "footfall", "walker_sim", "envs_gym")
COUNTS = ("inputs", "ok", "errors", "interrupted", "late", "unclear", "nonfinite", "crashes",
          "hangs", "skipped")


def _seeds(text: str) -> list[int]:
    if "-" in text:
        lo, hi = text.split("-")
        return list(range(int(lo), int(hi) + 1))
    return [int(s) for s in text.split(",")]


def run_batch(module: str, seed: int, examples: int, timeout: float) -> dict:
    """Counts of one child over one module's targets; a crash or hang names its last call."""
    code = ("import sys; sys.path.insert(0, %r); import fuzz_child as F; "
            "sys.exit(F.main([%r, %r] + F.public_targets(%r)))" % (HERE, str(seed), str(examples),
                                                                    module))
    env = dict(os.environ)
    env["PYTHONFAULTHANDLER"] = "1"
    start = time.monotonic()
    try:
        r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                           timeout=timeout, env=env)
        out, err, rc, hung = r.stdout, r.stderr, r.returncode, False
    except subprocess.TimeoutExpired as exc:  # a backstop: the child's watchdog ends a hang first
        out = exc.stdout.decode() if isinstance(exc.stdout, bytes) else (exc.stdout or "")
        err, rc, hung = "", None, True
    result = {k: 0 for k in COUNTS}
    result.update(samples={}, seconds=time.monotonic() - start)
    lines = out.splitlines()
    final = [l for l in lines if l.startswith("RESULT ")]
    if final and rc == 0:
        data = json.loads(final[-1][len("RESULT "):])
        result.update(data["counts"])
        result["samples"] = data["samples"]
        return result
    calls = [l for l in lines if l.startswith("CALL ")]
    result["inputs"] = len(calls)
    last = calls[-1][len("CALL "):][:600] if calls else "(before the first call)"
    hung = hung or "Timeout (" in err  # faulthandler.dump_traceback_later's exit
    kind = "hangs" if hung else "crashes"
    result[kind] = 1
    why = "still running after its interrupt signal" if hung else f"exit status {rc}"
    result["samples"][kind] = [f"{module} seed {seed}: {why} in {last}; {err[-800:]}"]
    return result


def campaign(examples: int, seeds: list[int], timeout: float, jobs: int) -> dict:
    total = {k: 0 for k in COUNTS}
    total.update(batches=0, seconds=0.0, samples={}, max_interrupt_delay=0.0)
    batches = [(m, s) for s in seeds for m in MODULES]
    with ThreadPoolExecutor(max_workers=jobs) as pool:
        for r in pool.map(lambda b: run_batch(b[0], b[1], examples, timeout), batches):
            total["batches"] += 1
            for k in COUNTS:
                total[k] += r[k]
            total["max_interrupt_delay"] = max(total["max_interrupt_delay"],
                                               r.get("max_interrupt_delay", 0.0))
            total["seconds"] += r["seconds"]
            for k, v in r["samples"].items():
                bucket = total["samples"].setdefault(k, [])
                bucket.extend(x for x in v[:60] if x not in bucket)
    total["skipped"] = len(total["samples"].get("skipped", []))  # distinct targets
    return total


def test_fuzz_every_module_with_a_fixed_seed():
    examples = int(os.environ.get("ERNEST_FUZZ_EXAMPLES", "20"))
    seeds = _seeds(os.environ.get("ERNEST_FUZZ_SEEDS", "0"))
    start = time.monotonic()
    t = campaign(examples, seeds, float(os.environ.get("ERNEST_FUZZ_TIMEOUT", "600")),
                 int(os.environ.get("ERNEST_FUZZ_JOBS", "2")))
    summary = {k: t[k] for k in COUNTS + ("max_interrupt_delay",)}
    summary["wall_s"] = round(time.monotonic() - start, 1)
    print("fuzz:", json.dumps(summary), "skipped:", t["samples"].get("skipped"))
    assert t["inputs"] > 5000, summary
    assert t["crashes"] == 0 and t["hangs"] == 0, t["samples"]
    assert t["nonfinite"] == 0, t["samples"].get("nonfinite")
    assert t["unclear"] == 0, t["samples"].get("unclear")
    # every target is reached: a new class without a default constructor needs an entry in
    # fuzz_child.FACTORIES (a valid instance), a new argument type one in arg_strategy
    assert t["skipped"] == 0, t["samples"].get("skipped")


if __name__ == "__main__":
    start = time.monotonic()
    result = campaign(int(os.environ.get("ERNEST_FUZZ_EXAMPLES", "60")),
                      _seeds(os.environ.get("ERNEST_FUZZ_SEEDS", "0-9")),
                      float(os.environ.get("ERNEST_FUZZ_TIMEOUT", "3600")),
                      int(os.environ.get("ERNEST_FUZZ_JOBS", "2")))
    result["wall_s"] = round(time.monotonic() - start, 1)
    print(json.dumps(result, indent=1))
