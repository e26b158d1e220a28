"""Diagrams: schemes and task trees as DOT, Mermaid, SVG and PNG.

Like py_trees' display module, this is the one place that knows how things
look.  Users write schemes in YAML but check them by looking at them, so a
scheme is drawn with the statechart conventions they know: compound states are
boxes around their children, parallel regions are dashed boxes side by side, a
black point marks where a state starts, history is a circled H, and the states
a running instance is in can be highlighted to show where a scenario stands.

DOT is built with the ``graphviz`` package and laid out by a ``dot``
executable: the system's when there is one, otherwise the one the
``graphviz-pure`` wheel ships, so a pip-only install can draw.  Mermaid is
written by hand (it is text, with its own identifier rules), for the places
that render it themselves: GitHub, editors, documentation sites.
"""

from __future__ import annotations

import html
import os
import re
import shutil
import subprocess
import sys
import sysconfig
from collections.abc import Iterable
from pathlib import Path

import graphviz

from planner.display.plans import text_width
from shary.kernel.tasktree import ACT, TASK, TaskTree
from shary.statechart.model import COMPOUND, FINAL, HISTORY, PARALLEL, Scheme, State, Transition
from userfiles.outputs import write_output

DOT_FORMATS = {".svg": "svg", ".png": "png"}
TEXT_SUFFIXES = (".dot", ".gv")
MERMAID_SUFFIXES = (".mmd", ".mermaid")
MARKDOWN_SUFFIX = ".md"
DOT_SUFFIXES = (*DOT_FORMATS, *TEXT_SUFFIXES)
"""What a DOT graph (a task tree, a plan) is drawn to."""
SUFFIXES = (*DOT_SUFFIXES, *MERMAID_SUFFIXES, MARKDOWN_SUFFIX)
"""What a scheme is drawn to."""

ACTIVE_FILL = "#ffe680"
"""Fill of an active state, the same in DOT and Mermaid."""
ACTIVE_LINE = "#b8860b"
ACTIVE_BACKGROUND = "#fff8dc"
"""Background of an active compound state: paler than ACTIVE_FILL, so that the
active states inside it still stand out."""
ACT_COLOUR = "#1f4e79"
STATE_COLOURS = {
    "planned": "#eeeeee", "todo": "#ffffff", "ongoing": "#9ecae1", "done": "#a1d99b",
    "failed": "#fc9272", "suspended": "#fdd0a2", "cancelled": "#d9d9d9",
}
_FONT = "DejaVu Sans"
"""The font dot measures SVG labels with.  DejaVu Sans is what a Linux viewer
falls back to for "Helvetica", and wider than Helvetica or Arial: boxes sized
for it hold their text in any viewer (sized for Helvetica, labels overflowed)."""
FONT_FALLBACKS = "DejaVu Sans,Verdana,Helvetica,Arial,sans-serif"
PNG_FONT = "Helvetica"
"""The font of PNG output, which dot both measures and draws (no viewer's fallback)."""
"""The SVG font-family written for ``_FONT``: viewers without DejaVu use a font no wider."""


# -- the dot executable ------------------------------------------------------


def find_dot() -> str:
    """The path of a Graphviz ``dot`` executable.

    A system Graphviz wins because its user may have set it up (fonts,
    plugins); ``graphviz-pure`` is the fallback that a pip install always
    brings.  Its script may be off PATH (a virtual environment used without
    being activated), hence the look next to the running interpreter.
    """
    folders = (sysconfig.get_path("scripts"), os.path.dirname(sys.executable))
    found = shutil.which("dot") or shutil.which("graphviz-pure") or next(
        filter(None, (shutil.which("graphviz-pure", path=folder) for folder in folders)), None)
    if found is None:
        raise RuntimeError("no Graphviz 'dot' found: install Graphviz, or "
                           "'pip install graphviz-pure' for a dot that comes from pip")
    return found


