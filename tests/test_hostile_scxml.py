"""Hostile SCXML charts and SCION traces: refused with positions, in bounded time and memory.

Charts go through ``shary import-scxml``, traces through ``shary conformance``
(beside a small valid chart).  Inputs too big for git (deep nesting, thousands
of transitions) are generated in ``tmp_path``.  Charts that loop are not
refused (they are valid SCXML): ``shary conformance`` fails them with the
reason, in bounded time.
"""

from __future__ import annotations

import re
import shutil
from pathlib import Path

import pytest
from hostile import HOSTILE, MAX_SECONDS, assert_refused, run_inprocess, run_subprocess

from shary.io.scxml import MAX_DEPTH, MAX_ELEMENTS

CHARTS = HOSTILE / "scxml"
TRACES = HOSTILE / "trace"

EXPECTED = {
    "invoke-parent-folder": "is outside the folder of invoke-parent-folder.scxml",
    "invoke-absolute": "is outside the folder of invoke-absolute.scxml",
    "invoke-file-url": "'/etc/hostname' is outside the folder of invoke-file-url.scxml",
    "invoke-cycle": r"invoke cycle: invoke-cycle.scxml -> invoke-cycle.scxml",
    "invoke-missing": "no file 'no-such-chart.scxml'",
    "invoke-both-sources": "either src= or one <content>",
    "invoke-http-type": "only SCXML charts can be invoked",
    "invoke-content-not-chart": "must hold one <scxml> chart",
    "invoke-inline-datamodel": "cond= needs a data model",
    "initial-bad-content": "<script> needs a data model",
    "expr-dunder": "the attribute '__bases__' is not allowed",
    "expr-script": "<script> is not supported",
    "expr-ecmascript": "cond= needs a data model",
    "expr-syntax": "syntax error in expression 'x === 1'",
}

TRACE_EXPECTED = {
    "string-delay": "number",
    "list-event": "object",
    "nan-delay": "number",
    "infinite-delay": "number",
    "overflow-delay": r"too large \(the limit is 86400000\)",
    "negative-delay": r"minimum|less than",
    "huge-delay": r"too large \(the limit is 86400000\)",
    "missing-next": "nextConfiguration",
    "number-event": "string",
    "string-configuration": "array|list",
    "events-not-a-list": "array|list",
    "top-level-list": "object|mapping",
    "truncated": ".",
    "duplicate-key": "duplicate",
    "deep-nesting": "deeper",
    "spaced-event": "name|pattern|match",
}

CHART = """\
<scxml xmlns="http://www.w3.org/2005/07/scxml" initial="a">
  <state id="a"><transition event="t" target="b"/></state>
  <state id="b"/>
</scxml>
"""


@pytest.fixture(autouse=True, scope="module")
def warm() -> None:
    """Pay for imports and schema compilation once, outside the measured refusals."""
    run_inprocess("validate", "give-object")


def test_every_corpus_file_has_an_expectation():
    assert {p.stem for p in CHARTS.glob("*.scxml")} == set(EXPECTED)
    assert {p.stem for p in TRACES.glob("*.json")} == set(TRACE_EXPECTED)


@pytest.mark.parametrize("name", sorted(EXPECTED))
def test_hostile_chart_is_refused(name, tmp_path):
    chart = CHARTS / f"{name}.scxml"
    outcome = run_inprocess("import-scxml", chart, "-o", tmp_path / "out.yaml")
    assert_refused(outcome, chart, message=EXPECTED[name])
    assert not (tmp_path / "out.yaml").exists()


@pytest.mark.parametrize("name", sorted(TRACE_EXPECTED))
def test_hostile_trace_is_refused(name, tmp_path):
    trace = tmp_path / f"{name}.json"
    shutil.copy(TRACES / f"{name}.json", trace)
    (tmp_path / f"{name}.scxml").write_text(CHART)
    outcome = run_inprocess("conformance", tmp_path)
    assert_refused(outcome, trace, message=TRACE_EXPECTED[name])


