"""The timeline SVG of a run: lanes per agent, acts and actions where and when they happened."""

from __future__ import annotations

import math
import xml.etree.ElementTree as ET
from pathlib import Path

import pytest
from scripted import World
from test_planning import fig10_world

from shary.log.contextlog import ContextLog, LogEvent, read_events
from shary.log.timeline import render_timeline, write_timeline

SVG = "{http://www.w3.org/2000/svg}"


def parse(svg: str) -> ET.Element:
    return ET.fromstring(svg)


def groups(root: ET.Element, *classes: str) -> list[ET.Element]:
    """The <g> elements whose class holds all of ``classes``."""
    return [g for g in root.iter(f"{SVG}g") if set(classes) <= set(g.get("class", "").split())]


def lane_agents(root: ET.Element) -> list[str]:
    return [g.get("data-agent", "") for g in groups(root, "lane")]


def time_to_x(root: ET.Element):
    """The x of a time, read back from the labelled ticks of the axis."""
    ticks = [(float(t.text.removesuffix(" s")), float(t.get("x")))
             for t in root.iter(f"{SVG}text") if t.get("class") == "tick"]
    (t1, x1), (t2, x2) = ticks[0], ticks[1]
    return lambda t: x1 + (t - t1) * (x2 - x1) / (t2 - t1)


def act_bars(root: ET.Element) -> list[ET.Element]:
    """The acts drawn as bars (those an agent received are diamonds)."""
    return [g for g in groups(root, "act") if "received" not in g.get("class")]


def bar(g: ET.Element) -> ET.Element:
    return next(r for r in g.iter(f"{SVG}rect") if r.get("class") == "bar")


def tooltip(g: ET.Element) -> str:
    return g.find(f"{SVG}title").text


@pytest.fixture
def distracted(tmp_path: Path) -> Path:
    """give-object: Alice agrees, looks away for 5 s during the arm motion, looks back."""
    path = tmp_path / "distracted.sqlite"
    with ContextLog(path) as log:
        World(log=log).distracted_give()
    return path


@pytest.fixture
def clean_up(tmp_path: Path) -> Path:
    """Fig. 10: Jido's pick fails (out of reach); in the new plan Jido asks Alice for help,
    she agrees and hands the bottle over, and Jido dumps it (as in test_planning)."""
    path = tmp_path / "clean-up.sqlite"
    with ContextLog(path) as log:
        world, _ = fig10_world(log=log)
        run = world.sup.start_task("clean-up", {"object": "yellow-bottle"})
        world.run(120)
        assert run.outcome == "done"
    return path


def event(seq: int, time: float, kind: str, task: str | None = None,
          agent: str | None = None, **data) -> LogEvent:
    return LogEvent(seq, time, kind, task, agent, data)


def test_one_lane_per_agent_robot_first(distracted: Path, clean_up: Path):
    assert lane_agents(parse(render_timeline(read_events(distracted)))) == ["jido", "alice"]
    root = parse(render_timeline(read_events(clean_up)))
    assert lane_agents(root) == ["jido", "alice"]
    alice = groups(root, "lane")[1]
    assert [g.get("data-act") for g in groups(alice, "received")] == ["H-AGREE"]
    assert not groups(alice, "action")  # everything else in this run is Jido's


def test_the_robot_lane_can_be_named(distracted: Path):
    root = parse(render_timeline(read_events(distracted), robot="alice"))
    assert lane_agents(root) == ["alice", "jido"]


def test_act_bars_span_the_logged_state_times(distracted: Path):
    root = parse(render_timeline(read_events(distracted)))
    x = time_to_x(root)
    acts = {g.get("data-act"): g for g in act_bars(root)}
    expected = {"ASK-TASK": (0.0, 0.0), "REALIZE-TASK": (0.0, 12.5),
                "WAIT-ATTENTION": (2.5, 7.5), "END-TASK": (12.5, 13.5)}
    assert set(acts) == set(expected)
    for act, (start, end) in expected.items():
        g = acts[act]
        assert (float(g.get("data-start")), float(g.get("data-end"))) == (start, end)
        rect = bar(g)
        assert float(rect.get("x")) == pytest.approx(x(start), abs=0.02)
        assert float(rect.get("width")) == pytest.approx(x(end) - x(start), abs=0.03)
    suspended = [r for r in acts["REALIZE-TASK"].iter(f"{SVG}rect")
                 if r.get("class") == "suspended"]
    assert [(float(r.get("data-start")), float(r.get("data-end"))) for r in suspended] == [
        (2.5, 7.5)]  # REALIZE-TASK waits while WAIT-ATTENTION runs
    (jido, alice) = groups(root, "lane")
    assert len(act_bars(jido)) == 4 and not act_bars(alice)