def render_dot(source: str, out: Path) -> None:
    """Write DOT ``source`` to ``out``: as text (.dot, .gv) or laid out (.svg, .png).

    The image is written only once ``dot`` has succeeded, so that a failure
    never leaves a truncated file behind to be mistaken for a drawing.
    """
    suffix = out.suffix.lower()
    if suffix in TEXT_SUFFIXES:
        write_output(out, source)
        return
    if suffix not in DOT_FORMATS:
        raise ValueError(f"cannot draw to {out.name!r}: use one of {', '.join(DOT_SUFFIXES)}")
    dot = find_dot()
    if suffix == ".png":
        # dot draws the picture itself: graphviz-pure has glyphs for Helvetica (and
        # draws other names in a serif), and measures with the same font it draws
        source = source.replace(f'fontname="{_FONT}"', f'fontname="{PNG_FONT}"')
    done = subprocess.run([dot, f"-T{DOT_FORMATS[suffix]}"], input=source.encode("utf-8"),
                          capture_output=True, check=False)
    if done.returncode != 0:
        raise RuntimeError(f"{dot} failed ({done.returncode}): "
                           f"{done.stderr.decode('utf-8', 'replace').strip()}")
    image = done.stdout
    if suffix == ".svg":
        image = image.replace(f'font-family="{_FONT}"'.encode(),
                              f'font-family="{FONT_FALLBACKS}"'.encode())
    write_output(out, image)


def edge_label(text: str) -> str:
    """An edge's label as an HTML-like label padded all round, so that the text
    keeps off its line (dot sets a plain label against the edge, touching it)."""
    return (f'<<table border="0" cellborder="0" cellpadding="3" cellspacing="0"><tr><td>'
            f"{html.escape(text)}</td></tr></table>>")


# -- schemes ---------------------------------------------------------------------


def scheme_dot(scheme: Scheme, active: Iterable[str] = ()) -> str:
    """DOT source of a scheme; the states named in ``active`` are highlighted."""
    return _SchemeDot(scheme, _active(scheme, active)).graph.source


def scheme_mermaid(scheme: Scheme, active: Iterable[str] = ()) -> str:
    """A Mermaid ``stateDiagram-v2`` of a scheme; ``active`` states get the class active."""
    return _SchemeMermaid(scheme, _active(scheme, active)).text()


def render_scheme(scheme: Scheme, out: Path, active: Iterable[str] = ()) -> None:
    """Draw a scheme to ``out``, the suffix says how: .svg, .png, .dot, .gv, Mermaid
    (.mmd, .mermaid) or a Markdown page holding a Mermaid block (.md)."""
    suffix = out.suffix.lower()
    if suffix in MERMAID_SUFFIXES:
        write_output(out, scheme_mermaid(scheme, active))
    elif suffix == MARKDOWN_SUFFIX:
        write_output(out, f"# {scheme.name}\n\n```mermaid\n{scheme_mermaid(scheme, active)}```\n")
    else:
        render_dot(scheme_dot(scheme, active), out)


def _active(scheme: Scheme, active: Iterable[str]) -> set[str]:
    """The names in ``active``, refused if one is no state: a typo would
    otherwise highlight nothing, silently."""
    names = set(active)
    unknown = sorted(names - scheme.states.keys())
    if unknown:
        raise ValueError(f"scheme {scheme.name!r} has no state {', '.join(map(repr, unknown))}")
    return names


def _safe_ids(scheme: Scheme) -> dict[str, str]:
    """An identifier of letters, digits and ``_`` for each state name.

    Names may hold ``.``, ``:`` and ``-``: Mermaid refuses them in ids and DOT
    reads ``a:b`` in an edge as node ``a``, port ``b``.  The ``s_`` prefix keeps
    ids apart from keywords (``end``, ``state``, ``node``) and from helper nodes.
    """
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


def _act_line(state: State) -> str | None:
    """``ASK-TASK (R-ACT)``: the act a state carries out and its type, if it has one."""
    if state.act is None:
        return None
    return f"{state.act} ({state.act_type.name})" if state.act_type else state.act


def _invoke_lines(state: State) -> list[str]:
    """``invokes give-object as ask (autoforward)``: the child schemes a state starts."""
    return [f"invokes {i.scheme.name}" + (f" as {i.id}" if i.id != state.name else "")
            + (" (autoforward)" if i.autoforward else "") for i in state.invokes]


def _history_mark(state: State) -> str:
    return "H*" if state.history == "deep" else "H"


