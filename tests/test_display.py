"""Diagrams of schemes and task trees (DOT, Mermaid, SVG, PNG), and their commands."""

from __future__ import annotations

import re
import textwrap

import pytest
from scripted import World

from shary import load_scheme
from shary.io.schemes import parse_scheme
from shary.kernel.tasktree import TaskTree
from shary.log.contextlog import ContextLog, read_events
from shary.log.display import (
    ACTIVE_BACKGROUND,
    ACTIVE_FILL,
    edge_label,
    find_dot,
    render_dot,
    render_scheme,
    render_tree,
    scheme_dot,
    scheme_mermaid,
    tree_dot,
)
from userfiles.yamlsafe import load_text

BUILT_IN = ["give-object", "give-object-attentive", "robot-task", "ask-help"]

PARALLEL = """\
    scheme: hand.over
    initial: ask
    states:
      ask:
        act: ASK-TASK
        on:
          H-AGREE: together
          ping: {target: null, do: [{log: 'say "hi"; <now>'}]}
      together:
        parallel: true
        on: {done.state.together: end, restart: together}
        states:
          arm:
            initial: "moving:1"
            states:
              "moving:1": {on: {reached: arm.done}}
              arm.done: {final: true}
          watch:
            initial: attending
            states:
              attending: {on: {look-away: away}}
              away: {on: {look-back: last}}
              last: {history: shallow, default: attending}
      end: {act: END-TASK, final: true}
    """


def parallel_scheme():
    return parse_scheme(load_text(textwrap.dedent(PARALLEL), "hand.over.yaml"))


_ATTR = re.compile(r'(\w+)=("(?:[^"\\]|\\.)*"|<.*?>(?= \w+=|$)|[^ \]]+)')


def _attrs(text: str) -> dict[str, str]:
    return {k: v[1:-1] if v.startswith('"') else v for k, v in _ATTR.findall(text)}


def edges(source: str) -> list[tuple[str, str, dict[str, str]]]:
    """The DOT edge statements: (tail, head, attributes)."""
    found = (re.match(r"^\s*(\w+) -> (\w+)(?: \[(.*)\])?$", line)
             for line in source.splitlines())
    return [(m.group(1), m.group(2), _attrs(m.group(3) or "")) for m in found if m]


def nodes(source: str) -> dict[str, dict[str, str]]:
    """The DOT node statements: node id -> its attributes."""
    found = (re.match(r"^\s*(\w+) \[(.*)\]$", line) for line in source.splitlines())
    return {m.group(1): _attrs(m.group(2)) for m in found if m and m.group(1) not in
            ("graph", "node", "edge")}


def clusters(source: str) -> dict[str, dict[str, str]]:
    """The attributes of each cluster (the line after its ``subgraph``)."""
    return {name: _attrs(line) for name, line in
            re.findall(r"subgraph (\S+) \{\n\s*(.*)", source)}


def _edge_text(label: str | None) -> str | None:
    """The text of an edge label (padded in an HTML-like table by :func:`edge_label`)."""
    found = re.search(r"<td>(.*?)</td>", label or "")
    return found.group(1) if found else label


@pytest.mark.parametrize("name", BUILT_IN)
def test_dot_names_every_state_and_labels_every_transition(name):
    scheme = load_scheme(name)
    source = scheme_dot(scheme)
    labels = [attrs.get("label") for _, _, attrs in edges(source)]
    for state in scheme.all_states():
        assert state.name in source
        if state.act:
            assert f"{state.act} ({state.act_type.name})" in source
        for t in state.transitions:
            assert labels.count(edge_label(t.label())) >= len(t.targets)
    points = [n for n, attrs in nodes(source).items() if attrs.get("shape") == "point"]
    compound = [s for s in scheme.all_states() if s.kind == "compound"]
    assert len(points) == 1 + len(compound)  # the root's initial point, and one each


def test_dot_edges_attach_to_compound_states_at_their_borders():
    drawn = {(_edge_text(attrs.get("label")), head): (tail, attrs) for tail, head, attrs in
             edges(scheme_dot(load_scheme("give-object-attentive")))}
    # into realize: to its initial point, clipped at its border
    assert drawn["H-AGREE", "init_s_realize"] == ("s_ask", {"label": edge_label("H-AGREE"),
                                                             "lhead": "cluster_realize"})
    # out of realize and out of engaged: clipped at the border they leave
    assert drawn["done", "s_end"][1]["ltail"] == "cluster_realize"
    assert drawn["attention-lost", "s_suspended"][1]["ltail"] == "cluster_engaged"
    # into the deep history state inside engaged, not to engaged itself
    assert "lhead" not in drawn["attention-back", "s_resume"][1]
    # the question is a compound (its wait, call and ask bounded together): the root's
    # initial point goes into it, and its own to ask
    assert drawn[None, "init_s_asking"][0] == "init_root"
    assert drawn[None, "s_ask"][0] == "init_s_asking"
    assert drawn[None, "init_s_engaged"] == ("init_s_realize", {"lhead": "cluster_engaged"})


