"""Importing SCXML charts into the scheme format.

The data-model-free part of W3C SCXML maps one to one onto schemes:
``<state>``, ``<parallel>``, ``<final>``, ``<history>``, ``<initial>``,
``<transition>`` with ``event``/``target``/``type``, and the executable content
``<raise>``, ``<send>`` (to the chart itself, optionally delayed, with an id),
``<cancel>``, ``<log label>``, in ``<onentry>``/``<onexit>``.  Anything that
needs a data model or an outside processor (``cond``, ``<script>``,
``<assign>``, ``<if>``, ``<invoke>``, ``expr`` attributes …) is refused by name
with its position, never half-translated.

Two differences are bridged on the way: a compound state without ``initial``
gets SCXML's default (its first child) written out, since schemes require it,
and a transition that can never be taken because an earlier unguarded one of
the same state takes the same events is dropped (schemes refuse dead
transitions).  The chart's behaviour is unchanged by either.
"""

from __future__ import annotations

import os
import re
import xml.parsers.expat
from dataclasses import dataclass, field
from typing import Any

import yaml

from shary.io.schemes import parse_scheme, unreachable
from shary.model import covers
from userfiles.errors import FileError, Problem
from userfiles.yamlsafe import Located, read_text

_NAME = re.compile(r"^[A-Za-z0-9_][A-Za-z0-9_.:-]*$")
_TIME = re.compile(r"^\s*([0-9]*\.?[0-9]+)\s*(ms|s)\s*$")
_STATES = {"state", "parallel", "final", "history"}
_ACTIONS = {"raise", "send", "cancel", "log"}
_NEEDS_DATAMODEL = {"script", "assign", "if", "elseif", "else", "foreach", "datamodel", "data",
                    "donedata", "param", "content", "invoke", "finalize"}


@dataclass
class _Element:
    tag: str
    attrs: dict[str, str]
    line: int
    col: int
    children: list[_Element] = field(default_factory=list)


def import_scxml(path: str | os.PathLike[str]) -> str:
    """The scheme YAML equivalent to an SCXML file; :class:`FileError` for what cannot be."""
    name = os.fspath(path)
    root = _parse(read_text(name), name)
    return _Translator(name).document(root)


def _parse(text: str, file: str) -> _Element:
    parser = xml.parsers.expat.ParserCreate(namespace_separator=" ")
    stack: list[_Element] = []
    top: list[_Element] = []

    def refuse(what: str) -> None:
        raise FileError([Problem(file, parser.CurrentLineNumber, parser.CurrentColumnNumber + 1,
                                 what)])

    def start(tag: str, attrs: dict[str, str]) -> None:
        local = tag.split(" ")[-1]
        element = _Element(local, {k.split(" ")[-1]: v for k, v in attrs.items()},
                           parser.CurrentLineNumber, parser.CurrentColumnNumber + 1)
        (stack[-1].children if stack else top).append(element)
        stack.append(element)

    def end(tag: str) -> None:
        stack.pop()

    parser.StartElementHandler = start
    parser.EndElementHandler = end
    parser.StartDoctypeDeclHandler = lambda *a: refuse("DOCTYPE declarations are not accepted")
    parser.EntityDeclHandler = lambda *a: refuse("entity declarations are not accepted")
    try:
        parser.Parse(text, True)
    except xml.parsers.expat.ExpatError as err:
        raise FileError([Problem(file, err.lineno, err.offset + 1,
                                 f"XML syntax: {xml.parsers.expat.errors.messages[err.code]}")]
                        ) from None
    if not top or top[0].tag != "scxml":
        raise FileError([Problem(file, 1, 1, "not an SCXML document (no <scxml> root)")])
    return top[0]


