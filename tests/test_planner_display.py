"""Plan pictures: the decomposition tree and the per-agent streams, as DOT."""

from __future__ import annotations

import re
import shutil
import subprocess

import pytest

from planner.display.plans import PALETTE, agent_colours, streams_dot, tree_dot
from planner.model.plan import CausalLink, Plan, PlanAction, TreeNode


def clean_up_plan() -> Plan:
    """The recovery plan of SHARY's Fig. 10: alice fetches the bottle and gives it
    to jido, who has come to the table meanwhile, then dumps it in the trash."""
    a = PlanAction
    actions = [
        a(0, "Move", ("alice", "table"), "alice", 2, 3, 0, 3),
        a(1, "Move", ("jido", "table"), "jido", 1, 4, 0, 4),
        a(2, "Pick", ("alice", "yellow-bottle", "table"), "alice", 1, 2, 3, 5),
        a(3, "Give", ("alice", "jido", "yellow-bottle"), "alice", 1, 2, 5, 7),
        a(4, "Move", ("jido", "trash"), "jido", 1, 3, 7, 10),
        a(5, "Dump", ("jido", "yellow-bottle", "trash"), "jido", 1, 1, 10, 11),
    ]
    links = [
        CausalLink(0, 2, "alice", "posTopo"),             # within alice's lane
        CausalLink(2, 3, "yellow-bottle", "holder"),      # within alice's lane
        CausalLink(1, 3, "jido", "posTopo"),              # jido -> alice
        CausalLink(3, 4, "yellow-bottle", "holder"),      # alice -> jido
        CausalLink(3, 5, "yellow-bottle", "holder"),      # alice -> jido
        CausalLink(4, 5, "jido", "posTopo"),              # within jido's lane
    ]
    t = TreeNode
    tree = {
        0: t(0, "CleanUp", ("yellow-bottle",), "with-help", [1, 6]),
        1: t(1, "GetObject", ("jido", "yellow-bottle"), "handed-over", [2, 5]),
        2: t(2, "ReachObject", ("alice", "yellow-bottle"), "on-furniture", [3, 4]),
        3: t(3, "Move", ("alice", "table"), action=0),
        4: t(4, "Pick", ("alice", "yellow-bottle", "table"), action=2),
        5: t(5, "HandOver", ("alice", "jido", "yellow-bottle"), "direct", [7, 8]),
        7: t(7, "Move", ("jido", "table"), action=1),
        8: t(8, "Give", ("alice", "jido", "yellow-bottle"), action=3),
        6: t(6, "Throw", ("jido", "yellow-bottle", "trash"), "dump", [9, 10]),
        9: t(9, "Move", ("jido", "trash"), action=4),
        10: t(10, "Dump", ("jido", "yellow-bottle", "trash"), action=5),
    }
    return Plan(actions, links, [], tree, [0], criteria={"cost": 7.0, "duration": 11.0},
                weights={"cost": 0.6, "duration": 0.4}, score=8.6)


COMPOUND = {
    "CleanUp(yellow-bottle)": "with-help",
    "GetObject(jido, yellow-bottle)": "handed-over",
    "ReachObject(alice, yellow-bottle)": "on-furniture",
    "HandOver(alice, jido, yellow-bottle)": "direct",
    "Throw(jido, yellow-bottle, trash)": "dump",
}


def node_lines(source: str) -> dict[str, str]:
    """Node id -> its DOT statement."""
    return {m.group(1): m.group(0)
            for m in re.finditer(r"^\s*(\w+) \[label=.*$", source, re.MULTILINE)}


def edges(source: str) -> list[tuple[str, str, str]]:
    """(tail, head, attributes) of every edge statement."""
    return [(m.group(1), m.group(2), m.group(3) or "")
            for m in re.finditer(r"^\s*(\w+) -> (\w+)(?: \[(.*)\])?$", source, re.MULTILINE)]


# -- the tree ----------------------------------------------------------------


def test_tree_has_every_action_compound_task_and_decomposition():
    plan = clean_up_plan()
    source = tree_dot(plan, "clean-up(yellow-bottle)")
    for action in plan.actions:
        assert str(action) in source
    for task, decomposition in COMPOUND.items():
        assert task in source
        assert f"[{decomposition}]" in source
    assert "clean-up(yellow-bottle)" in source
    assert ":" not in "".join(node_lines(source))
    assert set(node_lines(source)) == {f"t{i}" for i in plan.tree}


