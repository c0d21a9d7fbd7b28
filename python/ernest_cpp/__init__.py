"""ernest-cpp: open rover-mobility stack (ERNEST soil and dynamics, gait transitions, RL).

Subpackages mirror the C++ tree: ``ernest_cpp.soil`` wraps ``cpp/soil``.
"""

from . import _pickle  # noqa: F401  (pickle/deepcopy of the bound option structs)
from . import dynamics, opt, rl, sensing, soil, statics, walker

__all__ = ["dynamics", "opt", "rl", "sensing", "soil", "statics", "walker"]
__version__ = "0.1.0"
