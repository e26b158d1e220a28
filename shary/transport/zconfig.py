"""A user's Zenoh configuration (``--zenoh-config FILE``), merged over shary's safe defaults.

Zenoh reads its configuration as JSON5; deployments across machines need
parts of it that shary's commands do not spell out: TLS certificates
(``transport/link/tls/…``), mutual TLS (``enable_mtls``), ``access_control``,
other leases and buffers.  A file given with ``--zenoh-config`` is read as a
user file:

1. text: at most :data:`MAX_BYTES`, UTF-8 (:func:`userfiles.yamlsafe.read_text`);
2. JSON5 (the ``json5`` package), no duplicate key, every number finite, an
   object at the top;
3. every setting it makes (a path of keys to a value that is not an object)
   checked by Zenoh itself, on a configuration that already holds shary's
   defaults: Zenoh's own deserializer is the schema (it knows every field of
   its version and the type of each), so an unknown field or a wrong type is
   refused at its key, ``FILE:LINE:COL: error: …``;
4. shary's own rules: the file does not choose the ``mode`` (the managers
   are a router, an agent a client) nor the endpoints (``listen/endpoints``,
   ``connect/endpoints``: they come from ``--listen``/``--connect``, loopback
   unless given), so a file shared by every process of a team cannot make an
   agent listen where the managers do.

The result, :data:`Settings`, is applied by
:func:`shary.transport.zenohport.session_config` after its defaults.
"""

from __future__ import annotations

import json
import math
import os
import re
from typing import TYPE_CHECKING, Any

from userfiles.errors import FileError, Problem
from userfiles.yamlsafe import read_text

if TYPE_CHECKING:
    from shary.transport.zenohport import Settings
MAX_BYTES = 256 * 1024
"""Largest configuration accepted (Zenoh's documented default file is about 40 KB)."""
MAX_DEPTH = 32
"""Deepest nesting of objects and arrays (Zenoh's own configuration nests 6 deep)."""
CHOSEN = {
    ("mode",): "the mode is chosen by the command (the managers are a router, an agent a "
               "client)",
    ("listen", "endpoints"): "endpoints come from the command line: give --listen "
                             "(loopback unless given)",
    ("connect", "endpoints"): "endpoints come from the command line: give --connect",
    ("plugins_loading",): "shary loads no Zenoh plugins (a plugin is code to run)",
    ("plugins",): "shary loads no Zenoh plugins (a plugin is code to run)",
}
"""Settings a file may not make, and why."""
_TOKENS = re.compile(r'"(?:[^"\\]|\\.)*"|\'(?:[^\'\\]|\\.)*\'|//[^\n]*|/\*.*?\*/', re.S)
"""JSON5's strings and comments (where brackets and keys do not count)."""
_SYNTAX = re.compile(r"^<string>:(\d+) (.*?)(?: at column (\d+))?$", re.S)


def load_settings(path: str | os.PathLike[str]) -> Settings:
    """The settings of the Zenoh configuration file ``path`` (FileError if refused)."""
    import json5
    import zenoh

    from shary.transport.zenohport import session_config

    name = os.fspath(path)
    text = read_text(name, max_bytes=MAX_BYTES)
    depth = _depth(text)
    if depth > MAX_DEPTH:
        raise FileError([Problem(name, 1, 1, f"nested {depth} deep (at most {MAX_DEPTH})")])
    try:
        data = json5.loads(text, allow_duplicate_keys=False)
    except ValueError as exc:
        raise FileError([_syntax(name, text, str(exc))]) from None
    if not isinstance(data, dict):
        raise FileError([Problem(name, 1, 1, "a Zenoh configuration is a JSON5 object "
                                 f"({{…}}), not {_what(data)}")])
    settings: Settings = {}
    problems: list[Problem] = []
    trial = session_config()
    for keys, value in _leaves(data, ()):
        where = _locate(text, keys)
        chosen = next((why for prefix, why in CHOSEN.items()
                       if keys[:len(prefix)] == prefix), None)
        if chosen is not None:
            problems.append(Problem(name, *where, f"{'/'.join(keys)}: {chosen}"))
            continue
        if not _finite(value):
            problems.append(Problem(name, *where, f"{'/'.join(keys)}: a number that is "
                                    "not finite (NaN, Infinity)"))
            continue
        key = "/".join(keys)
        unknown = _unknown(trial, keys)
        if unknown:
            problems.append(Problem(name, *_locate(text, unknown),
                                    f"{'/'.join(unknown)}: Zenoh has no such setting"))
            continue
        try:
            trial.insert_json5(key, json.dumps(value))
        except zenoh.ZError as exc:
            problems.append(Problem(name, *where, f"{key}: {zenoh_reason(exc)}"))
            continue
        settings[key] = value
    if problems:
        raise FileError(problems)
    return settings


