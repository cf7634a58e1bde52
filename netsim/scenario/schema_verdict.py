"""How a scenario's run is judged stable or not (the top-level ``verdict:`` block; :mod:`netsim.results.verdict` does it).

Kept apart from :mod:`netsim.scenario.schema` (whose ``Scenario`` has the ``verdict`` field) so the block reads in
one place::

    verdict:
      growth: true          # the growth check of every metric's error (reference - output) and of `signals`
      window: 50 ms         # window of the error envelope (default: the run's duration / 20)
      windows: 4            # consecutive windows whose envelope must each grow ...
      growth_ratio: 1.15    # ... by at least this factor over the window before
      signals: [y]          # also check these signals about 0 (a regulator without a control_error metric)
      bound: {alpha: 1.0}   # |alpha| past 1.0: out of its operating region at once
      metrics: true         # a metric's own verdict (the pendulum metric: the pendulum fell)
      action: fail          # fail: status "unstable at t = ... s", exit 1; warn: status ok with a warning

``verdict: false`` (or ``off``) switches every check off; ``verdict`` left out means the defaults above (window
aside). Divergence (non-finite values, the plant's bound, ``control_error``'s ``diverged_above``) is judged
whatever this block says.
"""

from __future__ import annotations

from typing import Annotated, Any, Literal

from pydantic import ConfigDict, Field, StringConstraints, model_validator

from netsim.units import Duration, StrictModel

__all__ = ["VerdictSpec", "VerdictSettings", "DEFAULT_WINDOWS", "DEFAULT_GROWTH_RATIO", "WINDOWS_PER_RUN"]

#: Consecutive growing windows that make a loop unstable (``verdict.windows``).
DEFAULT_WINDOWS = 4
#: Growth of the envelope from one window to the next (``verdict.growth_ratio``).
DEFAULT_GROWTH_RATIO = 1.15
#: The default window is the run's duration divided by this.
WINDOWS_PER_RUN = 20

_Signal = Annotated[str, StringConstraints(min_length=1, max_length=200)]


def _switch(value: Any) -> Any:
    """``verdict: false | off`` switches every check off; ``true | on`` (or an empty block) keeps the defaults."""
    if value is False or (isinstance(value, str) and value.strip().lower() in ("off", "false", "no")):
        return {"growth": False, "metrics": False}
    if value is True or value is None or (isinstance(value, str) and value.strip().lower() in ("on", "true", "yes")):
        return {}
    return value


class VerdictSettings(StrictModel):
    """The block's fields (see the module docstring)."""

    model_config = ConfigDict(extra="forbid", frozen=True, allow_inf_nan=False)

    growth: bool = Field(True, description="check the error envelope of every metric's reference/output pair "
                                           "(and of `signals`) for sustained growth")
    window: Duration | None = Field(None, description="window of the envelope (default: duration / 20)")
    windows: int = Field(DEFAULT_WINDOWS, ge=2, le=1000,
                         description="consecutive windows whose envelope grows by growth_ratio")
    growth_ratio: float = Field(DEFAULT_GROWTH_RATIO, gt=1.0, le=1.0e6,
                                description="growth of the envelope from one window to the next")
    signals: list[_Signal] = Field(default_factory=list,
                                   description="more signals whose envelope about 0 is checked for growth")
    bound: dict[_Signal, Annotated[float, Field(gt=0)]] = Field(
        default_factory=dict, description="signal -> bound on its magnitude: past it the loop left its operating "
                                          "region")
    metrics: bool = Field(True, description="let a metric's own verdict (the pendulum fell) judge the run")
    action: Literal["fail", "warn"] = Field("fail", description="fail: status 'unstable at t = ... s' (exit 1); "
                                                                "warn: the status stays ok, a warning says it")

    @model_validator(mode="before")
    @classmethod
    def _on_off(cls, value: Any) -> Any:
        return _switch(value)


#: The ``verdict:`` block: a mapping of the fields above, or ``false``/``off`` (every check off).
VerdictSpec = VerdictSettings
