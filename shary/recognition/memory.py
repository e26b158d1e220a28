"""What the recognizer remembers of the facts its models name: current, and lately gone.

The fact base holds what is true now; recognition also asks what was true a
moment ago (who was holding the cube just before it appeared on the stack,
whether a hold that came back had vanished for less than ``settle``). So the
recognizer keeps its own small index of the facts of the models' predicates,
both ways (subject -> objects, object -> subjects) and with the time each one
vanished, forgotten after a horizon.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

__all__ = ["FactMemory"]


@dataclass
class FactMemory:
    """The current facts of the subscribed predicates, indexed both ways, and when the
    ones that vanished went (for flicker, preconditions held a moment ago, nearness)."""

    objects: dict[tuple[Any, Any], dict[Any, None]] = field(default_factory=dict)
    subjects: dict[tuple[Any, Any], dict[Any, None]] = field(default_factory=dict)
    gone: dict[tuple[Any, Any, Any], float] = field(default_factory=dict)
    gone_objects: dict[tuple[Any, Any], dict[Any, float]] = field(default_factory=dict)
    gone_subjects: dict[tuple[Any, Any], dict[Any, float]] = field(default_factory=dict)

    def add(self, s: Any, p: Any, o: Any) -> float | None:
        """Add a fact; when it had vanished, the time it went."""
        self.objects.setdefault((s, p), {})[o] = None
        self.subjects.setdefault((p, o), {})[s] = None
        went = self.gone.pop((s, p, o), None)
        if went is not None:
            self.gone_objects[(s, p)].pop(o, None)
            self.gone_subjects[(p, o)].pop(s, None)
        return went

    def remove(self, s: Any, p: Any, o: Any, now: float) -> None:
        self.objects.get((s, p), {}).pop(o, None)
        self.subjects.get((p, o), {}).pop(s, None)
        self.gone[(s, p, o)] = now
        self.gone_objects.setdefault((s, p), {})[o] = now
        self.gone_subjects.setdefault((p, o), {})[s] = now

    def forget(self, horizon: float) -> None:
        """Forget facts that vanished before ``horizon``."""
        for (s, p, o) in [f for f, t in self.gone.items() if t < horizon]:
            del self.gone[(s, p, o)]
            del self.gone_objects[(s, p)][o]
            del self.gone_subjects[(p, o)][s]

    def holds(self, s: Any, p: Any, o: Any) -> bool:
        return o in self.objects.get((s, p), ())

    def recently(self, s: Any, p: Any, o: Any, now: float, within: float) -> bool:
        """Holds, or held until ``within`` seconds ago or less."""
        if o in self.objects.get((s, p), ()):
            return True
        gone = self.gone.get((s, p, o))
        return gone is not None and now - gone <= within

    def completing(self, s: Any, p: Any, o: Any, now: float, within: float) -> list[Any]:
        """What fills the missing side of (s, p, ?) or (?, p, o), now or ``within`` seconds
        ago or less, in a stable order."""
        if o is None:
            found, went = self.objects.get((s, p), {}), self.gone_objects.get((s, p), {})
        else:
            found, went = self.subjects.get((p, o), {}), self.gone_subjects.get((p, o), {})
        values = list(found)
        values += [v for v, t in went.items() if now - t <= within and v not in found]
        return sorted(values, key=str) if len(values) > 1 else values
