"""Importing SCXML charts into the scheme format.

The data-model-free part of W3C SCXML maps one to one onto schemes:
``<state>``, ``<parallel>``, ``<final>``, ``<history>``, ``<initial>``,
``<transition>`` with ``event``/``target``/``type``, and the executable content
``<raise>``, ``<send>`` (to the chart itself, optionally delayed, with an id),
``<cancel>``, ``<log label>``, in ``<onentry>``/``<onexit>`` and on
``<initial>`` and history default transitions, and ``<invoke>`` of another
SCXML chart (inline ``<content>`` or a ``src`` file below the chart's folder),
written inline in the scheme.  A chart with ``datamodel="shary"`` (or
``python``) has its data model imported too
(:mod:`shary.io.scxml_data`); in one without, anything that needs a data
model (``cond``, ``<assign>``, ``<if>``, ``<param>``, ``expr`` attributes …)
is refused by name with its position, never half-translated, and so are, in
every chart, ``<script>`` and what an outside processor would do.

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
from urllib.parse import unquote, urlsplit

from shary.io import scxml_data
from shary.io.schemes import parse_scheme, unreachable
from shary.statechart.model import PARENT, Coverage
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
_IN = re.compile(r"""^\s*In\(\s*(['"])([A-Za-z0-9_][A-Za-z0-9_.:-]*)\1\s*\)\s*$""")
_TIME = re.compile(r"^\s*([0-9]*\.?[0-9]+)\s*(ms|s)\s*$")
_STATES = {"state", "parallel", "final", "history"}
_ACTIONS = {"raise", "send", "cancel", "log"}
_NEEDS_DATAMODEL = {"script", "assign", "if", "elseif", "else", "foreach", "datamodel", "data",
                    "donedata", "param", "content", "finalize"}
_SCXML_TYPES = ("", "scxml", "http://www.w3.org/TR/scxml/", "http://www.w3.org/TR/scxml")


@dataclass
class Element:
    """An XML element as read: local tag name, attributes and where it starts."""

    tag: str
    attrs: dict[str, str]
    line: int
    col: int
    children: list[Element] = field(default_factory=list)
    text: str = ""


def import_scxml(path: str | os.PathLike[str]) -> str:
    """The scheme YAML equivalent to an SCXML file; :class:`FileError` for what cannot be."""
    name = os.fspath(path)
    budget = [MAX_ELEMENTS]
    root = parse_xml(read_text(name), name, budget)
    out, pruned = _Translator(name, (os.path.realpath(name),), budget).scheme(root)
    text = dump(out)
    if pruned:
        text = f"# Left out, since no run can ever enter them: {', '.join(pruned)}\n" + text
    return text


def parse_xml(text: str, file: str, budget: list[int], root: str = "scxml") -> Element:
    """The element tree of an XML text whose top is ``<root>`` (SCXML's by default).

    ``budget`` counts down the elements left.
    """
    parser = xml.parsers.expat.ParserCreate(namespace_separator=" ")
    stack: list[Element] = []
    top: list[Element] = []

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
        element = Element(local, {k.split(" ")[-1]: v for k, v in attrs.items()},
                           parser.CurrentLineNumber, parser.CurrentColumnNumber + 1)
        (stack[-1].children if stack else top).append(element)
        stack.append(element)

    def end(tag: str) -> None:
        stack.pop()

    def characters(data: str) -> None:
        if stack:
            stack[-1].text += data

    parser.StartElementHandler = start
    parser.CharacterDataHandler = characters
    parser.EndElementHandler = end
    parser.StartDoctypeDeclHandler = lambda *a: refuse("DOCTYPE declarations are not accepted")
    parser.EntityDeclHandler = lambda *a: refuse("entity declarations are not accepted")
    try:
        parser.Parse(text, True)
    except xml.parsers.expat.ExpatError as err:
        raise FileError([Problem(file, err.lineno, err.offset + 1,
                                 f"XML syntax: {xml.parsers.expat.errors.messages[err.code]}")]
                        ) from None
    if not top or top[0].tag != root:
        what = "an SCXML document" if root == "scxml" else f"a <{root}> document"
        raise FileError([Problem(file, 1, 1, f"not {what} (no <{root}> root)")])
    return top[0]


class _Translator:
    def __init__(self, file: str, chain: tuple[str, ...], budget: list[int]):
        self.file = file
        self.chain = chain
        self.budget = budget
        self.problems: list[Problem] = []
        self.generated = 0
        self.datamodel = False
        """Whether the chart has a data model whose expressions are imported."""
        self.data: dict[str, Any] = {}
        self.reads: list[tuple[frozenset[str], Element]] = []
        """The variables each expression reads, and its element (checked at the end)."""
        self.declared: set[str] = set()
        """Variables a foreach declares (its item and index)."""
        self.assigned: dict[str, None] = {}
        """Variables assigned to: those the chart does not declare are declared unbound, as
        an assignment in ECMAScript creates the variable it names."""

    def refuse(self, element: Element, message: str) -> None:
        self.problems.append(Problem(self.file, element.line, element.col, message))

    def scheme(self, root: Element) -> tuple[dict[str, Any], list[str]]:
        """The scheme of an ``<scxml>`` element, and the unreachable states left out."""
        if root.attrs.get("datamodel", "") not in ("", "null", "ecmascript",
                                                   *scxml_data.DATAMODELS):
            self.refuse(root, f"datamodel={root.attrs['datamodel']!r} is not supported")
        if root.attrs.get("binding", "") not in ("", "early", "late"):
            self.refuse(root, f"binding={root.attrs['binding']!r} is not supported")
        self.datamodel = root.attrs.get("datamodel", "") in scxml_data.DATAMODELS
        self.late = False
        """Late binding: a state's <datamodel> is set when the state is first entered."""
        if root.attrs.get("binding") == "late":
            if self.datamodel:
                self.late = True
            else:
                self.refuse(root, "binding='late' is only for a chart with a data model")
        name = root.attrs.get("name") or os.path.splitext(os.path.basename(self.file))[0]
        states = self.children(root)
        out: dict[str, Any] = {"scheme": _safe_name(name),
                               "doc": f"Imported from {os.path.basename(self.file)}."}
        initial = root.attrs.get("initial", "").split()
        if initial:
            out["initial"] = initial[0] if len(initial) == 1 else initial
        elif states:
            out["initial"] = next(iter(states))
        for name in self.assigned:
            if name not in self.declared:
                self.data.setdefault(name, None)
        if self.datamodel:
            scxml_data.check_names(self, self.declared | set(self.data))
        if self.data:
            out["data"] = self.data
        if self.late:
            out["binding"] = "late"
        out["states"] = states
        if self.problems:
            raise FileError(self.problems)
        return out, _prune_unreachable(out, self.file)

    def children(self, element: Element) -> dict[str, Any]:
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
            elif child.tag == "datamodel" and self.datamodel:
                if not (self.late and element.tag != "scxml"):
                    scxml_data.data(self, child, self.data)
            elif child.tag == "donedata" and self.datamodel and element.tag == "final":
                continue
            elif child.tag in _NEEDS_DATAMODEL:
                self.refuse(child, f"<{child.tag}> {_needs(child.tag)}")
            elif child.tag not in ("initial", "transition", "onentry", "onexit", "invoke"):
                self.refuse(child, f"<{child.tag}> is not supported")
        return states

    def state(self, element: Element) -> dict[str, Any]:
        spec: dict[str, Any] = {}
        if element.tag == "final":
            spec["final"] = True
            done = scxml_data.donedata(self, element) if self.datamodel else None
            if done is not None:
                spec["donedata"] = done
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
            blocks = [self.actions(c) for c in element.children if c.tag == kind]
            if self.datamodel and len(blocks) > 1:  # an error ends only its own handler
                blocks = [[{"block": b}] for b in blocks if b]
            actions = [a for b in blocks for a in b]
            if actions:
                spec["on_entry" if kind == "onentry" else "on_exit"] = actions
        if self.late:
            own: dict[str, Any] = {}
            for child in element.children:
                if child.tag == "datamodel":
                    scxml_data.data(self, child, own)
            if own:
                spec["data"] = own
                self.declared.update(own)
        on = self.transitions(element)
        if on:
            spec["on"] = on
        invokes = [self.invoke(c) for c in element.children if c.tag == "invoke"]
        if invokes:
            spec["invoke"] = invokes[0] if len(invokes) == 1 else invokes
        if children:
            spec["states"] = children
        return spec or None  # type: ignore[return-value]

    def initial(self, transition: Element) -> Any:
        """The targets of an ``<initial>`` or history default transition, with its actions."""
        targets = _one_or_list(transition.attrs.get("target", "").split())
        actions = self.actions(transition)
        return {"target": targets, "do": actions} if actions else targets

    def invoke(self, element: Element) -> dict[str, Any]:
        """An ``<invoke>`` of another SCXML chart, its child written inline."""
        out: dict[str, Any] = {}
        for attr, value in element.attrs.items():
            if attr in ("typeexpr", "idlocation") and self.datamodel:
                out[attr] = scxml_data.check(self, element, value, location=attr == "idlocation")
            elif attr == "namelist" and self.datamodel:
                out[attr] = [scxml_data.check(self, element, name, location=True)
                             for name in value.split()]
            elif attr in ("typeexpr", "srcexpr", "idlocation", "namelist"):
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
            if self.datamodel and c.tag == "finalize" and c.children:
                out["finalize"] = self.actions(c)
            elif self.datamodel and c.tag == "param":
                continue
            elif c.tag != "content" and not (c.tag == "finalize" and not c.children):
                self.refuse(c, f"<{c.tag}> in <invoke> needs a data model")
        if self.datamodel and scxml_data.params(self, element):
            out["params"] = scxml_data.params(self, element)
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

    def src(self, element: Element, src: str) -> dict[str, Any] | None:
        """The chart an ``<invoke src>`` names: a file below this chart's folder.

        ``src`` is a URI: a relative path or a ``file:`` URI without host
        (``file:child.scxml``) resolves against the including chart's folder,
        within the same confinement; other schemes (``http:`` …) are refused.
        """
        parts = urlsplit(src)
        if parts.scheme == "file" and not (parts.netloc or parts.query or parts.fragment):
            src = unquote(parts.path)
        elif len(parts.scheme) > 1:  # (one letter is a drive, which confine refuses)
            self.refuse(element, f"<invoke src={src!r}>: only a relative path or a file: URI "
                        "naming a chart below this chart's folder can be invoked")
            return None
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
            root = parse_xml(read_text(shown), shown, self.budget)
        except FileError as err:
            self.problems.extend(err.problems)
            return None
        return self.child(root, shown, self.chain + (path,))

    def child(self, root: Element, file: str, chain: tuple[str, ...]) -> dict[str, Any] | None:
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

    def transitions(self, element: Element) -> dict[str, Any]:
        taken = Coverage()
        on: dict[str, Any] = {}
        for t in (c for c in element.children if c.tag == "transition"):
            guard = None
            cond = None
            if "cond" in t.attrs:
                guard = _in_state(t.attrs["cond"])
                if guard is None and self.datamodel:
                    cond = scxml_data.check(self, t, t.attrs["cond"])
                    if cond is None:
                        continue
                elif guard is None:
                    self.refuse(t, "cond= needs a data model (only In('STATE') does not): "
                                "datamodel=\"shary\" on <scxml>, or a scheme guard naming a "
                                "registered condition")
                    continue
            for attr in t.attrs:
                if attr not in ("event", "target", "type", "cond"):
                    self.refuse(t, f"transition attribute {attr!r} is not supported")
            events = tuple("*" if d == ".*" else d for d in t.attrs["event"].split()) \
                if "event" in t.attrs else None
            if taken.covering(events) is not None:
                continue  # an earlier transition takes all its events: it is never taken
            if guard is None and cond is None:
                taken.add(events, t)
            targets = t.attrs.get("target", "").split()
            actions = self.actions(t)
            body: dict[str, Any] = {}
            if len(targets) != 1 or actions or t.attrs.get("type") == "internal" or guard \
                    or cond is not None:
                body["target"] = _one_or_list(targets) if targets else None
                if guard:
                    body["guard"] = guard
                if cond is not None:
                    body["cond"] = cond
                if t.attrs.get("type") == "internal" and targets:
                    body["type"] = "internal"
                if actions:
                    body["do"] = actions
                value: Any = body
            else:
                value = _one_or_list(targets)
            key = " ".join(events) if events is not None else "always"
            while key in on and key != next(reversed(on)):
                # transitions on other events came between: a mapping cannot say that
                # order with the same key twice, so the key repeats its first descriptor
                # (same events, another key)
                key = f"{key} {key.split()[0]}" if key != "always" else key
                if key == "always":
                    break
            if key in on:  # a guarded transition before it: the scheme lists both
                on[key] = (on[key] if isinstance(on[key], list) else [on[key]]) + [value]
            else:
                on[key] = value
        return on

    def actions(self, element: Element) -> list[dict[str, Any]]:
        out: list[dict[str, Any]] = []
        for a in element.children:
            if self.datamodel and a.tag in ("assign", "if", "foreach", "script"):
                found = scxml_data.action(self, a)
                if found is not None:
                    out.append(found)
            elif a.tag in _NEEDS_DATAMODEL:
                self.refuse(a, f"<{a.tag}> {_needs(a.tag)}")
            elif a.tag not in _ACTIONS:
                self.refuse(a, f"<{a.tag}> is not supported in executable content")
            elif a.tag == "raise":
                out.append({"raise": a.attrs.get("event", "")})
            elif a.tag == "send":
                out.append(self.send(a))
            elif a.tag == "cancel" and self.datamodel and "sendidexpr" in a.attrs:
                out.append({"cancel": None,
                            "sendidexpr": scxml_data.check(self, a, a.attrs["sendidexpr"])})
            elif a.tag == "log" and self.datamodel and "expr" in a.attrs:
                out.append({"log": a.attrs.get("label", ""),
                            "expr": scxml_data.check(self, a, a.attrs["expr"])})
            elif a.tag == "cancel":
                if "sendid" not in a.attrs:
                    self.refuse(a, "<cancel> needs sendid= (sendidexpr needs a data model)")
                out.append({"cancel": a.attrs.get("sendid", "")})
            else:
                if "expr" in a.attrs:
                    self.refuse(a, "<log expr> needs a data model; use label=")
                out.append({"log": a.attrs.get("label", "")})
        return out

    def send(self, a: Element) -> dict[str, Any]:
        if self.datamodel:
            return self.send_data(a)
        for attr in a.attrs:
            if attr not in ("event", "delay", "id", "target", "type"):
                self.refuse(a, f"<send {attr}=…> is not supported (it needs a data model)")
        target = a.attrs.get("target", "")
        to = None
        if target == "#_parent":
            to = PARENT
        elif target.startswith("#_") and target != "#_internal":
            to = target[2:]
            if not _NAME.match(to) or to == PARENT:
                self.refuse(a, f"<send target={target!r}>: {to!r} cannot be an invoke id")
        elif target not in ("", "#_internal"):
            self.refuse(a, f"<send target={target!r}>: a chart sends to itself, to "
                        "'#_parent' or to a child by '#_INVOKEID', nowhere else")
        if a.attrs.get("type", "") not in ("", "scxml", "http://www.w3.org/TR/scxml/",
                                           "http://www.w3.org/TR/scxml/#SCXMLEventProcessor"):
            self.refuse(a, f"<send type={a.attrs['type']!r}>: only SCXML's own event "
                        "processor is supported")
        if a.children:
            self.refuse(a, "<send> with <param> or <content> needs a data model")
        if "event" not in a.attrs:
            self.refuse(a, "<send> needs event=")
        if a.attrs.get("target") == "#_internal":
            return {"raise": a.attrs.get("event", "")}
        out: dict[str, Any] = {"send": a.attrs.get("event", "")}
        if "delay" in a.attrs:
            self.delay(a, out)
        if "id" in a.attrs:
            out["id"] = a.attrs["id"]
        if to is not None:
            out["to"] = to
        return out

    def delay(self, a: Element, out: dict[str, Any]) -> None:
        """A ``<send>``'s ``delay`` in the scheme's spelling (``.5s`` -> ``0.5s``), or
        refused when it is not a time."""
        match = _TIME.match(a.attrs["delay"])
        if not match:
            self.refuse(a, f"delay {a.attrs['delay']!r} is not a time (write 10ms or 1.5s)")
            return
        number = match.group(1)
        out["delay"] = (("0" + number) if number.startswith(".") else number) + match.group(2)

    def send_data(self, a: Element) -> dict[str, Any]:
        """A ``<send>`` of a chart with a data model: every part may be computed, and the
        target is found when it runs (a wrong one is ``error.execution`` then, as SCXML says)."""
        if "event" not in a.attrs and "eventexpr" not in a.attrs:
            self.refuse(a, "<send> needs event= or eventexpr=")
        out: dict[str, Any] = {"send": a.attrs.get("event")}
        if "delay" in a.attrs:
            self.delay(a, out)
        for attr in ("id", "target", "type"):
            if a.attrs.get(attr):
                out[attr] = a.attrs[attr]
        scxml_data.send(self, a, out)
        return out


def _prune_unreachable(document: dict[str, Any], file: str) -> list[str]:
    """Remove the states no run can enter (schemes refuse them); return their names."""
    scheme = parse_scheme(Located(file, document), check_reachable=False)
    never = unreachable(scheme, histories=True)
    dead = {s.name for s in never if s.history is None}
    # a history no transition targets stays, unless its default is among the dead
    dead.update(s.name for s in never if s.history is not None and dead & set(s.default))

    def prune(states: dict[str, Any]) -> None:
        for name in [n for n in states if n in dead]:
            del states[name]
        for spec in states.values():
            if isinstance(spec, dict) and isinstance(spec.get("on"), dict):
                _drop_never_true(spec["on"], {f"in {n}" for n in dead})
            if isinstance(spec, dict) and isinstance(spec.get("states"), dict):
                prune(spec["states"])

    prune(document["states"])
    return sorted(dead, key=lambda n: scheme.states[n].order)


def _drop_never_true(on: dict[str, Any], never: set[str]) -> None:
    """Remove the transitions guarded ``in S`` for a state S no run enters: never taken."""
    for key in list(on):
        items = on[key] if isinstance(on[key], list) else [on[key]]
        kept = [t for t in items if not (isinstance(t, dict) and t.get("guard") in never)]
        if not kept:
            del on[key]
        elif len(kept) != len(items):
            on[key] = kept[0] if len(kept) == 1 else kept


def _in_state(cond: str) -> str | None:
    """The guard of a ``cond`` the null data model has: ``In('S')`` is ``in S``; else None."""
    match = _IN.match(cond)
    return None if match is None else f"in {match.group(2)}"


def _needs(tag: str) -> str:
    """Why an element of the data model is refused in a chart without one."""
    if tag == "script":
        return "needs a data model with scripts; shary's has expressions only, no scripts"
    return "needs a data model: datamodel=\"shary\" on <scxml> (see docs/conformance.md)"


def _one_or_list(items: list[str]) -> Any:
    """A name for one target, a list for several (as schemes write them)."""
    return items[0] if len(items) == 1 else list(items)


def _safe_name(name: str) -> str:
    safe = re.sub(r"[^A-Za-z0-9_.:-]", "-", name)
    return safe if _NAME.match(safe) else f"chart-{safe}"
