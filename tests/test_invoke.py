"""Invoked child schemes, default-entry content and loops, after the W3C SCXML tests' intent.

The SCION suite has no ``<invoke>`` test (its invoke tests are W3C ports that
need an ECMAScript data model), so the intent of the W3C tests is written
here: 422 (invokes start at the end of the macrostep, only for states still
active), 235/236 (``done.invoke.ID`` reaches the parent, last), 229
(autoforward), 250/252 (a cancelled child runs its on_exit and is never heard
from again), 412 (an ``<initial>`` transition's content runs after the
parent's on_entry and before the child's).
"""

from __future__ import annotations

import textwrap

import pytest
from conftest import problems

from shary.io.schemes import load_scheme, parse_scheme
from shary.io.scxml import import_scxml
from shary.statechart.clock import SimulatedClock
from shary.statechart.compiler import compile_scheme
from shary.statechart.conformance import run_test
from shary.statechart.instance import LivelockError, SchemeListener
from userfiles.errors import FileError
from userfiles.yamlsafe import load_text


class Record(SchemeListener):
    """Everything the instances (parent and children) tell their listener."""

    def __init__(self) -> None:
        self.seen: list[str] = []

    def invoking(self, instance, state, invoke):  # type: ignore[override]
        return self

    def entered(self, instance, state, event):  # type: ignore[override]
        self.seen.append(f"{instance.invoke_id or 'top'}:enter:{state.name}")

    def exited(self, instance, state, event):  # type: ignore[override]
        self.seen.append(f"{instance.invoke_id or 'top'}:exit:{state.name}")

    def logged(self, instance, text):  # type: ignore[override]
        self.seen.append(f"{instance.invoke_id or 'top'}:log:{text}")


def scheme(text: str, file: str = "<string>"):
    return parse_scheme(load_text(textwrap.dedent(text), file))


def run(text: str):
    record = Record()
    clock = SimulatedClock()
    instance = compile_scheme(scheme(text)).start(clock=clock, listener=record)
    return instance, record, clock


CHILD = """\
    scheme: child
    initial: working
    states:
      working:
        on_exit: [{log: child leaves working}]
        on: {finish: ok, fail: ko, after 2s: ok}
      ok: {final: true}
      ko: {final: true, outcome: failed}
"""

@pytest.fixture
def parent_text() -> str:
    return textwrap.dedent("""\
        scheme: parent
        initial: ask
        states:
          ask:
            invoke:
              id: sub
              AUTO
              scheme:
                scheme: child
                initial: working
                states:
                  working:
                    on_exit: [{log: child leaves working}]
                    on: {finish: ok, fail: ko, after 2s: ok}
                  ok: {final: true}
                  ko: {final: true, outcome: failed}
            on:
              done.invoke.sub.failed: gave-up
              done.invoke.sub: ended
              stop: stopped
          ended: {final: true}
          gave-up: {final: true}
          stopped: {final: true}
        """)


def test_done_invoke_reaches_the_parent_with_the_outcome(parent_text):
    instance, record, clock = run(parent_text.replace("AUTO", "autoforward: false"))
    assert record.seen == ["top:enter:ask", "sub:enter:working"]
    clock.advance(2)
    assert instance.configuration == ("ended",)
    assert record.seen[-3:] == ["sub:enter:ok", "top:exit:ask", "top:enter:ended"]


def test_child_outcome_failed_is_its_own_event(parent_text):
    instance, _, _ = run(parent_text.replace("AUTO", "autoforward: true"))
    instance.send("fail")
    assert instance.configuration == ("gave-up",)


def test_autoforward_passes_outside_events_on(parent_text):
    instance, _, _ = run(parent_text.replace("AUTO", "autoforward: true"))
    instance.send("finish")
    assert instance.configuration == ("ended",)
    quiet, _, _ = run(parent_text.replace("AUTO", "autoforward: false"))
    quiet.send("finish")
    assert quiet.configuration == ("ask",)  # the child never heard of it


def test_leaving_the_invoking_state_cancels_the_child(parent_text):
    instance, record, clock = run(parent_text.replace("AUTO", "autoforward: false"))
    instance.send("stop")
    assert instance.configuration == ("stopped",)
    assert record.seen[-4:] == ["sub:log:child leaves working", "sub:exit:working",
                                "top:exit:ask", "top:enter:stopped"]
    cancelled_at = len(record.seen)
    clock.advance(5)  # the child's timeout would have fired: nothing reaches anyone
    assert record.seen[cancelled_at:] == []
    assert clock.next_due() is None


