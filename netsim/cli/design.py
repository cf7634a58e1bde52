"""``netsim design FILE``: print what every ``state_feedback`` task of a scenario is designed to be, without running.

The scenario is loaded and validated as ``netsim run`` loads it (``--set`` applied), the plant and io channels
are built as ``netsim validate`` builds them, and each task's model, estimator and law are made by the same code
a run uses (:func:`netsim.programs.feedback_design.task_design`: the design the scenario's validation made, no
Riccati equation solved again). The summary is
:mod:`netsim.programs.design_summary`'s: the same data a run writes to ``design.json`` (``--json`` prints that
file's text), or by default a table per task.
"""

from __future__ import annotations

import argparse
import sys
from typing import TYPE_CHECKING, Any

from netsim.status import EXIT_INVALID, EXIT_OK

if TYPE_CHECKING:  # pragma: no cover
    from netsim.scenario.schema import Scenario

__all__ = ["cmd_design", "format_designs", "scenario_designs"]


def _g(x: Any) -> str:
    return "-" if x is None else f"{x:.6g}"


def _count(k: int, word: str) -> str:
    return f"{k} {word}{'s' if k != 1 else ''}"


def _mat(M: Any) -> str:
    if M is None:
        return "-"
    return "[" + ", ".join("[" + ", ".join(_g(v) for v in row) + "]" for row in M) + "]"


def _z(re_: float, im_: float) -> str:
    if im_ == 0:
        return f"{re_:.6g}"
    return f"{re_:.6g}{'+' if im_ > 0 else '-'}{abs(im_):.6g}j"


def _eig_table(parts: list[tuple[str, dict[str, Any]]]) -> list[str]:
    """Eigenvalues side by side, one column per part (each cell ``z  |z|``), then each part's radius and verdict."""
    cols: list[list[str]] = []
    for title, part in parts:
        ev = part.get("eigenvalues")
        if ev is None:
            cols.append([title, "-"])
            continue
        cells = [f"{_z(re_, im_)}  {mag:.4g}" for (re_, im_), mag in zip(ev, part["magnitudes"])]
        verdict = "stable" if part.get("stable") else "UNSTABLE"
        cols.append([title, *cells, f"radius {part['spectral_radius']:.6g}: {verdict}"])
    depth = max(len(c) for c in cols)
    for c in cols:
        c[-1:-1] = [""] * (depth - len(c))
    widths = [max(len(x) for x in c) for c in cols]
    head = "  eigenvalues"
    out = []
    for i in range(depth):
        lead = head if i == 0 else ""
        out.append(f"{lead:<17}" + "   ".join(c[i].ljust(w) for c, w in zip(cols, widths)).rstrip())
    return out


def _margin(dm: dict[str, Any], period_s: float) -> str:
    if dm.get("seconds") is not None:
        return f"{dm['seconds'] * 1e3:.6g} ms (stable up to {dm['stable_up_to_s'] * 1e3:.6g} ms; period " \
               f"{period_s * 1e3:.6g} ms)"
    if dm.get("stable_up_to_s") is not None:
        return f">= {dm['stable_up_to_s'] * 1e3:.6g} ms: {dm['reason']}"
    return f"unknown: {dm.get('reason')}"


def format_designs(name: str, designs: dict[str, dict[str, Any]]) -> str:
    """The human-readable table of :func:`netsim.programs.design_summary.static_designs`."""
    n = len(designs)
    lines = [f"{name}: {n} state_feedback task{'s' if n != 1 else ''}"]
    for key, d in sorted(designs.items()):
        model, law, est = d["model"], d["law"], d["estimator"]
        A = model["A"]
        B = model["B"]
        lines += ["", f"{key}  ({d['path']})",
                  f"  model          {model['source_text'] or model['source']}; period {model['period_s'] * 1e3:.6g} ms, "
                  f"{_count(len(A), 'state')}, {_count(len(B[0]) if B else 0, 'input')}, measured outputs {model['measured_outputs']}",
                  f"                 A = {_mat(A)}",
                  f"                 B = {_mat(B)}",
                  f"                 C = {_mat(model['C'])}"]
        lines.append(f"  law            {d['law_type']}: K = {_mat(law['K'])}, Ki = {_mat(law['Ki'])}")
        if law.get("pid") is not None:
            lines.append("                 " + ", ".join(f"{k} = {_g(v)}" for k, v in law["pid"].items()))
        if law.get("note"):
            lines.append(f"                 ({law['note']})")
        form = f", {est['form']} form" if est.get("form") else ""
        lines.append(f"  estimator      {d['estimator_type']}{form}: L = {_mat(est['gain'])}")
        if est.get("gain_kind"):
            lines.append(f"                 ({est['gain_kind']})")
        if est.get("dare_prior_covariance") is not None:
            lines.append(f"                 DARE prior M = {_mat(est['dare_prior_covariance'])}")
        if est.get("reason"):
            lines.append(f"                 ({est['reason']})")
        integ = " + integrator" if law.get("with_integrator") else ""
        lines += _eig_table([(f"state feedback{integ}", law), ("observer", est), ("nominal loop", d["nominal"])])
        for why in (d["nominal"].get("reason"), d["nominal"].get("note")):
            if why:
                lines.append(f"                 (nominal loop: {why})")
        lines.append(f"  delay margin   {_margin(d['delay_margin'], model['period_s'])}")
    return "\n".join(lines) + "\n"


def scenario_designs(scenario: Scenario, *, margin: bool = True) -> dict[str, dict[str, Any]]:
    """:func:`static_designs` of a valid scenario, its plant and io channels built as ``netsim validate`` builds
    them (:mod:`netsim.build.dry_run`); what ``netsim design`` prints."""
    from netsim.env import SimEnv
    from netsim.programs.design_summary import static_designs
    from netsim.build.builder import _build_io, _build_plant, _make_signals

    env = SimEnv(seed=scenario.seed, record=None if scenario.record is None else set(scenario.record))
    plant = _build_plant(scenario, env, _make_signals(scenario))
    _build_io(scenario, env, plant)
    return static_designs(scenario, plant, margin=margin)


def cmd_design(args: argparse.Namespace) -> int:
    """``netsim design FILE [--set ...] [--json]``."""
    from netsim.cli.commands import _err, _is_sweep, _overrides, _print_problems
    from netsim.errors import ConfigError
    from netsim.programs.design_summary import design_json
    from netsim.scenario import ScenarioError, load_scenario

    if _is_sweep(args.file):
        raise ConfigError(f"{args.file}: this is a sweep file; give its base scenario to netsim design")
    try:
        scenario = load_scenario(args.file, _overrides(args.overrides) or None)
    except ScenarioError as exc:
        _print_problems(exc.problems, sys.stderr)
        n = len(exc.errors)
        _err(f"{args.file}: {n} problem{'s' if n != 1 else ''}; nothing was designed")
        return EXIT_INVALID
    designs = scenario_designs(scenario)
    if args.json:
        sys.stdout.write(design_json(designs))
    else:
        sys.stdout.write(format_designs(scenario.name, designs))
    return EXIT_OK
