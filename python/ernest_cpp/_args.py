"""Argument types shared by the ``ernest`` subcommands (argparse names the option in the error)."""

from __future__ import annotations

import argparse
import math


def seed(text: str) -> int:
    """A random seed: a whole number in [0, 2**64) (the C++ generators take uint64)."""
    try:
        value = int(text, 0)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not a whole number") from None
    if not 0 <= value < 2 ** 64:
        raise argparse.ArgumentTypeError(f"{value} is outside [0, 2**64)")
    return value


def positive_finite(text: str) -> float:
    """A finite number > 0 (a rate in Hz): refuses 0, negatives, nan and inf."""
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not a number") from None
    if not (math.isfinite(value) and value > 0):
        raise argparse.ArgumentTypeError(f"{text} must be a finite number > 0")
    return value


def in_range(lo: float, hi: float, kind: type = float):
    """An argument type for a number of `kind` in [lo, hi]: argparse names the option and exits 2."""

    def parse(text: str):
        try:
            value = kind(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"{text!r} is not a {kind.__name__}") from None
        if not (math.isfinite(value) and lo <= value <= hi):
            raise argparse.ArgumentTypeError(f"{text} is outside the allowed range [{lo}, {hi}]")
        return value

    parse.__name__ = kind.__name__  # argparse's "invalid <name> value" message
    return parse
