"""The HATP-like planner: plans of several agents, social rules, anytime search,
explanations, the validator, and bad domain files."""

from __future__ import annotations

import dataclasses
import textwrap
from pathlib import Path

import pytest

from planner import PlanAction, load_domain, load_problem, plan, validate
from planner.model.domain import SelectedRule
from planner.search.branchbound import Search
from userfiles.errors import FileError

PROBLEMS = Path(__file__).resolve().parents[1] / "planner" / "problems"


def solve(problem, budget_ms=5000):
    result = plan(problem, budget_ms)
    assert result.plan is not None, result.explain()
    assert validate(problem, result.plan) == []
    return result.plan


def names(p) -> list[str]:
    return [f"{a}/{a.agent}" for a in p.actions]


def with_rules(problem, **penalties):
    problem.rules = {n.replace("_", "-"): SelectedRule(problem.domain.rules[n.replace("_", "-")],
                                                       {"default": v})
                     for n, v in penalties.items()}
    return problem


@pytest.fixture(scope="module")
def living():
    return load_domain("living-room")


@pytest.fixture(scope="module")
def fig6():
    return load_domain("fig6")


def test_clean_up_is_the_plan_of_fig_9b(living):
    p = solve(load_problem(PROBLEMS / "clean-up.yaml", living))
    assert names(p) == ["Move(jido, coffee-area)/jido",
                        "Pick(jido, yellow-bottle, coffee-table)/jido",
                        "Move(jido, trash-area)/jido", "Dump(jido, yellow-bottle, trash)/jido"]
    assert p.criteria["cost"] == 6 and p.makespan == 13
    root = p.tree[p.roots[0]]
    assert (root.task, root.decomposition) == ("CleanUp", "throw")


def test_unreachable_bottle_is_picked_and_given_by_the_human(living):
    p = solve(load_problem(PROBLEMS / "clean-up-unreachable.yaml", living))
    streams = {agent: [a.name for a in acts] for agent, acts in p.streams.items()}
    assert streams == {"alice": ["Move", "Pick", "Move", "Give"], "jido": ["Move", "Dump"]}
    give = next(a for a in p.actions if a.name == "Give")
    dump = next(a for a in p.actions if a.name == "Dump")
    assert any(k.producer == give.index and k.consumer == dump.index for k in p.links)
    assert dump.start >= give.end


def test_streams_overlap_when_nothing_orders_them(fig6):
    p = solve(with_rules(load_problem(PROBLEMS / "fig6.yaml", fig6), door_open=10))
    close = next(a for a in p.actions if a.name == "Close")
    human_moves = [a for a in p.actions if a.agent == "human" and a.name == "Move"]
    assert close.agent == "jido"
    assert any(m.start < close.end and close.start < m.end for m in human_moves)


def test_putdown_then_pickup_rule_makes_the_robot_hand_over(living):
    problem = load_problem(PROBLEMS / "serve-drink.yaml", living)
    assert [a.name for a in solve(problem).actions][-1] == "Give"
    problem.select_rules([])
    assert [a.name for a in solve(problem).actions][-2:] == ["PutDown", "Pick"]


def test_fig6_rules_change_the_plan_as_the_paper_says(fig6):
    def run(**rules):
        return [a.name + "/" + a.agent for a in solve(
            with_rules(load_problem(PROBLEMS / "fig6.yaml", fig6), **rules)).actions]

    alone = run()
    assert all(step.endswith("/human") for step in alone)           # cheapest: the human alone
    helped = run(effort_balance=0.4)                                 # (6) the robot helps...
    assert "PutDown/jido" in helped and "Pickup/human" in helped     # ...putting the glass down
    assert "Give/jido" in run(effort_balance=0.4, object_on_sofa=10)  # (1) not on the sofa
    assert "Give/jido" in run(effort_balance=0.4, putdown_pickup=10)  # (4) hand it over
    assert "Close/jido" not in alone and "Close/jido" in run(door_open=10)  # (2) close the door
    assert "Close/human" in run(door_open=10, open_close_different=5)  # (5) the opener closes
    assert any(s.endswith("/jido") for s in run(effort_balance=0.5))
    assert all(s.endswith("/human") for s in run(effort_balance=0.5, joint_actions=3))  # (7)


