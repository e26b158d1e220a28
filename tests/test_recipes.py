"""Recipe libraries: bad input refused with positions; planner and function recipes."""

from __future__ import annotations

from conftest import problems
from scripted import World

from shary.kernel.recipes import Step, Term

BASE = """\
predicates:
  isOn: an object lies on furniture
atomic:
  wave: {params: [to]}
tasks:
  greet:
    params: [person]
    roles: {partner: $person}
    scheme: give-object
"""


def _problems(shary, *paths) -> list[tuple[int, int, str]]:
    status, _, err = shary("validate", *paths)
    assert status == 2, err
    assert "Traceback" not in err
    return [(int(m["line"]), int(m["col"]), m["message"]) for m in problems(err)]


def test_a_good_library_passes(shary, write):
    path = write("ok.yaml", BASE + """\
        recipes:
          - task: greet
            act: ASK-TASK
            steps:
              - {do: wave, with: {to: $person}}
        """.replace("        ", ""))
    status, out, err = shary("validate", path)
    assert status == 0, err


def test_unknown_task_act_parameter_executor(shary, write):
    path = write("bad.yaml", BASE + """\
recipes:
  - task: gret
    act: ASK-TASK
  - task: greet
    act: ASK-TASKS
  - task: greet
    act: ASK-TASK
    steps:
      - {do: wav, with: {to: $person}}
      - {do: wave, with: {to: $persn}}
      - {do: wave, with: {too: $person}}
""")
    found = _problems(shary, path)
    text = " | ".join(m for _, _, m in found)
    assert "unknown task 'gret' (did you mean 'greet'?)" in text
    assert "unknown act 'ASK-TASKS'" in text
    assert "unknown atomic task 'wav' (did you mean 'wave'?)" in text
    assert "unknown parameter $persn (did you mean 'person'?)" in text
    assert "atomic task 'wave' has no parameter 'too'" in text
    assert "atomic task 'wave' needs to" in text
    lines = sorted({line for line, _, _ in found})
    assert lines == [11, 14, 18, 19, 20]


def test_act_not_in_the_tasks_scheme(shary, write):
    path = write("act.yaml", BASE + "recipes:\n  - {task: greet, act: ASK-HELP}\n")
    ((_, _, msg),) = _problems(shary, path)
    assert "carries out 'ASK-HELP'" in msg


def test_recipe_events_must_enter_the_act(shary, write):
    path = write("on.yaml", BASE + """\
recipes:
  - {task: greet, act: GIVE-UP, on: [after 15s, H-DISAGRE]}
  - {task: greet, act: END-TASK, on: [H-DISAGREE, done]}
""")
    ((line, col, msg),) = _problems(shary, path)
    assert (line, col) == (11, 49)  # at the event
    assert ("no transition of the scheme(s) of task 'greet' enters GIVE-UP on 'H-DISAGRE'"
            in msg and "events: after 15s, failed" in msg)


def test_the_event_that_entered_the_act_chooses_its_recipe():
    speech = {}
    for name, reply in (("yes", "H-AGREE"), ("no", "H-DISAGREE"), ("silence", None)):
        world = World()
        run = world.sup.start_task("give-object", {"object": "bottle", "partner": "alice"})
        if reply:
            world.run(0.5)
            world.sup.receive_act("alice", reply)
        world.run(40)
        speech[name] = [a.get("text") for _, n, a in world.executor.started if n == "speak"]
        assert run.ended
    assert speech["no"][-1] == "I will not give you the bottle."
    assert speech["silence"][-1] == "You did not answer, so I will not give you the bottle."
    assert speech["yes"][-1] == "I gave you the bottle."


def test_cyclic_ordering(shary, write):
    path = write("cycle.yaml", BASE + """\
recipes:
  - task: greet
    act: ASK-TASK
    steps:
      - {name: a, do: wave, with: {to: $person}, after: [c]}
      - {name: b, do: wave, with: {to: $person}}
      - {name: c, do: wave, with: {to: $person}}
""")
    ((line, _, msg),) = _problems(shary, path)
    assert "cycle" in msg and "a -> b -> c -> a" in msg and line == 14


def test_monitor_on_unknown_predicate(shary, write):
    path = write("mon.yaml", BASE + """\
recipes:
  - task: greet
    act: ASK-TASK
    monitors:
      - {added: [$person, looksAtt, $robot], emit: attention-back}
""")
    ((line, col, msg),) = _problems(shary, path)
    assert "unknown predicate 'looksAtt'" in msg and "did you mean 'looksAt'" in msg
    assert (line, col) == (14, 27)


def test_a_monitor_until_a_step_the_recipe_lacks(shary, write):
    path = write("until.yaml", BASE + """\
recipes:
  - task: greet
    act: ASK-TASK
    steps:
      - {do: wave, with: {to: $person}}
    monitors:
      - {removed: [$person, looksAt, $robot], emit: attention-lost, until: speak}
""")
    ((line, col, msg),) = _problems(shary, path)
    assert msg == "no step named 'speak' in this recipe"
    assert line == 16


def test_malformed_turtle(shary, write):
    path = write("world.ttl", "@prefix w: <http://shary.dev/world#> .\nw:a w:b w:c .\n"
                 "w:d w:e .\n")
    ((line, _, msg),) = _problems(shary, path)
    assert line == 3


