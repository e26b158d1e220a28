// The shared plan on the console page (JAHRVIS): applies the changes that
// shary/console/planview.py documents (plan, plan-state, plan-chose, plan-status,
// head, says, recognized), in place, through console.js's APPLY and HOOKS.
// Text goes in through textContent only; the one diagram is the server's dot SVG.
"use strict";

const PLAN_SCHEME = "shared-plan-task";
const PLAN_STATES = ["PLANNED", "TODO", "ONGOING", "EXECUTED", "SUSPENDED", "UNPLANNED",
  "NOT_STARTING", "NOT_FINISHED", "NOT_SEEN"];
const DUE = new Set(["TODO", "ONGOING", "NOT_STARTING", "NOT_FINISHED"]);
const MAX_RECOGNIZED = 40;

const pl = { built: false, plans: new Map(), rows: new Map(), focus: null, pinned: false,
  marks: null, showAll: false };
st.plan = pl;  // read by the browser tests

function planPanel() {
  // the panel's parts, built when the first plan comes
  if (pl.built) return;
  pl.built = true;
  const p = $("plan-panel");
  p.textContent = "";
  const h = el("h2", null, "Shared plan ");
  pl.statusEl = el("small");
  h.append(pl.statusEl);
  pl.robotEl = el("div", "plan-robot");
  pl.headEl = el("span", "head", "");
  pl.saysEl = el("span", "says", "");
  pl.robotEl.append(pl.headEl, pl.saysEl);
  const controls = el("div", "plan-controls");
  const all = el("input");
  all.type = "checkbox"; all.id = "plan-all";
  all.onchange = () => { pl.showAll = all.checked; for (const p of pl.plans.values()) shown(p); };
  const label = el("label", null, " show the branches not taken and the turn markers");
  label.prepend(all);
  controls.append(label);
  if (st.mode === "live") controls.append(stateBreakControls());
  const body = el("div", "plan-body");
  pl.tables = el("div", "plan-tables");
  const side = el("div", "plan-side");
  pl.focusEl = el("div", "plan-focus", "click a task to follow it; otherwise the latest change is shown");
  pl.diagram = el("div", "plan-diagram");
  pl.recEl = el("div", "recognized");
  side.append(el("h3", null, "Its state in each view (" + PLAN_SCHEME + ")"), pl.focusEl,
    pl.diagram, el("h3", null, "Recognized human actions"), pl.recEl);
  body.append(pl.tables, side);
  p.append(h, pl.robotEl, controls, body);
  p.hidden = false;
  // the plan takes the first screen's middle; the facts and lines go below it
  document.body.classList.add("has-plan");
  $("below").append($("more"));
  planDiagram();
}

function stateBreakControls() {
  const box = el("span", "plan-break", " break when a task goes ");
  const state = el("select"); state.id = "bp-state";
  for (const s of PLAN_STATES) { const o = el("option", null, s); o.value = s; state.append(o); }
  state.value = "NOT_SEEN";
  const view = el("select"); view.id = "bp-view";
  const any = el("option", null, "any view"); any.value = ""; view.append(any);
  pl.viewSelect = view;
  const set = el("button", null, "Set"); set.id = "bp-state-add";
  set.onclick = () => {
    const m = { kind: "breakpoint", state: state.value };
    if (view.value) m.agent = view.value;
    send(m);
  };
  pl.chips = el("span", "chips");
  box.append(state, " in ", view, " ", set, pl.chips);
  return box;
}

function planHead(views) {
  const tr = el("tr");
  tr.append(el("th", null, "task"), el("th", null, "agent"));
  views.forEach((v, i) => tr.append(el("th", "view", i ? v + " (estimated by " + views[0] + ")" : v + " (robot)")));
  if (st.mode === "live") tr.append(el("th", null, "operator"));
  const thead = el("thead"); thead.append(tr);
  return thead;
}

function plan(prefix, root, scheme, problem, views, rows) {
  planPanel();
  for (const old of pl.plans.values()) old.box.open = false;
  const box = el("details", "plan");
  box.open = true;
  box.dataset.prefix = prefix;
  const summary = el("summary", null, problem + " · " + prefix + " (tree node " + root + ") ");
  const state = el("span", "plan-state", "started");
  summary.append(state);
  const table = el("table", "plan-table");
  table.append(planHead(views));
  const body = el("tbody");
  const p = { box, state, views, rows: new Map(), open: new Set([""]), body };
  for (const [task, label, agent, kind, branch, opens, depth, decision] of rows) {
    const tr = el("tr", "k-" + kind + (opens ? " option" : ""));
    tr.dataset.task = task;
    const name = el("td", "label");
    name.style.paddingLeft = (4 + depth * 14) + "px";
    if (opens) name.append(el("span", "decision", "◇ " + decision + " "));
    name.append(el("span", null, label));
    name.title = task;
    tr.append(name, el("td", "agent", agent));
    const cells = new Map();
    for (const v of views) { const c = el("td", "ps PLANNED", "PLANNED"); cells.set(v, c); tr.append(c); }
    let act = null;
    if (st.mode === "live") {
      const td = el("td");
      if (kind === "action" && views.slice(1).includes(agent)) {
        act = el("button", "human-did", "done by " + agent);
        act.title = "tell the robot that " + agent + " did this (logged with your name)";
        act.onclick = () => send({ kind: "human-action", agent, plan_task: task });
        act.hidden = true;
        td.append(act);
      }
      tr.append(td);
    }
    tr.onclick = (e) => { if (e.target.tagName !== "BUTTON") { pl.pinned = pl.focus !== task || !pl.pinned; planFocus(task); } };
    const row = { tr, plan: p, label, agent, kind, branch, cells, act, states: new Map() };
    p.rows.set(task, row);
    pl.rows.set(task, row);
    body.append(tr);
  }
  table.append(body);
  box.append(summary, table);
  pl.tables.prepend(box);
  pl.plans.set(prefix, p);
  if (pl.viewSelect) {
    for (const v of views) {
      if (![...pl.viewSelect.options].some((o) => o.value === v)) {
        const o = el("option", null, v); o.value = v; pl.viewSelect.append(o);
      }
    }
  }
  shown(p);
}

