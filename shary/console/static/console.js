// The shary console page: applies the server's changes to the DOM in place.
// Every change kind is documented in shary/console/view.py; text always goes in
// through textContent (never parsed as HTML); the only markup inserted is the
// scheme diagrams the server drew with dot.
"use strict";

const $ = (id) => document.getElementById(id);
const SVGNS = "http://www.w3.org/2000/svg";
const MAX_LINES = 300, MAX_FACT_ROWS = 40;
const bench = location.search.includes("bench");
const MIN_TEXT_PX = 11;  // the smallest text of a diagram, on screen at the default zoom

const st = {
  ws: null, mode: null, status: {}, svgs: {}, time: 0, nextId: 1,
  agents: new Map(), tasks: new Map(), nodes: new Map(), items: new Map(), open: new Set(),
  lanes: new Map(), goals: new Map(), groups: new Map(), facts: new Map(), questions: new Map(),
  latencies: [], applied: 0, controls: [], now: new Map(), legend: new Set(),
};
window.shary = st;  // read by the browser tests and the benchmark
// what the page's other scripts (plan.js, team.js) hook into: a reset, a scheme drawn, a status
const HOOKS = { reset: [], scheme: [], status: [] };

function el(tag, cls, text) {
  const e = document.createElement(tag);
  if (cls) e.className = cls;
  if (text !== undefined) setText(e, text);
  return e;
}

const HYPHENATED = /(\S+-\S+)/;
function setText(e, text) {
  // a word with a hyphen ("Robonaut-B", "give-object") is kept whole in a nowrap span:
  // the browser would otherwise break the line after its hyphen, mid-name
  const parts = String(text).split(HYPHENATED);
  if (parts.length === 1 || e.tagName === "OPTION") { e.textContent = text; return e; }
  e.textContent = "";
  parts.forEach((part, i) => {
    if (i % 2) { const w = document.createElement("span"); w.className = "nb"; w.textContent = part; e.append(w); }
    else if (part) e.append(part);
  });
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
    setText(a.small, "(" + kind + ")");
    if (st.mode === "live") agentButtons(a, name, kind);
    nowShown();
  }
  return a;
}

function agentButtons(a, name, kind) {
  // a person's acts sent on their behalf; a robot's control authority only where the run
  // has a port for it (the hello's controls): a simulated SHARY robot has none
  const acts = kind === "human" ? ["H-AGREE", "H-DISAGREE"]
    : ["take-control", "hand-back"].filter((act) => st.controls.includes(act));
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
  a.tasks.prepend(box);  // the newest task first: the act going on now is at the top
  const t = { box, diagram, config, scheme, agent: who, name, active: [], marks: null };
  st.tasks.set(node, t);
  drawInto(t);
}

function drawInto(t) {
  const svg = st.svgs[t.scheme];
  if (!svg || t.marks) return;
  t.diagram.innerHTML = svg;
  fit(t.diagram);
  t.marks = new Map();
  for (const g of t.diagram.querySelectorAll("g[data-state]")) t.marks.set(g.dataset.state, g);
  highlight(t, t.active, []);
}

function fit(box) {
  // a diagram at the scale where its smallest text is MIN_TEXT_PX on screen (the server
  // draws all its labels at one size): every scheme at one scale, so that two agents'
  // schemes compare at a glance; what does not fit its box scrolls there
  const svg = box.querySelector("svg");
  if (!svg) return;
  const sizes = [...svg.querySelectorAll("text")].map((x) => Number(x.getAttribute("font-size")) || 14);
  const units = svg.viewBox.baseVal && svg.viewBox.baseVal.width ? svg.viewBox.baseVal.width
    : svg.width.baseVal.value;
  svg.style.width = (units * MIN_TEXT_PX / Math.min(...sizes, 14)) + "px";
  svg.style.height = "auto";
  svg.style.maxWidth = "none";
}

function highlight(t, now, before) {
  if (!t.marks) return;
  for (const s of before) { const g = t.marks.get(s); if (g) g.classList.remove("active"); }
  for (const s of now) { const g = t.marks.get(s); if (g) g.classList.add("active"); }
  inView(t.diagram, now.map((s) => t.marks.get(s)).filter(Boolean));
}

function inView(box, marks) {
  // the innermost active state (the last entered) in the middle of a diagram too big for
  // its box: what the task does now shows without scrolling by hand
  const g = marks[marks.length - 1];
  if (!g || box.scrollHeight <= box.clientHeight && box.scrollWidth <= box.clientWidth) return;
  const r = g.getBoundingClientRect(), b = box.getBoundingClientRect();
  box.scrollTop += r.top + r.height / 2 - (b.top + b.height / 2);
  box.scrollLeft += r.left + r.width / 2 - (b.left + b.width / 2);
}

function config(node, states) {
  const t = st.tasks.get(node);
  if (!t) return;
  highlight(t, states, t.active);
  t.active = states;
  setText(t.config, "active: " + (states.join(", ") || "—"));
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
  setText(t.config, "ended: " + outcome);
  t.box.parentNode.append(t.box);  // an ended task goes below the running ones
  highlight(t, t.active, []);  // moved, its box scrolled back to the top: its end in view
}

// -- the task tree ---------------------------------------------------------------

function node(id, parent, kind, name, state) {
  const li = el("li", "k-" + kind + " s-" + state);
  li.id = "t-" + id;
  const label = el("span", null, name);
  label.title = id + " (" + kind + ")";
  li.append(label);
  const p = parent && st.nodes.get(parent);
  if (p && !p.ul) { p.ul = el("ul"); p.li.append(p.ul); }
  (p ? p.ul : treeRoot(id)).append(li);
  st.nodes.set(id, { li, ul: null, parent: p ? parent : null, kind });
}

