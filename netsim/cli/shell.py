"""Two commands about netsim as installed, seen from a shell: ``netsim scenarios`` and ``netsim completion``.

``scenarios`` lists the scenarios and sweeps that install with netsim (:mod:`netsim.shipped`); ``completion``
prints a bash or zsh completion script that shtab writes from the command's own argument parser.
"""

from __future__ import annotations

import argparse
import sys

from netsim.status import EXIT_OK

__all__ = ["cmd_scenarios", "cmd_completion"]


def cmd_scenarios(args: argparse.Namespace) -> int:
    """``netsim scenarios``: each shipped scenario and sweep with its one-line summary (or ``--path``: the folder)."""
    from netsim import shipped

    if args.path:
        print(shipped.folder())
        return EXIT_OK
    items = shipped.catalogue()
    width = max((len(item.name) for item in items), default=0)
    for item in items:
        kind = "sweep   " if item.is_sweep else "scenario"
        print(f"{item.name:<{width}}  {kind}  {item.summary}".rstrip())
    return EXIT_OK


def cmd_completion(args: argparse.Namespace, parser: argparse.ArgumentParser) -> int:
    """``netsim completion bash|zsh``: a completion script written by shtab from ``parser``, the command's own."""
    import shtab

    sys.stdout.write(shtab.complete(parser, shell=args.shell))
    return EXIT_OK
