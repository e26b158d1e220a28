"""The wire format: messages as versioned JSON under key expressions.

A message on the wire is one JSON object: ``{"v": 1, "kind": …, "sender": …,
"to": …, "id": …, <the kind's fields>}`` (and ``"at"``: the simulated time it
was sent at, for a team on a shared clock), published under the key expression
``shary/<team>/<to>/<kind>``.  JSON rather than CBOR: the standard library
encodes and decodes a message of a few fields in a few microseconds (well
inside the transport's budget, see ``benchmarks/transport.py``), any
Zenoh tool (``z_sub``) shows it as text, and peers in other languages need
no CBOR library; CBOR would add a dependency for messages this small
without a measured gain.

Everything that arrives is checked before it becomes a message: size, JSON,
the version, the kind, that the key expression agrees with the payload, and
every field's type (derived from the message dataclasses, so the check and
the classes cannot drift apart; :func:`json_schema` gives the same rules as
a JSON Schema for other peers, shipped as ``shary/schemas/message.schema.json``).
A message that fails is refused with a :class:`WireError`, never executed.
"""

from __future__ import annotations

import json
import math
import re
from dataclasses import fields
from typing import Any

from shary.transport.messages import (
    KINDS,
    QUESTION_TYPES,
    Message,
    Question,
    build,
)

VERSION = 1
"""The schema version written; a message of another version is refused."""
MAX_BYTES = 1 << 20
"""The largest message accepted (1 MiB: questions carry image paths, not images)."""
PREFIX = "shary"
NAME = re.compile(r"^[A-Za-z0-9_][A-Za-z0-9_.:-]*$")
"""A team's or an agent's name as the team file allows it (safe in a key expression)."""


class WireError(ValueError):
    """A message that does not match the schema, and why."""


def key(team: str, address: str, kind: str) -> str:
    """The key expression a message of ``kind`` to ``address`` in ``team`` travels under."""
    for part in (team, address, kind):
        if not NAME.match(part):
            raise WireError(f"{part!r} cannot be part of a key expression (letters, digits, "
                            "'_', '.', ':', '-')")
    return f"{PREFIX}/{team}/{address}/{kind}"


def encode(message: Message, at: float | None = None) -> bytes:
    """The message's bytes on the wire; ``at``: the sender's simulated time when it sent
    it (a receiver whose clock is behind catches up before handling it)."""
    data = message.as_dict()
    data["v"] = VERSION
    if at is not None:
        data["at"] = at
    return _ENCODE(data).encode()


def _not_json(constant: str) -> Any:
    """NaN and Infinity: Python's json reads them, JSON has no such thing."""
    raise ValueError(f"{constant} is not a JSON number")


_ENCODE = json.JSONEncoder(separators=(",", ":"), ensure_ascii=False).encode
_DECODE = json.JSONDecoder(parse_constant=_not_json).decode
"""Made once: ``json.dumps``/``loads`` with options build a new coder on every call."""


def _is_str(v: Any) -> bool:
    return isinstance(v, str)


def _is_opt_str(v: Any) -> bool:
    return v is None or isinstance(v, str)


def _is_int(v: Any) -> bool:
    return isinstance(v, int) and not isinstance(v, bool)


def _is_number(v: Any) -> bool:
    return (isinstance(v, (int, float)) and not isinstance(v, bool)
            and math.isfinite(v))


def _is_opt_number(v: Any) -> bool:
    return v is None or _is_number(v)


def _is_bool(v: Any) -> bool:
    return isinstance(v, bool)


def _is_object(v: Any) -> bool:
    return isinstance(v, dict)


def _is_strings(v: Any) -> bool:
    return isinstance(v, list) and all(isinstance(x, str) for x in v)


def _is_triples(v: Any) -> bool:
    """Triples of names whose object may also be a number or a boolean (a pose, a flag)."""
    return isinstance(v, list) and all(
        isinstance(t, list) and len(t) == 3 and isinstance(t[0], str) and isinstance(t[1], str)
        and (isinstance(t[2], (str, bool)) or _is_number(t[2])) for t in v)