SMALL = """\
domain: small
types:
  Place: {}
  Agent: {agent: true, static: {kind: string}, dynamic: {at: Place, done: bool}}
actions:
  Hop:
    params: {ag: Agent, to: Place}
    agent: ag
    pre: ag.at != to
    effects: [ag.at = to]
    cost: 1
    duration: 1
  Walk:
    params: {ag: Agent, to: Place}
    agent: ag
    pre: ag.at != to
    effects: [ag.at = to]
    cost: 2.5
    duration: 1
  Work:
    params: {ag: Agent}
    agent: ag
    effects: [ag.done = true]
    cost: 1
    duration: 10
  Join:
    params: {ag: Agent, other: Agent}
    agent: ag
    pre: other.done
    effects: [ag.at = other.at]
    cost: 2.5
    duration: 1
  Check:
    params: {ag: Agent, other: Agent}
    agent: ag
    pre: other.done
    cost: 1
    duration: 1
methods:
  Reach:
    params: {ag: Agent, p: Place, via: Place}
    decompositions:
      - {name: hops, subtasks: ["Hop(ag, via)", "Hop(ag, p)"]}
      - {name: walk, subtasks: ["Walk(ag, p)"]}
  Team:
    params: {a: Agent, b: Agent}
    decompositions:
      - {name: wait, subtasks: ["Hop(a, b.at)", "Work(b)", "Check(a, b)"]}
      - {name: patient, subtasks: ["Work(b)", "Join(a, b)", "Check(a, b)"]}
rules:
  move-move:
    kind: sequence
    first: {action: Hop}
    then: {action: Hop}
    agents: same
  waits:
    kind: timeout
    max_wait: 2
"""


def small_problem(write, task: str, **rules):
    domain = load_domain(write("small.yaml", SMALL))
    problem = load_problem(write("p.yaml", f"""\
        problem: p
        entities:
          home: {{type: Place}}
          hall: {{type: Place}}
          room: {{type: Place}}
          r: {{type: Agent, kind: robot, at: home}}
          h: {{type: Agent, kind: human, at: room}}
        tasks: ["{task}"]
        """), domain)
    return with_rules(problem, **rules)


def test_move_then_move_rule(write):
    assert [a.name for a in solve(small_problem(write, "Reach(r, room, hall)")).actions] == \
        ["Hop", "Hop"]
    assert [a.name for a in solve(small_problem(write, "Reach(r, room, hall)",
                                                move_move=5)).actions] == ["Walk"]


def test_timeout_rule(write):
    waiting = solve(small_problem(write, "Team(r, h)"))
    assert [a.name for a in waiting.actions] == ["Hop", "Work", "Check"]
    patient = solve(small_problem(write, "Team(r, h)", waits=1))
    assert [a.name for a in patient.actions] == ["Work", "Join", "Check"]
    assert patient.criteria["waits"] == 0 and not patient.violations


def test_bad_decomposition_rule(living):
    problem = load_problem(PROBLEMS / "clean-up.yaml", living)
    assert solve(problem).tree[solve(problem).roots[0]].decomposition == "throw"
    problem.goals.clear()
    with_rules(problem, store_not_throw=5)
    p = solve(problem)
    assert p.tree[p.roots[0]].decomposition == "store" and p.actions[-1].name == "PutDown"


def test_anytime_reports_improvements_and_keeps_the_best(fig6):
    seen = []
    problem = load_problem(PROBLEMS / "fig6.yaml", fig6)
    result = plan(problem, 5000, on_improvement=lambda p: seen.append(p.score))
    assert result.complete and seen == sorted(seen, reverse=True) and len(seen) >= 2
    assert result.plan.score == seen[-1]
    short = plan(problem, 0.001)
    assert not short.complete


def test_deterministic(fig6):
    first = solve(load_problem(PROBLEMS / "fig6.yaml", fig6))
    second = solve(load_problem(PROBLEMS / "fig6.yaml", fig6))
    assert names(first) == names(second) and first.score == second.score


def test_no_plan_is_explained(living, write):
    text = (PROBLEMS / "clean-up-unreachable.yaml").read_text()
    text = text.replace("  alice: {type: Agent", "  # alice: {type: Agent")
    result = plan(load_problem(write("alone.yaml", text), living), 2000)
    assert result.plan is None and result.complete
    (failure,) = result.failures
    assert failure.path[0] == "CleanUp(yellow-bottle)"
    assert "Pick(jido, yellow-bottle, coffee-table)" in failure.path[-1]
    assert "precondition false" in failure.reason and "robot_reach" in failure.reason


def test_deep_plans_need_no_recursion(living, write):
    text = (PROBLEMS / "clean-up.yaml").read_text()
    text = text.replace('tasks: ["CleanUp(yellow-bottle)"]',
                        "tasks: [" + ", ".join(['"Goto(jido, base)"', '"Goto(jido, coffee-area)"']
                                               * 1500) + "]")
    text = text.replace("goals: {yellow-bottle.on: trash}", "")
    p = solve(load_problem(write("deep.yaml", text), living), 20000)
    assert len(p.actions) == 2999


def test_validator_refuses_tampered_plans(living):
    problem = load_problem(PROBLEMS / "clean-up.yaml", living)
    p = solve(problem)
    p.actions[1], p.actions[2] = p.actions[2], p.actions[1]
    assert validate(problem, p)
    p = solve(problem)
    p.tree[p.roots[0]].decomposition = "store"
    assert any("subtasks" in e or "precondition" in e for e in validate(problem, p))
    p = solve(problem)
    problem.goals[("yellow-bottle", "on")] = "store-table"
    assert any("goal" in e for e in validate(problem, p))


