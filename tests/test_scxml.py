"""SCXML import, and the SCION statechart suite as an outside yardstick."""

from __future__ import annotations

from pathlib import Path

import pytest
from conftest import REPO, problems
from suites import absent, needs, suite

from shary.io.schemes import parse_scheme
from shary.io.scxml import import_scxml
from shary.statechart.compiler import compile_scheme
from shary.statechart.conformance import run_test
from userfiles.errors import FileError
from userfiles.yamlsafe import load_text

SCION = suite("scion")
NO_DATAMODEL = REPO / "docs" / "examples" / "scion-no-datamodel.txt"
"""SCION's charts that need no data model (the suite's own list, kept with the README's
command: a clone of SCION's repository does not have it)."""

CHART = """\
<?xml version="1.0"?>
<scxml xmlns="http://www.w3.org/2005/07/scxml" version="1.0" initial="a">
  <state id="a">
    <onentry><send event="tick" delay="1.5s" id="t1"/></onentry>
    <transition event="tick" target="p"/>
    <transition event="tick" target="a"/>
  </state>
  <parallel id="p">
    <state id="r1"><state id="x"><transition event="go" target="done"/></state></state>
    <state id="r2"><state id="y"/><history id="h" type="deep"/></state>
  </parallel>
  <final id="done"/>
  <state id="never"/>
</scxml>
"""


def test_import_translates_and_prunes(write):
    text = import_scxml(write("c.scxml", CHART))
    assert text.startswith("# Left out, since no run can ever enter them: never")
    scheme = parse_scheme(load_text(text))
    assert scheme.state("p").kind == "parallel"
    assert scheme.state("h").history == "deep"
    assert [t.targets for t in scheme.state("a").transitions] == [("p",)]  # shadowed one dropped
    assert "never" not in scheme.states


@pytest.mark.parametrize("fragment, message", [
    ('<transition event="e" cond="x &gt; 1" target="a"/>', "cond= needs a data model"),
    ("<onentry><script>x = 1</script></onentry>", "<script> needs a data model"),
    ('<onentry><send event="e" target="http://example.org/"/></onentry>', "nowhere else"),
    ('<onentry><send event="e" type="http://www.w3.org/TR/scxml/#BasicHTTPEventProcessor"/>'
     '</onentry>', "only SCXML's own event processor"),
    ('<invoke src="http://example.org/c.scxml"/>', "only a relative path or a file: URI"),
    ('<invoke src="file://host/c.scxml"/>', "only a relative path or a file: URI"),
    ('<invoke src="file:../x.scxml"/>', "is outside the folder of u.scxml"),
    ('<invoke src="file:///etc/c.scxml"/>', "u.scxml"),
    ('<invoke src="../x.scxml"/>', "is outside the folder of u.scxml"),
    ('<invoke srcexpr="x"/>', "needs a data model"),
    ('<onentry><send event="e" delay="soon"/></onentry>', "is not a time"),
])
def test_unsupported_constructs_are_refused_by_name(shary, write, tmp_path, fragment, message):
    chart = f'<scxml xmlns="http://www.w3.org/2005/07/scxml">\n<state id="a">\n{fragment}\n' \
            '</state>\n</scxml>\n'
    source = write("u.scxml", chart)
    status, _, err = shary("import-scxml", source, "-o", tmp_path / "u.yaml")
    assert status == 2
    (m,) = problems(err)
    assert message in m["message"] and m["line"] == "3"
    assert not (tmp_path / "u.yaml").exists()


@pytest.mark.parametrize("text, message", [
    ("<scxml><state id='a'></scxml>", "XML syntax"),
    ('<!DOCTYPE x [<!ENTITY a "aaaa">]><scxml/>', "DOCTYPE"),
    ('<!DOCTYPE s [<!ENTITY a "aaaaaaaa"><!ENTITY b "&a;&a;&a;&a;&a;&a;&a;&a;">'
     '<!ENTITY c "&b;&b;&b;&b;&b;&b;&b;&b;">]><scxml><state id="&c;"/></scxml>', "DOCTYPE"),
    ('<!DOCTYPE s [<!ENTITY x SYSTEM "file:///etc/passwd">]><scxml><log label="&x;"/></scxml>',
     "DOCTYPE"),
    ('<!DOCTYPE scxml SYSTEM "http://example.invalid/scxml.dtd"><scxml/>', "DOCTYPE"),
    ("<html/>", "not an SCXML document"),
])
def test_broken_xml_is_refused(shary, write, tmp_path, text, message):
    status, _, err = shary("import-scxml", write("b.scxml", text), "-o", tmp_path / "b.yaml")
    assert status == 2 and message in err and "Traceback" not in err


