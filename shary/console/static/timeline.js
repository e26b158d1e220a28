// The timeline on the console page: one lane per agent, its items as bars (an act, an
// action, a question …) labelled and cut to their room, under a time axis, with a legend
// of the classes shown; the axis is an SVG of its own that stays at the top of the
// timeline's box when the lanes scroll under it.  Loaded after console.js: its change kinds (item, item-end) go
// into console.js's APPLY; console.js's clock and reset call clock and axis here.
"use strict";

const PX_PER_S = 14, LANE_ROW = 16, LANE_TOP = 18;
const TICK_S = 5;  // a label of the time axis every 5 s (70 px)
const MIN_LABEL_PX = 64;  // the room a label of an instant (an answer, a look) has beside it
const LEGEND = {  // the timeline's classes, as its legend names them
  act: "a robot's act", action: "action running", running: "action running", done: "done",
  failed: "failed", cancelled: "cancelled", received: "a person's act",
  recognized: "recognized action", "recognized-achieved": "achieved",
  "recognized-abandoned": "abandoned", "not-seen": "not seen", teamtask: "team task",
  question: "question open", answered: "answered", expired: "expired", answer: "answer",
  usermode: "user mode", assoc: "associated", message: "message", delegation: "delegation",
  respawn: "respawned",
};

function lane(name) {
  let l = st.lanes.get(name);
  if (!l) {
    const svg = $("timeline");
    const y = st.lanes.size ? [...st.lanes.values()].reduce((m, o) => Math.max(m, o.bottom), 0) : 4;
    const g = document.createElementNS(SVGNS, "g");
    const label = document.createElementNS(SVGNS, "text");
    label.setAttribute("class", "lane-name");
    label.setAttribute("x", 2); label.setAttribute("y", y + 12);
    label.textContent = name;
    g.append(label);
    svg.append(g);
    l = { g, y, shift: 0, rows: [], bottom: y + LANE_TOP + LANE_ROW };
    st.lanes.set(name, l);
    svg.setAttribute("height", l.bottom + 4);
  }
  return l;
}

function x(t) { return 70 + t * PX_PER_S; }

function item(id, laneName, t0, label, cls) {
  const l = lane(laneName || "?");
  let row = l.rows.findIndex((end) => end !== null && end <= t0);
  if (row < 0) { row = l.rows.length; l.rows.push(null); } else l.rows[row] = null;
  const bottom = l.y + l.shift + LANE_TOP + (row + 1) * LANE_ROW;
  if (bottom > l.bottom) growLane(l, bottom - l.bottom);
  const y = l.y + LANE_TOP + row * LANE_ROW;
  const rect = document.createElementNS(SVGNS, "rect");
  rect.setAttribute("x", x(t0)); rect.setAttribute("y", y);
  // as long as it has lasted by the page's clock (a replay's items come after its time)
  rect.setAttribute("height", LANE_ROW - 3); rect.setAttribute("width", Math.max(2, (st.time - t0) * PX_PER_S));
  rect.setAttribute("class", cls);
  const title = document.createElementNS(SVGNS, "title");
  title.textContent = (label || cls) + " from " + t0.toFixed(1) + " s";
  rect.append(title);
  const text = document.createElementNS(SVGNS, "text");
  text.setAttribute("x", x(t0) + 3); text.setAttribute("y", y + 10);
  text.textContent = label;
  l.g.append(rect, text);
  st.items.set(id, { rect, text, label: label || "", t0, l, row, lane: laneName, cls });
  st.open.add(id);
  legend(cls);
  widen(t0);
  if (cls === "action") nowShown();
}

function legend(cls) {
  // a swatch per class the timeline shows, named once (two classes may share a name)
  const name = LEGEND[cls];
  if (!name || st.legend.has(name)) return;
  st.legend.add(name);
  const key = el("span", "key");
  const swatch = document.createElementNS(SVGNS, "svg");
  swatch.setAttribute("class", "tl swatch"); swatch.setAttribute("width", 14); swatch.setAttribute("height", 11);
  const r = document.createElementNS(SVGNS, "rect");
  r.setAttribute("class", cls); r.setAttribute("width", 14); r.setAttribute("height", 11);
  swatch.append(r);
  key.append(swatch, " " + name);
  $("legend").append(key);
}

