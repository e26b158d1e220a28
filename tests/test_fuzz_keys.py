"""The ``keys-matter`` invariant (sim/fuzz/keys.py): every key a campaign draws changes the
run it is drawn for, each key run again without it; and the cues that say when a key's
moment came in a run."""

from __future__ import annotations

import dataclasses

import pytest

from sim.fuzz.behaviours import draw
from sim.fuzz.campaign import run_one
from sim.fuzz.drawn import Drawn
from sim.fuzz.keys import Follower, keys_matter, reached, same_without
from sim.run import run_scenario
from sim.scenario import builtin_scenarios


def _run(variation):
    return variation.run()


def test_a_key_the_simulation_ignores_is_a_violation():
    """A drawn key that changes nothing (here the scenario's ``doc``, which only
    describes it) is found: the run without it is the same, row for row."""
    variation = draw("stack", 5)
    ignored = Drawn("a word about the run", (("scenario", "doc"),))
    variation = dataclasses.replace(variation, keys=(*variation.keys, ignored))
    result = _run(variation)
    seen, _ = keys_matter(variation, result.events, result.truth)
    assert seen == ("drawn 'a word about the run' changed nothing: the run without it is "
                    "the same")


def test_every_key_a_stack_run_draws_changes_it():
    variation = draw("stack", 5)
    assert variation.keys, "seed 5 draws a behaviour"
    result = _run(variation)
    for key in variation.keys:
        assert reached(key.cue, result.events), key.says
        assert not same_without(variation, key, result.events, result.truth), key.says


def test_a_key_whose_moment_never_came_is_counted_not_run_again(monkeypatch):
    variation = draw("stack", 5)
    late = Drawn("looks away in an hour", (("scenario", "doc"),), cue=("at", 3600.0))
    variation = dataclasses.replace(variation, keys=(late,))
    result = _run(variation)
    ran = []
    monkeypatch.setattr("sim.fuzz.keys.same_without", lambda *a: ran.append(a) or True)
    assert keys_matter(variation, result.events, result.truth) == (None, 1)
    assert ran == []


def test_the_run_without_a_key_stops_at_its_first_different_row():
    rows = [(0.0, "speech", None, "jido", {"text": "Hello."}),
            (1.0, "speech", None, "jido", {"text": "Goodbye."})]
    follower = Follower(rows)
    follower.observe(0.0, "speech", None, "jido", {"text": "Hello."})
    follower.between(0.5)  # the same so far: the run goes on
    follower.observe(1.0, "speech", None, "jido", {"text": "Bye."})
    with pytest.raises(Exception) as stopped:
        follower.between(1.5)
    assert type(stopped.value).__name__ == "_Diverged"


def test_a_drawn_default_is_not_a_key():
    """What a person does unasked is not drawn as a key: a stack partner's default delay
    and decision wait, the plan's first option, a weld person's "yes", silence where their
    profile has no answer, a seam the base scenario never welds."""
    for seed in range(1, 301):
        for family in ("stack", "weld", "living-room", "dialogue"):
            for key in draw(family, seed).keys:
                says = key.says
                assert says not in ("delay 1s", "decides within 6s"), (family, seed, says)
                assert not says.startswith(("decision 1: placement_1", "decision 1: Place",
                                            "decision 1: Pick")), (family, seed, says)
                assert not says.endswith("answers yes"), (family, seed, says)
                assert "P1-P2" not in says, (family, seed, says)
                assert not (says.endswith("-> silence") and key.cue[3] == 1
                            and key.unasked is None), (family, seed, says)


