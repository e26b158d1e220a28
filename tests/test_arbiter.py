"""The body's arbiter: one head aim served at a time by priority, the previous aim
restored, superseded requests told cancelled, one arm motion and one sentence at a time."""

from __future__ import annotations

import pytest
from scripted import ScriptedExecutor

from shary.kernel.arbiter import ACT, TASK, WATCH, BodyArbiter
from shary.kernel.executors import ExecutorRegistry, Reporter, Request
from shary.kernel.loop import EventLoop
from shary.kernel.tasktree import ACT as ACT_NODE
from shary.kernel.tasktree import ATOMIC, TaskTree


class Body:
    """A tree, a loop, a scripted head and arm behind an arbiter, and what came back."""

    def __init__(self, look: float = 0.5, pick: float = 2.0):
        self.loop = EventLoop()
        self.tree = TaskTree()
        self.rows: list[dict] = []
        self.executor = ScriptedExecutor(self.loop, {"look-at": look, "pick": pick,
                                                     "speak": 1.5})
        self.registry = ExecutorRegistry(dict.fromkeys(("look-at", "pick", "speak"),
                                                       self.executor))
        self.registry.arbiter = BodyArbiter(self.tree, self.loop,
                                            lambda kind, **row: self.rows.append(row))
        self.results: list[tuple[float, str, str]] = []
        self._reporter = Reporter(lambda o: self.results.append(
            (self.loop.now(), o.request.id, o.status)), self.loop.call_soon)
        self._ids = iter(range(1, 1000))

    def node(self, under_act: bool = False) -> str:
        parent = self.tree.add(ACT_NODE, "an act", state="ongoing") if under_act else None
        return self.tree.add(ATOMIC, "a step", parent, state="ongoing")

    def ask(self, atomic: str, target: str, node: str, priority: int) -> str:
        request = Request(f"q{next(self._ids)}", atomic, {"target": target, "object": target},
                          "pr2", node, priority)
        self.registry.dispatch(request, self._reporter, lambda *a, **k: None)
        return request.id

    def looks(self) -> list[str]:
        return [args["target"] for _, atomic, args in self.executor.started
                if atomic == "look-at"]


def test_a_higher_aim_is_served_and_the_previous_one_restored_when_it_ends():
    body = Body()
    watch = body.node()
    body.ask("look-at", "stick", watch, WATCH)
    body.loop.advance(1.0)
    act = body.tree.parent(speak := body.node(under_act=True))
    body.ask("look-at", "alice", speak, TASK)
    body.loop.advance(1.0)
    assert body.looks() == ["stick", "alice"]
    body.tree.set_state(act, "done")  # the act that looked, then spoke, is over
    body.loop.advance(1.0)
    assert body.looks() == ["stick", "alice", "stick"]
    assert [r["action"] for r in body.rows] == ["serve", "serve", "release", "restore"]
    assert [s for _, _, s in body.results] == ["done", "done"]  # a restore has no requester


def test_a_request_superseded_while_the_head_moves_is_told_cancelled():
    body = Body(look=1.0)
    first = body.ask("look-at", "green_cube", body.node(), ACT)
    body.loop.advance(0.2)
    speak = body.node(under_act=True)
    second = body.ask("look-at", "alice", speak, ACT)  # as high, and newer
    body.loop.advance(2.0)
    assert (first, "cancelled") in [(i, s) for _, i, s in body.results]
    assert (second, "done") in [(i, s) for _, i, s in body.results]
    assert any(r["action"] == "supersede" for r in body.rows)


def test_a_lower_request_waits_for_the_higher_aim_then_gets_its_result():
    body = Body()
    acting = body.node()
    body.ask("look-at", "green_cube", acting, ACT)  # a robot action looks, then acts
    body.loop.advance(1.0)
    lower = body.ask("look-at", "alice", body.node(under_act=True), TASK)
    body.loop.advance(5.0)
    assert lower not in [i for _, i, _ in body.results]  # no answer while the action holds
    body.tree.set_state(acting, "done")
    body.loop.advance(1.0)
    assert (lower, "done") in [(i, s) for _, i, s in body.results]
    assert [r["action"] for r in body.rows][:2] == ["serve", "wait"]


def test_a_waiting_request_whose_task_ends_is_told_cancelled():
    body = Body()
    body.ask("look-at", "green_cube", body.node(), ACT)
    step = body.node(under_act=True)
    lower = body.ask("look-at", "alice", step, TASK)
    body.loop.advance(1.0)
    body.tree.set_state(body.tree.parent(step), "cancelled")
    body.loop.advance(1.0)
    assert (lower, "cancelled") in [(i, s) for _, i, s in body.results]


def test_one_arm_motion_at_a_time():
    body = Body(pick=2.0)
    first = body.ask("pick", "red_cube_1", body.node(), TASK)
    second = body.ask("pick", "blue_cube_1", body.node(), TASK)
    body.loop.advance(1.0)
    assert [a for _, a, _ in body.executor.started] == ["pick"]  # the second waits
    body.loop.advance(5.0)
    assert [i for _, i, s in body.results] == [first, second]
    starts = [t for t, a, _ in body.executor.started]
    assert starts[1] >= 2.0


@pytest.mark.parametrize("atomic, first, late", [
    ("pick", {"object": "red_cube_1"}, {"object": "blue_cube_1"}),
    ("speak", {"text": "All right, I will stop."}, {"text": "Sorry?"})])
def test_a_waiting_motion_or_sentence_cancelled_is_told_so_and_never_starts(atomic, first,
                                                                             late):
    body = Body(pick=2.0)
    body.registry.dispatch(Request("first", atomic, first, "pr2", body.node(), TASK),
                           body._reporter, lambda *a, **k: None)
    request = Request("late", atomic, late, "pr2", body.node(), TASK)
    body.registry.dispatch(request, body._reporter, lambda *a, **k: None)
    body.registry.get(atomic).cancel(request)
    body.loop.advance(5.0)
    assert ("late", "cancelled") in [(i, s) for _, i, s in body.results]
    assert [a for _, a, _ in body.executor.started] == [atomic]


def test_one_sentence_at_a_time_the_later_said_when_the_earlier_has_been():
    body = Body()
    first = body.ask("speak", "I have put the yellow bottle away.", body.node(), TASK)
    look = body.ask("look-at", "alice", body.node(), TASK)
    second = body.ask("speak", "Goodbye, Alice.", body.node(), TASK)
    body.loop.advance(0.1)
    # the head is free to turn while the robot speaks; the second sentence waits
    assert [a for _, a, _ in body.executor.started] == ["speak", "look-at"]
    assert {"part": "voice", "action": "wait", "atomic": "speak", "behind": first}.items() \
        <= body.rows[-1].items()
    body.loop.advance(5.0)
    assert [i for _, i, s in body.results] == [look, first, second]
    starts = [t for t, a, _ in body.executor.started if a == "speak"]
    assert starts == [0.0, 1.5]
