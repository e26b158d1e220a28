"""Pictures of plans, as DOT source: the decomposition tree and the per-agent streams.

Two views of one :class:`~planner.model.plan.Plan`, after the SHARY paper's figures:

* :func:`tree_dot` -- the HTN decomposition tree (Fig. 9b): compound tasks with
  the decomposition chosen, actions as leaves coloured by agent;
* :func:`streams_dot` -- one lane per agent (Fig. 10): each agent's actions in
  time order, and the causal links that tie one agent's stream to another's.

Both return DOT text built with the ``graphviz`` package; laying it out (to
SVG, PNG...) is left to the caller.  Every label is an HTML-like label with its
text escaped, so task arguments may hold any character; node identifiers are
``t<id>`` (tree nodes) and ``a<index>`` (actions), never with a ``:``, which DOT
would read as a port.  An agent has the same colour in both pictures.
"""

from __future__ import annotations

import html
from typing import Any

import graphviz

from planner.model.plan import Plan, PlanAction, TreeNode

FONT = "DejaVu Sans"
"""The font dot measures labels with: wider than Helvetica or Arial, so a box sized
for it holds its label in any viewer (an SVG viewer on Linux draws Helvetica as
DejaVu Sans; boxes measured for Helvetica overflowed)."""

PALETTE: tuple[tuple[str, str], ...] = (
    ("#c6dbef", "#2171b5"),  # blue
    ("#fdd0a2", "#d94801"),  # orange
    ("#c7e9c0", "#238b45"),  # green
    ("#dadaeb", "#6a51a3"),  # purple
    ("#fcbba1", "#cb181d"),  # red
    ("#d9d9d9", "#525252"),  # grey
    ("#f6e8c3", "#8c6d31"),  # brown
    ("#ccebc5", "#01665e"),  # teal
)
"""(fill, line) colour pairs, given to the agents in order of first appearance."""

MAIN_SIZE = 11
SMALL_SIZE = 8
NODE_MARGIN = (0.12, 0.05)
"""A box's margin around its label, in inches (dot's ``margin``)."""
_NARROW = set("fijlrtIJ' .,:;!|-·/()[]")
_WIDE = set("mwMW=<>&…%@")

TASK_FILL = "#f7f7f7"
TASK_LINE = "#636363"
SMALL = "#555555"


def text_width(text: str, size: float) -> float:
    """An estimate of ``text``'s rendered width in points (pixels at 72 dpi), from
    DejaVu Sans (wider than Helvetica or Arial) plus a few per cent, so that a box
    sized by it holds its text in any viewer.  The timeline sizes its labels by it too."""
    return 1.04 * size * sum(
        0.36 if c in _NARROW else 0.96 if c in _WIDE else 0.72 if c.isupper()
        else 0.62 if c.isascii() else 1.0 for c in text)


def _text(value: Any) -> str:
    return html.escape(str(value), quote=True)


def _time(value: float) -> str:
    return f"{value:g}"


def _call(name: str, args: tuple[Any, ...]) -> str:
    return f"{name}({', '.join(str(a) for a in args)})"


def _label(main: str, *small: str, size: int = SMALL_SIZE) -> str:
    """An HTML-like label: ``main`` in the node's font, then lines of small grey text."""
    lines = [_text(main)]
    lines += [f'<font point-size="{size}" color="{SMALL}">{_text(s)}</font>'
              for s in small if s]
    return "<" + "<br/>".join(lines) + ">"


def _title(*lines: str) -> str:
    first, *rest = [line for line in lines if line]
    out = f"<<b>{_text(first)}</b>"
    out += "".join(f'<br/><font point-size="10">{_text(r)}</font>' for r in rest)
    return out + ">"


def agent_colours(plan: Plan) -> dict[str, tuple[str, str]]:
    """Each agent's (fill, line) colour: the palette in order of first appearance
    among the plan's actions (by index), cycling if there are more agents."""
    out: dict[str, tuple[str, str]] = {}
    for action in sorted(plan.actions, key=lambda a: a.index):
        if action.agent not in out:
            out[action.agent] = PALETTE[len(out) % len(PALETTE)]
    return out


