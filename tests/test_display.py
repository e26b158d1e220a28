"""Diagrams of schemes and task trees (DOT, Mermaid, SVG, PNG), and their commands."""

from __future__ import annotations

from scripted import World

from shary import load_scheme
from shary.display import find_dot, render_scheme, scheme_dot, scheme_mermaid, tree_dot
from shary.log import ContextLog, read_events
from shary.tasktree import TaskTree


def test_dot_has_every_state_and_transition_label():
    scheme = load_scheme("give-object-attentive")
    source = scheme_dot(scheme)
    for state in scheme.all_states():
        if state.kind in ("atomic", "final"):
            assert state.name in source
        elif state.kind in ("compound", "parallel"):
            assert f"cluster_{state.name}" in source
    for state in scheme.all_states():
        for t in state.transitions:
            assert t.label() in source
    assert "H*" in source and "REALIZE-TASK (R-ACT)" in source


def test_active_states_are_highlighted_and_only_them():
    scheme = load_scheme("give-object-attentive")
    plain = scheme_dot(scheme)
    lit = scheme_dot(scheme, active=["suspended", "realize"])
    assert "#ffe680" not in plain and "#fff8dc" not in plain
    assert lit.count("#ffe680") == 1 and lit.count("#fff8dc") == 1


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


def test_render_scheme_command(shary, tmp_path):
    status, out, _ = shary("render", "scheme", "ask-help", "-o", tmp_path / "a.svg",
                           "--active", "ask")
    assert status == 0 and (tmp_path / "a.svg").exists()
    status, _, err = shary("render", "scheme", "ask-help", "-o", tmp_path / "a.pdf")
    assert status == 1 and ".svg" in err


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
