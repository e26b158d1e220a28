// The shary console page: applies the server's changes to the DOM in place.
// Every change kind is documented in shary/console/view.py; text always goes in
// through textContent (never parsed as HTML); the only markup inserted is the
// scheme diagrams the server drew with dot.
"use strict";

const $ = (id) => document.getElementById(id);
const SVGNS = "http://www.w3.org/2000/svg";
const MAX_LINES = 300, MAX_FACT_ROWS = 40, PX_PER_S = 14, LANE_ROW = 16, LANE_TOP = 18;
const MIN_LABEL_PX = 64;  // the room a label of an instant (an answer, a look) has beside it
const bench = location.search.includes("bench");
const SCALE = 0.6, SUB_SCALE = 0.45;  // of a scheme as dot draws it (14 pt state names)

const st = {
  ws: null, mode: null, status: {}, svgs: {}, time: 0, nextId: 1,
  agents: new Map(), tasks: new Map(), nodes: new Map(), items: new Map(), open: new Set(),
  lanes: new Map(), goals: new Map(), facts: new Map(), questions: new Map(),
  latencies: [], applied: 0,
};
window.shary = st;  // read by the browser tests and the benchmark
// what the page's other scripts (plan.js, team.js) hook into: a reset, a scheme drawn, a status
const HOOKS = { reset: [], scheme: [], status: [] };

function el(tag, cls, text) {
  const e = document.createElement(tag);
  if (cls) e.className = cls;
  if (text !== undefined) e.textContent = text;
  return e;
}

function send(message) {
  message.by = $("operator").value.trim() || "operator";
  message.id = st.nextId++;
  st.ws.send(JSON.stringify(message));
}

// -- agents and their schemes --------------------------------------------------

function agent(name, kind) {
  let a = st.agents.get(name);
  if (!a) {
    const box = el("div", "agent");
    box.dataset.agent = name;
    const h = el("h2", null, name + " ");
    const small = el("small");
    h.append(small);
    box.append(h, el("div", "tasks"));
    $("agents").append(box);
    a = { box, small, tasks: box.lastChild, kind: "agent" };
    st.agents.set(name, a);
  }
  if (kind !== "agent" && a.kind !== kind) {
    a.kind = kind;
    a.small.textContent = "(" + kind + ")";
    if (st.mode === "live") agentButtons(a, name, kind);
  }
  return a;
}

function agentButtons(a, name, kind) {
  // a person's acts sent on their behalf; a robot's control authority (refused by a
  // simulated SHARY robot: the page says why)
  const acts = kind === "human" ? ["H-AGREE", "H-DISAGREE"] : ["take-control", "hand-back"];
  for (const act of acts) {
    const b = el("button", "agent-act", act);
    b.dataset.agent = name;
    b.title = kind === "human" ? "send " + act + " for " + name : act + " of " + name;
    b.onclick = () => send(kind === "human" ? { kind: "act", agent: name, act }
      : { kind: act, agent: name });
    a.small.parentNode.append(b);
  }
}

function task(node, who, name, scheme, roles) {
  const a = st.agents.get(who) || agent(who || "?", "agent");
  const box = el("div", "task");
  box.dataset.node = node;
  const h = el("h3", null, name + " ");
  const others = Object.entries(roles || {}).filter(([r]) => r !== "robot");
  h.append(el("small", null, node + " · " + scheme + (others.length ? " · " +
    others.map(([r, w]) => r + "=" + w).join(", ") : "")));
  if (st.mode === "live") {
    const b = el("button", "cancel", "cancel");
    b.title = "cancel this task (the operator's action is logged)";
    b.onclick = () => send({ kind: "cancel", task: node });
    h.append(b);
  }
  const diagram = el("div", "diagram"), config = el("div", "config");
  box.append(h, diagram, config);
  const n = st.nodes.get(node);
  if (n && n.parent) box.classList.add("sub");
  a.tasks.append(box);
  const t = { box, diagram, config, scheme, agent: who, name, active: [], marks: null };
  st.tasks.set(node, t);
  drawInto(t);
}

