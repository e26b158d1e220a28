"""Pictures and text of conditional plans: the policy, the explored tree, the streams.

Three views of one :class:`~planner.conditional.policy.Policy`, drawn from the same
abstract/primitive tasks the supervisor reads (:func:`planner.conditional.sharedplan.to_dict`),
so that the ids in a picture are the plan's:

* :func:`policy_dot` -- the policy, top to bottom: each task a box in its
  agent's colour (an AgentX box is striped with the candidates' colours), each
  human decision a diamond whose edges name the option, its probability and
  the cost expected after it, each leaf the branch's cost;
* :func:`tree_dot` -- the same, plus the robot's options the policy did not
  keep (dashed, grey, with the cost they would have had): what was explored;
* :func:`streams_dot` -- one cluster per branch, one row per agent, the
  agent's tasks in order, a column per round of turns: who does what, and
  when, in each case.

:func:`policy_lines` is the terminal's view: the policy as an indented list.
"""

from __future__ import annotations

from typing import Any

import graphviz

from planner.conditional.policy import Choice, Policy
from planner.conditional.sharedplan import to_dict
from planner.display.plans import FONT, PALETTE, SMALL, TASK_FILL, TASK_LINE, _label, _text, _title

_MARKER = {"wait": "#eeeeee", "idle": "#f7f7f7", "done": "#f7f7f7"}


def _colours(plan: dict[str, Any]) -> dict[str, tuple[str, str]]:
    return {agent: PALETTE[i % len(PALETTE)] for i, agent in enumerate(plan["agents"])}


def _param(value: Any) -> str:
    if isinstance(value, dict):
        if "any-of" in value:
            return "any-of[" + ", ".join(value["any-of"]) + "]"
        return f"?{value['var']}"
    return str(value)


def task_text(task: dict[str, Any]) -> str:
    """``Name(params)`` as people read it, open values included."""
    return f"{task['name']}({', '.join(_param(p) for p in task['params'])})"


def _who(task: dict[str, Any]) -> str:
    return _param(task["agent"])


def _graph(name: str, plan: dict[str, Any], title: str, rankdir: str = "TB"
           ) -> graphviz.Digraph:
    graph = graphviz.Digraph(name, graph_attr={
        "rankdir": rankdir, "fontname": FONT, "labelloc": "t", "nodesep": "0.3",
        "ranksep": "0.3"},
        node_attr={"fontname": FONT, "fontsize": "11", "shape": "box", "style": "filled",
                   "margin": "0.12,0.05"},
        edge_attr={"color": "#777777", "arrowsize": "0.6", "fontname": FONT, "fontsize": "9"})
    cost = "no plan" if plan["cost"] is None else f"{plan['mode']} cost {plan['cost']:.4g}"
    graph.attr(label=_title(title or plan["problem"], f"{cost}   {len(plan['branches'])} "
                            f"branches in the policy, {plan['leaves_explored']} explored"),
               fontsize="14")
    return graph


def _task_node(graph: graphviz.Digraph, task: dict[str, Any],
               colours: dict[str, tuple[str, str]], node_id: str = "") -> None:
    node_id = node_id or f"p{task['id']}"
    if task["kind"] != "action":
        graph.node(node_id, _label(task["name"].lower(), _who(task), size=7),
                   fillcolor=_MARKER[task["kind"]], color="#bbbbbb", fontcolor=SMALL,
                   fontsize="8", style="rounded,filled")
        return
    agent = task["agent"]
    queries = [f"?{p['var']}: {p['query']}  ({' | '.join(p['candidates'])})"
               for p in task["params"] if isinstance(p, dict) and "query" in p]
    if isinstance(agent, dict):  # AgentX: the candidates' colours side by side
        fills = ":".join(colours.get(a, PALETTE[-1])[0] for a in agent["any-of"])
        graph.node(node_id, _label(task_text(task), f"#{task['id']}  {_who(task)}", *queries),
                   fillcolor=fills, style="striped", color=TASK_LINE)
        return
    fill, line = colours.get(agent, PALETTE[-1])
    graph.node(node_id, _label(task_text(task), f"#{task['id']}  {agent}", *queries),
               fillcolor=fill, color=line)


def _draw(graph: graphviz.Digraph, plan: dict[str, Any]) -> dict[int, dict]:
    colours = _colours(plan)
    tasks = {t["id"]: t for t in plan["primitive"]}
    for task in plan["primitive"]:
        _task_node(graph, task, colours)
    decided = {o["task"] for d in plan["decisions"] for o in d["options"]}
    for task in plan["primitive"]:
        for before in task["predecessors"]:
            if task["id"] not in decided:
                graph.edge(f"p{before}", f"p{task['id']}")
    for decision in plan["decisions"]:
        node = f"decide_{decision['id']}"
        graph.node(node, _label(f"{decision['agent']} decides", decision["id"], size=8),
                   shape="diamond", fillcolor=colours.get(decision["agent"], PALETTE[-1])[0],
                   color=colours.get(decision["agent"], PALETTE[-1])[1], margin="0.02")
        if decision["after"] is not None:
            graph.edge(f"p{decision['after']}", node)
        for option in decision["options"]:
            graph.edge(node, f"p{option['task']}", label=_text(
                f"p={option['probability']:.2g}, then {option['cost']:.4g}"),
                fontcolor=SMALL, penwidth="1.4")
    for number, branch in enumerate(plan["branches"], start=1):
        leaf = f"leaf{number}"
        graph.node(leaf, _label(f"branch {number}", f"cost {branch['cost']:.4g}", size=8),
                   shape="box", style="rounded,filled,bold", fillcolor=TASK_FILL,
                   color=TASK_LINE, fontsize="9")
        if branch["leaf"] is not None:
            graph.edge(f"p{branch['leaf']}", leaf)
    return tasks