class _Translator:
    def __init__(self, file: str):
        self.file = file
        self.problems: list[Problem] = []
        self.generated = 0

    def refuse(self, element: _Element, message: str) -> None:
        self.problems.append(Problem(self.file, element.line, element.col, message))

    def document(self, root: _Element) -> str:
        for attr in ("datamodel", "binding"):
            if root.attrs.get(attr, "") not in ("", "ecmascript", "null", "early"):
                self.refuse(root, f"{attr}={root.attrs[attr]!r} is not supported")
        name = root.attrs.get("name") or os.path.splitext(os.path.basename(self.file))[0]
        states = self.children(root)
        out: dict[str, Any] = {"scheme": _safe_name(name),
                               "doc": f"Imported from {os.path.basename(self.file)}."}
        initial = root.attrs.get("initial", "").split()
        if initial:
            out["initial"] = initial[0] if len(initial) == 1 else initial
        elif states:
            out["initial"] = next(iter(states))
        out["states"] = states
        if self.problems:
            raise FileError(self.problems)
        pruned = _prune_unreachable(out, self.file)
        text = yaml.safe_dump(out, sort_keys=False, allow_unicode=True, width=100)
        if pruned:
            text = (f"# Left out, since no run can ever enter them: {', '.join(pruned)}\n"
                    + text)
        return text

    def children(self, element: _Element) -> dict[str, Any]:
        states: dict[str, Any] = {}
        for child in element.children:
            if child.tag in _STATES:
                ident = child.attrs.get("id")
                if ident is None:
                    self.generated += 1
                    ident = f"_state{self.generated}"
                elif not _NAME.match(ident):
                    self.refuse(child, f"state id {ident!r} cannot be a scheme state name")
                    continue
                states[ident] = self.state(child)
            elif child.tag in _NEEDS_DATAMODEL:
                self.refuse(child, f"<{child.tag}> needs a data model, which schemes do not have")
            elif child.tag not in ("initial", "transition", "onentry", "onexit"):
                self.refuse(child, f"<{child.tag}> is not supported")
        return states

    def state(self, element: _Element) -> dict[str, Any]:
        spec: dict[str, Any] = {}
        if element.tag == "final":
            spec["final"] = True
        elif element.tag == "parallel":
            spec["parallel"] = True
        elif element.tag == "history":
            spec["history"] = element.attrs.get("type", "shallow")
            defaults = [c for c in element.children if c.tag == "transition"]
            if defaults:
                if [c for c in defaults[0].children]:
                    self.refuse(defaults[0], "actions on a history's default transition are "
                                "not supported")
                spec["default"] = _one_or_list(defaults[0].attrs.get("target", "").split())
            return spec
        initial = element.attrs.get("initial", "").split()
        for child in element.children:
            if child.tag == "initial":
                transition = next((c for c in child.children if c.tag == "transition"), None)
                if transition is None:
                    self.refuse(child, "<initial> without a <transition>")
                    continue
                if transition.children:
                    self.refuse(transition, "actions on an <initial> transition are not "
                                "supported")
                initial = transition.attrs.get("target", "").split()
        children = self.children(element)
        if element.tag == "state" and children and not initial:
            proper = [n for n, s in children.items() if "history" not in (s or {})]
            if len(proper) > 1:
                initial = proper[:1]
        if initial and element.tag == "state":
            spec["initial"] = _one_or_list(initial)
        for kind in ("onentry", "onexit"):
            actions = [a for c in element.children if c.tag == kind for a in self.actions(c)]
            if actions:
                spec["on_entry" if kind == "onentry" else "on_exit"] = actions
        on = self.transitions(element)
        if on:
            spec["on"] = on
        if children:
            spec["states"] = children
        return spec or None  # type: ignore[return-value]

    def transitions(self, element: _Element) -> dict[str, Any]:
        kept: list[tuple[str, tuple[str, ...] | None, Any]] = []
        for t in (c for c in element.children if c.tag == "transition"):
            if "cond" in t.attrs:
                self.refuse(t, "cond= needs a data model; use a scheme guard naming a "
                            "registered condition instead")
                continue
            for attr in t.attrs:
                if attr not in ("event", "target", "type"):
                    self.refuse(t, f"transition attribute {attr!r} is not supported")
            events = tuple(t.attrs["event"].split()) if "event" in t.attrs else None
            if any(covers(earlier, events) for _, earlier, _ in kept):
                continue
            targets = t.attrs.get("target", "").split()
            actions = self.actions(t)
            body: dict[str, Any] = {}
            if len(targets) != 1 or actions or t.attrs.get("type") == "internal":
                body["target"] = _one_or_list(targets) if targets else None
                if t.attrs.get("type") == "internal" and targets:
                    body["type"] = "internal"
                if actions:
                    body["do"] = actions
                value: Any = body
            else:
                value = _one_or_list(targets)
            key = " ".join(events) if events is not None else "always"
            kept.append((key, events, value))
        grouped: dict[str, list[Any]] = {}
        for index, (key, events, value) in enumerate(kept):
            if key in grouped:
                order = list(grouped)
                moved = [k for k, e, _ in kept[:index]
                         if k != key and order.index(k) > order.index(key) and _overlap(events, e)]
                if moved:
                    self.refuse(element, f"transitions on {key!r} are interleaved with others "
                                "that take the same events; their order cannot be kept")
                    continue
            grouped.setdefault(key, []).append(value)
        return {k: v[0] if len(v) == 1 else v for k, v in grouped.items()}

    def actions(self, element: _Element) -> list[dict[str, Any]]:
        out: list[dict[str, Any]] = []
        for a in element.children:
            if a.tag in _NEEDS_DATAMODEL:
                self.refuse(a, f"<{a.tag}> needs a data model, which schemes do not have")
            elif a.tag not in _ACTIONS:
                self.refuse(a, f"<{a.tag}> is not supported in executable content")
            elif a.tag == "raise":
                out.append({"raise": a.attrs.get("event", "")})
            elif a.tag == "send":
                out.append(self.send(a))
            elif a.tag == "cancel":
                if "sendid" not in a.attrs:
                    self.refuse(a, "<cancel> needs sendid= (sendidexpr needs a data model)")
                out.append({"cancel": a.attrs.get("sendid", "")})
            else:
                if "expr" in a.attrs:
                    self.refuse(a, "<log expr> needs a data model; use label=")
                out.append({"log": a.attrs.get("label", "")})
        return out

    def send(self, a: _Element) -> dict[str, Any]:
        for attr in a.attrs:
            if attr not in ("event", "delay", "id", "target", "type"):
                self.refuse(a, f"<send {attr}=…> is not supported (it needs a data model)")
        if a.attrs.get("target", "#_internal") not in ("#_internal",):
            self.refuse(a, "<send> to another target than the chart itself is not supported")
        if a.children:
            self.refuse(a, "<send> with <param> or <content> needs a data model")
        if "event" not in a.attrs:
            self.refuse(a, "<send> needs event=")
        if a.attrs.get("target") == "#_internal":
            return {"raise": a.attrs.get("event", "")}
        out: dict[str, Any] = {"send": a.attrs.get("event", "")}
        if "delay" in a.attrs:
            match = _TIME.match(a.attrs["delay"])
            if not match:
                self.refuse(a, f"delay {a.attrs['delay']!r} is not a time (write 10ms or 1.5s)")
            else:
                number = match.group(1)
                out["delay"] = (("0" + number) if number.startswith(".") else number) \
                    + match.group(2)
        if "id" in a.attrs:
            out["id"] = a.attrs["id"]
        return out


def _prune_unreachable(document: dict[str, Any], file: str) -> list[str]:
    """Remove the states no run can enter (schemes refuse them); return their names."""
    scheme = parse_scheme(Located(file, document), check_reachable=False)
    dead = {s.name for s in unreachable(scheme)}

    def prune(states: dict[str, Any]) -> None:
        for name in [n for n in states if n in dead]:
            del states[name]
        for spec in states.values():
            if isinstance(spec, dict) and isinstance(spec.get("states"), dict):
                prune(spec["states"])

    prune(document["states"])
    return sorted(dead, key=lambda n: scheme.states[n].order)


def _one_or_list(items: list[str]) -> Any:
    return items[0] if len(items) == 1 else list(items)


def _safe_name(name: str) -> str:
    safe = re.sub(r"[^A-Za-z0-9_.:-]", "-", name)
    return safe if _NAME.match(safe) else f"chart-{safe}"


def _overlap(a: tuple[str, ...] | None, b: tuple[str, ...] | None) -> bool:
    """True when some event could be taken by both descriptor lists."""
    if a is None or b is None:
        return a is None and b is None
    return any(covers((x,), (y,)) or covers((y,), (x,)) for x in a for y in b)
