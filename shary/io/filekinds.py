"""The kinds of files ``shary validate`` knows, and the per-file reports it gives.

Each kind says how to recognise its files (a suffix, or the top-level keys of a
YAML mapping) and how to check a batch of them with what the files before
have declared: files given together are checked as one set (acts files come
first, so their acts are known to schemes, recipes, scenarios and profiles; the
acts a scheme declares under its ``acts:`` are known to the files after it).
The engine registers its own kinds here; other parts register theirs through
the ``shary.file_kinds`` entry-point
group (``sim`` registers scenarios and profiles), since ``shary`` never
imports ``sim``.

:func:`validate` reports each file once, by the name the user gave it when
they gave it, and never says ``ok`` for a file whose dependencies fail.
"""

from __future__ import annotations

import os
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from importlib.metadata import entry_points
from pathlib import Path
from typing import Any

from shary import builtin
from shary.statechart.acts import ActRegistry, builtin_acts, load_acts
from shary.statechart.conditions import ConditionRegistry
from userfiles import yamlsafe
from userfiles.errors import FileError, Problem
from userfiles.reader import confine, spelled

ENTRY_POINTS = "shary.file_kinds"
"""Entry-point group: each entry is a sequence of :class:`FileKind` to register."""


@dataclass
class Context:
    """What the files checked so far declare, for the files checked after them."""

    acts: ActRegistry = field(default_factory=builtin_acts)
    conditions: ConditionRegistry = field(default_factory=ConditionRegistry.installed)
    notes: list[Problem] = field(default_factory=list)
    """What a kind notes without refusing the file (a robot binding's interface type
    that is not installed here), shown as ``FILE:LINE:COL: note: …``."""


Check = Callable[[list[Path], Context], list[Problem]]


@dataclass(frozen=True)
class FileKind:
    """A kind of user file: how to recognise it and how to check a batch of them."""

    name: str
    check: Check
    """Problems of the files (each read by the kind's own reader, with its limits)."""
    rank: int = 5
    """Kinds of lower rank are checked first (acts: 0, so that others know their acts)."""
    suffixes: tuple[str, ...] = ()
    """Files with these suffixes are of this kind and are not read as YAML."""
    detect: Callable[[dict[str, Any]], bool] | None = None
    """Whether a YAML mapping is a file of this kind."""
    keys: str = ""
    """The keys that make a file of this kind, for the message about unknown files."""
    shipped: Callable[[], list[Path]] | None = None
    """The files of this kind that ship with its package (``shary validate`` alone checks
    them)."""


_kinds: dict[str, FileKind] = {}
_unavailable: list[str] = []
"""Why registered kinds could not be loaded (a part that is not installed), for messages."""
_loaded = False


def register(kind: FileKind) -> None:
    """Make a kind of file known to ``shary validate``."""
    _kinds[kind.name] = kind


def kinds() -> list[FileKind]:
    """Every registered kind, the engine's and the installed parts', by rank."""
    global _loaded
    if not _loaded:
        _loaded = True
        for entry in entry_points(group=ENTRY_POINTS):
            try:
                loaded = entry.load()
            except ModuleNotFoundError as err:
                _unavailable.append(f"the kinds of files of '{entry.name}' are unavailable "
                                    f"(package '{err.name}' is not installed)")
                continue
            except Exception as err:  # noqa: BLE001 -- a broken part must not stop the others
                _unavailable.append(f"the kinds of files of '{entry.name}' are unavailable "
                                    f"(entry point '{entry.name} = {entry.value}' failed to "
                                    f"load: {type(err).__name__}: {err})")
                continue
            for kind in loaded:
                register(kind)
    return sorted(_kinds.values(), key=lambda k: (k.rank, k.name))


def shipped_files() -> list[Path]:
    """Every file that ships with the installed parts, by kind: what ``shary validate``
    checks when it is given no file."""
    return [path for kind in kinds() if kind.shipped is not None for path in kind.shipped()]


@dataclass
class Report:
    """What ``shary validate`` found in one file."""

    file: str
    kind: str | None
    problems: list[Problem]
    depends_on: list[str] = field(default_factory=list)
    """Files this one uses that have errors (it cannot be ok while they are not)."""
    notes: list[Problem] = field(default_factory=list)
    """What is worth knowing but not wrong (see :attr:`Context.notes`)."""

    @property
    def ok(self) -> bool:
        return not self.problems

    def as_json(self) -> dict[str, Any]:
        report = {"file": self.file, "kind": self.kind, "ok": self.ok,
                  "depends_on": self.depends_on,
                  "problems": [{"file": p.file, "line": p.line, "col": p.col,
                                "message": p.message} for p in self.problems]}
        if self.notes:
            report["notes"] = [{"file": p.file, "line": p.line, "col": p.col,
                                "message": p.message} for p in self.notes]
        return report


