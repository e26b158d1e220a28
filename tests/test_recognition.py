"""Human action recognition and robot action execution from action models, without the sim."""

from __future__ import annotations

import pytest

from shary.facts.database import FactDatabase
from shary.io.recipes import load_library
from shary.kernel.executors import ExecutorRegistry
from shary.kernel.loop import EventLoop
from shary.kernel.supervisor import Supervisor
from shary.log.contextlog import ContextLog
from shary.recognition.models import builtin_models, load_action_models
from shary.recognition.recognizer import Recognizer


class World:
    """A fact base with the stack task's models, a hand-moved clock and a recognizer."""

    def __init__(self) -> None:
        self.facts = FactDatabase()
        self.models = load_action_models([builtin_models("stack")], self.facts)
        self.now = 0.0
        self.rows: list[dict] = []
        for name, kind in [("alice", "Human"), ("bob", "Human"), ("pr2", "Robot"),
                           ("cube-1", "Cube"), ("cube-2", "Cube"), ("cube-3", "Cube"),
                           ("base-1", "Placement"), ("base-2", "Placement")]:
            self.facts.add(name, "type", kind)
        self.facts.add("cube-1", "isReachableBy", "alice")
        self.recognizer = Recognizer(self.models, self.facts, clock=lambda: self.now,
                                     record=lambda kind, **row: self.rows.append(row))
        self.recognizer.start()

    def at(self, t: float, change: str, s: str, p: str, o: str) -> None:
        self.now = t
        getattr(self.facts, change)(s, p, o)

    def seen(self) -> list[tuple]:
        return [(r["state"], r["action"], r.get("agent"), *r["params"].values())
                for r in self.rows]


@pytest.fixture
def world() -> World:
    return World()


def test_a_pick_then_a_place_are_started_by_moves_and_achieved_by_their_effects(world):
    world.at(1, "add", "alice", "handMovingToward", "cube-1")
    world.at(2, "add", "alice", "isHolding", "cube-1")
    world.at(3, "add", "alice", "handMovingToward", "base-1")
    world.at(4, "remove", "alice", "isHolding", "cube-1")
    world.at(4.2, "add", "cube-1", "isOn", "base-1")
    assert world.seen() == [
        ("started", "pick", "alice", "cube-1"),
        ("achieved", "pick", "alice", "cube-1"),
        ("started", "place", "alice", "cube-1", "base-1"),   # Pickable bound by the precondition
        ("progressing", "place", "alice", "cube-1", "base-1"),
        ("achieved", "place", "alice", "cube-1", "base-1")]
    assert world.rows[-1]["action_class"] == "HumanPlaceAction"
    assert world.rows[-1]["fact"] == "isOn(cube-1, base-1)"
    assert [r.action for r in world.recognizer.achieved] == ["pick", "place"]
    assert not world.recognizer.possibly_started and not world.recognizer.possibly_progressing


def test_a_cube_is_not_placed_on_itself(world):
    """Holding cube-1 and moving toward it (to put it down) binds Support and Pickable to
    one cube: no candidate places a thing on itself."""
    world.facts.add("cube-1", "type", "Support")
    world.at(1, "add", "alice", "isHolding", "cube-1")
    world.at(2, "add", "alice", "handMovingToward", "cube-1")
    assert ("started", "place", "alice", "cube-1", "cube-1") not in world.seen()


def test_a_gesture_achieved_as_one_action_is_no_other_action(world):
    """Alice, holding cube-2, moves her hand toward cube-1 and puts cube-2 on it: the pick
    of cube-1 the same move started ends with the place, instead of running on."""
    world.facts.add("cube-1", "type", "Support")  # a cube in a stack holds the next one
    world.at(1, "add", "alice", "isHolding", "cube-2")
    world.at(2, "add", "alice", "handMovingToward", "cube-1")
    world.at(3, "remove", "alice", "isHolding", "cube-2")
    world.at(3.2, "add", "cube-2", "isOn", "cube-1")
    seen = world.seen()
    assert ("started", "pick", "alice", "cube-1") in seen
    assert ("achieved", "place", "alice", "cube-2", "cube-1") in seen
    assert seen[-1] == ("abandoned", "pick", "alice", "cube-1")
    assert not world.recognizer.possibly_started


