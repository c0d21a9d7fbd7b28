"""Every script in examples/ runs to the end and writes what its docstring promises."""

from __future__ import annotations

import os
import subprocess
import sys

import pytest

import ernest_cpp

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
EXAMPLES = os.path.join(ROOT, "examples")
PACKAGE_ROOT = os.path.dirname(os.path.dirname(os.path.abspath(ernest_cpp.__file__)))

# script -> files it writes into --out
OUTPUTS = {
    "drive_rover.py": ["drive_rover.png"],
    "soil_curves.py": ["soil_curves.png"],
    "td3_vs_sb3.py": ["td3_vs_sb3.csv"],
    "export_and_run_cpp.py": ["policy.pt", "runtime_actions.csv", "runtime_telemetry.csv"],
    "gait_transition.py": ["gait_transition.png"],
    "footfall_step.py": ["footfall_map.png", "footfall_step.png"],
}


def test_every_example_is_listed():
    assert sorted(OUTPUTS) == sorted(f for f in os.listdir(EXAMPLES) if f.endswith(".py"))


@pytest.mark.parametrize("script", sorted(OUTPUTS))
def test_example_runs(script, tmp_path):
    env = dict(os.environ, MPLBACKEND="Agg", OMP_WAIT_POLICY="PASSIVE")
    # the ernest_cpp this test imports, also when the run is from the output folder (where a
    # relative PYTHONPATH would not reach it)
    env["PYTHONPATH"] = os.pathsep.join([PACKAGE_ROOT, env.get("PYTHONPATH", "")])
    r = subprocess.run([sys.executable, os.path.join(EXAMPLES, script), "--out", str(tmp_path)],
                       capture_output=True, text=True, timeout=120, env=env, cwd=tmp_path)
    assert r.returncode == 0, r.stdout + r.stderr
    for name in OUTPUTS[script]:
        path = tmp_path / name
        assert path.is_file() and path.stat().st_size > 0, (name, r.stdout)