function axis() {
  // every TICK_S seconds a label and a tick on the axis, and a faint line down the lanes,
  // added as the timeline widens (the lanes' lines go with a reset, the axis stays)
  const svg = $("timeline"), top = $("axis");
  const width = Number(svg.getAttribute("width"));
  top.setAttribute("width", width);
  let grid = svg.querySelector("g.grid");
  if (!grid) {
    grid = document.createElementNS(SVGNS, "g");
    grid.setAttribute("class", "grid");
    grid.dataset.upTo = -TICK_S;
    svg.prepend(grid);
  }
  for (let s = Number(grid.dataset.upTo) + TICK_S; x(s) + 30 <= width; s += TICK_S) {
    grid.append(line(x(s), 0, "100%"));
    grid.dataset.upTo = s;
  }
  for (let s = Number(top.dataset.upTo || -TICK_S) + TICK_S; x(s) + 30 <= width; s += TICK_S) {
    const label = document.createElementNS(SVGNS, "text");
    label.setAttribute("class", "tick"); label.setAttribute("x", x(s) + 2); label.setAttribute("y", 13);
    label.textContent = s + " s";
    top.append(line(x(s), 14, 20), label);
    top.dataset.upTo = s;
  }
}

function line(at, y1, y2) {
  const l = document.createElementNS(SVGNS, "line");
  l.setAttribute("x1", at); l.setAttribute("x2", at); l.setAttribute("y1", y1); l.setAttribute("y2", y2);
  return l;
}

function growLane(l, by) {
  let below = false;
  for (const other of st.lanes.values()) {  // lanes are stacked in the order they came
    if (below) {
      other.shift += by; other.bottom += by;
      other.g.setAttribute("transform", "translate(0," + other.shift + ")");
    }
    if (other === l) below = true;
  }
  l.bottom += by;
  const total = [...st.lanes.values()].reduce((m, o) => Math.max(m, o.bottom), 0);
  $("timeline").setAttribute("height", total + 4);
}

function itemEnd(id, t1, cls) {
  const it = st.items.get(id);
  if (!it) return;
  const bar = Math.max(2, (t1 - it.t0) * PX_PER_S);
  it.rect.setAttribute("width", bar);
  it.rect.setAttribute("class", cls);
  legend(cls);
  it.rect.firstChild.textContent += " to " + t1.toFixed(1) + " s (" + cls + ")";
  // the label, cut to its bar (or to a short word beside an instant), holds its row as
  // long as the bar: the next item of the row starts after both, never on top of them
  const used = shorten(it.text, it.label, Math.max(bar, MIN_LABEL_PX) - 4);
  it.l.rows[it.row] = used ? it.t0 + Math.max(bar, used + 6) / PX_PER_S : t1;
  st.open.delete(id);
  if (it.cls === "action") nowShown();
}

function shorten(text, label, room) {
  // the text's width once it fits in room pixels, cut with an ellipsis (the whole label
  // stays in the bar's tooltip)
  let width = text.getComputedTextLength();
  if (width <= room) return width;
  let keep = Math.max(0, Math.floor(label.length * room / width));
  do {
    text.textContent = keep ? label.slice(0, keep) + "…" : "";
    width = keep ? text.getComputedTextLength() : 0;
    keep--;
  } while (width > room && keep >= 0);
  return width;
}

function widen(t) {
  // in steps of 600 px: a width changed at every update would lay the page out again each time
  const svg = $("timeline");
  const w = x(t) + 120;
  if (w > Number(svg.getAttribute("width"))) {
    svg.setAttribute("width", Math.ceil(w / 600) * 600);
    axis();
  }
}

function clock(t) {
  st.time = t;
  $("clock").textContent = t.toFixed(1) + " s";
  for (const id of st.open) {
    const it = st.items.get(id);
    it.rect.setAttribute("width", Math.max(2, (t - it.t0) * PX_PER_S));
  }
  widen(t);
}

Object.assign(APPLY, { "item": item, "item-end": itemEnd });
axis();
