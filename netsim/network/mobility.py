"""Node mobility on a radio channel: a piecewise-linear path over time, or a constant velocity.

A wireless network's ``mobility`` maps a node to a :class:`Motion`; the node starts at its ``positions`` entry
at time 0 and then follows the motion:

``path: {<time>: [x, y], ...}``
    waypoints (metres) at times after 0 (``"10 s": [50, 0]``); the node moves in a straight line at constant
    speed from each point to the next, starting from its position at 0, and stays at the last waypoint.
``velocity: [vx, vy]``
    a constant velocity (metres per second) from its position at 0, for the whole run.

:class:`Track` answers the position at any time (exactly: a linear interpolation in float metres of the
integer-nanosecond time). The radio evaluates positions, hence the path loss, at the instants it needs them:
when a transmission goes on the air (the interference it adds), when it ends (whether each receiver got it)
and at every carrier sense.
"""

from __future__ import annotations

import math
from bisect import bisect_right
from typing import Any

from pydantic import (
    Field,
    field_serializer,
    field_validator,
    model_serializer,
    model_validator,
)

from netsim.timebase import S, TimeParseError, format_time, parse_time
from netsim.units import NUMBER_LIMIT, StrictModel, Time

__all__ = ["Motion", "Track"]


def _point(value: Any, what: str) -> tuple[float, float]:
    if (isinstance(value, (list, tuple)) and len(value) == 2
            and all(isinstance(v, (int, float)) and not isinstance(v, bool) for v in value)):
        x, y = float(value[0]), float(value[1])
        if all(math.isfinite(v) and abs(v) <= NUMBER_LIMIT for v in (x, y)):
            return x, y
    raise ValueError(f"{what}: expected [x, y] (two finite numbers of at most {NUMBER_LIMIT:g}, metres), "
                     f"got {value!r}")


def _waypoints(path: Any) -> Any:
    """Check ``path``'s waypoints one by one, so that a problem names its waypoint at the ``path`` key (a time
    such as ``"8 s"`` is not a path part a message can point into) and two keys that are the same time
    (``"1 s"`` and ``"1000 ms"``) are refused instead of one silently replacing the other."""
    if not isinstance(path, dict):
        return path  # the field's type reports it
    seen: dict[int, Any] = {}
    for key, point in path.items():
        try:
            t = parse_time(key)
        except (TimeParseError, TypeError) as exc:
            raise ValueError(f"waypoint {key!r}: {exc}") from None
        if t in seen:
            raise ValueError(f"waypoints {seen[t]!r} and {key!r} are the same time ({format_time(t)}); "
                             "remove one of them")
        seen[t] = key
        _point(point, f"waypoint {key!r}")
    return path


class Motion(StrictModel):
    """How one node moves: exactly one of ``path`` (waypoints by time) and ``velocity`` (m/s)."""

    path: dict[Time, tuple[float, float]] | None = Field(
        None, description="time -> [x, y] (m): waypoints after 0 s, reached in straight lines from the node's "
                          "position at 0; it stays at the last")
    velocity: tuple[float, float] | None = Field(None, description="[vx, vy] in m/s from the node's position at 0 s")

    @field_validator("path", mode="before")
    @classmethod
    def _path_points(cls, value: Any) -> Any:
        return _waypoints(value)

    @model_validator(mode="after")
    def _check(self) -> "Motion":
        if (self.path is None) == (self.velocity is None):
            raise ValueError("give exactly one of 'path' (waypoints by time) and 'velocity' ([vx, vy] in m/s)")
        if self.velocity is not None:
            _point(self.velocity, "velocity")
        if self.path is not None:
            if not self.path:
                raise ValueError("path: give at least one waypoint, e.g. {'10 s': [50, 0]}")
            if any(t <= 0 for t in self.path):
                raise ValueError("path: every waypoint time must be after 0 s (the node stands at its 'positions' "
                                 "entry at 0)")
            object.__setattr__(self, "path", {t: _point(p, f"path.{format_time(t)}")
                                              for t, p in sorted(self.path.items())})
        return self

    @model_serializer(mode="wrap")
    def _only_given(self, handler: Any) -> Any:
        data = handler(self)
        return {k: v for k, v in data.items() if v is not None} if isinstance(data, dict) else data

    @field_serializer("path", when_used="json")
    def _path_text(self, path: dict[int, tuple[float, float]] | None) -> dict[str, list[float]] | None:
        return None if path is None else {format_time(t): [float(x), float(y)] for t, (x, y) in path.items()}

    @field_serializer("velocity", when_used="json")
    def _velocity_list(self, v: tuple[float, float] | None) -> list[float] | None:
        return None if v is None else [float(v[0]), float(v[1])]


class Track:
    """The position over time of one node that starts at ``start`` and follows ``motion``."""

    __slots__ = ("_times", "_xs", "_ys", "_v")

    def __init__(self, start: tuple[float, float], motion: Motion) -> None:
        self._v: tuple[float, float] | None = motion.velocity
        points = [(0, start)] + list((motion.path or {}).items())
        self._times = [t for t, _ in points]
        self._xs = [float(p[0]) for _, p in points]
        self._ys = [float(p[1]) for _, p in points]

    def at(self, t_ns: int) -> tuple[float, float]:
        """Position (metres) at ``t_ns``."""
        if self._v is not None:
            dt = t_ns / S
            return self._xs[0] + self._v[0] * dt, self._ys[0] + self._v[1] * dt
        times = self._times
        i = bisect_right(times, t_ns) - 1
        if i >= len(times) - 1:
            return self._xs[-1], self._ys[-1]
        f = (t_ns - times[i]) / (times[i + 1] - times[i])
        return (self._xs[i] + f * (self._xs[i + 1] - self._xs[i]),
                self._ys[i] + f * (self._ys[i + 1] - self._ys[i]))