function drawInto(t) {
  const svg = st.svgs[t.scheme];
  if (!svg || t.marks) return;
  t.diagram.innerHTML = svg;
  fit(t);
  t.marks = new Map();
  for (const g of t.diagram.querySelectorAll("g[data-state]")) t.marks.set(g.dataset.state, g);
  highlight(t, t.active, []);
}

function fit(t) {
  // every scheme at one scale, whatever its size: its text stays legible (state names
  // 11 px, a subtask's 8.5 px) and two agents' schemes compare at a glance; what does not
  // fit the column scrolls in its box
  const svg = t.diagram.querySelector("svg");
  if (!svg) return;
  const scale = t.box.classList.contains("sub") ? SUB_SCALE : SCALE;
  svg.style.width = (svg.width.baseVal.value * scale) + "px";
  svg.style.height = "auto";
}

function highlight(t, now, before) {
  if (!t.marks) return;
  for (const s of before) { const g = t.marks.get(s); if (g) g.classList.remove("active"); }
  for (const s of now) { const g = t.marks.get(s); if (g) g.classList.add("active"); }
}

function config(node, states) {
  const t = st.tasks.get(node);
  if (!t) return;
  highlight(t, states, t.active);
  t.active = states;
  t.config.textContent = "active: " + (states.join(", ") || "—");
}

function taskEnd(node, outcome) {
  const t = st.tasks.get(node);
  if (!t) return;
  const n = st.nodes.get(node);
  if (n && n.parent) {  // a subtask's diagram goes once it is over; the tree keeps it
    t.box.remove();
    st.tasks.delete(node);
    return;
  }
  t.box.classList.add("ended");
  t.config.textContent = "ended: " + outcome;
}

// -- the task tree ---------------------------------------------------------------

function node(id, parent, kind, name, state) {
  const li = el("li", "k-" + kind + " s-" + state);
  li.id = "t-" + id;
  const label = el("span", null, name);
  label.title = id + " (" + kind + ")";
  li.append(label);
  const p = parent && st.nodes.get(parent);
  let ul = $("tree");
  if (p) {
    if (!p.ul) { p.ul = el("ul"); p.li.append(p.ul); }
    ul = p.ul;
  }
  ul.append(li);
  st.nodes.set(id, { li, ul: null, parent: p ? parent : null, kind });
  const t = st.tasks.get(id);
  if (t && p && !t.box.classList.contains("sub")) { t.box.classList.add("sub"); fit(t); }
}

function nodeState(id, state) {
  const n = st.nodes.get(id);
  if (n) n.li.className = "k-" + n.kind + " s-" + state;
}

function cut(ids) {
  for (const id of ids) {
    const n = st.nodes.get(id);
    if (n) { n.li.remove(); st.nodes.delete(id); }
  }
}

// -- the timeline -----------------------------------------------------------------

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
  rect.setAttribute("height", LANE_ROW - 3); rect.setAttribute("width", 2);
  rect.setAttribute("class", cls);
  const title = document.createElementNS(SVGNS, "title");
  title.textContent = (label || cls) + " from " + t0.toFixed(1) + " s";
  rect.append(title);
  const text = document.createElementNS(SVGNS, "text");
  text.setAttribute("x", x(t0) + 3); text.setAttribute("y", y + 10);
  text.textContent = label;
  l.g.append(rect, text);
  st.items.set(id, { rect, text, label: label || "", t0, l, row });
  st.open.add(id);
  widen(t0);
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
  it.rect.firstChild.textContent += " to " + t1.toFixed(1) + " s (" + cls + ")";
  // the label, cut to its bar (or to a short word beside an instant), holds its row as
  // long as the bar: the next item of the row starts after both, never on top of them
  const used = shorten(it.text, it.label, Math.max(bar, MIN_LABEL_PX) - 4);
  it.l.rows[it.row] = used ? it.t0 + Math.max(bar, used + 6) / PX_PER_S : t1;
  st.open.delete(id);
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
  if (w > Number(svg.getAttribute("width"))) svg.setAttribute("width", Math.ceil(w / 600) * 600);
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

