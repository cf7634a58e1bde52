"""Plants a scenario describes by their equations: ``plant: {type: ss, ...}`` and ``plant: {type: tf, ...}``.

Registered as plant models ``ss`` and ``tf`` (registry kind ``plant``), so a scenario writes either::

    plant: {type: ss, A: [[0, 1], [0, -1]], B: [[0], [1000]], C: [[1, 0]], D: 0, dt: null,
            inputs: [u], outputs: [y], x0: [0, 0], process_noise: [0, 1e-4]}
    plant: {type: tf, num: [1000], den: [1, 1, 0]}              # SISO
    plant: {type: tf, num: [[[1], [2]]], den: [[[1, 1], [1, 2]]]}   # MIMO: one list per output, per input

(``type: ss`` is short for ``model: ss`` with the matrices under ``params:``; both forms load the same.)

``ss``
    ``A`` (n x n), ``B`` (n x m), ``C`` (p x n), ``D`` (p x m; omitted or ``0``: zeros), ``dt``: ``null`` for a
    continuous model, propagated exactly by :class:`~netsim.plant.lti.LTIPlant` (one matrix exponential per
    distinct step length), or a time (``"10 ms"``) for a discrete model stepped at multiples of ``dt`` by
    :class:`~netsim.plant.discrete.DiscretePlant`. A 1-D ``B`` is one column (single input) and a 1-D ``C`` one
    row (single output). Each shape is checked against ``A`` with a message naming the field.
``tf``
    ``num``, ``den``: polynomial coefficients, highest power first (SISO), or a matrix of them (``num[i][j]`` is
    the numerator from input ``j`` to output ``i``). Converted once, when the plant is built, to a state-space
    realisation by python-control (``control.ss(control.tf(num, den, dt))``); the transfer function must be
    proper.

Both take ``inputs``, ``outputs`` (names; default ``u[0]``... / ``y[0]``...), ``states`` (``ss`` only) and
``name`` (default ``plant``, the prefix of the recorded ``<name>.x`` and ``<name>.u``). The initial state
(``x0``), process noise, disturbances and ``record_grid`` are the plant section's own keys.

From Python, :func:`plant_spec_from_system` turns a python-control ``StateSpace`` or ``TransferFunction`` into
the same YAML-able mapping (the matrices are extracted once), so a scenario given as a mapping may hold the
system object itself as its ``plant`` (:func:`resolve_plant_object`). A ``NonlinearIOSystem`` becomes the plant
model ``nonlinear_io``: a :class:`~netsim.plant.nonlinear.NonlinearPlant` whose right-hand side and output are
the system's ``updfcn(t, x, u, params)`` and ``outfcn`` (called by the ODE solver between events); the scenario
data holds a token naming the system (its name, ``updfcn`` and identity in this process), not the functions.
"""

from __future__ import annotations

from typing import Annotated, Any

import numpy as np
from pydantic import (
    BeforeValidator,
    Field,
    PlainSerializer,
    ValidationInfo,
    field_validator,
)

from netsim.errors import ConfigError
from netsim.registry import register
from netsim.units import Duration, StrictModel

__all__ = [
    "NonlinearIOParams",
    "SSParams",
    "TFParams",
    "is_control_system",
    "nonlinear_io_plant",
    "plant_spec_from_system",
    "resolve_plant_object",
    "ss_plant",
    "tf_plant",
]


def _matrix(value: Any, name: str) -> np.ndarray:
    """A finite 2-D float array from a number, a list or a list of lists (error text names ``name``)."""
    try:
        arr = np.array(value, dtype=float)
    except (TypeError, ValueError):
        raise ValueError(f"{name} must be a matrix of numbers (a list of rows), got {value!r:.80}") from None
    if arr.ndim == 0:
        arr = arr.reshape(1, 1)
    elif arr.ndim == 1:
        arr = arr.reshape(1, -1)
    if arr.ndim > 2:
        raise ValueError(f"{name} must be a matrix (a list of rows), got {arr.ndim} levels of lists")
    if not np.all(np.isfinite(arr)):
        raise ValueError(f"{name} contains NaN or infinite entries")
    return arr


