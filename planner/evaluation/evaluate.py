"""Evaluating a plan: streams, causal links, times, criteria, social rules, score.

A total-order plan from the search is read as HATP reads it: one stream per
agent, with causal links (an action needs a value another action set) and
ordering constraints (an action must not overwrite what an earlier one still
reads, or what an earlier one wrote).  Actions start as soon as their
predecessors in those relations, and their agent's previous action, are over:
actions of different agents overlap when nothing orders them.

The score is HATP's: action costs plus the penalties of the social rules the
problem selected, or, when the problem compares criteria with the Analytic
Hierarchy Process, the weighted sum of the criteria (each divided by its
scale).  Every criterion is kept so that the score can be broken down.
"""

from __future__ import annotations

import itertools
from typing import Any

from planner.model.domain import Problem, SelectedRule
from planner.model.plan import CausalLink, Plan, PlanAction, Relations, TreeNode

BASE_CRITERIA = ("cost", "duration", "human-effort", "robot-effort", "rules")
MONOTONE = ("cost", "human-effort", "robot-effort")
REPLAYED = ("state", "crossed-links")
"""The kinds of rule that score what the replay finds: states, causal links."""


class Evaluator:
    """Turns search trails into evaluated :class:`Plan` objects for one problem."""

    def __init__(self, problem: Problem):
        self.problem = problem
        self.domain = problem.domain
        if problem.weights:
            self.weights = dict(problem.weights)
        else:
            self.weights = {"cost": 1.0, **{name: 1.0 for name in problem.rules}}
        self.scale = {name: problem.scale.get(name, 1.0) for name in self.weights}
        self._bound = tuple((self.weights.get(c, 0.0) / self.scale.get(c, 1.0))
                            for c in MONOTONE)
        self.kinds: dict[str, str | None] = {}
        """Each agent's kind, as first looked up (the problem's static attribute)."""
        self.initial = dict(problem.initial)
        """The state the plans start from (a plan may derive its links after the search)."""
        self.replays = any(r.rule.kind in REPLAYED for r in problem.rules.values())
        """Whether the score needs the replay of every plan (see :meth:`evaluate`)."""

    # -- what a partial plan already costs (the search's bound) --------------------------

    @property
    def cost_weight(self) -> float:
        """What one unit of cost adds to the score."""
        return self._bound[0]

    def step_rate(self, kind: str | None) -> float:
        """What one unit of cost of an action by an agent of this kind adds to the score
        (cost, and human or robot effort)."""
        wc, wh, wr = self._bound
        return wc + (wh if kind == "human" else wr if kind == "robot" else 0.0)

    def _rule_rate(self, selected: SelectedRule) -> float:
        """What one unit of a rule's penalty adds to the score (as the rule, and as part
        of all the rules)."""
        name = selected.rule.name
        return selected.weight * (self.weights.get(name, 0.0) / self.scale.get(name, 1.0)
                                  + self.weights.get("rules", 0.0)
                                  / self.scale.get("rules", 1.0))

    def link_rates(self) -> list[tuple[SelectedRule, float]]:
        """The crossed-links rules that weigh in the score, with their rate.  Their
        penalty can only grow as a plan grows: a causal link between two actions of a
        plan is one in every longer plan."""
        return [(r, self._rule_rate(r)) for r in self.problem.rules.values()
                if r.rule.kind == "crossed-links" and self._rule_rate(r) > 0]

    def wait_rates(self) -> list[tuple[SelectedRule, float]]:
        """The timeout rules that weigh in the score, with their rate: a wait between two
        actions of a partial plan is one in every longer plan (an action starts when
        its predecessors, all before it, end)."""
        return [(r, self._rule_rate(r)) for r in self.problem.rules.values()
                if r.rule.kind == "timeout" and self._rule_rate(r) > 0]

    @property
    def duration_rate(self) -> float:
        """What one unit of makespan adds to the score (AHP's ``duration`` criterion)."""
        return self.weights.get("duration", 0.0) / self.scale.get("duration", 1.0)

    def decomposition_floor(self) -> dict[tuple[str, str], float]:
        """For each (method, decomposition) a decomposition rule penalizes, the least it
        adds to the score (the cheapest penalty of any agent: the agent it is charged to
        is known only when the subtree's first action is)."""
        floor: dict[tuple[str, str], float] = {}
        for selected in self.problem.rules.values():
            rule = selected.rule
            if rule.kind != "decomposition" or rule.method is None:
                continue
            table = list(selected.penalties.values())
            if "default" not in selected.penalties:
                table.append(1.0)
            least = max(min(table), 0.0) * self._rule_rate(selected)
            key = (rule.method, rule.decomposition or "")
            floor[key] = floor.get(key, 0.0) + least
        return {k: v for k, v in floor.items() if v > 0}

    # -- from the search's trail to a plan -------------------------------------------

    def plan(self, trail: Any, roots: list[int]) -> Plan:
        """The plan a search trail (a linked list of its choices, last first) describes."""
        records = []
        while trail is not None:
            records.append(trail[0])
            trail = trail[1]
        records.reverse()
        return self.build(records, roots)

    def build(self, records: list[tuple], root_ids: list[int]) -> Plan:
        """A plan from the search's records: ("method", …) and ("act", …) in order;
        ``root_ids`` are the tree ids of the problem's top tasks."""
        tree: dict[int, TreeNode] = {}
        roots: list[int] = []
        for root, (name, args) in zip(root_ids, self.problem.tasks, strict=True):
            tree[root] = TreeNode(root, name, tuple(args))
            roots.append(root)
        # The top tasks nothing was recorded under yet: the first record under one is
        # its own decomposition (or action), which the top node then stands for (alias).
        fresh = set(roots)
        alias: dict[int, int] = {}
        actions: list[tuple] = []  # (name, args, agent, cost, duration): timed later
        for record in records:
            parent = record[2]
            if record[0] == "method":
                _, node, _, name, args, dec, binding = record
                if parent in fresh:
                    fresh.discard(parent)
                    top = tree[parent]
                    top.decomposition = dec
                    top.bindings = dict(binding)
                    alias[node] = parent
                    continue
                tree[node] = TreeNode(node, name, tuple(args), dec, [], None, dict(binding))
            else:
                _, node, _, name, args, agent, price, length = record
                index = len(actions)
                actions.append((name, tuple(args), agent, float(price), float(length)))
                if parent in fresh:
                    fresh.discard(parent)
                    tree[parent].action = index
                    continue
                tree[node] = TreeNode(node, name, tuple(args), None, [], index, {})
            tree[alias.get(parent, parent)].children.append(node)
        return self.evaluate(actions, tree, roots)

    # -- links, times, criteria ----------------------------------------------------------

    def evaluate(self, actions: list[tuple], tree: dict[int, TreeNode],
                 roots: list[int]) -> Plan:
        """Links, orderings, times, rules and score of the actions ``(name, args, agent,
        cost, duration)`` in plan order.  When the score needs no replay of the plan (one
        agent, whose chain times everything, and no rule on states or links), the links
        and orderings are left for the plan to derive if they are ever read."""
        penalties: dict[str, float] = {name: 0.0 for name in self.problem.rules}
        violations: list[str] = []
        if self.replays or len({agent for _, _, agent, _, _ in actions}) > 1:
            links, orderings = self._replay(actions, penalties, violations)
            plan = Plan(self._schedule(actions, links, orderings), links, orderings, tree,
                        roots)
        else:
            plan = Plan(self._schedule(actions, [], []), None, None, tree, roots,
                        relate=lambda: self._replay(actions, {}, []))
        self._plan_rules(plan, penalties, violations)
        self._score(plan, penalties, violations)
        return plan

    def _replay(self, actions: list[tuple], penalties: dict[str, float],
                violations: list[str]) -> Relations:
        """Replay the actions from the initial state: their causal links and orderings
        (sorted), and the state rules' penalties and violations on the way."""
        problem = self.problem
        values = dict(self.initial)
        writer: dict[tuple[str, str], int] = {}
        readers: dict[tuple[str, str], list[int]] = {}
        links: dict[tuple, CausalLink] = {}
        orderings: set[tuple[int, int]] = set()
        during_rules = [r for r in problem.rules.values()
                        if r.rule.kind == "state" and r.rule.during]
        reads: set[tuple[str, str]] = set()
        writes: list[tuple[tuple[str, str], Any]] = []

        def get(entity: str, attribute: str) -> Any:
            key = (entity, attribute)
            reads.add(key)
            return values.get(key)

        def put(entity: str, attribute: str, value: Any) -> None:
            writes.append(((entity, attribute), value))

        domain_actions = self.domain.actions
        for index, (name, args, *_) in enumerate(actions):
            action = domain_actions[name]
            env = dict(zip(action.names, args, strict=True))
            reads.clear()
            writes.clear()
            if action.pre is not None:
                action.pre.fn(env, get)
            action.apply(env, get, put)
            for key in reads:  # the links are sorted at the end
                producer = writer.get(key)
                if producer is not None and producer != index:
                    links[(producer, index, key)] = CausalLink(producer, index, key[0], key[1])
                known = readers.get(key)
                if known is None:
                    readers[key] = [index]
                else:
                    known.append(index)
            for key, value in writes:
                for reader in readers.get(key, ()):
                    if reader != index:
                        orderings.add((reader, index))
                if key in writer and writer[key] != index:
                    orderings.add((writer[key], index))
                writer[key] = index
                # Its later writers are ordered after this action as its writer; as a
                # reader of the key too, it would only give the same pairs.
                readers[key] = []
                values[key] = value
            for selected in during_rules:
                self._state_rule(selected, values, writer, actions, penalties, violations)
        for selected in problem.rules.values():
            if selected.rule.kind == "state" and not selected.rule.during:
                self._state_rule(selected, values, writer, actions, penalties, violations)
        return (sorted(links.values(), key=lambda k: (k.consumer, k.producer, k.entity,
                                                       k.attribute)),
                sorted(orderings))

    def _schedule(self, actions: list[tuple], links: list[CausalLink],
                  orderings: list[tuple[int, int]]) -> list[PlanAction]:
        """Each action starts when its predecessors (links, orderings, its agent's
        previous action) are over."""
        if len({agent for _, _, agent, _, _ in actions}) <= 1:
            # One agent: its chain orders everything, and every predecessor of an action
            # ends by the end of the action just before it.
            timed, clock = [], 0.0
            for index, (name, args, agent, cost, duration) in enumerate(actions):
                timed.append(PlanAction.timed(index, name, args, agent, cost, duration, clock,
                                              clock + duration))
                clock += duration
            return timed
        before: dict[int, set[int]] = {index: set() for index in range(len(actions))}
        for link in links:
            before[link.consumer].add(link.producer)
        for first, second in orderings:
            before[second].add(first)
        last: dict[str, int] = {}
        for index, (_, _, agent, _, _) in enumerate(actions):
            if agent in last:
                before[index].add(last[agent])
            last[agent] = index
        ends: dict[int, float] = {}
        timed = []
        for index, (name, args, agent, cost, duration) in enumerate(actions):
            start = max((ends[p] for p in before[index]), default=0.0)
            ends[index] = start + duration
            timed.append(PlanAction.timed(index, name, args, agent, cost, duration, start,
                                          start + duration))
        return timed

    # -- social rules ------------------------------------------------------------------------

    def _kind(self, agent: str | None) -> str | None:
        if agent is None:
            return None
        kind = self.kinds.get(agent, self)
        if kind is self:
            kind = self.kinds[agent] = self.problem.kind(agent)
        return kind  # type: ignore[return-value]

    def _charge(self, selected: SelectedRule, agent: str | None, amount: float,
                penalties: dict[str, float], violations: list[str], what: str) -> None:
        cost = selected.penalty(agent, self._kind(agent)) * amount
        if cost > 0:
            penalties[selected.rule.name] += cost
            violations.append(f"{selected.rule.name}: {what} (+{cost:g})")

    def _state_rule(self, selected: SelectedRule, values: dict, writer: dict,
                    actions: list[tuple], penalties: dict, violations: list) -> None:
        rule = selected.rule
        names = [v for v, _ in rule.vars]
        choices = [self.problem.of_type(t) for _, t in rule.vars]
        for combo in itertools.product(*choices):
            env = dict(zip(names, combo, strict=True))
            reads: set[tuple[str, str]] = set()

            def get(entity: str, attribute: str, _reads: set = reads) -> Any:
                _reads.add((entity, attribute))
                return values.get((entity, attribute))

            if rule.when is not None and rule.when(env, get):
                culprits = [writer[k] for k in reads if k in writer]
                agent = actions[max(culprits)][2] if culprits else None
                self._charge(selected, agent, 1.0, penalties, violations,
                             f"{rule.when.text} with " + ", ".join(
                                 f"{k}={v}" for k, v in env.items()))

    def _plan_rules(self, plan: Plan, penalties: dict, violations: list) -> None:
        if not self.problem.rules:
            return
        actions = sorted(plan.actions, key=lambda a: a.index)
        for selected in self.problem.rules.values():
            rule = selected.rule
            if rule.kind == "sequence":
                self._sequence(selected, actions, penalties, violations)
            elif rule.kind == "decomposition":
                for node in plan.tree.values():
                    if node.task == rule.method and node.decomposition == rule.decomposition:
                        agent = self._first_agent(plan, node)
                        self._charge(selected, agent, 1.0, penalties, violations,
                                     f"{node.task} decomposed as {node.decomposition}")
            elif rule.kind == "effort":
                human = sum(a.cost for a in actions if self._kind(a.agent) == "human")
                robot = sum(a.cost for a in actions if self._kind(a.agent) == "robot")
                humans = [a.agent for a in actions if self._kind(a.agent) == "human"]
                if human > robot:
                    self._charge(selected, humans[0] if humans else None, human - robot,
                                 penalties, violations,
                                 f"human effort {human:g} > robot effort {robot:g}")
            elif rule.kind == "timeout":
                for agent, stream in plan.streams.items():
                    for prev, nxt in zip(stream, stream[1:], strict=False):
                        gap = nxt.start - prev.end
                        if gap > rule.max_wait:
                            self._charge(selected, agent, gap - rule.max_wait, penalties,
                                         violations, f"{agent} waits {gap:g} between {prev} "
                                         f"and {nxt}")
            elif rule.kind == "crossed-links":
                by_index = {a.index: a for a in actions}
                for link in plan.links:
                    producer, consumer = by_index[link.producer], by_index[link.consumer]
                    if producer.agent != consumer.agent:
                        self._charge(selected, consumer.agent, 1.0, penalties, violations,
                                     f"{producer} ({producer.agent}) -> {consumer} "
                                     f"({consumer.agent}) on {link.fact}")

    def _first_agent(self, plan: Plan, node: TreeNode) -> str | None:
        stack = [node]
        while stack:
            current = stack.pop(0)
            if current.action is not None:
                return plan.actions[current.action].agent
            stack[:0] = [plan.tree[c] for c in current.children]
        return None

    def _matches(self, act: PlanAction, pattern: tuple[str, str | None] | None) -> bool:
        if pattern is None:
            return False
        name, kind = pattern
        return act.name == name and (kind is None or self._kind(act.agent) == kind)

    def _arg(self, act: PlanAction, param: str) -> Any:
        params = [p for p, _ in self.domain.actions[act.name].params]
        return act.args[params.index(param)] if param in params else None

    def _sequence(self, selected: SelectedRule, actions: list[PlanAction], penalties: dict,
                  violations: list) -> None:
        rule = selected.rule
        for i, first in enumerate(actions):
            if not self._matches(first, rule.first):
                continue
            linked = {self._arg(first, p) for p, _ in rule.link}
            for second in actions[i + 1:]:
                if rule.link:
                    related = all(self._arg(first, p) == self._arg(second, q)
                                  for p, q in rule.link)
                    touches = bool(linked & set(second.args))
                elif rule.agents == "same":
                    related = touches = second.agent == first.agent
                else:
                    related = touches = True
                if not touches and rule.immediately:
                    continue
                agents_ok = (rule.agents == "any"
                             or (rule.agents == "same") == (second.agent == first.agent))
                if related and agents_ok and self._matches(second, rule.then):
                    self._charge(selected, second.agent, 1.0, penalties, violations,
                                 f"{first} ({first.agent}) then {second} ({second.agent})")
                    break
                if rule.immediately:
                    break

    # -- the score ------------------------------------------------------------------------------

    def _score(self, plan: Plan, penalties: dict[str, float], violations: list[str]) -> None:
        actions = plan.actions
        kinds = {agent: self._kind(agent) for agent in {a.agent for a in actions}}
        criteria = {
            "cost": sum(a.cost for a in actions),
            "duration": plan.makespan,
            "human-effort": sum(a.cost for a in actions if kinds[a.agent] == "human"),
            "robot-effort": sum(a.cost for a in actions if kinds[a.agent] == "robot"),
        }
        weighted = {name: self.problem.rules[name].weight * value
                    for name, value in penalties.items()}
        criteria["rules"] = sum(weighted.values())
        criteria.update(weighted)
        plan.criteria = criteria
        plan.weights = {name: self.weights.get(name, 0.0) / self.scale.get(name, 1.0)
                        for name in criteria}
        plan.score = sum(plan.weights[name] * value for name, value in criteria.items())
        plan.violations = violations