def test_import_cli_writes_a_valid_scheme(shary, write, tmp_path):
    out = tmp_path / "c.yaml"
    status, _, _ = shary("import-scxml", write("c.scxml", CHART), "-o", out)
    assert status == 0
    assert shary("validate", out)[0] == 0
    text = out.read_text(encoding="utf-8")
    assert "'on'" not in text and "\n    on:\n" in text  # as every scheme writes it


def test_plain_chart_passes_when_it_reaches_pass(write, tmp_path):
    chart = write("plain.scxml", """\
        <scxml xmlns="http://www.w3.org/2005/07/scxml" initial="wait">
          <state id="wait">
            <onentry><send event="later" delay="2s"/></onentry>
            <transition event="later" target="pass"/>
          </state>
          <final id="pass"/>
        </scxml>
        """)
    assert run_test(chart).passed
    failing = write("fail.scxml", chart.read_text().replace('target="pass"', 'target="fail"')
                    .replace('<final id="pass"/>', '<final id="fail"/>'))
    outcome = run_test(failing)
    assert not outcome.passed and "not 'pass'" in outcome.reason


def _no_datamodel_charts() -> list:
    """The charts as parameters, or one skipped parameter saying how to get the suite."""
    if not SCION.is_dir():
        return [pytest.param(None, marks=pytest.mark.skip(reason=absent("scion")),
                             id="suite-missing")]
    return NO_DATAMODEL.read_text(encoding="utf-8").split()


@pytest.mark.parametrize("name", _no_datamodel_charts())
def test_scion_no_datamodel(name):
    outcome = run_test(SCION / name, SCION)
    assert outcome.passed, outcome.reason


@needs("scion")
def test_conformance_command_counts(shary):
    status, out, _ = shary("conformance", SCION, "--only", NO_DATAMODEL)
    assert status == 0
    assert out.strip().splitlines()[-1] == f"{len(_no_datamodel_charts())} passed, 0 failed"


def test_conformance_command_reports_failures(shary, write, tmp_path: Path):
    write("bad.scxml", '<scxml xmlns="http://www.w3.org/2005/07/scxml"><state id="a">'
          '<transition cond="1" event="e" target="a"/></state></scxml>')
    status, out, _ = shary("conformance", tmp_path)
    assert status == 1
    assert "FAIL bad.scxml: refused: cond= needs a data model" in out
    assert out.strip().splitlines()[-1] == "0 passed, 1 failed"


DATA_CHART = """\
<scxml xmlns="http://www.w3.org/2005/07/scxml" datamodel="shary" initial="a">
  <datamodel><data id="n" expr="0"/><data id="items">[1, 2, 3]</data></datamodel>
  <state id="a">
    <onentry>
      <foreach array="items" item="i"><assign location="n" expr="n + i"/></foreach>
      <if cond="n == 6"><send event="sum"><param name="total" expr="n"/></send>
      <else/><raise event="wrong"/></if>
    </onentry>
    <transition event="sum" cond="_event.data.total == 6" target="done"/>
    <transition event="*" target="fail"/>
  </state>
  <final id="done"><donedata><param name="total" expr="n"/></donedata></final>
  <final id="fail"/>
</scxml>
"""


def test_a_chart_with_a_data_model_imports_to_the_schemes_data_model_and_runs(write):
    text = import_scxml(write("d.scxml", DATA_CHART))
    document = load_text(text).data
    assert document["data"] == {"n": "0", "items": "[1, 2, 3]"}
    on_entry = document["states"]["a"]["on_entry"]
    assert on_entry[0] == {"foreach": "items", "item": "i",
                           "do": [{"assign": "n", "expr": "n + i"}]}
    assert on_entry[1]["if"] == "n == 6" and on_entry[1]["else"] == [{"raise": "wrong"}]
    assert on_entry[1]["then"] == [{"send": "sum", "params": {"total": "n"}}]
    assert document["states"]["done"]["donedata"] == {"params": {"total": "n"}}
    instance = compile_scheme(parse_scheme(load_text(text))).start()
    assert instance.configuration == ("done",) and instance.data["n"] == 6


def test_an_expression_of_a_chart_is_refused_at_its_element(write):
    chart = DATA_CHART.replace('expr="n + i"', 'expr="n +"')
    with pytest.raises(FileError) as err:
        import_scxml(write("d.scxml", chart))
    (problem,) = err.value.problems
    assert problem.line == 5 and "syntax error in expression 'n +'" in problem.message
