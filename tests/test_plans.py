"""Shared plans on the engine, without the simulator: the StackBuildingTask's conditional
plan from the planner, followed with a scripted robot and a scripted human."""

from __future__ import annotations

from typing import Any

import planner
from planner.conditional.exploration import explore
from planner.conditional.policy import select
from shary.facts.database import FactDatabase
from shary.io.recipes import load_library
from shary.kernel.executors import ExecutorRegistry
from shary.kernel.loop import EventLoop
from shary.kernel.supervisor import Supervisor
from shary.plans.execution import PlanFollower
from shary.plans.states import STATES, compiled_scheme
from shary.plans.tasks import SharedPlan
from shary.recognition.models import builtin_models, load_action_models

CUBES = ["red_cube_1", "red_cube_2", "stick", "blue_cube_1", "blue_cube_2", "green_cube"]


def stack_plan(problem: str = "stack") -> SharedPlan:
    domain = planner.load_domain("stack")
    prob = planner.load_problem(f"planner/problems/{problem}.yaml", domain)
    return SharedPlan.from_policy(select(prob, explore(prob)))


class Log:
    def __init__(self) -> None:
        self.rows: list[tuple[float, str, str | None, str | None, dict]] = []
        self.listeners: list[Any] = []

    def record(self, t: float, kind: str, *, task=None, agent=None, **data) -> None:
        self.rows.append((t, kind, task, agent, data))
        for listener in self.listeners:
            listener(kind, task, agent, data)

    def of(self, kind: str) -> list[tuple]:
        return [(agent, data) for _, k, _, agent, data in self.rows if k == kind]


class Robot:
    """Scripted executors: pick, place, look-at and speak take a second or less and
    change the facts as a robot would; ``faults`` makes the next places fail."""

    def __init__(self, table: Table):
        self.table = table
        self.faults: dict[str, int] = {}
        self.said: list[str] = []
        self.hang: set[str] = set()
        """Atomic tasks that never end (an executor that hangs)."""

    def start(self, request, reporter) -> None:
        loop, facts, robot = self.table.loop, self.table.facts, self.table.robot
        args = request.args

        def finish() -> None:
            if self.faults.get(request.atomic):
                self.faults[request.atomic] -= 1
                reporter.failed(request, "the cube slipped")
                return
            if request.atomic == "pick":
                facts.add(robot, "isHolding", args["object"])
            elif request.atomic == "place":
                facts.remove(robot, "isHolding", args["object"])
                facts.add(args["object"], "isOn", args["on"])
            elif request.atomic == "speak":
                self.said.append(args["text"])
            elif request.atomic == "look-at" and args["target"] in self.table.hidden:
                facts.add(*self.table.hidden.pop(args["target"]))  # seen once looked at
            reporter.done(request)

        if request.atomic in self.hang:
            return
        loop.call_later({"look-at": 0.2, "speak": 1.0}.get(request.atomic, 1.5), finish)

    def cancel(self, request) -> None:
        pass