def test_every_act_bar_starts_at_a_logged_act(clean_up: Path):
    events = read_events(clean_up)
    root = parse(render_timeline(events))
    logged = sorted((e.time, e.agent, e.data["act"]) for e in events if e.kind == "act")
    drawn = sorted((float(g.get("data-start")), g.get("data-agent"), g.get("data-act"))
                   for g in act_bars(root))
    assert drawn == logged
    assert all(g.get("data-end") is not None for g in act_bars(root))  # every act ended
    alice = groups(root, "lane")[1]
    (helping,) = act_bars(alice)  # the act Alice performs in the joint task ask-help
    assert (helping.get("data-act"), helping.get("data-start"), helping.get("data-end")) == (
        "REALIZE-TASK", "8.0", "16.0")  # after her glance, "I could not pick …", the question


def test_human_acts_are_diamonds_in_their_lane(distracted: Path):
    root = parse(render_timeline(read_events(distracted)))
    alice = groups(root, "lane")[1]
    (agree,) = groups(alice, "act", "received")
    assert agree.get("data-act") == "H-AGREE" and agree.find(f"{SVG}polygon") is not None


def test_a_failed_action_is_drawn_as_failed(clean_up: Path):
    root = parse(render_timeline(read_events(clean_up)))
    (failed,) = groups(root, "action", "failed")
    assert failed.get("data-agent") == "jido" and failed.get("data-atomic") == "pick"
    assert bar(failed).get("fill") == "#e15759"
    assert "out of reach" in tooltip(failed)
    assert (float(failed.get("data-start")), float(failed.get("data-end"))) == (2.0, 3.0)
    done = groups(root, "action", "done")
    assert done and all(bar(g).get("fill") != "#e15759" for g in done)


def test_cancelled_actions_are_drawn_as_cancelled(distracted: Path):
    root = parse(render_timeline(read_events(distracted)))
    cancelled = groups(root, "action", "cancelled")
    assert sorted((g.get("data-atomic"), float(g.get("data-end"))) for g in cancelled) == [
        ("look-at", 0.0), ("move-arm", 2.5)]
    assert {bar(g).get("fill") for g in cancelled} == {"#d3d3d3"}
    labels = ["".join(g.itertext()) for g in cancelled]
    assert any("move-arm alice" in text for text in labels)


def test_actions_still_running_are_open_ended(tmp_path: Path):
    path = tmp_path / "cut.sqlite"
    with ContextLog(path) as log:
        world = World(log=log)
        world.executor.durations["speak"] = 3.0
        world.give()
        world.run(2.0)  # the question is still being asked when the log stops
    root = parse(render_timeline(read_events(path)))
    (running,) = groups(root, "action", "running")
    assert running.get("data-atomic") == "speak" and running.get("data-end") is None
    assert bar(running).get("fill") == "url(#hatch)"
    assert any(p.get("class") == "open-end" for p in running.iter(f"{SVG}polygon"))
    (ask,) = groups(root, "act")
    assert ask.get("data-act") == "ASK-TASK" and ask.get("data-end") is None


def test_task_lines_mark_top_level_tasks_only(clean_up: Path):
    root = parse(render_timeline(read_events(clean_up)))
    lines = [ln for ln in root.iter(f"{SVG}line") if "task-line" in ln.get("class", "")]
    assert sorted(ln.get("class") for ln in lines) == ["task-line task-end", "task-line task-start"]
    (task,) = groups(root, "task")
    assert "clean-up: done" in "".join(task.itertext())
    plans = groups(root, "plan")
    assert [p.get("data-start") for p in plans] == ["0.0", "3.0"]
    assert "out of reach" in tooltip(plans[1])  # the new plan says why it was needed


def test_attention_row_from_looks_at_facts():
    events = [
        event(1, 0.0, "task-start", "n1", "jido", name="give"),
        event(2, 0.0, "fact-added", None, "alice", s="alice", p="looksAt", o="jido"),
        event(3, 2.0, "fact-removed", None, "alice", s="alice", p="looksAt", o="jido"),
        event(4, 2.0, "fact-added", None, "alice", subject="alice", predicate="looksAt",
              object="tv"),
        event(5, 3.0, "fact-added", None, None, s="bottle", p="isOn", o="table"),
        event(6, 4.0, "task-end", "n1", outcome="done"),
    ]
    root = parse(render_timeline(events))
    assert lane_agents(root) == ["jido", "alice"]
    looks = groups(root, "look")
    assert [(g.get("data-agent"), g.get("data-start"), g.get("data-end")) for g in looks] == [
        ("alice", "0.0", "2.0"), ("alice", "2.0", None)]
    assert "looks at tv" in tooltip(looks[1])


def test_no_attention_row_without_looks_at_facts(distracted: Path):
    root = parse(render_timeline(read_events(distracted)))
    assert not groups(root, "look")
    assert "looks at" not in [t.text for t in root.iter(f"{SVG}text")]


