"""Two Python threads on one bound object: every object with mutable state refuses the second
thread with the documented RuntimeError ("in use by another thread") instead of corrupting
memory, and the objects documented as safe to share give the single-thread answers.

Each case runs in a child process (tests/python/threads_child.py), so a segfault or an abort
fails that case instead of killing the test run. The child prints the number of calls made, the
number refused, and any other error.
"""

from __future__ import annotations

import json
import pathlib
import subprocess
import sys

import pytest

CHILD = pathlib.Path(__file__).with_name("threads_child.py")

GUARDED = ["leg_ik", "vec_env", "gym_env", "rover_env", "stability_mapper", "planner",
           "segmenter", "walker_sim", "elevation_map", "stereo_mapper", "stereo_matcher"]
SHARED = ["raycaster", "soil", "walker_model"]


def run_case(case: str) -> dict:
    r = subprocess.run([sys.executable, str(CHILD), case], capture_output=True, text=True,
                       timeout=300)
    assert r.returncode == 0, f"{case}: exit {r.returncode}\n{r.stderr[-3000:]}"
    return json.loads(r.stdout.strip().splitlines()[-1])


@pytest.mark.parametrize("case", GUARDED)
def test_a_second_thread_is_refused_not_a_crash(case):
    res = run_case(case)
    assert res["other"] == [], res["other"]
    assert res["calls"] > 0
    assert res["after"] is True  # the object still works after the contest


@pytest.mark.parametrize("case", SHARED)
def test_objects_safe_to_share_give_single_thread_results(case):
    res = run_case(case)
    assert res["other"] == [] and res["refused"] == 0
    assert res["same"] is True


def test_the_second_thread_gets_the_documented_error():
    res = run_case("walker_sim_held")
    assert res["refused"] > 0
    assert "WalkerSim.joint_angles: the object is in use by another thread" in res["message"]