class Human:
    """A scripted partner: does each of their tasks when it is due, as ``choices`` say
    at decisions (``wait`` leaves it to the robot), with their hand's moves and the
    effects the recognizer sees."""

    def __init__(self, table: Table, name: str = "human", choices: list[str] | None = None):
        self.table, self.name = table, name
        self.choices = list(choices or [])
        self.done: set[int] = set()
        self.skip: tuple[str, ...] = ()
        """Tasks (label prefixes) they never do."""
        self.unseen: tuple[str, ...] = ()
        """Places (label prefixes) whose result the robot sees only once it looks there."""

    def on(self, kind: str, task: Any, agent: Any, data: dict) -> None:
        if kind == "plan-task" and agent == self.table.robot and data["state"] == "TODO":
            self.table.loop.call_later(0.5, self.consider)

    def consider(self) -> None:
        """Do the task due now if it is ours, choosing at decisions as told."""
        follower = self.table.follower
        due = [t for t in follower.current if t not in self.done]
        if not due or follower.finished:
            return
        labels = [follower.plan.primitive[t].label() for t in due]
        if not labels[0].split("(")[1].startswith(self.name):
            return
        if len(due) > 1:
            choice = self.choices.pop(0) if self.choices else "0"
            self.done.update(due)
            if choice != "wait":
                self.act(labels[int(choice)])
        elif not labels[0].startswith("WaitForCube"):
            self.done.update(due)
            self.act(labels[0])

    def act(self, label: str) -> None:
        if label.startswith(self.skip or ("-",)):
            return
        name, args = label.rstrip(")").split("(")
        params = [a.strip() for a in args.split(",")][1:]
        self.do(name, *params, hidden=label.startswith(self.unseen or ("-",)))

    def do(self, name: str, *params: str, look_away: bool = False, hidden: bool = False
           ) -> None:
        loop, facts, h = self.table.loop, self.table.facts, self.name
        if name == "Pick":
            loop.call_later(0.3, facts.add, h, "handMovingToward", params[0])
            loop.call_later(1.0, facts.add, h, "isHolding", params[0])
            loop.call_later(1.1, facts.remove, h, "handMovingToward", params[0])
        else:  # Place, PlaceStick: onto the first support
            loop.call_later(0.3, facts.add, h, "handMovingToward", params[1])
            loop.call_later(1.0, facts.remove, h, "isHolding", params[0])
            if hidden:
                self.table.hidden[params[1]] = (params[0], "isOn", params[1])
            else:
                loop.call_later(1.1, facts.add, params[0], "isOn", params[1])
            loop.call_later(1.2, facts.remove, h, "handMovingToward", params[1])


class Table:
    """The StackBuildingTask's facts, a supervisor with the stack action models, a
    scripted robot and human, and a plan follower."""

    def __init__(self, choices: list[str] | None = None, replan: bool = True,
                 problem: str = "stack"):
        self.loop = EventLoop()
        self.facts = FactDatabase()
        self.log = Log()
        self.robot = "robot"
        self.hidden: dict[str, tuple[str, str, str]] = {}
        """Support -> an effect out of the camera's view until the robot looks there."""
        self.executor = Robot(self)
        self.sup = Supervisor(load_library(), self.facts, robot=self.robot,
                              loop=self.loop, log=self.log,
                              executors=ExecutorRegistry({n: self.executor for n in (
                                  "pick", "place", "look-at", "speak")}))
        for name, kind in [("human", "Human"), ("robot", "Robot"), ("table", "Support"),
                           ("placement_1", "Placement"), ("placement_2", "Placement")]:
            self.facts.add(name, "type", kind)
        for cube in CUBES:
            self.facts.add(cube, "type", "Cube")
            self.facts.add(cube, "type", "Support")
            self.facts.add(cube, "color", cube.split("_")[0])
            self.facts.add(cube, "isReachableBy", "human")
            self.facts.add(cube, "isReachableBy", "robot")
        self.facts.add("stick", "type", "Stick")
        self.facts.add("human", "looksAt", "robot")
        self.sup.recognize(load_action_models([builtin_models("stack")], self.facts))
        self.human = Human(self, choices=choices)
        self.log.listeners.append(self.human.on)
        self.outcome: list[str] = []
        self.agendas: list[dict[str, list[str]]] = []
        self.follower = PlanFollower(self.sup, stack_plan(problem), humans=["human"],
                                     replan=self.replan if replan else None,
                                     done=self.outcome.append)

    def replan(self, agendas: dict[str, list[str]]) -> SharedPlan:
        self.agendas.append(agendas)
        return stack_plan()  # the tests' worlds are replanned from the start's plan

    def run(self, seconds: float = 120) -> None:
        self.follower.start()
        self.loop.advance(seconds)

    def states(self, view: str) -> dict[str, str]:
        out: dict[str, str] = {}
        for agent, data in self.log.of("plan-task"):
            if agent == view:
                out[data["name"]] = data["state"]
        return out


def test_the_scheme_has_the_nine_states_of_table_iii():
    states = compiled_scheme().scheme.states
    names = {name.replace("-", "_").upper() for name, s in states.items() if s.is_atomic}
    assert names == set(STATES)