def test_dot_shapes_and_act_lines():
    source = scheme_dot(load_scheme("give-object-attentive"))
    drawn = nodes(source)
    assert drawn["s_resume"]["label"] == "H*" and drawn["s_resume"]["shape"] == "circle"
    assert drawn["s_ended"]["peripheries"] == "2" and "peripheries" not in drawn["s_end"]
    assert drawn["s_ask"]["label"].startswith("<ask<BR/>")
    assert "ASK-TASK (R-ACT)" in drawn["s_ask"]["label"]
    assert "REALIZE-TASK (R-ACT)" in clusters(source)["cluster_realize"]["label"]
    assert "compound=true" in source


def test_dot_parallel_regions_and_odd_names(tmp_path):
    source = scheme_dot(parallel_scheme())
    drawn = clusters(source)
    assert "dashed" in drawn["cluster_arm"]["style"]
    assert "dashed" in drawn["cluster_watch"]["style"]
    assert "dashed" not in drawn["cluster_together"]["style"]
    assert {"s_moving_1", "s_arm_done", "s_last"} <= set(nodes(source))  # from ':' and '.'
    assert nodes(source)["s_last"]["label"] == "H"  # shallow history
    # targetless and re-entering transitions are listed in the state, not drawn
    assert "say &quot;hi&quot;; &lt;now&gt;" in nodes(source)["s_ask"]["label"]
    assert "restart (re-enters)" in drawn["cluster_together"]["label"]
    assert "restart" not in [attrs.get("label") for _, _, attrs in edges(source)]
    render_dot(source, tmp_path / "p.svg")  # dot accepts it all
    assert "<svg" in (tmp_path / "p.svg").read_text()


def test_only_active_states_are_highlighted():
    scheme = load_scheme("give-object-attentive")
    source = scheme_dot(scheme, active=["suspended", "realize", "ended"])
    lit = {node for node, attrs in nodes(source).items()
           if attrs.get("fillcolor") == ACTIVE_FILL}
    assert lit == {"s_suspended", "s_ended"}
    drawn = clusters(source)
    assert [c for c, attrs in drawn.items() if "fillcolor" in attrs] == ["cluster_realize"]
    assert drawn["cluster_realize"]["fillcolor"] == ACTIVE_BACKGROUND
    assert drawn["cluster_realize"]["penwidth"] == "3"
    assert drawn["cluster_engaged"]["penwidth"] == "1"  # set, so not inherited
    assert ACTIVE_FILL not in scheme_dot(scheme) and ACTIVE_BACKGROUND not in scheme_dot(scheme)
    with pytest.raises(ValueError, match="nowhere"):
        scheme_dot(scheme, active=["nowhere"])


def test_mermaid_nests_states_separates_regions_and_marks_initials():
    text = scheme_mermaid(parallel_scheme(), active=["away"])
    lines = [line.strip() for line in text.splitlines()]
    assert lines[0] == "stateDiagram-v2"
    assert "state s_together {" in lines and "--" in lines
    assert lines[lines.index("state s_arm {") + 1] == "[*] --> s_moving_1"
    assert "[*] --> s_ask" in lines and "s_arm_done --> [*]" in lines
    assert 'state "H last" as s_last' in lines and "s_last --> s_attending" in lines
    assert "s_ask : ASK-TASK (R-ACT)" in lines
    assert "s_ask : ping / log 'say #34;hi#34;#59; #60;now#62;'" in lines
    assert "classDef active fill:#ffe680,stroke:#b8860b,stroke-width:3px" in lines
    assert [line for line in lines if line.startswith("class ")] == ["class s_away active"]
    ids = {word for line in lines for word in re.findall(r"\bs_\S+", line)}
    assert all(re.fullmatch(r"s_\w+", i) for i in ids)


def test_mermaid_is_a_state_diagram_with_safe_ids():
    text = scheme_mermaid(load_scheme("give-object-attentive"), active=["suspended"])
    assert text.startswith("stateDiagram-v2")
    assert "[*] --> s_ask" in text and "s_give_up" in text and "give-up" not in text.replace(
        '"give-up', "")
    assert "class s_suspended active" in text
    assert "s_ask --> s_realize : H-AGREE" in text