def test_tree_edges_go_parent_to_child_in_order_with_siblings_on_one_rank():
    plan = clean_up_plan()
    source = tree_dot(plan)
    expected = [(f"t{n.id}", f"t{c}") for n in plan.tree.values() for c in n.children]
    found = [(tail, head) for tail, head, _ in edges(source)]
    assert sorted(found) == sorted(expected)
    # Children of a node appear left to right in plan order.
    assert found.index(("t1", "t2")) < found.index(("t1", "t5"))
    assert found.index(("t5", "t7")) < found.index(("t5", "t8"))
    assert "ordering=out" in source
    assert "rank=same" in source
    assert re.search(r"rank=same\s+t2\s+t5", source)


def test_tree_colours_actions_by_agent_in_order_of_first_appearance():
    plan = clean_up_plan()
    colours = agent_colours(plan)
    assert list(colours) == ["alice", "jido"]
    assert colours["alice"] == PALETTE[0] and colours["jido"] == PALETTE[1]
    nodes = node_lines(tree_dot(plan))
    for node in plan.tree.values():
        if node.action is None:
            continue
        agent = plan.actions[node.action].agent
        assert f'fillcolor="{colours[agent][0]}"' in nodes[f"t{node.id}"]
        assert agent in nodes[f"t{node.id}"]


def test_tree_labels_are_escaped():
    plan = Plan([PlanAction(0, "Say", ('"<hi> & bye"',), "r2", 1, 1, 0, 1)], [], [],
                {0: TreeNode(0, "Talk", ("a<b",), "x&y", [1]),
                 1: TreeNode(1, "Say", (), action=0)}, [0])
    source = tree_dot(plan)
    assert "Talk(a&lt;b)" in source and "[x&amp;y]" in source
    assert "Say(&quot;&lt;hi&gt; &amp; bye&quot;)" in source


def test_tree_refuses_a_node_pointing_at_a_missing_action():
    plan = Plan([], [], [], {0: TreeNode(0, "Ghost", (), action=3)}, [0])
    with pytest.raises(ValueError, match="action 3"):
        tree_dot(plan)


# -- the streams ---------------------------------------------------------------


def test_streams_have_one_cluster_per_agent_and_every_action_with_its_times():
    plan = clean_up_plan()
    source = streams_dot(plan, "clean-up")
    clusters = re.findall(r"subgraph (cluster_\d+) \{\s*.*label=<(\w+)>", source)
    assert [agent for _, agent in clusters] == ["alice", "jido"]
    assert source.count("subgraph cluster") == 2
    nodes = node_lines(source)
    for action in plan.actions:
        line = nodes[f"a{action.index}"]
        assert str(action) in line
        assert f"{action.start:g}-{action.end:g}" in line


def test_streams_join_consecutive_actions_of_a_lane():
    plan = clean_up_plan()
    plain = {(tail, head) for tail, head, attrs in edges(streams_dot(plan))
             if tail.startswith("a") and "dashed" not in attrs}
    assert plain == {("a0", "a2"), ("a2", "a3"), ("a1", "a4"), ("a4", "a5")}


def test_streams_draw_one_dashed_labelled_edge_per_inter_agent_link():
    plan = clean_up_plan()
    source = streams_dot(plan)
    dashed = [(tail, head, attrs) for tail, head, attrs in edges(source) if "dashed" in attrs]
    crossing = [link for link in plan.links
                if plan.actions[link.producer].agent != plan.actions[link.consumer].agent]
    assert len(crossing) == 3
    assert sorted((t, h) for t, h, _ in dashed) == sorted(
        (f"a{link.producer}", f"a{link.consumer}") for link in crossing)
    colours = agent_colours(plan)
    for link in crossing:
        attrs = next(a for t, h, a in dashed
                     if (t, h) == (f"a{link.producer}", f"a{link.consumer}"))
        assert f"<td>{link.entity}.{link.attribute}</td>" in attrs  # padded off its line
        assert f'color="{colours[plan.actions[link.producer].agent][1]}"' in attrs
    assert source.count("posTopo") == 1  # the within-lane posTopo links are not drawn


