"""Events between an invoking scheme and its children: ``send`` with ``to:``.

After the intent of the W3C SCXML tests on ``<send target="#_parent">`` and
``"#_INVOKEID"`` (191, 192, 207, 229, 232, 236, 252, 347), written as
schemes and as small charts of our own; the W3C files themselves run in
``tests/test_w3c.py`` when they are at hand.
"""

from __future__ import annotations

import textwrap

import pytest
from conftest import problems

from shary.io.schemes import parse_scheme
from shary.io.scxml import import_scxml
from shary.statechart.clock import SimulatedClock
from shary.statechart.compiler import compile_scheme
from shary.statechart.conformance import run_test
from shary.statechart.instance import LivelockError
from userfiles.errors import FileError
from userfiles.yamlsafe import load_text


def start(text: str):
    clock = SimulatedClock()
    scheme = parse_scheme(load_text(textwrap.dedent(text)))
    return compile_scheme(scheme).start(clock=clock), clock


PING_PONG = """\
    scheme: parent
    initial: talk
    states:
      talk:
        invoke:
          id: kid
          scheme:
            scheme: kid
            initial: hello
            states:
              hello:
                on_entry: [{send: ready, to: parent}]
                on: {ping: {target: bye, do: [{send: pong, to: parent}]}}
              bye: {final: true}
        initial: waiting
        states:
          waiting:
            on: {ready: {target: asked, do: [{send: ping, to: kid}]}}
          asked:
            on: {pong: heard}
          heard:
            on: {done.invoke.kid: ended}
      ended: {final: true}
"""


def test_parent_and_child_talk_by_parent_and_invoke_id():
    instance, _ = start(PING_PONG)
    assert instance.finished and instance.configuration == ("ended",)


def test_a_childs_events_come_before_its_done_invoke_even_from_its_final_on_exit():
    instance, _ = start("""\
        scheme: parent
        initial: s0
        states:
          s0:
            invoke:
              scheme:
                scheme: kid
                initial: end
                states:
                  end: {final: true, on_entry: [{send: one, to: parent}],
                        on_exit: [{send: two, to: parent}]}
            initial: a
            states:
              a: {on: {one: b}}
              b: {on: {two: c}}
              c: {on: {done.invoke: pass}}
            on: {"*": fail}
          pass: {final: true}
          fail: {final: true}
    """)
    assert instance.configuration == ("pass",)


def test_a_child_heard_while_its_parent_is_idle_is_heard_in_order():
    instance, clock = start("""\
        scheme: parent
        initial: s0
        states:
          s0:
            invoke:
              scheme:
                scheme: kid
                initial: wait
                states:
                  wait: {on: {after 1s: {target: end, do: [{send: late, to: parent}]}}}
                  end: {final: true}
            initial: a
            states:
              a: {on: {late: b}}
              b: {on: {done.invoke: pass}}
            on: {"*": fail}
          pass: {final: true}
          fail: {final: true}
    """)
    clock.advance(1.0)
    assert instance.configuration == ("pass",)


def test_a_cancelled_child_is_not_heard_and_its_delayed_sends_die_with_it():
    instance, clock = start("""\
        scheme: parent
        initial: s0
        states:
          s0:
            on_entry: [{send: leave}]
            invoke:
              scheme:
                scheme: kid
                initial: wait
                states:
                  wait:
                    on_entry: [{send: later, to: parent, delay: 1s}]
                    on_exit: [{send: bye, to: parent}]
                    on: {after 5s: end}
                  end: {final: true}
            on: {leave: s1}
          s1:
            on: {bye: fail, later: fail, after 3s: pass}
          pass: {final: true}
          fail: {final: true}
    """)
    clock.advance(4.0)
    assert instance.configuration == ("pass",)


def test_autoforward_passes_a_childs_own_event_back_to_it():
    instance, clock = start("""\
        scheme: parent
        initial: s0
        states:
          s0:
            invoke:
              autoforward: true
              scheme:
                scheme: kid
                initial: sub0
                states:
                  sub0:
                    on_entry: [{send: childToParent, to: parent}]
                    on:
                      childToParent: {target: end, do: [{send: eventReceived, to: parent}]}
                      after 3s: end
                  end: {final: true}
            on:
              childToParent: {target: null}
              eventReceived: pass
              "*": fail
          pass: {final: true}
          fail: {final: true}
    """)
    assert instance.configuration == ("pass",)


