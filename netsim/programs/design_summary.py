"""What a ``state_feedback`` task was designed to be: gains, eigenvalues and delay margin as plain data.

:func:`summarize` reads the built parts of one task (the :class:`~netsim.control.parts.Design`, the estimator
and the law of its :class:`~netsim.programs.feedback_design.TaskDesign`) and returns a JSON-ready mapping
(:func:`summary_of` makes it once per design: validation's warning, the run's warning and ``design.json`` share
it):

``model``
    ``A``, ``B``, ``C`` (measured rows) at the task period, the period, where the model came from, and ``Cr``.
``law``
    ``K`` and ``Ki`` (``None`` without integral action) and the eigenvalues of the state-feedback loop on the
    model, ``A - B K``, or with integral action ``[[A - B K, -B Ki], [-Cr, I]]`` (``z[k+1] = z[k] - Cr x``
    at ``r = 0``). An MPC reports the gain of its unconstrained first move (the LQR gain when ``P`` is the
    default terminal weight); a PID is an output feedback (no ``K``: see ``nominal``).
``estimator``
    The gain ``L`` as the estimator applies it, its form (``current``: ``x_hat = x_bar + L (y - C x_bar)``;
    ``predictor``: ``x_hat[k+1] = A x_hat + B u + L (y - C x_hat)``) and the eigenvalues of its error
    dynamics, ``(I - L C) A`` (current) or ``A - L C`` (predictor), read from the estimator object where it
    has them (:attr:`~netsim.control.luenberger.LuenbergerObserver.error_matrix`). The time-varying Kalman
    filter is summarised by its steady-state gain (the filter DARE of its ``Q``, ``R``: the gain its
    covariance settles to), the steady-state filter by the gain it uses; both give the DARE's prior
    covariance ``M`` and the posterior ``P = M - L C M``. ``none`` (the state measured) is the current form
    with ``L = C^-1``. The extended Kalman filter has no constant gain (``None`` with the reason).
``nominal``
    The eigenvalues of the whole loop on the discrete model, no network and no delay: plant
    ``x[k+1] = A x + B u``, ``y = C x``, and the controller the estimator and the law make together (at
    ``r = 0``), ``xc[k+1] = Ac xc + Bc y``, ``u = Cc xc + Dc y``. For a state-fed law this is the union of the
    state-feedback and observer eigenvalues (separation); ``stable`` is False when one has magnitude >= 1.
``delay_margin``
    For a plant with a continuous LTI model (the ``zoh`` model source; a nonlinear plant's linearisation, the
    model the design used): the constant delay from the sample to the actuation at which the sampled loop
    loses stability, found with :func:`netsim.analysis.lqg.lqg_cost` (its second-moment recursion's spectral
    radius reaches 1) as the first unstable point of a grid over the period, refined by bisection (a loss and
    recovery of stability between two grid points would be missed). That analysis covers delays up to one period, so a loop still stable
    at one period reports ``seconds: None`` with the reason (and ``stable_up_to_s``); so does every case the
    analysis cannot take (no continuous model, a nonlinear estimator, an unstable nominal loop).

Complex numbers are ``[re, im]``; matrices are lists of rows. :func:`run_designs` and :func:`write_design`
are the runner's side (``design.json`` in the run folder), :func:`static_designs` is what ``netsim design``
prints (:mod:`netsim.cli.design` builds the plant for it), and :func:`nominal_warning` /
:func:`nominal_warnings_at` give the warning for an unstable nominal loop.
"""

from __future__ import annotations

import copy
import json
import logging
import sys
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from netsim.errors import ConfigError

if TYPE_CHECKING:
    from netsim.scenario.schema import Scenario

__all__ = [
    "DESIGN_FILE",
    "LinearController",
    "delay_margin",
    "design_json",
    "nominal_warnings_at",
    "nominal_warning",
    "run_designs",
    "static_designs",
    "summarize",
    "summary_of",
    "write_design",
]

log = logging.getLogger(__name__)

#: The run-folder file :func:`write_design` writes.
DESIGN_FILE = "design.json"
#: Format tag of ``design.json``.
FORMAT = "netsim-design/1"
#: A loop whose largest eigenvalue magnitude reaches this is not asymptotically stable.
UNSTABLE_AT = 1.0 - 1e-9
#: Delay-margin search: grid points over one period, then bisection steps on the first unstable interval.
_GRID = 8
_BISECT = 12