def test_ahp_weights_the_criteria(fig6, write):
    text = (PROBLEMS / "fig6.yaml").read_text() + textwrap.dedent("""\
        criteria:
          names: [cost, duration, rules]
          matrix: [[1, 3, 1/2], [1/3, 1, 1/5], [2, 5, 1]]
          scale: {duration: 10}
        """)
    p = solve(load_problem(write("ahp.yaml", text), fig6))
    assert set(p.weights) >= {"cost", "duration", "rules"}
    assert p.weights["rules"] > p.weights["cost"] > p.weights["duration"] * 10
    assert abs(sum(p.breakdown()[k] for k in ("cost", "duration", "rules")) - p.score) < 1e-9


def test_inconsistent_ahp_matrix_is_an_error(fig6, write):
    text = (PROBLEMS / "fig6.yaml").read_text() + textwrap.dedent("""\
        criteria:
          names: [cost, duration, rules]
          matrix: [[1, 9, 1/9], [1/9, 1, 9], [9, 1/9, 1]]
        """)
    with pytest.raises(FileError) as err:
        load_problem(write("bad-ahp.yaml", text), fig6)
    assert "inconsistent" in str(err.value) or "CR" in str(err.value)


def test_a_timed_action_is_the_frozen_dataclass_the_constructor_makes():
    fast = PlanAction.timed(3, "Give", ("alice", "jido"), "alice", 1.0, 2.0, 4.0, 6.0)
    assert fast == PlanAction(3, "Give", ("alice", "jido"), "alice", 1.0, 2.0, 4.0, 6.0)
    assert hash(fast) == hash(PlanAction(3, "Give", ("alice", "jido"), "alice", 1.0, 2.0,
                                         4.0, 6.0))
    assert (fast.start, fast.end, str(fast)) == (4.0, 6.0, "Give(alice, jido)")
    with pytest.raises(dataclasses.FrozenInstanceError):
        fast.start = 0.0


# -- search budgets ----------------------------------------------------------------------

HOSTILE_SEARCH = Path(__file__).resolve().parent / "hostile" / "search"


def _hostile(name: str):  # type: ignore[no-untyped-def]
    domain = load_domain(HOSTILE_SEARCH / f"{name}.domain.yaml")
    return load_problem(HOSTILE_SEARCH / f"{name}.problem.yaml", domain)


def test_a_recursion_without_end_meets_the_depth_budget() -> None:
    result = plan(_hostile("recursive"), budget_ms=60_000, max_depth=100)
    assert result.plan is None and not result.complete
    assert "depth budget (100 nested tasks)" in result.exhausted
    assert "Pace(jido, hall, door)" in result.exhausted
    assert result.explain().startswith("search budget exhausted: ")


def test_too_many_bindings_meet_the_node_budget() -> None:
    result = plan(_hostile("explosive"), budget_ms=60_000, max_nodes=5_000)
    assert result.plan is None and not result.complete
    assert "node budget (5,000 nodes" in result.exhausted


def test_a_budget_that_runs_out_keeps_the_best_plan_so_far() -> None:
    domain = load_domain("living-room")
    problem = load_problem(PROBLEMS / "clean-up-unreachable.yaml", domain)
    search = Search(problem)
    complete = search.run(60_000)
    assert complete.complete and complete.exhausted is None
    cut = plan(problem, budget_ms=60_000, max_nodes=search.nodes - 1)
    assert cut.plan is not None and not cut.complete and "node budget" in cut.exhausted
    assert validate(problem, cut.plan) == []


COUNTDOWN = """
domain: countdown
types:
  Agent:
    agent: true
    static: {kind: string}
    dynamic: {left: number}
actions:
  Tick:
    params: {ag: Agent}
    agent: ag
    pre: ag.left > 0
    effects: [ag.left = ag.left - 1]
    cost: 1
methods:
  Count:
    params: {ag: Agent}
    decompositions:
      - {name: done, pre: ag.left == 0, subtasks: []}
      - {name: more, pre: ag.left > 0, subtasks: ["Tick(ag)", "Count(ag)"]}
"""


def test_a_deep_but_finite_decomposition_fits_the_default_budgets(write) -> None:
    """Recursion that ends is fine: 3,000 nested Counts, one action each."""
    domain = load_domain(write("countdown.yaml", COUNTDOWN))
    problem = load_problem(write("count.yaml", "problem: count\ndomain: countdown\n"
                                 "entities: {jido: {type: Agent, kind: robot, left: 3000}}\n"
                                 'tasks: ["Count(jido)"]\n'), domain)
    result = plan(problem, budget_ms=60_000)
    assert result.complete and result.exhausted is None
    assert len(result.plan.actions) == 3000 and validate(problem, result.plan) == []
    shallow = plan(problem, budget_ms=60_000, max_depth=1000)
    assert shallow.plan is None and "cut the search at Count(jido)" in shallow.exhausted
