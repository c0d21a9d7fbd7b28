"""The ``ernest`` console command. Each subsystem registers its subcommands here."""

from __future__ import annotations

import argparse
import sys

from . import (__version__, evaluate, perception_demo, reproduce, rover_statics, slope_demo,
               soil_curves, transitions, walker_demo, footfall_demo)
from .rl import commands as rl_commands
from .rl import pipeline as rl_pipeline
from .viewer import command as view_command

# Each module exposes add_parser(subparsers) and sets `func` on its parser.
_COMMANDS = [soil_curves, evaluate, rl_commands, rl_pipeline, transitions, slope_demo, reproduce,
             rover_statics, walker_demo, perception_demo, footfall_demo, view_command]

DESCRIPTION = ("ERNEST rover simulation, training and evaluation: run `ernest COMMAND --help` "
               "for one command's options.")


def _plain(text: str | None) -> str | None:
    """Help text without reStructuredText markup (module docstrings serve as descriptions)."""
    return text.replace("``", "`") if text else text


def build_parser() -> tuple[argparse.ArgumentParser, argparse._SubParsersAction]:
    parser = argparse.ArgumentParser(prog="ernest", description=DESCRIPTION)
    parser.add_argument("--version", action="version", version=f"ernest {__version__}")
    sub = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")
    for module in _COMMANDS:
        module.add_parser(sub)
    for p in sub.choices.values():
        p.description = _plain(p.description)
    return parser, sub


def main(argv: list[str] | None = None) -> int:
    parser, sub = build_parser()
    args, unknown = parser.parse_known_args(argv)
    if unknown:  # the subcommand's usage, not the top-level one (argparse's default)
        sub.choices[args.command].error(f"unrecognized arguments: {' '.join(unknown)}")
    try:
        return int(args.func(args) or 0)
    except (ValueError, OSError) as exc:  # bad user input or path: one clear line, no traceback
        if isinstance(exc, OSError) and exc.filename is not None and exc.strerror:
            msg = f"{exc.filename}: {exc.strerror}"
        else:
            msg = str(exc)
        print(f"ernest {args.command}: error: {msg}", file=sys.stderr)
        return 2


if __name__ == "__main__":
    sys.exit(main())
