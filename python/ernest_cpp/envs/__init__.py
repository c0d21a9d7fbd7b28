"""Gymnasium environments of seed 004 §4.5 (training scenarios) and §5 (evaluation courses).

Registered ids (kwargs of ``gymnasium.make`` go to :class:`ErnestEnv`); each scenario's short name
(``SCENARIOS``, what every command line takes) maps to one. Each stands on its scenario's soil
unless ``soil`` is given (``core.default_soil``: Table 2's dry sand for the Bickler trap, M90
elsewhere; ``ernest_runtime`` takes the same)::

    ernest/RockField-v0  ernest/Step-v0  ernest/Ripples-v0  ernest/Slope-v0
    ernest/BicklerTrap-v0  ernest/SlopeEval-v0  ernest/WheelStep-v0  ernest/Course-v0
    ernest/Flat-v0

``make_vec(id, num_envs)`` gives the C++-backed vector environment.

From code that has not imported this package: ``gym.make("ernest_cpp.envs:ernest/Slope-v0")``
(Gymnasium imports the module before the id). Gymnasium 1.x no longer loads the
``gymnasium.envs`` entry point of pyproject.toml, so a bare ``gym.make("ernest/Slope-v0")`` needs
``import ernest_cpp.envs`` first.
"""

import gymnasium as gym

from ..scenarios import SCENARIOS, scenario_env_id, scenario_name  # noqa: F401

from .core import ErnestEnv, make_options  # noqa: F401
from .vector import ErnestVectorEnv, make_vec  # noqa: F401

#: Gymnasium id -> the scenario's short name (``ernest_cpp.scenarios.SCENARIOS`` inverted).
ENV_IDS = {env_id: name for name, env_id in SCENARIOS.items()}




def register_envs() -> None:
    """Register the ids above (idempotent). Runs on import of this module; gymnasium < 1.0 also
    runs it through the plugin entry point, gymnasium 1.x does not (see the module docstring)."""
    for env_id, scenario in ENV_IDS.items():
        if env_id not in gym.registry:
            gym.register(id=env_id, entry_point="ernest_cpp.envs.core:ErnestEnv",
                         kwargs={"scenario": scenario},
                         disable_env_checker=True)


register_envs()
