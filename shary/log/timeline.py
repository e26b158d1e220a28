"""A timeline of a run, drawn from its context log as one SVG file (cf. Fig. 10 of SHARY).

The context log says everything a run did, but as a list of events; what a
reader wants to see is *who did what, when*: the robot's communication acts
and the humans' answers, the actions each agent performed and how they ended,
where each agent was looking. :func:`render_timeline` draws one horizontal
lane per agent (the robot first, then the humans in order of appearance) on a
common time axis in engine seconds. Inside a lane:

* **acts** (``act`` events) are bars from the entry of the scheme state that
  carries the act to its exit, or to the end of the task, veiled while the
  act x task node is suspended; acts the agent *sent* (``act-received``,
  H-AGREE …) are diamonds, hollow when no task expected them
  (``act-unexpected``);
* **actions** (``exec-request`` … ``exec-result``, paired by request id; and a
  simulated person's own actions, ``person-action`` … ``person-action-end``)
  are bars coloured by how they ended: done, failed, cancelled, or still
  running when the log ends (hatched, up to the end of the log);
* **recognized actions** (``recognition`` events, :mod:`shary.recognition`)
  are a row of a human's lane, drawn only when the log holds them: a light
  bar while the action is possibly started, a darker one while possibly
  progressing, a green diamond when possibly achieved, grey when abandoned;
  effects nobody is known to have caused go to a lane of their own, (nobody);
* **attention** (``fact-added`` / ``fact-removed`` of ``AGENT looksAt X``) is
  a thin row, drawn only when the log holds such facts;
* a **team**'s rows (:mod:`shary.team`): each agent's team tasks, associations
  and user-mode control as bars in a ``team`` row, questions, help requests
  and answers as points among the acts, respawns in the task band.

:mod:`shary.log.lanes` reads the log into these items; this module draws them.

Top-level tasks get dotted vertical lines at their start and end, labelled in
a band above the lanes, where the planner's plans are marked too. Items that
overlap in time go to separate sub-rows, so no bar hides another; a bar too
narrow for its label shows it truncated, or beside the bar when the bar is a
mere instant, and every item carries its full text and exact times in a
``<title>`` tooltip.

The SVG is written as text, with no drawing library, so the module adds no
dependency. Every item's exact times are also in ``data-start`` /
``data-end`` attributes, which is what tests and scripts read.
"""

from __future__ import annotations

import bisect
import math
import re
from collections.abc import Iterable
from pathlib import Path
from typing import Any
from xml.sax.saxutils import escape, quoteattr

from planner.display.plans import text_width
from shary.log.contextlog import LogEvent, stream_events
from shary.log.lanes import (
    ACTION_STYLES,
    LOOK_COLOUR,
    POINT_COLOURS,
    TEAM_COLOURS,
    Item,
    TaskSpan,
    Timeline,
    collect,
    shown_time,
)
from shary.plans.lane import PLAN_STATE_COLOURS
from userfiles.outputs import write_output

# -- geometry (pixels) ---------------------------------------------------------

NAME_WIDTH = 130       # the column of agent names on the left
MARGIN = 16
MIN_WIDTH = 800        # the whole picture, however short the run
MAX_PLOT_WIDTH = 6000  # past this, labels are truncated rather than the picture widened
PX_PER_SECOND = (40.0, 160.0)  # the range of the default scale: see _preferred_scale
WIDE_PLOT = 2000       # the default scale widens a run's plot past this only to 40 px/s
ROW = 22               # one row of acts or actions
LOOK_ROW = 18          # one row of attention
LANE_PAD = 6
BAND_ROW = 18          # one row of the task band
FONT = 11
SMALL = 9
MIN_LABEL_INSIDE = 36  # a bar narrower than this has its label beside it
LABEL_ROWS = 3         # a label beside a bar never opens a sub-row past this many
FONT_FAMILY = "DejaVu Sans, Helvetica, Arial, sans-serif"
RECOGNIZED_STYLES = {  # a recognized human action's state: (fill, stroke, text)
    "rec-started": ("#fdebd0", "#c77c12", "#5c3a06"),
    "rec-progressing": ("#f6b04d", "#c77c12", "#3d2604"),
    "rec-achieved": ("#59a14f", "#2f6b2a", "#ffffff"),
    "rec-abandoned": ("#eeeeee", "#9a9a9a", "#666666"),
}
ROWS = ("act", "action", "plan-task", "recognized", "team", "look")
"""The rows of a lane, top to bottom (all but acts and actions only when the log has them)."""
_NOT_XML = re.compile("[\x00-\x08\x0b\x0c\x0e-\x1f\ufffe\uffff\ud800-\udfff]")