function treeRoot(id) {
  // a team's robots name their nodes "ROBOT/n1": each robot's tasks go under its name
  const slash = id.indexOf("/");
  if (slash < 0) return $("tree");
  const robot = id.slice(0, slash);
  let ul = st.groups.get(robot);
  if (!ul) {
    const li = el("li", "robot-group");
    li.dataset.agent = robot;
    ul = el("ul");
    li.append(el("b", null, robot), ul);
    $("tree").append(li);
    st.groups.set(robot, ul);
  }
  return ul;
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
  setText(cells[0], typeof id === "number" ? "#" + id : id); setText(cells[1], name + (args ? " (" + args + ")" : ""));
  setText(cells[2], "priority " + priority); setText(cells[3], state);
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
  if (kind === "act" || kind === "received") { st.now.set(who, { t, text }); nowShown(); }
}

function nowShown() {
  // the story's first line: each robot's latest act and its actions under way, each
  // person's latest act (the lines and the timeline's open items say it)
  const box = $("now");
  box.textContent = "";
  const over = st.status.state === "ended" || st.status.state === "error";
  box.append(el("b", null, over ? "At the end " : "Now "));
  for (const [who, a] of st.agents) {
    if (a.kind !== "robot" && a.kind !== "human") continue;
    const n = st.now.get(who);
    const part = el("span", a.kind);
    part.dataset.agent = who;
    part.append(el("b", null, who + ": "));
    if (a.kind === "robot") {
      const doing = [...st.open].map((id) => st.items.get(id))
        .filter((it) => it.lane === who && it.cls === "action").map((it) => it.label);
      part.append(el("span", "what", n ? n.text : "no act yet"));
      if (n) part.append(el("span", "since", " since " + n.t.toFixed(1) + " s"));
      if (doing.length && !over) part.append(el("span", "doing", " · " + doing.join(", ")));
    } else {
      part.append(el("span", "what", n ? n.text : "no act yet"));
      if (n) part.append(el("span", "since", " at " + n.t.toFixed(1) + " s"));
    }
    box.append(part);
  }
}

function question(node, act, people, answers, image) {
  questionEnd(node);
  const box = el("div", "question");
  box.dataset.node = node;
  const t = st.tasks.get(node);
  box.append(el("div", null, (t ? t.agent : "The robot") + " asks (" + act + ", task " +
    (t ? t.name : "?") + ", " + node + "). Answer for:"));
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
  if (image) {  // below the answers, which stay in view whatever the picture's size
    const img = el("img");
    img.src = "/run/" + encodeURIComponent(image);
    img.alt = "what the robot saw when it asked";
    box.append(img);
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
  setText(pill, s.state + (s.why ? " (" + s.why + ")" : ""));
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
    if (!slider.dataset.moved) { slider.value = s.end; setText($("slider-time"), "at " + Number(s.end).toFixed(1) + " s"); }
  }
  const v = $("verdict");
  if (s.verdict) {
    v.hidden = false;
    v.className = s.verdict.passed ? "passed" : "failed";
    v.textContent = (s.verdict.passed ? "PASSED" : "FAILED") +
      (s.verdict.differences.length ? ": " + s.verdict.differences.join("; ") : "");
    v.title = v.textContent;
  }
  nowShown();
}

// -- applying changes --------------------------------------------------------------------

const APPLY = {
  "time": (t) => clock(t),
  "agent": agent, "task": task, "config": config, "task-end": taskEnd,
  "node": node, "state": nodeState, "cut": cut,
  "goal": goal, "fact": fact, "line": line, "question": question, "question-end": questionEnd,
};

function reset() {
  for (const id of ["agents", "tree", "lines", "facts"]) $(id).textContent = "";
  $("agenda").tBodies[0].textContent = "";
  $("timeline").textContent = "";
  $("timeline").setAttribute("height", 40);
  for (const q of st.questions.values()) q.remove();
  for (const m of ["agents", "tasks", "nodes", "items", "lanes", "goals", "facts", "questions",
    "groups", "now", "legend"]) st[m].clear();
  st.open.clear();
  $("legend").textContent = "";
  axis();
  noneShown();
  nowShown();
  for (const f of HOOKS.reset) f();
}

function receive(message) {
  switch (message.type) {
    case "hello":
      st.mode = message.mode;
      st.controls = message.controls || [];
      setText($("title"), message.title);
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
      setText(r, message.ok ? "" : "refused: " + message.error);
      break;
    }
  }
  if (bench && message.sent && message.type === "changes") st.latencies.push(performance.timeOrigin + performance.now() - message.sent);
}

function connect() {
  const ws = new WebSocket((location.protocol === "https:" ? "wss://" : "ws://") + location.host + "/ws");
  st.ws = ws;
  ws.onmessage = (e) => receive(JSON.parse(e.data));
  ws.onclose = () => { setText($("status"), "disconnected"); $("status").className = "pill error"; };
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
  setText($("slider-time"), "at " + Number(slider.value).toFixed(1) + " s");
  if (seekDue === null) seekDue = setTimeout(() => { seekDue = null; send({ kind: "seek", time: Number(slider.value) }); }, 30);
};
document.addEventListener("DOMContentLoaded", connect);  // after the page's other scripts (plan.js) are in
