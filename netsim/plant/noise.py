"""Random disturbances given from a scenario: white noise held on plant inputs, random-walk noise on plant states.

Both are entries of the plant section's ``process_noise`` (one entry, or a list of them)::

    process_noise: {inputs: [u], sigma: 0.2, sample: 1 ms}             # held white noise on input u
    process_noise: {states: [x, y], sigma: [0.01, 0.01], sample: 10 ms}  # random walk on states x and y
    process_noise: {states: [v], sigma: 0.5, sample: 1 ms, model: rate}  # a held random rate on dv/dt

(the older forms, a number, a vector or a matrix, remain the intensity ``Qc`` of an LTI plant's white process
noise, :class:`~netsim.plant.lti.LTIPlant`).

Models, with ``T`` the ``sample`` period, ``k = 0, 1, 2, ...`` and ``e_k ~ N(0, 1)`` independent:

``inputs``
    The plant sees ``u_i(t) + sigma_i e_k`` for ``t`` in ``[k T, (k+1) T)``: white noise held per sample (a
    zero-order-held discrete white sequence, :class:`HeldNoise`). It is a piecewise-constant input, so an LTI
    plant still propagates exactly: its integration is split at the sample instants, as at any input change.
    ``sigma`` is in the input's own units.
``states``
    At each instant ``k T`` (``k >= 1``) the state jumps: ``x_i += sigma_i sqrt(T) e_k`` (a random-walk
    increment). ``sigma`` is an intensity in state units per square root of a second, so the variance added
    over a time ``t`` is ``sigma_i^2 t`` whatever ``T`` is: the Wiener part of ``dx = f dt + sigma dW``,
    sampled exactly at the grid. The plant's own integrator (exact, ODE solver or the model's own) runs
    unchanged between the instants; the jump is applied after the plant has reached ``k T`` and before
    anything that happens at ``k T`` reads it (a mode switch is re-selected after it, as after
    :meth:`~netsim.plant.Plant.set_state`). Works on every plant, including plugin plants such as
    ``unicycle``.
``states`` with ``model: rate``
    A held additive rate: ``dx_i/dt += sigma_i e_k`` for ``t`` in ``[k T, (k+1) T)`` (``e_0`` drawn at the
    start; ``sigma`` in state units per second). The plant integrates it with its dynamics: an LTI plant keeps
    the rates as constant states of its augmented model (still exact), a
    :class:`~netsim.plant.nonlinear.NonlinearPlant` adds them to the right-hand side of whichever mode is
    active. Plants with their own integrator (``unicycle``, the cart) and discrete plants refuse it.

Draws come from the scenario seed's own streams (one seed fixes every draw): ``plant.<name>.disturbance.<input>``
for input noise (the stream of the input's noisy disturbance models) and ``plant.<name>.state_noise`` for state
noise, so adding one never moves the draws of another feature (the LTI intensity noise uses
``plant.<name>.process``).
"""

from __future__ import annotations

import math
from typing import Any, Literal

import numpy as np
from pydantic import Field, model_validator

from netsim.errors import BuildError, ConfigError
from netsim.plant.disturbance import LTIDisturbance, _StateNoise
from netsim.units import Duration, StrictModel

__all__ = ["HeldNoise", "NoiseEntry", "add_held_noise", "apply_entries", "noise_entries", "normalized_entries", "state_noise"]


class HeldNoise(LTIDisturbance):
    """White noise held per sample: ``d(t) = sigma e_k`` on ``[k dt, (k+1) dt)``, ``e_k ~ N(0, 1)``.

    A discrete :class:`LTIDisturbance` with ``A = 0``, ``B = C = 1`` and noise variance ``sigma^2`` whose first
    value is drawn too (``x0 ~ N(0, sigma^2)`` at the plant's start), so every sample, the first included, is
    a fresh draw.

    Parameters
    ----------
    sigma
        Standard deviation of each held value (the input's units), ``>= 0``.
    dt_ns
        The sample period: values are drawn at the multiples of ``dt_ns``.
    """

    draw_initial = True

    def __init__(self, sigma: float, dt_ns: int) -> None:
        s = float(sigma)
        if not s >= 0.0 or s == float("inf"):
            raise ConfigError(f"input noise sigma must be a finite number >= 0, got {sigma!r}")
        super().__init__([[0.0]], [[1.0]], [[1.0]], dt_ns=dt_ns, noise_cov=[[s * s]])
        self.sigma = s


