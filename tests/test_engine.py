"""Behaviour of running schemes: acts, history, parallel regions, timeouts, guards, queues."""

from __future__ import annotations

import textwrap

import pytest

from shary import ConditionRegistry, SimulatedClock, compile_scheme, load_scheme
from shary.io.schemes import parse_scheme
from shary.statechart.instance import LivelockError, SchemeListener
from userfiles.yamlsafe import load_text


def scheme(text: str, conditions: ConditionRegistry | None = None):
    return parse_scheme(load_text(textwrap.dedent(text), "test.yaml"), conditions=conditions)


class Recorder(SchemeListener):
    def __init__(self):
        self.trace: list[str] = []

    def entered(self, instance, state, event):
        self.trace.append(f"+{state.name}")

    def exited(self, instance, state, event):
        self.trace.append(f"-{state.name}")

    def logged(self, instance, text):
        self.trace.append(f"log:{text}")

    def finished(self, instance, state):
        self.trace.append(f"finished:{state.name}")


@pytest.fixture
def give():
    return compile_scheme(load_scheme("give-object"))


def test_give_object_agreed_realized_ended(give):
    rec = Recorder()
    run = give.start(listener=rec)
    assert run.configuration == ("ask",)
    run.send("H-AGREE")
    assert run.configuration == ("realize",)
    run.send("done")
    run.send("done")
    assert run.finished and run.configuration == ("ended",)
    assert rec.trace == ["+ask", "-ask", "+realize", "-realize", "+end", "-end", "+ended",
                         "finished:ended"]


def test_give_object_refused_goes_to_end(give):
    run = give.start()
    run.send("H-DISAGREE")
    assert run.configuration == ("end",)


def test_give_object_silence_gives_up_on_the_clock(give):
    clock = SimulatedClock()
    run = give.start(clock=clock)
    clock.advance(14.9)
    assert run.configuration == ("ask",)
    clock.advance(0.2)
    assert run.configuration == ("give-up",)


def test_timeout_cancelled_when_the_state_is_left(give):
    clock = SimulatedClock()
    run = give.start(clock=clock)
    run.send("H-AGREE")
    clock.advance(100)
    assert run.configuration == ("realize",)
    assert clock.next_due() is None


def test_events_after_the_end_are_ignored(give):
    run = give.start()
    run.send("H-DISAGREE")
    run.send("done")
    run.send("H-AGREE")
    assert run.configuration == ("ended",) and run.finished


def test_states_carry_acts_and_act_types():
    s = load_scheme("ask-help")
    assert (s.state("ask").act, s.state("ask").act_type.name) == ("ASK-HELP", "R-ACT")
    assert (s.state("helping").act, s.state("helping").act_type.name) == ("REALIZE-TASK",
                                                                          "H-ACT")


def test_attentive_variant_resumes_where_it_stopped():
    clock = SimulatedClock()
    run = compile_scheme(load_scheme("give-object-attentive")).start(clock=clock)
    run.send("H-AGREE")
    run.send("reached")
    assert run.configuration == ("handover",)
    run.send("attention-lost")
    assert run.configuration == ("suspended",)
    assert run.is_active("realize")
    clock.advance(29)
    run.send("attention-back")
    assert run.configuration == ("handover",)


def test_attentive_variant_gives_up_when_attention_never_returns():
    clock = SimulatedClock()
    run = compile_scheme(load_scheme("give-object-attentive")).start(clock=clock)
    run.send("H-AGREE")
    run.send("attention-lost")
    clock.advance(30)
    assert run.configuration == ("give-up",)


HISTORY = """\
    scheme: h
    initial: outer
    states:
      outer:
        initial: a
        on: {pause: paused}
        states:
          a:
            initial: a1
            states:
              a1: {on: {next: a2}}
              a2: {on: {side: b}}
          b: {}
          shallow: {history: shallow}
          deep: {history: deep}
      paused:
        on: {back-shallow: shallow, back-deep: deep}
    """


@pytest.mark.parametrize("back, expected", [("back-shallow", ("a1",)), ("back-deep", ("a2",))])
def test_shallow_and_deep_history(back, expected):
    run = compile_scheme(scheme(HISTORY)).start()
    run.send("next")
    run.send("pause")
    run.send(back)
    assert run.configuration == expected


def test_history_default_when_never_visited():
    text = HISTORY.replace("initial: outer", "initial: paused")
    run = compile_scheme(scheme(text)).start()
    run.send("back-deep")
    assert run.configuration == ("a1",)


PARALLEL = """\
    scheme: p
    initial: together
    states:
      together:
        parallel: true
        on: {done.state.together: over}
        states:
          arm:
            initial: moving
            states:
              moving: {on: {reached: holding}}
              holding: {on: {taken: arm-done}}
              arm-done: {final: true}
          watch:
            initial: attending
            states:
              attending: {on: {look-away: away}}
              away: {on: {look-back: attending, taken: watch-done}}
              watch-done: {final: true}
      over: {final: true}
    """