def _size(info: ValidationInfo, key: str) -> int | None:
    value = info.data.get(key)
    return None if value is None else int(np.array(value, dtype=float).shape[0])


class SSParams(StrictModel):
    """A state-space plant ``x' = A x + B u`` (or ``x[k+1] = A x[k] + B u[k]`` with ``dt``), ``y = C x + D u``."""

    A: list[list[float]] = Field(description="state matrix, n x n")
    B: list[list[float]] = Field(description="input matrix, n x m (a 1-D list is one column)")
    C: list[list[float]] = Field(description="output matrix, p x n (a 1-D list is one row)")
    D: list[list[float]] | None = Field(None, description="feed-through, p x m (omitted or 0: zeros)")
    dt: Duration | None = Field(None, description="null: continuous; a time: discrete, stepped at dt")
    inputs: list[str] | None = Field(None, description="input names (m)")
    outputs: list[str] | None = Field(None, description="output names (p)")
    states: list[str] | None = Field(None, description="state names (n)")
    name: str = Field("plant", min_length=1, description="plant name (recorded as <name>.x, <name>.u)")

    @field_validator("A", mode="before")
    @classmethod
    def _a(cls, value: Any) -> Any:
        A = _matrix(value, "A")
        if A.shape[0] != A.shape[1]:
            raise ValueError(f"A must be square (n x n), got {A.shape[0]}x{A.shape[1]}")
        return A.tolist()

    @field_validator("B", mode="before")
    @classmethod
    def _b(cls, value: Any, info: ValidationInfo) -> Any:
        n = _size(info, "A")
        B = _matrix(value, "B")
        if np.ndim(value) == 1 and n is not None and n > 1:
            B = B.reshape(-1, 1)  # a list of n numbers: one input column
        if n is not None and B.shape[0] != n:
            raise ValueError(f"B must have n = {n} rows (one per state, as A), got {B.shape[0]}x{B.shape[1]}")
        return B.tolist()

    @field_validator("C", mode="before")
    @classmethod
    def _c(cls, value: Any, info: ValidationInfo) -> Any:
        n = _size(info, "A")
        C = _matrix(value, "C")
        if n is not None and C.shape[1] != n:
            raise ValueError(f"C must have n = {n} columns (one per state, as A), got {C.shape[0]}x{C.shape[1]}")
        return C.tolist()

    @field_validator("D", mode="before")
    @classmethod
    def _d(cls, value: Any, info: ValidationInfo) -> Any:
        if value is None:
            return None
        B, C = info.data.get("B"), info.data.get("C")
        if B is None or C is None:
            return _matrix(value, "D").tolist()
        p, m = len(C), len(B[0])
        D = _matrix(value, "D")
        if D.shape == (1, 1) and float(D[0, 0]) == 0.0:
            return np.zeros((p, m)).tolist()
        if D.size == p * m and D.shape != (p, m) and min(D.shape) == 1 and min(p, m) == 1:
            D = D.reshape(p, m)
        if D.shape != (p, m):
            raise ValueError(f"D must be p x m = {p}x{m} (rows of C x columns of B), got {D.shape[0]}x{D.shape[1]}")
        return D.tolist()

    @field_validator("inputs", "outputs", "states")
    @classmethod
    def _names(cls, value: list[str] | None, info: ValidationInfo) -> list[str] | None:
        if value is None:
            return None
        key = info.field_name
        ref = {"inputs": ("B", 1, "columns of B"), "outputs": ("C", 0, "rows of C"), "states": ("A", 0, "rows of A")}
        mat, axis, what = ref[key]  # type: ignore[index]
        M = info.data.get(mat)
        if M is not None:
            size = len(M) if axis == 0 else len(M[0])
            if len(value) != size:
                raise ValueError(f"{key} must name {size} signals (the {what}), got {len(value)}")
        if len(set(value)) != len(value):
            raise ValueError(f"{key} must be unique names, got {value}")
        return value

    def arrays(self) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """``(A, B, C, D)`` as float arrays (``D`` zeros when omitted)."""
        A, B, C = (np.array(M, dtype=float) for M in (self.A, self.B, self.C))
        D = np.zeros((C.shape[0], B.shape[1])) if self.D is None else np.array(self.D, dtype=float)
        return A, B, C, D


