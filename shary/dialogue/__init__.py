"""The communication manager: the robot's dialogue with people, and its language.

The language (verbalization, referring expressions, requests) is in
:mod:`~shary.dialogue.verbalize`, :mod:`~shary.dialogue.reg` and
:mod:`~shary.dialogue.requests`.

SHARY's section 2.2: "either partner may propose at any time".  The engine
core only delivers an act to a task that expects it; this package adds what
a conversation needs on top of that, with schemes and recipes like any task:

- :mod:`~shary.dialogue.initiative`: a person's ASK-TASK starts a task with its
  H-initiated variant (the robot agrees or refuses), a person's CANCEL stops
  one, a person's MODIFY-PLAN changes who does a step of a plan;
- :mod:`~shary.dialogue.attention`: a communication waits until the person
  attends (the ``inform`` scheme), then speaks, calls, or gives up;
- :mod:`~shary.dialogue.disambiguation`: a request whose description fits
  several things is asked about (the ``disambiguate`` scheme);
- :mod:`~shary.dialogue.sessions`: interaction sessions (greeting, tasks,
  farewell) and the agenda's rule that tasks with a person run inside one;
- :mod:`~shary.dialogue.steps`: the steps their recipes are made of (say, look).

:func:`install` wires them into a :class:`~shary.kernel.supervisor.Supervisor`: the
recipe functions the built-in dialogue recipes name, and the initiative
handler for acts no task expects.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from shary.kernel.supervisor import Supervisor


def install(sup: Supervisor) -> Any:
    """Give ``sup`` the dialogue: recipe functions and the person-initiative handler.

    Returns the :class:`~shary.dialogue.initiative.Initiative` (it holds the
    sessions and pending questions).  Installing twice is harmless.
    """
    from shary.dialogue.initiative import Initiative

    found = getattr(sup, "dialogue", None)
    return found if found is not None else Initiative(sup)