# -- drawing ---------------------------------------------------------------------


def render_timeline(events: Iterable[LogEvent], title: str = "", *, robot: str | None = None,
                    px_per_second: float | None = None) -> str:
    """The SVG text of a run's timeline; ``robot`` names the first lane (default: the
    agent of the first task), ``px_per_second`` fixes the time scale."""
    tl = collect(events, robot)
    span = max(tl.t_max - tl.t_min, 1e-9)
    scale = px_per_second or max((MIN_WIDTH - NAME_WIDTH - 2 * MARGIN) / span,
                                 min(_preferred_scale(tl), MAX_PLOT_WIDTH / span,
                                     max(PX_PER_SECOND[0], WIDE_PLOT / span)))
    step = _tick_step(scale)
    t0 = math.floor(tl.t_min / step) * step
    end = max(t0 + step, math.ceil(tl.t_max / step - 1e-9) * step)
    x0 = MARGIN + NAME_WIDTH

    def x(t: float) -> float:
        return x0 + (t - t0) * scale

    # Pack everything first: the picture must be wide enough for the labels beside bars.
    band = [_task_item(s, tl.t_max) for s in tl.tasks] + tl.plans
    band_rows, right = _pack(band, x, tl.t_max)
    lanes: list[tuple[str, dict[str, list[tuple[Item, int]]]]] = []
    for agent in tl.agents:
        rows = {}
        for kind in ROWS:
            rows[kind], r = _pack([i for i in tl.items if i.agent == agent and i.row == kind],
                                  x, tl.t_max, FONT - 1 if kind == "look" else FONT)
            right = max(right, r)
        lanes.append((agent, rows))
    width = max(MIN_WIDTH, x(end) + 30 + MARGIN, right + MARGIN + 4)
    heading = title or "run timeline"

    out: list[str] = [_text(MARGIN, MARGIN + 18, heading, "title", size=16, weight="bold")]
    band_top = MARGIN + 30
    out += [_band(item, band_top + row * BAND_ROW, x, tl.t_max) for item, row in band_rows]
    y = band_top + max(1, _rows(band_rows)) * BAND_ROW + 22
    out.append(_axis(t0, end, step, x, y, above=True))
    lanes_top = y = y + 6
    heights = {"act": ROW, "action": ROW, "plan-task": ROW, "recognized": ROW, "team": ROW,
               "look": LOOK_ROW}
    captions = {"act": "acts", "action": "actions", "plan-task": "plan tasks",
                "recognized": "recognized", "team": "team", "look": "looks at"}
    for index, (agent, rows) in enumerate(lanes):
        counts = {kind: max(kind in ("act", "action"), _rows(rows[kind])) for kind in rows}
        lane_h = 2 * LANE_PAD + sum(counts[k] * heights[k] for k in counts)
        parts = [f'<rect class="lane-bg" x="{MARGIN}" y="{_n(y)}" '
                 f'width="{_n(width - 2 * MARGIN)}" height="{_n(lane_h)}" '
                 f'fill="{"#f4f6f8" if index % 2 == 0 else "#ffffff"}" stroke="#c9ced4"/>',
                 _text(MARGIN + 6, y + LANE_PAD + 14, _fit(agent, NAME_WIDTH - 40, FONT + 1),
                       "agent", size=FONT + 1, weight="bold", tooltip=agent)]
        if index == 0 and tl.robot == agent:
            parts.append(_text(MARGIN + 6, y + LANE_PAD + 27, "robot", "role", size=SMALL,
                               fill="#777"))
        top = y + LANE_PAD
        for kind, placed in rows.items():
            if counts[kind]:
                parts.append(_text(x0 - 12, top + heights[kind] / 2 + 3, captions[kind],
                                   "caption", size=SMALL, fill="#888", anchor="end"))
            parts += [_item(item, top + row * heights[kind], heights[kind], x, tl.t_max)
                      for item, row in placed]
            top += counts[kind] * heights[kind]
        out.append(f'<g class="lane" data-agent={quoteattr(_clean(agent))}>'
                   + "".join(parts) + "</g>")
        y += lane_h
    grid = [f'<line class="grid" x1="{_n(x(t))}" y1="{_n(lanes_top)}" x2="{_n(x(t))}" '
            f'y2="{_n(y)}" stroke="#e3e6ea"/>' for t in _ticks(t0, end, step)]
    for s in tl.tasks:
        for t, what in ((s.start, "start"), (s.end, "end")):
            if t is not None:
                out.append(f'<line class="task-line task-{what}" '
                           f'data-task={quoteattr(_clean(s.node))} x1="{_n(x(t))}" '
                           f'y1="{_n(band_top)}" x2="{_n(x(t))}" y2="{_n(y)}" '
                           'stroke="#555" stroke-dasharray="2,3"/>')
    out.append(_axis(t0, end, step, x, y + 4, above=False))
    legend, legend_h = _legend(tl, MARGIN, y + 34, width - 2 * MARGIN)
    height = y + 34 + legend_h + MARGIN
    head = (f'<svg xmlns="http://www.w3.org/2000/svg" width="{_n(width)}" height="{_n(height)}" '
            f'viewBox="0 0 {_n(width)} {_n(height)}" font-family="{FONT_FAMILY}" '
            f'font-size="{FONT}">')
    return "\n".join([head, f"<title>{_esc(heading)}</title>", _DEFS,
                      '<rect width="100%" height="100%" fill="#ffffff"/>', *grid, *out, legend,
                      "</svg>"]) + "\n"


