"""Imported first by the benchmarks that use the ``planner`` package.

A script's folder comes first on ``sys.path`` when it runs, and this folder holds
``benchmarks/planner.py`` (the planner's benchmark), which would shadow the
package: ``python benchmarks/scenarios.py`` would import the benchmark instead of
the planner.  So the package is imported with this folder off the path (an
editable install's finder comes after every path entry, so the folder cannot
merely go last), then the folder comes back, last, for the helpers beside the
scripts (``livingroom.py`` …).
"""

import sys
from pathlib import Path

HERE = Path(__file__).resolve().parent
sys.path[:] = [p for p in sys.path if Path(p or ".").resolve() != HERE]
import planner  # noqa: E402, F401  (cached in sys.modules: the package, whatever comes after)

sys.path.append(str(HERE))
