"""Guards name conditions registered in Python; files never carry code.

A condition is a side-effect-free callable ``(instance, event) -> bool``.
Applications register theirs on a :class:`ConditionRegistry`; packages can
also publish conditions under the ``shary.statechart.conditions`` entry-point group, which
is how ``shary validate`` knows every name a scheme may use.
"""

from __future__ import annotations

from collections.abc import Callable, Iterator
from importlib.metadata import entry_points
from typing import Any

Condition = Callable[[Any, Any], bool]
ENTRY_POINT_GROUP = "shary.statechart.conditions"


class ConditionRegistry:
    """Named conditions that scheme guards may refer to."""

    def __init__(self, conditions: dict[str, Condition] | None = None):
        self._conditions: dict[str, Condition] = dict(conditions or {})

    def register(self, name: str, func: Condition | None = None) -> Any:
        """Register ``func`` under ``name``; usable as a decorator."""
        def add(f: Condition) -> Condition:
            self._conditions[name] = f
            return f
        return add(func) if func is not None else add

    def __contains__(self, name: object) -> bool:
        return name in self._conditions

    def __iter__(self) -> Iterator[str]:
        return iter(self._conditions)

    def __getitem__(self, name: str) -> Condition:
        return self._conditions[name]

    @classmethod
    def installed(cls) -> ConditionRegistry:
        """The conditions that installed packages publish as entry points."""
        found = {ep.name: ep for ep in entry_points(group=ENTRY_POINT_GROUP)}
        return cls({name: _Lazy(ep) for name, ep in found.items()})


class _Lazy:
    """Loads an entry point's condition the first time it is called."""

    def __init__(self, entry_point: Any):
        self.entry_point = entry_point
        self.func: Condition | None = None

    def __call__(self, instance: Any, event: Any) -> bool:
        if self.func is None:
            self.func = self.entry_point.load()
        return bool(self.func(instance, event))