def _action_of(by_index: dict[int, PlanAction], node: TreeNode) -> PlanAction:
    if node.action not in by_index:
        raise ValueError(f"tree node {node.id} ({node.task}) refers to action "
                         f"{node.action}, which the plan does not have")
    return by_index[node.action]


def _tree_order(plan: Plan) -> list[int]:
    """The tree's node ids, depth first from the roots in order (then any node no
    root reaches, so that nothing is silently dropped)."""
    seen: set[int] = set()
    order: list[int] = []
    starts = list(plan.roots) + sorted(plan.tree)
    for start in starts:
        stack = [start]
        while stack:
            node_id = stack.pop()
            if node_id in seen or node_id not in plan.tree:
                continue
            seen.add(node_id)
            order.append(node_id)
            stack.extend(reversed(plan.tree[node_id].children))
    return order


def tree_dot(plan: Plan, title: str = "") -> str:
    """DOT source of the plan's decomposition tree (like SHARY's Fig. 9b).

    Compound tasks are rounded grey boxes labelled ``Task(args)`` with the chosen
    decomposition in small text; actions are boxes labelled ``Action(args)`` with
    their agent, filled with the agent's colour.  Edges go parent -> child; the
    children of a node share a rank and keep the plan's order, left to right.
    """
    colours = agent_colours(plan)
    graph = graphviz.Digraph("plan_tree", graph_attr={
        "rankdir": "TB", "ordering": "out", "fontname": FONT, "labelloc": "t",
        "nodesep": "0.25", "ranksep": "0.45"},
        node_attr={"fontname": FONT, "fontsize": "11", "style": "filled", "margin": "0.12,0.05"},
        edge_attr={"color": "#777777", "arrowsize": "0.6"})
    if title:
        graph.attr(label=_title(title), fontsize="14")
    order = _tree_order(plan)
    by_index = {a.index: a for a in plan.actions}
    for node_id in order:
        node = plan.tree[node_id]
        if node.action is not None:
            action = _action_of(by_index, node)
            fill, line = colours[action.agent]
            graph.node(f"t{node_id}", _label(str(action), action.agent), shape="box",
                       fillcolor=fill, color=line)
        else:
            small = f"[{node.decomposition}]" if node.decomposition else ""
            graph.node(f"t{node_id}", _label(_call(node.task, node.args), small),
                       shape="box", style="rounded,filled", fillcolor=TASK_FILL,
                       color=TASK_LINE)
    for node_id in order:
        children = [c for c in plan.tree[node_id].children if c in plan.tree]
        for child in children:
            graph.edge(f"t{node_id}", f"t{child}")
        if len(children) > 1:
            with graph.subgraph() as rank:
                rank.attr(rank="same")
                for child in children:
                    rank.node(f"t{child}")
    return graph.source


def _box_width(action: PlanAction) -> float:
    """The width, in points, of an action's box in the streams: its label and margins."""
    return max(text_width(str(action), MAIN_SIZE),
               text_width(_span(action), SMALL_SIZE)) + 2 * 72 * NODE_MARGIN[0]


def _span(action: PlanAction) -> str:
    return f"{_time(action.start)}-{_time(action.end)}"


def _columns(plan: Plan) -> dict[float, list[PlanAction]]:
    """The actions tied to each distinct start time: in each lane, the first of the
    actions that start then (with zero durations, the others follow it, left to right)."""
    firsts: dict[float, list[PlanAction]] = {}
    for actions in plan.streams.values():
        for before, action in zip([None, *actions], actions, strict=False):
            if before is None or before.start != action.start:
                firsts.setdefault(action.start, []).append(action)
    return dict(sorted(firsts.items()))


