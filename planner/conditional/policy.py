"""Choosing the policy of a conditional plan: the robot's best answer to every human choice.

HATP/EHDA's selection, over the AND/OR graph of :mod:`planner.conditional.exploration`:
at the planner's turn (OR) the option of least cost is kept; at a human's
turn (AND) every option is kept and the turn costs their **expected** cost
(weighted by the decompositions' ``weight``, uniform by default) or, in
**worst**-case mode, the most expensive.  A branch costs its actions' costs
(plus the problem's ``wait_cost`` and ``idle_cost`` for waits and idling).

With social rules or AHP criteria the problem scores each *branch* -- a
root-to-leaf path is a total-order plan -- with the same
:class:`~planner.evaluation.evaluate.Evaluator` as the total-order planner, and the
expectation and the minimum are taken over those branch scores: rules apply
per branch and, through them, to the policy.  Without them the score of a
branch is the sum of its costs, so the value of a turn does not depend on how
it was reached and each turn of the DAG is valued once.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

from planner.conditional.exploration import (
    DONE,
    IDLE,
    LEAF_KIND,
    MAX_STEPS,
    WAIT,
    Exploration,
    OpenValue,
    Step,
    Turn,
    deep,
)
from planner.evaluation.evaluate import Evaluator
from planner.model.domain import Problem

MODES = ("expected", "worst")


@dataclass(eq=False)
class Choice:
    """A turn of the policy: the option(s) kept, each with what follows and its value."""

    agent: str
    kind: str
    """``or``, ``and`` or ``leaf``."""
    options: list[tuple[Step, float, Choice]] = field(default_factory=list)
    """(step, probability of the option (1 for the planner's), the turn after it)."""
    value: float = 0.0
    """The cost of the rest of the plan from this turn (expected or worst)."""
    others: list[tuple[Step, float]] = field(default_factory=list)
    """At the planner's turns: the options not kept, with the value they would have had."""


@dataclass
class Policy:
    """The chosen conditional plan and what it was chosen from."""

    problem: Problem
    exploration: Exploration
    mode: str
    root: Choice | None
    cost: float | None
    """The policy's cost: expected (or worst-case) over the humans' choices."""
    leaves: int
    """Branches explored (every root-to-leaf path of the AND/OR graph, HATP/EHDA's count)."""
    branches: list[list[Step]] = field(default_factory=list)
    """The policy's branches, root to leaf."""
    branch_costs: list[float] = field(default_factory=list)


def select(problem: Problem, exploration: Exploration, mode: str = "expected") -> Policy:
    """The best policy of the explored graph (None as ``root`` when there is none)."""
    from planner.conditional.exploration import count_leaves

    if mode not in MODES:
        raise ValueError(f"mode must be one of {', '.join(MODES)}, not {mode!r}")
    leaves = count_leaves(exploration.root)
    if exploration.root is None:
        return Policy(problem, exploration, mode, None, None, leaves)
    chooser = _Chooser(problem, mode)
    with deep(MAX_STEPS):
        root = chooser.choice(exploration.root, ())
    policy = Policy(problem, exploration, mode, root, root.value, leaves)
    for branch in walk(root):
        policy.branches.append([step for step, _ in branch])
        policy.branch_costs.append(chooser.branch_score([s for s, _ in branch]))
    return policy


def walk(root: Choice) -> list[list[tuple[Step, Choice]]]:
    """The policy's branches: for each leaf, the steps from the root and the turn each
    step was taken at."""
    out: list[list[tuple[Step, Choice]]] = []
    stack: list[tuple[Choice, list[tuple[Step, Choice]]]] = [(root, [])]
    while stack:
        node, path = stack.pop()
        if node.kind == LEAF_KIND:
            out.append(path)
            continue
        for step, _, child in reversed(node.options):
            stack.append((child, path + [(step, node)]))
    return out


class _Chooser:
    def __init__(self, problem: Problem, mode: str):
        self.problem = problem
        self.worst = mode == "worst"
        self.additive = not problem.rules and not problem.weights
        self.evaluator = None if self.additive else Evaluator(problem)
        self.memo: dict[int, Choice] = {}

    def choice(self, turn: Turn, prefix: tuple[Step, ...]) -> Choice:
        """The policy from ``turn`` on; ``value`` is the branch score still to come
        (additive scores) or the whole branches' expected score (rules, criteria)."""
        if self.additive:
            known = self.memo.get(id(turn))
            if known is not None:
                return known
        if turn.kind == LEAF_KIND:
            node = Choice("", LEAF_KIND, value=0.0 if self.additive
                          else self.branch_score(list(prefix)))
        else:
            node = self._turn(turn, prefix)
        if self.additive:
            self.memo[id(turn)] = node
        return node

    def _turn(self, turn: Turn, prefix: tuple[Step, ...]) -> Choice:
        valued = []
        for step, child in turn.children:
            sub = self.choice(child, () if self.additive else prefix + (step,))
            valued.append((step, (step.cost if self.additive else 0.0) + sub.value, sub))
        node = Choice(turn.agent, turn.kind)
        if turn.kind == "or":
            best = min(range(len(valued)), key=lambda i: valued[i][1])
            step, value, sub = valued[best]
            node.options = [(step, 1.0, sub)]
            node.value = value
            node.others = [(s, v) for i, (s, v, _) in enumerate(valued) if i != best]
            return node
        total = sum(step.weight for step, _, _ in valued)
        node.options = [(step, step.weight / total, sub) for step, _, sub in valued]
        if self.worst:
            node.value = max(value for _, value, _ in valued)
        else:
            node.value = sum(step.weight * value for step, value, _ in valued) / total
        return node

    def branch_score(self, steps: list[Step]) -> float:
        """A branch's score: its costs, or the evaluator's score of its actions (the
        open values at their first candidate) plus its waits and idling."""
        extra = sum(s.cost for s in steps if s.name in (IDLE, WAIT, DONE))
        if self.evaluator is None:
            return sum(s.cost for s in steps if s.name not in (IDLE, WAIT, DONE)) + extra
        actions = [(s.name, tuple(_first(a) for a in s.args),
                    _first(performer(self.problem, s)), s.cost, s.duration)
                   for s in steps if s.name not in (IDLE, WAIT, DONE)]
        plan = self.evaluator.evaluate(actions, {}, [])
        return plan.score + extra


def performer(problem: Problem, step: Step) -> Any:
    """Who performs a step: its action's agent parameter (an AgentX token when left open),
    or the agent whose turn it is (waits, idling)."""
    action = problem.domain.actions.get(step.name)
    if action is None or action.agent is None:
        return step.agent
    return step.args[action.names.index(action.agent)]


def _first(value: Any) -> Any:
    return value.candidates[0] if isinstance(value, OpenValue) else value
