"""``plant.integrator``: how a nonlinear plant is integrated between events (numerics in :mod:`netsim.plant.integrator`).

Kept apart from :mod:`netsim.scenario.schema` as the task and sync fields are, and free of ``netsim.plant``
imports so that loading a scenario does not import the simulation.
"""

from __future__ import annotations

from typing import Any, Literal

from pydantic import Field, model_validator

from netsim.timebase import S
from netsim.units import Duration, StrictModel

__all__ = ["IntegratorSpec"]


class IntegratorSpec(StrictModel):
    """``plant.integrator``: how a nonlinear plant is integrated between events (LTI plants are exact)."""

    method: Literal["solve_ivp", "rk4"] = Field(
        "solve_ivp", description="solve_ivp: scipy's adaptive solver once per segment (default); rk4: classical "
        "fourth-order Runge-Kutta with fixed steps of at most max_step, no scipy call")
    max_step: Duration | None = Field(
        None, description="rk4: the largest step (required; each segment is cut into equal steps no longer than "
        "this); solve_ivp: a bound on its adaptive step (default unbounded)")
    solver: str = Field("RK45", min_length=1, description="solve_ivp only: scipy's method name (RK45, DOP853, "
                        "Radau, BDF, LSODA ...)")
    rtol: float | None = Field(None, gt=0, description="solve_ivp only: relative tolerance (default 1e-8)")
    atol: float | None = Field(None, gt=0, description="solve_ivp only: absolute tolerance (default 1e-10)")

    @model_validator(mode="after")
    def _consistent(self) -> "IntegratorSpec":
        if self.method == "rk4":
            if self.max_step is None:
                raise ValueError("method rk4 needs max_step (e.g. 'max_step: 1 ms'): its fixed step is not chosen "
                                 "by an error estimate")
            given = [k for k in ("rtol", "atol") if getattr(self, k) is not None]
            if "solver" in self.model_fields_set:
                given.insert(0, "solver")
            if given:
                raise ValueError(f"{', '.join(given)} apply to method solve_ivp only; rk4's accuracy is set by "
                                 "max_step")
        elif self.solver.lower() == "rk4":
            raise ValueError("rk4 is a method of its own: write 'method: rk4' (and max_step), not 'solver: rk4'")
        return self

    def plant_kwargs(self) -> dict[str, Any]:
        """The keyword arguments of :meth:`NonlinearPlant.set_integrator`."""
        out: dict[str, Any] = {"method": self.method}
        if self.max_step is not None:
            out["max_step"] = self.max_step / S
        if self.method == "solve_ivp":
            out["solver"] = self.solver
            for key in ("rtol", "atol"):
                if getattr(self, key) is not None:
                    out[key] = getattr(self, key)
        return out