_DEFS = ('<defs><pattern id="hatch" width="6" height="6" patternUnits="userSpaceOnUse" '
         'patternTransform="rotate(45)"><rect width="6" height="6" fill="#eef3f8"/>'
         '<line x1="0" y1="0" x2="0" y2="6" stroke="#7fa6cc" stroke-width="2"/></pattern>'
         '<pattern id="pause" width="6" height="6" patternUnits="userSpaceOnUse" '
         'patternTransform="rotate(45)"><rect width="6" height="6" fill="#ffffff" '
         'opacity="0.55"/><line x1="0" y1="0" x2="0" y2="6" stroke="#ffffff" '
         'stroke-width="2" opacity="0.6"/></pattern></defs>')
"""The fill of actions still running, and the veil over suspended acts."""


def _task_item(s: TaskSpan, t_end: float) -> Item:
    """A top-level task as an item of the band: a line from start to end."""
    over = s.end is not None
    return Item("", "task", s.start, s.end if over else t_end,
                f"{s.name}: {s.outcome}" if over else f"{s.name}: still running",
                f"task {s.name} [{s.node}] {shown_time(s.start)} – "
                + (f"{shown_time(s.end)} s, {s.outcome}" if s.end is not None else "…"), "task",
                attrs={"data-task": s.node, "data-start": repr(s.start)}
                | ({"data-end": repr(s.end)} if s.end is not None else {}))


def write_timeline(log_path: str | Path, out_path: str | Path, title: str = "") -> Path:
    """Render the log at ``log_path`` into ``out_path`` (titled by the log's name if no title)."""
    out = Path(out_path)
    with stream_events(log_path) as events:  # streamed: a long log is never held whole
        svg = render_timeline(events, title or Path(log_path).stem)
    write_output(out, svg)
    return out


# -- pieces ----------------------------------------------------------------------