def test_odd_names_are_escaped_and_the_svg_well_formed():
    odd = '<bob & "co">'
    events = [
        event(1, 0.0, "task-start", "t<1>", "r&d", name="give <&>"),
        event(2, 0.0, "enter", "t<1>", state="s&"),
        event(3, 0.0, "act", "t<1>", "r&d", act="ASK-<TASK>"),
        event(4, 0.5, "act-received", None, odd, act="H-&AGREE"),
        event(5, 1.0, "exec-request", "t<1>", odd, atomic="pick&place", request="r<1>",
              args={"object": "a<b\x01"}),
        event(6, 2.0, "exec-result", "t<1>", odd, request="r<1>", status="failed",
              reason="</svg> & more"),
        event(7, 2.0, "exit", "t<1>", state="s&", event="e"),
        event(8, 3.0, "task-end", "t<1>", outcome="done"),
    ]
    title = 'run <1> & "two"\x07'
    root = parse(render_timeline(events, title=title))
    assert root.find(f"{SVG}title").text == 'run <1> & "two"\ufffd'
    assert lane_agents(root) == ["r&d", odd]
    (failed,) = groups(root, "action", "failed")
    assert failed.get("data-atomic") == "pick&place"
    assert "</svg> & more" in tooltip(failed) and "a<b\ufffd" in tooltip(failed)
    (act,) = act_bars(root)
    assert act.get("data-act") == "ASK-<TASK>" and act.get("data-end") == "2.0"
    (agree,) = groups(root, "received")
    assert agree.get("data-act") == "H-&AGREE"


def test_narrow_bars_truncate_labels_and_keep_the_full_text_in_the_tooltip():
    events = [event(1, 0.0, "exec-request", "n1", "jido", atomic="navigate", request="r1",
                    args={"place": "the-far-end-of-the-living-room"}),
              event(2, 0.5, "exec-result", "n1", "jido", request="r1", status="done"),
              event(3, 30.0, "exec-request", "n1", "jido", atomic="speak", request="r2",
                    args={"text": "bye"}),
              event(4, 60.0, "exec-result", "n1", "jido", request="r2", status="done")]
    root = parse(render_timeline(events, px_per_second=100))
    navigate = next(g for g in groups(root, "action") if g.get("data-atomic") == "navigate")
    label = next(t for t in navigate.iter(f"{SVG}text") if "label" in t.get("class"))
    shown = label.find(f"{SVG}title").tail  # the label's own tooltip comes first
    assert shown.endswith("…") and len(shown) < len("navigate the-far-end")
    assert label.find(f"{SVG}title").text == "navigate the-far-end-of-the-living-room"
    assert "navigate(place=the-far-end-of-the-living-room)" in tooltip(navigate)
    assert float(root.get("width")) > 60 * 100  # the width grows with the duration


def test_short_and_empty_runs_still_make_a_picture():
    root = parse(render_timeline([]))
    assert float(root.get("width")) >= 800 and not lane_agents(root)
    root = parse(render_timeline([event(1, 5.0, "act-received", None, "alice", act="H-HELLO")]))
    assert float(root.get("width")) >= 800 and lane_agents(root) == ["alice"]
    assert all(math.isfinite(float(t.get("x"))) for t in root.iter(f"{SVG}text"))


def test_write_timeline_names_the_picture_after_the_log(distracted: Path, tmp_path: Path):
    out = write_timeline(distracted, tmp_path / "timeline.svg")
    assert out == tmp_path / "timeline.svg"
    assert parse(out.read_text(encoding="utf-8")).find(f"{SVG}title").text == "distracted"
    titled = write_timeline(distracted, tmp_path / "t2.svg", title="Fig. 11")
    assert parse(titled.read_text(encoding="utf-8")).find(f"{SVG}title").text == "Fig. 11"


def test_plan_marks_count_their_steps_in_words():
    events = [event(1, 0.0, "task-start", "n1", name="fetch", args={}),
              event(2, 0.0, "plan", "n1", recipe="fetch/REALIZE-TASK#1", steps=["1-move"]),
              event(3, 1.0, "replan", "n1", reason="1-move failed: blocked", attempt=1),
              event(4, 1.0, "plan", "n1", recipe="fetch/REALIZE-TASK#1",
                    steps=["1-move", "2-pick"]),
              event(5, 2.0, "task-end", "n1", name="fetch", outcome="done")]
    root = parse(render_timeline(events))
    labels = ["".join(g.find(f"{SVG}text").itertext()) for g in groups(root, "plan")]
    assert labels == ["plan: 1 step", "new plan: 2 steps"]


def test_a_run_of_many_short_actions_is_not_drawn_screens_wide():
    """The PR2 looking at one cube after another (0.2 s each, long labels) for 30 s: the
    default scale stops at a 2,000 px plot (labels beside or in their tooltips) instead of
    the 160 px/s that would show each label inside its bar, 4,800 px."""
    events, n = [], 0
    for k in range(150):
        n += 1
        events.append(event(n, k * 0.2, "exec-request", "n1", "pr2", atomic="look-at",
                            request=f"r{k}", args={"target": f"blue_cube_{k % 3}"}))
        n += 1
        events.append(event(n, k * 0.2 + 0.15, "exec-result", "n1", "pr2", request=f"r{k}",
                            status="done"))
    root = parse(render_timeline(events))
    assert 2000 <= float(root.get("width")) <= 2400
