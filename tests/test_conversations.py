"""Conversations that stay right when people do the unexpected: the regression scenarios
of what the robot said wrong (judged by every campaign invariant), and the invariants that
see conversations, each shown to fail on the rows of the run it forbids."""

from __future__ import annotations

from types import SimpleNamespace

import pytest

from sim.fuzz.campaign import judge
from sim.fuzz.invariants import INVARIANTS, Run
from sim.run import run_scenario
from sim.scenario import builtin_scenarios, load_scenario

REGRESSIONS = {
    "stack-failure-said-on-the-phone": "stack",
    "stack-told-across-a-replan": "stack",
    "stack-inform-waits-for-the-head": "stack",
    "stack-partner-walks-out": "stack",
    "give-bottle-walks-out": "living-room",
}


@pytest.fixture(scope="module")
def runs():
    found = {}
    for name, family in REGRESSIONS.items():
        scenario = load_scenario(builtin_scenarios()[name])
        found[name] = (scenario, run_scenario(scenario), family)
    return found


@pytest.mark.parametrize("name", sorted(REGRESSIONS))
def test_the_regression_meets_its_expectations_and_every_invariant(runs, name):
    scenario, result, family = runs[name]
    assert result.passed, result.differences
    _, _, violations = judge(family, scenario, result)
    assert violations == {}


def _rows(runs, name, *kinds):
    return [(t, kind, task, agent, data) for t, kind, task, agent, data in runs[name][1].events
            if kind in kinds]


def test_a_failed_plan_says_why_to_a_partner_on_the_phone_at_once(runs):
    (at, _, _, _, end), = _rows(runs, "stack-failure-said-on-the-phone", "plan-end")
    said = [(t, d["text"]) for t, _, _, a, d in _rows(runs, "stack-failure-said-on-the-phone",
                                                      "speech") if a == "pr2"]
    assert (at, end["text"]) in said


def test_nothing_is_said_to_a_partner_who_walked_out_and_why_is_logged_unheard(runs):
    name = "stack-partner-walks-out"
    farewell = next(t for t, _, _, _, d in _rows(runs, name, "act")
                    if d["act"] == "FAREWELL")
    after = [d["text"] for t, _, _, a, d in _rows(runs, name, "speech")
             if a == "pr2" and t >= farewell]
    assert after == ["Goodbye, Alice."]
    (_, _, _, _, end), = _rows(runs, name, "plan-end")
    assert any(who == "alice" and d["text"] == end["text"]
               for _, _, _, who, d in _rows(runs, name, "unheard"))


def test_a_hand_over_ends_when_the_partner_leaves_with_that_reason(runs):
    name = "give-bottle-walks-out"
    farewell = next(t for t, _, _, _, d in _rows(runs, name, "act")
                    if d["act"] == "FAREWELL")
    (over, _, _, _, goal), = _rows(runs, name, "goal-over")
    assert goal["outcome"] == "cancelled" and goal["reason"] == "alice left"
    assert over == farewell


# -- the invariants, on the rows they forbid --------------------------------------------

def _run(rows, family="stack", people=("alice",)):
    return Run(family, rows, frozenset(), 60.0, 300.0, "pr2", people,
               SimpleNamespace(team=None))


def _check(name, run):
    invariant = next(i for i in INVARIANTS if i.name == name)
    return invariant.check(run)


def _look(t, kind="fact-added", who="alice"):
    return (t, kind, None, None, {"s": who, "p": "looksAt", "o": "pr2",
                                  "perspective": "robot"})


def _inform_rows(task, text, at, said_at, achieved_at, node):
    return [(achieved_at, "plan-task", task, "pr2", {"state": "EXECUTED"}),
            (at, "inform", task, "alice", {"text": text}),
            (at, "task-start", node, "pr2", {"name": "inform",
                                             "roles": {"partner": "alice", "robot": "pr2"}}),
            (said_at, "speech", None, "pr2", {"text": text}),
            (said_at + 1, "task-end", node, None, {"state": "told"})]


def test_order_sees_a_later_event_told_first():
    rows = sorted(_inform_rows("P-1-2", "I picked up the red cube.", 1, 9, 1, "n8")
                  + _inform_rows("P-2-2", "I placed the red cube.", 7, 8, 7, "n9"),
                  key=lambda r: r[0])
    assert "I picked up the red cube." in _check("order", _run(rows))
    rows = sorted(_inform_rows("P-1-2", "I picked up the red cube.", 1, 8, 1, "n8")
                  + _inform_rows("P-2-2", "I placed the red cube.", 7, 9, 7, "n9"),
                  key=lambda r: r[0])
    assert _check("order", _run(rows)) is None


def test_belief_sees_a_told_task_left_not_seen():
    rows = _inform_rows("P-1-2", "I picked up the red cube.", 1, 8, 1, "n8")
    rows.insert(0, (1, "plan-task", "P-1-2", "alice", {"state": "NOT_SEEN"}))
    assert "not EXECUTED" in _check("belief", _run(rows))
    rows.append((9.5, "plan-task", "P-1-2", "alice", {"state": "EXECUTED"}))
    assert _check("belief", _run(rows)) is None