def _pack(items: list[Item], x: Any, t_end: float,
          size: int = FONT) -> tuple[list[tuple[Item, int]], float]:
    """Sub-rows so that no bar or label covers another, and the rightmost pixel used.

    Bars wide enough to hold their label are placed first, in time order, so
    that a sequence of actions stays on one row; instants and points, whose
    labels go beside them, then fill the gaps that are left. Where the gaps
    are full (a long, dense run), a label beside is dropped rather than a row
    added for it: its text stays in the tooltip.
    """
    spans: list[tuple[Item, float, float, float]] = []  # item, left, bar's right, label's
    for item in items:
        left = x(item.start) - (7 if item.point else 0)
        right = x(item.end if item.end is not None else t_end) + (6 if item.end is None else 0)
        item.beside = item.point or right - left < MIN_LABEL_INSIDE
        label = (left + (16 if item.point else 4) + text_width(item.label, size) + 6
                 if item.beside else right)
        spans.append((item, left, right, max(right, label)))
    spans.sort(key=lambda s: (s[0].beside, s[1]))
    rows: list[tuple[list[float], list[float]]] = []  # per row: lefts and rights, sorted
    placed: list[tuple[Item, int]] = []
    for item, left, right, labelled in spans:
        index = next((i for i, (lefts, rights) in enumerate(rows)
                      if _free(lefts, rights, left, labelled)), len(rows))
        if index >= LABEL_ROWS and labelled > right:
            item.beside = False  # no room for the label: the bar alone
            index = next((i for i, (lefts, rights) in enumerate(rows)
                          if _free(lefts, rights, left, right)), len(rows))
        else:
            right = labelled
        if index == len(rows):
            rows.append(([], []))
        lefts, rights = rows[index]
        at = bisect.bisect_right(lefts, left)
        lefts.insert(at, left)
        rights.insert(at, right)
        placed.append((item, index))
    return placed, max((max(r[1][-1] for r in rows) if rows else 0.0), 0.0)


def _free(lefts: list[float], rights: list[float], left: float, right: float) -> bool:
    """Whether [left, right] overlaps none of a row's sorted, disjoint spans."""
    at = bisect.bisect_right(lefts, left)
    return ((at == 0 or rights[at - 1] <= left + 0.01)
            and (at == len(lefts) or lefts[at] >= right - 0.01))


def _rows(placed: list[tuple[Item, int]]) -> int:
    return max((row for _, row in placed), default=-1) + 1


def _item(item: Item, top: float, height: float, x: Any, t_end: float) -> str:
    attrs = "".join(f" {k}={quoteattr(_clean(v))}" for k, v in item.attrs.items())
    cls = f"{item.row} {item.kind}"
    head = (f'<g class={quoteattr(_clean(cls))} data-agent={quoteattr(_clean(item.agent))}{attrs}>'
            f"<title>{_esc(item.tooltip)}</title>")
    mid = top + height / 2
    if item.point:
        cx = x(item.start)
        r = height / 2 - 4
        fill, stroke = (RECOGNIZED_STYLES["rec-achieved"][:2] if item.kind == "rec-achieved"
                        else (POINT_COLOURS.get(item.kind, POINT_COLOURS["received"]),
                              "#9e2a63"))
        shape = (f'<polygon points="{_n(cx)},{_n(mid - r)} {_n(cx + r)},{_n(mid)} '
                 f'{_n(cx)},{_n(mid + r)} {_n(cx - r)},{_n(mid)}" fill="{fill}" '
                 f'stroke="{stroke}" stroke-width="1.5"/>')
        text = _text(cx + r + 4, mid + 4, item.label, "label") if item.beside else ""
        return head + shape + text + "</g>"
    left = x(item.start)
    width = (x(item.end) if item.end is not None else x(t_end)) - left
    pad = 2 if item.row != "look" else 1.5
    y, h = top + pad, height - 2 * pad
    if item.row == "action":
        fill, stroke, ink = ACTION_STYLES[item.kind]
    elif item.row == "recognized":
        fill, stroke, ink = RECOGNIZED_STYLES[
            "rec-abandoned" if item.kind == "rec-abandoned" else "rec-started"]
    elif item.row == "look":
        fill, stroke, ink = item.colour, "#4f8f8a", "#1f3f3c"
    else:
        fill, stroke, ink = item.colour, item.colour, "#ffffff"
    body = (f'<rect class="bar" x="{_n(left)}" y="{_n(y)}" width="{_n(width)}" height="{_n(h)}" '
            f'rx="2" fill="{fill}" stroke="{stroke}" stroke-width="1"/>')
    if item.end is None and item.row != "action":
        body += (f'<rect class="open" x="{_n(left)}" y="{_n(y)}" width="{_n(width)}" '
                 f'height="{_n(h)}" fill="url(#hatch)" opacity="0.45"/>')
    for start, stop in item.suspended:
        s_left = x(start)
        s_width = x(stop if stop is not None else t_end) - s_left
        until = f' data-end="{stop!r}"' if stop is not None else ""
        body += (f'<rect class="suspended" data-start="{start!r}"{until} x="{_n(s_left)}" '
                 f'y="{_n(y)}" width="{_n(s_width)}" height="{_n(h)}" fill="url(#pause)"/>')
    if item.row == "recognized":
        body += _recognition_marks(item, x, y, h, mid)
    if width < 2:  # an instant: a visible tick, the bar itself keeping its exact extent
        body += (f'<rect class="instant" x="{_n(left - 1)}" y="{_n(y)}" width="2" '
                 f'height="{_n(h)}" fill="{stroke}"/>')
    if item.end is None:  # still going when the log ends: an arrow past the last event
        tip = left + max(width, 0)
        body += (f'<polygon class="open-end" points="{_n(tip + 1)},{_n(y)} {_n(tip + 6)},'
                 f'{_n(mid)} {_n(tip + 1)},{_n(y + h)}" fill="{stroke}"/>')
    size = FONT - 1 if item.row == "look" else FONT
    if width >= MIN_LABEL_INSIDE:
        label = _fit(item.label, width - 8, size)
        if label:
            body += _text(left + 4, mid + size * 0.36, label, "label", size=size, fill=ink,
                          tooltip=item.label)
    elif item.beside:
        beside = left + max(width, 0) + (10 if item.end is None else 4)
        body += _text(beside, mid + size * 0.36, item.label, "label outside",
                      size=size, fill="#333")
    return head + body + "</g>"


