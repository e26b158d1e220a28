"""Files in and out of the planner: its own YAML, HDDL, and the IPC's plan format.

- :mod:`~planner.io.domainfiles` -- domains and problems from YAML, schema first, then
  meaning (:func:`load_domain`, :func:`load_problem`, the built-in ones);
- :mod:`~planner.io.hddl` -- the HDDL reader (tokens, S-expressions, a checked tree);
- :mod:`~planner.io.translate` -- HDDL into the planner's model (:func:`load_hddl`);
- :mod:`~planner.io.ipc` -- plans in the IPC 2020 HTN track's format, written and read.
"""
