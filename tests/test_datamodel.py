"""Schemes with a data model: variables, guards on event data, executable content, errors.

A scheme without one runs as before (its instances hold no data); these check
what the data model adds, through schemes written as users write them.
"""

from __future__ import annotations

import json
import re
from pathlib import Path

import pytest

from shary.io.schemes import parse_scheme
from shary.statechart.compiler import compile_scheme
from shary.statechart.datamodel import MAX_ITERATIONS
from shary.statechart.instance import SchemeListener
from userfiles.errors import FileError
from userfiles.yamlsafe import load_text

COUNTER = """
scheme: ask-three-times
data: {tries: 0, answer: null}
initial: ask
states:
  ask:
    on_entry: [{assign: tries, expr: tries + 1}]
    on:
      reply:
        - {target: agreed, cond: "_event.data.answer == 'yes'",
           do: [{assign: answer, expr: _event.data.answer}]}
        - {target: ask, cond: tries < 3}
        - gave-up
  agreed: {final: true, donedata: {params: {answer: answer, tries: tries}}}
  gave-up: {final: true, outcome: failed}
"""


class Heard(SchemeListener):
    def __init__(self) -> None:
        self.logs: list[str] = []

    def logged(self, instance, text: str) -> None:
        self.logs.append(text)


def start(text: str, listener=None):
    return compile_scheme(parse_scheme(load_text(text, "s.yaml"))).start(listener=listener)


def test_a_counter_and_a_guard_on_event_data():
    instance = start(COUNTER)
    instance.send("reply", {"answer": "no"})
    assert instance.configuration == ("ask",) and instance.data["tries"] == 2
    instance.send("reply", {"answer": "yes"})
    assert instance.configuration == ("agreed",) and instance.data["answer"] == "yes"
    instance = start(COUNTER)
    for _ in range(3):
        instance.send("reply", {"answer": "no"})
    assert instance.configuration == ("gave-up",) and instance.data["tries"] == 3


def test_a_scheme_without_a_data_model_holds_no_data():
    instance = start("scheme: plain\ninitial: a\nstates:\n  a: {on: {go: b}}\n  b: {}\n")
    instance.send("go")
    assert instance.data is None and instance.configuration == ("b",)


def test_if_foreach_and_log_of_a_value():
    heard = Heard()
    start("""
scheme: sums
data: {total: 0, items: [1, 2, 3], item: null}
initial: a
states:
  a:
    on_entry:
      - {foreach: items, item: item, do: [{assign: total, expr: total + item}]}
      - if: total > 10
        then: [{log: big}]
        elif: [{if: total == 6, then: [{log: total, expr: total}]}]
        else: [{log: small}]
""", heard)
    assert heard.logs == ["total: 6"]


def test_a_failing_expression_raises_error_execution_and_stops_its_block():
    instance = start("""
scheme: fails
data: {n: 0}
initial: a
states:
  a:
    on_entry: [{assign: n, expr: 1 / 0}, {assign: n, expr: 5}]
    on: {error.execution: {target: b, cond: "n == 0"}}
  b: {}
""")
    assert instance.configuration == ("b",)
    assert "ZeroDivisionError" in instance.data["_event"]["data"]["error"]


def test_a_send_carries_params_and_the_child_gets_its_variables_from_the_parent():
    instance = start("""
scheme: parent
data: {who: "'bob'", got: null}
initial: a
states:
  a:
    invoke:
      id: child
      params: {name: who}
      scheme:
        scheme: child
        data: {name: null}
        initial: c
        states:
          c:
            on_entry: [{send: hello, target: "#_parent", params: {name: name}}]
    on:
      hello: {target: b, do: [{assign: got, expr: _event.data.name}]}
  b: {}
""")
    assert instance.configuration == ("b",) and instance.data["got"] == "bob"
    assert instance.data["_event"]["invokeid"] == "child"


def test_the_system_variables_are_bound():
    instance = start(COUNTER)
    data = instance.data
    assert data["_name"] == "ask-three-times" and data["_sessionid"]
    assert data["_ioprocessors"]["scxml"]["location"] == f"#_scxml_{data['_sessionid']}"