# --------------------------------------------------------------------------------------------- plain data
def _num(x: float) -> float | None:
    x = float(x)
    return x if np.isfinite(x) else None


def _matrix(M: Any) -> list[list[float | None]] | None:
    if M is None:
        return None
    return [[_num(v) for v in row] for row in np.atleast_2d(np.asarray(M, dtype=float))]


def _eigs(M: np.ndarray) -> np.ndarray:
    """Eigenvalues, largest magnitude first (ties by real, then imaginary part: a stable order)."""
    if M.size == 0:
        return np.zeros(0, dtype=complex)
    ev = np.linalg.eigvals(M).astype(complex)
    order = sorted(range(ev.size), key=lambda i: (-np.round(abs(ev[i]), 12), np.round(ev[i].real, 12),
                                                   np.round(ev[i].imag, 12)))
    return ev[order]


def _spectrum(M: np.ndarray) -> dict[str, Any]:
    ev = _eigs(M)
    mags = np.abs(ev)
    radius = float(mags.max()) if mags.size else 0.0
    return {"eigenvalues": [[_num(z.real), _num(z.imag)] for z in ev], "magnitudes": [_num(m) for m in mags],
            "spectral_radius": _num(radius), "stable": bool(radius < UNSTABLE_AT)}


# --------------------------------------------------------------------------------------------- the parts
@dataclass(frozen=True)
class LinearController:
    """The controller an estimator and a law make together at ``r = 0``: ``xc[k+1] = Ac xc + Bc y``,
    ``u = Cc xc + Dc y`` (``y``: the rows ``rows`` of the design's measured outputs)."""

    Ac: np.ndarray
    Bc: np.ndarray
    Cc: np.ndarray
    Dc: np.ndarray
    rows: tuple[int, ...]


def _estimator(est: Any, design: Any) -> tuple[dict[str, Any], tuple[str, np.ndarray] | None]:
    """The estimator's summary, and ``(form, L)`` when it is a linear estimator with a constant gain."""
    from netsim.control.kalman import KalmanFilter, kalman_gain
    from netsim.control.luenberger import LuenbergerObserver
    from netsim.control.model_ekf import ModelEKF
    from netsim.control.parts import DirectState

    A, C = design.A, design.C
    n = A.shape[0]
    out: dict[str, Any] = {"class": type(est).__name__, "form": None, "gain": None, "gain_kind": None,
                           "dare_prior_covariance": None, "dare_posterior_covariance": None,
                           "error_matrix": None, "eigenvalues": None, "magnitudes": None, "spectral_radius": None,
                           "stable": None, "reason": None}
    if isinstance(est, ModelEKF):
        out["reason"] = ("the extended Kalman filter linearises the plant's nonlinear model at every step: it has "
                         "no constant gain")
        return out, None
    if isinstance(est, LuenbergerObserver):
        form, L, E = est.form, est.L, est.error_matrix
        out["gain_kind"] = "Luenberger gain by pole placement"
    elif isinstance(est, KalmanFilter):
        form = "current"
        if est.steady_state:
            L, M = est.K_ss, est.M_ss
            out["gain_kind"] = "steady-state Kalman gain (filter DARE), the gain the filter uses"
        else:
            try:
                M = est.dare_prior()
            except ConfigError as exc:
                out["reason"] = f"time-varying Kalman filter without a steady state: {exc.message}"
                return out, None
            L = kalman_gain(M, est.C, est.R)
            out["gain_kind"] = ("steady-state gain of the time-varying Kalman filter (filter DARE of its Q, R: the "
                                "gain its covariance settles to)")
        out["dare_prior_covariance"] = _matrix(M)
        out["dare_posterior_covariance"] = _matrix(M - L @ est.C @ M)
        E = (np.eye(n) - L @ C) @ A
    elif isinstance(est, DirectState):
        form, L = "current", np.linalg.inv(C)
        out["gain_kind"] = "state measured: x_hat = C^-1 y (the current form with L = C^-1)"
        E = (np.eye(n) - L @ C) @ A
    else:
        out["reason"] = f"estimator {type(est).__name__} has no linear gain this summary can read"
        return out, None
    out["form"] = form
    out["gain"] = _matrix(L)
    out["error_matrix"] = _matrix(E)
    out.update(_spectrum(np.asarray(E, dtype=float)))
    return out, (form, np.asarray(L, dtype=float))


