"""The house's rules on imports, read off the real import graph (grimp parses every module).

- Layers: ``sim`` above ``shary`` above ``planner`` above ``userfiles``; a lower layer
  never imports a higher one.
- ``shary.ros`` and ``shary.console`` are leaves: nothing in the engine's kernel imports
  them (only the commands and ``sim``, which sit above, do).
- No import circles between modules (an import under ``TYPE_CHECKING`` is for the type
  checker only and does not count).

A broken rule fails with the import that breaks it: ``importer -> imported (line N)``.
The last tests add a forbidden import to the graph and check that each rule sees it.
"""

from __future__ import annotations

import grimp
import networkx as nx
import pytest

LAYERS = ("sim", "shary", "planner", "userfiles")
LEAVES = ("shary.ros", "shary.console")
ABOVE_THE_KERNEL = ("shary.cli", "shary.__main__", "shary.commands", *LEAVES)
"""The parts of ``shary`` that may import the leaves: the command line and the leaves."""


@pytest.fixture(scope="module")
def graph() -> grimp.ImportGraph:
    return grimp.build_graph(*LAYERS, include_external_packages=False, cache_dir=None,
                             exclude_type_checking_imports=True)


def _where(graph: grimp.ImportGraph, importer: str, imported: str) -> str:
    lines = sorted(d["line_number"] for d in graph.get_import_details(importer=importer,
                                                                       imported=imported))
    return f"{importer} -> {imported} (line {', '.join(map(str, lines)) or '?'})"


def layer_breaks(graph: grimp.ImportGraph) -> list[str]:
    """Each import by which a lower layer reaches a higher one, first step named."""
    found = []
    for dependency in graph.find_illegal_dependencies_for_layers(layers=LAYERS):
        for route in dependency.routes:
            head = min(route.heads)
            step = route.middle[0] if route.middle else min(route.tails)
            found.append(f"{dependency.importer} must not import {dependency.imported}: "
                         + _where(graph, head, step))
    return sorted(found)


def leaf_breaks(graph: grimp.ImportGraph) -> list[str]:
    """Each import chain from the kernel into ``shary.ros`` or ``shary.console``."""
    kernel = [m for m in graph.find_children("shary")
              if not m.startswith(ABOVE_THE_KERNEL)] + ["planner", "userfiles"]
    found = []
    for source in ["shary", *kernel]:  # shary alone: its __init__, not its subpackages
        for leaf in LEAVES:
            chain = graph.find_shortest_chain(importer=source, imported=leaf,
                                              as_packages=source != "shary")
            if chain:
                steps = " -> ".join(chain)
                found.append(f"{source} reaches the leaf {leaf}: {steps}; the import into it: "
                             + _where(graph, chain[-2], chain[-1]))
    return found


def circles(graph: grimp.ImportGraph) -> list[str]:
    """One circle of module imports per strongly connected group, each import named."""
    edges = nx.DiGraph()
    for module in graph.modules:
        for imported in graph.find_modules_directly_imported_by(module):
            edges.add_edge(module, imported)
    found = []
    for group in nx.strongly_connected_components(edges):
        if len(group) > 1:
            cycle = nx.find_cycle(edges.subgraph(group))
            found.append("circle: " + "; ".join(_where(graph, a, b) for a, b in cycle))
    return sorted(found)


def test_the_layers_point_one_way(graph):
    breaks = layer_breaks(graph)
    assert not breaks, "\n".join(breaks)


def test_the_kernel_never_imports_ros_or_the_console(graph):
    breaks = leaf_breaks(graph)
    assert not breaks, "\n".join(breaks)


def test_no_module_imports_itself_through_others(graph):
    found = circles(graph)
    assert not found, "\n".join(found)


def test_a_planner_module_importing_shary_breaks_the_layers(graph):
    graph.add_import(importer="planner.model.domain", imported="shary.kernel.supervisor",
                     line_number=7, line_contents="from shary.kernel.supervisor import X")
    try:
        breaks = layer_breaks(graph)
    finally:
        graph.remove_import(importer="planner.model.domain", imported="shary.kernel.supervisor")
    assert breaks == ["planner must not import shary: "
                      "planner.model.domain -> shary.kernel.supervisor (line 7)"]


def test_the_kernel_importing_the_console_is_named(graph):
    graph.add_import(importer="shary.kernel.loop", imported="shary.console.server",
                     line_number=12, line_contents="from shary.console.server import serve")
    try:
        breaks = leaf_breaks(graph)
    finally:
        graph.remove_import(importer="shary.kernel.loop", imported="shary.console.server")
    assert any(b.startswith("shary.kernel reaches the leaf shary.console")
               and b.endswith("shary.kernel.loop -> shary.console.server (line 12)")
               for b in breaks), breaks


def test_a_circle_is_named_import_by_import(graph):
    graph.add_import(importer="shary.statechart.model", imported="shary.statechart.compiler",
                     line_number=3, line_contents="from shary.statechart.compiler import X")
    try:
        found = circles(graph)
    finally:
        graph.remove_import(importer="shary.statechart.model",
                            imported="shary.statechart.compiler")
    assert len(found) == 1
    assert "shary.statechart.model -> shary.statechart.compiler (line 3)" in found[0]
