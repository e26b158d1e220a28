"""The W3C SCXML implementation report's tests, translated to shary's data model.

The W3C's IRP (https://www.w3.org/Voice/2013/scxml-irp/) writes its tests
once, data-model-agnostic, in ``.txml`` files whose ``conf:`` attributes and
elements each implementation's stylesheet turns into its own data model
(``conf:targetpass`` into ``target="pass"``, ``conf:expr`` into an
ECMAScript expression …).  ``manifest.xml`` says which tests are mandatory
or optional, and which need a person to judge them.

Here the translation is shary's own, as ``confEcma.xsl`` is ECMAScript's:
:data:`_ATTRIBUTES` and :data:`_ELEMENTS` give each ``conf:`` construct its
SCXML attribute or element with an expression in shary's language
(:mod:`shary.statechart.expressions`), and a test using a construct they do
not know is refused with it named.  The translated charts then run as every
plain chart does (:func:`shary.statechart.conformance.run_test`: they pass by
reaching ``pass``).
"""

from __future__ import annotations

import re
import tempfile
from collections.abc import Callable, Iterator
from pathlib import Path

from shary.io.scxml import parse_xml
from shary.statechart.conformance import REFUSED, Outcome, run_test
from shary.statechart.datamodel import SCXML_PROCESSOR
from userfiles.errors import FileError
from userfiles.yamlsafe import read_text

MANIFEST = "manifest.xml"
MAX_MANIFEST_ELEMENTS = 10_000
"""Most XML elements a manifest may have (the IRP's has about 1,300)."""

_CONF_ATTR = re.compile(r'\bconf:([A-Za-z0-9_]+)="([^"]*)"')
_CONF_ELEMENT = re.compile(r"<conf:([A-Za-z0-9_]+)((?:\s+[A-Za-z0-9_]+=\"[^\"]*\")*)\s*/>")
_CONF_NS = re.compile(r'\s+xmlns:conf="[^"]*"')
_COMPARISON = re.compile(r"^\s*([0-9]+)\s*([=<>]=?)\s*(.*?)\s*$")
_CONF = re.compile(r"\bconf:([A-Za-z_][\w.-]*)")
_COMMENT = re.compile(r"<!--.*?-->", re.S)
_TOP_SCRIPT = re.compile(r"(<scxml\b[^>]*>\s*)<conf:script\s*/>")
"""A script at the top of a test declares ``Var1 = 1`` when the chart is loaded: shary has no
scripts, and says it with a variable (below, in executable content, it is an assignment)."""
FAILING = "1 / 0"
"""What stands for an illegal expression: one that compiles (so the chart loads) and fails
when evaluated, which is when SCXML raises ``error.execution``."""


def _op(op: str) -> str:
    return "==" if op == "=" else op


def _compare(value: str, left: str = "Var{}", right: str = "{}") -> str:
    """``N=V`` (or ``<``, ``>=`` …) as ``VarN == V``."""
    match = _COMPARISON.match(value)
    if match is None:
        return FAILING
    number, op, rest = match.groups()
    return f"{left.format(number)} {_op(op)} {right.format(rest)}"


