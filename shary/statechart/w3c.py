"""The W3C SCXML implementation report's tests, run on the null data model.

The W3C's IRP (https://www.w3.org/Voice/2013/scxml-irp/) writes its tests
once, data-model-agnostic, in ``.txml`` files whose ``conf:`` attributes and
elements each implementation's stylesheet turns into its own data model
(``conf:targetpass`` into ``target="pass"``, ``conf:expr`` into an
ECMAScript expression …).  ``manifest.xml`` says which tests are mandatory
and which need a person to judge them.

Here the translation is the null data model's: the constructs that need no
data model (``conf:targetpass``/``targetfail``, ``conf:pass``/``fail``,
``conf:datamodel``, ``conf:delay``, a fixed number of seconds, and
``conf:inState``, the null data model's ``In()``) are rewritten, and a test
using any other ``conf:`` construct is refused with those constructs named,
as a chart with ``cond`` or ``<script>`` is.  The
translated charts then run as every plain chart does
(:func:`shary.statechart.conformance.run_test`: they pass by reaching ``pass``).
"""

from __future__ import annotations

import re
import tempfile
from collections.abc import Iterator
from pathlib import Path

from shary.io.scxml import parse_xml
from shary.statechart.conformance import REFUSED, Outcome, run_test
from userfiles.errors import FileError
from userfiles.yamlsafe import read_text

MANIFEST = "manifest.xml"
MAX_MANIFEST_ELEMENTS = 10_000
"""Most XML elements a manifest may have (the IRP's has about 1,300)."""

_REWRITES = [
    (re.compile(r'\bconf:targetpass="[^"]*"'), 'target="pass"'),
    (re.compile(r'\bconf:targetfail="[^"]*"'), 'target="fail"'),
    (re.compile(r"<conf:pass\s*/>"), '<final id="pass"/>'),
    (re.compile(r"<conf:fail\s*/>"), '<final id="fail"/>'),
    (re.compile(r'\bconf:datamodel="[^"]*"'), 'datamodel="null"'),
    (re.compile(r'\bconf:delay="\s*([0-9]*\.?[0-9]+)\s*"'), r'delay="\1s"'),
    (re.compile(r'\bconf:inState="([A-Za-z0-9_.:-]*)"'), r'cond="In(' + "'" + r'\1' + "'" + ')"'),
    (re.compile(r'\s+xmlns:conf="[^"]*"'), ""),
]
_CONF = re.compile(r"\bconf:([A-Za-z_][\w.-]*)")
_COMMENT = re.compile(r"<!--.*?-->", re.S)


def is_irp(folder: Path) -> bool:
    """True when ``folder`` holds the IRP's ``manifest.xml``."""
    return (folder / MANIFEST).is_file()


def irp_tests(folder: Path) -> list[Path]:
    """The mandatory, automated tests the manifest lists, as ``.txml`` files under ``folder``.

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
        if test.attrs.get("conformance") != "mandatory" or test.attrs.get("manual") != "false":
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
    for pattern, replacement in _REWRITES:
        text = pattern.sub(replacement, text)
    left = sorted(set(_CONF.findall(_COMMENT.sub("", text))))
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
                refused[source] = f"refused: needs a data model: {', '.join(left)}"
            else:
                (out / f"{source.stem}.scxml").write_text(text, encoding="utf-8")
        for test in tests:
            name = str(test.relative_to(folder))
            if test in refused:
                yield Outcome(name, False, refused[test], REFUSED)
                continue
            outcome = run_test(out / f"{test.stem}.scxml")
            yield Outcome(name, outcome.passed, outcome.reason, outcome.kind)