def _poly(value: Any, name: str) -> list[float]:
    try:
        arr = np.array(value, dtype=float)
    except (TypeError, ValueError):
        raise ValueError(f"{name} must be a list of coefficients (highest power first), got {value!r:.80}") from None
    arr = np.atleast_1d(arr)
    if arr.ndim != 1:
        raise ValueError(f"{name} must be a list of coefficients, got {arr.ndim} levels of lists")
    if not np.all(np.isfinite(arr)):
        raise ValueError(f"{name} contains NaN or infinite coefficients")
    return arr.tolist()


def _depth(value: Any) -> int:
    d = 0
    while isinstance(value, (list, tuple)) and value:
        value = value[0]
        d += 1
    return d


def _poly_matrix(value: Any, name: str) -> list[list[list[float]]]:
    """SISO (a list of numbers) or MIMO (a matrix of lists) coefficients as a p x m matrix of lists."""
    depth = _depth(value)
    if depth <= 1:
        return [[_poly(value, name)]]
    if depth != 3 or not all(isinstance(row, (list, tuple)) for row in value):
        raise ValueError(f"{name} must be a list of coefficients (SISO) or a matrix of such lists (MIMO: one row "
                         "per output, one list per input)")
    rows = [[_poly(entry, f"{name}[{i}][{j}]") for j, entry in enumerate(row)] for i, row in enumerate(value)]
    if len({len(r) for r in rows}) != 1:
        raise ValueError(f"{name}: every output row must list one polynomial per input (rows of different length)")
    return rows


class TFParams(StrictModel):
    """A transfer-function plant ``num / den`` (SISO) or a matrix of them (MIMO)."""

    num: Any = Field(description="numerator coefficients, highest power first (MIMO: [[num_ij]])")
    den: Any = Field(description="denominator coefficients, highest power first (MIMO: [[den_ij]])")
    dt: Duration | None = Field(None, description="null: continuous (s); a time: discrete (z), stepped at dt")
    inputs: list[str] | None = Field(None, description="input names (m)")
    outputs: list[str] | None = Field(None, description="output names (p)")
    name: str = Field("plant", min_length=1, description="plant name (recorded as <name>.x, <name>.u)")

    @field_validator("num", mode="before")
    @classmethod
    def _num(cls, value: Any) -> Any:
        return _poly_matrix(value, "num")

    @field_validator("den", mode="before")
    @classmethod
    def _den(cls, value: Any, info: ValidationInfo) -> Any:
        den = _poly_matrix(value, "den")
        num = info.data.get("num")
        if num is not None and (len(num), len(num[0])) != (len(den), len(den[0])):
            raise ValueError(f"den must have the shape of num ({len(num)}x{len(num[0])} polynomials), "
                             f"got {len(den)}x{len(den[0])}")
        for i, row in enumerate(den):
            for j, poly in enumerate(row):
                where = "den" if len(den) == len(row) == 1 else f"den[{i}][{j}]"
                d = np.trim_zeros(np.array(poly, dtype=float), "f")
                if d.size == 0:
                    raise ValueError(f"{where} is zero: a transfer function needs a nonzero denominator")
                if num is not None:
                    nn = np.trim_zeros(np.array(num[i][j], dtype=float), "f")
                    if nn.size > d.size:
                        raise ValueError(f"{where}: the transfer function is not proper (numerator degree "
                                         f"{nn.size - 1} > denominator degree {d.size - 1}); add poles")
        return den

    @field_validator("inputs", "outputs")
    @classmethod
    def _names(cls, value: list[str] | None, info: ValidationInfo) -> list[str] | None:
        num = info.data.get("num")
        if value is not None and num is not None:
            size = len(num) if info.field_name == "outputs" else len(num[0])
            if len(value) != size:
                raise ValueError(f"{info.field_name} must name {size} signals, got {len(value)}")
        return value

    def system(self) -> Any:
        """The python-control ``TransferFunction`` (imports python-control)."""
        import control

        dt = 0 if self.dt is None else self.dt / 1e9
        if len(self.num) == 1 and len(self.num[0]) == 1:
            return control.tf(self.num[0][0], self.den[0][0], dt)
        return control.tf(self.num, self.den, dt)