YAML_SUFFIXES = (".yaml", ".yml")


def validate(paths: Sequence[str | os.PathLike[str]]) -> list[Report]:
    """One report per file: those given, in order, then the files they depend on that
    have problems (each problem once, under the name the user gave the file).  A folder
    stands for the files directly in it that a kind can be (see :func:`_in_folders`)."""
    known = kinds()
    paths, problems = _in_folders(paths, known)
    given = {Path(p).resolve(): os.fspath(p) for p in paths}
    batches: dict[str, list[Path]] = {}
    of_kind: dict[str, str | None] = {os.fspath(p): None for p in paths}
    for path in map(Path, paths):
        kind = next((k for k in known if path.suffix in k.suffixes), None)
        outline = None
        if kind is None:
            # Only the outline (top-level keys) here: the kind's reader then reads the
            # file once, with its format's limits.
            try:
                outline = yamlsafe.outline(path)
            except FileError as err:
                problems.update(err.problems)
                continue
            keys = dict.fromkeys(outline.keys or ())
            kind = next((k for k in known if k.detect is not None and outline.keys is not None
                         and k.detect(keys)), None)
        if kind is None:
            problems.add(_unknown(path, outline, known))
            if outline is not None:  # what else is wrong with it (duplicate keys …)
                try:
                    problems.update(yamlsafe.load_file(path).problems)
                except FileError as err:
                    problems.update(err.problems)
            continue
        of_kind[os.fspath(path)] = kind.name
        batches.setdefault(kind.name, []).append(path)
    context = Context()
    for kind in known:
        if kind.name in batches:
            problems.update(kind.check(batches[kind.name], context))
    reports = _reports(paths, given, of_kind, problems)
    for report in reports:
        full = Path(report.file).resolve()
        report.notes = sorted(Problem(report.file, n.line, n.col, n.message)
                              for n in context.notes if Path(n.file).resolve() == full)
    return reports


def _in_folders(paths: Sequence[str | os.PathLike[str]],
                known: list[FileKind]) -> tuple[list[str | os.PathLike[str]], set[Problem]]:
    """The paths given, each folder replaced by its YAML files and the files of a kind's
    suffix (``.ttl``) directly in it, by name: ``shary validate my-robot/`` checks a
    folder of files together, as naming them would.  Folders below are not entered (a
    folder may hold a virtual environment, or files that are not the user's).  A folder
    without such files is a problem of its own, which says what to give instead."""
    suffixes = list(dict.fromkeys([*YAML_SUFFIXES, *(s for k in known for s in k.suffixes)]))
    files: list[str | os.PathLike[str]] = []
    problems: set[Problem] = set()
    for path in paths:
        if not Path(path).is_dir():
            files.append(path)
            continue
        inside = sorted(f for f in Path(path).iterdir() if f.suffix in suffixes and f.is_file())
        if not inside:
            problems.add(Problem(os.fspath(path), 1, 1, (
                f"a folder with no {', '.join(suffixes[:-1])} or {suffixes[-1]} file in it "
                "(shary validate reads the files directly in a folder, not those in folders "
                "below): name the files or folders to check")))
        files.extend(inside)
    return files, problems


def _unknown(path: Path, outline: yamlsafe.Outline | None, known: list[FileKind]) -> Problem:
    yaml_kinds = [k for k in known if k.keys]
    names = ", ".join(k.name for k in yaml_kinds[:-1]) + f" or {yaml_kinds[-1].name}"
    keys = ", ".join(f"'{k.keys}'" for k in yaml_kinds)
    what = ("a mapping" if outline is not None and outline.keys is not None
            else "expected a mapping")
    message = f"not a known kind of file ({names}): {what} with {keys}"
    if _unavailable:
        message += "; " + "; ".join(_unavailable)
    return Problem(os.fspath(path), *(outline.mark if outline is not None else (1, 1)), message)


def _reports(paths: Sequence[str | os.PathLike[str]], given: dict[Path, str],
             of_kind: dict[str, str | None], problems: set[Problem]) -> list[Report]:
    by_file: dict[str, list[Problem]] = {}
    for problem in problems:
        full = Path(problem.file).resolve()
        name = given.get(full) or spelled(full, like=os.fspath(paths[0]) if paths else "")
        by_file.setdefault(name, []).append(
            Problem(name, problem.line, problem.col, problem.message))
    bad = set(by_file)
    reports = []
    for name in [os.fspath(p) for p in paths] + sorted(set(by_file) - set(map(os.fspath,
                                                                               paths))):
        found = sorted(set(by_file.get(name, [])))
        depends = sorted({d for d in _depends(found) if d in bad})
        reports.append(Report(name, of_kind.get(name), found, depends))
    return reports


_DEPENDS = "depends on "


