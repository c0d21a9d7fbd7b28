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


def command_argv(command: str, **options) -> list[str]:
    """The command line ``ernest COMMAND ...`` for keyword options: each keyword is an option's
    name with underscores (``out="x"`` -> ``--out x``, ``no_video=True`` -> ``--no-video``,
    ``scenario=["step", "bickler"]`` -> ``--scenario step --scenario bickler``, positional
    arguments by their name: ``runs=["runs/a"]``); None leaves an option at its default. An
    unknown command or keyword raises TypeError naming the known ones."""
    _, sub = build_parser()
    if command not in sub.choices:
        raise TypeError(f"unknown command {command!r}; commands: {', '.join(sub.choices)}")
    actions = {a.dest: a for a in sub.choices[command]._actions
               if a.dest not in ("help", argparse.SUPPRESS)}
    unknown = sorted(set(options) - set(actions))
    if unknown:
        raise TypeError(f"ernest {command}: unknown keyword(s) {', '.join(unknown)}; known: "
                        f"{', '.join(sorted(actions))}")
    argv, positional = [command], []
    for dest, value in options.items():
        action = actions[dest]
        if value is None:
            continue
        values = [str(v) for v in value] if isinstance(value, (list, tuple)) else [str(value)]
        if not action.option_strings:  # a positional argument
            positional += values
        elif action.nargs == 0:  # a flag (store_true): given when True
            if not isinstance(value, bool):
                raise TypeError(f"ernest {command}: {dest} = {value!r} must be True or False")
            if value:
                argv.append(action.option_strings[-1])
        elif isinstance(action, argparse._AppendAction):
            for v in values:
                argv += [action.option_strings[-1], v]
        else:
            argv += [action.option_strings[-1], *values]
    return argv + (["--", *positional] if positional else [])


def run(command: str, **options) -> int:
    """``ernest COMMAND`` from Python with keyword arguments (``command_argv``), e.g.
    ``cli.run("evaluate", out="out/report", scenario=["bickler"], no_video=True)``. The options are
    checked as on the command line; a bad value raises ValueError with the command's message, and
    the command's own errors propagate (no exit, no one-line report). Returns the exit status."""
    import contextlib
    import io

    argv = command_argv(command, **options)
    parser, _ = build_parser()
    err = io.StringIO()
    try:
        with contextlib.redirect_stderr(err):
            args = parser.parse_args(argv)
    except SystemExit:
        lines = err.getvalue().strip().splitlines()
        raise ValueError(lines[-1] if lines else f"ernest {command}: invalid options") from None
    return int(args.func(args) or 0)


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
