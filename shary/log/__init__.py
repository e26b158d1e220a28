"""The context log and its pictures: what happened, kept, read back and drawn.

- :mod:`~shary.log.contextlog` -- :class:`ContextLog`: one SQLite file per run, written,
  checked and streamed back; :mod:`~shary.log.rows` -- what a logged row must hold to be
  read; :mod:`~shary.log.told` -- :class:`Told`: the log told, event by event, to
  listeners the engine does not know (the console, the ROS views);
- :mod:`~shary.log.lanes` -- a run's timeline collected from its log (items in agents'
  lanes); :mod:`~shary.log.timeline` -- that timeline drawn as SVG;
- :mod:`~shary.log.display` -- DOT, Mermaid, SVG and PNG of schemes and task trees;
- :mod:`~shary.log.terminal` -- what commands print: ``FILE:LINE:COL`` lines, error lines,
  one JSON document.
"""