def test_invokes_start_at_the_end_of_the_macrostep_only_for_states_still_active():
    text = """\
        scheme: passing
        initial: a
        states:
          a:
            on: {go: b}
          b:
            invoke: {scheme: {scheme: c1, states: {only: {}}}}
            on: {always: c}
          c:
            invoke: {scheme: {scheme: c2, states: {only2: {on_entry: [{log: c2 started}]}}}}
        """
    instance, record, _ = run(text)
    instance.send("go")
    assert instance.configuration == ("c",)
    assert "b:enter:only" not in record.seen
    assert record.seen[-2:] == ["c:enter:only2", "c:log:c2 started"]


def test_parent_finishing_cancels_its_children():
    text = """\
        scheme: p
        initial: a
        states:
          a:
            states:
              x:
                invoke: {scheme: {scheme: k, states: {k1: {on_exit: [{log: k1 out}]}}}}
            on: {end: fin}
          fin: {final: true}
        """
    instance, record, _ = run(text)
    instance.send("end")
    assert instance.finished and "x:log:k1 out" in record.seen


def test_initial_transition_content_runs_between_entries():
    text = """\
        scheme: w3c412
        initial: p
        states:
          p:
            on_entry: [{log: p entered}]
            initial: {target: c, do: [{log: initial content}, {raise: go}]}
            states:
              c:
                on_entry: [{log: c entered}]
                on: {go: d}
              d: {}
        """
    instance, record, _ = run(text)
    assert [s for s in record.seen if ":log:" in s] == [
        "top:log:p entered", "top:log:initial content", "top:log:c entered"]
    assert instance.configuration == ("d",)


def test_history_default_content_and_a_default_declared_later():
    text = """\
        scheme: hist
        initial: out
        states:
          out:
            on: {in: h}
          p:
            initial: first
            states:
              h: {history: shallow, default: {target: later, do: [{log: default taken}]}}
              first: {}
              later: {}
        """
    instance, record, _ = run(text)
    instance.send("in")
    assert instance.configuration == ("later",)
    assert "top:log:default taken" in record.seen


def test_builtin_and_path_invokes(tmp_path):
    (tmp_path / "parts").mkdir()
    (tmp_path / "parts" / "sub.yaml").write_text(textwrap.dedent(CHILD))
    (tmp_path / "top.yaml").write_text(textwrap.dedent("""\
        scheme: top
        initial: a
        states:
          a:
            invoke: [{scheme: parts/sub.yaml, id: one}, {scheme: give-object, id: two}]
            on: {done.invoke.one: b}
          b: {}
        """))
    loaded = load_scheme(tmp_path / "top.yaml")
    assert [i.scheme.name for i in loaded.state("a").invokes] == ["child", "give-object"]
    instance = compile_scheme(loaded).start(clock=SimulatedClock())
    instance.send("finish")  # not forwarded
    assert instance.configuration == ("a",)


@pytest.mark.parametrize("target, message", [
    ("../outside.yaml", "is outside the folder of self.yaml"),
    ("/etc/passwd", "is outside the folder of self.yaml"),
    ("give-objet", "unknown scheme 'give-objet' (did you mean 'give-object'?)"),
    ("missing.yaml", "no file 'missing.yaml' next to self.yaml"),
    ("self.yaml", r"invoke cycle: self.yaml -> self.yaml"),
])
def test_bad_invoke_targets_are_refused(shary, tmp_path, target, message):
    (tmp_path / "outside.yaml").write_text(textwrap.dedent(CHILD))
    folder = tmp_path / "f"
    folder.mkdir()
    path = folder / "self.yaml"
    path.write_text(f"scheme: s\nstates:\n  a:\n    invoke: {{scheme: {target}}}\n")
    status, _, err = shary("validate", path)
    assert status == 2
    found = problems(err)
    assert any(message in m["message"] and m["line"] == "4" for m in found), err


def test_invoke_cycle_through_two_files(shary, tmp_path):
    (tmp_path / "a.yaml").write_text("scheme: a\nstates:\n  x:\n    invoke: {scheme: b.yaml}\n")
    (tmp_path / "b.yaml").write_text("scheme: b\nstates:\n  y:\n    invoke: {scheme: a.yaml}\n")
    status, _, err = shary("validate", tmp_path / "a.yaml")
    assert status == 2 and "invoke cycle: a.yaml -> b.yaml -> a.yaml" in err


def test_child_errors_are_reported_in_the_child_file(shary, tmp_path):
    (tmp_path / "kid.yaml").write_text("scheme: kid\nstates:\n  x: {on: {go: nowhere}}\n")
    (tmp_path / "top.yaml").write_text("scheme: top\nstates:\n  a:\n"
                                       "    invoke: {scheme: kid.yaml}\n")
    status, _, err = shary("validate", tmp_path / "top.yaml")
    files = {(m["file"].rsplit("/", 1)[-1], m["line"]) for m in problems(err)}
    assert status == 2 and ("kid.yaml", "3") in files and ("top.yaml", "4") in files