def test_a_hold_flickering_ten_times_during_a_place_is_one_place(world):
    world.at(1, "add", "alice", "isHolding", "cube-1")
    world.at(3, "add", "alice", "handMovingToward", "base-1")
    for i in range(10):
        world.at(3.1 + i * 0.1, "remove", "alice", "isHolding", "cube-1")
        world.at(3.15 + i * 0.1, "add", "alice", "isHolding", "cube-1")
    world.at(4.5, "remove", "alice", "isHolding", "cube-1")
    world.at(4.6, "add", "cube-1", "isOn", "base-1")
    assert world.seen() == [
        ("achieved", "pick", "alice", "cube-1"),            # seen holding: an effect seen
        ("started", "place", "alice", "cube-1", "base-1"),
        ("progressing", "place", "alice", "cube-1", "base-1"),
        ("achieved", "place", "alice", "cube-1", "base-1")]


def test_an_effect_without_a_start_goes_to_a_human_who_was_near_or_to_nobody(world):
    world.at(1, "add", "bob", "isNear", "base-2")
    world.at(2, "add", "cube-2", "isOn", "base-2")         # nobody was seen holding cube-2
    world.at(20, "add", "cube-3", "isOn", "base-1")        # nobody near cube-3 or base-1
    assert world.seen() == [("achieved", "place", "bob", "cube-2", "base-2"),
                            ("achieved", "place", None, "cube-3", "base-1")]
    assert [r["cause"] for r in world.rows] == ["near", "nobody"]


def test_nearness_fades_after_the_window(world):
    world.at(1, "add", "bob", "isNear", "base-2")
    world.at(2, "remove", "bob", "isNear", "base-2")
    world.at(2 + world.models.near_within + 1, "add", "cube-2", "isOn", "base-2")
    assert world.seen() == [("achieved", "place", None, "cube-2", "base-2")]


def test_a_place_by_someone_who_held_the_cube_a_moment_ago_is_theirs(world):
    world.at(1, "add", "bob", "isNear", "base-1")
    world.at(2, "add", "alice", "isHolding", "cube-1")
    world.at(5, "add", "cube-1", "isOn", "base-1")          # no move seen (looked away)
    world.at(5.5, "remove", "alice", "isHolding", "cube-1")  # the hold is let go after
    assert world.seen()[-1] == ("achieved", "place", "alice", "cube-1", "base-1")
    assert world.rows[-1]["cause"] == "before"


def test_what_the_robot_does_is_not_a_human_action(world):
    world.at(1, "add", "alice", "isNear", "base-1")
    world.at(2, "add", "pr2", "isHolding", "cube-1")
    world.at(3, "add", "pr2", "handMovingToward", "base-1")
    world.at(5, "remove", "pr2", "isHolding", "cube-1")
    world.at(5.5, "add", "cube-1", "isOn", "base-1")
    assert world.seen() == []


def test_a_candidate_left_alone_is_forgotten(world):
    world.at(1, "add", "alice", "handMovingToward", "cube-1")
    world.at(1 + world.models.forget + 1, "add", "bob", "isNear", "base-2")
    assert world.seen() == [("started", "pick", "alice", "cube-1"),
                            ("abandoned", "pick", "alice", "cube-1")]


def test_it_subscribes_to_exactly_the_predicates_the_models_name(world):
    watched = {world.facts.name(s._key[1]) for s in world.recognizer._subscriptions}
    assert watched == {*world.models.predicates(), "type", "rdf:type"}
    assert world.models.predicates() == ["handMovingToward", "isHolding", "isNear", "isOn",
                                         "isReachableBy"]
    world.at(1, "add", "alice", "looksAt", "cube-1")
    assert world.rows == []


class _Flaky:
    """An executor that fails its first ``failures`` requests, then succeeds."""

    def __init__(self, failures: int):
        self.failures = failures
        self.requests: list = []

    def start(self, request, reporter) -> None:
        self.requests.append(request)
        if len(self.requests) <= self.failures:
            reporter.failed(request, "the gripper slipped")
        else:
            reporter.done(request)

    def cancel(self, request) -> None:
        pass