def policy_dot(policy: Policy, title: str = "") -> str:
    """DOT source of the policy: tasks, human decisions, leaves with their cost."""
    plan = to_dict(policy)
    graph = _graph("conditional_policy", plan, title)
    _draw(graph, plan)
    return graph.source


def tree_dot(policy: Policy, title: str = "") -> str:
    """DOT source of the policy and the planner's options it did not keep (dashed)."""
    plan = to_dict(policy)
    graph = _graph("conditional_tree", plan, title)
    tasks = _draw(graph, plan)
    rejected = _rejected(policy, plan, tasks)
    for number, (after, text, value) in enumerate(rejected):
        node = f"r{number}"
        graph.node(node, _label(text, f"not chosen: {value:.4g} from here"), style="dashed",
                   color="#999999", fontcolor="#777777")
        graph.edge(f"p{after}" if after is not None else node, node, style="dashed",
                   color="#999999")
    return graph.source


def _rejected(policy: Policy, plan: dict[str, Any], tasks: dict[int, dict]
              ) -> list[tuple[int | None, str, float]]:
    """The planner's options not kept, placed after the task that precedes them: the
    policy's turns are walked in the order :func:`to_dict` numbered them."""
    out: list[tuple[int | None, str, float]] = []
    first = [t for t in plan["primitive"] if not t["predecessors"]]
    stack: list[tuple[Choice, int | None, list[dict]]] = [(policy.root, None, first)] \
        if policy.root is not None else []
    children: dict[int | None, list[dict]] = {}
    for task in plan["primitive"]:
        for before in task["predecessors"] or [None]:
            children.setdefault(before, []).append(task)
    while stack:
        node, previous, nexts = stack.pop()
        if node.kind == "leaf":
            continue
        for step, value in node.others:
            out.append((previous, str(step), step.cost + value))
        for (_, _, child), task in zip(node.options, nexts, strict=False):
            stack.append((child, task["id"], children.get(task["id"], [])))
    return out


def streams_dot(policy: Policy, title: str = "") -> str:
    """DOT source of each branch of the policy as one row of tasks per agent."""
    plan = to_dict(policy)
    colours = _colours(plan)
    graph = _graph("conditional_streams", plan, title, rankdir="LR")
    tasks = {t["id"]: t for t in plan["primitive"]}
    count = len(plan["agents"])
    numbered = list(enumerate(plan["branches"], start=1))
    for number, branch in reversed(numbered):  # dot stacks LR clusters bottom up
        chosen = [_option_text(plan, tasks[i]) for i in branch["tasks"]
                  if "decision" in tasks[i]]
        with graph.subgraph(name=f"cluster_b{number}") as cluster:
            cluster.attr(label=_label(f"branch {number}: cost {branch['cost']:.4g}",
                                      "; ".join(chosen) or "no decision"),
                         style="rounded", color="#999999", labeljust="l")
            rounds: dict[int, list[str]] = {}
            for agent in plan["agents"]:
                head = f"b{number}_{agent}"
                line = colours[agent][1]
                cluster.node(head, _label(agent), shape="plaintext", style="",
                             fontcolor=line)
                rounds.setdefault(-1, []).append(head)
                before = head
                for turn, task_id in enumerate(branch["tasks"]):
                    task = tasks[task_id]
                    if task["kind"] == "done" or not _owner(task, agent):
                        continue
                    node = f"b{number}_{task_id}"
                    _task_node(cluster, task, colours, node)
                    cluster.edge(before, node, style="invis" if before == head else "")
                    rounds.setdefault(turn // count, []).append(node)
                    before = node
            for nodes in rounds.values():  # one column per round of turns
                with cluster.subgraph() as rank:
                    rank.attr(rank="same")
                    for node in nodes:
                        rank.node(node)
    return graph.source


def _owner(task: dict[str, Any], agent: str) -> bool:
    who = task["agent"]
    return who == agent or (isinstance(who, dict) and who["any-of"][0] == agent)


def _option_text(plan: dict[str, Any], task: dict[str, Any]) -> str:
    return f"{task['decision']}: {task_text(task)}"


def policy_lines(policy: Policy) -> list[str]:
    """The policy as indented text: the tasks in turn, each decision's options below it."""
    plan = to_dict(policy)
    children: dict[int | None, list[dict]] = {}
    for task in plan["primitive"]:
        children.setdefault(task["predecessors"][0] if task["predecessors"] else None,
                            []).append(task)
    leaves = {b["leaf"]: (n, b["cost"]) for n, b in enumerate(plan["branches"], start=1)}
    lines: list[str] = []
    stack: list[tuple[dict, int]] = [(t, 0) for t in reversed(children.get(None, []))]
    while stack:
        task, depth = stack.pop()
        pad = "  " * depth
        if "decision" in task:
            option = next(o for d in plan["decisions"] if d["id"] == task["decision"]
                          for o in d["options"] if o["task"] == task["id"])
            lines.append(f"{pad}[{task['decision']} option {task['option'] + 1}, "
                         f"p={option['probability']:.3g}, cost after {option['cost']:.4g}]")
        if task["kind"] == "action":
            lines.append(f"{pad}  #{task['id']:<4} {_who(task):<12} {task_text(task)}")
        elif task["kind"] == "wait":
            lines.append(f"{pad}  #{task['id']:<4} {_who(task):<12} (waits)")
        if task["id"] in leaves:
            number, cost = leaves[task["id"]]
            lines.append(f"{pad}  -> branch {number} done, cost {cost:.4g}")
        nexts = children.get(task["id"], [])
        deeper = depth + (1 if len(nexts) > 1 else 0)
        stack.extend((t, deeper) for t in reversed(nexts))
    return lines
