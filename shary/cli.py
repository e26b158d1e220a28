"""The ``shary`` command: a parser built from the commands that packages register.

The engine does not know which parts are installed.  Each command is a Python
entry point in the group ``shary.commands`` whose name is the command's name
and whose value is a function ``add(subparsers)`` that adds that one command
(its arguments, and ``func`` in its defaults).  The engine's own commands, the
planner's and the simulator's are registered this way in ``pyproject.toml``;
another package adds commands by declaring entry points in the same group.

A command whose entry point cannot be loaded (its package is absent, or it is
broken) stays in the list, marked unavailable; running it prints one line
saying why and exits with status 2.  The other commands work as usual.

Problems in a user's file are printed as ``FILE:LINE:COL: error: …`` on
standard error and the command exits with status 2; nothing a file contains
can make it print a traceback.
"""

from __future__ import annotations

import argparse
import sys
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from importlib import metadata
from pathlib import Path
from typing import NoReturn

from shary.log.terminal import emit_json, error, output_refused, refused
from userfiles.errors import FileError
from userfiles.outputs import OutputError
from userfiles.reader import allow_paths

GROUP = "shary.commands"
"""The entry-point group that commands register in."""


@dataclass(frozen=True)
class Unavailable:
    """A registered command that cannot be offered, and why (one line)."""

    name: str
    reason: str

    def __call__(self, args: argparse.Namespace) -> int:
        return error(f"'shary {self.name}' is unavailable: {self.reason}",
                     json_mode="--json" in getattr(args, "rest", ()))


def main(argv: Sequence[str] | None = None) -> int:
    parser = build_parser()
    if parser is None:
        return error(f"no shary commands are registered (entry-point group {GROUP!r}); the "
                     "installed package metadata is stale or missing: reinstall shary "
                     "(pip install -e . in a checkout)")
    argv = list(sys.argv[1:] if argv is None else argv)
    _Parser.json_mode = "--json" in argv
    args = parser.parse_args(argv)
    allow_paths(args.allow_path)
    json_mode = bool(getattr(args, "json", False))
    try:
        return int(args.func(args) or 0)
    except FileError as err:
        return refused(err.problems, json_mode=json_mode)
    except OutputError as err:  # PATH: error: … (no line: an output has none)
        return output_refused(err, json_mode=json_mode)
    except KeyboardInterrupt:
        return 130


def build_parser() -> _Parser | None:
    """The ``shary`` parser with every registered command (None when none is registered)."""
    commands = registered_commands()
    if not commands:
        return None
    parser = _Parser(
        prog="shary", description="A SHARY-style supervision engine for robots that work "
        "with people.", formatter_class=_Formatter)
    parser.add_argument("--version", action="version", version=f"shary {installed_version()}")
    parser.add_argument("--allow-path", action="append", default=[], type=Path,
                        metavar="FOLDER", help="a folder that user files may name files in, "
                        "besides their own folder (repeatable)")
    sub = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")
    for name, entry in sorted(commands.items()):
        problem = entry if isinstance(entry, Unavailable) else _add(sub, name, entry)
        if problem is not None:
            _add_unavailable(sub, problem)
    return parser


def registered_commands() -> dict[str, metadata.EntryPoint | Unavailable]:
    """Command name -> its entry point; a name claimed twice becomes :class:`Unavailable`."""
    found: dict[str, metadata.EntryPoint | Unavailable] = {}
    for entry in metadata.entry_points(group=GROUP):
        first = found.get(entry.name)
        if first is None:
            found[entry.name] = entry
        elif isinstance(first, metadata.EntryPoint) and first.value != entry.value:
            found[entry.name] = Unavailable(entry.name, f"two packages register it "
                                            f"({first.value} and {entry.value})")
    return found


def installed_version() -> str:
    """The installed distribution's version (``unknown`` when run from an uninstalled tree)."""
    try:
        return metadata.version("shary")
    except metadata.PackageNotFoundError:
        return "unknown"


def _add(sub: argparse._SubParsersAction, name: str,
         entry: metadata.EntryPoint) -> Unavailable | None:
    """Load one command's entry point and let it add itself; why not, if it cannot."""
    where = f"entry point '{name} = {entry.value}'"
    try:
        add: Callable[[argparse._SubParsersAction], object] = entry.load()
    except ModuleNotFoundError as err:
        missing = (err.name or "?").split(".")[0]
        if entry.module.split(".")[0] == missing:
            return Unavailable(name, f"the package '{missing}' that provides it is not "
                               f"installed ({where})")
        return Unavailable(name, f"{where} needs '{err.name}', which is not installed")
    except Exception as err:  # noqa: BLE001 -- any failure of a plugin is reported, not raised
        return Unavailable(name, f"{where} failed to load: {type(err).__name__}: {err}")
    try:
        add(sub)
    except Exception as err:  # noqa: BLE001
        _forget(sub, name)
        return Unavailable(name, f"{where} failed to add the command: "
                           f"{type(err).__name__}: {err}")
    if name not in sub.choices:
        return Unavailable(name, f"{where} did not add a command named {name!r}")
    return None


class _Parser(argparse.ArgumentParser):
    """argparse's parser; with ``--json`` on the line, a usage error is a JSON document too."""

    json_mode = False

    def error(self, message: str) -> NoReturn:
        if _Parser.json_mode:
            emit_json({"error": message})
        super().error(message)


class _Formatter(argparse.HelpFormatter):
    """Command names and their help on one line each.

    argparse measures the command names without the indentation it prints
    them with, so a long name pushes its help to the next line.
    """

    def add_argument(self, action: argparse.Action) -> None:
        super().add_argument(action)
        if isinstance(action, argparse._SubParsersAction):
            self._action_max_length += self._indent_increment


def _forget(sub: argparse._SubParsersAction, name: str) -> None:
    """Undo a command half-added by an entry point that then failed."""
    sub.choices.pop(name, None)
    sub._choices_actions[:] = [a for a in sub._choices_actions if a.dest != name]


def _add_unavailable(sub: argparse._SubParsersAction, command: Unavailable) -> None:
    """Keep an unavailable command in the list; running it says why."""
    # no option prefix: whatever follows the name is taken as is, then refused by the call
    p = sub.add_parser(command.name, help=f"(unavailable: {command.reason})", add_help=False,
                       prefix_chars="\0")
    p.add_argument("rest", nargs="*")
    p.set_defaults(func=command)


if __name__ == "__main__":
    sys.exit(main())
