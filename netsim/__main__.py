"""``python -m netsim`` runs the command-line interface.

``python -m`` puts the current folder first on ``sys.path``; it is removed before anything else is imported,
so that a ``models.py`` or ``models/`` (or any module) in the folder where a scenario is run is never imported
in place of netsim's own (issue 14; ``python -P`` / ``PYTHONSAFEPATH`` already leave it out).
"""

import os
import sys

if not sys.flags.safe_path and sys.path and sys.path[0] in ("", os.getcwd()):
    del sys.path[0]

from netsim.cli import main  # noqa: E402

raise SystemExit(main())