def _lti(A: Any, B: Any, C: Any, D: Any, dt_ns: int | None, **kwargs: Any) -> Any:
    if dt_ns is None:
        from netsim.plant.lti import LTIPlant

        return LTIPlant(A, B, C, D, **kwargs)
    from netsim.plant.discrete import DiscretePlant

    return DiscretePlant(A, B, C, D, int(dt_ns), **kwargs)


@register("plant", "ss", "a state-space plant: A, B, C, D and dt (null: continuous, exact; a time: discrete)")
def ss_plant(params: SSParams) -> Any:
    """The plant of ``plant: {type: ss, ...}``: an :class:`LTIPlant` (``dt: null``) or a :class:`DiscretePlant`."""
    A, B, C, D = params.arrays()
    return _lti(A, B, C, D, params.dt, input_names=params.inputs, output_names=params.outputs,
                state_names=params.states, name=params.name)


def _ss_ports(params: SSParams) -> tuple[list[Any], list[Any]]:
    m, p = len(params.B[0]), len(params.C)
    return (list(params.inputs) if params.inputs else list(range(m)),
            list(params.outputs) if params.outputs else list(range(p)))


ss_plant.Params = SSParams  # type: ignore[attr-defined]
ss_plant.ports = _ss_ports  # type: ignore[attr-defined]


@register("plant", "tf", "a transfer-function plant: num/den (SISO) or a matrix of them; realised by python-control")
def tf_plant(params: TFParams) -> Any:
    """The plant of ``plant: {type: tf, ...}``: python-control's state-space realisation, built once."""
    import control

    try:
        sys = control.ss(params.system())
    except Exception as exc:  # noqa: BLE001 - python-control's own refusal, reported with the field
        raise ConfigError(f"python-control cannot realise this transfer function: {exc}") from None
    A, B, C, D = (np.atleast_2d(np.asarray(M, dtype=float)) for M in (sys.A, sys.B, sys.C, sys.D))
    if A.size == 0:  # a static gain: one dummy state that nothing reaches
        A, B, C = np.zeros((1, 1)), np.zeros((1, D.shape[1])), np.zeros((D.shape[0], 1))
    return _lti(A, B, C, D, params.dt, input_names=params.inputs, output_names=params.outputs, name=params.name)


def _tf_ports(params: TFParams) -> tuple[list[Any], list[Any]]:
    p, m = len(params.num), len(params.num[0])
    return (list(params.inputs) if params.inputs else list(range(m)),
            list(params.outputs) if params.outputs else list(range(p)))


tf_plant.Params = TFParams  # type: ignore[attr-defined]
tf_plant.ports = _tf_ports  # type: ignore[attr-defined]


#: NonlinearIOSystems given from Python in this process, by the token the scenario data holds instead of them
#: (scenario data stays plain: it is copied, dumped, hashed and written to run folders).
_LIVE_SYSTEMS: dict[str, Any] = {}