def test_the_plan_of_the_planner_reads_as_abstract_and_primitive_tasks():
    plan = stack_plan()
    assert len(plan.decisions) >= 2
    first = plan.next(None)
    assert [t.label() for t in first] == ["Pick(robot, red_cube_1)"]
    options = plan.next(plan.decisions["d1"].after)
    assert len(options) == 3 and {t.decision for t in options} == {"d1"}
    assert plan.ancestors(first[0].id) and plan.abstract[plan.ancestors(first[0].id)[-1]].name \
        == "RobotStack"


def test_a_replan_s_agendas_keep_the_tasks_the_branch_found_already_done():
    """The first branch has the human place a blue cube on the stick, so the planner
    found their ``HumanTopBlue`` (and the robot's ``CheckDone``) done with nothing
    to do: no primitive task.  A replan from just before the human's blue cube must
    still ask for them: if the human now leaves the first blue cube to the robot,
    theirs goes on top (``shary fuzz stack --replay 58``)."""
    from shary.plans.replan import remaining_agendas

    plan = stack_plan()
    branch, task = [], None
    while True:
        following = plan.next(task)
        if not following:
            break
        task = following[0].id
        branch.append(task)
    blue = next(t for t in branch if plan.primitive[t].label() == "Pick(human, blue_cube_2)")
    agendas = remaining_agendas(plan, [blue], set(branch[:branch.index(blue)]), {})
    assert agendas["human"] == ["HumanFirstBlue(human, blue_cube_2, stick)",
                                "HumanTopBlue(human, blue_cube_2, green_cube)"]
    assert agendas["robot"][-1] == "CheckDone(robot, green_cube)"


def test_nominal_the_human_does_their_part_and_the_stack_is_built():
    table = Table(choices=["0", "0"])
    table.run()
    assert table.outcome == ["achieved"]
    assert ("green_cube", "blue_cube_2") in {(str(s), str(o)) for s, _, o in
                                             table.facts.triples() if str(_) == "isOn"}
    robot = table.states("robot")
    assert robot["Place(human, red_cube_2, placement_1)"] == "EXECUTED"
    assert robot["Place(human, red_cube_2, placement_2)"] == "UNPLANNED"
    assert robot["WaitForCube(human)"] == "UNPLANNED"
    decisions = [d["chosen"] for _, d in table.log.of("plan-decision")]
    assert decisions == ["Place(human, red_cube_2, placement_1)", "Pick(human, blue_cube_2)"]


def test_the_human_leaves_it_to_the_robot_at_both_decisions():
    table = Table(choices=["wait", "wait"])
    table.run()
    assert table.outcome == ["achieved"]
    decisions = [d["chosen"] for _, d in table.log.of("plan-decision")]
    assert decisions == ["WaitForCube(human)", "WaitForCube(human)"]
    assert [m["match"] for _, m in table.log.of("plan-match")] == ["waits", "waits"]


def test_the_human_chooses_the_other_placement():
    table = Table(choices=["1", "0"])
    table.run()
    assert table.outcome == ["achieved"]
    assert table.facts.holds("red_cube_2", "isOn", "placement_2")
    assert table.states("robot")["Place(human, red_cube_2, placement_1)"] == "UNPLANNED"


def test_a_robot_action_done_while_the_human_looked_away_is_not_seen_then_told():
    table = Table(choices=["0", "0"])
    # the human looks away while the robot picks and places the green cube
    table.loop.call_later(11.5, table.facts.remove, "human", "looksAt", "robot")
    table.loop.call_later(11.5, table.facts.add, "human", "looksAt", "window")
    table.loop.call_later(17.0, table.facts.remove, "human", "looksAt", "window")
    table.loop.call_later(17.0, table.facts.add, "human", "looksAt", "robot")
    table.run()
    assert table.outcome == ["achieved"]
    human_view = [(d["name"], d["state"]) for a, d in table.log.of("plan-task") if a == "human"]
    placed = "Place(robot, green_cube, blue_cube_2)"
    assert (placed, "NOT_SEEN") in human_view and (placed, "EXECUTED") in human_view
    assert human_view.index((placed, "NOT_SEEN")) < human_view.index((placed, "EXECUTED"))
    assert table.states("robot")[placed] == "EXECUTED"
    assert any("placed the green cube" in text for text in table.executor.said), \
        table.executor.said


