"""Plants from FMUs: ``plant: {type: fmu, path: ...}`` runs an FMI 2.0 or FMI 3.0 FMU with FMPy.

A scenario writes::

    plant:
      type: fmu
      path: fmu/dc_motor          # a .fmu file or an unpacked FMU folder, relative to the scenario file
      interface: co_simulation    # or model_exchange (default: co-simulation when the FMU has it)
      inputs: [u]                 # FMU input variables, in plant input order (default: all, as declared)
      outputs: [theta]            # FMU output variables, in plant output order (default: all)
      states: [theta, omega]      # variables read as the plant state (default: the states of the FMU's
                                  # ModelStructure/Derivatives; none: no state)
      parameters: {k: 1000, a: 1} # start values set before initialisation
      x0: [0, 0]                  # the plant section's own keys as for every plant
      record_grid: 1 ms

The names are the FMU's variable names: ``io`` channels name them as they name any plant port
(``{type: dac, input: u}``, ``{type: adc, output: theta}``). The variables mapped are scalar floating-point ones:
``Real`` in FMI 2.0, ``Float64`` in FMI 3.0; naming a variable of another type (an FMI 3.0 ``Float32`` or
``Int32``, an array) is refused at its YAML path.

**An FMU is code.** Its library runs inside netsim, so an ``fmu`` plant is loaded only with the permission
plugin files need (:mod:`netsim.trust`: ``--allow-plugins``, ``allow_plugins=True``, ``NETSIM_ALLOW_PLUGINS``
or the user's config); without it ``netsim validate`` and ``netsim run`` refuse the scenario at ``plant.path``.
A relative ``path`` is read from the scenario file's folder (the working folder for a scenario given as a
mapping; a sweep writes its base scenario's FMU path as an absolute path, :func:`absolute_fmu_path`).

**Co-simulation: stepping.** The plant is advanced lazily like every plant (:mod:`netsim.plant`): when anything
samples or actuates it, one ``fmi2DoStep`` (``fmi3DoStep``) takes the FMU from the plant's time to that instant
under the inputs held since the last change (zero-order hold), and ``fmi2SetReal`` (``fmi3SetFloat64``) writes an
input when it changes. So the FMU is stepped exactly between the events that touch it. The recorder's ``record_grid`` samples are such events too:
the plant steps to each record instant, so the recorded outputs are the FMU's own values there, not an
interpolation (an FMU that integrates with a fixed internal step is therefore asked for communication steps that
need not be multiples of it: the FMU decides how it handles a short step). ``x0`` sets the state variables during
initialisation (before the first step); setting the state later (state noise) is refused, and disturbances must
be piecewise constant or held (no sinusoid, no continuous disturbance model).

**Model exchange.** netsim integrates the FMU's derivatives with the plant's integrator
(:mod:`netsim.plant.fmu_exchange`); FMUs with event indicators (state events) are refused.

**FMI 3.0.** The same plant runs FMI 3.0 FMUs (FMPy's ``FMU3Slave`` and ``FMU3Model``): start values are set
after instantiation and the start time is given to ``fmi3EnterInitializationMode`` (FMI 3.0 has no
``setupExperiment``); a co-simulation FMU is instantiated without event mode and without early return, so it
handles its own events inside ``fmi3DoStep``, and a step that ends early or asks to terminate stops the run with
the instant. FMUs with clocks are refused at ``plant.interface``; configuration mode is not used (structural
parameters keep their start values). FMI 1.0 FMUs are refused at ``plant.path``. The FMU's files are read,
unpacked and (a source FMU) compiled by :mod:`netsim.plant.fmu_files`.
"""

from __future__ import annotations

import logging
import weakref
from pathlib import Path
from typing import Any, Literal, Sequence

import numpy as np
from pydantic import Field, PrivateAttr, ValidationInfo, field_validator, model_validator

from netsim.errors import ConfigError, SimulationError
from netsim.plant.base import Plant
from netsim.plant.disturbance import _Source
from netsim.registry import register
from netsim.units import StrictModel

__all__ = ["FmuParams", "FmuPlant", "absolute_fmu_path", "fmu_plant"]

_log = logging.getLogger(__name__)

#: The refusal without permission (the words of the loader's refusal of a plugin file).
NOT_ALLOWED = "this scenario loads code from the FMU"

