"""``python -m shary``: the same command as ``shary``."""

import sys

from shary.cli import main

sys.exit(main())
