"""``guard: in STATE``: SCXML's ``In()``, the one predicate of the null data model."""

from __future__ import annotations

import textwrap

import pytest

from shary.io.schemes import parse_scheme
from shary.io.scxml import import_scxml
from shary.statechart.clock import SimulatedClock
from shary.statechart.compiler import compile_scheme
from shary.statechart.conformance import run_test
from userfiles.errors import FileError
from userfiles.yamlsafe import load_text

REGIONS = """\
    scheme: regions
    initial: p
    states:
      p:
        parallel: true
        states:
          left:
            initial: l1
            states:
              l1:
                on:
                  go: [{target: l2, guard: in r2}, {target: l3, guard: not in r2}]
              l2: {}
              l3: {}
          right:
            initial: r1
            states:
              r1: {on: {flip: r2}}
              r2: {}
"""


def start(text: str):
    scheme = parse_scheme(load_text(textwrap.dedent(text), "regions.yaml"))
    return compile_scheme(scheme).start(clock=SimulatedClock())


@pytest.mark.parametrize("events, leaf", [(["go"], "l3"), (["flip", "go"], "l2")])
def test_a_guard_in_a_state_reads_the_configuration(events, leaf):
    instance = start(REGIONS)
    for event in events:
        instance.send(event)
    assert leaf in instance.configuration


def test_a_guard_in_an_unknown_state_is_refused_at_the_transition():
    with pytest.raises(FileError) as err:
        start(REGIONS.replace("guard: in r2}, {", "guard: in right2}, {"))
    (problem,) = err.value.problems
    assert problem.message == "guard 'in right2' names an unknown state (did you mean 'right'?)"
    assert (problem.line, problem.col) == (12, 15)


CHART = """\
<scxml xmlns="http://www.w3.org/2005/07/scxml" version="1.0" initial="p" datamodel="null">
  <parallel id="p">
    <state id="a">
      <transition cond="In('never')" target="fail"/>
      <transition cond='In( "b" )' target="pass"/>
      <transition target="fail"/>
    </state>
    <state id="b"/>
  </parallel>
  <state id="never"/>
  <final id="pass"/>
  <final id="fail"/>
</scxml>
"""


def test_scxml_in_becomes_a_guard_and_a_state_never_entered_drops_its_transition(write):
    chart = write("in.scxml", CHART)
    text = import_scxml(chart)
    assert "guard: in b" in text and "in never" not in text
    assert run_test(chart).passed


@pytest.mark.parametrize("cond", ["In(b)", "!In(&apos;b&apos;)", "In(&apos;b&apos;) and 1",
                                  "_event"])
def test_other_conditions_still_need_a_data_model(write, cond):
    chart = write("c.scxml", CHART.replace("""'In( "b" )'""", f'"{cond}"'))
    with pytest.raises(FileError, match=r"only In\('STATE'\) does not"):
        import_scxml(chart)