def _recognition_marks(item: Item, x: Any, y: float, h: float, mid: float) -> str:
    """The progressing part of a recognized action's bar, and its achievement."""
    marks = ""
    if "data-progressing" in item.attrs:
        since = x(float(item.attrs["data-progressing"]))
        until = x(item.end) if item.end is not None else since + 6
        fill, stroke, _ = RECOGNIZED_STYLES["rec-progressing"]
        marks += (f'<rect class="progressing" x="{_n(since)}" y="{_n(y)}" '
                  f'width="{_n(max(until - since, 2))}" height="{_n(h)}" fill="{fill}" '
                  f'stroke="{stroke}" stroke-width="1"/>')
    if item.kind == "rec-achieved" and item.end is not None:
        fill, stroke, _ = RECOGNIZED_STYLES["rec-achieved"]
        cx, r = x(item.end), h / 2 - 1
        marks += (f'<polygon class="achieved" points="{_n(cx)},{_n(mid - r)} '
                  f'{_n(cx + r)},{_n(mid)} {_n(cx)},{_n(mid + r)} {_n(cx - r)},{_n(mid)}" '
                  f'fill="{fill}" stroke="{stroke}" stroke-width="1.5"/>')
    return marks


def _band(item: Item, top: float, x: Any, t_end: float) -> str:
    attrs = "".join(f" {k}={quoteattr(_clean(v))}" for k, v in item.attrs.items())
    left = x(item.start)
    right = x(item.end if item.end is not None else t_end)
    mid = top + BAND_ROW / 2
    if item.point:
        fill, stroke = ("#e15759", "#7a1f20") if item.kind == "respawn" else ("#edc948",
                                                                               "#8a6d00")
        return (f'<g class="{item.kind}"{attrs}><title>{_esc(item.tooltip)}</title>'
                f'<polygon points="{_n(left)},{_n(mid - 5)} {_n(left + 5)},{_n(mid + 5)} '
                f'{_n(left - 5)},{_n(mid + 5)}" fill="{fill}" stroke="{stroke}"/>'
                + _text(left + 8, mid + 4, item.label, "label", fill=stroke) + "</g>")
    return (f'<g class="task"{attrs}><title>{_esc(item.tooltip)}</title>'
            f'<line x1="{_n(left)}" y1="{_n(mid + 5)}" x2="{_n(right)}" y2="{_n(mid + 5)}" '
            'stroke="#555" stroke-width="2"/>'
            + _text(left + 4, mid + 1, _fit(item.label, max(right - left - 8, 0), FONT)
                    if right - left >= MIN_LABEL_INSIDE else item.label, "label", weight="bold",
                    fill="#333", tooltip=item.label)
            + "</g>")


