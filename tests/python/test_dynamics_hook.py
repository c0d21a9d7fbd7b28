"""The solver hook checked: whether ODE's constraint solves reach the sparse
solver is visible from Python (``fast_lcp_active()``, ``SolverStats.fast_lcp``), and a hook found
off gives one RuntimeWarning."""

import warnings

import pytest

from ernest_cpp import dynamics as D


def test_fast_path_is_active_in_this_build_and_visible_per_simulator():
    assert D.fast_lcp_active() is True
    fast = D.make_sim("rigid")
    dense = D.make_sim("rigid", sparse_lcp=False)
    assert fast.solver_stats.fast_lcp is True
    assert dense.solver_stats.fast_lcp is False  # SimOptions.sparse_lcp off
    fast.reset(0.0, 0.0, 0.0)
    for _ in range(8):
        fast.step()
    assert fast.solver_stats.sparse_solves > 0  # the flag says what happens
    assert "fast_lcp=True" in repr(fast.solver_stats)
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # active: no warning
        D.fast_lcp_active()


class _HookOff:
    """The C++ functions as with a libode whose call does not reach the hook."""

    @staticmethod
    def fast_lcp_active():
        return False

    @staticmethod
    def fast_lcp_inactive_reason():
        return "ODE's constraint solves do not reach ernest's dxSolveLCP"


def test_an_inactive_hook_warns_once(monkeypatch):
    monkeypatch.setattr(D, "_dyn", _HookOff)
    monkeypatch.setattr(D, "_fast_lcp_warned", False)
    with pytest.warns(RuntimeWarning, match="fast constraint solver is off .*do not reach"):
        assert D.fast_lcp_active() is False
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # the second time: no warning
        assert D.fast_lcp_active() is False