#: Disturbance kinds an FMU plant takes (piecewise-constant inputs: held, so exact).
_KINDS = ("piecewise", "held", "lti_d")


def _resolve(written: str) -> Path:
    from netsim.trust import scenario_folder

    path = Path(written).expanduser()
    return (path if path.is_absolute() else scenario_folder() / path).resolve()


_DESCRIPTIONS: dict[tuple[str, int, int], Any] = {}


def _description(path: Path) -> Any:
    """The model description of ``path``, read once per (path, modification time, size)."""
    from netsim.plant.fmu_files import read_description

    try:
        st = path.stat()
        key = (str(path), st.st_mtime_ns, st.st_size)
    except OSError:
        return read_description(path)  # raises: not found
    found = _DESCRIPTIONS.get(key)
    if found is None:
        found = _DESCRIPTIONS[key] = read_description(path)
    return found


def _real(md: Any) -> str:
    """The variable type netsim maps: ``Real`` (FMI 2.0) or ``Float64`` (FMI 3.0)."""
    return "Real" if md.fmiVersion == "2.0" else "Float64"


def _variables(md: Any, causality: str | None = None) -> dict[str, Any]:
    """The FMU's scalar ``Real``/``Float64`` variables (of ``causality``) by name."""
    real = _real(md)
    return {v.name: v for v in md.modelVariables
            if v.type == real and not v.shape and (causality is None or v.causality == causality)}


def _why_not(md: Any, name: str, causality: str | None = None) -> str:
    """`` ('n' is Int32: ...)`` when ``name`` is a variable (of ``causality``) netsim cannot map, else ``''``."""
    found = next((v for v in md.modelVariables if v.name == name), None)
    if found is None or (causality is not None and found.causality != causality):
        return ""
    if found.type != _real(md):
        return f" ('{name}' is {found.type}: netsim maps {_real(md)} variables only)"
    if found.shape:
        return f" ('{name}' is an array of shape {tuple(found.shape)}: netsim maps scalar variables only)"
    return ""


def _clocks(md: Any) -> list[str]:
    return [v.name for v in md.modelVariables if v.type == "Clock"]


def _interface_of(md: Any, chosen: str | None) -> str:
    if chosen is not None:
        return chosen
    return "co_simulation" if md.coSimulation is not None else "model_exchange"


def _default_states(md: Any) -> list[str]:
    return [d.variable.derivative.name for d in md.derivatives if d.variable.derivative is not None]