def _depends(problems: list[Problem]) -> list[str]:
    return [p.message[len(_DEPENDS):].split(", which has errors")[0]
            for p in problems if p.message.startswith(_DEPENDS)]


# -- the engine's own kinds ----------------------------------------------------------


def _check_acts(files: list[Path], context: Context) -> list[Problem]:
    problems: list[Problem] = []
    for path in files:
        try:
            context.acts = context.acts.extended(load_acts(path))
        except FileError as err:
            problems.extend(err.problems)
    return problems


def _check_schemes(files: list[Path], context: Context) -> list[Problem]:
    from shary.io.schemes import load_scheme

    problems: list[Problem] = []
    for path in files:
        try:
            scheme = load_scheme(path, acts=context.acts, conditions=context.conditions)
        except FileError as err:
            problems.extend(err.problems)
        else:  # the acts a scheme declares are known to the files checked with it
            context.acts = context.acts.extended(scheme.acts.acts)
    return problems


def _check_recipes(files: list[Path], context: Context) -> list[Problem]:
    from shary.io.recipes import load_library

    try:
        load_library(files, acts=context.acts)
    except FileError as err:
        return list(err.problems)
    return []


def _check_domains(files: list[Path], context: Context) -> list[Problem]:
    import planner

    problems: list[Problem] = []
    for path in files:
        try:
            planner.load_domain(path)
        except FileError as err:
            problems.extend(err.problems)
    return problems


def _check_problems(files: list[Path], context: Context) -> list[Problem]:
    """A problem file is checked with the domain it names: a built-in name, or a file
    below its own folder."""
    import planner

    problems: list[Problem] = []
    for path in files:
        try:
            located = yamlsafe.load_file(path)
        except FileError as err:
            problems.extend(err.problems)
            continue
        name = located.data.get("domain")
        if not isinstance(name, str):
            problems.append(located.problem((), "a problem file names its domain "
                                            "('domain:') for shary validate to check it"))
            continue
        try:
            if name.endswith((".yaml", ".yml")):
                full, refusal = confine(path, name)
                if refusal is not None:
                    problems.append(located.problem(("domain",), refusal))
                    continue
                try:
                    domain = planner.load_domain(full)
                except FileError as err:
                    problems.extend(err.problems)
                    problems.append(located.problem(
                        ("domain",), f"depends on {spelled(full, like=path)}, which has errors"))
                    continue
            else:
                domain = planner.load_domain(name)
            planner.load_problem(path, domain)
        except FileError as err:
            problems.extend(err.problems)
    return problems


def _check_turtle(files: list[Path], context: Context) -> list[Problem]:
    from shary.facts.database import FactDatabase

    problems: list[Problem] = []
    for path in files:
        try:
            FactDatabase().load_turtle(path)
        except FileError as err:
            problems.extend(err.problems)
    return problems


def _check_teams(files: list[Path], context: Context) -> list[Problem]:
    from shary.team.teamfile import load_team

    problems: list[Problem] = []
    for path in files:
        try:
            load_team(path)
        except FileError as err:
            problems.extend(err.problems)
    return problems


def _models() -> Any:
    from shary.recognition import models

    return models


def _shipped_recipes() -> list[Path]:
    from shary.io.recipes import builtin_library_files

    return builtin_library_files()


def _shipped_domains() -> list[Path]:
    import planner

    return planner.builtin_domains()


def _shipped_problems() -> list[Path]:
    import planner

    return planner.builtin_problems()


for _kind in (
    FileKind("acts", _check_acts, 0, detect=lambda d: set(d) == {"acts"}, keys="acts:"),
    FileKind("scheme", _check_schemes, 1, detect=lambda d: "scheme" in d or "states" in d,
             keys="scheme:", shipped=lambda: builtin.files("schemes")),
    FileKind("recipes", _check_recipes, 2, keys="tasks:/recipes:/atomic:/predicates:",
             detect=lambda d: bool(set(d) & {"predicates", "atomic", "tasks", "recipes",
                                            "chronicles"})
             and not set(d) & {"scenario", "profile", "problem", "scheme", "team", "binding"},
             shipped=_shipped_recipes),
    FileKind("domain", _check_domains, 3, detect=lambda d: "domain" in d and "types" in d,
             keys="domain:", shipped=_shipped_domains),
    FileKind("problem", _check_problems, 4, detect=lambda d: "problem" in d,
             keys="problem:", shipped=_shipped_problems),
    FileKind("turtle", _check_turtle, 5, suffixes=(".ttl",)),
    FileKind("team", _check_teams, 6, detect=lambda d: "team" in d and "agents" in d,
             keys="team:"),
    FileKind("action-models", lambda files, context: _models().check_files(files), 6,
             detect=lambda d: "action-models" in d, keys="action-models:",
             shipped=lambda: _models().shipped_files()),
):
    register(_kind)
