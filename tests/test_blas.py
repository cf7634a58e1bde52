"""netsim.blas: one BLAS thread and the same OpenBLAS kernels on every x86-64 machine."""

import os
import subprocess
import sys

from netsim.blas import PINNED_CORETYPE, configure, cpu_has_avx2_fma

AVX512_CPU = "processor\t: 0\nflags\t\t: fpu sse2 avx avx2 fma avx512f avx512dq\n"
AVX_ONLY_CPU = "processor\t: 0\nflags\t\t: fpu sse2 avx\n"


def test_a_cpu_with_avx2_and_fma_gets_the_haswell_kernels() -> None:
    env: dict[str, str] = {}
    configure(env, cpuinfo=AVX512_CPU)
    assert env["OPENBLAS_CORETYPE"] == PINNED_CORETYPE == "Haswell"
    assert env["OPENBLAS_NUM_THREADS"] == env["OMP_NUM_THREADS"] == env["MKL_NUM_THREADS"] == "1"


def test_a_cpu_without_avx2_is_not_pinned() -> None:
    env: dict[str, str] = {}
    configure(env, cpuinfo=AVX_ONLY_CPU)
    assert "OPENBLAS_CORETYPE" not in env
    assert not cpu_has_avx2_fma("no flags line at all")


def test_the_users_own_settings_are_kept() -> None:
    env = {"OPENBLAS_CORETYPE": "SkylakeX", "OPENBLAS_NUM_THREADS": "4"}
    configure(env, cpuinfo=AVX512_CPU)
    assert env["OPENBLAS_CORETYPE"] == "SkylakeX"
    assert env["OPENBLAS_NUM_THREADS"] == "4"


def test_importing_netsim_sets_the_kernels_before_numpy_loads_openblas() -> None:
    env = {k: v for k, v in os.environ.items() if k != "OPENBLAS_CORETYPE"}
    code = "import os, netsim, numpy; print(os.environ.get('OPENBLAS_CORETYPE', 'unset'))"
    out = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True, check=True).stdout
    expected = PINNED_CORETYPE if cpu_has_avx2_fma() else "unset"
    assert out.strip() == expected