TYPES: dict[str, tuple[Any, dict[str, Any]]] = {
    "str": (_is_str, {"type": "string"}),
    "str | None": (_is_opt_str, {"type": ["string", "null"]}),
    "int": (_is_int, {"type": "integer"}),
    "float": (_is_number, {"type": "number"}),
    "float | None": (_is_opt_number, {"type": ["number", "null"]}),
    "bool": (_is_bool, {"type": "boolean"}),
    "dict[str, Any]": (_is_object, {"type": "object"}),
    "tuple[str, ...]": (_is_strings, {"type": "array", "items": {"type": "string"}}),
    "tuple[tuple[str, str, Any], ...]": (_is_triples, {
        "type": "array", "items": {"type": "array", "prefixItems": [
            {"type": "string"}, {"type": "string"},
            {"type": ["string", "number", "boolean"]}], "items": False,
            "minItems": 3, "maxItems": 3}}),
}
"""A dataclass field's annotation -> (its check, its JSON Schema)."""

CHECKS: dict[str, dict[str, Any]] = {
    kind: {f.name: TYPES[str(f.type)][0] for f in fields(cls)} for kind, cls in KINDS.items()}
REQUIRED = ("sender", "to")
_NAMES_SEEN: set[str] = set()
"""Names already found good (a team has a few; a regex per message is not free)."""


def decode(payload: bytes, *, key_expr: str | None = None) -> Message:
    """The message in ``payload`` (received under ``key_expr``), or :class:`WireError`."""
    return decode_timed(payload, key_expr=key_expr)[0]


def decode_timed(payload: bytes, *, key_expr: str | None = None) -> tuple[Message,
                                                                          float | None]:
    """The message in ``payload`` and the time it was sent at (None if not given), or
    :class:`WireError`."""
    if len(payload) > MAX_BYTES:
        raise WireError(f"message of {len(payload)} bytes (at most {MAX_BYTES})")
    try:
        data = _DECODE(payload.decode())
    except (ValueError, RecursionError) as exc:
        raise WireError(f"not JSON: {str(exc)[:80]}") from None
    if not isinstance(data, dict):
        raise WireError(f"a message is a JSON object, not {type(data).__name__}")
    version = data.pop("v", None)
    if version != VERSION:
        raise WireError(f"schema version {version!r} (this peer reads version {VERSION})")
    at = data.pop("at", None)
    if at is not None and not (_is_number(at) and at >= 0):
        raise WireError(f"'at' is a time in seconds, not {json.dumps(at)[:60]}")
    kind = data.pop("kind", None)
    checks = CHECKS.get(kind) if isinstance(kind, str) else None
    if checks is None:
        raise WireError(f"unknown kind {kind!r} (one of {', '.join(KINDS)})")
    for name in REQUIRED:
        if name not in data:
            raise WireError(f"{_a(kind)} message needs {name!r}")
    for name, value in data.items():
        check = checks.get(name)
        if check is None:
            raise WireError(f"{_a(kind)} message has no field {name!r}")
        if not check(value):
            raise WireError(f"field {name!r} of {_a(kind)} message: {json.dumps(value)[:60]} "
                            "has the wrong type")
    for name in REQUIRED:
        if data[name] not in _NAMES_SEEN:
            if not NAME.match(data[name]):
                raise WireError(f"field {name!r}: {data[name][:60]!r} is not an agent's name")
            if len(_NAMES_SEEN) < 10_000:
                _NAMES_SEEN.add(data[name])
    if kind == Question.kind and data.get("type", QUESTION_TYPES[0]) not in QUESTION_TYPES:
        raise WireError(f"question type {data['type']!r} (one of {', '.join(QUESTION_TYPES)})")
    if key_expr is not None:
        parts = key_expr.split("/")
        if len(parts) != 4 or parts[2] != data["to"] or parts[3] != kind:
            raise WireError(f"{_a(kind)} message to {data['to']!r} published under "
                            f"{key_expr!r}")
    return build(kind, data), at


def _a(kind: str) -> str:
    return f"an {kind}" if kind[0] in "aeiou" else f"a {kind}"


def json_schema() -> dict[str, Any]:
    """The wire format as a JSON Schema (the same rules :func:`decode` checks)."""
    variants = []
    for kind, cls in KINDS.items():
        props: dict[str, Any] = {"v": {"const": VERSION}, "kind": {"const": kind},
                                 "at": {"type": "number", "minimum": 0}}
        for f in fields(cls):
            props[f.name] = dict(TYPES[str(f.type)][1])
        for name in REQUIRED:
            props[name] = {"type": "string", "pattern": NAME.pattern}
        if kind == Question.kind:
            props["type"] = {"enum": list(QUESTION_TYPES)}
        variants.append({"type": "object", "properties": props,
                         "required": ["v", "kind", *REQUIRED], "additionalProperties": False})
    return {"$schema": "https://json-schema.org/draft/2020-12/schema",
            "$id": "https://shary.dev/schemas/message.schema.json",
            "title": "a shary message on the wire (version 1)", "oneOf": variants}