def test_an_expression_error_is_found_at_load_time_with_its_position():
    with pytest.raises(FileError) as err:
        parse_scheme(load_text("scheme: s\ndata: {n: 0}\ninitial: a\nstates:\n"
                               "  a: {on: {go: {target: a, cond: m > 1}}}\n", "s.yaml"))
    (problem,) = err.value.problems
    assert (problem.line, problem.col) == (5, 34) and "unknown variable 'm'" in problem.message


def test_the_example_of_docs_schemes_md_runs_as_shown(tmp_path, shary):
    doc = (Path(__file__).resolve().parent.parent / "docs" / "schemes.md").read_text()
    chart = re.search(r"```yaml\n(scheme: ask-for-object\n.*?)```", doc, re.S)
    shown = re.search(r"\$ shary simulate ask-for-object.yaml (.*?)\n(.*?)```", doc, re.S)
    assert chart and shown
    (tmp_path / "ask-for-object.yaml").write_text(chart.group(1))
    words = re.findall(r"'([^']*)'|(\S+)", shown.group(1))
    status, out, err = shary("simulate", tmp_path / "ask-for-object.yaml",
                             *[quoted or plain for quoted, plain in words])
    assert status == 0, err
    assert [line.strip() for line in out.splitlines()[1:]] == \
        [line.strip() for line in shown.group(2).splitlines()]


@pytest.mark.parametrize(("script", "acts", "end"), [
    ("disambiguate attended SAY-WHICH unclear SAY-WHICH unclear done",
     ["WAIT-ATTENTION", "ASK-WHICH", "SAY-WHICH", "ASK-WHICH", "SAY-WHICH", "GIVE-UP"],
     "unresolved"),
    ("disambiguate attended SAY-WHICH unclear SAY-WHICH chosen",
     ["WAIT-ATTENTION", "ASK-WHICH", "SAY-WHICH", "ASK-WHICH", "SAY-WHICH"], "chosen"),
    ("inform 10s done 10s done",
     ["WAIT-ATTENTION", "CALL-ATTENTION", "WAIT-ATTENTION", "GIVE-UP"], "untold"),
    ("inform done attention-lost 10s done 10s done",
     ["WAIT-ATTENTION", "INFORM", "WAIT-ATTENTION", "CALL-ATTENTION", "WAIT-ATTENTION",
      "GIVE-UP"], "untold"),
    ("inform 10s done done", ["WAIT-ATTENTION", "CALL-ATTENTION", "WAIT-ATTENTION", "INFORM"],
     "tell"),
])
def test_the_built_in_schemes_that_count_carry_out_the_acts_their_copies_of_states_did(
        script, acts, end, shary):
    """The act sequences are those of the schemes before they counted (ask-again,
    attend-again), taken from runs of those versions."""
    status, out, err = shary("simulate", *script.split(), "--json")
    assert status == 0, err
    run = json.loads(out)
    assert [e["act"] for e in run["trace"] if e["kind"] == "enter" and e["act"]] == acts
    assert run["configuration"] == [end]


def test_nested_foreach_rounds_are_bounded_and_end_in_error_execution():
    instance = start("""
scheme: rounds
data: {big: "list(str(0) * 1000)", x: null, y: null, z: null, n: 0}
initial: a
states:
  a:
    on_entry:
      - foreach: big
        item: x
        do: [{foreach: big, item: y, do: [{assign: n, expr: n + 1}]}]
    on: {error.execution: b}
  b: {}
""")
    assert instance.configuration == ("b",)
    assert MAX_ITERATIONS - 1_000 < instance.data["n"] < MAX_ITERATIONS  # not 1000 * 1000


def test_late_binding_sets_a_states_variables_when_it_is_first_entered():
    instance = start("""
scheme: late
binding: late
data: {seen: null}
initial: a
states:
  a:
    on: {go: {target: b, do: [{assign: seen, expr: "bound('answer')"}]}}
  b:
    data: {answer: 42}
""")
    assert instance.data["answer"] is None
    instance.send("go")
    assert instance.data["seen"] is False and instance.data["answer"] == 42