class FmuParams(StrictModel):
    """An FMI 2.0 or 3.0 FMU run by FMPy (co-simulation or model exchange): inputs, outputs and states by variable
    name."""

    path: str = Field(min_length=1, description="the .fmu file or unpacked FMU folder, relative to the scenario "
                                                "file (loaded only with --allow-plugins: an FMU is code)")
    interface: Literal["co_simulation", "model_exchange"] | None = Field(
        None, validate_default=True, description="co_simulation: the FMU steps itself (doStep); model_exchange: netsim integrates its "
                          "derivatives (plant.integrator); default: co-simulation when the FMU has it")
    inputs: list[str] | None = Field(None, description="FMU input variables, in plant input order (default: all)")
    outputs: list[str] | None = Field(None, description="FMU output variables, in plant output order (default: all)")
    states: list[str] | None = Field(None, description="FMU variables read as the plant state (default: the states "
                                                       "of ModelStructure/Derivatives)")
    parameters: dict[str, float] = Field(default_factory=dict, description="start values of FMU variables, set "
                                                                           "before initialisation")
    name: str = Field("plant", min_length=1, description="plant name (recorded as <name>.x, <name>.u)")
    _file: Path | None = PrivateAttr(default=None)

    @field_validator("path")
    @classmethod
    def _path(cls, value: str) -> str:
        from netsim.trust import plugins_allowed

        path = _resolve(value)
        if not plugins_allowed():
            raise ValueError(f"{NOT_ALLOWED} {path}; rerun with --allow-plugins if you trust it "
                             "(Python: allow_plugins=True)")
        try:
            _description(path)
        except ConfigError as exc:
            raise ValueError(exc.message) from None
        return value

    @field_validator("interface")
    @classmethod
    def _interface(cls, value: str | None, info: ValidationInfo) -> str | None:
        md = cls._md(info)
        if md is None:
            return value
        if value is not None and (md.coSimulation if value == "co_simulation" else md.modelExchange) is None:
            has = "co_simulation" if md.coSimulation is not None else "model_exchange"
            raise ValueError(f"the FMU has no {value} interface; it has {has} only")
        if _clocks(md):
            raise ValueError(f"the FMU has clocks {_clocks(md)[:5]}; netsim runs FMUs without clocks (FMI 3.0 "
                             "scheduled execution and clocked partitions are not supported)")
        if _interface_of(md, value) == "model_exchange" and md.numberOfEventIndicators:
            raise ValueError(f"the FMU's model exchange interface has {md.numberOfEventIndicators} event indicators; "
                             "netsim integrates model-exchange FMUs without state events: use its co-simulation "
                             "interface (interface: co_simulation) or an FMU without events")
        return value

    @staticmethod
    def _md(info: ValidationInfo) -> Any:
        written = info.data.get("path")
        return None if written is None else _description(_resolve(written))

    @field_validator("inputs", "outputs")
    @classmethod
    def _ports(cls, value: list[str] | None, info: ValidationInfo) -> list[str] | None:
        md = cls._md(info)
        if value is None or md is None:
            return value
        causality = "input" if info.field_name == "inputs" else "output"
        known = _variables(md, causality)
        for name in value:
            if name not in known:
                raise ValueError(f"the FMU has no {_real(md)} {causality} '{name}'{_why_not(md, name, causality)}; "
                                 f"its {causality}s are {list(known)}")
        if len(set(value)) != len(value):
            raise ValueError(f"{info.field_name} must be unique names, got {value}")
        return value

    @field_validator("states")
    @classmethod
    def _states(cls, value: list[str] | None, info: ValidationInfo) -> list[str] | None:
        md = cls._md(info)
        if value is None or md is None:
            return value
        known = _variables(md)
        for name in value:
            if name not in known:
                raise ValueError(f"the FMU has no {_real(md)} variable '{name}'{_why_not(md, name)}; its states are "
                                 f"{_default_states(md)}")
        if _interface_of(md, info.data.get("interface")) == "model_exchange" and value != _default_states(md):
            raise ValueError(f"with model exchange the state is the FMU's continuous state {_default_states(md)}; "
                             "omit states or list exactly these")
        return value

    @field_validator("parameters")
    @classmethod
    def _parameters(cls, value: dict[str, float], info: ValidationInfo) -> dict[str, float]:
        md = cls._md(info)
        if md is None:
            return value
        known = {n: v for n, v in _variables(md).items() if v.causality == "parameter" or v.initial == "exact"}
        for name in value:
            if name not in known:
                raise ValueError(f"the FMU has no {_real(md)} parameter '{name}' to set{_why_not(md, name)}; its "
                                 f"parameters are {[n for n, v in known.items() if v.causality == 'parameter']}")
        return value

    @model_validator(mode="after")
    def _remember(self) -> "FmuParams":
        self._file = _resolve(self.path)  # the scenario folder is known only while validating
        return self

    def kind(self) -> str:
        """The interface run: ``co_simulation`` or ``model_exchange``."""
        return _interface_of(self.description(), self.interface)

    def file(self) -> Path:
        """The FMU's absolute path (resolved when validated)."""
        return self._file if self._file is not None else _resolve(self.path)

    def description(self) -> Any:
        """FMPy's model description of the FMU."""
        return _description(self.file())

    def port_names(self) -> tuple[list[str], list[str], list[str]]:
        """``(inputs, outputs, states)``, the defaults filled in from the model description."""
        md = self.description()
        ins = list(self.inputs) if self.inputs is not None else list(_variables(md, "input"))
        outs = list(self.outputs) if self.outputs is not None else list(_variables(md, "output"))
        states = list(self.states) if self.states is not None else _default_states(md)
        return ins, outs, states


def _release(slave: Any, mode: list[str]) -> None:
    """Terminate and free the FMU instance (at garbage collection or exit).

    The library stays loaded: FMPy's ``freeLibrary`` unloads it even while another instance of the same FMU (the
    plant ``netsim validate`` built, another run in this process) still uses it, which crashes that one."""
    try:
        if mode[0] in ("init", "step"):
            if mode[0] == "step":
                slave.terminate()
            slave.freeInstance()
            mode[0] = "freed"
    except Exception as exc:  # noqa: BLE001 - a finaliser must not raise; the run's results are already made
        _log.debug("releasing the FMU failed: %s", exc)