def _axis(t0: float, end: float, step: float, x: Any, y: float, *, above: bool) -> str:
    parts = [f'<line x1="{_n(x(t0))}" y1="{_n(y)}" x2="{_n(x(end))}" y2="{_n(y)}" '
             'stroke="#555" stroke-width="1"/>']
    for t in _ticks(t0, end, step):
        tick = -4 if above else 4
        parts.append(f'<line x1="{_n(x(t))}" y1="{_n(y)}" x2="{_n(x(t))}" y2="{_n(y + tick)}" '
                     'stroke="#555" stroke-width="1"/>')
        parts.append(_text(x(t), y - 7 if above else y + 15, f"{shown_time(t)} s", "tick",
                           size=SMALL + 1, fill="#444", anchor="middle"))
    return f'<g class="axis">{"".join(parts)}</g>'


def _legend(tl: Timeline, left: float, top: float, width: float) -> tuple[str, float]:
    """Swatches for what the picture shows, wrapped to the picture's width."""
    entries: list[tuple[str, str]] = []
    acts = dict.fromkeys(i.attrs.get("data-act", "") for i in tl.items
                         if i.row == "act" and not i.point)
    for act in acts:
        colour = next(i.colour for i in tl.items if i.attrs.get("data-act") == act)
        entries.append((f'<rect width="18" height="10" y="-9" fill="{colour}"/>', act))
    if any(i.suspended for i in tl.items):
        entries.append(('<rect width="18" height="10" y="-9" fill="#59a14f"/>'
                        '<rect width="18" height="10" y="-9" fill="url(#pause)"/>',
                        "act suspended"))
    kinds = {i.kind for i in tl.items}
    diamond = '<polygon points="9,-10 15,-4 9,2 3,-4" fill="{}" stroke="#9e2a63"/>'
    for kind, fill, text in (("received", "#e15f99", "act sent by a human"),
                             ("unexpected", "#ffffff", "act no task expected")):
        if kind in kinds:
            entries.append((diamond.format(fill), text))
    for status, text in (("done", "action done"), ("failed", "action failed"),
                         ("cancelled", "action cancelled"),
                         ("running", "still going at the end")):
        if status in kinds or (status == "running" and any(i.end is None for i in tl.items)):
            fill, stroke, _ = ACTION_STYLES[status]
            entries.append((f'<rect width="18" height="10" y="-9" fill="{fill}" '
                            f'stroke="{stroke}"/>', text))
    recognized = [i for i in tl.items if i.row == "recognized"]
    shown_states = {"rec-started": any(not i.point for i in recognized),
                    "rec-progressing": any("data-progressing" in i.attrs for i in recognized),
                    "rec-achieved": "rec-achieved" in kinds,
                    "rec-abandoned": "rec-abandoned" in kinds}
    for kind, text, point in (("rec-started", "possibly started", False),
                              ("rec-progressing", "possibly progressing", False),
                              ("rec-achieved", "possibly achieved", True),
                              ("rec-abandoned", "abandoned", False)):
        if shown_states[kind]:
            fill, stroke, _ = RECOGNIZED_STYLES[kind]
            entries.append((f'<polygon points="9,-10 15,-4 9,2 3,-4" fill="{fill}" '
                            f'stroke="{stroke}"/>' if point else
                            f'<rect width="18" height="10" y="-9" fill="{fill}" '
                            f'stroke="{stroke}"/>', text))
    for state, colour in PLAN_STATE_COLOURS.items():
        if f"plan-{state}" in kinds:
            entries.append((f'<rect width="18" height="10" y="-9" fill="{colour}"/>',
                            f"task {state}"))
    if any(i.row == "look" for i in tl.items):
        entries.append((f'<rect width="18" height="6" y="-7" fill="{LOOK_COLOUR}"/>',
                        "looks at"))
    for kind, text in (("question", "question or help request"), ("answer", "answer"),
                       ("expired", "question expired"), ("breakpoint", "breakpoint")):
        if kind in kinds:
            entries.append((diamond.format(POINT_COLOURS[kind]), text))
    team = [i for i in tl.items if i.row == "team"]
    for colour, text, shown in (
            ("done", "team task done", any(i.attrs.get("data-status") == "done" for i in team)),
            ("failed", "team task failed",
             any(i.attrs.get("data-status") == "failed" for i in team)),
            ("team-task", "team task under way",
             any(i.kind == "team-task" and i.end is None for i in team)),
            ("associated", "associated with a person", "associated" in kinds),
            ("user-mode", "user mode (a person drives)", "user-mode" in kinds)):
        if shown:
            entries.append((f'<rect width="18" height="10" y="-9" '
                            f'fill="{TEAM_COLOURS[colour]}"/>', text))
    if any(p.kind == "plan" for p in tl.plans):
        entries.append(('<polygon points="9,-9 14,1 4,1" fill="#edc948" stroke="#8a6d00"/>',
                        "plan from the planner"))
    if any(p.kind == "respawn" for p in tl.plans):
        entries.append(('<polygon points="9,-9 14,1 4,1" fill="#e15759" stroke="#7a1f20"/>',
                        "task respawned"))
    entries.append(('<line x1="9" y1="-12" x2="9" y2="4" stroke="#555" stroke-dasharray="2,3"/>',
                    "task start / end"))
    parts, cx, cy = [], left, top
    for swatch, text in entries:
        w = 24 + text_width(text, FONT) + 18
        if cx + w > left + width and cx > left:
            cx, cy = left, cy + 18
        parts.append(f'<g class="legend-entry" transform="translate({_n(cx)},{_n(cy)})">'
                     f"{swatch}{_text(24, 0, text, 'legend')}</g>")
        cx += w
    return f'<g class="legend">{"".join(parts)}</g>', cy - top + 18