class _Rows:
    def __init__(self) -> None:
        self.rows: list[tuple] = []

    def record(self, t, kind, *, task=None, agent=None, **data) -> None:
        self.rows.append((kind, data))


@pytest.mark.parametrize("failures, status, attempts", [(0, "done", 1), (1, "done", 2),
                                                         (2, "failed", 2)])
def test_a_robot_place_is_retried_then_its_failure_goes_to_the_task(failures, status, attempts):
    place, look = _Flaky(failures), _Flaky(0)
    loop, log = EventLoop(), _Rows()
    sup = Supervisor(load_library(), FactDatabase(), robot="pr2", loop=loop, log=log,
                     executors=ExecutorRegistry({"place": place, "look-at": look}))
    sup.recognize(load_action_models([builtin_models("stack")], sup.facts))
    results = []
    sup.robot_actions.perform("place", {"Pickable": "cube-1", "Support": "base-1"}, "n1",
                              results.append)
    loop.run_until_idle()
    [result] = results
    assert (result.status, result.attempts) == (status, attempts)
    assert [r.args for r in look.requests] == [{"target": "base-1"}]
    assert all(r.args == {"object": "cube-1", "on": "base-1"} for r in place.requests)
    if status == "failed":
        assert result.reason == "max_attempts (2) reached: the gripper slipped"
    states = [d["state"] for kind, d in log.rows if kind == "robot-action"]
    assert states == ["started", *["retry"] * (attempts - 1), status]


def test_recognitions_are_in_the_context_log_for_shary_log(tmp_path, capsys):
    from shary.cli import main

    path = tmp_path / "run.sqlite"
    loop = EventLoop()
    with ContextLog(path) as log:
        sup = Supervisor(load_library(), FactDatabase(), loop=loop, log=log)
        sup.facts.add("alice", "type", "Human")
        sup.recognize(load_action_models([builtin_models("living-room")], sup.facts))
        sup.facts.add("alice", "isHolding", "bottle")
    assert main(["log", str(path), "--kind", "recognition", "--json"]) == 0
    out = capsys.readouterr().out
    assert '"state": "achieved"' in out and '"action": "pick"' in out


def test_a_hold_seen_back_after_a_long_gap_is_not_a_second_pick(world):
    world.at(1, "add", "alice", "isHolding", "cube-1")
    world.at(2, "remove", "alice", "isHolding", "cube-1")
    world.at(6, "add", "alice", "isHolding", "cube-1")       # perception lost it for 4 s
    assert [s for s in world.seen() if s[0] == "achieved"] == [
        ("achieved", "pick", "alice", "cube-1")]


def test_a_removal_nothing_started_counts_once_it_lasts(world):
    world.at(1, "add", "alice", "isHolding", "cube-1")
    world.at(10, "remove", "alice", "isHolding", "cube-1")
    world.at(10.2, "add", "alice", "isHolding", "cube-1")    # flicker: forgotten
    world.at(20, "remove", "alice", "isHolding", "cube-1")
    world.at(20.5, "add", "bob", "isNear", "base-2")          # not yet a second
    assert world.seen()[1:] == []
    world.at(21.5, "add", "bob", "isNear", "base-1")          # lasted: possibly placing
    assert world.seen()[1:] == [("progressing", "place", "alice", "cube-1", None)]


def test_a_move_after_an_effect_joins_the_candidate_the_effect_made(world):
    world.at(1, "add", "alice", "isHolding", "cube-1")
    world.at(10, "remove", "alice", "isHolding", "cube-1")
    world.at(12, "add", "alice", "handMovingToward", "base-1")
    [joined] = world.recognizer.candidates["place"].values()
    assert joined.binding == {"Human": "alice", "Pickable": "cube-1", "Support": "base-1"}
    world.at(13, "add", "cube-1", "isOn", "base-1")
    assert world.seen()[1:] == [("progressing", "place", "alice", "cube-1", None),
                                ("achieved", "place", "alice", "cube-1", "base-1")]
    assert world.rows[-1]["candidate"] == world.rows[-2]["candidate"] == joined.id


