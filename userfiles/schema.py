"""JSON Schema checks of located YAML, reported with file positions.

jsonschema's raw messages are rewritten where a user would otherwise be
puzzled: unknown keys get a "did you mean", and a failed ``anyOf`` reports the
branch that came closest instead of "is not valid under any of the given
schemas".  Each package keeps its own schemas (``shary/schemas``,
``planner/schemas``) and builds validators with :func:`validator`.
"""

from __future__ import annotations

import difflib
import json
import re
from functools import cache
from pathlib import Path
from typing import Any
from urllib.parse import urldefrag, urljoin

from jsonschema import Draft202012Validator, FormatChecker
from jsonschema.exceptions import ValidationError, best_match
from referencing import Registry, Resource

from userfiles.errors import Problem
from userfiles.limits import MAX_DURATION, seconds, show_seconds
from userfiles.yamlsafe import Located

FORMATS = FormatChecker(formats=())
"""Formats that carry a limit: ``"format": "duration"`` on a schema's duration
definition bounds every duration of that format at once (see limits.py)."""


@FORMATS.checks("duration")
def _duration(value: Any) -> bool:
    try:
        amount = seconds(value)
    except (ValueError, TypeError):
        return True  # the shape is the pattern's business, reported once, there
    return not amount > MAX_DURATION  # NaN was reported by yamlsafe, once


_REGISTRIES: dict[str, Registry] = {}
"""The registry each schema read by :func:`_folder` resolves its ``$ref`` in, by the
schema's ``$id``: where :func:`_document_of` finds the file a sub-schema is written in."""


@cache
def _folder(folder: Path) -> tuple[Registry, dict[str, Any]]:
    """The schemas of ``folder``, read once: a registry of them by ``$id``, and each by
    name.  Every validator of the folder shares these documents, which
    :func:`_follow` recognizes by identity."""
    documents = {f.name.removesuffix(".schema.json"): json.loads(f.read_text("utf-8"))
                 for f in sorted(folder.iterdir()) if f.name.endswith(".schema.json")}
    registry = Registry().with_resources(
        (doc["$id"], Resource.from_contents(doc)) for doc in documents.values())
    _REGISTRIES.update((doc["$id"], registry) for doc in documents.values())
    return registry, documents


def validator(folder: Path, name: str) -> Draft202012Validator:
    """A validator for ``folder/NAME.schema.json``, resolving ``$ref`` to its siblings,
    with the limits of :data:`FORMATS` checked."""
    registry, documents = _folder(folder)
    return Draft202012Validator(documents[name], registry=registry, format_checker=FORMATS)


def _document_of(checker: Draft202012Validator,
                 error: ValidationError) -> Draft202012Validator:
    """A validator rooted at the schema file that ``error.schema`` is written in.

    The advice on an unknown key checks values against sub-schemas of the error
    (``checker.evolve(schema=sub)``), and an evolved validator resolves a local
    ``$ref`` (``#/$defs/description``) against its root.  When the error lies
    behind a ``$ref`` to another file (a scenario's inline profile is checked by
    ``profile.schema.json``), that root must be the other file: following the
    error's schema path through the registry says which file it is."""
    uri = checker.schema.get("$id") if isinstance(checker.schema, dict) else None
    registry = _REGISTRIES.get(uri) if isinstance(uri, str) else None
    if registry is None:
        return checker
    found = _follow(checker.schema, list(error.absolute_schema_path)[:-1], error.schema,
                    uri, registry)
    if found is None or found == uri:
        return checker
    return Draft202012Validator(registry.contents(found), registry=registry,
                                format_checker=FORMATS)


def _follow(node: Any, steps: list[str | int], target: Any, uri: str,
            registry: Registry) -> str | None:
    """The file (its ``$id``) in which ``steps`` from ``node`` lead to ``target``.

    A schema path leaves out the ``$ref`` it went through (``oneOf/1`` then
    ``additionalProperties`` of the file referred to), and a schema may hold both a
    ``$ref`` and keywords of its own: each step is tried in ``node`` first, then in
    what its ``$ref`` refers to, and the way that ends at ``target`` is the one the
    validator took."""
    if node is target and not steps:
        return uri
    step = steps[0] if steps else None
    if isinstance(node, dict) and isinstance(step, str) and step in node \
            or isinstance(node, list) and isinstance(step, int) and 0 <= step < len(node):
        found = _follow(node[step], steps[1:], target, uri, registry)
        if found is not None:
            return found
    ref = node.get("$ref") if isinstance(node, dict) else None
    if not isinstance(ref, str):
        return None
    contents = registry.resolver(base_uri=uri).lookup(ref).contents
    return _follow(contents, steps, target, urldefrag(urljoin(uri, ref))[0], registry)