def _preferred_scale(tl: Timeline) -> float:
    """Pixels per second at which a typical (median) action shows its whole label.

    Actions are the shortest bars that carry labels, so sizing the scale on
    them keeps most labels whole; the range keeps one odd run from drawing
    a minute as a few pixels or an instant as a page, and :data:`WIDE_PLOT`
    keeps a run of many short actions (the PR2 looking at each cube in turn)
    from a picture four screens wide: their labels go beside them, or whole in
    their tooltips.
    """
    needs = sorted((text_width(i.label, FONT) + 10) / (i.end - i.start) for i in tl.items
                   if i.row == "action" and i.end is not None and i.end > i.start)
    low, high = PX_PER_SECOND
    return min(max(needs[len(needs) // 2] if needs else low, low), high)


def _tick_step(scale: float) -> float:
    """The smallest 1-2-5 step at least 70 px wide, so tick labels never touch."""
    raw = 70 / scale
    power = 10 ** math.floor(math.log10(raw))
    return next(m * power for m in (1, 2, 5, 10) if m * power >= raw - 1e-12)


def _ticks(t0: float, end: float, step: float) -> list[float]:
    return [round(t0 + k * step, 9) for k in range(int(round((end - t0) / step)) + 1)]


def _text(x: float, y: float, text: str, cls: str, *, size: int = FONT, weight: str = "",
          fill: str = "#222", anchor: str = "", tooltip: str = "") -> str:
    extra = (f' font-weight="{weight}"' if weight else "") + (
        f' text-anchor="{anchor}"' if anchor else "")
    tip = f"<title>{_esc(tooltip)}</title>" if tooltip and tooltip != text else ""
    return (f'<text class="{cls}" x="{_n(x)}" y="{_n(y)}" font-size="{size}" fill="{fill}"'
            f'{extra}>{tip}{_esc(text)}</text>')


def _fit(text: str, room: float, size: float) -> str:
    """``text`` or its longest prefix + '…' that fits ``room`` pixels ('' when none does)."""
    if text_width(text, size) <= room:
        return text
    for cut in range(len(text) - 1, 0, -1):
        short = text[:cut].rstrip() + "…"
        if text_width(short, size) <= room:
            return short
    return ""

def _n(v: float) -> str:
    return f"{v:.2f}".rstrip("0").rstrip(".")


def _clean(text: str) -> str:
    """Text that XML 1.0 can hold at all: control characters become U+FFFD."""
    return _NOT_XML.sub("\ufffd", text)


def _esc(text: str) -> str:
    return escape(_clean(text))