def test_duplicate_invoke_ids_and_invokes_on_final_states():
    with pytest.raises(FileError) as err:
        scheme("""\
            scheme: d
            initial: a
            states:
              a:
                invoke: [{scheme: give-object, id: x}, {scheme: robot-task, id: x}]
                on: {go: f}
              f: {final: true, invoke: {scheme: give-object}}
            """)
    text = str(err.value)
    assert "duplicate invoke id 'x'" in text and "a final state cannot have 'invoke'" in text


# -- SCXML ---------------------------------------------------------------------

INVOKING = """\
<scxml xmlns="http://www.w3.org/2005/07/scxml" initial="s0">
  <state id="s0">
    <invoke id="kid" autoforward="true">
      <content>
        <scxml initial="k0">
          <state id="k0"><transition event="go" target="kdone"/></state>
          <final id="kdone"/>
        </scxml>
      </content>
    </invoke>
    <transition event="done.invoke.kid" target="pass"/>
  </state>
  <final id="pass"/>
</scxml>
"""


def test_scxml_invoke_with_content_imports_and_runs(tmp_path):
    chart = tmp_path / "inv.scxml"
    chart.write_text(INVOKING)
    loaded = parse_scheme(load_text(import_scxml(chart)))
    (invoke,) = loaded.state("s0").invokes
    assert invoke.id == "kid" and invoke.autoforward
    assert set(invoke.scheme.states) == {"k0", "kdone"}
    instance = compile_scheme(loaded).start(clock=SimulatedClock())
    instance.send("go")
    assert instance.configuration == ("pass",)


def test_scxml_invoke_src_below_the_folder_and_cycles(tmp_path, shary):
    (tmp_path / "kid.scxml").write_text(
        '<scxml xmlns="http://www.w3.org/2005/07/scxml"><state id="k">'
        '<transition event="go" target="end"/></state><final id="end"/></scxml>')
    chart = tmp_path / "top.scxml"
    chart.write_text(INVOKING.replace('<invoke id="kid" autoforward="true">',
                                      '<invoke id="kid" autoforward="true" src="kid.scxml">')
                     .split("<content>")[0] + "</invoke>" + INVOKING.split("</invoke>")[1])
    instance = compile_scheme(parse_scheme(load_text(import_scxml(chart)))).start(
        clock=SimulatedClock())
    instance.send("go")
    assert instance.configuration == ("pass",)
    (tmp_path / "loop.scxml").write_text(
        '<scxml xmlns="http://www.w3.org/2005/07/scxml"><state id="a">\n'
        '<invoke src="loop.scxml"/></state></scxml>')
    status, _, err = shary("import-scxml", tmp_path / "loop.scxml", "-o", tmp_path / "o.yaml")
    assert status == 2 and "invoke cycle: loop.scxml -> loop.scxml" in err


def test_scxml_initial_content_imports(tmp_path):
    chart = tmp_path / "i.scxml"
    chart.write_text(
        '<scxml xmlns="http://www.w3.org/2005/07/scxml"><state id="p">'
        '<initial><transition target="later"><raise event="go"/></transition></initial>'
        '<state id="first"/><state id="later"><transition event="go" target="pass"/></state>'
        '</state><final id="pass"/></scxml>')
    assert run_test(chart).passed


# -- loops -----------------------------------------------------------------------


@pytest.mark.parametrize("states, message", [
    ("a: {on_entry: [{raise: ping}], on: {ping: {target: a, do: [{raise: ping}]}}}",
     "more than 1000 microsteps"),
    ("a: {on: {go: b}}\n  b: {on: {always: c}}\n  c: {on: {always: b}}", "microsteps"),
    ("a: {on: {go: b}}\n  b: {on_entry: [{send: again}], on: {again: {target: b}}}",
     "zero-delay loop of sends, timers or invokes"),
    ("a: {on: {go: b}}\n  b: {on: {after 0s: b}}", "zero-delay loop of sends, timers or invokes"),
    ("a: {on: {go: b}}\n  b:\n    invoke: {scheme: {scheme: k, states: {end: {final: true}}}}"
     "\n    on: {done.invoke: b}", "zero-delay loop of sends, timers or invokes"),
])
def test_loops_are_livelock_errors_placed_in_the_file(states, message):
    compiled = compile_scheme(scheme(f"scheme: loop\ninitial: a\nstates:\n  {states}\n",
                                     "loop.yaml"))
    clock = SimulatedClock()
    with pytest.raises(LivelockError) as err:
        instance = compiled.start(clock=clock)
        instance.send("go")
        clock.advance(1)
    assert message in str(err.value)
    assert err.value.problem.file == "loop.yaml" and err.value.problem.line >= 4