_ATTRIBUTES: dict[str, Callable[[str], tuple[str, str]]] = {
    "targetpass": lambda v: ("target", "pass"),
    "targetfail": lambda v: ("target", "fail"),
    "datamodel": lambda v: ("datamodel", "shary"),
    "id": lambda v: ("id", f"Var{v}"),
    "name": lambda v: ("name", f"Var{v}"),
    "location": lambda v: ("location", f"Var{v}"),
    "invalidLocation": lambda v: ("location", "_x.bar.baz"),
    "systemVarLocation": lambda v: ("location", v),
    "expr": lambda v: ("expr", v or "None"),
    "targetVar": lambda v: ("targetexpr", f"Var{v}"),
    "quoteExpr": lambda v: ("expr", repr(v)),
    "varExpr": lambda v: ("expr", f"Var{v}"),
    "varChildExpr": lambda v: ("expr", f"Var{v}"),
    "systemVarExpr": lambda v: ("expr", v),
    "varNonexistentStruct": lambda v: ("expr", f"Var{v}.bar"),
    "illegalExpr": lambda v: ("expr", FAILING),
    "illegalTarget": lambda v: ("target", "baz"),
    "unreachableTarget": lambda v: ("target", "#_scxml_foo"),
    "invalidSessionID": lambda v: ("expr", "27"),
    "invalidSendType": lambda v: ("type", "27"),
    "invalidSendTypeExpr": lambda v: ("expr", "27"),
    "eventName": lambda v: ("expr", "_event.name"),
    "eventType": lambda v: ("expr", "_event.type"),
    "eventSendid": lambda v: ("expr", "_event.sendid"),
    "eventField": lambda v: ("expr", f"_event.{v}"),
    "eventDataFieldValue": lambda v: ("expr", f"_event.data.{v}"),
    "eventDataParamValue": lambda v: ("expr", f"_event.data.{v}"),
    "eventDataNamelistValue": lambda v: ("expr", f"_event.data.Var{v}"),
    "scxmlEventIOLocation": lambda v: ("expr", f"_ioprocessors[{SCXML_PROCESSOR!r}].location"),
    "eventExpr": lambda v: ("eventexpr", f"Var{v}"),
    "targetExpr": lambda v: ("targetexpr", f"Var{v}"),
    "typeExpr": lambda v: ("typeexpr", f"Var{v}"),
    "delayFromVar": lambda v: ("delayexpr", f"Var{v}"),
    "delay": lambda v: ("delayexpr", repr(f"{v}s")),
    "idlocation": lambda v: ("idlocation", f"Var{v}"),
    "sendIDExpr": lambda v: ("sendidexpr", f"Var{v}"),
    "namelist": lambda v: ("namelist", f"Var{v}"),
    "invalidNamelist": lambda v: ("namelist", "_x.foo"),
    "idVal": lambda v: ("cond", _compare(v)),
    "varIdVal": lambda v: ("cond", _compare(v)),
    "namelistIdVal": lambda v: ("cond", _compare(v)),
    "idQuoteVal": lambda v: ("cond", _compare(v, right="{!r}")),
    "compareIDVal": lambda v: ("cond", _compare(v, right="Var{}")),
    "idSomeVal": lambda v: ("cond", f"Var{v} == 123"),
    "VarEqVar": lambda v: ("cond", " == ".join(f"Var{n}" for n in re.findall(r"[0-9]+", v))),
    "VarEqVarStruct": lambda v: ("cond", " == ".join(f"Var{n}"
                                                     for n in re.findall(r"[0-9]+", v))),
    "eventNameVal": lambda v: ("cond", f"_event.name == {v!r}"),
    "eventvarVal": lambda v: ("cond", _compare(v, left="_event.data['Var{}']")),
    "idSystemVarVal": lambda v: ("cond", _compare(v)),
    "eventdataVal": lambda v: ("cond", f"_event.data == {v}"),
    "eventdataSomeVal": lambda v: ("cond", "_event.data == 123"),
    "emptyEventData": lambda v: ("cond", "_event.data is None"),
    "nameVarVal": lambda v: ("cond", f"_name == {v!r}"),
    "varPrefix": lambda v: ("cond", "Var{1}[:len(Var{0})] == Var{0}".format(*v.split()[::-1])
                            if len(v.split()) == 2 else FAILING),
    "inState": lambda v: ("cond", f"In({v!r})"),
    "nonBoolean": lambda v: ("cond", FAILING),
    "isBound": lambda v: ("cond", f"bound('Var{v}')"),
    "unboundVar": lambda v: ("cond", f"not bound('Var{v}')"),
    "systemVarIsBound": lambda v: ("cond", f"{v} is not None"),
    "noValue": lambda v: ("cond", f"not Var{v}"),
    "true": lambda v: ("cond", "True"),
    "false": lambda v: ("cond", "False"),
    "eventFieldsAreBound": lambda v: ("cond", " and ".join(
        f"{f!r} in _event" for f in ("name", "type", "sendid", "origin", "origintype",
                                     "invokeid", "data"))),
    "eventDataHasField": lambda v: ("cond", f"{v!r} in _event.data"),
    "eventFieldHasNoValue": lambda v: ("cond", f"_event.{v} is None"),
    "originTypeEq": lambda v: ("cond", f"_event.origintype == {v!r}"),
    "arrayVar": lambda v: ("array", f"Var{v}"),
    "arrayTextVar": lambda v: ("array", f"Var{v}"),
    "illegalArray": lambda v: ("array", "7"),
    "item": lambda v: ("item", f"Var{v}"),
    "illegalItem": lambda v: ("item", "_x.item"),
    "index": lambda v: ("index", f"Var{v}"),
}
"""shary's translation of the IRP's ``conf:`` attributes, as ``confEcma.xsl`` is ECMAScript's:
each gives the SCXML attribute and its value in shary's expression language."""

_ELEMENTS: dict[str, Callable[[dict[str, str]], str]] = {
    "pass": lambda a: '<final id="pass"/>',
    "fail": lambda a: '<final id="fail"/>',
    "incrementID": lambda a: _assign(f"Var{a['id']}", f"Var{a['id']} + 1"),
    "concatVars": lambda a: _assign(f"Var{a['id1']}", f"Var{a['id1']} + Var{a['id2']}"),
    "sumVars": lambda a: _assign(f"Var{a['id1']}", f"Var{a['id1']} + Var{a['id2']}"),
    "extendArray": lambda a: _assign(f"Var{a['id']}", f"Var{a['id']} + [4]"),
    "script": lambda a: _assign("Var1", "1"),
    "array123": lambda a: "[1, 2, 3]",
    "someInlineVal": lambda a: "123",
    "contentFoo": lambda a: "<content>foo</content>",
    "illegalContent": lambda a: "<content> xyz </content>",
    "sendToSender": lambda a: f'<send event="{_xml(a["name"])}" targetexpr="_event.origin" '
                              'typeexpr="_event.origintype"/>',
}
"""shary's translation of the IRP's ``conf:`` elements."""