def test_each_cue_reads_its_moment_from_the_rows():
    give = run_scenario(builtin_scenarios()["give-bottle"], seed=1).events
    assert reached((), give)
    assert reached(("at", 5.0), give) and not reached(("at", 1e6), give)
    assert reached(("asked", "ASK-TASK", "alice", 1), give)
    assert not reached(("asked", "ASK-TASK", "alice", 2), give)
    assert not reached(("asked", "ASK-HELP", "alice", 1), give)
    assert reached(("answered", "ASK-TASK", "alice", 1, "H-AGREE"), give)
    assert not reached(("answered", "ASK-TASK", "alice", 2, "H-AGREE"), give)  # asked once
    assert not reached(("answered", "ASK-TASK", "alice", 1, "H-DISAGREE"), give)
    assert reached(("starts", "give", "alice"), give)
    assert not reached(("starts", "pick", "alice"), give)  # a pick is not towards her
    assert reached(("exec", "navigate"), give) and not reached(("exec", "dump"), give)
    assert reached(("offered", "alice", 0.5, None), give)
    assert not reached(("offered", "alice", 0.5, 1.0), give)  # she walked out first
    assert not reached(("offered", "alice", 1e3, None), give)  # she took it long before
    assert not reached(("blink", "isHolding"), give)  # no noise: nothing blinks
    help_ = run_scenario(builtin_scenarios()["clean-up-unreachable"], seed=1).events
    assert reached(("agreed", "ASK-HELP", "alice"), help_)
    assert not reached(("agreed", "ASK-TASK", "alice"), help_)
    stack = _run(draw("stack", 5)).events
    assert reached(("decided", draw("stack", 5).scenario["shared-plan"]["partner"], 1), stack)
    assert reached(("done", "Pick(pr2, red_cube_1)"), stack)
    assert not reached(("done", "Fly(pr2"), stack)
    weld = run_scenario(builtin_scenarios()["weld-nominal"], seed=1).events
    assert reached(("row", "message", "tasks", {"to": "EVA1", "type": "assignment"}), weld)
    assert reached(("row", "exec-request", None, {"atomic": "weld",
                                                  "args": {"seam": "P2-P3"}}), weld)
    assert not reached(("row", "exec-request", None, {"atomic": "weld",
                                                      "args": {"seam": "P1-P2"}}), weld)


def test_a_flicker_that_gets_past_the_hold_is_a_blink():
    variation = next(v for v in (draw("stack", s) for s in range(1, 60))
                     if (v.scenario.get("noise") or {}).get("hold") == "0s")
    predicate, = variation.scenario["noise"]["flicker"]
    assert reached(("blink", predicate), _run(variation).events)


def test_a_look_away_during_another_is_not_reached():
    """Seed 30 draws a look-away when the robot's first pick starts and another as the
    pick fails and is tried again 0.2 s later: the second turns no head."""
    variation = draw("stack", 30)
    result = _run(variation)
    aways = [k for k in variation.keys if k.cue and k.cue[0] == "away"]
    assert [reached(k.cue, result.events) for k in aways] == [True, False]


@pytest.mark.parametrize(("family", "seed"), [("weld", 2), ("living-room", 3)])
def test_keys_matter_is_judged_in_a_campaign_run(family, seed):
    outcome = run_one(family, seed)
    assert "keys-matter" not in outcome.violations
    assert outcome.keys == len(draw(family, seed).keys)
    assert 0 <= outcome.unreached <= outcome.keys


def test_a_person_whose_first_look_a_flicker_hides_is_still_seen():
    """Living-room seed 32: looksAt flickers from the start and nothing moves while the
    robot waits for her to engage; perception stopped looking, so she was never seen and
    her ``attention: store-table`` changed nothing (keys-matter found it)."""
    variation = draw("living-room", 32)
    result = _run(variation)
    assert any(r[1] == "fact-added" and r[4]["s"] == "alice" and r[4]["p"] == "looksAt"
               for r in result.events)
    assert keys_matter(variation, result.events, result.truth)[0] is None


def test_a_member_killed_before_replying_never_has_the_moment():
    """Weld seed 241: IVA is asked at 34 s and killed at 38 s, before the reply drawn
    (1–30 s): the reply's moment never came, so it is not run again (nor a violation)."""
    variation = draw("weld", 241)
    result = _run(variation)
    replies, = (k for k in variation.keys if k.says == "IVA answers questions")
    assert not reached(replies.cue, result.events)
    assert keys_matter(variation, result.events, result.truth) == (None, 1)