def test_deeply_nested_chart_is_refused_at_the_element(tmp_path):
    depth = 5000
    chart = tmp_path / "deep.scxml"
    chart.write_text('<scxml xmlns="http://www.w3.org/2005/07/scxml">\n'
                     + "".join(f'<state id="d{i}">\n' for i in range(depth))
                     + "</state>" * depth + "\n</scxml>\n")
    outcome = run_subprocess("import-scxml", chart, "-o", tmp_path / "out.yaml")
    assert_refused(outcome, chart, message=f"nested more than {MAX_DEPTH} deep")
    (m,) = outcome.problems()
    assert m["line"] == str(MAX_DEPTH + 1)


def test_too_many_elements_are_refused_at_the_top(tmp_path):
    chart = tmp_path / "huge.scxml"
    chart.write_text('<scxml xmlns="http://www.w3.org/2005/07/scxml"><state id="a">\n'
                     + "".join(f'<transition event="e{i}"/>\n' for i in range(MAX_ELEMENTS))
                     + "</state></scxml>\n")
    outcome = run_subprocess("import-scxml", chart, "-o", tmp_path / "out.yaml")
    assert_refused(outcome, chart, message=f"more than {MAX_ELEMENTS} XML elements")
    (m,) = outcome.problems()
    assert (m["line"], m["col"]) == ("1", "1")


@pytest.mark.parametrize("shape", ["one state, 4000 transitions", "4000 states in a ring"])
def test_big_valid_charts_import_in_time(shape, tmp_path):
    n = 4000
    if shape.startswith("one"):
        body = '<state id="a">' + "".join(f'<transition event="e{i}" target="b"/>\n'
                                          for i in range(n)) + '</state><state id="b"/>'
    else:
        body = "".join(f'<state id="s{i}"><transition event="e{i}" target="s{(i + 1) % n}"/>'
                       "</state>\n" for i in range(n))
    chart = tmp_path / "big.scxml"
    chart.write_text(f'<scxml xmlns="http://www.w3.org/2005/07/scxml">{body}</scxml>\n')
    outcome = run_subprocess("import-scxml", chart, "-o", tmp_path / "big.yaml")
    assert outcome.status == 0, outcome.err
    assert outcome.seconds < MAX_SECONDS


LOOPS = {
    "raise": '<state id="a"><onentry><raise event="e"/></onentry>'
             '<transition event="e" target="a"/></state>',
    "eventless": '<state id="a"><transition target="b"/></state>'
                 '<state id="b"><transition target="a"/></state>',
    "zero-delay": '<state id="a"><onentry><send event="e" delay="0s"/></onentry>'
                  '<transition event="e" target="a"/></state>',
    "tiny-delay": '<state id="a"><onentry><send event="e" delay="0.000001s"/></onentry>'
                  '<transition event="e" target="a"/></state>',
}


def test_looping_charts_fail_with_the_reason_in_bounded_time(tmp_path):
    for name, body in LOOPS.items():
        (tmp_path / f"{name}.scxml").write_text(
            f'<scxml xmlns="http://www.w3.org/2005/07/scxml">{body}</scxml>')
    outcome = run_subprocess("conformance", tmp_path)
    assert outcome.status == 1 and "Traceback" not in outcome.err, outcome.err
    assert outcome.seconds < MAX_SECONDS
    fails = dict(re.findall(r"^FAIL (\S+)\.scxml: (.*)$", outcome.out, re.M))
    assert set(fails) == set(LOOPS)
    assert all("livelock" in fails[n] for n in ("raise", "eventless", "zero-delay"))
    assert "timer loop" in fails["tiny-delay"]
    assert outcome.out.strip().endswith(f"0 passed, {len(LOOPS)} failed")


def test_a_valid_trace_still_runs(tmp_path):
    (tmp_path / "ok.scxml").write_text(CHART)
    Path(tmp_path / "ok.json").write_text(
        '{"initialConfiguration": ["a"], "events": [{"event": {"name": "t"}, "after": 10, '
        '"nextConfiguration": ["b"]}]}')
    outcome = run_inprocess("conformance", tmp_path)
    assert outcome.status == 0 and "1 passed, 0 failed" in outcome.out
