"""Files that users write, read safely and checked, with problems as FILE:LINE:COL.

Shared by ``shary`` and ``planner`` (which must not import ``shary``): safe,
located YAML (:mod:`userfiles.yamlsafe`), JSON Schema checks with readable
messages (:mod:`userfiles.schema`) and the problems themselves
(:mod:`userfiles.errors`).
"""
