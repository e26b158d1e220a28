// The team's part of the shary console: an HRI/OS team's members, the Task Manager's
// table, the Resource Manager's delegations, the Interaction Manager's questions, and the
// operator's team actions.  The change kinds are documented in shary/console/teamview.py.
// Loaded after console.js: its kinds go into console.js's APPLY, its reset into HOOKS.
// Text goes in through textContent only.
"use strict";

(() => {
  const tm = {
    members: new Map(), tasks: new Map(), questions: new Map(), robots: new Map(),
    people: new Map(),
  };
  window.sharyTeam = tm;  // read by the browser tests

  const live = () => window.shary.mode === "live";
  const humans = () => [...tm.members].filter(([, m]) => m.kind === "human").map(([n]) => n);

  function shown() {
    if (!$("team-panel").hidden) return;
    $("team-panel").hidden = false;
    document.body.classList.add("team");
  }

  // -- members -------------------------------------------------------------------------

  function member(name, kind, about) {
    shown();
    const a = window.shary.agents.get(name);
    let m = tm.members.get(name);
    if (!m) {
      const box = el("div", "team-agent " + kind);
      box.dataset.agent = name;
      const facts = el("div", "team-facts");
      box.append(facts);
      if (a) a.box.insertBefore(box, a.tasks);
      m = { box, facts, kind, about };
      tm.members.set(name, m);
      if (kind === "robot") robotBlock(name, m);
      if (kind === "human") personBlock(name, m);
    }
    m.kind = kind; m.about = about;
    if (own(name)) elsewhere(name, m);
    facts(name);
    for (const r of tm.robots.values()) people(r);
  }

  // A member in a process of its own (a distributed run): what only that process may do
  // (a person's answer, a robot's controls) is not offered here; the server would refuse it.
  function own(name) {
    const m = tm.members.get(name);
    return Boolean(m && m.about && m.about.process === "own");
  }

  function elsewhere(name, m) {
    const r = tm.robots.get(name);
    if (r) { r.box.remove(); tm.robots.delete(name); }
    const a = window.shary.agents.get(name);
    if (a) a.box.classList.add("own-process");  // its SHARY tasks' cancel buttons go too
    if (m.kind === "robot" && live() && !m.box.querySelector(".elsewhere")) {
      m.box.append(el("div", "robot-controls elsewhere", name + " runs in its own process: " +
        "control, teleoperation and breakpoints come from a person's own interface there"));
    }
  }

  function facts(name) {
    const m = tm.members.get(name);
    if (!m) return;
    const about = m.about || {};
    const parts = [];
    if (about.skills && about.skills.length) parts.push("skills: " + about.skills.join(", "));
    if (about.services && about.services.length) parts.push("services: " + about.services.join(", "));
    if (about.remote) parts.push("remote");
    if (about.process === "own") parts.push("own process");
    parts.push("holds: " + (m.holds || "—"));
    if (m.kind === "robot") {
      parts.push("mode: " + (m.mode === "user" ? "user (driven by " + m.by + ")" : "system"));
      if (m.assoc) parts.push("associated with " + m.assoc);
      if (m.brk && m.brk !== "cleared") parts.push("breakpoint: " + m.brk + (m.before ? " before " + m.before : ""));
    }
    setText(m.facts, parts.join(" · "));
  }

  function robotBlock(name, m) {
    if (!live() || own(name)) return;
    const r = { name, box: el("div", "robot-controls") };
    r.person = el("select", "person");
    r.person.title = "the person the operator acts for";
    r.take = button("take control", "take control of " + name + " for the person", () =>
      send({ kind: "take-control", agent: name, person: r.person.value }));
    r.back = button("hand back", "give " + name + " its autonomy back", () =>
      send({ kind: "hand-back", agent: name, person: r.person.value }));
    r.brk = button("breakpoint", "stop " + name + " before its next atomic task", () =>
      send({ kind: r.brk.dataset.on ? "clear-robot-breakpoint" : "robot-breakpoint", agent: name }));
    r.atomic = el("select", "atomic");
    r.args = el("span", "args");
    r.go = button("teleoperate", "send this atomic task to " + name, () => {
      const args = {};
      for (const input of r.args.querySelectorAll("input")) args[input.name] = input.value;
      send({ kind: "teleoperate", agent: name, person: r.person.value, atomic: r.atomic.value, args });
    });
    r.atomic.onchange = () => params(r, m);
    r.box.append(el("span", null, "for "), r.person, r.take, r.back, r.brk, el("br"),
      r.atomic, r.args, r.go);
    m.box.append(r.box);
    tm.robots.set(name, r);
    people(r);
    controls(name);
  }

  function button(text, title, onclick) {
    const b = el("button", "team-act", text);
    b.title = title; b.onclick = onclick;
    return b;
  }

  function people(r) {
    const now = humans();
    if ([...r.person.options].map((o) => o.value).join() === now.join()) return;
    const chosen = r.person.value;
    r.person.textContent = "";
    for (const h of now) r.person.append(new Option(h, h));
    if (now.includes(chosen)) r.person.value = chosen;
  }

  function params(r, m) {
    const atomic = (m.about && m.about.atomic) || {};
    if (r.atomic.options.length !== Object.keys(atomic).length) {
      r.atomic.textContent = "";
      for (const a of Object.keys(atomic).sort()) r.atomic.append(new Option(a, a));
    }
    r.args.textContent = "";
    for (const p of atomic[r.atomic.value] || []) {
      const input = el("input");
      input.name = p; input.placeholder = p; input.size = 10;
      r.args.append(input);
    }
  }

  function controls(name) {
    const r = tm.robots.get(name), m = tm.members.get(name);
    if (!r || !m) return;
    if (!r.atomic.options.length) params(r, m);
    const driven = m.mode === "user";
    r.take.disabled = driven;
    r.back.disabled = !driven;
    r.go.disabled = !driven;
    r.atomic.disabled = !driven;
    if (driven && m.by) r.person.value = m.by;
    const on = m.brk && m.brk !== "cleared";
    setText(r.brk, on ? "clear breakpoint" : "breakpoint");
    if (on) r.brk.dataset.on = "1"; else delete r.brk.dataset.on;
  }

  function personBlock(name, m) {
    m.open = el("div", "person-questions");
    m.answers = el("ul", "person-answers");
    m.box.append(m.open, m.answers);
    tm.people.set(name, m);
  }

  function holds(agent, task) {
    const m = tm.members.get(agent);
    if (m) { m.holds = task; facts(agent); }
  }

  function control(robot, mode, by) {
    const m = tm.members.get(robot);
    if (m) { m.mode = mode; m.by = by; facts(robot); controls(robot); }
  }

  function assoc(robot, who) {
    const m = tm.members.get(robot);
    if (m) { m.assoc = who; facts(robot); }
  }

  function robotBreak(robot, state, before) {
    const m = tm.members.get(robot);
    if (m) { m.brk = state; m.before = before; facts(robot); controls(robot); }
  }

  // -- the Task Manager --------------------------------------------------------------------

  function teamTask(name, t) {
    shown();
    let row = tm.tasks.get(name);
    if (!row) {
      row = el("tr");
      row.dataset.task = name;
      for (let i = 0; i < 6; i++) row.append(el("td"));
      $("team-tasks").tBodies[0].append(row);
      tm.tasks.set(name, row);
    }
    const c = row.children;
    setText(c[0], name); setText(c[1], t.skill || "");
    setText(c[2], t.state); c[2].className = "tstate " + t.state;
    setText(c[3], t.agent || "");
    c[4].textContent = "#" + t.attempt + (t.respawns ? " · respawned ×" + t.respawns : "") +
      (t.reason ? " · " + t.reason : "");
    c[5].textContent = "";
    if (live() && (t.state === "running" || t.state === "offered")) {
      c[5].append(button("cancel", "cancel this team task (it fails for the Task Manager)",
        () => send({ kind: "cancel-team-task", team_task: name })));
    }
  }

  // -- the Resource Manager -------------------------------------------------------------------

  function delegation(t, subject, need, skill, chosen, ranking) {
    shown();
    const box = el("div", "delegation");
    box.append(el("div", "dhead", t.toFixed(1) + " s  " + need + " " + subject +
      (skill ? " (" + skill + ")" : "") + " → " + (chosen || "nobody")));
    const total = ranking.reduce((s, r) => s + r.score, 0) || 1;
    for (const r of ranking) {
      const row = el("div", "rank" + (r.agent === chosen ? " chosen" : ""));
      const bar = el("span", "share");
      bar.style.width = Math.round(100 * r.score / total) + "px";
      row.append(el("span", "rname", r.agent), bar,
        el("span", "rscore", r.score.toFixed(3) + " (" + Math.round(100 * r.score / total) + "%)"));
      row.title = Object.entries(r.by || {}).map(([k, v]) => k + " " + v).join(", ");
      box.append(row);
    }
    const list = $("delegations");
    list.prepend(box);
    while (list.childElementCount > 40) list.lastChild.remove();
  }

  // -- the Interaction Manager ------------------------------------------------------------------

  function tq(qid, q) {
    shown();
    let entry = tm.questions.get(qid);
    if (!entry) {
      entry = { row: el("tr"), q };
      entry.row.dataset.question = qid;
      for (let i = 0; i < 5; i++) entry.row.append(el("td"));
      $("team-questions").tBodies[0].append(entry.row);
      tm.questions.set(qid, entry);
    }
    entry.q = q;
    const c = entry.row.children;
    setText(c[0], qid); setText(c[1], q.asker + ": “" + q.text + "”");
    setText(c[2], "priority " + q.priority); setText(c[3], "→ " + (q.holder || "nobody yet"));
    countdown(entry);
    personQuestion(qid, entry);
  }

  function countdown(entry) {
    const cell = entry.row.children[4];
    if (entry.answer) return;
    if (entry.q.expires === null || entry.q.expires === undefined) { setText(cell, "no expiry"); return; }
    const left = entry.q.expires - window.shary.time;
    setText(cell, left > 0 ? "expires in " + left.toFixed(1) + " s" : "expiring");
    cell.className = left < 5 ? "urgent" : "";
  }

  // an open question goes in the Questions panel, for its holder, and in the holder's block
  function personQuestion(qid, entry) {
    for (const b of [entry.box, entry.mine]) if (b) b.remove();
    entry.box = entry.mine = null;
    const q = entry.q, m = tm.people.get(q.holder);
    if (!m || entry.answer) return noneOpen();
    entry.mine = el("div", "asked", "asked by " + q.asker + " (" + qid + "): " + q.text);
    m.open.append(entry.mine);
    const box = el("div", "question team-question");
    box.dataset.question = qid;
    box.dataset.agent = q.holder;
    box.append(el("div", null, q.asker + " asks " + q.holder + " (" + qid +
      (q.task ? ", " + q.task : "") + ", priority " + q.priority + "): " + q.text));
    if (live() && own(q.holder)) {
      box.append(el("div", "elsewhere", q.holder + " answers from their own interface " +
        "(shary agent " + q.holder + ")"));
    } else if (live()) {
      const answer = (text) => send({ kind: "answer", question: qid, agent: q.holder, text });
      const row = el("div", null, "answer for " + q.holder + ": ");
      const options = q.type === "yes-no" ? ["yes", "no"] : q.choices;
      if (q.type === "free-text" || !options.length) {
        const input = el("input");
        input.size = 24; input.placeholder = "your answer";
        row.append(input, button("send", "answer " + qid, () => { if (input.value.trim()) answer(input.value.trim()); }));
      } else {
        for (const o of options) {
          const b = button(o, "answer " + o + " for " + q.holder, () => answer(o));
          b.dataset.text = o;
          row.append(b);
        }
      }
      box.append(row);
    }
    if (q.image) {  // below the answers, which stay in view whatever the picture's size
      const img = el("img");
      img.src = "/run/" + encodeURIComponent(q.image);
      img.alt = "the picture " + q.asker + " attached";
      box.append(img);
    }
    $("questions").append(box);
    entry.box = box;
    noneOpen();
  }

  function noneOpen() {
    const none = $("questions").querySelector(".none");
    if (none) none.hidden = $("questions").querySelector(".question") !== null;
  }

  function tqEnd(qid, answer) {
    const entry = tm.questions.get(qid);
    if (!entry) return;
    entry.answer = answer;
    for (const b of [entry.box, entry.mine]) if (b) b.remove();
    entry.box = entry.mine = null;
    noneOpen();
    entry.row.classList.add("answered");
    setText(entry.row.children[4], (answer.expired ? "expired → " : "answered ") +
      JSON.stringify(answer.value) + (answer.by ? " by " + answer.by : ""));
    entry.row.children[4].className = "";
    if (answer.by && !answer.expired) {  // the story line: what the person did last
      const said = "answered " + JSON.stringify(answer.value) + " (" + qid + ")";
      window.shary.now.set(answer.by, { t: answer.t, text: said });
      nowShown();
    }
    const m = tm.people.get(answer.by) || tm.people.get(entry.q.holder);
    if (m) {
      m.answers.append(el("li", null, answer.t.toFixed(1) + " s  " + entry.q.text + " → " +
        JSON.stringify(answer.value) + (answer.expired ? " (expired)" : "")));
    }
  }

  function reset() {
    for (const id of ["team-tasks", "team-questions"]) $(id).tBodies[0].textContent = "";
    $("delegations").textContent = "";
    for (const k of Object.keys(tm)) tm[k].clear();
  }

  setInterval(() => { for (const e of tm.questions.values()) countdown(e); }, 250);

  Object.assign(APPLY, {
    "member": member, "team-task": teamTask, "holds": holds, "delegation": delegation,
    "tq": tq, "tq-end": tqEnd, "control": control, "assoc": assoc, "robot-break": robotBreak,
  });
  HOOKS.reset.push(reset);
})();