def _leaves(data: dict[str, Any], keys: tuple[str, ...]) -> list[tuple[tuple[str, ...], Any]]:
    """Every (path of keys, value) whose value is not a non-empty object."""
    found: list[tuple[tuple[str, ...], Any]] = []
    for key, value in data.items():
        if isinstance(value, dict) and value:
            found.extend(_leaves(value, (*keys, key)))
        else:
            found.append(((*keys, key), value))
    return found


def _unknown(conf: Any, keys: tuple[str, ...]) -> tuple[str, ...]:
    """The shortest path of ``keys`` Zenoh does not know (empty: it knows them all)."""
    import zenoh

    for n in range(1, len(keys) + 1):
        try:
            conf.get_json("/".join(keys[:n]))
        except zenoh.ZError:
            return keys[:n]
    return ()


def _finite(value: Any) -> bool:
    if isinstance(value, float):
        return math.isfinite(value)
    if isinstance(value, list):
        return all(_finite(v) for v in value)
    if isinstance(value, dict):
        return all(_finite(v) for v in value.values())
    return True


def _depth(text: str) -> int:
    """How deep brackets nest, outside strings and comments (before any parser
    recurses into them)."""
    depth = deepest = 0
    for match in re.finditer(_TOKENS.pattern + r"|[\[{]|[\]}]", text, re.S):
        token = match.group()
        if token in "[{":
            depth += 1
            deepest = max(deepest, depth)
        elif token in "]}":
            depth -= 1
    return deepest


def _syntax(name: str, text: str, message: str) -> Problem:
    """json5's error (``<string>:LINE Unexpected … at column COL``) at its place."""
    found = _SYNTAX.match(message)
    if found is None:
        duplicate = re.match(r'Duplicate key "(.*)" found', message)
        if duplicate:
            at = _key_at(_uncommented(text), duplicate[1], 0, nth=2)
            return Problem(name, *at, f"key {duplicate[1]!r} given twice")
        return Problem(name, 1, 1, f"not JSON5: {message[:200]}")
    line = min(int(found[1]), max(text.count("\n") + 1, 1))
    col = int(found[3]) if found[3] else 1
    return Problem(name, line, col, f"not JSON5: {found[2][:200]}")


def _uncommented(text: str) -> str:
    """``text`` with its comments blanked (same length, same lines): keys are found
    where the parser reads them, not in a comment that names them."""
    def blank(match: re.Match[str]) -> str:
        token = match.group()
        return token if token[0] in "\"'" else re.sub(r"[^\n]", " ", token)
    return _TOKENS.sub(blank, text)


def _locate(text: str, keys: tuple[str, ...]) -> tuple[int, int]:
    """Line and column of the last of ``keys``, found in order in ``text``."""
    text = _uncommented(text)
    at, found = 0, (1, 1)
    for key in keys:
        place = _find(text, key, at)
        if place is None:
            break
        at = place
        found = _mark(text, place)
    return found


def _key_at(text: str, key: str, start: int, *, nth: int = 1) -> tuple[int, int]:
    at = start
    place = None
    for _ in range(nth):
        place = _find(text, key, at)
        if place is None:
            break
        at = place + 1
    return _mark(text, place) if place is not None else (1, 1)


def _find(text: str, key: str, start: int) -> int | None:
    quoted = re.escape(key)
    pattern = rf"""(?<![\w$])(?:"{quoted}"|'{quoted}'|{quoted})\s*:"""
    match = re.compile(pattern).search(text, start)
    return match.start() if match else None


def _mark(text: str, at: int) -> tuple[int, int]:
    line = text.count("\n", 0, at) + 1
    return line, at - (text.rfind("\n", 0, at) + 1) + 1


def _what(value: Any) -> str:
    return {list: "an array", str: "a string", bool: "a boolean", type(None): "null"}.get(
        type(value), "a number")


def zenoh_reason(exc: Exception) -> str:
    """Zenoh's message, without the Rust source location it ends with (and, for a value
    of the wrong shape, without the Rust structure around the deserializer's words)."""
    text = re.sub(r"\s+at /\S+?\.rs:\d+\.?", "", str(exc)).strip()
    inner = re.search(r'msg: "((?:[^"\\]|\\.)*)"', text)
    return inner[1].replace('\\"', '"') if inner else text