def did_you_mean(word: str, choices: Any) -> str:
    """`` (did you mean 'x'?)`` when a close match exists, else an empty string."""
    close = difflib.get_close_matches(word, [str(c) for c in choices], n=1, cutoff=0.6)
    return f" (did you mean {close[0]!r}?)" if close else ""


def check(located: Located, checker: Draft202012Validator) -> list[Problem]:
    """Every violation of a schema in ``located`` (and its loading problems)."""
    problems: list[Problem] = list(located.problems)
    for error in checker.iter_errors(located.data):
        problems.extend(_explain(located, error, checker))
    return problems


def _keys_elsewhere(root: dict[str, Any]) -> dict[str, list[tuple[str, Any]]]:
    """Every key the schema ``root`` knows, with the objects it is a key of ("a state",
    "the top level", "an entry of 'people'") and its schema there: a key a file puts
    under the wrong parent is known there, and saying where beats a "did you mean" on a
    look-alike key."""
    cached = _ELSEWHERE.get(id(root))
    if cached is not None and cached[0] is root:
        return cached[1]
    places: dict[str, list[tuple[str, Any]]] = {}
    seen: set[int] = set()

    def walk(schema: Any, label: str) -> None:
        if not isinstance(schema, dict) or id(schema) in seen:
            return
        seen.add(id(schema))
        for key, sub in (schema.get("properties") or {}).items():
            places.setdefault(key, []).append((label, sub))
        for key, sub in (schema.get("properties") or {}).items():
            walk(sub, f"'{key}'")
        for name, sub in (schema.get("$defs") or {}).items():
            walk(sub, _article(name.replace("_", " ")))
        for sub in [*(schema.get("patternProperties") or {}).values(),
                    schema.get("additionalProperties"), schema.get("items")]:
            walk(sub, f"an entry of {label}" if label.startswith("'") else label)
        for name in ("anyOf", "oneOf", "allOf"):
            for sub in schema.get(name) or []:
                walk(sub, label)

    walk(root, "the top level")
    _ELSEWHERE[id(root)] = (root, places)
    return places


_ELSEWHERE: dict[int, tuple[dict[str, Any], dict[str, list[tuple[str, Any]]]]] = {}
""":func:`_keys_elsewhere` by schema (a hostile file may have thousands of unknown keys)."""


def size_limits(checker: Draft202012Validator) -> dict[tuple, int]:
    """The size limits (``maxProperties``, ``maxItems``) along the schema's plain
    ``properties``, by path of keys, for the event pass of :mod:`userfiles.yamlsafe`:
    a file of ten thousand people is refused at the key after reading the 51st,
    instead of after building and validating each of them."""
    limits: dict[tuple, int] = {}

    def walk(schema: Any, path: tuple) -> None:
        if not isinstance(schema, dict):
            return
        for name in ("maxProperties", "maxItems"):
            if isinstance(schema.get(name), int):
                limits[path] = schema[name]
        for key, sub in (schema.get("properties") or {}).items():
            walk(sub, path + (key,))

    walk(checker.schema, ())
    return limits


def _entry_of(checker: Draft202012Validator, schema: dict[str, Any], key: str,
              value: Any) -> list[str]:
    """The properties of ``schema`` under which ``key: value`` would be a valid entry
    (an event under a state's ``on``): where a key one level too high belongs."""
    found = []
    for name, sub in (schema.get("properties") or {}).items():
        ref = sub.get("$ref") if isinstance(sub, dict) else None
        if isinstance(ref, str) and ref.startswith("#/"):
            sub = _local(checker.schema, ref)
        if not isinstance(sub, dict) or sub.get("type") not in ("object", None):
            continue
        entries = [v for p, v in (sub.get("patternProperties") or {}).items() if _matches(p, key)]
        if isinstance(sub.get("additionalProperties"), dict):
            entries.append(sub["additionalProperties"])
        if any(checker.evolve(schema=entry).is_valid(value) for entry in entries):
            found.append(f"'{name}'")
    return found