def _law(law: Any, design: Any) -> tuple[dict[str, Any], Any]:
    """The law's summary, and its linear form at ``r = 0``: ``("state", K, Ki, Cr)``, ``("pid", matrices)``
    or ``None``."""
    from netsim.control.lqr import LQR, StateFeedback
    from netsim.control.mpc import LinearMPC
    from netsim.control.pid import PIDLaw

    A, B = design.A, design.B
    out: dict[str, Any] = {"class": type(law).__name__, "K": None, "Ki": None, "eigenvalues": None,
                           "magnitudes": None, "spectral_radius": None, "stable": None, "note": None}
    if isinstance(law, PIDLaw):
        pid = law.pid
        out["pid"] = {"K": pid.K, "Ti": pid.Ti, "Td": pid.Td, "N": pid.N, "b": pid.b, "h_s": pid.h,
                      "u_min": pid.u_min, "u_max": pid.u_max}
        out["note"] = ("a PID is an output feedback on the first measured output: its loop eigenvalues are the "
                       "nominal loop's")
        # the PID's states [I, D, y_prev] as PID.step updates them at r = 0 (the integral only when Ti is set)
        ad, bd, bi = pid.ad, pid.bd, pid.bi
        Ac = np.array([[1.0, 0.0, 0.0], [0.0, ad, bd], [0.0, 0.0, 0.0]])
        Bc = np.array([[-bi], [-bd], [1.0]])
        Cc = np.array([[1.0, ad, bd]])
        Dc = np.array([[-pid.K - bd]])
        if bi == 0.0:  # no integral action: the integrator state is not part of the law
            Ac, Bc, Cc = Ac[1:, 1:], Bc[1:], Cc[:, 1:]
        return out, ("pid", Ac, Bc, Cc, Dc)
    if isinstance(law, LinearMPC):
        Mall = law._Mall  # the unconstrained optimum U* = Mall [x0; x_s; u_s]
        K = -np.asarray(Mall[: law.m, : law.n])  # its first move: u0 = -K x0
        Ki, Cr = None, None
        out["lqr_K"] = _matrix(law.K)
        out["horizon"] = law.N
        out["note"] = ("MPC: K is the gain of its unconstrained first move (no constraint active), the LQR gain when "
                       "P is the default terminal weight; constraints make the law nonlinear")
    elif isinstance(law, StateFeedback):
        K, Ki, Cr = law.K, law.Ki, law.Cr
        if isinstance(law, LQR):
            out["riccati_P"] = _matrix(law.P)
    else:
        out["note"] = f"law {type(law).__name__} has no linear gain this summary can read"
        return out, None
    out["K"], out["Ki"] = _matrix(K), _matrix(Ki)
    if Ki is None:
        Acl = A - B @ K
    else:
        assert Cr is not None  # an integral gain needs Cr (StateFeedback refuses Ki without it)
        q = Ki.shape[1]
        Acl = np.block([[A - B @ K, -B @ Ki], [-Cr, np.eye(q)]])
    out.update(_spectrum(Acl))
    out["with_integrator"] = Ki is not None
    return out, ("state", np.asarray(K, dtype=float), None if Ki is None else np.asarray(Ki, dtype=float), Cr)


def _controller(design: Any, est_form: tuple[str, np.ndarray] | None, law_form: Any,
                fed_state: bool) -> tuple[LinearController | None, str | None]:
    """The estimator and the law as one linear controller (see :class:`LinearController`), or the reason not."""
    if law_form is None:
        return None, "the law is not linear"
    A, B, C = design.A, design.B, design.C
    n, p = A.shape[0], C.shape[0]
    if law_form[0] == "pid":
        _, Ac, Bc, Cc, Dc = law_form
        return LinearController(Ac, Bc, Cc, Dc, (0,)), None
    if not fed_state:
        return None, "the law is fed the measurement, not the estimate"
    if est_form is None:
        return None, "the estimator has no constant gain"
    form, L = est_form
    _, K, Ki, Cr = law_form
    if form == "current":  # x_hat = E xb + F y (xb: the prior), xb+ = G xb + H y + B u
        E, F = np.eye(n) - L @ C, L
        G, H = A @ E, A @ L
    else:  # predictor: x_hat = xb, xb+ = (A - L C) xb + L y + B u
        E, F = np.eye(n), np.zeros((n, p))
        G, H = A - L @ C, L
    q = 0 if Ki is None else Ki.shape[1]
    Kz = np.zeros((K.shape[0], 0)) if Ki is None else Ki
    Crm = np.zeros((0, n)) if Ki is None else np.asarray(Cr, dtype=float)
    Ac = np.block([[G - B @ K @ E, -B @ Kz], [-Crm @ E, np.eye(q)]])
    Bc = np.vstack([H - B @ K @ F, -Crm @ F])
    Cc = np.hstack([-K @ E, -Kz])
    Dc = -K @ F
    return LinearController(Ac, Bc, Cc, Dc, tuple(range(p))), None


