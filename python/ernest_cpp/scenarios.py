"""The scenarios' names: one short name each, used by every command line (``ernest train
--scenario``, ``ernest evaluate --scenario``, ``ernest_runtime --scenario``) and by
``envs.ErnestEnv`` (which refuses any other name), and the Gymnasium id it is registered under.
The short names are the C++
core's (``envs.scenario_names()``); docs/envs.md has the table.
"""

from __future__ import annotations

#: short name -> Gymnasium id, training scenarios (seed 004 §4.5) first, then the evaluation
#: courses (§5) and flat ground.
SCENARIOS = {
    "rockfield": "ernest/RockField-v0",
    "step": "ernest/Step-v0",
    "ripples": "ernest/Ripples-v0",
    "slope": "ernest/Slope-v0",
    "bickler": "ernest/BicklerTrap-v0",
    "slope_eval": "ernest/SlopeEval-v0",
    "wheel_step": "ernest/WheelStep-v0",
    "course": "ernest/Course-v0",
    "flat": "ernest/Flat-v0",
}
#: The training scenarios of seed 004 §4.5 (Table 3), the specialists' defaults.
TRAINING_SCENARIOS = ("rockfield", "step", "ripples", "slope")


def scenario_env_id(name: str) -> str:
    """The Gymnasium id of the scenario ``name`` (a short name), else ValueError listing them."""
    if name not in SCENARIOS:
        raise ValueError(f"scenario {name!r}: choose one of {', '.join(SCENARIOS)}")
    return SCENARIOS[name]


def scenario_name(env_id: str) -> str:
    """The short name of a registered ernest Gymnasium id, else ValueError."""
    for name, gid in SCENARIOS.items():
        if gid == env_id:
            return name
    raise ValueError(f"{env_id!r} is not an ernest scenario id; ids: {', '.join(SCENARIOS.values())}")