class NoiseEntry(StrictModel):
    """One random disturbance of the plant section's ``process_noise`` (see :mod:`netsim.plant.noise`)."""

    states: list[int | str] | None = Field(
        None, min_length=1, description="plant states (names or indices) that take random-walk increments")
    inputs: list[int | str] | None = Field(
        None, min_length=1, description="plant inputs (names or indices) that take held white noise")
    sigma: float | list[float] = Field(
        description="one number for every listed signal, or one per signal: the held value's standard deviation "
                    "(inputs, input units) or the increment intensity (states, units per sqrt(s))")
    sample: Duration = Field(description="noise sample period: draws at its multiples")
    model: Literal["held", "increment", "rate"] | None = Field(
        None, description="inputs: 'held' (the value held over a sample); states: 'increment' (default, x += "
                          "sigma sqrt(sample) N(0,1) at each sample instant) or 'rate' (sigma N(0,1) held over a "
                          "sample and added to dx/dt)")

    @model_validator(mode="after")
    def _one_target(self) -> "NoiseEntry":
        if (self.states is None) == (self.inputs is None):
            raise ValueError("give either 'states' (random-walk increments) or 'inputs' (held white noise)")
        n = len(self.targets)
        sig = self.sigmas()
        if len(sig) != n:
            raise ValueError(f"sigma has {len(sig)} values for {n} {self.kind}; give one number or one per entry")
        if any(not (s >= 0.0 and s < float("inf")) for s in sig):
            raise ValueError(f"sigma must be finite numbers >= 0, got {self.sigma}")
        allowed = ("increment", "rate") if self.states is not None else ("held",)
        if self.model is not None and self.model not in allowed:
            raise ValueError(f"model '{self.model}' does not apply to {self.kind}: {self.kind} take "
                             f"{' or '.join(repr(a) for a in allowed)} noise")
        return self

    @property
    def kind(self) -> str:
        """``"states"`` or ``"inputs"``."""
        return "states" if self.states is not None else "inputs"

    @property
    def targets(self) -> list[int | str]:
        """The listed states or inputs."""
        return list(self.states if self.states is not None else self.inputs or [])

    def sigmas(self) -> list[float]:
        """One sigma per listed signal."""
        if isinstance(self.sigma, list):
            return [float(s) for s in self.sigma]
        return [float(self.sigma)] * len(self.targets)


def is_entry_form(noise: Any) -> bool:
    """True when ``noise`` is given as entries (a mapping or a list of mappings), not as an intensity."""
    if isinstance(noise, (dict, NoiseEntry)):
        return True
    return isinstance(noise, (list, tuple)) and bool(noise) and all(isinstance(e, (dict, NoiseEntry)) for e in noise)


def noise_entries(noise: Any) -> list[NoiseEntry]:
    """The entries of a ``process_noise`` given as a mapping or a list of mappings (ValueError otherwise)."""
    if not is_entry_form(noise):
        raise ValueError(f"expected {{states|inputs: [...], sigma: ..., sample: ...}} or a list of them, got {noise!r}")
    items = [noise] if isinstance(noise, (dict, NoiseEntry)) else list(noise)
    return [e if isinstance(e, NoiseEntry) else NoiseEntry.model_validate(e) for e in items]