def test_a_place_that_fails_twice_fails_the_plan_which_is_replanned():
    table = Table(choices=["0", "0"])
    table.executor.faults["place"] = 2
    table.run()
    retries = [d for _, d in table.log.of("robot-action") if d["state"] == "retry"]
    failed = [d for _, d in table.log.of("robot-action") if d["state"] == "failed"]
    assert len(retries) == 1 and len(failed) == 1
    assert "max_attempts (2)" in failed[0]["reason"]
    states = [d["state"] for _, d in table.log.of("shared-plan")]
    assert states[:3] == ["started", "replan", "started"] or "replan" in states
    reasons = [d.get("reason") for _, d in table.log.of("shared-plan") if d["state"] == "replan"]
    assert reasons[0].startswith("Place(robot, red_cube_1, placement_2) failed: max_attempts")
    # what was left: the failed place's abstract task whole, not the robot's first pick
    assert table.agendas[0]["robot"][0] == "PlaceRed(robot, red_cube_1)"
    assert table.agendas[0]["human"][0] == "Pick(human, stick)"


def test_without_a_replan_port_a_failed_action_fails_the_plan():
    table = Table(choices=["0", "0"], replan=False)
    table.executor.faults["pick"] = 2
    table.run(30)
    assert table.outcome == ["failed"]
    assert table.states("robot")["Pick(robot, red_cube_1)"] == "UNPLANNED"


def test_the_human_places_a_cube_the_robot_was_to_place_and_it_is_accepted():
    table = Table(choices=["0", "0"])
    # at 14.5 s the human has placed blue_cube_2 on the stick; they put the green cube on it
    table.loop.call_later(11.0, table.human.do, "Pick", "green_cube")
    table.loop.call_later(16.0, table.human.do, "Place", "green_cube", "blue_cube_2")
    table.run()
    assert table.outcome == ["achieved"]
    useful = [d for _, d in table.log.of("plan-match") if d["match"] == "useful"]
    assert [d["action"] for d in useful] == ["pick", "place"], table.log.of("plan-match")
    assert table.log.of("plan-wait"), "the robot did not wait while the human held the cube"
    assert table.states("robot")["Place(robot, green_cube, blue_cube_2)"] == "EXECUTED"


def test_an_action_the_plan_does_not_expect_makes_it_replan():
    table = Table(choices=["0", "0"])
    table.loop.call_later(2.0, table.human.do, "Pick", "blue_cube_1")  # useful: accepted
    table.loop.call_later(4.0, table.human.do, "Place", "blue_cube_1", "table")  # harmful
    table.run(40)
    harmful = [d for _, d in table.log.of("plan-match") if d["match"] == "harmful"]
    assert harmful and harmful[0]["action"] == "place"
    assert table.follower.replans >= 1


def test_an_agentx_plan_chooses_its_actor_and_its_cube_when_the_step_starts():
    table = Table(problem="stack-agentx")
    for cube in ("blue_cube_1", "blue_cube_2"):
        table.facts.add(cube, "type", "BlueCube")
    table.facts.remove("blue_cube_1", "isReachableBy", "robot")  # the human's side only
    table.facts.add("green_cube", "isOn", "placement_1")
    table.run(30)
    assert table.outcome == ["achieved"]
    resolved = [(agent, d["params"]) for agent, d in table.log.of("plan-resolve")]
    assert resolved[0] == ("robot", ["robot", "blue_cube_2"])
    queries = [d for _, d in table.log.of("plan-query")]
    assert queries[0]["answers"] == ["blue_cube_2"] and queries[0]["bound"] == "robot"
    assert table.facts.holds("blue_cube_2", "isOn", "green_cube")


