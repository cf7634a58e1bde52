"""BLAS settings that make a run's numbers the same on every x86-64 machine, set before numpy is imported.

netsim multiplies tiny matrices (a 10-state plant, a 2x2 gain), so BLAS threads only cost time: one thread per
process, parallelism comes from processes (FIELD_NOTES: 2-10x slower tiny matrix work with threads on a loaded
machine).

OpenBLAS picks its compute kernels by the CPU it finds, and the AVX-512 kernels round differently from the AVX2
ones in the last bit: the same scenario and seed then gave ``signals.csv`` files that differed at 1e-13 between an
AVX2 and an AVX-512 machine (measured on dc_servo_ideal and hdd_case1, numpy 2.4.6, scipy 1.17.1). For runs that
are byte-identical across machines, :func:`configure` asks OpenBLAS for its Haswell (AVX2 + FMA) kernels on every
x86-64 Linux CPU that has AVX2 and FMA. A user's own setting of ``OPENBLAS_CORETYPE`` (or of a thread count) is
kept; on other CPUs (no AVX2, ARM) nothing is pinned and results may differ from an x86-64 run in the last bits.

The settings only take effect when made before numpy is first imported, so :mod:`netsim` calls :func:`configure` on
import, and the ``netsim`` command and sweep workers import netsim before numpy.
"""

from __future__ import annotations

import os
import platform
import sys

__all__ = ["configure", "cpu_has_avx2_fma", "PINNED_CORETYPE"]

#: The OpenBLAS kernel set netsim pins on x86-64 CPUs that support it.
PINNED_CORETYPE = "Haswell"

_THREAD_VARIABLES = ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS")


def cpu_has_avx2_fma(cpuinfo: str | None = None) -> bool:
    """Whether this is an x86-64 Linux CPU with the AVX2 and FMA instructions the Haswell kernels need.

    Parameters
    ----------
    cpuinfo
        The text of ``/proc/cpuinfo`` (read from the system when not given; for tests).
    """
    if cpuinfo is None:
        if not sys.platform.startswith("linux") or platform.machine().lower() not in ("x86_64", "amd64"):
            return False
        try:
            with open("/proc/cpuinfo", encoding="ascii", errors="replace") as handle:
                cpuinfo = handle.read(1 << 16)
        except OSError:
            return False
    for line in cpuinfo.splitlines():
        if line.startswith("flags"):
            flags = set(line.partition(":")[2].split())
            return {"avx2", "fma"} <= flags
    return False


def configure(environ: "os._Environ[str] | dict[str, str] | None" = None, cpuinfo: str | None = None) -> None:
    """Pin BLAS to one thread and, where the CPU allows, to OpenBLAS's Haswell kernels.

    Values already in the environment are kept (``setdefault``), so a user can choose otherwise.

    Parameters
    ----------
    environ
        The environment to update (``os.environ`` when not given; for tests).
    cpuinfo
        The text of ``/proc/cpuinfo`` (for tests).
    """
    env = os.environ if environ is None else environ
    for name in _THREAD_VARIABLES:
        env.setdefault(name, "1")
    if "OPENBLAS_CORETYPE" not in env and cpu_has_avx2_fma(cpuinfo):
        env["OPENBLAS_CORETYPE"] = PINNED_CORETYPE
