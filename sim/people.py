"""People who behave: a profile (:mod:`sim.humans`) played out on the supervisor's loop.

A :class:`Person` hears the robot's acts (the supervisor tells its act
listeners when an act starts, as a person sees and hears the robot begin to
ask, to hand over, to give up) and answers after the robot has finished
speaking and the profile's delay; looks where the profile says (at the robot,
or away on a phone call triggered by a time or by the robot starting an
action towards them); takes what the robot holds out when attending to it;
helps when asked (fetches the object and hands it to the robot); and plays a
script of its own (walk to the table, put a bottle down, leave).
"""

from __future__ import annotations

import math
import random
from collections.abc import Callable
from typing import Any

from .humans import ARM_LENGTH, HUMAN_PLACES, Profile
from .motion import Activity, Instant, Lazy, Sequence, Wait
from .simulation import Simulation, Walk, standing_height

AWAY = "away"
"""Attention on nothing in the room (a phone call)."""
OUTSIDE = (2.55, -3.4)
"""Where a person who left the room is: beyond the door, facing away (out of sight: too
far from the robot's places to be at one, looking at nothing in the room)."""
UNSPOKEN_ANSWER = 5.0
"""Seconds after an act begins by which a person answers even if the robot said nothing."""


class _Logged(Activity):
    """A person's action, logged like the robot's (``person-action`` … ``-end``) so that
    the timeline shows each person's stream, as HATP's plans do (Fig. 10)."""

    def __init__(self, person: Person, inner: Activity, atomic: str, args: dict[str, Any]):
        self.person = person
        self.inner = inner
        self.atomic = atomic
        self.args = args
        self.label = atomic
        self.id = ""

    def advance(self, dt: float) -> bool:
        if not self.id:
            self.id = self.person.log_start(self)
        if self.inner.advance(dt):
            self.person.log_end(self, "done")
            return True
        return False