def test_parallel_regions_and_done_events():
    run = compile_scheme(scheme(PARALLEL)).start()
    assert run.configuration == ("moving", "attending")
    run.send("reached")
    run.send("look-away")
    assert run.configuration == ("holding", "away")
    run.send("taken")  # both regions take it in one step, then done.state.together fires
    assert run.configuration == ("over",) and run.finished


def test_conflicting_transitions_between_regions_resolved_in_document_order():
    text = """\
        scheme: c
        initial: p
        states:
          p:
            parallel: true
            states:
              r1:
                initial: x
                states:
                  x: {on: {go: out1}}
              r2:
                initial: y
                states:
                  y: {on: {go: out2}}
          out1: {}
          out2: {}
        """
    run = compile_scheme(scheme(text)).start()
    run.send("go")
    assert run.configuration == ("out1",)


def test_guards_name_registered_conditions_and_can_be_negated():
    conditions = ConditionRegistry()
    ready = {"value": False}
    conditions.register("partner-ready", lambda instance, event: ready["value"])
    text = """\
        scheme: g
        initial: a
        states:
          a:
            on:
              go:
                - {target: b, guard: partner-ready}
                - {target: c, guard: not partner-ready}
          b: {}
          c: {}
        """
    compiled = compile_scheme(scheme(text, conditions), conditions)
    first = compiled.start()
    first.send("go")
    ready["value"] = True
    second = compiled.start()
    second.send("go")
    assert (first.configuration, second.configuration) == (("c",), ("b",))


def test_conditions_see_the_event_data():
    conditions = ConditionRegistry()
    conditions.register("from-alice", lambda instance, event: event.data == "alice")
    text = """\
        scheme: d
        initial: a
        states:
          a: {on: {H-AGREE: {target: b, guard: from-alice}}}
          b: {}
        """
    run = compile_scheme(scheme(text, conditions), conditions).start()
    run.send("H-AGREE", "bob")
    assert run.configuration == ("a",)
    run.send("H-AGREE", "alice")
    assert run.configuration == ("b",)


def test_unregistered_condition_is_refused_at_compile_time():
    text = "scheme: d\ninitial: a\nstates:\n  a: {on: {go: {target: a, guard: nope}}}\n"
    with pytest.raises(KeyError, match="nope"):
        compile_scheme(scheme(text))


def test_targetless_transition_runs_actions_without_leaving():
    text = """\
        scheme: t
        initial: a
        states:
          a:
            on_exit: [{log: left}]
            on: {ping: {do: [{log: pong}]}}
        """
    rec = Recorder()
    run = compile_scheme(scheme(text)).start(listener=rec)
    run.send("ping")
    assert rec.trace == ["+a", "log:pong"]


def test_raised_events_run_before_outside_ones_and_eventless_before_raised():
    text = """\
        scheme: q
        initial: a
        states:
          a: {on: {go: {target: b, do: [{raise: inner}]}}}
          b: {on: {always: c, inner: fail}}
          c: {on: {inner: d, outer: fail}}
          d: {}
          fail: {}
        """
    rec = Recorder()
    compiled = compile_scheme(scheme(text))
    run = compiled.start(listener=rec)

    class Sender(SchemeListener):
        def entered(self, instance, state, event):
            if state.name == "b":
                instance.send("outer")  # queued: the instance is busy

    run.listener = Sender()
    run.send("go")
    assert run.configuration == ("d",)


def test_delayed_send_and_cancel():
    text = """\
        scheme: s
        initial: a
        states:
          a:
            on_entry: [{send: ring, delay: 2s, id: alarm}, {send: other, delay: 1s}]
            on: {ring: rang, other: {do: [{cancel: alarm}]}}
          rang: {}
        """
    clock = SimulatedClock()
    run = compile_scheme(scheme(text)).start(clock=clock)
    clock.advance(5)
    assert run.configuration == ("a",)


def test_eventless_loop_is_reported_not_hung():
    text = "scheme: l\ninitial: a\nstates:\n  a: {on: {always: b}}\n  b: {on: {always: a}}\n"
    with pytest.raises(LivelockError):
        compile_scheme(scheme(text)).start()


def test_underscores_and_dashes_in_names():
    text = """\
        scheme: names
        initial: ASK_TASK_state
        states:
          ASK_TASK_state:
            initial: inner_one
            states:
              inner_one: {on: {go_now: inner-two}}
              inner-two: {}
        """
    run = compile_scheme(scheme(text)).start()
    run.send("go_now")
    assert run.configuration == ("inner-two",)


def test_instances_share_one_compiled_machine(give):
    runs = [give.start() for _ in range(200)]
    for i, run in enumerate(runs):
        run.send("H-AGREE" if i % 2 else "H-DISAGREE")
    states_before = give.flat_states
    more = [give.start() for _ in range(200)]
    for run in more:
        run.send("H-AGREE")
    assert give.flat_states == states_before
    assert {r.configuration for r in runs} == {("realize",), ("end",)}
    assert not hasattr(runs[0], "__dict__")