def _system_token(sys: Any) -> str:
    """The text a scenario holds for a python-control system given from Python (its name and identity)."""
    token = (f"python-control:{type(sys).__name__}:{getattr(sys, 'name', '?')}:"
             f"{getattr(getattr(sys, 'updfcn', None), '__qualname__', '?')}:{id(sys):x}")
    _LIVE_SYSTEMS[token] = sys
    return token


def _live_system(value: Any) -> Any:
    if isinstance(value, str):
        sys = _LIVE_SYSTEMS.get(value)
        if sys is None:
            raise ValueError("a NonlinearIOSystem plant can only be given from Python, in the process that runs it "
                             "(netsim.run({..., 'plant': sys})); from YAML, use a registered plant model")
        return sys
    return value


class NonlinearIOParams(StrictModel):
    """A python-control ``NonlinearIOSystem`` given from Python (``netsim.run({..., "plant": sys})``)."""

    system: Annotated[Any, BeforeValidator(_live_system), PlainSerializer(_system_token, return_type=str)] = Field(
        description="the python-control NonlinearIOSystem (continuous)")
    params: dict[str, Any] = Field(default_factory=dict, description="overrides of the system's own params")
    method: str = Field("RK45", description="scipy solve_ivp method")
    rtol: float = Field(1e-8, gt=0, description="solve_ivp relative tolerance")
    atol: float = Field(1e-10, gt=0, description="solve_ivp absolute tolerance")

    @field_validator("system")
    @classmethod
    def _nonlinear(cls, value: Any) -> Any:
        if not (is_control_system(value) and callable(getattr(value, "updfcn", None))):
            raise ValueError(f"expected a python-control NonlinearIOSystem, got {type(value).__name__}")
        if getattr(value, "dt", 0) not in (0, None):
            raise ValueError(f"the system is discrete (dt = {value.dt}); netsim integrates continuous "
                             "NonlinearIOSystems (give a StateSpace with dt for a discrete linear plant)")
        return value


@register("plant", "nonlinear_io", "a python-control NonlinearIOSystem given from Python (updfcn, outfcn)")
def nonlinear_io_plant(params: NonlinearIOParams) -> Any:
    """A :class:`~netsim.plant.nonlinear.NonlinearPlant` running the system's ``updfcn(t, x, u, params)`` and
    ``outfcn(t, x, u, params)`` (no ``outfcn``: the output is the state), with ``{**sys.params, **params}``."""
    from netsim.plant.nonlinear import NonlinearPlant

    sys = params.system
    out = sys.outfcn
    if out is None:
        def out(t: float, x: Any, u: Any, p: Any) -> Any:  # python-control's convention: y = x
            return x
    return NonlinearPlant(
        sys.updfcn, out, sys.nstates, sys.ninputs, sys.noutputs, params={**(sys.params or {}), **params.params},
        input_names=_labels(sys.input_labels, "u"), output_names=_labels(sys.output_labels, "y"),
        state_names=_labels(sys.state_labels, "x"), name=str(sys.name) if sys.name else "plant",
        method=params.method, rtol=params.rtol, atol=params.atol)


def _nl_ports(params: NonlinearIOParams) -> tuple[list[Any], list[Any]]:
    sys = params.system
    ins, outs = _labels(sys.input_labels, "u"), _labels(sys.output_labels, "y")
    return (ins or list(range(sys.ninputs))), (outs or list(range(sys.noutputs)))


nonlinear_io_plant.Params = NonlinearIOParams  # type: ignore[attr-defined]
nonlinear_io_plant.ports = _nl_ports  # type: ignore[attr-defined]


# --------------------------------------------------------------------------------------------- from Python
def is_control_system(obj: Any) -> bool:
    """True for a python-control ``StateSpace``, ``TransferFunction`` or ``NonlinearIOSystem`` (without importing
    python-control)."""
    module = type(obj).__module__ or ""
    return module.startswith("control.") and hasattr(obj, "ninputs") and hasattr(obj, "noutputs")