class FmuPlant(Plant):
    """An FMI 2.0 or 3.0 co-simulation FMU as a plant: one ``doStep`` per propagation (see :mod:`netsim.plant.fmu`).

    Parameters
    ----------
    folder
        Unpacked FMU folder holding the library for this platform (:func:`netsim.plant.fmu_files.binary_folder`).
    description
        FMPy's model description.
    inputs, outputs, states
        Variable names of the plant's inputs, outputs and state.
    parameters
        Start values set after instantiation, before initialisation.
    name
        Plant name (also the FMU instance name).
    """

    _cache_output = True

    def __init__(self, folder: Path, description: Any, inputs: Sequence[str], outputs: Sequence[str],
                 states: Sequence[str], parameters: dict[str, float] | None = None, *, name: str = "plant",
                 divergence_bound: float = 1e12) -> None:
        super().__init__(len(states), len(inputs), len(outputs), input_names=list(inputs),
                         output_names=list(outputs), state_names=list(states), name=name,
                         divergence_bound=divergence_bound)
        variables = _variables(description)
        self._vr_in = [variables[n].valueReference for n in inputs]
        self._vr_out = [variables[n].valueReference for n in outputs]
        self._vr_x = [variables[n].valueReference for n in states]
        self._parameters = [(variables[n].valueReference, float(v)) for n, v in (parameters or {}).items()]
        self._fmi3 = description.fmiVersion != "2.0"
        if self._fmi3:
            from fmpy.fmi3 import FMU3Slave as Slave
        else:
            from fmpy.fmi2 import FMU2Slave as Slave
        self._slave = Slave(guid=description.guid, unzipDirectory=str(folder),
                            modelIdentifier=description.coSimulation.modelIdentifier, instanceName=name)
        # the typed value functions: fmi2GetReal/fmi2SetReal or fmi3GetFloat64/fmi3SetFloat64
        self._get = self._slave.getFloat64 if self._fmi3 else self._slave.getReal
        self._set = self._slave.setFloat64 if self._fmi3 else self._slave.setReal
        self._mode = ["loaded"]  # loaded -> init (instantiated, initialising) -> step (stepped at least once)
        weakref.finalize(self, _release, self._slave, self._mode)

    def _start(self) -> None:
        slave, start = self._slave, self._t / 1e9
        slave.instantiate()  # FMI 3.0: without event mode or early return (the FMU handles its events in doStep)
        if not self._fmi3:
            slave.setupExperiment(startTime=start)
        if self._parameters:
            self._set([vr for vr, _ in self._parameters], [v for _, v in self._parameters])
        if self._fmi3:
            slave.enterInitializationMode(startTime=start)  # FMI 3.0 has no setupExperiment
        else:
            slave.enterInitializationMode()
        self._mode[0] = "init"
        super()._start()

    def _check_source(self, src: _Source) -> None:
        if src.kind not in _KINDS:
            what = "state noise" if src.kind == "state" else f"a {src.kind} disturbance"
            raise ConfigError(f"plant {self.name}: an FMU plant takes piecewise-constant or held disturbances on its "
                              f"inputs only, not {what} (an LTI plant takes it)")

    def add_state_noise(self, states: Sequence[int | str], sigma: float | Sequence[float], sample_ns: int,
                        model: str = "increment") -> None:
        """Refused: noise on the state would set the FMU's state during the run (see :meth:`_set_state_now`)."""
        raise ConfigError(f"plant {self.name}: an FMU plant takes no state noise (its state can be set only before "
                          "the first step); put the noise on an input ({inputs: [...], sigma, sample})")

    def _update_effective_input(self, t: int) -> None:
        if self._mode[0] == "loaded" or not self._vr_in:
            return
        u = self._piecewise_input() if self._sources else self._u
        self._set(self._vr_in, u.tolist())

    def _step(self, t: int) -> bool:
        slave = self._slave
        if self._mode[0] == "init":
            slave.exitInitializationMode()
            self._mode[0] = "step"
        try:
            done = slave.doStep(self._t / 1e9, (t - self._t) / 1e9)
        except Exception as exc:  # noqa: BLE001 - FMPy's FMICallException, reported with the instant
            raise SimulationError(f"plant {self.name}: the FMU's doStep to t = {t / 1e9:.9g} s failed: {exc}") from None
        if self._fmi3:
            _check_fmi3_step(self.name, t, done)
        self._t = t
        x = self._state_now() if self._vr_x else self._output_now()
        if not (x.dot(x) <= self._bound2):
            self._diverged(t, x)
        return False

    def _output_now(self) -> np.ndarray:
        return np.array(self._get(self._vr_out), dtype=float)

    def _state_now(self) -> np.ndarray:
        if not self._vr_x:
            return np.zeros(0)
        return np.array(self._get(self._vr_x), dtype=float)

    def _set_state_now(self, x: np.ndarray) -> None:
        if self._mode[0] != "init":
            raise SimulationError(f"plant {self.name}: an FMU's state can be set only before its first step "
                                  "(x0), not during the run")
        if self._vr_x:
            self._set(self._vr_x, [float(v) for v in x])