def test_png_and_svg_without_system_graphviz(tmp_path):
    assert find_dot()
    scheme = load_scheme("give-object")
    render_scheme(scheme, tmp_path / "g.png")
    render_scheme(scheme, tmp_path / "g.svg")
    render_scheme(scheme, tmp_path / "g.dot")
    assert (tmp_path / "g.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert "<svg" in (tmp_path / "g.svg").read_text()
    assert (tmp_path / "g.dot").read_text().startswith("digraph")
    render_scheme(scheme, tmp_path / "g.mmd", active=["ask"])
    render_scheme(scheme, tmp_path / "g.md")
    assert (tmp_path / "g.mmd").read_text().startswith("stateDiagram-v2")
    assert "```mermaid\nstateDiagram-v2" in (tmp_path / "g.md").read_text()


def test_render_dot_refuses_unknown_formats_and_reports_dot_errors(tmp_path):
    with pytest.raises(ValueError, match=r"use one of \.svg, \.png, \.dot, \.gv$"):
        render_dot("digraph {}", tmp_path / "g.pdf")
    with pytest.raises(RuntimeError, match="syntax"):
        render_dot("digraph { a -> }", tmp_path / "bad.svg")
    assert not (tmp_path / "bad.svg").exists()


def test_find_dot_says_how_to_get_one(monkeypatch):
    monkeypatch.setattr("shary.log.display.shutil.which", lambda *args, **kwargs: None)
    with pytest.raises(RuntimeError, match="pip install graphviz-pure"):
        find_dot()


def test_render_scheme_command(shary, tmp_path):
    status, out, _ = shary("render", "scheme", "ask-help", "-o", tmp_path / "a.svg",
                           "--active", "ask")
    assert status == 0 and (tmp_path / "a.svg").exists()


def test_render_refuses_unknown_active_states(shary, tmp_path):
    status, _, err = shary("render", "scheme", "give-object", "-o", tmp_path / "x.dot",
                           "--active", "nowhere")
    assert status == 2 and "nowhere" in err


def _logged_run(path):
    with ContextLog(path) as log:
        world = World(log=log)
        world.distracted_give()
        return world


def test_tree_replayed_from_the_log_matches_the_live_tree(tmp_path):
    world = _logged_run(tmp_path / "run.sqlite")
    replayed = TaskTree.replay(read_events(tmp_path / "run.sqlite"))
    live = world.sup.tree
    assert sorted(replayed.graph.edges) == sorted(live.graph.edges)
    assert {n: replayed.state(n) for n in replayed.graph} == {n: live.state(n)
                                                               for n in live.graph}


def test_tree_at_a_past_time_shows_the_suspension(tmp_path):
    _logged_run(tmp_path / "run.sqlite")
    tree = TaskTree.replay(read_events(tmp_path / "run.sqlite"), until=3.0)
    states = {tree.node(n)["name"]: tree.state(n) for n in tree.graph}
    assert states["REALIZE-TASK x give-object"] == "suspended"
    assert states["WAIT-ATTENTION x give-object"] == "ongoing"
    assert states["pick"] == "done" and states["move-arm"] == "suspended"
    source = tree_dot(tree)
    assert "ellipse" in source and "#fdd0a2" in source


def test_render_tree_command(shary, tmp_path):
    _logged_run(tmp_path / "run.sqlite")
    status, out, _ = shary("render", "tree", tmp_path / "run.sqlite", "--at", "3",
                           "-o", tmp_path / "tree.png")
    assert status == 0 and "6 nodes" in out
    assert (tmp_path / "tree.png").read_bytes()[:4] == b"\x89PNG"
    status, _, err = shary("render", "tree", tmp_path / "tree.png", "-o", tmp_path / "t.svg")
    assert status == 2 and "not a shary context log" in err


SVG_NS = "{http://www.w3.org/2000/svg}"


def _boxes_and_texts(svg: str):
    """Each drawn node of an SVG from dot: (box width, [(text, font size)])."""
    import xml.etree.ElementTree as ET

    out = []
    for g in ET.fromstring(svg).iter(f"{SVG_NS}g"):
        if g.get("class") != "node" or g.findtext(f"{SVG_NS}title") == "legend":
            continue
        polygon = g.find(f"{SVG_NS}polygon")
        path = g.find(f"{SVG_NS}path")
        shape = polygon.get("points") if polygon is not None else (
            path.get("d") if path is not None else None)
        if shape is None:
            continue
        xs = [float(v) for v in re.findall(r"(-?[\d.]+),-?[\d.]+", shape)]
        texts = [(t.text or "", float(t.get("font-size"))) for t in g.iter(f"{SVG_NS}text")]
        out.append((max(xs) - min(xs), texts))
    return out


def test_tree_boxes_hold_their_labels_in_a_wide_font(tmp_path):
    from planner.display.plans import text_width

    tree = TaskTree()
    root = tree.add("task", "give-object", state="done",
                    args={"object": "a-rather-long-yellow-bottle", "partner": "alice-in-the-sofa"})
    act = tree.add("act", "REALIZE-TASK x give-object", root, state="ongoing",
                   act_type="R-ACT", agent="jido")
    tree.add("atomic", "move-for-manipulate-somewhere", act, state="cancelled")
    render_tree(tree, tmp_path / "t.svg")
    svg = (tmp_path / "t.svg").read_text()
    assert 'font-family="DejaVu Sans,' in svg  # measured with DejaVu, fallbacks no wider
    boxes = [(w, texts) for w, texts in _boxes_and_texts(svg) if texts]
    assert len(boxes) == 2  # the task and the atomic task (the act is an ellipse)
    for width, texts in boxes:
        for text, size in texts:
            assert width >= text_width(text, size), (text, width)


def test_edge_labels_are_padded_off_their_lines():
    source = scheme_dot(load_scheme("give-object"))
    assert 'label=<<table border="0" cellborder="0" cellpadding="3"' in source
    assert edge_label("a<b").count("a&lt;b") == 1
