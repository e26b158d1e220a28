"""Diagrams: schemes and task trees as DOT, Mermaid, SVG and PNG.

Like py_trees' display module, this is the one place that knows how things
look.  DOT is built with the ``graphviz`` package and laid out by a ``dot``
executable: the system's when there is one, otherwise the one the
``graphviz-pure`` wheel ships, so a pip-only install can draw.  Mermaid is
written by hand (it is text, with its own identifier rules).
"""

from __future__ import annotations

import os
import re
import shutil
import subprocess
import sys
import sysconfig
from collections.abc import Iterable
from pathlib import Path
from typing import Any

import graphviz

from shary.model import COMPOUND, FINAL, HISTORY, PARALLEL, Scheme, State, Transition
from shary.tasktree import ACT, TASK, TaskTree

DOT_FORMATS = {".svg": "svg", ".png": "png"}
TEXT_SUFFIXES = (".dot", ".gv")
MERMAID_SUFFIXES = (".mmd", ".mermaid")
SUFFIXES = (*DOT_FORMATS, *TEXT_SUFFIXES, *MERMAID_SUFFIXES)

ACTIVE_FILL = "#ffe680"
ACTIVE_LINE = "#b8860b"
STATE_COLOURS = {
    "planned": "#eeeeee", "todo": "#ffffff", "ongoing": "#9ecae1", "done": "#a1d99b",
    "failed": "#fc9272", "suspended": "#fdd0a2", "cancelled": "#d9d9d9",
}
_FONT = "Helvetica"


# -- the dot executable ------------------------------------------------------


def find_dot() -> str:
    """A Graphviz ``dot``: on PATH, else the ``graphviz-pure`` executable."""
    found = shutil.which("dot")
    if found:
        return found
    folders = [sysconfig.get_path("scripts"), os.path.dirname(sys.executable)]
    for folder in [None, *folders]:
        candidate = shutil.which("graphviz-pure", path=folder) if folder else \
            shutil.which("graphviz-pure")
        if candidate:
            return candidate
    raise RuntimeError("no Graphviz 'dot' found: install Graphviz, or "
                       "'pip install graphviz-pure' for a dot that comes from pip")


def render_dot(source: str, out: Path) -> None:
    """Write DOT ``source`` to ``out``: as text (.dot, .gv) or laid out (.svg, .png)."""
    suffix = out.suffix.lower()
    if suffix in TEXT_SUFFIXES:
        out.write_text(source, encoding="utf-8")
        return
    if suffix not in DOT_FORMATS:
        raise ValueError(f"cannot draw to {out.name!r}: use one of {', '.join(SUFFIXES)}")
    done = subprocess.run([find_dot(), f"-T{DOT_FORMATS[suffix]}", "-o", str(out)],
                          input=source.encode("utf-8"), capture_output=True, check=False)
    if done.returncode != 0:
        raise RuntimeError(f"dot failed ({done.returncode}): "
                           f"{done.stderr.decode('utf-8', 'replace').strip()}")


# -- schemes ---------------------------------------------------------------------


def _act_line(state: State) -> str:
    if state.act is None:
        return ""
    kind = f" ({state.act_type.name})" if state.act_type else ""
    return f"\n{state.act}{kind}"


