"""The W3C SCXML IRP's tests on the null data model (:mod:`shary.statechart.w3c`).

The translation and the runner are tested on small ``.txml`` files of our
own; the W3C's own tests run when a copy is at hand: set ``SHARY_W3C_IRP``
to a folder holding the IRP's ``manifest.xml`` and its ``.txml`` files
(``wget -r -np -nH --cut-dirs=3 -A txml,xml https://www.w3.org/Voice/2013/scxml-irp/``,
or the ``test/w3c`` folder of a clone of github.com/tklab-tud/uscxml), or
put it at ``../shared/suites/w3c-irp``.
"""

from __future__ import annotations

import os
from pathlib import Path

import pytest
from suites import SUITES

from shary.statechart.conformance import REFUSED
from shary.statechart.w3c import irp_tests, run_irp, translate

NS = 'xmlns="http://www.w3.org/2005/07/scxml" xmlns:conf="http://www.w3.org/2005/scxml-conformance"'

PARENT = f"""<?xml version="1.0"?>
<!-- a comment naming conf:expr is no construct -->
<scxml initial="s0" version="1.0" conf:datamodel="" {NS}>
  <state id="s0">
    <onentry><send event="timeout" conf:delay="2"/></onentry>
    <invoke type="http://www.w3.org/TR/scxml/" src="file:test901sub1.scxml"/>
    <transition event="childToParent" conf:inState="s0" conf:targetpass=""/>
    <transition event="*" conf:targetfail=""/>
  </state>
  <conf:pass/>
  <conf:fail/>
</scxml>
"""

CHILD = f"""<?xml version="1.0"?>
<scxml initial="sub0" version="1.0" conf:datamodel="" {NS}>
  <state id="sub0">
    <onentry><send event="childToParent" target="#_parent"/></onentry>
  </state>
</scxml>
"""

NEEDS_DATA = f"""<?xml version="1.0"?>
<scxml initial="s0" version="1.0" conf:datamodel="" {NS}>
  <state id="s0"><transition conf:expr="1" conf:targetpass=""/></state>
  <conf:pass/>
</scxml>
"""

MANIFEST = """<?xml version="1.0"?>
<assertions>
  <assert id="1"><test id="901" conformance="mandatory" manual="false">
    <start uri="901/test901.txml"/></test></assert>
  <assert id="2"><test id="902" conformance="mandatory" manual="false">
    <start uri="902/test902.txml"/></test></assert>
  <assert id="3"><test id="903" conformance="optional" manual="false">
    <start uri="903/test903.txml"/></test></assert>
  <assert id="4"><test id="904" conformance="mandatory" manual="true">
    <start uri="904/test904.txml"/></test></assert>
</assertions>
"""


def test_translation_rewrites_what_needs_no_data_model_and_names_the_rest():
    text, left = translate(PARENT)
    assert left == []
    assert 'datamodel="null"' in text and 'delay="2s"' in text and 'target="pass"' in text
    assert '<final id="pass"/>' in text and "xmlns:conf" not in text
    assert "cond=\"In('s0')\"" in text
    _, left = translate(NEEDS_DATA)
    assert left == ["conf:expr"]


@pytest.fixture
def irp(tmp_path: Path) -> Path:
    files = {"manifest.xml": MANIFEST, "901/test901.txml": PARENT,
             "901/test901sub1.txml": CHILD, "902/test902.txml": NEEDS_DATA,
             "903/test903.txml": PARENT, "904/test904.txml": PARENT}
    for name, text in files.items():
        (tmp_path / name).parent.mkdir(exist_ok=True)
        (tmp_path / name).write_text(text)
    return tmp_path


def test_the_manifests_mandatory_automated_tests_run(irp, shary):
    tests = irp_tests(irp)
    assert [t.name for t in tests] == ["test901.txml", "test902.txml"]
    outcomes = list(run_irp(irp, tests))
    assert [(o.name, o.passed) for o in outcomes] == [("901/test901.txml", True),
                                                       ("902/test902.txml", False)]
    assert outcomes[1].kind == REFUSED and "needs a data model: conf:expr" in outcomes[1].reason
    status, out, _ = shary("conformance", irp)
    assert status == 1 and "1 passed, 1 failed" in out


def test_a_broken_manifest_is_refused_at_its_line(irp, shary):
    (irp / "manifest.xml").write_text("<assertions>\n<test>\n</assertions>\n")
    status, _, err = shary("conformance", irp)
    assert status == 2 and "manifest.xml:3:" in err


def _irp_copy() -> Path | None:
    for folder in (os.environ.get("SHARY_W3C_IRP"), SUITES / "w3c-irp"):
        if folder and (Path(folder) / "manifest.xml").is_file():
            return Path(folder)
    return None


@pytest.mark.skipif(_irp_copy() is None, reason="the W3C IRP tests are not here: set "
                    "SHARY_W3C_IRP to a folder with its manifest.xml (see this file's docstring)")
def test_every_w3c_test_the_null_data_model_can_express_passes():
    folder = _irp_copy()
    assert folder is not None
    outcomes = list(run_irp(folder, irp_tests(folder)))
    ran = [o for o in outcomes if o.kind != REFUSED]
    assert [o for o in ran if not o.passed] == []
    assert len(ran) == 41