def _nominal(design: Any, ctrl: LinearController) -> np.ndarray:
    """The loop matrix of the discrete model and the controller, state ``[x; xc]``."""
    A, B = design.A, design.B
    Cy = design.C[list(ctrl.rows)]
    return np.block([[A + B @ ctrl.Dc @ Cy, B @ ctrl.Cc], [ctrl.Bc @ Cy, ctrl.Ac]])


def delay_margin(plant: Any, rows: list[int], period_s: float, ctrl: LinearController) -> dict[str, Any]:
    """The smallest constant sample-to-actuation delay in ``[0, period_s]`` that makes the sampled loop of the
    continuous plant and ``ctrl`` unstable (see the module docstring), with how it was found."""
    from netsim.analysis.lqg import SampledLoop, lqg_cost

    Ap, Bp = np.atleast_2d(np.asarray(plant.A, float)), np.atleast_2d(np.asarray(plant.B, float))
    Cp = np.atleast_2d(np.asarray(plant.C, float))[[rows[r] for r in ctrl.rows]]
    n, m = Bp.shape
    loop = SampledLoop(A=Ap, B=Bp, C=Cp, period_s=period_s, Q1=np.zeros((n, n)), Q2=np.zeros((m, m)),
                       Ac=ctrl.Ac if ctrl.Ac.size else None, Bc=ctrl.Bc if ctrl.Ac.size else None,
                       Cc=ctrl.Cc if ctrl.Ac.size else None, Dc=ctrl.Dc)

    def stable(tau: float) -> bool:  # lqg's spectral radius is that of F kron F: below 1 iff F is stable
        return lqg_cost(loop, delay=tau).spectral_radius < UNSTABLE_AT

    method = (f"netsim.analysis.lqg.lqg_cost: spectral radius of the sampled loop under a constant delay, on "
              f"{_GRID + 1} delays over one period, refined by {_BISECT} bisection steps")
    out: dict[str, Any] = {"seconds": None, "stable_up_to_s": None, "method": method, "reason": None}
    if not stable(0.0):
        out["reason"] = "the loop is unstable without delay"
        return out
    lo = 0.0
    for i in range(1, _GRID + 1):
        tau = period_s * i / _GRID
        if stable(tau):
            lo = tau
            continue
        hi = tau
        for _ in range(_BISECT):
            mid = 0.5 * (lo + hi)
            lo, hi = (mid, hi) if stable(mid) else (lo, mid)
        out["seconds"] = hi
        out["stable_up_to_s"] = lo
        return out
    out["stable_up_to_s"] = period_s
    out["reason"] = ("stable for every constant delay up to one period; netsim.analysis.lqg covers delays up to one "
                     "period, so the margin is at least the period")
    return out


