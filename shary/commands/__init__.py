"""The engine's own ``shary`` commands, one module per concern.

Each module offers ``add_NAME(subparsers)`` functions, registered as entry
points of the group ``shary.commands`` in ``pyproject.toml`` (see
:mod:`shary.cli`).  The simulator's commands live in :mod:`sim.cli`.
"""