def test_a_task_the_human_never_does_is_looked_for_asked_for_then_taken_over():
    """NOT_STARTING leads somewhere: look (nothing is seen here), ask, and, since the robot
    can reach the stick, take the task over; the plan is achieved."""
    table = Table(choices=["0", "0"])
    table.human.skip = ("Pick(human, stick)", "PlaceStick(human")
    table.run(300)
    assert table.outcome == ["achieved"]
    rungs = [d["rung"] for _, d in table.log.of("plan-recover")
             if d["name"] == "Pick(human, stick)"]
    assert rungs == ["look", "ask", "take-over"]
    assert any("pick up the stick" in text for text in table.executor.said), table.executor.said
    assert table.states("robot")["Pick(human, stick)"] == "EXECUTED"
    assert "stick" in [d["params"]["Pickable"] for _, d in table.log.of("robot-action")
                       if d["state"] == "started" and d["action"] == "pick"]


def test_a_task_nobody_else_can_do_climbs_the_ladder_and_the_plan_ends_with_a_reason():
    """Out of the robot's reach, the stick cannot be taken over: replan; once the replans
    are spent the plan fails and the robot says why, instead of waiting forever."""
    table = Table(choices=["0", "0"])
    table.facts.remove("stick", "isReachableBy", "robot")
    table.human.skip = ("Pick(human, stick)",)
    table.run(900)
    assert table.outcome == ["failed"]
    rungs = [d["rung"] for _, d in table.log.of("plan-recover")
             if d["name"] == "Pick(human, stick)"]
    assert rungs[:2] == ["look", "ask"] and "replan" in rungs
    assert any("pick up the stick" in text for text in table.executor.said), table.executor.said
    assert any("so I stop here" in text for text in table.executor.said), \
        table.executor.said
    (end,) = [d for _, d in table.log.of("shared-plan") if d["state"] == "failed"]
    assert "did not get done (nothing moved within 8s after the ask)" in end["reason"]
    # the fake replanner gives the start's plan back: the first replan was for the stick
    first = next(d for _, d in table.log.of("shared-plan") if d["state"] == "replan")
    assert first["reason"].startswith("Pick(human, stick) did not get done")


def test_a_place_whose_result_is_out_of_view_is_looked_at_and_recognized():
    """The human's place ends where the camera does not look: the robot looks there
    (perception's unknown is not 'not done') and recognizes it."""
    table = Table(choices=["0", "0"])
    table.human.unseen = ("Place(human, blue_cube_2",)
    table.run()
    assert table.outcome == ["achieved"]
    looks = [d["why"] for _, d in table.log.of("plan-recover")
             if d["rung"] == "look" and d["name"] == "Place(human, blue_cube_2, stick)"]
    assert looks == ["under way out of view"]
    assert table.states("robot")["Place(human, blue_cube_2, stick)"] == "EXECUTED"


def test_a_robot_action_that_never_ends_fails_when_not_finished_and_the_plan_ends():
    table = Table(choices=["0", "0"])
    table.executor.hang = {"pick"}
    table.run(300)
    replans = [d["reason"] for _, d in table.log.of("shared-plan") if d["state"] == "replan"]
    assert replans[0] == "Pick(robot, red_cube_1) never ended (NOT_FINISHED in the plan)"
    assert table.outcome == ["failed"]  # every new plan starts with the same hanging pick


def test_the_watchdog_acts_when_nothing_in_the_plan_progresses():
    """A plan in which nothing happens (the robot waits for a human who holds the cube
    it must pick, and she never lets go) is not left waiting: the watchdog says so
    and replans."""
    table = Table(choices=["0", "0"])
    table.facts.add("human", "isHolding", "red_cube_1")  # the robot's first pick's cube
    table.run(900)
    dogs = [d for _, d in table.log.of("watchdog")]
    assert dogs and dogs[0]["action"] == "replan"
    assert dogs[0]["due"] == ["Pick(robot, red_cube_1)"]
    assert dogs[0]["why"] == "nothing in the plan progressed for 45s"
    assert table.outcome == ["failed"]