def test_unknown_file_kind(shary, write):
    ((_, _, msg),) = _problems(shary, write("what.yaml", "hello: world\n"))
    assert "not a known kind of file (acts, scheme, recipes, domain, problem, profile, " in msg
    assert "scenario" in msg and "team" in msg and "action-models" in msg  # the parts' too


def test_chronicle_goal_needs_bound_variables(shary, write):
    path = write("chron.yaml", BASE + """\
chronicles:
  hello:
    events:
      - added: [$someone, isOn, sofa]
    goal: {task: greet, with: {person: $nobody}}
""")
    ((_, _, msg),) = _problems(shary, path)
    assert "$nobody is not bound" in msg


class PlannerDouble:
    """Test double: a fixed plan (the real planner lives in planner/)."""

    def __init__(self):
        self.calls = []

    def plan_steps(self, spec, args, facts):
        self.calls.append((spec.domain, spec.task, args))
        return [Step("navigate-1", "navigate", None, {"place": Term("const", args["place"])},
                     None, ()),
                Step("look-1", "look-at", None, {"target": Term("const", args["place"])},
                     None, ("navigate-1",))]


PLANNED = """\
tasks:
  survey:
    params: [place]
    scheme: robot-task
recipes:
  - task: survey
    act: REALIZE-TASK
    plan: {domain: living-room, task: survey-place, with: {place: $place}}
  - task: survey
    act: END-TASK
    function: say-done
"""


def test_planner_backed_and_function_recipes(write):
    planner = PlannerDouble()

    def say_done(run, recipe):
        return [Step("say", "speak", None, {"text": Term("const", f"{run.env['place']} seen")},
                     None, ())]

    world = World(extra_library=[write("planned.yaml", PLANNED)],
                  planners={"living-room": planner}, functions={"say-done": say_done})
    run = world.sup.start_task("survey", {"place": "kitchen"})
    world.run(10)
    assert planner.calls == [("living-room", "survey-place", {"place": "kitchen"})]
    assert world.executor.names() == ["navigate", "look-at", "speak"]
    assert world.executor.started[-1][2] == {"text": "kitchen seen"}
    assert run.outcome == "done"


def test_same_inputs_same_log(tmp_path):
    from shary.log.contextlog import ContextLog, read_events

    def scenario(path):
        with ContextLog(path, seed=3) as log:
            World(log=log, seed=3).distracted_give()
        return [(e.time, e.kind, e.task, e.agent, e.data) for e in read_events(path)]

    first = scenario(tmp_path / "a.sqlite")
    second = scenario(tmp_path / "b.sqlite")
    assert first == second
    kinds = {kind for _, kind, _, _, _ in first}
    assert {"act", "enter", "exit", "task-state", "exec-request", "exec-result", "monitor",
            "node", "node-removed", "event", "recipe"} <= kinds


def test_plan_fact_readings_are_checked(shary, write):
    """A shape problem first (meaning is only checked on a file of the right shape:
    ``at: 3`` is not a predicate name), then, once it is fixed, the unknown predicate."""
    text = BASE + """\
recipes:
  - task: greet
    act: REALIZE-TASK
    plan: {domain: living-room, task: Greet, facts: {on: [isOnn], at: AT}}
"""
    found = _problems(shary, write("facts.yaml", text.replace("AT", "3")))
    assert any(line == 13 and "expected a string here, got a number (3)" in msg
               for line, _, msg in found), found
    found = _problems(shary, write("facts.yaml", text.replace("AT", "isAt")))
    assert (13, 59, "unknown predicate 'isOnn' (did you mean 'isOn'?)") in found


def test_custom_act_of_a_scheme_runs_end_to_end(tmp_path):
    """OFFER-AGAIN, declared in the user's scheme, is usable by their recipes and by their
    scenario's expectations: validated together, then run."""
    from conftest import REPO

    from shary.cli import main

    folder = REPO / "docs" / "tutorial" / "offer-again"
    files = sorted(folder.glob("*.yaml"))
    assert main(["validate", *map(str, files)]) == 0
    assert main(["run", str(folder / "scenario.yaml"), "--out", str(tmp_path), "--quiet"]) == 0


def test_initiator_is_implicit_and_names_nobody_in_a_task_nobody_asked_for(shary, write):
    """``$initiator`` is the person who asked for a task: every recipe may name it, no task
    declares it, and a condition about it holds nothing, negated or not, when nobody
    asked (so a recipe for the asker is not chosen for the robot's own goal)."""
    from shary.kernel.recipes import Condition, Pattern

    path = write("asker.yaml", BASE.replace("params: [person]", "params: [person, initiator]")
                 + "recipes:\n  - task: greet\n    act: ASK-TASK\n    when:\n"
                   "      - not: [$initiator, looksAt, $robot]\n")
    ((_, _, msg),) = _problems(shary, path)
    assert msg == "'initiator' is implicit: every task has it"
    world = World()
    looks = Pattern(Term("param", "initiator"), Term("const", "looksAt"),
                    Term("param", "robot"))
    for negated in (False, True):
        assert not world.sup.holds((Condition(looks, negated),), {"robot": "jido"})
    asked = {"robot": "jido", "initiator": "alice"}
    assert world.sup.holds((Condition(looks),), asked)  # the scripted Alice looks at Jido
    world.facts.remove("alice", "looksAt", "jido")
    assert world.sup.holds((Condition(looks, True),), asked)