def _unknown_key(checker: Draft202012Validator | None, schema: dict[str, Any], key: str,
                 value: Any) -> str:
    """Why ``key: value`` is refused in an object of ``schema``, in the order a user
    most likely erred: a typo of a key here whose value fits (``method`` for
    ``methods``), a key of another object (put under the wrong parent), an entry of a
    child mapping one level too high (an event beside ``on:`` instead of under it), a
    look-alike key, else the keys here."""
    known = list(schema.get("properties", {}))
    wrong_parent = " (indented under the wrong parent?)"
    close = difflib.get_close_matches(key, known, n=1, cutoff=0.6)
    if close and checker is not None and checker.evolve(
            schema=schema["properties"][close[0]]).is_valid(value):
        return f"unknown key {key!r} (did you mean {close[0]!r}?)"
    elsewhere = [] if checker is None else list(dict.fromkeys(
        label for label, sub in _keys_elsewhere(checker.schema).get(key, [])
        if checker.evolve(schema=sub).is_valid(value)))
    if elsewhere:
        return f"{key!r} is not a key here: it is a key of {' or '.join(elsewhere[:3])}" \
            + wrong_parent
    below = _entry_of(checker, schema, key, value) if checker is not None else []
    if below:
        return f"{key!r} is not a key here: it reads as an entry of {' or '.join(below)}" \
            + wrong_parent
    if close:
        return f"unknown key {key!r} (did you mean {close[0]!r}?)"
    return f"unknown key {key!r}" + (f"; expected one of: {', '.join(known)}" if known else "")


def _local(root: dict[str, Any], ref: str) -> Any:
    """What a local ``$ref`` (``#/$defs/on``) names in ``root``."""
    target: Any = root
    for part in ref[2:].split("/"):
        target = target.get(part) if isinstance(target, dict) else None
    return target


def _explain(located: Located, error: ValidationError,
             checker: Draft202012Validator | None = None) -> list[Problem]:
    path = tuple(error.absolute_path)
    if error.validator in ("anyOf", "oneOf") and error.context:
        # A branch that fails on the type of the value itself was not the one meant.
        meant = [e for e in error.context
                 if not (e.validator == "type" and not e.relative_path)]
        # An error inside the value (a list item) beats a branch that failed at its root.
        inside = [e for e in meant if e.relative_path]
        return _explain(located, best_match(inside or meant or error.context), checker)
    if error.validator == "additionalProperties" and isinstance(error.instance, dict):
        checker = _document_of(checker, error) if checker is not None else None
        known = list(error.schema.get("properties", {}))
        allowed = set(known)
        patterns = list(error.schema.get("patternProperties", {}))
        out = []
        for key in error.instance:
            if key in allowed or any(_matches(p, key) for p in patterns):
                continue
            out.append(located.problem(path + (key,), _unknown_key(
                checker, error.schema, key, error.instance[key]), key=True))
        return out
    if error.validator == "required":
        return [located.problem(path, error.message.replace("is a required property",
                                                            "is missing (required)"))]
    if error.validator == "type":
        expected = error.validator_value
        if isinstance(expected, list):
            expected = " or ".join(expected)
        return [located.problem(path, f"expected {_article(expected)} here, "
                                      f"got {_describe(error.instance)}")]
    if error.validator == "enum":
        hint = did_you_mean(str(error.instance), error.validator_value)
        choices = ", ".join(str(v) for v in error.validator_value)
        return [located.problem(path, f"{error.instance!r} is not one of: {choices}{hint}")]
    if error.validator == "pattern":
        what = error.schema.get("description", f"must match {error.validator_value}")
        return [located.problem(path, f"{error.instance!r}: {what}")]
    if error.validator == "format" and error.validator_value == "duration":
        return [located.problem(path, f"duration {error.instance} is too long (the limit is "
                                      f"{show_seconds(MAX_DURATION)})")]
    if error.validator in ("maximum", "exclusiveMaximum"):
        return [located.problem(path, f"{error.instance} is too large (the limit is "
                                      f"{error.validator_value})")]
    if error.validator in ("maxProperties", "maxItems"):
        return [located.problem(path, f"{len(error.instance)} entries: too many (the limit "
                                      f"is {error.validator_value})")]
    if error.validator == "propertyNames":
        return [located.problem(path, error.message)]
    return [located.problem(path, error.message)]


def _matches(pattern: str, key: str) -> bool:
    return re.search(pattern, key) is not None


def _article(kind: str) -> str:
    return ("an " if kind[:1] in "aeiou" else "a ") + kind if " or " not in kind else kind


def _describe(value: Any) -> str:
    if value is None:
        return "nothing (null)"
    if isinstance(value, bool):
        return f"a boolean ({value})"
    if isinstance(value, (int, float)):
        return f"a number ({value})"
    if isinstance(value, str):
        return f"a string ({value!r})"
    if isinstance(value, list):
        return "a list"
    if isinstance(value, dict):
        return "a mapping"
    return type(value).__name__
