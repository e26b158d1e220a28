"""A scripted world for kernel tests: fake executors on the loop's clock, no physics."""

from __future__ import annotations

from dataclasses import dataclass, field

from shary.facts.database import FactDatabase
from shary.io.recipes import load_library
from shary.kernel.executors import ExecutorRegistry, Reporter, Request
from shary.kernel.loop import EventLoop
from shary.kernel.supervisor import Supervisor


@dataclass
class ScriptedExecutor:
    """Performs every atomic task in ``durations`` seconds; fails as scripted."""

    loop: EventLoop
    durations: dict[str, float] = field(default_factory=dict)
    failures: dict[str, list[str]] = field(default_factory=dict)
    started: list[tuple[float, str, dict]] = field(default_factory=list)
    cancelled: list[tuple[float, str]] = field(default_factory=list)
    running: dict[str, tuple] = field(default_factory=dict)

    def start(self, request: Request, reporter: Reporter) -> None:
        self.started.append((self.loop.now(), request.atomic, dict(request.args)))
        reasons = self.failures.get(request.atomic)
        if reasons:
            reason = reasons.pop(0)
            timer = self.loop.call_later(self.durations.get(request.atomic, 1.0),
                                         reporter.failed, request, reason)
        else:
            timer = self.loop.call_later(self.durations.get(request.atomic, 1.0),
                                         reporter.done, request)
        self.running[request.id] = (timer, reporter)

    def cancel(self, request: Request) -> None:
        found = self.running.pop(request.id, None)
        if found is not None:
            timer, reporter = found
            timer.cancel()
            self.cancelled.append((self.loop.now(), request.atomic))
            reporter.cancelled(request)

    def names(self) -> list[str]:
        return [name for _, name, _ in self.started]


class World:
    """Jido, Alice, a bottle and a table, with a supervisor over them."""

    def __init__(self, *, log=None, extra_library=None, seed: int = 0, **supervisor_args):
        self.loop = EventLoop(seed=seed)
        self.facts = FactDatabase()
        self.facts.add("alice", "looksAt", "jido")
        self.facts.add("bottle", "isOn", "table")
        self.facts.add("bottle", "isReachableBy", "jido")
        self.executor = ScriptedExecutor(self.loop)
        library = load_library(extra_library or [])
        registry = ExecutorRegistry({name: self.executor for name in library.atomic})
        self.sup = Supervisor(library, self.facts, robot="jido", loop=self.loop,
                              executors=registry, log=log, **supervisor_args)

    def give(self, **kwargs):
        run = self.sup.start_task("give-object", {"object": "bottle", "partner": "alice"},
                                  **kwargs)
        self.loop.run_until_idle()
        return run

    def run(self, seconds: float) -> None:
        self.loop.advance(seconds)

    def distracted_give(self) -> None:
        """give-object where Alice agrees, looks away during the arm motion, looks back."""
        self.executor.durations.update({"move-arm": 4.0})
        self.give()
        self.sup.receive_act("alice", "H-AGREE")
        self.run(2.5)
        self.facts.remove("alice", "looksAt", "jido")
        self.run(5)
        self.facts.add("alice", "looksAt", "jido")
        self.run(30)
