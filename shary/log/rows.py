"""What a row of a context log must hold to be read: bounds, types, and a shape per kind.

A context log is a file like any other a user hands to ``shary``: it may come
from another version, another tool, a crash, or a hand edit.  Every reader
(``shary log``, the task-tree replay, the timeline) goes through
:func:`check_row`, so a row that is not what the writer writes is refused with
a sentence saying what is wrong with it, never a ``KeyError`` or a
``RecursionError`` from deep inside a drawing.

Why these checks and not a JSON Schema per kind: a long run logs millions of
rows and ``jsonschema`` costs tens of microseconds a row; the shapes below are
a few dictionary look-ups.  They are the format's documentation as much as its
check (docs/recipes.md, "The context log").

The bounds (:data:`MAX_DATA_BYTES`, :data:`MAX_DEPTH`) keep a hostile row from
costing more than the rule for user files allows (10 s, 500 MB): the depth is
measured without recursion *before* the JSON is parsed, because Python's JSON
parser recurses and a row of ``[[[[…`` would otherwise end in a
``RecursionError``.
"""

from __future__ import annotations

import json
import math
import re
from itertools import accumulate
from typing import Any

MAX_DATA_BYTES = 4 * 1024 * 1024
"""The largest ``data`` of one event (a plan of a thousand steps is about 100 KB).
Parsed JSON takes up to twenty times its text: the bound keeps one row under 100 MB."""
MAX_DEPTH = 64
"""The deepest nesting of lists and objects in an event's ``data`` (the writer's
deepest is about five); the same bound as YAML files (``userfiles.yamlsafe``)."""

_STRING = re.compile(r'"(?:[^"\\]++|\\.)*+"')
_NOT_BRACKET = re.compile(r"[^\[\]{}]+")
_STEP = {"[": 1, "{": 1, "]": -1, "}": -1}


# The shapes of the kinds that readers take apart.  ``task`` is the row's column;
# the other names are keys of ``data``; a trailing ``?`` lets a field be absent or
# null.  A kind not listed here is read as any JSON object: ``shary log`` shows
# it as it is.
KIND_SHAPES: dict[str, dict[str, str]] = {
    "node": {"task": "text", "node_kind": "text", "name": "text", "state": "text",
             "parent": "text?", "args": "object?"},
    "task-state": {"task": "text", "state": "text", "reason": "text?"},
    "node-removed": {"task": "text", "nodes": "list of text"},
    "recognition": {"candidate": "text", "state": "text", "action": "text",
                    "params": "object"},
}
"""Kind -> field -> what it must be: ``text``, ``object``, ``list of text`` (``?``: optional)."""

_TYPE_NAMES = {str: "text", list: "a list", dict: "an object", float: "a number",
               int: "a number", bool: "true or false", type(None): "null"}
_IS = {"text": lambda v: isinstance(v, str), "object": lambda v: isinstance(v, dict),
       "list of text": lambda v: isinstance(v, list) and all(isinstance(i, str) for i in v)}
_FIELDS = {kind: [(name, {"text": str, "object": dict, "list of text": list}[
                       wanted.rstrip("?")], wanted.endswith("?"))
                  for name, wanted in shape.items()]
           for kind, shape in KIND_SHAPES.items()}
"""The shapes as (field, exact type, optional), for the common case's quick test."""


def decode_data(text: Any) -> dict[str, Any] | str:
    """An event's ``data`` parsed, or what is wrong with it (a sentence)."""
    if not isinstance(text, str):
        return f"data is {_kind_of(text)}, not the text of a JSON object"
    problem = decode_bounds(text)
    if problem is not None:
        return problem
    try:
        data = json.loads(text)
    except ValueError as err:
        return f"data is not JSON ({err})"
    if not isinstance(data, dict):
        return f"data is {_kind_of(data)}, not a JSON object"
    return data


def decode_bounds(text: str) -> str | None:
    """What makes a JSON text too costly to parse (size, depth), or None."""
    if len(text) > MAX_DATA_BYTES // 4 and len(text.encode("utf-8", "replace")) > MAX_DATA_BYTES:
        return f"data is larger than {MAX_DATA_BYTES // 2**20} MiB"
    if nesting(text) > MAX_DEPTH:
        return f"data nests lists and objects deeper than {MAX_DEPTH} levels"
    return None


def nesting(text: str) -> int:
    """How deep lists and objects nest in a JSON text, counted without recursion.

    Brackets inside strings do not count.  An unbalanced text may count deeper
    than the parser would go, which errs on the side of refusing it.
    """
    if text.count("[") + text.count("{") <= MAX_DEPTH:
        return 0  # cannot be deeper than the brackets it holds: most rows stop here
    brackets = _NOT_BRACKET.sub("", _STRING.sub("", text))
    return max(accumulate(map(_STEP.__getitem__, brackets)), default=0)


def check_row(time: Any, kind: Any, task: Any, agent: Any,
              data: dict[str, Any]) -> str | None:
    """What is wrong with a row whose data is already decoded, or None.

    A row as the writer makes it passes a few exact type tests (a replay reads
    tens of thousands of rows a second); any other row is examined by
    :func:`_what_is_wrong`, which has the last word and says why.
    """
    if (type(time) is float and math.isfinite(time) and type(kind) is str and kind
            and (task is None or type(task) is str) and (agent is None or type(agent) is str)):
        fields = _FIELDS.get(kind)
        if fields is None or _fits(fields, task, data):
            return None
    return _what_is_wrong(time, kind, task, agent, data)


def _fits(fields: list[tuple[str, type, bool]], task: Any, data: dict[str, Any]) -> bool:
    for name, wanted, optional in fields:
        value = task if name == "task" else data.get(name)
        if value is None:
            if not optional:
                return False
        elif type(value) is not wanted or (
                wanted is list and not all(type(item) is str for item in value)):
            return False
    return True


def _what_is_wrong(time: Any, kind: Any, task: Any, agent: Any,
                   data: dict[str, Any]) -> str | None:
    if isinstance(time, bool) or not isinstance(time, (int, float)) or not math.isfinite(time):
        return f"time is {_shown(time)}, not a finite number of seconds"
    if not isinstance(kind, str) or not kind:
        return f"kind is {_shown(kind)}, not a non-empty text"
    for column, value in (("task", task), ("agent", agent)):
        if value is not None and not isinstance(value, str):
            return f"{column} is {_kind_of(value)}, not text or null"
    for name, wanted in KIND_SHAPES.get(kind, {}).items():
        value = task if name == "task" else data.get(name)
        where = "task" if name == "task" else f"data.{name}"
        if wanted.endswith("?"):
            if value is not None and not _IS[wanted[:-1]](value):
                return f"{where} is {_kind_of(value)}, not {wanted[:-1]}"
        elif name != "task" and name not in data:
            return f"{where} is missing"
        elif isinstance(value, list) and wanted == "list of text":
            odd = next((item for item in value if not isinstance(item, str)), None)
            if odd is not None:
                return f"{where} holds {_kind_of(odd)}, not only text"
        elif not _IS[wanted](value):
            return f"{where} is {_kind_of(value)}, not {wanted}"
    return None


def _kind_of(value: Any) -> str:
    return _TYPE_NAMES.get(type(value), type(value).__name__)


def _shown(value: Any) -> str:
    """A value in a message: short, and quoted when it is text."""
    if isinstance(value, str):
        return json.dumps(value[:40], ensure_ascii=False) if value else "empty"
    if isinstance(value, float):
        return repr(value)
    return _kind_of(value)