class Person:
    """One simulated person (see the module's docstring)."""

    def __init__(self, name: str, profile: Profile, sim: Simulation, sup: Any,
                 rng: random.Random, robot_arm: Any, say: Callable[[str, str], Any]):
        self.name = name
        self.profile = profile
        self.sim = sim
        self.sup = sup
        self.rng = rng
        self.robot_arm = robot_arm
        self.say = say
        self.avatar = sim.people[name]
        self.attention = sim.robot if profile.attention == "robot" else profile.attention
        self.default_attention = self.attention
        self.offer: tuple[str, str, Callable[[], Any]] | None = None
        self._take_timer: Any = None
        self._script = list(profile.script)
        self._triggered: set[int] = set()
        self.busy: int | None = None
        self._pending: list[tuple[Any, str, Any]] = []
        self._current_step: Any = None
        self._open: list[_Logged] = []
        self._answered: dict[str, int] = {}
        """Act -> how many times the person was asked it (which answer comes next)."""
        self._action_ids = 0

    # -- start -------------------------------------------------------------------

    def begin(self) -> None:
        for i, d in enumerate(self.profile.distractions):
            if d.at is not None:
                self._triggered.add(i)
                self.sim.loop.call_later(d.at + self._draw(d.after), self._distract, d)
        self._next_script_step()
        self.refresh()

    def _draw(self, span: tuple[float, float]) -> float:
        low, high = span
        return low if high <= low else self.rng.uniform(low, high)

    # -- attention ------------------------------------------------------------------

    def refresh(self) -> None:
        """Turn the head to what the person attends to (it may have moved)."""
        a = self.avatar
        if self.attention == AWAY:
            point = (a.x + 1.5 * math.cos(a.yaw + 1.9), a.y + 1.5 * math.sin(a.yaw + 1.9), 0.7)
        elif self.attention == self.sim.robot:
            point = self.sim.world.link_position(self.sim.robot, "camera_link")
        elif self.attention in self.sim.people:
            point = self.sim.people[self.attention].eyes
        else:
            try:
                point = self.sim.world.position(self.attention)
                if self.attention in self.sim.world.footprints:
                    f = self.sim.world.footprints[self.attention]
                    point = (f.x, f.y, self.sim.world.top(self.attention))
            except KeyError:
                return
        a.look_at_point(point)

    def look(self, target: str) -> None:
        self.attention = self.sim.robot if target == "robot" else target
        self.refresh()
        self.sim.observe()
        self._consider_offer()

    def _distract(self, distraction: Any) -> None:
        self.say(self.name, "(takes a phone call)" if distraction.look in (AWAY, "phone")
                 else f"(looks at {distraction.look})")
        self.look(AWAY if distraction.look == "phone" else distraction.look)
        if distraction.duration is not None:
            self.sim.loop.call_later(distraction.duration, self.look, self.default_attention)

    def robot_started(self, atomic: str, args: dict[str, Any]) -> None:
        """The robot began an action: a phone call may ring now (Fig. 11)."""
        if self.name not in args.values():
            return
        for i, d in enumerate(self.profile.distractions):
            if d.robot_starts == atomic and i not in self._triggered:
                self._triggered.add(i)
                self.sim.loop.call_later(self._draw(d.after), self._distract, d)

    # -- answering acts ---------------------------------------------------------------

    def on_act(self, run: Any, state: Any, agent: str) -> None:
        """An act began in a task; answer it once the robot has said it (or soon)."""
        if agent == self.name or self.name not in run.roles.values():
            return
        answers = self.profile.answers.get(state.act)
        if not answers:
            return
        count = self._answered[state.act] = self._answered.get(state.act, 0) + 1
        answer = answers[min(count, len(answers)) - 1]
        if answer.reply is None and answer.words is None:
            return
        pending = (run, state.act, answer)
        self._pending.append(pending)
        # an act with nothing to say is answered all the same, a little later
        self.sim.loop.call_later(UNSPOKEN_ANSWER, self._unspoken, pending)

    def _unspoken(self, pending: tuple[Any, str, Any]) -> None:
        if self.robot_arm.speaking:
            return  # it is saying it now: the answer comes when it has finished
        self._reply(pending)

    def heard(self) -> None:
        """The robot finished saying something: answer what it was asking."""
        for pending in list(self._pending):
            self._reply(pending)

    def _reply(self, pending: tuple[Any, str, Any]) -> None:
        if pending not in self._pending:
            return
        self._pending.remove(pending)
        run, act, answer = pending
        self.sim.loop.call_later(self._draw(answer.after), self._answer, run, act, answer)

    def _answer(self, run: Any, act: str, answer: Any) -> None:
        if run.ended:
            return
        reply = answer.reply
        data: dict[str, Any] | None = None
        if reply is None:  # words alone: a sentence the robot reads
            self.tell(None, None, {}, answer.words)
            return
        if answer.words is not None:
            self.say(self.name, answer.words)
            data = {"text": answer.words}
        elif answer.choose is not None:
            self.say(self.name, "(points at the " + " and ".join(
                f"{'one on' if p == 'isOn' else 'one in'} the {str(v).replace('-', ' ')}"
                if p in ("isOn", "isIn") else str(v) for p, v in answer.choose.items()) + ")")
            data = {"choice": dict(answer.choose)}
        else:
            self.say(self.name, {"H-AGREE": "Yes.", "H-DISAGREE": "No, thanks."}.get(reply,
                                                                                   reply))
        self.sup.receive_act(self.name, reply, data, task=run.node)
        if act == "ASK-HELP" and reply == "H-AGREE" and self.profile.helps:
            obj = run.env.get("object")
            if obj is not None:
                self.help(str(obj))

    # -- taking what is held out ---------------------------------------------------------

    def offered(self, obj: str, giver: str, taken: Callable[[], Any]) -> None:
        self.offer = (obj, giver, taken)
        self._consider_offer()

    def withdraw(self) -> None:
        self.offer = None
        if self._take_timer is not None:
            self._take_timer.cancel()
            self._take_timer = None

    def _consider_offer(self) -> None:
        if (self.offer is None or self.profile.takes is None or self._take_timer is not None
                or self.attention != self.offer[1]):
            return
        self._take_timer = self.sim.loop.call_later(self._draw(self.profile.takes), self._take)

    def _take(self) -> None:
        self._take_timer = None
        if self.offer is None or self.attention != self.offer[1]:
            return  # looked away meanwhile: wait until attending again
        obj, _, taken = self.offer
        self.offer = None
        self.sim.attach(obj, self.name)
        self.sim.observe()
        taken()

    # -- doing things ------------------------------------------------------------------

    def _logged(self, activity: Activity, atomic: str, **args: Any) -> Activity:
        return _Logged(self, activity, atomic, args)

    def log_start(self, action: _Logged) -> str:
        self._action_ids += 1
        action_id = f"{self.name}-{self._action_ids}"
        self._open.append(action)
        self.sup.record("person-action", agent=self.name, atomic=action.atomic,
                        args=action.args, request=action_id)
        return action_id

    def log_end(self, action: _Logged, status: str) -> None:
        if action in self._open:
            self._open.remove(action)
            self.sup.record("person-action-end", agent=self.name, request=action.id,
                            status=status)

    def _run(self, activity: Activity, done: Callable[[], Any] | None = None) -> None:
        if self.busy is not None:
            self.sim.stop(self.busy)
            for action in list(self._open):
                self.log_end(action, "cancelled")

        def over() -> None:
            self.busy = None
            if done is not None:
                done()

        self.busy = self.sim.start(activity, over)

    def _walk(self, goal: Callable[[], tuple[float, float, float]], seated: bool = False,
              what: str = "walk") -> Activity:
        """Walk to ``goal()`` = (x, y, final heading), computed when the walk starts; a
        person who finds no way says so and stays (their next steps may still work)."""
        def build() -> Activity:
            try:
                x, y, yaw = goal()
                return Walk(self.avatar, self.sim.person_path(self.name, (x, y), yaw),
                            self.profile.speed, yaw, seated)
            except LookupError as err:
                self.say(self.name, f"({err})")
                return Instant(lambda: None)
        return Lazy(build, what)

    def walk_to(self, place: str) -> Activity:
        x, y, yaw, seated = HUMAN_PLACES[place]
        return self._logged(self._walk(lambda: (x, y, yaw), seated, f"walk to {place}"),
                            "walk", to=place)

    def _walk_near(self, obj: str) -> Activity:
        def goal() -> tuple[float, float, float]:
            target = self.sim.world.position(obj)
            place = min(HUMAN_PLACES, key=lambda p: math.dist(HUMAN_PLACES[p][:2], target[:2])
                        if not HUMAN_PLACES[p][3] else math.inf)
            x, y, _, _ = HUMAN_PLACES[place]
            return x, y, math.atan2(target[1] - y, target[0] - x)
        return self._logged(self._walk(goal, what=f"walk to {obj}"), "walk", to=obj)

    def _reach(self, point: Callable[[], tuple[float, float, float]] | None) -> Activity:
        def act() -> None:
            self.avatar.hand_out = None if point is None else point()
            self.avatar.place()
            self.sim.carry()
        return Sequence([Instant(act, "reach"), Wait(0.6)], "reach")

    def _pick(self, obj: str) -> Activity:
        def grab() -> None:
            x, y, _ = self.sim.world.position(obj)
            holder = self.sim.holder.get(obj)
            if holder not in (None, self.name):  # nobody pulls it out of another's hand
                self.say(self.name, f"(the {obj} is in {holder}'s hand)")
            elif math.hypot(x - self.avatar.x, y - self.avatar.y) <= ARM_LENGTH:
                self.sim.attach(obj, self.name)
            else:
                self.say(self.name, f"(cannot reach the {obj})")
        return self._logged(Sequence([self._reach(lambda: self.sim.world.position(obj)),
                                      Instant(grab), self._reach(None)], f"pick {obj}"),
                            "pick", object=obj)

    def help(self, obj: str) -> None:
        """Fetch ``obj`` and hand it to the robot (the helper's part of Fig. 10)."""
        def beside_robot() -> tuple[float, float, float]:
            x, y = self.sim.meeting_point(self.name)
            rx, ry, _ = self.sim.world.base_pose(self.sim.robot)
            return x, y, math.atan2(ry - y, rx - x)

        def hold_out() -> tuple[float, float, float]:
            a = self.avatar
            return (a.x + 0.45 * math.cos(a.yaw), a.y + 0.45 * math.sin(a.yaw), 0.85)

        def hand_over() -> None:
            if self.sim.held_by(self.name) != obj:
                return
            if not self.robot_arm.take_from(self.name, obj, self._handed):
                self.say(self.name, f"({self.sim.robot}'s hand is not free; keeps the {obj})")
                self._handed()

        steps: list[Activity] = []
        if self.sim.held_by(self.name) != obj:
            steps += [self._walk_near(obj), self._pick(obj)]
        robot = self.sim.robot
        steps += [self._logged(self._walk(beside_robot, what=f"walk to {robot}"), "walk",
                               to=robot),
                  self._logged(Sequence([self._reach(hold_out), Instant(hand_over, "hold out")],
                                        "give"), "give", object=obj, to=robot)]
        if self.busy is not None and self._current_step is not None:
            self._script.insert(0, self._current_step)  # helping first, then back to it
        self._run(Sequence(steps, f"help with {obj}"), self._next_script_step)

    def _handed(self) -> None:
        self.avatar.hand_out = None
        self.avatar.place()

    # -- the script ------------------------------------------------------------------------

    def _next_script_step(self) -> None:
        if not self._script:
            return
        step = self._script.pop(0)
        delay = self._draw(step.after)
        if step.at is not None:
            delay += max(0.0, step.at - self.sim.loop.now())
        self.sim.loop.call_later(delay, self._do, step)

    def _do(self, step: Any) -> None:
        self._current_step = step
        if step.look is not None:
            self.look(step.look)
        if step.act is not None or step.words is not None:
            self.tell(step.act, step.task, step.args, step.words)
        activity: Activity | None = None
        if step.walk is not None:
            activity = self.walk_to(step.walk)
        elif step.take is not None:
            activity = Sequence([self._walk_near(step.take), self._pick(step.take)],
                                f"take {step.take}")
        elif step.put is not None:
            activity = self._put(step.put, step.on or "coffee-table")
        elif step.leave:
            activity = self.leaving()
        if activity is None:
            self._current_step = None
            self._next_script_step()
        else:
            self._run(activity, self._step_done)

    def _step_done(self) -> None:
        self._current_step = None
        self._next_script_step()

    def _put(self, obj: str, furniture: str) -> Activity:
        def spot() -> tuple[float, float, float]:
            f = self.sim.world.footprints[furniture]
            a = self.avatar
            # the point of the furniture top nearest the person, 8 cm inside its edge
            lx = max(-f.half_x + 0.08, min(f.half_x - 0.08, (a.x - f.x)))
            ly = max(-f.half_y + 0.08, min(f.half_y - 0.08, (a.y - f.y)))
            return (f.x + lx, f.y + ly, standing_height(self.sim.world.top(furniture)))

        def let_go() -> None:
            if self.sim.held_by(self.name) == obj:
                self.sim.settle(obj, spot())
                self.sim.observe()

        return self._logged(Sequence([self._reach(spot), Instant(let_go, f"put {obj}"),
                                      self._reach(None)], f"put {obj} on {furniture}"),
                            "place", object=obj, on=furniture)

    def leaving(self) -> Activity:
        """Walk to the door and out of it (out of the robot's perception: it says goodbye)."""
        return Sequence([self.walk_to("door"), Instant(self._exit, "leave")], "leave")

    def _exit(self) -> None:
        """Out of the door: out of the room and of the robot's perception."""
        self.avatar.x, self.avatar.y = OUTSIDE
        self.avatar.yaw = -math.pi / 2
        self.attention = self.default_attention = AWAY
        self.avatar.place()
        self.refresh()
        self.sim.observe()

    def tell(self, act: str | None, task: str | None, args: dict[str, Any],
             words: str | None) -> None:
        """Start a communication act (a request, a cancellation), saying ``words``; or,
        without an act, say ``words`` to the robot, which reads them as a request."""
        if words:
            self.say(self.name, words)
        if act is None:
            if words:
                self.sup.dialogue.hear(self.name, words)
            return
        data: dict[str, Any] = {"with": dict(args)} if args else {}
        if task is not None:
            data["task"] = task
        self.sup.receive_act(self.name, act, data or None)

    @property
    def pending(self) -> bool:
        """Whether the person still has something to do on their own."""
        return bool(self._script) or self.busy is not None