// -- agenda, facts, lines, questions ------------------------------------------------

function goal(id, name, args, priority, state) {
  let row = st.goals.get(id);
  if (!row) {
    row = el("tr");
    for (let i = 0; i < 4; i++) row.append(el("td"));
    $("agenda").tBodies[0].append(row);
    st.goals.set(id, row);
  }
  const cells = row.children;
  cells[0].textContent = typeof id === "number" ? "#" + id : id; cells[1].textContent = name + (args ? " (" + args + ")" : "");
  cells[2].textContent = "priority " + priority; cells[3].textContent = state;
}

function fact(perspective, s, p, o, added) {
  let f = st.facts.get(perspective);
  if (!f) {
    const box = el("div", "facts-of");
    box.append(el("h3", null, perspective), el("table"));
    box.lastChild.append(el("tbody"));
    $("facts").append(box);
    f = { body: box.lastChild.tBodies[0], rows: new Map() };
    st.facts.set(perspective, f);
  }
  const key = s + "\u0000" + p + "\u0000" + o;
  const old = f.rows.get(key);
  if (old) { old.remove(); f.rows.delete(key); }
  if (!added) return;
  const row = el("tr", "fresh");
  row.append(el("td", null, s), el("td", null, p), el("td", null, o));
  if (f.body.firstChild) f.body.firstChild.className = "";
  f.body.prepend(row);
  f.rows.set(key, row);
  if (f.body.rows.length > MAX_FACT_ROWS) {
    const last = f.body.lastChild;
    f.rows.delete(last.children[0].textContent + "\u0000" + last.children[1].textContent +
      "\u0000" + last.children[2].textContent);
    last.remove();
  }
}

function line(t, who, kind, text) {
  const box = $("lines");
  const d = el("div", "line " + kind);
  d.append(el("span", "t", t.toFixed(1) + " s"), el("span", "who", who), el("span", "what", text));
  const atEnd = box.scrollTop + box.clientHeight >= box.scrollHeight - 4;
  box.append(d);
  if (box.childElementCount > MAX_LINES) box.firstChild.remove();
  if (atEnd) box.scrollTop = box.scrollHeight;
}

function question(node, act, people, answers, image) {
  questionEnd(node);
  const box = el("div", "question");
  box.dataset.node = node;
  const t = st.tasks.get(node);
  box.append(el("div", null, (t ? t.agent : "The robot") + " asks (" + act + ", task " +
    (t ? t.name : "?") + ", " + node + "). Answer for:"));
  if (image) {
    const img = el("img");
    img.src = "/run/" + encodeURIComponent(image);
    img.alt = "what the robot saw when it asked";
    box.append(img);
  }
  for (const who of people) {
    const row = el("div", null, who + ": ");
    for (const a of answers) {
      const b = el("button", null, a);
      b.dataset.agent = who; b.dataset.act = a;
      b.disabled = st.mode !== "live";
      b.onclick = () => send({ kind: "answer", task: node, agent: who, act: a });
      row.append(b);
    }
    box.append(row);
  }
  $("questions").append(box);
  st.questions.set(node, box);
  noneShown();
}

function questionEnd(node) {
  const box = st.questions.get(node);
  if (box) { box.remove(); st.questions.delete(node); }
  noneShown();
}

function noneShown() {
  const none = $("questions").querySelector(".none");
  if (none) none.hidden = st.questions.size > 0;
}

// -- the run's status ------------------------------------------------------------------