def normalized_entries(noise: Any) -> list[dict[str, Any]]:
    """The entries as plain data (``sample`` as text), for the scenario schema; ValueError with one line naming the
    entry and field otherwise."""
    from pydantic import ValidationError

    items = [noise] if isinstance(noise, dict) else list(noise)
    out = []
    for i, item in enumerate(items):
        try:
            entry = NoiseEntry.model_validate(item)
        except ValidationError as exc:
            where = "" if isinstance(noise, dict) else f"entry {i}: "
            err = exc.errors()[0]
            loc = ".".join(str(p) for p in err["loc"])
            msg = str(err["msg"]).removeprefix("Value error, ")
            raise ValueError(f"{where}{loc + ': ' if loc else ''}{msg}") from None
        out.append(entry.model_dump(mode="json", exclude_none=True))
    return out


def state_noise(plant: str, states: list[int], sigma: Any, sample_ns: int, rate: bool = False) -> _StateNoise:
    """The source of noise on the state indices ``states`` of plant ``plant`` (checked), ``sigma`` one number or
    one per state: random-walk increments (``sd = sigma sqrt(sample)``) or, with ``rate``, held rates
    (``sd = sigma``)."""
    if len(set(states)) != len(states):
        raise ConfigError(f"plant {plant}: state noise lists a state twice: {list(states)}")
    sig = np.full(len(states), float(sigma)) if np.ndim(sigma) == 0 else np.asarray(sigma, dtype=float)
    if sig.shape != (len(states),) or not np.all(np.isfinite(sig)) or np.any(sig < 0):
        raise ConfigError(f"plant {plant}: state noise needs one finite sigma >= 0 per state, got {sigma}")
    dt = int(sample_ns)
    if dt <= 0:
        raise ConfigError(f"plant {plant}: state noise sample must be positive, got {sample_ns}")
    return _StateNoise(states, sig if rate else sig * math.sqrt(dt / 1e9), dt, rate)


def apply_entries(plant: Any, noise: Any) -> None:
    """Add ``process_noise`` entries to ``plant`` (:meth:`~netsim.plant.Plant.add_input_noise` per listed input,
    :meth:`~netsim.plant.Plant.add_state_noise` per states entry); ConfigError for another form."""
    if not is_entry_form(noise):
        raise ConfigError(
            f"plant {plant.name} takes process noise as entries {{states: [...], sigma: ..., sample: ...}} or "
            f"{{inputs: [...], sigma: ..., sample: ...}}; got {noise!r}"
        )
    entries = noise_entries(noise)
    for i, entry in enumerate(entries):
        # the scenario schema hands a single mapping over as a list of one: index only when there are several
        _check_names(plant, entry, f"plant.process_noise{f'[{i}]' if len(entries) > 1 else ''}.{entry.kind}")
        if entry.kind == "inputs":
            for target, sigma in zip(entry.targets, entry.sigmas()):
                plant.add_input_noise(target, sigma, entry.sample)
        else:
            plant.add_state_noise(entry.targets, entry.sigmas(), entry.sample, entry.model or "increment")


def _check_names(plant: Any, entry: NoiseEntry, at: str) -> None:
    """Refuse a state or input ``entry`` names that ``plant`` does not have, at ``at[j]``, listing the known
    names (a renamed ``plant.states``/``inputs`` entry leaves a noise entry naming the old one)."""
    names = list(plant.state_names if entry.kind == "states" else plant.input_names)
    what = entry.kind[:-1]
    for j, target in enumerate(entry.targets):
        if isinstance(target, str) and target not in names:
            raise ConfigError(f"plant {plant.name} has no {what} '{target}'; use one of its {entry.kind} "
                              f"(known: {', '.join(map(str, names))}) or a {what} index", path=f"{at}[{j}]")


def add_held_noise(plant: Any, index: int, sigma: float, sample_ns: int) -> None:
    """Add :class:`HeldNoise` to input ``index`` of ``plant``; a model that refuses sampled disturbances is
    refused with what to write instead."""
    noise = HeldNoise(sigma, sample_ns)
    try:
        plant.add_disturbance(index, noise)
    except (BuildError, ConfigError) as exc:
        if plant._started:
            raise
        raise type(exc)(f"plant {plant.name} does not take random input noise (its model refuses a sampled "
                        f"disturbance: {exc}); put the noise on its states instead: {{states: [...], "
                        "sigma: ..., sample: ...}") from None
