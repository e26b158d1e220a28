"""Importing SCXML charts into the scheme format.

The data-model-free part of W3C SCXML maps one to one onto schemes:
``<state>``, ``<parallel>``, ``<final>``, ``<history>``, ``<initial>``,
``<transition>`` with ``event``/``target``/``type``, and the executable content
``<raise>``, ``<send>`` (to the chart itself, optionally delayed, with an id),
``<cancel>``, ``<log label>``, in ``<onentry>``/``<onexit>`` and on
``<initial>`` and history default transitions, and ``<invoke>`` of another
SCXML chart (inline ``<content>`` or a ``src`` file below the chart's folder),
written inline in the scheme.  Anything that needs a data model or an outside
processor (``cond``, ``<script>``, ``<assign>``, ``<if>``, ``<param>``,
``expr`` attributes …) is refused by name with its position, never
half-translated.

The XML is read with the standard library's expat, without DOCTYPE (so no
entity is ever declared, expanded or fetched: no entity bombs, no external
entities), element by element: a chart nested deeper than
:data:`MAX_DEPTH` or larger than :data:`MAX_ELEMENTS` stops the reading at
that element, and nothing after it is recursed into.

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

from shary.io.schemes import parse_scheme, unreachable
from shary.model import Coverage
from userfiles.errors import FileError, Problem
from userfiles.reader import confine, spelled
from userfiles.yamlsafe import Located, dump, read_text

MAX_DEPTH = 28
"""Deepest nesting of XML elements: a scheme file allows 64 levels of YAML, and each
level of states takes two (the state and its ``states:``)."""
MAX_ELEMENTS = 10_000
"""Most XML elements a chart (with the charts it invokes) may have."""
MAX_INVOKE_DEPTH = 8
"""Most charts a chain of ``<invoke src>`` may go through."""

_NAME = re.compile(r"^[A-Za-z0-9_][A-Za-z0-9_.:-]*$")
_TIME = re.compile(r"^\s*([0-9]*\.?[0-9]+)\s*(ms|s)\s*$")
_STATES = {"state", "parallel", "final", "history"}
_ACTIONS = {"raise", "send", "cancel", "log"}
_NEEDS_DATAMODEL = {"script", "assign", "if", "elseif", "else", "foreach", "datamodel", "data",
                    "donedata", "param", "content", "finalize"}
_SCXML_TYPES = ("", "scxml", "http://www.w3.org/TR/scxml/", "http://www.w3.org/TR/scxml")


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
    budget = [MAX_ELEMENTS]
    root = _parse(read_text(name), name, budget)
    out, pruned = _Translator(name, (os.path.realpath(name),), budget).scheme(root)
    text = dump(out)
    if pruned:
        text = f"# Left out, since no run can ever enter them: {', '.join(pruned)}\n" + text
    return text


def _parse(text: str, file: str, budget: list[int]) -> _Element:
    """The element tree of an SCXML text; ``budget`` counts down the elements left."""
    parser = xml.parsers.expat.ParserCreate(namespace_separator=" ")
    stack: list[_Element] = []
    top: list[_Element] = []

    def refuse(what: str, line: int | None = None, col: int | None = None) -> None:
        raise FileError([Problem(file, line or parser.CurrentLineNumber,
                                 col or parser.CurrentColumnNumber + 1, what)])

    def start(tag: str, attrs: dict[str, str]) -> None:
        if len(stack) >= MAX_DEPTH:
            refuse(f"elements nested more than {MAX_DEPTH} deep: the limit of a chart")
        budget[0] -= 1
        if budget[0] < 0:
            refuse(f"more than {MAX_ELEMENTS} XML elements: the limit of a chart (with the "
                   "charts it invokes)", 1, 1)
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
    def __init__(self, file: str, chain: tuple[str, ...], budget: list[int]):
        self.file = file
        self.chain = chain
        self.budget = budget
        self.problems: list[Problem] = []
        self.generated = 0

    def refuse(self, element: _Element, message: str) -> None:
        self.problems.append(Problem(self.file, element.line, element.col, message))

    def scheme(self, root: _Element) -> tuple[dict[str, Any], list[str]]:
        """The scheme of an ``<scxml>`` element, and the unreachable states left out."""
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
        return out, _prune_unreachable(out, self.file)

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
            elif child.tag not in ("initial", "transition", "onentry", "onexit", "invoke"):
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
                spec["default"] = self.initial(defaults[0])
            return spec
        initial: Any = _one_or_list(element.attrs.get("initial", "").split()) \
            if "initial" in element.attrs else None
        for child in element.children:
            if child.tag == "initial":
                transition = next((c for c in child.children if c.tag == "transition"), None)
                if transition is None:
                    self.refuse(child, "<initial> without a <transition>")
                    continue
                initial = self.initial(transition)
        children = self.children(element)
        if element.tag == "state" and children and not initial:
            proper = [n for n, s in children.items() if "history" not in (s or {})]
            if len(proper) > 1:
                initial = proper[0]
        if initial and element.tag == "state":
            spec["initial"] = initial
        for kind in ("onentry", "onexit"):
            actions = [a for c in element.children if c.tag == kind for a in self.actions(c)]
            if actions:
                spec["on_entry" if kind == "onentry" else "on_exit"] = actions
        on = self.transitions(element)
        if on:
            spec["on"] = on
        invokes = [self.invoke(c) for c in element.children if c.tag == "invoke"]
        if invokes:
            spec["invoke"] = invokes[0] if len(invokes) == 1 else invokes
        if children:
            spec["states"] = children
        return spec or None  # type: ignore[return-value]

    def initial(self, transition: _Element) -> Any:
        """The targets of an ``<initial>`` or history default transition, with its actions."""
        targets = _one_or_list(transition.attrs.get("target", "").split())
        actions = self.actions(transition)
        return {"target": targets, "do": actions} if actions else targets

    def invoke(self, element: _Element) -> dict[str, Any]:
        """An ``<invoke>`` of another SCXML chart, its child written inline."""
        out: dict[str, Any] = {}
        for attr, value in element.attrs.items():
            if attr in ("typeexpr", "srcexpr", "idlocation", "namelist"):
                self.refuse(element, f"<invoke {attr}=…> needs a data model")
            elif attr == "type" and value not in _SCXML_TYPES:
                self.refuse(element, f"<invoke type={value!r}>: only SCXML charts can be "
                            "invoked")
            elif attr not in ("type", "src", "id", "autoforward"):
                self.refuse(element, f"<invoke {attr}=…> is not supported")
        if "id" in element.attrs:
            if _NAME.match(element.attrs["id"]):
                out["id"] = element.attrs["id"]
            else:
                self.refuse(element, f"invoke id {element.attrs['id']!r} cannot be a scheme "
                            "name")
        if element.attrs.get("autoforward") == "true":
            out["autoforward"] = True
        contents = [c for c in element.children if c.tag == "content"]
        for c in element.children:
            if c.tag != "content" and not (c.tag == "finalize" and not c.children):
                self.refuse(c, f"<{c.tag}> in <invoke> needs a data model")
        if "src" in element.attrs and contents or len(contents) > 1:
            self.refuse(element, "<invoke> takes either src= or one <content>")
        elif contents:
            inner = [c for c in contents[0].children if c.tag == "scxml"]
            if "expr" in contents[0].attrs or len(inner) != 1:
                self.refuse(contents[0], "<content> of an <invoke> must hold one <scxml> chart "
                            "(expr= needs a data model)")
            else:
                out["scheme"] = self.child(inner[0], self.file, self.chain)
        elif "src" in element.attrs:
            out["scheme"] = self.src(element, element.attrs["src"])
        elif "srcexpr" not in element.attrs:
            self.refuse(element, "<invoke> needs src= or a <content> chart")
        return out

    def src(self, element: _Element, src: str) -> dict[str, Any] | None:
        """The chart an ``<invoke src>`` names: a file below this chart's folder."""
        full, refusal = confine(self.file, src)
        if refusal is not None:
            self.refuse(element, refusal)
            return None
        path = str(full)
        if path in self.chain:
            names = [os.path.basename(f) for f in self.chain[self.chain.index(path):]]
            self.refuse(element, f"invoke cycle: {' -> '.join([*names, os.path.basename(path)])}")
            return None
        if len(self.chain) >= MAX_INVOKE_DEPTH:
            self.refuse(element, f"invokes nest more than {MAX_INVOKE_DEPTH} charts deep")
            return None
        shown = spelled(path, like=self.file)
        try:
            root = _parse(read_text(shown), shown, self.budget)
        except FileError as err:
            self.problems.extend(err.problems)
            return None
        return self.child(root, shown, self.chain + (path,))

    def child(self, root: _Element, file: str, chain: tuple[str, ...]) -> dict[str, Any] | None:
        if root.tag != "scxml":
            self.refuse(root, f"<{root.tag}> is not an SCXML chart")
            return None
        translator = _Translator(file, chain, self.budget)
        try:
            scheme, _ = translator.scheme(root)
        except FileError as err:
            self.problems.extend(err.problems)
            return None
        return scheme

    def transitions(self, element: _Element) -> dict[str, Any]:
        taken = Coverage()
        on: dict[str, Any] = {}
        for t in (c for c in element.children if c.tag == "transition"):
            if "cond" in t.attrs:
                self.refuse(t, "cond= needs a data model; use a scheme guard naming a "
                            "registered condition instead")
                continue
            for attr in t.attrs:
                if attr not in ("event", "target", "type"):
                    self.refuse(t, f"transition attribute {attr!r} is not supported")
            events = tuple(t.attrs["event"].split()) if "event" in t.attrs else None
            if taken.covering(events) is not None:
                continue  # an earlier transition takes all its events: it is never taken
            taken.add(events, t)
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
            on[" ".join(events) if events is not None else "always"] = value
        return on

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
    """A name for one target, a list for several (as schemes write them)."""
    return items[0] if len(items) == 1 else list(items)


def _safe_name(name: str) -> str:
    safe = re.sub(r"[^A-Za-z0-9_.:-]", "-", name)
    return safe if _NAME.match(safe) else f"chart-{safe}"