# --------------------------------------------------------------------------------------------- summary
def summarize(design: Any, estimator: Any, law: Any, fed_state: bool, *, rows: list[int] | None = None,
              source: str | None = None, plant: Any = None, margin: bool = True) -> dict[str, Any]:
    """The design of one ``state_feedback`` task as plain data (see the module docstring).

    Parameters
    ----------
    design, estimator, law, fed_state
        What :func:`~netsim.programs.feedback_design.task_design` made.
    rows
        The plant outputs the task measures (the rows of ``design.C``).
    source
        Where the model came from (a key of :data:`~netsim.programs.feedback_design.MODEL_SOURCES`).
    plant
        The plant, for the delay margin (used only when ``source`` is ``"zoh"``: a continuous LTI model).
    margin
        False: skip the delay margin (``None`` with the reason): the warning needs only the eigenvalues.
    """
    from netsim.programs.feedback_design import MODEL_SOURCES

    est_out, est_form = _estimator(estimator, design)
    law_out, law_form = _law(law, design)
    ctrl, why = _controller(design, est_form, law_form, fed_state)
    nominal: dict[str, Any] = {"eigenvalues": None, "magnitudes": None, "spectral_radius": None, "stable": None,
                               "reason": why, "note": None}
    if ctrl is not None:
        nominal.update(_spectrum(_nominal(design, ctrl)))
        if law_form[0] == "pid":
            nominal["reason"] = "the PID law on the first measured output (the estimator does not feed it)"
    margin_out: dict[str, Any] = {"seconds": None, "stable_up_to_s": None, "method": None, "reason": None}
    if not margin:
        margin_out["reason"] = "not computed"
    elif ctrl is None:
        margin_out["reason"] = f"no linear loop: {why}"
    elif source != "zoh" or plant is None:
        margin_out["reason"] = ("netsim.analysis.lqg needs the plant's continuous LTI model; this task's model is "
                                + MODEL_SOURCES.get(source or "", "not the plant's"))
    elif not nominal["stable"]:
        margin_out["reason"] = "the nominal loop is unstable"
    else:
        margin_out = delay_margin(plant, list(rows or range(design.C.shape[0])), design.period_s, ctrl)
    return {
        "model": {"A": _matrix(design.A), "B": _matrix(design.B), "C": _matrix(design.C), "Cr": _matrix(design.Cr),
                  "period_s": design.period_s, "measured_outputs": None if rows is None else list(rows),
                  "source": source, "source_text": MODEL_SOURCES.get(source or "")},
        "law": law_out,
        "estimator": est_out,
        "nominal": nominal,
        "delay_margin": margin_out,
    }


def summary_of(made: Any, plant: Any, source: str | None, *, margin: bool = True) -> dict[str, Any]:
    """:func:`summarize` of a :class:`~netsim.programs.feedback_design.TaskDesign`, made once per design and
    option (validation's warning, the run's warning and ``design.json`` share it); a copy."""
    got = made.summaries.get(margin)
    if got is None:
        got = summarize(made.design, made.estimator, made.law, made.fed_state, rows=made.rows, source=source,
                        plant=plant, margin=margin)
        made.summaries[margin] = got
    return copy.deepcopy(got)


def _task_entry(node: str, index: int, spec: Any, summary: dict[str, Any], program: Any = None) -> dict[str, Any]:
    p = spec.validated_params() if program is None else program.p
    entry = {"node": node, "task": spec.name, "path": f"nodes.{node}.tasks[{index}]",
             "period_ns": int(spec.period) if spec.period is not None else None,
             "estimator_type": str(p.estimator.type), "law_type": str(p.law.type)}
    entry.update(summary)
    delay, applied = p.input_delay, p.applied_input is not None
    entry["input_delay_s"] = None if delay is None else int(delay) / 1e9
    entry["applied_input"] = applied
    if delay is not None or applied:  # the program's delay-aware prediction (issue 26 s5) is not in the loop above
        fed = "the input delayed by input_delay" if delay is not None else "the inputs the actuator reports"
        entry["nominal"]["note"] = (f"the estimator predicts with {fed}; these eigenvalues and the delay margin are "
                                    "the design's without that option (the gains do not depend on it)")
    return entry


def _state_feedback_tasks(scenario: Scenario) -> list[tuple[str, int, Any]]:
    from netsim import registry

    found = []
    for node, spec in scenario.nodes.items():
        for i, task in enumerate(spec.tasks):
            try:
                cls = registry.lookup("program", task.program)
            except ConfigError:  # an unknown program is validate's problem, not a design
                continue
            found.append((node, i, task, cls))
    # no subclass of StateFeedbackProgram exists unless its module was imported (the lookups import the programs'):
    # a scenario without one imports neither it nor the control parts it loads (issue 29, start-up)
    base = getattr(sys.modules.get("netsim.programs.state_feedback"), "StateFeedbackProgram", None)
    return [(n, i, t) for n, i, t, cls in found if base is not None and isinstance(cls, type) and issubclass(cls, base)]