def _is_cluster(state: State) -> bool:
    return state.kind in (COMPOUND, PARALLEL)


def _internal(state: State) -> list[Transition]:
    """Targetless transitions.  They act without leaving the state, so they are
    listed inside it, as UML does, rather than drawn as loops (a loop on a
    compound state would hang on its initial point and read as re-entering it)."""
    return [t for t in state.transitions if not t.targets]


class _SchemeDot:
    """The DOT drawing of one scheme: clusters for compound and parallel states."""

    def __init__(self, scheme: Scheme, active: set[str]) -> None:
        self.scheme = scheme
        self.active = active
        self.ids = _safe_ids(scheme)
        self.graph = graphviz.Digraph(scheme.name, graph_attr={
            "compound": "true", "fontname": _FONT, "fontsize": "16", "labelloc": "t",
            "label": f"<<B>{html.escape(scheme.name)}</B>>", "nodesep": "0.4",
            "ranksep": "0.5"},
            node_attr={"shape": "box", "style": "rounded", "fontname": _FONT, "fontsize": "12"},
            edge_attr={"fontname": _FONT, "fontsize": "10", "color": "#444444",
                       "arrowsize": "0.7"})
        self._contents(self.graph, scheme.root)
        for state in [scheme.root, *scheme.all_states()]:
            if state.kind == COMPOUND:
                for name in state.initial:
                    self._edge(None, self._initial_point(state), self.scheme.states[name], "")
            for transition in state.transitions:
                for name in transition.targets:
                    if not (_is_cluster(state) and name == state.name):  # listed in its label
                        self._edge(state, self._exit(state), self.scheme.states[name],
                                   transition.label())
            for name in state.default:
                self._edge(state, self._exit(state), self.scheme.states[name], "")

    def _contents(self, graph: graphviz.Digraph, state: State) -> None:
        """What is drawn inside ``state``: its initial point, then its children."""
        if state.kind == COMPOUND:
            graph.node(self._initial_point(state), "", shape="point", width="0.12")
        for child in state.children:
            if _is_cluster(child):
                with graph.subgraph(name=self._cluster(child)) as cluster:
                    self._cluster_attrs(cluster, child, region=state.kind == PARALLEL)
                    self._contents(cluster, child)
            else:
                self._node(graph, child)

    def _cluster_attrs(self, cluster: graphviz.Digraph, state: State, region: bool) -> None:
        # Style, width and colour are set on every cluster: a nested cluster
        # would otherwise inherit its parent's, the highlight among them.
        on = state.name in self.active
        style = ["rounded", "dashed" if region else "solid", *(["filled"] if on else [])]
        attrs = {"label": self._label(state, bold=True), "labeljust": "l", "fontsize": "13",
                 "style": ",".join(style), "penwidth": "3" if on else "1",
                 "color": ACTIVE_LINE if on else "#777777",
                 "tooltip": graphviz.escape(state.doc or state.name)}
        if on:
            attrs["fillcolor"] = ACTIVE_BACKGROUND
        cluster.attr(**attrs)

    def _node(self, graph: graphviz.Digraph, state: State) -> None:
        attrs = {"tooltip": graphviz.escape(state.doc or state.name)}
        if state.kind == HISTORY:
            attrs.update(shape="circle", label=_history_mark(state), fixedsize="true",
                         width="0.35", fontsize="11")
        else:
            attrs["label"] = self._label(state, bold=False)
        if state.kind == FINAL:
            # A double border rather than UML's bull's-eye: the name and the act
            # fit inside, where a bull's-eye would grow huge or need an outside
            # label that dot places over the edges.
            attrs["peripheries"] = "2"
        if state.name in self.active:
            style = "filled,bold" if state.kind == HISTORY else "rounded,filled,bold"
            attrs.update(style=style, fillcolor=ACTIVE_FILL, penwidth="2.5", color=ACTIVE_LINE)
        graph.node(self.ids[state.name], **attrs)

    def _label(self, state: State, bold: bool) -> str:
        """An HTML-like label: the name, the act line, then the listed transitions.

        A cluster's label (``bold``) has its lines flush left, in line with
        the cluster's corner; a node's are centred in the node.
        """
        name = html.escape(state.name)
        lines = [f"<B>{name}</B>" if bold else name]
        act = _act_line(state)
        if act:
            lines.append(f'<FONT POINT-SIZE="10" COLOR="{ACT_COLOUR}">{html.escape(act)}</FONT>')
        lines += [f'<FONT POINT-SIZE="10">{html.escape(text)}</FONT>'
                  for text in _invoke_lines(state)]
        lines += [f'<FONT POINT-SIZE="9"><I>{html.escape(text)}</I></FONT>'
                  for text in self._listed(state)]
        if bold:
            return "<" + "".join(line + '<BR ALIGN="LEFT"/>' for line in lines) + ">"
        return "<" + "<BR/>".join(lines) + ">"

    def _listed(self, state: State) -> list[str]:
        """Transitions written inside a state instead of drawn: the targetless ones
        and, on a compound state, those that re-enter it (dot draws no loop on a
        cluster; a loop on its initial point would not read as leaving it)."""
        texts = [t.label() for t in _internal(state)]
        if _is_cluster(state):
            texts += [f"{t.label()} (re-enters)" for t in state.transitions
                      if state.name in t.targets]
        return texts

    def _cluster(self, state: State) -> str:
        return f"cluster_{state.name}"

    def _initial_point(self, state: State) -> str:
        return "init_" + (self.ids[state.name] if state.parent else "root")

    def _anchor(self, state: State) -> str:
        """The node that edges to or from ``state`` attach to.

        A cluster is no node, so an edge touching a compound state goes to its
        initial point and is clipped at the cluster's border (``lhead``,
        ``ltail``); a parallel state lends the anchor of its first region.
        """
        if state.kind == COMPOUND:
            return self._initial_point(state)
        if state.kind == PARALLEL:
            return self._anchor(state.proper_children()[0])
        return self.ids[state.name]

    def _exit(self, state: State) -> str:
        """The node that edges leaving ``state`` start from: its last child, recursively.

        dot ranks an edge's head below its tail; starting from a node low in
        the cluster sends the targets below it instead of beside its top.
        """
        children = state.proper_children()
        return self._exit(children[-1]) if _is_cluster(state) and children else self._anchor(state)

    def _edge(self, source: State | None, tail: str, target: State, label: str) -> None:
        """An edge from ``tail`` (in ``source``, None for an initial point) to ``target``.

        It is clipped at the borders of the compound states it leaves or enters.
        When one end lies inside the other, dot can clip neither, and the edge
        must not rank its ends either: a transition from a child back to its
        parent would sink the parent's initial point below the child.
        """
        attrs = {"label": edge_label(label)} if label else {}
        if source is not None and (source is target or source.is_descendant_of(target)
                                   or target.is_descendant_of(source)):
            attrs["constraint"] = "false"
        else:
            if source is not None and _is_cluster(source):
                attrs["ltail"] = self._cluster(source)
            if _is_cluster(target):
                attrs["lhead"] = self._cluster(target)
        self.graph.edge(tail, self._anchor(target), **attrs)