def _xml(value: str) -> str:
    return value.replace("&", "&amp;").replace("<", "&lt;").replace(">", "&gt;") \
        .replace('"', "&quot;")


def _assign(location: str, expr: str) -> str:
    return f'<assign location="{location}" expr="{_xml(expr)}"/>'


def _unescape(value: str) -> str:
    return value.replace("&lt;", "<").replace("&gt;", ">").replace("&quot;", '"') \
        .replace("&apos;", "'").replace("&amp;", "&")


def is_irp(folder: Path) -> bool:
    """True when ``folder`` holds the IRP's ``manifest.xml``."""
    return (folder / MANIFEST).is_file()


def irp_tests(folder: Path, conformance: str = "mandatory") -> list[Path]:
    """The automated tests the manifest lists as ``conformance`` (``mandatory`` or
    ``optional``), as ``.txml`` files under ``folder``.

    The manifest names them ``355/test355.txml`` (the W3C's layout); copies
    that keep them elsewhere under the folder (``txml/test355.txml``) are
    found by name.  :class:`FileError` for a broken manifest.
    """
    manifest = folder / MANIFEST
    root = parse_xml(read_text(manifest), str(manifest), [MAX_MANIFEST_ELEMENTS],
                     root="assertions")
    by_name = {p.name: p for p in sorted(folder.rglob("*.txml"))}
    tests: list[Path] = []
    for test in _walk(root, "test"):
        if test.attrs.get("conformance") != conformance or test.attrs.get("manual") != "false":
            continue
        for start in (c for c in test.children if c.tag == "start"):
            uri = start.attrs.get("uri", "")
            found = folder / uri if (folder / uri).is_file() else by_name.get(Path(uri).name)
            if found is not None and found not in tests:
                tests.append(found)
    return tests


def _walk(element, tag: str) -> Iterator:
    for child in element.children:
        if child.tag == tag:
            yield child
        yield from _walk(child, tag)


def translate(text: str) -> tuple[str, list[str]]:
    """A ``.txml`` test in the null data model, and the ``conf:`` constructs that need another.

    When the second list is not empty the first is of no use.
    """
    text = _COMMENT.sub("", text)

    def attribute(match: re.Match) -> str:
        rule = _ATTRIBUTES.get(match.group(1))
        if rule is None:
            return match.group(0)
        name, value = rule(_unescape(match.group(2)))
        return f'{name}="{_xml(value)}"'

    def element(match: re.Match) -> str:
        rule = _ELEMENTS.get(match.group(1))
        if rule is None:
            return match.group(0)
        attrs = {k: _unescape(v) for k, v in re.findall(r'([A-Za-z0-9_]+)="([^"]*)"',
                                                         match.group(2))}
        return rule(attrs)
    text = _TOP_SCRIPT.sub(r'\1<datamodel><data id="Var1" expr="1"/></datamodel>', text)
    text = _CONF_NS.sub("", _CONF_ELEMENT.sub(element, _CONF_ATTR.sub(attribute, text)))
    left = sorted(set(_CONF.findall(text)))
    return text, [f"conf:{name}" for name in left]


def run_irp(folder: Path, tests: list[Path]) -> Iterator[Outcome]:
    """Run the given ``.txml`` tests of an IRP ``folder`` (see :func:`irp_tests`).

    Every ``.txml`` beside a test is translated too, into a temporary
    folder, as ``NAME.scxml``: that is the name the tests' ``<invoke
    src="file:…">`` give their sub-charts.
    """
    with tempfile.TemporaryDirectory(prefix="shary-w3c-") as tmp:
        out = Path(tmp)
        refused: dict[Path, str] = {}
        for source in sorted({p for t in tests for p in t.parent.glob("*.txml")}):
            try:
                text, left = translate(read_text(source))
            except FileError as err:
                refused[source] = f"refused: {err.problems[0].message}"
                continue
            if left:
                refused[source] = f"refused: not translated to shary's data model: " \
                    f"{', '.join(left)}"
            else:
                (out / f"{source.stem}.scxml").write_text(text, encoding="utf-8")
        for test in tests:
            name = str(test.relative_to(folder))
            if test in refused:
                yield Outcome(name, False, refused[test], REFUSED)
                continue
            outcome = run_test(out / f"{test.stem}.scxml")
            yield Outcome(name, outcome.passed, outcome.reason, outcome.kind)
