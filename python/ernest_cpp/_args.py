"""Argument types shared by the ``ernest`` subcommands (argparse names the option in the error)."""

from __future__ import annotations

import argparse


def seed(text: str) -> int:
    """A random seed: a whole number in [0, 2**64) (the C++ generators take uint64)."""
    try:
        value = int(text, 0)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not a whole number") from None
    if not 0 <= value < 2 ** 64:
        raise argparse.ArgumentTypeError(f"{value} is outside [0, 2**64)")
    return value
