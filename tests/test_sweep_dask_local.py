"""The local Dask cluster of a sweep (``--dask-local``): no dashboard, and no HTTP at all, unless asked for.

Before: ``dashboard_address=None`` still had the scheduler serve its info pages on port 8787
(``scheduler_info()["services"] == {"dashboard": 8787}``, ``/info/main/workers.html`` answered 200).
An in-process cluster (``processes=False``) keeps this test fast; the scheduler is the same object either way.
"""

from __future__ import annotations

import socket
import urllib.error
import urllib.request

import pytest

from netsim.sweep.executor import open_executor


def _answers_http(port: int) -> bool:
    try:
        with urllib.request.urlopen(f"http://127.0.0.1:{port}/info/main/workers.html", timeout=5) as r:
            return r.status == 200
    except (urllib.error.URLError, OSError):
        return False


def _listening(port: int) -> bool:
    with socket.socket() as s:
        s.settimeout(2)
        return s.connect_ex(("127.0.0.1", port)) == 0


@pytest.mark.parametrize("dashboard", [None, "127.0.0.1:0"])
def test_local_dask_dashboard_is_off_unless_asked_for(dashboard: str | None) -> None:
    with open_executor(local_dask=True, workers=1, dashboard=dashboard,
                       cluster_kwargs={"processes": False}) as (executor, _, desc):
        scheduler = executor.client.cluster.scheduler  # type: ignore[attr-defined]
        port = scheduler.http_server.port
        services = executor.client.scheduler_info()["services"]  # type: ignore[attr-defined]
        if dashboard is None:  # before: {'dashboard': 8787} and the info pages answered there
            assert "dashboard" not in services and "dashboard" not in desc
            assert not _listening(port)
        else:
            assert services.get("dashboard") == port and f":{port}" in desc
            assert _answers_http(port)


def test_cli_dask_dashboard_needs_dask_local(tmp_path, capsys) -> None:
    from netsim.cli import main

    sweep = tmp_path / "s.yaml"
    sweep.write_text("sweep: s\n")
    assert main(["sweep", str(sweep), "--dask-dashboard", "127.0.0.1:8787"]) == 2
    err = capsys.readouterr().err
    assert "--dask-dashboard needs --dask-local" in err and "Traceback" not in err
