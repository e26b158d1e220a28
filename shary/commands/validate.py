"""``shary validate``: check the files users write, each against its schema and for meaning."""

from __future__ import annotations

import argparse
from importlib import metadata
from pathlib import Path
from typing import Protocol

from shary import builtin
from shary.acts import ActRegistry, builtin_acts, load_acts
from shary.conditions import ConditionRegistry
from shary.terminal import (
    EXIT_BAD_INPUT,
    add_json_flag,
    emit_json,
    escape,
    print_problems,
    problems_json,
)
from shary.terminal import err as _err
from shary.terminal import out as _out
from userfiles import yamlsafe
from userfiles.errors import FileError, Problem

EXIT_BAD_FILE = EXIT_BAD_INPUT


KINDS = "shary.filekinds"
"""The entry-point group of the kinds of user files other packages check (the simulator's
scenarios and profiles): the name is the file's top key, the value a :class:`FileKind`."""


class FileKind(Protocol):
    """A kind of user file that another package knows how to check."""

    def builtin_files(self) -> list[Path]:
        """The files of this kind that ship with the package (``shary validate`` alone)."""

    def check(self, path: Path, acts: set[str]) -> None:
        """Raise :class:`FileError` with every problem of the file; ``acts`` are the known acts."""


def registered_kinds() -> dict[str, FileKind | str]:
    """Kind name -> its checker, or why it cannot be checked (its package is absent)."""
    kinds: dict[str, FileKind | str] = {}
    for entry in metadata.entry_points(group=KINDS):
        where = f"entry point '{entry.name} = {entry.value}'"
        try:
            kinds[entry.name] = entry.load()
        except ModuleNotFoundError as err:
            kinds[entry.name] = (f"the package '{err.name}' that checks it is not installed "
                                 f"({where})")
        except Exception as err:  # noqa: BLE001 -- reported on the files of that kind
            kinds[entry.name] = (f"it cannot be checked: {where} failed to load "
                                 f"({type(err).__name__}: {err})")
    return kinds


def add_validate(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("validate", help="check schemes, acts, recipe libraries and Turtle files "
                       "(default: the built-in ones)")
    p.add_argument("paths", nargs="*", type=Path, metavar="PATH",
                   help="files to check; acts files among them extend the acts of the others, "
                   "recipe files are checked together with the built-in library")
    add_json_flag(p, "each file's verdict and the problems")
    p.set_defaults(func=cmd_validate)


def cmd_validate(args: argparse.Namespace) -> int:
    import planner
    from shary.facts import FactDatabase
    from shary.io.recipes import builtin_library_files, load_library
    from shary.io.schemes import parse_scheme

    kinds = registered_kinds()
    paths = list(args.paths) or (builtin.files("schemes") + builtin_library_files()
                                 + planner.builtin_domains() + planner.builtin_problems()
                                 + [f for k in kinds.values() if not isinstance(k, str)
                                    for f in k.builtin_files()])
    problems: list[Problem] = []
    schemes: list[yamlsafe.Located] = []
    libraries: list[Path] = []
    planning: list[tuple[Path, yamlsafe.Located]] = []
    other: list[tuple[str, Path, yamlsafe.Located]] = []
    acts: ActRegistry = builtin_acts()
    for path in paths:
        if path.suffix == ".ttl":
            try:
                FactDatabase().load_turtle(path)
            except FileError as err:
                problems.extend(err.problems)
            continue
        try:
            located = yamlsafe.load_file(path)
        except FileError as err:
            problems.extend(err.problems)
            continue
        kind = _kind_of(located, kinds)
        if kind == "acts":
            try:
                acts = acts.extended(load_acts(path))
            except FileError as err:
                problems.extend(err.problems)
        elif kind == "scheme":
            schemes.append(located)
        elif kind == "recipes":
            libraries.append(path)
        elif kind in ("domain", "problem"):
            planning.append((path, located))
        elif kind in kinds:
            other.append((kind, path, located))
        else:
            problems.extend(located.problems)
            what = "a mapping" if isinstance(located.data, dict) else "expected a mapping"
            *names, last = ["scheme", "acts", "recipe", "domain", "problem", *kinds]
            names = f"{', '.join(names)} or {last}"
            keys = " ".join(f"'{k}:'," for k in ["scheme", "acts", "domain", "problem", *kinds])
            problems.append(located.problem((), f"not a {names} file: {what} with {keys} or "
                                            "some of 'predicates:', 'atomic:', 'tasks:', "
                                            "'recipes:', 'chronicles:'"))
    conditions = ConditionRegistry.installed()
    for located in schemes:
        try:
            parse_scheme(located, acts=acts, conditions=conditions)
        except FileError as err:
            problems.extend(err.problems)
    if libraries:
        try:
            load_library(libraries, acts=acts)
        except FileError as err:
            problems.extend(err.problems)
    for path, located in planning:
        problems.extend(_check_planning(path, located))
    for kind, path, located in other:
        problems.extend(_check_other(kinds[kind], kind, path, located, acts))
    problems.sort()
    print_problems(problems)
    bad = {p.file for p in problems}
    if args.json:
        emit_json({"files": [{"path": str(path), "ok": str(path) not in bad} for path in paths],
                   "problems": problems_json(problems)})
    else:
        for path in paths:
            if str(path) not in bad:
                _out.print(f"[green]ok[/green]    {escape(str(path))}")
    if problems:
        _err.print(f"{len(problems)} problem(s) in {len(bad)} file(s) of {len(paths)} checked")
        return EXIT_BAD_FILE
    return 0


def _check_other(checker: FileKind | str, kind: str, path: Path, located: yamlsafe.Located,
                 acts: ActRegistry) -> list[Problem]:
    """Problems of a file of a kind another package checks (a scenario, a profile)."""
    if isinstance(checker, str):
        return [located.problem((kind,), f"a {kind} file: {checker}", key=True)]
    try:
        checker.check(path, set(acts.vocabulary()))
    except FileError as err:
        return list(err.problems)
    return []


def _check_planning(path: Path, located: yamlsafe.Located) -> list[Problem]:
    """Problems of a planning domain, or of a problem with the domain it names."""
    import planner

    try:
        if _kind_of(located, {}) == "domain":
            planner.load_domain(path)
            return []
        name = located.data.get("domain")
        if not isinstance(name, str):
            return [located.problem((), "a problem file names its domain ('domain:') for "
                                    "shary validate to check it")]
        local = path.parent / name
        domain = planner.load_domain(local if local.suffix in (".yaml", ".yml") else name)
        planner.load_problem(path, domain)
    except FileError as err:
        return list(err.problems)
    return []


def _kind_of(located: yamlsafe.Located, kinds: dict[str, FileKind | str]) -> str | None:
    data = located.data
    if not isinstance(data, dict):
        return None
    if "domain" in data and "types" in data:
        return "domain"
    if "problem" in data:
        return "problem"
    for kind in kinds:
        if kind in data:
            return kind
    if "scheme" in data or "states" in data:
        return "scheme"
    if set(data) == {"acts"}:
        return "acts"
    if set(data) & {"predicates", "atomic", "tasks", "recipes", "chronicles"}:
        return "recipes"
    return None