def test_sends_to_nobody_raise_error_communication():
    instance, _ = start("""\
        scheme: lonely
        initial: s0
        states:
          s0:
            on_entry: [{send: hello, to: parent}]
            on: {error.communication: s1, "*": fail}
          s1:
            invoke:
              id: kid
              scheme: {scheme: kid, initial: end, states: {end: {final: true}}}
            on: {done.invoke.kid: s2}
          s2:
            on_entry: [{send: hello, to: kid}]
            on: {error.communication: pass, "*": fail}
          pass: {final: true}
          fail: {final: true}
    """)
    assert instance.configuration == ("pass",)


def test_a_zero_delay_ping_pong_between_parent_and_child_is_a_livelock():
    with pytest.raises(LivelockError, match="sent itself more than"):
        start("""\
            scheme: parent
            initial: s0
            states:
              s0:
                invoke:
                  id: kid
                  scheme:
                    scheme: kid
                    initial: k
                    states:
                      k:
                        on_entry: [{send: ping, to: parent}]
                        on: {pong: {target: null, do: [{send: ping, to: parent}]}}
                on: {ping: {target: null, do: [{send: pong, to: kid}]}}
        """)


@pytest.mark.parametrize("send, message", [
    ("{send: e, to: kidd}", "send to 'kidd': no invoke of this scheme has that id "
                            "(did you mean 'kid'?)"),
    ("{send: e, to: 3}", "string"),
])
def test_send_targets_are_checked(send, message):
    text = textwrap.dedent(f"""\
        scheme: s
        initial: a
        states:
          a:
            on_entry: [{send}]
            invoke:
              id: kid
              scheme: {{scheme: kid, initial: end, states: {{end: {{final: true}}}}}}
    """)
    with pytest.raises(FileError) as err:
        parse_scheme(load_text(text, "s.yaml"))
    (problem,) = err.value.problems
    assert message in problem.message and (problem.line, problem.col) == (5, 30)


def test_parent_is_no_invoke_id():
    with pytest.raises(FileError, match="invoke id 'parent' is reserved"):
        parse_scheme(load_text(textwrap.dedent("""\
            scheme: s
            initial: a
            states:
              a:
                invoke:
                  id: parent
                  scheme: {scheme: kid, initial: end, states: {end: {final: true}}}
        """)))


CHART = """\
<scxml xmlns="http://www.w3.org/2005/07/scxml" version="1.0" initial="s0">
  <state id="s0" initial="s01">
    <onentry><send event="timeout" delay="5s"/></onentry>
    <invoke type="scxml" id="invokedChild" src="file:child%20one.scxml"/>
    <transition event="timeout" target="fail"/>
    <state id="s01">
      <transition event="childToParent" target="s02">
        <send target="#_invokedChild" event="parentToChild"/>
      </transition>
    </state>
    <state id="s02"><transition event="eventReceived" target="pass"/></state>
  </state>
  <final id="pass"/>
  <final id="fail"/>
</scxml>
"""

CHILD = """\
<scxml xmlns="http://www.w3.org/2005/07/scxml" version="1.0" initial="sub0">
  <state id="sub0">
    <onentry><send event="childToParent" target="#_parent"/></onentry>
    <transition event="parentToChild" target="subFinal">
      <send target="#_parent" event="eventReceived"/>
    </transition>
  </state>
  <final id="subFinal"/>
</scxml>
"""


def test_scxml_sends_between_parent_and_a_file_uri_child(write):
    write("child one.scxml", CHILD)
    chart = write("parent.scxml", CHART)
    text = import_scxml(chart)
    assert "to: invokedChild" in text and "to: parent" in text
    assert run_test(chart).passed


def test_scxml_history_default_names_a_later_state_only_it_leads_to(write):
    chart = write("h.scxml", """\
        <scxml xmlns="http://www.w3.org/2005/07/scxml" version="1.0" initial="s1">
          <state id="s0" initial="a">
            <history id="hs" type="shallow"><transition target="a"/></history>
            <history id="hd" type="deep"><transition target="b"/></history>
            <state id="a"><transition target="pass"/></state>
            <state id="b"/>
          </state>
          <state id="s1"><transition target="hs"/></state>
          <final id="pass"/>
        </scxml>
    """)
    assert import_scxml(chart).startswith("# Left out, since no run can ever enter them: hd, b")
    assert run_test(chart).passed


def test_scxml_send_to_an_unknown_place_is_refused(write, shary, tmp_path):
    chart = write("u.scxml", '<scxml xmlns="http://www.w3.org/2005/07/scxml">\n<state id="a">'
                  '<onentry><send event="e" target="#_no such"/></onentry></state></scxml>\n')
    status, _, err = shary("import-scxml", chart, "-o", tmp_path / "u.yaml")
    assert status == 2
    (m,) = problems(err)
    assert m["line"] == "2" and "cannot be an invoke id" in m["message"]
