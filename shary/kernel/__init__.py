"""The supervision kernel: tasks run as schemes, acts launch recipes, recipes grow the tree.

- :mod:`~shary.kernel.supervisor` -- :class:`Supervisor` and :class:`TaskRun`: a task's
  scheme instance and its acts; :mod:`~shary.kernel.acttask` -- act x task: recipe
  choice, steps, monitors, retry, suspend, resume, stop;
- :mod:`~shary.kernel.recipes` -- tasks, atomic tasks, recipes, monitors, chronicles;
- :mod:`~shary.kernel.tasktree` -- the dynamic task tree (and its replay from a log);
- :mod:`~shary.kernel.agenda` -- the Task Agenda and the chronicle recognizer;
- :mod:`~shary.kernel.executors` -- the executor port (requests, reporter, registry);
  :mod:`~shary.kernel.arbiter` -- one owner for the head and the arms, by priority;
- :mod:`~shary.kernel.planning` -- the planner port, filled with :mod:`planner`;
- :mod:`~shary.kernel.loop` -- the one event loop (ready work, timers, idle hooks) and
  the wall clock.
"""
