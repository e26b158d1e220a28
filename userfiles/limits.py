"""The stated limits of user files, and the duration syntax every format shares.

Each limit is named in the message of the problem that enforces it, and listed
in docs/architecture.md ("User files").  They bound what a run may be asked
to do, so that a file that validates can never make a run hang, allocate
gigabytes or loop for hours.
"""

from __future__ import annotations

import re
from typing import Any

MAX_DURATION = 24 * 3600.0
"""Longest duration a file may give (one day): timeouts, delays, goal times, `within`."""
MAX_COUNT = 1000
"""Most repetitions a file may ask for (e.g. how many times an injected fault fires)."""

_DURATION = re.compile(r"^([0-9]+(?:\.[0-9]+)?)(ms|s|min|h)?$")
_UNIT = {"ms": 0.001, "s": 1.0, "min": 60.0, "h": 3600.0, None: 1.0}


def seconds(value: Any) -> float:
    """A duration as files write it: a number of seconds, ``500ms``, ``5s``, ``2 min``,
    ``1.5h`` (spaces ignored); ValueError when it is none of those."""
    if isinstance(value, bool):
        raise ValueError(f"not a duration: {value!r}")
    if isinstance(value, int | float):
        return float(value)
    match = _DURATION.match("".join(str(value).split()))
    if not match:
        raise ValueError(f"not a duration: {value!r}")
    return float(match.group(1)) * _UNIT[match.group(2)]


def show_seconds(amount: float) -> str:
    """``86400`` -> ``24h``, ``90`` -> ``90s``: a limit as a user would write it."""
    if amount >= 3600 and amount % 3600 == 0:
        return f"{amount / 3600:g}h"
    return f"{amount:g}s"
