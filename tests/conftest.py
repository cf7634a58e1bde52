"""Shared pytest set-up: single-threaded BLAS (tiny matrices) and a non-interactive plot backend."""

import os

import netsim  # noqa: F401  (first: pins BLAS threads and kernels before numpy is imported, netsim.blas)

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
os.environ.setdefault("OMP_NUM_THREADS", "1")
os.environ.setdefault("MPLBACKEND", "Agg")
