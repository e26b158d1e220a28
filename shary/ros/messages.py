"""Messages from a binding's templates, and text and values from messages.

A binding's goal maps field paths (``pose.pose.position.x``) to values: a
constant, or a template.  A value that is a single template keeps the type it
resolves to (a code is a number, a fact's component a float); text around
templates makes a string.  Each value is converted to the field's type (the
message class says it), so ``"{fact:place:position:0}"`` fills a ``double``.
Message objects are plain Python objects: building one needs no rclpy.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

from shary.ros.binding import _PARAM, TEMPLATE, convert, field_type


class TemplateError(Exception):
    """A template cannot be resolved now (a fact that is not known); the message is why."""


def resolve(value: Any, args: Mapping[str, Any], *, codes: Mapping[str, int],
            fact: Any = None) -> Any:
    """The value of a binding value for a task's ``args``; ``fact(subject, predicate)``
    gives the object of a fact of the robot's perspective, or None."""
    if not isinstance(value, str):
        return value
    found = TEMPLATE.findall(value)
    if len(found) == 1 and value == "{" + found[0] + "}":
        return _one(found[0], args, codes, fact)
    return TEMPLATE.sub(lambda m: str(_one(m.group(1), args, codes, fact)), value)


def _one(text: str, args: Mapping[str, Any], codes: Mapping[str, int], fact: Any) -> Any:
    m = _PARAM.match(text)
    if m is None:
        raise TemplateError(f"{{{text}}} is not a template")
    if m.group(1):
        name = str(args.get(m.group(2), ""))
        if name not in codes:
            raise TemplateError(f"{name!r} has no code in the binding")
        return codes[name]
    if m.group(3):
        subject, predicate = str(args.get(m.group(4), "")), m.group(5)
        known = fact(subject, predicate) if fact is not None else None
        if known is None:
            raise TemplateError(f"the robot knows no {predicate} of {subject!r}")
        if m.group(6) is None:
            return known
        parts = str(known).split()
        index = int(m.group(6))
        if index >= len(parts):
            raise TemplateError(f"the {predicate} of {subject!r} ({known}) has no part {index}")
        return float(parts[index])
    return args.get(m.group(7), "")


def build(cls: Any, fields: Mapping[str, Any], args: Mapping[str, Any], *,
          codes: Mapping[str, int], fact: Any = None) -> Any:
    """A ``cls`` message with ``fields`` resolved for ``args`` (raises TemplateError)."""
    message = cls()
    for path, value in fields.items():
        resolved = resolve(value, args, codes=codes, fact=fact)
        kind = field_type(cls, path) or "string"
        *parents, last = path.split(".")
        target = message
        for part in parents:
            target = getattr(target, part)
        setattr(target, last, convert(resolved, kind))
    return message


def read_field(message: Any, path: str) -> Any:
    """The value at ``a.b.c`` of a message (None when it has no such field)."""
    value = message
    for part in path.split("."):
        value = getattr(value, part, None)
        if value is None:
            return None
    return value


def shown(value: Any) -> str:
    """A field's value as text in a progress row or a reason."""
    if isinstance(value, float):
        return f"{value:.3g}"
    return str(value)


def text(template: str, message: Any, item: Any = None) -> str:
    """``template`` with each ``{a.b}`` replaced by that field of ``message`` (``{item}``
    and ``{item.x}``: of ``item``)."""
    def field(match: Any) -> str:
        path = match.group(1)
        if path == "item" or path.startswith("item."):
            value = item if path == "item" else read_field(item, path[5:])
        else:
            value = read_field(message, path)
        return shown(value)

    return TEMPLATE.sub(field, template)


def matches(message: Any, wanted: Mapping[str, Any]) -> list[str]:
    """The fields of ``message`` that differ from ``wanted``, as ``field=value`` texts."""
    return [f"{path}={shown(read_field(message, path))}" for path, value in wanted.items()
            if read_field(message, path) != value]
