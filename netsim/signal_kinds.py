"""What a scenario declares about its recorded signals, for figures: each signal's kind (sensor, actuator,
reference), the loops signals belong to, their units, and how a name is typeset.

Everything is read from declared parameters (``io`` channel types and ``unit:``, ``signals``, the tasks' and
metrics' ``channel``/``output``/``reference``), never guessed from names. :mod:`netsim.plotting` re-exports it.
"""

from __future__ import annotations

from typing import Any, Mapping

__all__ = ["signal_roles", "signal_loops", "signal_units", "signal_label"]


def signal_roles(scenario: Mapping[str, Any] | None) -> dict[str, str]:
    """Each declared signal's kind from the scenario: ``sensor``, ``actuator`` or ``reference``.

    ``io`` channels of type ``adc`` and ``encoder`` are sensors, ``dac`` actuators (also their
    ``<name>.command``), ``signals`` entries references. Names the scenario does not declare are absent.
    """
    roles: dict[str, str] = {}
    if not scenario:
        return roles
    for name, ch in (scenario.get("io") or {}).items():
        kind = (ch or {}).get("type") if isinstance(ch, Mapping) else None
        if kind == "dac":
            roles[name] = roles[f"{name}.command"] = "actuator"
        elif kind in ("adc", "encoder"):
            roles[name] = "sensor"
    for name in scenario.get("signals") or {}:
        roles.setdefault(name, "reference")
    return roles


def signal_loops(scenario: Mapping[str, Any] | None) -> list[list[str]]:
    """Groups of signals that belong to one loop, from declared parameters (never from their names).

    A task's or handler's ``channel`` (the measured output), ``output_channel`` and ``reference`` form a loop,
    and a metric's ``output`` and ``reference``; loops sharing an output or an actuator merge. A reference that
    several loops follow (three servos on one set-point) belongs to none of them: it is drawn in black.
    """
    loops: list[tuple[set[str], set[str]]] = []  # (outputs and actuators, references)

    def add(own: list[Any], refs: list[Any]) -> None:
        mine = {n for n in own if isinstance(n, str) and n}
        follows = {n for n in refs if isinstance(n, str) and n}
        if not mine:
            return
        for loop in [lp for lp in loops if lp[0] & mine]:
            mine |= loop[0]
            follows |= loop[1]
            loops.remove(loop)
        loops.append((mine, follows))

    if scenario:
        for node in (scenario.get("nodes") or {}).values():
            for kind in ("tasks", "handlers"):
                for entry in (node or {}).get(kind) or []:
                    p = (entry or {}).get("params") or {}
                    add([p.get("channel"), p.get("output_channel")], [p.get("reference")])
        for metric in scenario.get("metrics") or []:
            p = (metric or {}).get("params") or {}
            add([p.get("output")], [p.get("reference")])
    followed = [r for _, refs in loops for r in refs]
    shared = {r for r in followed if followed.count(r) > 1}
    groups = [sorted(own | (refs - shared)) for own, refs in loops]
    return [g for g in groups if len(g) > 1]


def signal_units(scenario: Mapping[str, Any] | None, ports: tuple[list[str], list[str]] | None = None
                 ) -> dict[str, str]:
    """Each signal's unit, from the ``unit:`` of the scenario's ``io`` channels (never from names).

    An ADC or encoder channel's unit is also that of the plant output it reads (named, e.g. ``output: theta``,
    or numbered, ``output: 0``, when ``ports`` gives the plant's ``(output names, input names)``); a DAC's that
    of ``<name>.command`` and of the plant input it drives. A reference takes the unit
    of the outputs that follow it (a task's ``channel``, a metric's ``output``; a state-feedback task's measured
    outputs) when they agree. Signals whose unit nobody declared are absent.

    Examples
    --------
    >>> signal_units({"io": {"y": {"type": "adc", "output": "angle", "unit": "rad"}}})
    {'y': 'rad', 'angle': 'rad'}
    >>> signal_units({"io": {"y": {"type": "adc", "output": 1, "unit": "m/s"}}}, (["p", "v"], ["u"]))
    {'y': 'm/s', 'v': 'm/s'}
    """
    units: dict[str, str] = {}
    if not scenario:
        return units
    for name, ch in (scenario.get("io") or {}).items():
        if not isinstance(ch, Mapping) or not ch.get("unit"):
            continue
        unit = str(ch["unit"])
        units[name] = unit
        port = ch.get("input") if ch.get("type") == "dac" else ch.get("output")
        if isinstance(port, int) and not isinstance(port, bool) and ports is not None:
            known = ports[1] if ch.get("type") == "dac" else ports[0]
            port = known[port] if 0 <= port < len(known) else None
        if isinstance(port, str):
            units.setdefault(port, unit)
        if ch.get("type") == "dac":
            units[f"{name}.command"] = unit
    followers: dict[str, set[str]] = {}

    def follow(ref: Any, outs: list[Any]) -> None:
        if isinstance(ref, str) and ref:
            followers.setdefault(ref, set()).update(units[o] for o in outs if isinstance(o, str) and o in units)

    for node in (scenario.get("nodes") or {}).values():
        for kind in ("tasks", "handlers"):
            for entry in (node or {}).get(kind) or []:
                p = (entry or {}).get("params") or {}
                measured = [o for m in p.get("measurements") or [] if isinstance(m, Mapping)
                            for o in [m.get("channel"), *(m.get("outputs") or [])]]
                follow(p.get("reference"), [p.get("channel"), *measured])
    for metric in scenario.get("metrics") or []:
        p = (metric or {}).get("params") or {}
        follow(p.get("reference"), [p.get("output")])
    for ref, found in followers.items():
        if len(found) == 1 and ref not in units:
            units[ref] = next(iter(found))
    return units


def signal_label(name: str) -> str:
    """A signal's name as printed in a legend: ``x_hat[3]`` -> :math:`\\hat{x}_3`, ``alpha`` -> :math:`\\alpha`,
    ``theta_m`` -> :math:`\\theta_m`, ``r`` -> :math:`r`; a name with nothing to typeset stays as written (``y1``,
    ``u.command``).

    Examples
    --------
    >>> signal_label("x_hat[3]"), signal_label("alpha"), signal_label("y1")
    ('$\\\\hat{x}_{3}$', '$\\\\alpha$', 'y1')
    """
    from netsim.figure_style import symbol

    base, _, rest = name.partition("[")
    index = rest.rstrip("]") if rest.endswith("]") else ""
    if (rest and not index) or "." in base or not base:
        return name
    hat = base.endswith("_hat") and len(base) > 4
    stem = base[:-4] if hat else base
    shown = symbol(stem)
    if shown.startswith("$"):
        core = shown.strip("$")
    elif stem.isidentifier() and "_" not in stem and len(stem) == 1:
        core = stem
    elif not hat and not index:
        return shown if "_" in stem else name
    else:
        core = r"\mathrm{" + shown.replace(" ", r"\ ") + "}"
    if hat:
        core = r"\hat{" + core + "}"
    if index:
        core = core + "_{" + index + "}" if "_{" not in core else "{" + core + "}_{" + index + "}"
    return f"${core}$" if (hat or index or shown.startswith("$") or len(stem) == 1) else name
