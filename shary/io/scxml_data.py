"""Importing the data model of an SCXML chart: ``<datamodel>``, ``cond``, ``<assign>`` …

A chart whose ``datamodel`` is ``shary`` (or ``python``: shary's expressions
are a subset of Python's, with the same meaning) has its expressions carried
over as they are: ``<data>`` into the scheme's ``data:``
(all of them, wherever declared, since SCXML binds them all when the chart
starts), ``cond`` into a transition's ``cond``, and the executable content
of the data model into the scheme's actions of the same meaning.  The scheme
loader then compiles and checks every expression (:mod:`shary.io.scheme_data`),
so an expression the language does not have is refused with its position.
"""

from __future__ import annotations

import re
from dataclasses import replace
from typing import TYPE_CHECKING, Any

from shary.statechart.expressions import (
    SYSTEM_VARIABLES,
    ExpressionError,
    compile_expression,
    compile_location,
)
from userfiles.schema import did_you_mean

if TYPE_CHECKING:
    from shary.io.scxml import Element, _Translator

DATAMODELS = ("shary", "python")
"""``datamodel=`` values whose expressions are imported.  ECMAScript is not among them:
some of its expressions parse as Python's with another meaning (``++x`` is ``x + 1``
there and ``x`` here, ``1 == '1'`` is true there), so a chart written for it is refused
where it needs a data model rather than run with other answers."""
_ROOT = re.compile(r"^\s*[A-Za-z][A-Za-z0-9_]*")
_SEND_EXPRS = {"eventexpr": "eventexpr", "targetexpr": "targetexpr", "typeexpr": "typeexpr",
               "delayexpr": "delayexpr", "idlocation": "idlocation"}


def text_value(text: str) -> str:
    """An element's text as an expression: itself if it is a constant expression (``123``,
    ``[1, 2, 3]``), else the text as a string."""
    text = text.strip()
    try:
        if text and not compile_expression(text).names:
            return text
    except ExpressionError:
        pass
    return repr(" ".join(text.split()))


def check(translator: _Translator, element: Element, text: str | None,
          location: bool = False) -> str | None:
    """``text`` if it compiles as an expression (or a location), else None, refused at the
    element; the variables it reads are kept to be checked once all are declared."""
    if text is None:
        return None
    try:
        compiled = compile_location(text) if location else compile_expression(text)
    except ExpressionError as err:
        translator.refuse(element, err.message)
        return None
    translator.reads.append((compiled.names, element))
    return text


def check_names(translator: _Translator, declared: set[str]) -> None:
    """Refuse, at their elements, the expressions that read variables the chart never declares."""
    known = declared | set(SYSTEM_VARIABLES)
    for names, element in translator.reads:
        for name in sorted(names - known):
            translator.refuse(element, f"unknown variable {name!r}{did_you_mean(name, known)}; "
                              "declare it with <data>")


def data(translator: _Translator, element: Element, out: dict[str, Any]) -> None:
    """The ``<data>`` of a ``<datamodel>``, added to ``out``."""
    for item in element.children:
        if item.tag != "data":
            translator.refuse(item, f"<{item.tag}> in <datamodel>: only <data> belongs there")
            continue
        ident = item.attrs.get("id", "")
        if "src" in item.attrs:
            translator.refuse(item, "<data src=…>: data is written in the chart, never fetched")
        elif "expr" in item.attrs:
            out[ident] = check(translator, item, item.attrs["expr"])
        elif item.text.strip() or item.children:
            out[ident] = text_value(item.text) if not item.children else None
        else:
            out[ident] = None


def action(translator: _Translator, a: Element) -> dict[str, Any] | None:
    """An action of the data model, or None after refusing it."""
    if a.tag == "assign":
        if "location" not in a.attrs:
            translator.refuse(a, "<assign> needs location=")
            return None
        expr = a.attrs.get("expr")
        root = _ROOT.match(a.attrs["location"])
        if root is not None and not root.group(0).startswith("_"):
            translator.assigned.setdefault(root.group(0))
        return {"assign": check(translator, a, a.attrs["location"], location=True),
                "expr": check(translator, a, expr) if expr is not None else text_value(a.text)}
    if a.tag == "if":
        return _if(translator, a)
    if a.tag == "foreach":
        out: dict[str, Any] = {"foreach": check(translator, a, a.attrs.get("array", "")),
                               "item": a.attrs.get("item", "")}
        translator.declared.add(a.attrs.get("item", ""))
        if "index" in a.attrs:
            out["index"] = a.attrs["index"]
            translator.declared.add(a.attrs["index"])
        out["do"] = translator.actions(a)
        return out
    translator.refuse(a, f"<{a.tag}> is not supported: expressions are shary's, not a script")
    return None


def _if(translator: _Translator, a: Element) -> dict[str, Any]:
    branches: list[tuple[str | None, list]] = [(check(translator, a, a.attrs.get("cond", "False")),
                                                 [])]
    for child in a.children:
        if child.tag == "elseif":
            branches.append((check(translator, child, child.attrs.get("cond", "False")), []))
        elif child.tag == "else":
            branches.append((None, []))
        else:
            branches[-1][1].append(child)
    out: dict[str, Any] = {"if": branches[0][0], "then": _content(translator, a,
                                                                  branches[0][1])}
    for cond, children in branches[1:]:
        actions = _content(translator, a, children)
        if cond is None:
            out["else"] = actions
            break
        out.setdefault("elif", []).append({"if": cond, "then": actions})
    return out


def _content(translator: _Translator, parent: Element, children: list) -> list:
    return translator.actions(replace(parent, attrs={}, children=children))


def params(translator: _Translator, element: Element) -> dict[str, Any]:
    """``<param name expr|location>`` children as named expressions."""
    out: dict[str, Any] = {}
    for p in element.children:
        if p.tag == "param":
            value = p.attrs.get("expr", p.attrs.get("location"))
            if "name" not in p.attrs or value is None:
                translator.refuse(p, "<param> needs name= and expr= or location=")
            else:
                out[p.attrs["name"]] = check(translator, p, value)
    return out


def content(translator: _Translator, element: Element) -> str | None:
    """The value of a ``<content>`` child (its expr, or its text), if any."""
    for c in element.children:
        if c.tag == "content":
            if "expr" in c.attrs:
                return check(translator, c, c.attrs["expr"])
            if c.children:
                translator.refuse(c, "<content> holding markup is only an invoked chart")
                return None
            return text_value(c.text)
    return None


def send(translator: _Translator, a: Element, out: dict[str, Any]) -> None:
    """The data-model parts of a ``<send>`` added to ``out``."""
    for attr, key in _SEND_EXPRS.items():
        if attr in a.attrs:
            out[key] = check(translator, a, a.attrs[attr], location=attr == "idlocation")
    if "eventexpr" in a.attrs and "event" not in a.attrs:
        out["send"] = None
    if "namelist" in a.attrs:
        out["namelist"] = a.attrs["namelist"].split()
    found = params(translator, a)
    if found:
        out["params"] = found
    value = content(translator, a)
    if value is not None:
        out["content"] = value


def donedata(translator: _Translator, element: Element) -> dict[str, Any] | None:
    for d in element.children:
        if d.tag == "donedata":
            value = content(translator, d)
            return {"content": value} if value is not None else \
                {"params": params(translator, d)}
    return None