def test_belief_sees_a_missed_task_never_told_to_a_partner_who_looked_back():
    rows = [(1, "plan-task", "P-1-2", "alice", {"state": "NOT_SEEN"}), _look(5),
            (20, "shared-plan", None, "pr2", {"state": "achieved"})]
    assert "ended NOT_SEEN" in _check("belief", _run(rows))
    assert _check("belief", _run([rows[0], rows[2]])) is None


def test_no_call_while_looking_sees_a_call_to_someone_looking():
    start = (0, "task-start", "n8", "pr2", {"name": "inform",
                                            "roles": {"partner": "alice", "robot": "pr2"}})
    act = (10, "act", "n8", "pr2", {"act": "CALL-ATTENTION"})
    call = (10.4, "speech", None, "pr2", {"text": "Excuse me, Alice."})
    assert "while alice looks" in _check("no-call-while-looking",
                                         _run([start, act, _look(10.2), call]))
    assert _check("no-call-while-looking", _run([start, act, call])) is None


def test_after_farewell_sees_words_and_goals_for_someone_who_left():
    session = (0, "task-start", "n1", "pr2", {"name": "session",
                                              "roles": {"partner": "alice", "robot": "pr2"}})
    give = (1, "task-start", "n3", "pr2", {"name": "give-object",
                                           "roles": {"partner": "alice", "robot": "pr2"}})
    goal = (1, "goal-added", None, None, {"goal": 1, "name": "give-object",
                                          "args": {"partner": "alice"}})
    farewell = (27, "act", "n1", "pr2", {"act": "FAREWELL"})
    give_up = (52, "act", "n3", "pr2", {"act": "GIVE-UP"})
    busy = (52, "speech", None, "pr2", {"text": "You are busy."})
    over = (52, "goal-over", "n3", None, {"goal": 1, "outcome": "failed"})
    seen = _check("after-farewell", _run([session, give, goal, farewell, give_up, busy, over],
                                         "living-room"))
    assert "who had left" in seen
    seen = _check("after-farewell", _run([session, give, goal, farewell, over],
                                         "living-room"))
    assert "after their goodbye" in seen
    ended = (27, "goal-over", "n3", None, {"goal": 1, "outcome": "cancelled"})
    assert _check("after-farewell", _run([session, give, goal, farewell, ended],
                                         "living-room")) is None


def test_reason_heard_sees_a_reason_neither_said_nor_logged():
    end = (5, "plan-end", None, "alice", {"text": "I cannot go on."})
    assert "neither said" in _check("reason-heard", _run([end]))
    said = (5, "speech", None, "pr2", {"text": "I cannot go on."})
    assert _check("reason-heard", _run([end, said])) is None
    unheard = (5, "unheard", None, "alice", {"text": "I cannot go on."})
    assert _check("reason-heard", _run([end, unheard])) is None


def test_one_voice_sees_a_sentence_begun_over_another():
    stop = (12.0, "speech", None, "pr2", {"text": "All right, I will stop.", "request": "r7"})
    sorry = (15.0, "speech", None, "pr2", {"text": "Sorry?", "request": "r9"})
    said = (16.7, "exec-result", "n9", "pr2", {"request": "r7", "status": "done"})
    assert "while still saying 'All right, I will stop.'" in _check(
        "one-voice", _run([stop, sorry, said], "dialogue"))
    later = (16.7, "speech", None, "pr2", {"text": "Sorry?", "request": "r9"})
    assert _check("one-voice", _run([stop, said, later], "dialogue")) is None
    cut = (15.0, "exec-cancel", "n9", "pr2", {"request": "r7"})
    assert _check("one-voice", _run([stop, cut, sorry], "dialogue")) is None


def test_a_sentence_is_judged_with_the_people_of_the_task_that_said_it():
    """A sentence that waited for the voice is said after another task's act: it is
    said to the people of its own task (its speak request's place in the tree)."""
    def inform(node, act, step, partner, t):
        return [(t, "task-start", node, "pr2", {"name": "inform",
                                                "roles": {"partner": partner, "robot": "pr2"}}),
                (t, "node", act, "pr2", {"parent": node, "node_kind": "act", "act": "INFORM"}),
                (t, "node", step, "pr2", {"parent": act, "node_kind": "atomic"}),
                (t, "act", node, "pr2", {"act": "INFORM"})]
    rows = [*inform("n1", "n2", "n3", "alice", 0),
            (0, "exec-request", "n3", "pr2", {"atomic": "speak", "request": "r1"}),
            _look(0.5), *inform("n4", "n5", "n6", "bob", 1)]
    said = (2, "speech", None, "pr2", {"text": "The bottle is in the trash.", "request": "r1"})
    run = _run([*rows, said], people=("alice", "bob"))
    assert _check("told-unseen", run) is None
    unknown = (2, "speech", None, "pr2", {"text": "The bottle is in the trash."})
    assert "bob not looking" in _check("told-unseen", _run([*rows, unknown],
                                                           people=("alice", "bob")))
