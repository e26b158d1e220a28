"""Finding and checking the child schemes that states invoke.

An invoke names its child scheme in one of three ways: a built-in scheme by
name (``give-object``), a file by a path relative to the invoking scheme's own
folder (``parts/hand-over.yaml``), or a whole scheme written inline (what an
SCXML ``<invoke>`` with ``<content>`` becomes).  A path never leaves that
folder (or an ``--allow-path`` folder: :func:`userfiles.reader.confine`), so
a scheme handed to a robot cannot make it read other files.

Children are loaded by the invoking scheme's builder (:mod:`shary.io.schemes`, which
calls this module, not the reverse), with every check a scheme gets, and their own problems are
reported in their own files.  A scheme that invokes itself, directly or
through others, is refused with the whole cycle named: starting it would start
copies of itself without end.
"""

from __future__ import annotations

import os
from pathlib import Path
from typing import TYPE_CHECKING, Any

from shary import builtin
from shary.statechart.model import Scheme
from userfiles.errors import FileError
from userfiles.reader import confine, spelled
from userfiles.schema import did_you_mean
from userfiles.yamlsafe import Located

MAX_DEPTH = 16
"""Schemes a chain of invokes may go through (a file may be invoked many times: each
file is loaded once per top-level load)."""

if TYPE_CHECKING:
    from shary.io.schemes import SchemeBuilder


def identity(file: str) -> str:
    """How a scheme file is known in a chain of invokes (its real path, or its name)."""
    return os.path.realpath(file) if os.path.isfile(file) else file


def child_scheme(builder: SchemeBuilder, value: Any, path: tuple) -> Scheme | None:
    """The checked child scheme an invoke names, or None (with the problems recorded)."""
    if isinstance(value, dict):
        found = _parse(builder, path, lambda: builder.parse_child(rooted(builder.located, path)))
        if isinstance(found, FileError):
            _refused(builder, path, found)
            return None
        return found
    if not isinstance(value, str) or not value:
        return None  # the schema reported it
    if _is_path(value):
        file = _below(builder, value, path)
    else:
        found = builtin.find("schemes", value) if value != "acts" else None
        if found is None:
            names = [p.stem for p in builtin.files("schemes") if p.stem != "acts"]
            builder.problem(path, f"unknown scheme {value!r}{did_you_mean(value, names)}: "
                            "an invoke names a built-in scheme or a file below this scheme's "
                            f"folder (built-in schemes: {', '.join(names)})")
            return None
        file = str(found)
    if file is None:
        return None
    key = identity(file)
    if len(builder.chain) >= MAX_DEPTH:
        builder.problem(path, f"invokes nest more than {MAX_DEPTH} schemes deep")
        return None
    if key in builder.chain:
        loop = [Path(f).name for f in builder.chain[builder.chain.index(key):]]
        builder.problem(path, f"invoke cycle: {' -> '.join([*loop, Path(file).name])}; a "
                        "scheme that invokes itself would start copies of itself without end")
        return None
    if key not in builder.loaded:
        builder.loaded[key] = _parse(builder, path, lambda: builder.load_child(file))
    found = builder.loaded[key]
    if isinstance(found, FileError):
        _refused(builder, path, found)
        return None
    return found


def _parse(builder: SchemeBuilder, path: tuple, load: Any) -> Scheme | FileError:
    try:
        return load()
    except FileError as err:
        return err


def _refused(builder: SchemeBuilder, path: tuple, err: FileError) -> None:
    builder.problems.extend(err.problems)
    if any(p.file != builder.located.file for p in err.problems):
        builder.problem(path, "the invoked scheme is refused (its errors are listed with "
                        "its file)")


def _is_path(value: str) -> bool:
    return "/" in value or "\\" in value or value.endswith((".yaml", ".yml")) \
        or value.startswith(".")


def _below(builder: SchemeBuilder, value: str, path: tuple) -> str | None:
    """The file a relative invoke path names, if it stays below the scheme's folder."""
    file = builder.located.file
    if not os.path.isfile(file):
        builder.problem(path, f"{value!r} is a path, but this scheme was not read from a "
                        "file: name a built-in scheme or write the child inline")
        return None
    full, refusal = confine(file, value)
    if refusal is not None:
        builder.problem(path, refusal)
        return None
    return spelled(full, like=file)


def rooted(located: Located, prefix: tuple) -> Located:
    """The part of a located document at ``prefix``, as a document of its own (same file)."""
    n = len(prefix)
    return Located(located.file, _at(located.data, prefix),
                   {p[n:]: m for p, m in located.marks.items() if p[:n] == prefix},
                   {p[n:]: m for p, m in located.key_marks.items() if p[:n] == prefix})


def _at(data: Any, path: tuple) -> Any:
    for key in path:
        data = data[key]
    return data
