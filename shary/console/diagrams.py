"""Scheme diagrams for the page: drawn once per scheme, highlighted in place.

The page gets each scheme's SVG once (laid out by the same ``dot`` as
``shary render``) with every state's group marked ``data-state="NAME"``; when
the configuration changes it only toggles a CSS class on those groups.
Re-rendering a diagram costs a ``dot`` run (tens of milliseconds and more);
toggling a class costs microseconds, which is what keeps updates fast.
"""

from __future__ import annotations

import html
import re
import tempfile
from pathlib import Path

from shary.log.display import _is_cluster, _safe_ids, render_dot, scheme_dot
from shary.statechart.model import Scheme

_GROUP = re.compile(r'<g id="(?:node|clust)\d+" class="(node|cluster)">\s*<title>([^<]*)</title>')


def scheme_svg(scheme: Scheme) -> str:
    """The scheme drawn as SVG text, each state's group carrying ``data-state``."""
    with tempfile.TemporaryDirectory(prefix="shary-console-") as folder:
        out = Path(folder) / "scheme.svg"
        render_dot(scheme_dot(scheme), out)
        svg = out.read_text(encoding="utf-8")
    names: dict[str, str] = {}
    ids = _safe_ids(scheme)
    for state in scheme.all_states():
        names[f"cluster_{state.name}" if _is_cluster(state) else ids[state.name]] = state.name

    def mark(match: re.Match[str]) -> str:
        state = names.get(html.unescape(match.group(2)))
        if state is None:
            return match.group(0)
        return match.group(0).replace(
            "<g ", f'<g data-state="{html.escape(state, quote=True)}" ', 1)

    svg = _GROUP.sub(mark, svg)
    return svg[svg.index("<svg"):]  # the XML prologue and DOCTYPE cannot go inside a page
