"""Dask's own INFO logging is silenced during a sweep unless the user asked for -v (issue 21)."""

import logging

from netsim.sweep.executor import _quiet_dask_logs


def _level_inside(netsim_level: int) -> int:
    netsim_logger = logging.getLogger("netsim")
    old = netsim_logger.level
    netsim_logger.setLevel(netsim_level)
    try:
        with _quiet_dask_logs():
            return logging.getLogger("distributed.client").getEffectiveLevel()
    finally:
        netsim_logger.setLevel(old)


def test_dask_is_quiet_by_default_and_speaks_with_minus_v() -> None:
    assert _level_inside(logging.WARNING) > logging.CRITICAL          # netsim run/sweep without -v
    import distributed  # noqa: F401 - configures its loggers

    untouched = logging.getLogger("distributed.client").getEffectiveLevel()
    assert untouched <= logging.CRITICAL
    assert _level_inside(logging.INFO) == untouched                    # -v: Dask's logging as Dask set it
