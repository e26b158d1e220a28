"""Operator messages from the page: parsed, checked against a JSON Schema, or refused.

A message is one JSON object (``operator.schema.json`` ships beside this
module).  Nothing in it is evaluated: its ``kind`` selects one of a fixed set
of actions, and its fields are names checked by patterns.  A refusal says
what is wrong in one line, which is sent back to the page and logged with
who sent it.
"""

from __future__ import annotations

import json
from dataclasses import dataclass
from functools import cache
from importlib import resources
from typing import Any

from jsonschema import Draft202012Validator
from jsonschema.exceptions import best_match

MAX_MESSAGE_BYTES = 4096
"""Longer messages are refused unread: no operator action needs more."""
RUN_CONTROLS = ("pause", "resume", "step", "speed", "breakpoint", "clear-breakpoint")


@dataclass(frozen=True)
class Refused(Exception):
    """A message that is not executed, and why."""

    reason: str
    by: str = "unknown"
    raw: str = ""


@cache
def validator() -> Draft202012Validator:
    text = resources.files("shary.console").joinpath("operator.schema.json").read_text("utf-8")
    return Draft202012Validator(json.loads(text))


def parse(text: str | bytes) -> dict[str, Any]:
    """The message as a dict, or :class:`Refused` saying why not."""
    raw = text if isinstance(text, str) else text.decode("utf-8", "replace")
    shown = raw[:200]
    if len(raw.encode("utf-8", "replace")) > MAX_MESSAGE_BYTES:
        raise Refused(f"message of {len(raw)} characters (at most {MAX_MESSAGE_BYTES} bytes)",
                      raw=shown)
    try:
        message = json.loads(raw, parse_constant=_no_constant, object_pairs_hook=_once)
    except (ValueError, RecursionError) as err:
        raise Refused(f"not JSON: {err}", raw=shown) from None
    by = message.get("by") if isinstance(message, dict) else None
    by = by if isinstance(by, str) and validator().is_valid({"kind": "pause", "by": by}) \
        else "unknown"
    error = best_match(validator().iter_errors(message))
    if error is not None:
        where = "/".join(map(str, error.absolute_path))
        said = error.message
        if error.validator == "oneOf" and not where and message.get("kind") == "answer":
            said = ("an answer gives either 'task' and 'act' (a robot's question) or "
                    "'question' and 'text' (a team's question), with 'agent'")
        elif error.validator == "oneOf" and isinstance(error.schema, dict):
            said = error.schema.get("description", said)  # which shapes are allowed
        raise Refused(f"{where + ': ' if where else ''}{said}"[:300], by=by, raw=shown)
    return message


def _no_constant(name: str) -> float:
    raise ValueError(f"{name} is not a number")


def _once(pairs: list[tuple[str, Any]]) -> dict[str, Any]:
    """An object whose keys are all different: ``{"kind": "pause", "kind": "resume"}``
    would otherwise mean whatever the last one says."""
    found: dict[str, Any] = {}
    for key, value in pairs:
        if key in found:
            raise ValueError(f"the key {key!r} is given twice")
        found[key] = value
    return found
