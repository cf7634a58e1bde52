"""A run's recorded signals as other libraries' objects: python-control's :class:`control.TimeResponseData`.

Which recorded columns are the plant's outputs, inputs and states is read from the plant itself (built again from
the run's resolved scenario, never run): its output names (recorded on ``plant.record_grid``), its held inputs
``<plant>.u[i]`` and states ``<plant>.x[i]`` (recorded at events when ``record:`` is omitted or names
``<plant>.u``/``<plant>.x``). Where the plant's own outputs or inputs were not recorded, the ``io`` channels stand
in: the ADC and encoder readings for the outputs, the DAC values for the inputs.
"""

from __future__ import annotations

import logging
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np
import pandas as pd

if TYPE_CHECKING:
    from control import TimeResponseData

__all__ = ["PlantColumns", "plant_columns", "to_timeresponse"]

log = logging.getLogger(__name__)


@dataclass(frozen=True)
class PlantColumns:
    """Recorded signal columns by role, each with the label it gets (the plant's port or state name).

    Attributes
    ----------
    outputs, inputs, states : list of (str, str)
        ``(column of the signals table, label)`` pairs, in the plant's port order; empty when none is recorded.
    """

    outputs: list[tuple[str, str]]
    inputs: list[tuple[str, str]]
    states: list[tuple[str, str]]


def _plant_names(scenario: Mapping[str, Any] | None) -> tuple[str, list[str], list[str], list[str]] | None:
    """``(name, output names, input names, state names)`` of the scenario's plant, or None without one (or when
    it cannot be built here: a plugin plant not allowed in this session, say)."""
    if not scenario or not scenario.get("plant"):
        return None
    from netsim.errors import NetsimError
    from netsim.scenario import load_scenario
    from netsim.build.builder import make_plant

    try:
        spec = load_scenario(dict(scenario)).plant
        if spec is None:
            return None
        plant = make_plant(spec.model, spec.plugin(), spec.validated_params())
    except NetsimError as exc:  # the io channels stand in (plant_columns)
        log.info("to_timeresponse: the plant cannot be built again (%s); using the io channels", exc)
        return None
    return plant.name, list(plant.output_names), list(plant.input_names), list(plant.state_names)


def _indexed(columns: Sequence[str], prefix: str, labels: list[str]) -> list[tuple[str, str]]:
    found = [(f"{prefix}[{i}]", label) for i, label in enumerate(labels)]
    return found if found and all(c in columns for c, _ in found) else []


def plant_columns(signals: pd.DataFrame, scenario: Mapping[str, Any] | None) -> PlantColumns:
    """The recorded plant outputs, inputs and states of a run (see the module docstring for the rules).

    Parameters
    ----------
    signals : pandas.DataFrame
        The run's signals table (``time_s`` first).
    scenario : Mapping or None
        The run's resolved scenario (``RunResult.scenario``).

    Returns
    -------
    PlantColumns
        The columns and their labels.

    Examples
    --------
    >>> import pandas as pd
    >>> table = pd.DataFrame({"time_s": [0.0], "y": [0.0], "u": [1.0]})
    >>> scenario = {"io": {"y": {"type": "adc", "output": 0}, "u": {"type": "dac", "input": 0}}}
    >>> plant_columns(table, scenario)
    PlantColumns(outputs=[('y', 'y')], inputs=[('u', 'u')], states=[])
    """
    columns = [c for c in signals.columns if c != "time_s"]
    names = _plant_names(scenario)
    outputs: list[tuple[str, str]] = []
    inputs: list[tuple[str, str]] = []
    states: list[tuple[str, str]] = []
    if names is not None:
        plant, out_names, in_names, state_names = names
        outputs = [(n, n) for n in out_names if n in columns]
        inputs = _indexed(columns, f"{plant}.u", in_names)
        states = _indexed(columns, f"{plant}.x", state_names)
    io = (scenario or {}).get("io") or {}
    kinds = {name: (ch or {}).get("type") for name, ch in io.items() if isinstance(ch, Mapping)}
    if not outputs:
        outputs = [(n, n) for n, kind in kinds.items() if kind in ("adc", "encoder") and n in columns]
    if not inputs:
        inputs = [(n, n) for n, kind in kinds.items() if kind == "dac" and n in columns]
    return PlantColumns(outputs, inputs, states)


def _block(signals: pd.DataFrame, pairs: list[tuple[str, str]]) -> np.ndarray:
    return np.vstack([signals[c].to_numpy(dtype=float) for c, _ in pairs])


def to_timeresponse(signals: pd.DataFrame, scenario: Mapping[str, Any] | None, *, name: str = "",
                    outputs: Sequence[str] | None = None, inputs: Sequence[str] | None = None,
                    states: Sequence[str] | None = None) -> TimeResponseData:
    """The recorded signals as a python-control :class:`control.TimeResponseData`.

    Parameters
    ----------
    signals : pandas.DataFrame
        The run's signals table (``time_s`` first; each column holds its last value between its samples, and is
        NaN before its first).
    scenario : Mapping or None
        The run's resolved scenario: the source of the plant's port and state names (:func:`plant_columns`).
    name : str, optional
        The response's ``sysname`` (the scenario's name).
    outputs, inputs, states : sequence of str, optional
        Recorded columns to use instead of the plant's (labelled by their column names); ``states=[]`` leaves the
        states out.

    Returns
    -------
    control.TimeResponseData
        ``time`` in seconds; ``outputs``, ``inputs`` and ``states`` one row per signal, with their labels.

    Raises
    ------
    KeyError
        A named column was not recorded.
    ValueError
        No output was recorded (nothing to build a response from).

    Examples
    --------
    >>> import pandas as pd
    >>> table = pd.DataFrame({"time_s": [0.0, 0.1], "y": [0.0, 0.5], "u": [1.0, 1.0]})
    >>> io = {"io": {"y": {"type": "adc", "output": 0}, "u": {"type": "dac", "input": 0}}}
    >>> resp = to_timeresponse(table, io)
    >>> resp.output_labels, resp.input_labels, resp.outputs.tolist()
    (['y'], ['u'], [0.0, 0.5])
    """
    import control

    found = plant_columns(signals, scenario)
    missing = [c for c in (*(outputs or ()), *(inputs or ()), *(states or ())) if c not in signals.columns]
    if missing:
        raise KeyError(f"no recorded signal '{missing[0]}'; recorded: {', '.join(signals.columns[1:])}")
    outs = [(c, c) for c in outputs] if outputs is not None else found.outputs
    ins = [(c, c) for c in inputs] if inputs is not None else found.inputs
    xs = [(c, c) for c in states] if states is not None else found.states
    if not outs:
        raise ValueError("no plant output was recorded: record the plant's outputs (plant.record_grid) or an io "
                         "sensor channel, or name the columns with outputs=[...]")
    return control.TimeResponseData(
        signals["time_s"].to_numpy(dtype=float), _block(signals, outs),
        states=_block(signals, xs) if xs else np.empty((0, len(signals))),  # None breaks .states (control 0.10)
        inputs=_block(signals, ins) if ins else None,
        output_labels=[label for _, label in outs], input_labels=[label for _, label in ins] if ins else None,
        state_labels=[label for _, label in xs], sysname=name or None, plot_inputs=bool(ins))