class _SchemeMermaid:
    """The Mermaid text of one scheme: the tree of states, then the transitions.

    Every transition is written at the top level, after all the states.
    Mermaid makes a state a child of the block where it last meets its id
    (the top level excepted), so a transition written inside a composite
    would pull its ends out of their own composites into that one.
    """

    def __init__(self, scheme: Scheme, active: set[str]) -> None:
        self.scheme = scheme
        self.active = active
        self.ids = _safe_ids(scheme)
        self.lines = ["stateDiagram-v2", f"    %% {_mermaid_text(scheme.name)}"]

    def text(self) -> str:
        self._contents(self.scheme.root, 1)
        for source in self.scheme.all_states():
            sid = self.ids[source.name]
            for transition in source.transitions:
                self.lines += [f"    {sid} --> {self.ids[name]} : "
                               f"{_mermaid_text(transition.label())}"
                               for name in transition.targets]
            self.lines += [f"    {sid} --> {self.ids[name]}" for name in source.default]
        self.lines.append(f"    classDef active fill:{ACTIVE_FILL},stroke:{ACTIVE_LINE},"
                          "stroke-width:3px")
        self.lines += [f"    class {self.ids[name]} active"
                       for name in sorted(self.active, key=lambda n: self.scheme.states[n].order)]
        return "\n".join(self.lines) + "\n"

    def _contents(self, state: State, depth: int) -> None:
        """The initial arrows of ``state``, then its children, regions apart."""
        pad = "    " * depth
        self.lines += [f"{pad}[*] --> {self.ids[name]}" for name in state.initial]
        for index, child in enumerate(state.children):
            if state.kind == PARALLEL and index:
                self.lines.append(f"{pad}--")
            self._state(child, depth)

    def _state(self, state: State, depth: int) -> None:
        pad = "    " * depth
        sid = self.ids[state.name]
        title = state.name
        if state.kind == HISTORY:
            title = f"{_history_mark(state)} {state.name}"
        act = _act_line(state)
        details = [_mermaid_text(line)
                   for line in ([act] if act else []) + _invoke_lines(state)
                   + [t.label() for t in _internal(state)]]
        if _is_cluster(state):
            # Mermaid refuses descriptions on composite states: the details join the title.
            self.lines.append(f'{pad}state "{"<br/>".join([_mermaid_text(title), *details])}"'
                              f" as {sid}")
            self.lines.append(f"{pad}state {sid} {{")
            self._contents(state, depth + 1)
            self.lines.append(f"{pad}}}")
            return
        self.lines.append(f'{pad}state "{_mermaid_text(title)}" as {sid}')
        self.lines += [f"{pad}{sid} : {line}" for line in details]
        if state.kind == FINAL:
            self.lines.append(f"{pad}{sid} --> [*]")