def test_streams_title_has_score_and_makespan():
    plan = clean_up_plan()
    source = streams_dot(plan, "recovery plan")
    assert "recovery plan" in source
    assert "score 8.6" in source and "makespan 11" in source


def test_streams_line_lanes_up_on_a_time_axis():
    source = streams_dot(clean_up_plan())
    # A tick per distinct start time, the last one with the makespan; 4 is only an end.
    ticks = re.findall(r"<td align=\"(?:left|right)\"[^>]*>t = (\d+)</td>", source)
    assert ticks == ["0", "3", "5", "7", "10", "11"]
    # Both moves start at 0: on the rank of the first tick.
    assert re.search(r"rank=same\s+time0\s+a0\s+a1", source)


def test_empty_plan_still_gives_a_graph():
    plan = Plan([], [], [], {}, [])
    assert tree_dot(plan).startswith("digraph")
    source = streams_dot(plan)
    assert "makespan 0" in source and "cluster" not in source


# -- layout through graphviz-pure ------------------------------------------------


def _graphviz_pure() -> str:
    found = shutil.which("graphviz-pure")
    if not found:
        pytest.skip("graphviz-pure is not installed")
    return found


@pytest.mark.parametrize("draw", [tree_dot, streams_dot])
def test_dot_renders_through_graphviz_pure(draw, tmp_path):
    executable = _graphviz_pure()
    source = draw(clean_up_plan(), "clean-up(yellow-bottle)")
    for fmt in ("png", "svg"):
        out = tmp_path / f"{draw.__name__}.{fmt}"
        done = subprocess.run([executable, f"-T{fmt}", "-o", str(out)],
                              input=source.encode("utf-8"), capture_output=True, timeout=60,
                              check=False)
        assert done.returncode == 0, done.stderr.decode("utf-8", "replace")
        assert out.stat().st_size > 0
    svg = (tmp_path / f"{draw.__name__}.svg").read_text(encoding="utf-8")
    assert "Dump(jido, yellow&#45;bottle, trash)" in svg.replace("-", "&#45;")


def _svg_nodes(svg: str) -> dict[str, tuple[float, float, list[tuple[str, float, float]]]]:
    """Each node of an SVG from dot: id -> (left, right, [(text, x, font size)])."""
    import xml.etree.ElementTree as ET

    ns = "{http://www.w3.org/2000/svg}"
    out = {}
    for g in ET.fromstring(svg).iter(f"{ns}g"):
        if g.get("class") != "node":
            continue
        texts = [(t.text or "", float(t.get("x")), float(t.get("font-size")))
                 for t in g.iter(f"{ns}text")]
        polygon = g.find(f"{ns}polygon")
        xs = ([float(v) for v in re.findall(r"(-?[\d.]+),-?[\d.]+", polygon.get("points"))]
              if polygon is not None else [t[1] for t in texts])
        out[g.findtext(f"{ns}title")] = (min(xs), max(xs), texts)
    return out


def test_streams_boxes_hold_their_labels_and_the_ruler_marks_their_left_edges(tmp_path):
    from planner.display.plans import text_width

    svg = subprocess.run([_graphviz_pure(), "-Tsvg"], capture_output=True, check=True,
                         input=streams_dot(clean_up_plan()).encode()).stdout.decode()
    found = _svg_nodes(svg)
    plan = clean_up_plan()
    for action in plan.actions:
        left, right, texts = found[f"a{action.index}"]
        for text, _, size in texts:
            assert right - left >= text_width(text, size), text
    starts = sorted({a.start for a in plan.actions})
    for number, moment in enumerate(starts):
        _, _, texts = found[f"time{number}"]
        tick_x = texts[0][1]  # the start time, flush left
        lefts = [found[f"a{a.index}"][0] for a in plan.actions if a.start == moment]
        assert any(abs(tick_x - left) < 3 for left in lefts), (moment, tick_x, lefts)
    # the makespan, flush right on the last tick, at the right edge of the last boxes
    _, _, texts = found[f"time{len(starts) - 1}"]
    assert texts[-1][0] == f"t = {plan.makespan:g}"