def _time_axis(graph: graphviz.Digraph, plan: Plan, columns: dict[float, list[PlanAction]],
               widths: dict[float, float]) -> None:
    """A ruler of time ticks, one per distinct start time, each on the rank of the
    actions that start then, so that the lanes line up by time.

    Each rank is a column as wide as its widest box; every box of the column is
    given that width and so is the tick, whose time sits flush left: the tick
    marks the boxes' left edges, where they start.  The last tick also shows
    the makespan, flush right, at the boxes' right edges.
    """
    if not columns:
        return
    moments = list(columns)
    with graph.subgraph(name="time_axis") as axis:
        for number, moment in enumerate(moments):
            width = widths[moment]
            start = _text(f"t = {_time(moment)}")
            cells = f'<td align="left" width="{width:.0f}">{start}</td>'
            if number == len(moments) - 1 and plan.makespan > moment:
                end = f"t = {_time(plan.makespan)}"
                room = text_width(end, 9) + 2
                cells = (f'<td align="left" width="{width - room:.0f}">{start}</td>'
                         f'<td align="right" width="{room:.0f}">{_text(end)}</td>')
            axis.node(f"time{number}",
                      f'<<table border="0" cellborder="0" cellspacing="0" cellpadding="0" '
                      f'width="{width:.0f}" fixedsize="true"><tr>{cells}</tr></table>>',
                      shape="plaintext", style="", fontsize="9", fontcolor=SMALL, margin="0",
                      width=f"{width / 72:.3f}", height="0.2")
        for number in range(len(moments) - 1):
            axis.edge(f"time{number}", f"time{number + 1}", color="#bbbbbb", arrowhead="none")
    for number, moment in enumerate(moments):
        with graph.subgraph() as rank:
            rank.attr(rank="same")
            rank.node(f"time{number}")
            for action in sorted(columns[moment], key=lambda a: a.index):
                rank.node(f"a{action.index}")


def streams_dot(plan: Plan, title: str = "") -> str:
    """DOT source of the plan's per-agent streams (like SHARY's Fig. 10).

    One horizontal lane (a cluster) per agent, its actions left to right in time
    order with their ``start-end`` times, consecutive actions joined by plain
    edges.  Causal links from one agent's action to another agent's are coloured
    (the producer's colour) dashed edges labelled ``entity.attribute``; links
    within a lane are already implied by the lane's order and are not drawn.
    The title carries the plan's score and makespan.
    """
    colours = agent_colours(plan)
    graph = graphviz.Digraph("plan_streams", graph_attr={
        "rankdir": "LR", "fontname": FONT, "labelloc": "t", "nodesep": "0.6",
        "ranksep": "0.35", "newrank": "true"},
        node_attr={"fontname": FONT, "fontsize": str(MAIN_SIZE), "shape": "box",
                   "style": "filled", "margin": f"{NODE_MARGIN[0]},{NODE_MARGIN[1]}"},
        edge_attr={"color": "#444444", "arrowsize": "0.6", "fontname": FONT,
                   "fontsize": "9"})
    graph.attr(label=_title(title or "plan streams",
                            f"score {plan.score:.4g}   makespan {_time(plan.makespan)}"),
               fontsize="14")
    streams = plan.streams
    columns = _columns(plan)
    widths = {moment: max(_box_width(a) for a in tied) for moment, tied in columns.items()}
    box_width = {a.index: widths[moment] for moment, tied in columns.items() for a in tied}
    lanes = sorted(streams, key=lambda agent: list(colours).index(agent))
    for number, agent in enumerate(lanes):
        fill, line = colours[agent]
        with graph.subgraph(name=f"cluster_{number}") as lane:
            lane.attr(label=_label(agent), color=line, style="rounded", penwidth="1.2",
                      fontname=FONT, fontsize="12", labeljust="l")
            actions = streams[agent]
            for action in actions:
                sized = {"width": f"{box_width[action.index] / 72:.3f}"} \
                    if action.index in box_width else {}
                lane.node(f"a{action.index}", _label(str(action), _span(action)),
                          fillcolor=fill, color=line, **sized)
            for before, after in zip(actions, actions[1:], strict=False):
                lane.edge(f"a{before.index}", f"a{after.index}")
    _time_axis(graph, plan, columns, widths)
    agent_of = {a.index: a.agent for a in plan.actions}
    for link in plan.links:
        producer, consumer = agent_of.get(link.producer), agent_of.get(link.consumer)
        if producer is None or consumer is None or producer == consumer:
            continue
        line = colours[producer][1]
        graph.edge(f"a{link.producer}", f"a{link.consumer}",
                   label=f'<<table border="0" cellborder="0" cellpadding="3" cellspacing="0">'
                         f"<tr><td>{_text(link.fact)}</td></tr></table>>", style="dashed",
                   color=line, fontcolor=line, penwidth="1.3")
    return graph.source