def _is_nonlinear(obj: Any) -> bool:
    return type(obj).__name__ == "NonlinearIOSystem"


def _dt_text(dt: Any) -> str | None:
    if dt in (0, None) or dt is False:
        return None
    if dt is True:
        raise ConfigError("the system is discrete with an unspecified sampling time (dt=True); give dt in seconds")
    from netsim.timebase import from_seconds

    return f"{from_seconds(float(dt))} ns"


def _labels(labels: Any, default_prefix: str) -> list[str] | None:
    names = [str(s) for s in labels]
    if all(n.startswith(default_prefix + "[") for n in names):
        return None  # python-control's defaults u[0], y[0], x[0]: netsim's defaults are the same
    return names


def plant_spec_from_system(sys: Any) -> dict[str, Any]:
    """The scenario ``plant:`` mapping of a python-control ``StateSpace`` or ``TransferFunction``.

    The matrices (or polynomials) are copied out once, as plain lists; the system's signal labels become the
    plant's ``inputs``/``outputs``/``states`` when they are not python-control's defaults, and ``sys.dt`` its
    ``dt`` (``0``/``None``: continuous).

    Raises
    ------
    ConfigError
        For another kind of object (a ``NonlinearIOSystem`` is not described by matrices).
    """
    import control

    if isinstance(sys, control.TransferFunction):
        num = [[np.asarray(sys.num[i][j], dtype=float).tolist() for j in range(sys.ninputs)] for i in range(sys.noutputs)]
        den = [[np.asarray(sys.den[i][j], dtype=float).tolist() for j in range(sys.ninputs)] for i in range(sys.noutputs)]
        spec: dict[str, Any] = {"type": "tf", "num": num, "den": den, "dt": _dt_text(sys.dt)}
    elif isinstance(sys, control.StateSpace):
        spec = {"type": "ss", "A": np.asarray(sys.A, dtype=float).tolist(), "B": np.asarray(sys.B, dtype=float).tolist(),
                "C": np.asarray(sys.C, dtype=float).tolist(), "D": np.asarray(sys.D, dtype=float).tolist(),
                "dt": _dt_text(sys.dt)}
        states = _labels(sys.state_labels, "x")
        if states is not None:
            spec["states"] = states
    else:
        raise ConfigError(f"a plant from Python must be a python-control StateSpace or TransferFunction, got "
                          f"{type(sys).__name__} (a NonlinearIOSystem: netsim.plant.NonlinearPlant.from_system)")
    inputs, outputs = _labels(sys.input_labels, "u"), _labels(sys.output_labels, "y")
    if inputs is not None:
        spec["inputs"] = inputs
    if outputs is not None:
        spec["outputs"] = outputs
    if spec["dt"] is None:
        del spec["dt"]
    return spec


def resolve_plant_object(raw: Any) -> Any:
    """``raw`` with a python-control system given as its ``plant`` (or as ``plant.system``) replaced by the
    equivalent ``plant:`` mapping; anything else is returned unchanged.

    ``plant: <StateSpace>`` and ``plant: {system: <StateSpace>, x0: [...], process_noise: ...}`` are accepted
    (the second keeps the plant section's own keys).
    """
    if not isinstance(raw, dict):
        return raw
    plant = raw.get("plant")
    if is_control_system(plant):
        plant = {"system": plant}
    if isinstance(plant, dict) and is_control_system(plant.get("system")):
        sys = plant["system"]
        rest = {k: v for k, v in plant.items() if k != "system"}
        if _is_nonlinear(sys):
            extra = rest.pop("params", None) or {}  # solver settings, params overrides
            return {**raw, "plant": {"model": "nonlinear_io", "params": {**extra, "system": _system_token(sys)}, **rest}}
        return {**raw, "plant": {**plant_spec_from_system(sys), **rest}}
    return raw
