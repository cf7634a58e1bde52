"""``python -m netsim`` runs the command-line interface."""

from netsim.cli import main

raise SystemExit(main())