def _check_fmi3_step(name: str, t: int, done: Any) -> None:
    """Stop the run when an FMI 3.0 ``doStep`` to ``t`` ns asked to terminate or did not reach ``t``.

    ``done`` is FMPy's ``(eventHandlingNeeded, terminateSimulation, earlyReturn, lastSuccessfulTime)``;
    eventHandlingNeeded is meaningless without event mode (the FMU was instantiated with eventModeUsed false)."""
    _, terminate, early, last = done
    if terminate:
        raise SimulationError(f"plant {name}: the FMU asked to terminate the simulation in its step to "
                              f"t = {t / 1e9:.9g} s (fmi3DoStep's terminateSimulation)")
    if early:
        raise SimulationError(f"plant {name}: the FMU's step to t = {t / 1e9:.9g} s returned early at "
                              f"t = {last:.9g} s")


@register("plant", "fmu", "an FMI 2.0 or 3.0 FMU run by FMPy, co-simulation or model exchange (needs --allow-plugins: "
                          "an FMU is code)")
def fmu_plant(params: FmuParams) -> FmuPlant:
    """The plant of ``plant: {type: fmu, ...}``: the FMU unpacked (and a source FMU compiled) once, then loaded: an
    :class:`FmuPlant` (co-simulation) or a :class:`~netsim.plant.nonlinear.NonlinearPlant` over the FMU's
    derivatives (model exchange, :mod:`netsim.plant.fmu_exchange`)."""
    from netsim.errors import BuildError
    from netsim.plant.fmu_files import binary_folder

    md = params.description()
    kind = params.kind()
    try:
        folder = binary_folder(params.file(), md, kind)
    except ConfigError as exc:
        raise BuildError(exc.message, path="plant.path") from None
    ins, outs, states = params.port_names()
    if kind == "model_exchange":
        from netsim.plant.fmu_exchange import exchange_plant

        try:
            return exchange_plant(folder, md, ins, outs, params.parameters, name=params.name)
        except ConfigError as exc:  # an FMI 3.0 FMU with a time event or a request to terminate at initialisation
            raise BuildError(exc.message, path="plant.interface") from None
    return FmuPlant(folder, md, ins, outs, states, params.parameters, name=params.name)


def absolute_fmu_path(raw: dict[str, Any], folder: Path) -> None:
    """Write the FMU path of a raw scenario's ``fmu`` plant as an absolute path, relative paths taken from ``folder``
    (a sweep's base scenario: its points are validated as mappings, in worker processes with their own working
    folders)."""
    plant = raw.get("plant")
    if not isinstance(plant, dict) or "fmu" not in (plant.get("type"), plant.get("model")):
        return
    params = plant.get("params")
    holder = params if isinstance(params, dict) and "path" in params else plant
    written = holder.get("path")
    if isinstance(written, str) and written and not Path(written).expanduser().is_absolute():
        holder["path"] = str((folder / written).resolve())


def _fmu_ports(params: FmuParams) -> tuple[list[Any], list[Any]]:
    ins, outs, _ = params.port_names()
    return ins, outs


fmu_plant.Params = FmuParams  # type: ignore[attr-defined]
fmu_plant.ports = _fmu_ports  # type: ignore[attr-defined]