function status(s) {
  st.status = s;
  const pill = $("status");
  pill.textContent = s.state + (s.why ? " (" + s.why + ")" : "");
  pill.className = "pill " + s.state;
  if (s.mode === "live") {
    $("run-controls").hidden = false;
    const over = s.state === "ended" || s.state === "error";
    for (const id of ["pause", "resume", "step", "speed", "bp-add", "bp-act"]) $(id).disabled = over;
    document.body.classList.toggle("run-over", over);
    $("speed").value = String(s.speed);
    const chips = $("breakpoints");
    chips.textContent = "";
    for (const act of s.breakpoints || []) {
      const c = el("span", "chip", act + " ✕");
      c.title = "clear this breakpoint";
      c.onclick = () => send({ kind: "clear-breakpoint", act });
      chips.append(c);
    }
  } else if (s.mode === "replay") {
    $("replay-controls").hidden = false;
    const slider = $("slider");
    slider.max = s.end;
    if (!slider.dataset.moved) { slider.value = s.end; $("slider-time").textContent = "at " + Number(s.end).toFixed(1) + " s"; }
  }
  const v = $("verdict");
  if (s.verdict) {
    v.hidden = false;
    v.className = s.verdict.passed ? "passed" : "failed";
    v.textContent = (s.verdict.passed ? "PASSED" : "FAILED") +
      (s.verdict.differences.length ? ": " + s.verdict.differences.join("; ") : "");
  }
}

// -- applying changes --------------------------------------------------------------------

const APPLY = {
  "time": (t) => clock(t),
  "agent": agent, "task": task, "config": config, "task-end": taskEnd,
  "node": node, "state": nodeState, "cut": cut, "item": item, "item-end": itemEnd,
  "goal": goal, "fact": fact, "line": line, "question": question, "question-end": questionEnd,
};

function reset() {
  for (const id of ["agents", "tree", "lines", "facts"]) $(id).textContent = "";
  $("agenda").tBodies[0].textContent = "";
  $("timeline").textContent = "";
  $("timeline").setAttribute("height", 40);
  for (const q of st.questions.values()) q.remove();
  for (const m of ["agents", "tasks", "nodes", "items", "lanes", "goals", "facts", "questions"]) st[m].clear();
  st.open.clear();
  noneShown();
  for (const f of HOOKS.reset) f();
}

function receive(message) {
  switch (message.type) {
    case "hello":
      st.mode = message.mode;
      $("title").textContent = message.title;
      document.title = message.title + " — shary console";
      break;
    case "scheme":
      st.svgs[message.name] = message.svg;
      for (const t of st.tasks.values()) if (t.scheme === message.name) drawInto(t);
      for (const f of HOOKS.scheme) f(message.name);
      break;
    case "changes":
      if (message.reset) reset();
      for (const c of message.changes) APPLY[c[0]](...c.slice(1));
      st.applied += message.changes.length;
      break;
    case "status":
      status(message.status);
      for (const f of HOOKS.status) f(message.status);
      break;
    case "reply": {
      const r = $("reply");
      r.hidden = message.ok;
      r.className = message.ok ? "" : "error";
      r.textContent = message.ok ? "" : "refused: " + message.error;
      break;
    }
  }
  if (bench && message.sent && message.type === "changes") st.latencies.push(performance.timeOrigin + performance.now() - message.sent);
}

function connect() {
  const ws = new WebSocket((location.protocol === "https:" ? "wss://" : "ws://") + location.host + "/ws");
  st.ws = ws;
  ws.onmessage = (e) => receive(JSON.parse(e.data));
  ws.onclose = () => { $("status").textContent = "disconnected"; $("status").className = "pill error"; };
}

$("pause").onclick = () => send({ kind: "pause" });
$("resume").onclick = () => send({ kind: "resume" });
$("step").onclick = () => send({ kind: "step" });
$("speed").onchange = () => send({ kind: "speed", value: Number($("speed").value) });
$("bp-add").onclick = () => { const act = $("bp-act").value.trim(); if (act) send({ kind: "breakpoint", act }); };
let seekDue = null;
$("slider").oninput = () => {
  const slider = $("slider");
  slider.dataset.moved = "1";
  $("slider-time").textContent = "at " + Number(slider.value).toFixed(1) + " s";
  if (seekDue === null) seekDue = setTimeout(() => { seekDue = null; send({ kind: "seek", time: Number(slider.value) }); }, 30);
};
document.addEventListener("DOMContentLoaded", connect);  // after the page's other scripts (plan.js) are in