def test_simulate_reports_a_livelock_and_unknown_events(shary, tmp_path):
    path = tmp_path / "loop.yaml"
    path.write_text("scheme: loop\ninitial: a\nstates:\n  a: {on: {go: b}}\n"
                    "  b: {on: {always: c}}\n  c: {on: {always: b}}\n")
    status, _, err = shary("simulate", path, "go")
    assert status == 2 and f"{path}:6:" in err and "livelock" in err
    status, _, err = shary("simulate", "give-object", "H-AGRE")
    assert status == 2 and "did you mean 'H-AGREE'" in err and "Traceback" not in err
    assert shary("simulate", "give-object", "H-AGREE", "done")[0] == 0


def test_conformance_reports_loops_as_failed_charts(shary, tmp_path):
    (tmp_path / "raise.scxml").write_text(
        '<scxml xmlns="http://www.w3.org/2005/07/scxml"><state id="a"><onentry>'
        '<raise event="e"/></onentry><transition event="e" target="a"/></state></scxml>')
    (tmp_path / "timer.scxml").write_text(
        '<scxml xmlns="http://www.w3.org/2005/07/scxml"><state id="a"><onentry>'
        '<send event="e" delay="0s"/></onentry><transition event="e" target="a"/></state>'
        '</scxml>')
    (tmp_path / "tiny.scxml").write_text(
        '<scxml xmlns="http://www.w3.org/2005/07/scxml"><state id="a"><onentry>'
        '<send event="e" delay="0.000001s"/></onentry><transition event="e" target="a"/>'
        '</state></scxml>')
    status, out, _ = shary("conformance", tmp_path)
    assert status == 1
    assert "FAIL raise.scxml: livelock" in out and "FAIL timer.scxml: livelock" in out
    assert "FAIL tiny.scxml:" in out and "timer events" in out
    assert out.strip().endswith("0 passed, 3 failed")


def test_conformance_runs_an_invoking_chart(tmp_path):
    chart = tmp_path / "kid-ends.scxml"
    chart.write_text("""\
<scxml xmlns="http://www.w3.org/2005/07/scxml" initial="s0">
  <state id="s0">
    <invoke id="kid"><content><scxml initial="k">
      <state id="k"><onentry><send event="tick" delay="1s"/></onentry>
        <transition event="tick" target="kend"/></state>
      <final id="kend"/>
    </scxml></content></invoke>
    <transition event="done.invoke.kid" target="pass"/>
    <transition event="tick" target="fail"/>
  </state>
  <final id="pass"/>
  <final id="fail"/>
</scxml>
""")
    outcome = run_test(chart)
    assert outcome.passed, outcome.reason


def test_scxml_history_default_declared_later_with_content(tmp_path):
    chart = tmp_path / "h.scxml"
    chart.write_text("""\
<scxml xmlns="http://www.w3.org/2005/07/scxml" initial="a">
  <state id="a"><transition event="t" target="h"/></state>
  <state id="p" initial="first">
    <history id="h" type="deep">
      <transition target="inner"><raise event="go"/></transition>
    </history>
    <state id="first"/>
    <state id="q">
      <state id="x"/><state id="inner"><transition event="go" target="pass"/></state>
    </state>
  </state>
  <final id="pass"/>
</scxml>
""")
    (tmp_path / "h.json").write_text('{"initialConfiguration": ["a"], "events": '
                                     '[{"event": {"name": "t"}, "nextConfiguration": ["pass"]}]}')
    outcome = run_test(chart)
    assert outcome.passed, outcome.reason


def test_freezing_a_parent_freezes_its_children(parent_text):
    instance, _, clock = run(parent_text.replace("AUTO", "autoforward: false"))
    instance.freeze()
    clock.advance(5)  # the child's 2 s timeout is frozen with it
    assert instance.configuration == ("ask",)
    instance.thaw()
    clock.advance(2)
    assert instance.configuration == ("ended",)


def test_children_are_silent_unless_the_listener_asks(parent_text):
    class Parent(Record):
        def invoking(self, instance, state, invoke):  # type: ignore[override]
            return None

    record = Parent()
    instance = compile_scheme(scheme(parent_text.replace("AUTO", "autoforward: true"))).start(
        clock=SimulatedClock(), listener=record)
    instance.send("finish")
    assert record.seen == ["top:enter:ask", "top:exit:ask", "top:enter:ended"]
