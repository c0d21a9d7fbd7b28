"""The ``ernest`` console command. Each subsystem registers its subcommands here."""

from __future__ import annotations

import argparse
import sys

from . import (evaluate, perception_demo, reproduce, rover_statics, slope_demo, soil_curves,
               transitions, walker_demo)
from .rl import commands as rl_commands

# Each module exposes add_parser(subparsers) and sets `func` on its parser.
_COMMANDS = [soil_curves, evaluate, rl_commands, transitions, slope_demo, reproduce,
             rover_statics, walker_demo, perception_demo]


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="ernest", description=__doc__)
    sub = parser.add_subparsers(dest="command", required=True)
    for module in _COMMANDS:
        module.add_parser(sub)
    args = parser.parse_args(argv)
    try:
        return int(args.func(args) or 0)
    except ValueError as exc:  # bad user input: one clear line, no traceback
        print(f"ernest {args.command}: error: {exc}", file=sys.stderr)
        return 2


if __name__ == "__main__":
    sys.exit(main())