def test_the_timeline_shows_each_recognized_action_in_its_humans_lane(world):
    import xml.etree.ElementTree as ET

    from shary.log.contextlog import LogEvent
    from shary.log.timeline import render_timeline

    world.at(1, "add", "alice", "handMovingToward", "base-1")   # no hold: no candidate
    world.at(2, "add", "alice", "isHolding", "cube-1")
    world.at(3, "add", "alice", "handMovingToward", "base-2")
    world.at(4, "remove", "alice", "isHolding", "cube-1")
    world.at(5, "add", "cube-1", "isOn", "base-2")
    world.at(20, "add", "cube-3", "isOn", "base-1")            # nobody near
    events = [LogEvent(i, t, "recognition", None, row.get("agent"),
                       {k: v for k, v in row.items() if k != "agent"})
              for i, (t, row) in enumerate(zip([2, 3, 4, 5, 20], world.rows, strict=True))]
    root = ET.fromstring(render_timeline(events, "recognized"))
    ns = "{http://www.w3.org/2000/svg}"
    bars = {g.get("data-candidate"): g for g in root.iter(f"{ns}g")
            if "recognized" in g.get("class", "").split()}
    assert sorted((g.get("data-agent"), g.get("data-action"), g.get("data-state"))
                  for g in bars.values()) == [("(nobody)", "place", "achieved"),
                                              ("alice", "pick", "achieved"),
                                              ("alice", "place", "achieved")]
    place = bars[world.rows[1]["candidate"]]
    assert (place.get("data-start"), place.get("data-progressing"), place.get("data-end")) == (
        "3", "4", "5")
    assert place.find(f"{ns}polygon[@class='achieved']") is not None
    legend = [t.text for t in root.iter(f"{ns}text") if t.get("class") == "legend"]
    assert {"possibly started", "possibly progressing", "possibly achieved"} <= set(legend)


def test_a_scenario_naming_unknown_or_broken_action_models_is_refused(tmp_path):
    from hostile import assert_refused, run_inprocess

    models = tmp_path / "mine.yaml"
    models.write_text("action-models: mine\nhuman:\n  juggle: {agent: Human, "
                      "necessary: ['isOn(Human, Human)']}\n")
    scenario = tmp_path / "s.yaml"
    scenario.write_text("scenario: s\naction-models: [juggling, mine.yaml]\n"
                        "expect: {facts: []}\n")
    assert_refused(run_inprocess("validate", scenario), scenario, models,
                   message="no built-in action models 'juggling' \\(shipped: living-room, stack\\)")
    scenario.write_text("scenario: s\naction-models: [mine.yaml]\nexpect: {facts: []}\n")
    outcome = run_inprocess("validate", scenario)
    assert_refused(outcome, scenario, models, message="depends on action models with errors")
    assert "no class of the action ontology is called 'juggle'" in outcome.err


def test_a_models_file_brings_its_own_classes_in_turtle(tmp_path):
    (tmp_path / "kinds.ttl").write_text(
        "@prefix w: <http://shary.dev/world#> .\n"
        "@prefix rdfs: <http://www.w3.org/2000/01/rdf-schema#> .\n"
        "w:Mug rdfs:subClassOf w:Pickable .\n"
        "w:HumanPickMug rdfs:subClassOf w:HumanPickAction .\n")
    (tmp_path / "mugs.yaml").write_text(
        "action-models: mugs\nontology: [kinds.ttl]\nhuman:\n  pick-mug:\n"
        "    class: HumanPickMug\n    agent: Human\n    params: {Pickable: Mug}\n"
        "    necessary: ['isHolding(Human, Pickable)']\n")
    facts = FactDatabase()
    models = load_action_models([tmp_path / "mugs.yaml"], facts)
    assert models.human["pick-mug"].action_class == "HumanPickMug"
    assert models.ontology.label("HumanPickMug") == "{Agent} @Pick_up {Pickable}"
    assert facts.holds("Mug", "rdfs:subClassOf", "Pickable")
