"""The human partner of the StackBuildingTask: follows the shared plan as a profile says.

The partner is one of the scenario's people (their avatar, their hands, their
gaze); this controller decides what they do with the plan the robot follows,
as a person would who knows their part (JAHRVIS assumes the human knows what
to do).  Its profile (a scenario's ``shared-plan: partner:``) says:

* ``choices``: at each human decision, in order, a word of the option to take
  (``placement_2``, ``place``) or ``wait`` (leave it to the robot);
* ``delay``: how long they take before acting on a task that is due;
* ``look-away``: ``{during: TASK, for: SECONDS}``, look away when the robot's
  task whose label starts with TASK begins, and look back after SECONDS; or
  ``{at: SECONDS, for: SECONDS}``, look away that long after the plan starts
  (whatever is under way then); or a list of them, each happening once (two
  look-aways in one plan);
* ``before``: ``{TASK: [[Pick, obj], [Place, obj, support]]}``, actions of their
  own they do when the task TASK is due, before it (the robot's turn taken, an
  unexpected action);
* ``leave``: ``{after: TASK}``, walk out of the door once that task is done (out of
  the robot's perception: their session closes).
"""

from __future__ import annotations

from typing import Any

from sim.motion import Instant, Sequence
from sim.simulation import standing_height

from .world import top_of

__all__ = ["StackPartner"]


class StackPartner:
    """Drives ``person`` (a :class:`sim.people.Person`) along ``follower``'s plan."""

    def __init__(self, person: Any, follower: Any, profile: dict[str, Any]):
        self.person = person
        self.sim = person.sim
        self.follower = follower
        self.choices = [str(c) for c in profile.get("choices", ())]
        self.delay = float(profile.get("delay", 1.0))
        away = profile.get("look-away")
        self.look_aways: list[dict[str, Any]] = [dict(a) for a in (
            away if isinstance(away, list) else [away] if away else [])]
        """The look-aways still to come (each happens once)."""
        self.before = {str(k): [list(map(str, a)) for a in v]
                       for k, v in (profile.get("before") or {}).items()}
        self.leave = (profile.get("leave") or {}).get("after")
        self.queue: list[list[str]] = []
        self.handled: set[int] = set()
        self.timers: list[Any] = []
        """What they mean to do later (act, look back, leave): cancelled by :meth:`stop`."""
        follower.watchers.append(self.plan_event)
        for away in self.look_aways:
            if "at" in away:
                self._later(float(away["at"]), self._look_away, away)

    @property
    def name(self) -> str:
        return self.person.name

    def _later(self, seconds: float, callback: Any, *args: Any) -> None:
        self.timers = [t for t in self.timers if not t.cancelled and t.due > self.sim.loop.now()]
        self.timers.append(self.sim.loop.call_later(seconds, callback, *args))

    def stop(self) -> None:
        """The shared task is over and the robot has nothing left to say: what they would
        still do on their own (look back in ten minutes) changes nothing the run decides,
        so it is dropped and the run can end."""
        for timer in self.timers:
            timer.cancel()
        self.timers = []

    def plan_event(self, event: str, task: int) -> None:
        """The follower's news: a task ``due`` or ``started`` by the robot, ``done``."""
        label = self.follower.plan.primitive[task].label()
        during = next((a for a in self.look_aways if "during" in a
                       and label.startswith(str(a["during"]))), None)
        if event == "started" and during is not None:
            self._look_away(during)
        elif event == "done" and self.leave and label.startswith(str(self.leave)):
            self._later(self.delay, self._leave)
        elif event == "due":
            self._later(self.delay, self._consider)

    def _look_away(self, away: dict[str, Any]) -> None:
        if away not in self.look_aways:
            return
        self.look_aways.remove(away)
        self.person.look("away")
        self._later(float(away.get("for", 5.0)), self.person.look, "robot")

    def _consider(self) -> None:
        follower = self.follower
        due = [t for t in follower.current if t not in self.handled]
        if not due or follower.finished:
            return
        labels = [follower.plan.primitive[t].label() for t in due]
        for prefix in list(self.before):
            if any(label.startswith(prefix) for label in labels):
                self._do_all(self.before.pop(prefix))
                return
        if not labels[0].split("(")[1].startswith(self.name):
            return
        self.handled.update(due)
        if len(due) > 1:
            choice = self.choices.pop(0) if self.choices else labels[0]
            if choice == "wait":
                return
            chosen = next((label for label in labels if choice in label
                           and not label.startswith("WaitForCube")), labels[0])
            self._act(chosen)
        elif not labels[0].startswith("WaitForCube"):
            self._act(labels[0])

    def _act(self, label: str) -> None:
        name, args = label.rstrip(")").split("(")
        params = [a.strip() for a in args.split(",")][1:]
        self._do_all([[name, *params]])

    def _do_all(self, actions: list[list[str]]) -> None:
        self.person._run(Sequence([self._activity(a) for a in actions], "stack part"))

    def _activity(self, action: list[str]) -> Any:
        name, *params = action
        if name == "Pick":
            return self.person._pick(params[0])
        if name == "PlaceStick":
            return self._put(params[0], params[1], params[2])
        return self._put(params[0], params[1])

    def _put(self, obj: str, support: str, other: str | None = None) -> Any:
        """Put ``obj`` on ``support`` (across it and ``other`` for the stick)."""
        person, world = self.person, self.sim.world

        def spot() -> tuple[float, float, float]:
            x, y, z = top_of(world, support)
            if other is not None:
                x2, y2, z2 = top_of(world, other)
                x, y, z = (x + x2) / 2, (y + y2) / 2, max(z, z2)
            return (x, y, standing_height(z, world.sizes[obj][0]))

        def let_go() -> None:
            if self.sim.held_by(self.name) == obj:
                self.sim.settle(obj, spot())
                self.sim.observe()

        return person._logged(Sequence([person._reach(spot), Instant(let_go, f"put {obj}"),
                                        person._reach(None)], f"put {obj} on {support}"),
                              "place", object=obj, on=support)

    def _leave(self) -> None:
        self.handled.update(self.follower.plan.primitive)  # gone: they do nothing more
        self.person.look("away")
        self.person._run(self.person.leaving())