class _SchemeDot:
    """Builds the DOT of one scheme (clusters for compound and parallel states)."""

    def __init__(self, scheme: Scheme, active: Iterable[str]):
        self.scheme = scheme
        self.active = set(active)
        self.graph = graphviz.Digraph(scheme.name, graph_attr={
            "compound": "true", "fontname": _FONT, "label": scheme.name, "labelloc": "t",
            "fontsize": "16", "nodesep": "0.4", "ranksep": "0.5"},
            node_attr={"fontname": _FONT, "fontsize": "11"},
            edge_attr={"fontname": _FONT, "fontsize": "9", "color": "#555555"})

    def build(self) -> str:
        root = self.scheme.root
        self.graph.node("start", "", shape="point", width="0.15")
        for state in root.children:
            self._state(self.graph, state)
        for name in root.initial:
            self._edge("start", self.scheme.states[name], None, "")
        for state in self.scheme.all_states():
            if state.kind in (COMPOUND,) and state.initial:
                for name in state.initial:
                    self._edge(self._anchor(state), self.scheme.states[name], None, "",
                               style="solid")
            for t in state.transitions:
                self._transition(t)
        return self.graph.source

    def _id(self, state: State) -> str:
        return f"s{state.order}"  # names may hold ':' which DOT reads as a port

    def _anchor(self, state: State) -> str:
        """A node inside a state's drawing that edges can attach to."""
        if state.kind == COMPOUND:
            return f"i{state.order}"
        if state.kind == PARALLEL:
            return self._anchor(state.proper_children()[0])
        return self._id(state)

    def _state(self, parent: graphviz.Digraph, state: State) -> None:
        on = state.name in self.active
        if state.kind in (COMPOUND, PARALLEL):
            with parent.subgraph(name=f"cluster_{state.name}") as sub:
                region = state.parent is not None and state.parent.kind == PARALLEL
                style = "dashed,rounded" if region else "rounded"
                sub.attr(label=f"{state.name}{_act_line(state)}", style=style,
                         fontname=_FONT, fontsize="12", penwidth="2.5" if on else "1",
                         color=ACTIVE_LINE if on else "#777777",
                         bgcolor="#fff8dc" if on else "white")
                if state.kind == COMPOUND:
                    sub.node(f"i{state.order}", "", shape="point", width="0.12")
                for child in state.children:
                    self._state(sub, child)
            return
        attrs: dict[str, Any] = {}
        if state.kind == FINAL:
            attrs.update(shape="doublecircle", label="", xlabel=state.name, width="0.2")
        elif state.kind == HISTORY:
            attrs.update(shape="circle", label="H*" if state.history == "deep" else "H",
                         width="0.3", fixedsize="true", tooltip=state.name)
        else:
            attrs.update(shape="box", style="rounded", label=f"{state.name}{_act_line(state)}")
        if on:
            attrs.update(style=",".join(filter(None, [attrs.get("style"), "filled"])),
                         fillcolor=ACTIVE_FILL, penwidth="2.5", color=ACTIVE_LINE)
        parent.node(self._id(state), **attrs)

    def _transition(self, t: Transition) -> None:
        source = t.source
        if not t.targets:
            self._edge(self._anchor(source), source, source, t.label(), style="dashed",
                       self_loop=True)
            return
        for name in t.targets:
            self._edge(self._anchor(source), self.scheme.states[name], source, t.label())

    def _edge(self, tail: str, target: State, source: State | None, label: str,
              style: str = "solid", self_loop: bool = False) -> None:
        attrs: dict[str, Any] = {"label": label, "style": style}
        head = self._anchor(target)
        if self_loop:
            head = tail
        elif target.kind in (COMPOUND, PARALLEL) and not (
                source is not None and (source is target or source.is_descendant_of(target))):
            attrs["lhead"] = f"cluster_{target.name}"
        if source is not None and source.kind in (COMPOUND, PARALLEL) and not self_loop \
                and not (target is source or target.is_descendant_of(source)):
            attrs["ltail"] = f"cluster_{source.name}"
        if label == "":
            attrs["arrowsize"] = "0.7"
        self.graph.edge(tail, head, **attrs)


def scheme_dot(scheme: Scheme, active: Iterable[str] = ()) -> str:
    """DOT source of a scheme; states named in ``active`` are highlighted."""
    return _SchemeDot(scheme, active).build()


def _mermaid_ids(scheme: Scheme) -> dict[str, str]:
    ids: dict[str, str] = {}
    used: set[str] = set()
    for state in scheme.all_states():
        base = "s_" + re.sub(r"[^A-Za-z0-9_]", "_", state.name)
        candidate, n = base, 1
        while candidate in used:
            n += 1
            candidate = f"{base}_{n}"
        used.add(candidate)
        ids[state.name] = candidate
    return ids