function shown(p) {
  // a row shows when its branch is open (the trunk, a chosen option's), turn markers aside
  for (const row of p.rows.values()) {
    row.tr.hidden = !pl.showAll && (!p.open.has(row.branch) || row.kind !== "action");
  }
}

function planState(task, view, state) {
  const row = pl.rows.get(task);
  if (!row) return;
  const cell = row.cells.get(view);
  if (cell) { cell.className = "ps " + state; setText(cell, state); }
  row.states.set(view, state);
  if (view === row.plan.views[0]) {
    row.tr.dataset.state = state;
    if (row.act) row.act.hidden = !DUE.has(state);
  }
  if (!pl.pinned) planFocus(task);
  else if (pl.focus === task) planFocus(task);
}

function planChose(prefix, decision, task) {
  const p = pl.plans.get(prefix);
  const row = pl.rows.get(task);
  if (!p || !row) return;
  p.open.add(task);
  row.tr.classList.add("chosen");
  shown(p);
}

function planStatus(prefix, state, text) {
  const p = pl.plans.get(prefix);
  if (!p) return;
  setText(p.state, state + (text ? " (" + text + ")" : ""));
  p.state.className = "plan-state " + state;
  if (pl.statusEl && state !== "replaced") setText(pl.statusEl, "(" + prefix + ": " + state + ")");
}

function head(agent, target) {
  planPanel();
  setText(pl.headEl, agent + " looks at " + target);
}

function says(agent, text) {
  planPanel();
  setText(pl.saysEl, agent + " says “" + text + "”");
}

function recognized(id, t, agent, action, params, state) {
  planPanel();
  const d = el("div", "rec " + state);
  d.append(el("span", "t", t.toFixed(1) + " s"), el("span", "who", agent),
    el("span", "what", action + " " + params), el("span", "rstate", state));
  pl.recEl.prepend(d);
  st.now.set(agent, { t, text: action + " " + params + " (" + state + ")" });  // the story line
  nowShown();
  while (pl.recEl.childElementCount > MAX_RECOGNIZED) pl.recEl.lastChild.remove();
}

// -- the task-state diagram: drawn once, recoloured for the task in focus ------------

function schemeState(state) { return state.toLowerCase().replace(/_/g, "-"); }

function planDiagram() {
  const svg = st.svgs[PLAN_SCHEME];
  if (!svg || pl.marks || !pl.diagram) return;
  pl.diagram.innerHTML = svg;
  fit(pl.diagram);
  pl.marks = new Map();
  for (const g of pl.diagram.querySelectorAll("g[data-state]")) pl.marks.set(g.dataset.state, g);
  if (pl.focus) planFocus(pl.focus);
}

function planFocus(task) {
  const row = pl.rows.get(task);
  if (!row) return;
  const before = pl.focus && pl.rows.get(pl.focus);
  if (before) before.tr.classList.remove("focus");
  row.tr.classList.add("focus");
  pl.focus = task;
  const views = row.plan.views;
  setText(pl.focusEl, row.label + (pl.pinned ? " (followed; click again to release)" : "") + ": " +
    views.map((v) => v + " " + (row.states.get(v) || "PLANNED")).join(", "));
  if (!pl.marks) return;
  for (const g of pl.marks.values()) g.classList.remove("active", "est");
  views.forEach((v, i) => {
    const g = pl.marks.get(schemeState(row.states.get(v) || "PLANNED"));
    if (g) g.classList.add(i ? "est" : "active");
  });
  inView(pl.diagram, [pl.marks.get(schemeState(row.states.get(views[0]) || "PLANNED"))].filter(Boolean));
}

// -- hooks into console.js ------------------------------------------------------------

Object.assign(APPLY, {
  "plan": plan, "plan-state": planState, "plan-chose": planChose, "plan-status": planStatus,
  "head": head, "says": says, "recognized": recognized,
});
HOOKS.scheme.push((name) => { if (name === PLAN_SCHEME) planDiagram(); });
HOOKS.reset.push(() => {
  $("plan-panel").textContent = "";
  $("plan-panel").hidden = true;
  document.body.classList.remove("has-plan");
  document.querySelector("main").append($("more"));
  Object.assign(pl, { built: false, focus: null, marks: null, viewSelect: null, chips: null });
  pl.plans.clear(); pl.rows.clear();
});
HOOKS.status.push((s) => {
  if (!pl.chips) return;
  pl.chips.textContent = "";
  for (const [state, agent] of s.plan_breakpoints || []) {
    const c = el("span", "chip", state + (agent ? " in " + agent : "") + " ✕");
    c.title = "clear this breakpoint";
    c.onclick = () => { const m = { kind: "clear-breakpoint", state }; if (agent) m.agent = agent; send(m); };
    pl.chips.append(c);
  }
});