_MERMAID_ENTITIES = {"#": "#35;", ";": "#59;", '"': "#34;", "<": "#60;", ">": "#62;"}


def _mermaid_text(text: str) -> str:
    """Text safe on one line of Mermaid.  ``;`` ends a statement, ``"`` a name and
    ``<``/``>`` would be read as HTML, so they become entity codes, which Mermaid
    shows as the characters themselves (``#`` too, as it starts an entity)."""
    return "".join(_MERMAID_ENTITIES.get(c, c) for c in " ".join(text.split()))


# -- task trees ------------------------------------------------------------------


TREE_FONT_SIZE = 10


def _box_width(label: str, size: float) -> str:
    """A box's least width (inches) for a label: its widest line by our estimate of
    DejaVu Sans, and dot's default margins, so no viewer's font overflows it."""
    return f"{(max(text_width(line, size) for line in label.split(chr(10))) + 16) / 72:.3f}"


def tree_dot(tree: TaskTree, title: str = "task tree") -> str:
    """DOT source of a task tree: tasks as boxes, act x task nodes as ellipses, atomic
    tasks as small rounded boxes, all filled by state (a legend says which colour)."""
    graph = graphviz.Digraph("tree", graph_attr={
        "rankdir": "TB", "fontname": _FONT, "label": title, "labelloc": "t", "fontsize": "14",
        "ranksep": "0.4"},
        node_attr={"fontname": _FONT, "fontsize": str(TREE_FONT_SIZE), "style": "filled"},
        edge_attr={"color": "#666666", "arrowsize": "0.6"})
    for node in tree.graph.nodes:
        data = tree.node(node)
        state = data["state"]
        fill = STATE_COLOURS.get(state, "#ffffff")
        if data["kind"] == TASK:
            args = data.get("args") or {}
            text = ", ".join(f"{k}={v}" for k, v in args.items())
            label = f"{data['name']}\n{text}\n[{state}]" if text else f"{data['name']}\n[{state}]"
            graph.node(node, label, shape="box", penwidth="2", fillcolor=fill,
                       width=_box_width(label, TREE_FONT_SIZE))
        elif data["kind"] == ACT:
            who = f" by {data['agent']}" if data.get("agent") else ""
            graph.node(node, f"{data['name']}\n{data.get('act_type') or ''}{who}\n[{state}]",
                       shape="ellipse", fillcolor=fill)
        else:
            label = f"{data['name']}\n[{state}]"
            graph.node(node, label, shape="box",
                       style="rounded,filled" + (",dashed" if state == "cancelled" else ""),
                       fillcolor=fill, width=_box_width(label, TREE_FONT_SIZE))
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
