"""Reinforcement learning for ERNEST (seed 004 §4): TD3 with the paper's networks, §4.4 Markov
exploration, FTS noise injection on replay sampling, specialist training, consolidation (§4.6) and
TorchScript export.

Submodules are imported lazily so that ``import ernest_cpp`` does not load torch:
``ernest_cpp.rl.td3``, ``.networks``, ``.exploration``, ``.replay``, ``.layout``, ``.trainer``,
``.consolidate``, ``.export``, ``.config``, ``.toy_envs``; ``.ray_backend`` and ``.ray_trainer``
(``ernest train --backend ray``) need the optional extra ernest-cpp[ray].
"""

from __future__ import annotations

import importlib

_SUBMODULES = ("config", "consolidate", "exploration", "export", "layout", "networks", "ray_backend",
               "ray_trainer", "replay", "storage", "td3", "toy_envs", "trainer")
_NAMES = {"TD3": "td3", "TD3Config": "td3", "Actor": "networks", "Critic": "networks",
          "TwinCritic": "networks", "MarkovExploration": "exploration",
          "GaussianExploration": "exploration", "ReplayBuffer": "replay",
          "CorruptFileError": "storage", "ObservationLayout": "layout", "paper_layout": "layout",
          "Trainer": "trainer", "RayTrainer": "ray_trainer", "consolidate_runs": "consolidate", "export_actor": "export",
          "load_policy": "export", "build_config": "config"}

__all__ = list(_SUBMODULES) + list(_NAMES)


def __getattr__(name):
    if name in _SUBMODULES:
        return importlib.import_module(f".{name}", __name__)
    if name in _NAMES:
        return getattr(importlib.import_module(f".{_NAMES[name]}", __name__), name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