def scheme_mermaid(scheme: Scheme, active: Iterable[str] = ()) -> str:
    """A Mermaid ``stateDiagram-v2`` of a scheme; ``active`` states get the class active."""
    ids = _mermaid_ids(scheme)
    active = set(active)
    lines = ["stateDiagram-v2", f"    %% {scheme.name}"]

    def label(state: State) -> str:
        if state.kind == HISTORY:
            return "H*" if state.history == "deep" else "H"
        return state.name + (f"<br/>{state.act} ({state.act_type.name})"
                             if state.act and state.act_type else "")

    def block(state: State, indent: str) -> None:
        sid = ids[state.name]
        lines.append(f'{indent}state "{label(state)}" as {sid}')
        if state.kind not in (COMPOUND, PARALLEL):
            return
        lines.append(f"{indent}state {sid} {{")
        children = state.children
        if state.kind == COMPOUND:
            for name in state.initial:
                lines.append(f"{indent}    [*] --> {ids[name]}")
            for child in children:
                block(child, indent + "    ")
        else:
            for i, child in enumerate(state.proper_children()):
                if i:
                    lines.append(f"{indent}    --")
                block(child, indent + "    ")
        lines.append(f"{indent}}}")

    for name in scheme.root.initial:
        lines.append(f"    [*] --> {ids[name]}")
    for state in scheme.root.children:
        block(state, "    ")
    for state in scheme.all_states():
        if state.kind == FINAL and state.parent is scheme.root:
            lines.append(f"    {ids[state.name]} --> [*]")
        for t in state.transitions:
            text = t.label().replace(":", "∶")
            for name in t.targets or (state.name,):
                lines.append(f"    {ids[state.name]} --> {ids[name]} : {text}")
    lines.append(f"    classDef active fill:{ACTIVE_FILL},stroke:{ACTIVE_LINE},"
                 "stroke-width:3px")
    for name in sorted(active & set(ids)):
        lines.append(f"    class {ids[name]} active")
    return "\n".join(lines) + "\n"


def render_scheme(scheme: Scheme, out: Path, active: Iterable[str] = ()) -> None:
    """Draw a scheme to ``out`` (.svg, .png, .dot, .gv, .mmd): the suffix says how."""
    if out.suffix.lower() in MERMAID_SUFFIXES:
        out.write_text(scheme_mermaid(scheme, active), encoding="utf-8")
    else:
        render_dot(scheme_dot(scheme, active), out)


# -- task trees ------------------------------------------------------------------


def tree_dot(tree: TaskTree, title: str = "task tree") -> str:
    """DOT source of a task tree: tasks as boxes, act x task nodes as ellipses, atomic
    tasks as small rounded boxes, all filled by state (a legend says which colour)."""
    graph = graphviz.Digraph("tree", graph_attr={
        "rankdir": "TB", "fontname": _FONT, "label": title, "labelloc": "t", "fontsize": "14",
        "ranksep": "0.4"}, node_attr={"fontname": _FONT, "fontsize": "10", "style": "filled"},
        edge_attr={"color": "#666666", "arrowsize": "0.6"})
    for node in tree.graph.nodes:
        data = tree.node(node)
        state = data["state"]
        fill = STATE_COLOURS.get(state, "#ffffff")
        if data["kind"] == TASK:
            args = data.get("args") or {}
            text = ", ".join(f"{k}={v}" for k, v in args.items())
            graph.node(node, f"{data['name']}\n{text}\n[{state}]" if text
                       else f"{data['name']}\n[{state}]", shape="box", penwidth="2",
                       fillcolor=fill)
        elif data["kind"] == ACT:
            who = f" by {data['agent']}" if data.get("agent") else ""
            graph.node(node, f"{data['name']}\n{data.get('act_type') or ''}{who}\n[{state}]",
                       shape="ellipse", fillcolor=fill)
        else:
            graph.node(node, f"{data['name']}\n[{state}]", shape="box",
                       style="rounded,filled" + (",dashed" if state == "cancelled" else ""),
                       fillcolor=fill)
    for tail, head in tree.graph.edges:
        graph.edge(tail, head)
    cells = "".join(f'<td bgcolor="{colour}">{state}</td>'
                    for state, colour in STATE_COLOURS.items())
    graph.node("legend", f'<<table border="0" cellborder="1" cellspacing="0" '
               f'cellpadding="4"><tr>{cells}</tr></table>>', shape="plaintext",
               style="", fontsize="9")
    return graph.source


def render_tree(tree: TaskTree, out: Path, title: str = "task tree") -> None:
    """Draw a task tree to ``out`` (.svg, .png, .dot, .gv)."""
    if out.suffix.lower() in MERMAID_SUFFIXES:
        raise ValueError("task trees are drawn to .svg, .png, .dot or .gv")
    render_dot(tree_dot(tree, title), out)