def static_designs(scenario: Scenario, plant: Any, *, margin: bool = True) -> dict[str, dict[str, Any]]:
    """``{"node.task": design}`` of every ``state_feedback`` task of a valid scenario, built as validation builds
    them (:func:`~netsim.programs.feedback_design.task_design`: the designs validation made, nothing simulated)."""
    out: dict[str, dict[str, Any]] = {}
    for node, i, task in _state_feedback_tasks(scenario):
        from netsim.programs.feedback_design import model_source, task_design  # only with such tasks (issue 29)
        params = task.validated_params()
        period = task.period if task.release_kind == "periodic" else None
        path = f"nodes.{node}.tasks[{i}]"
        made = task_design(params, scenario, plant, period, path, node)
        summary = summary_of(made, plant, model_source(params, plant), margin=margin)
        out[f"{node}.{task.name}"] = _task_entry(node, i, task, summary)
    return out


def run_designs(sim: Any, *, margin: bool = True) -> dict[str, dict[str, Any]]:
    """``{"node.task": design}`` of every ``state_feedback`` task of a built simulation, read from the programs
    it runs (their estimator and law objects)."""
    plant = sim.env.components.get("plant")
    out: dict[str, dict[str, Any]] = {}
    for node, i, task in _state_feedback_tasks(sim.scenario):
        from netsim.programs.feedback_design import model_source  # only with such tasks (issue 29)
        prog = sim.programs.get(f"{node}.{task.name}")
        if prog is None:
            continue
        summary = summary_of(prog.task_design, plant, model_source(prog.p, plant), margin=margin)
        out[f"{node}.{task.name}"] = _task_entry(node, i, task, summary, prog)
    return out


def design_json(designs: dict[str, dict[str, Any]]) -> str:
    """The text of ``design.json``: plain JSON (no NaN), keys sorted."""
    return json.dumps({"format": FORMAT, "tasks": designs}, indent=1, sort_keys=True, allow_nan=False) + "\n"


def write_design(folder: str | Path, sim: Any, tables: bool = True) -> Path | None:
    """Write ``design.json`` into a run folder (atomically) when the scenario has ``state_feedback`` tasks;
    with ``tables`` False (a sweep's ``runs: metrics``) remove a stale one instead. Returns the file or None."""
    from netsim.safe_write import write_atomic

    path = Path(folder) / DESIGN_FILE
    designs = run_designs(sim) if tables else {}
    if not designs:
        path.unlink(missing_ok=True)
        return None
    return write_atomic(path, design_json(designs))


# --------------------------------------------------------------------------------------------- warning
def nominal_warning(key: str, design: dict[str, Any], with_path: bool = True) -> str | None:
    """The warning for a task whose nominal loop is unstable, naming the task (and its YAML path unless
    ``with_path`` is False: a validation problem carries it) and the eigenvalue magnitude."""
    nominal = design["nominal"]
    if nominal.get("stable") is not False:
        return None
    re_, im_ = nominal["eigenvalues"][0]
    parts = []
    if design["law"].get("stable") is False:
        parts.append(f"state feedback |z| = {design['law']['spectral_radius']:.6g}")
    if design["estimator"].get("stable") is False:
        parts.append(f"observer |z| = {design['estimator']['spectral_radius']:.6g}")
    where = f" ({', '.join(parts)})" if parts else ""
    at = f" ({design['path']}.params)" if with_path else ""
    return (f"task {key}{at}: the nominal closed loop (estimator and law on the discrete "
            f"model, no network) is unstable: eigenvalue {complex(re_, im_):.6g} has magnitude "
            f"{nominal['spectral_radius']:.6g} >= 1{where}; check the law's gain or weights and the estimator")


def design_warnings(designs: dict[str, dict[str, Any]]) -> list[str]:
    """:func:`nominal_warning` of each design that has one."""
    return [w for key, d in sorted(designs.items()) if (w := nominal_warning(key, d)) is not None]


def run_warnings(sim: Any) -> list[str]:
    """The unstable-nominal-loop warnings of a built simulation (the runner records them in ``meta.json``)."""
    return design_warnings(run_designs(sim, margin=False))


def nominal_warnings_at(scenario: Scenario, plant: Any) -> list[tuple[str, str]]:
    """The same warnings for ``netsim validate``: ``(YAML path, message)`` at each task's ``params.law``
    (:mod:`netsim.build.dry_run` makes them warning problems)."""
    designs = static_designs(scenario, plant, margin=False)
    out = []
    for key, d in sorted(designs.items()):
        text = nominal_warning(key, d, with_path=False)
        if text is not None:
            out.append((f"{d['path']}.params.law", text))
    return out
