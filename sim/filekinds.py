"""The kinds of files ``sim`` adds to ``shary validate``: scenarios and profiles.

Registered through the ``shary.file_kinds`` entry point (see pyproject.toml),
because the engine never imports ``sim``.
"""

from __future__ import annotations

from pathlib import Path

from shary.io.filekinds import Context, FileKind
from userfiles.errors import FileError, Problem


def _check_scenarios(files: list[Path], context: Context) -> list[Problem]:
    """Each scenario with the recipe files it names (their problems included, once)."""
    from sim.scenario import load_scenario

    problems: list[Problem] = []
    for path in files:
        try:
            load_scenario(path, acts=context.acts)
        except FileError as err:
            problems.extend(err.problems)
    return problems


def _check_profiles(files: list[Path], context: Context) -> list[Problem]:
    from sim.scenario import load_profile

    problems: list[Problem] = []
    for path in files:
        try:
            load_profile(path, acts=set(context.acts.vocabulary()))
        except FileError as err:
            problems.extend(err.problems)
    return problems


def _shipped_scenarios() -> list[Path]:
    from sim.scenario import builtin_scenarios

    return list(builtin_scenarios().values())


def _shipped_profiles() -> list[Path]:
    from sim.scenario import builtin_profiles

    return builtin_profiles()


KINDS = (
    FileKind("scenario", _check_scenarios, 5, detect=lambda d: "scenario" in d,
             keys="scenario:", shipped=_shipped_scenarios),
    FileKind("profile", _check_profiles, 5, detect=lambda d: "profile" in d, keys="profile:",
             shipped=_shipped_profiles),
)
