"""Golden traces: a compact digest of every shipped scenario's run folder.

A digest holds, per CSV file of the run folder (and the resolved ``scenario.yaml``), its SHA-256, its row
count and, for every numeric column, the sum and the largest absolute value (so that a changed hash also
says *where* the output moved), plus the run's status and every metric value. ``meta.json`` is left out:
it holds wall-clock times.

Regenerate after a change that is meant to move an output (and say why in the commit)::

    python tests/golden/golden_traces.py                 # every shipped scenario
    python tests/golden/golden_traces.py hdd_case1 cart  # only these
"""

from __future__ import annotations

import hashlib
import json
import math
import sys
import tempfile
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parents[2]
SCENARIOS = ROOT / "scenarios"
DIGESTS = Path(__file__).resolve().parent / "digests"
FILES = ("scenario.yaml", "signals.csv", "jobs.csv", "messages.csv", "metrics.csv")


def shipped_scenarios() -> list[str]:
    """Names of the shipped single-run scenarios (sweep files are left out: they name a base scenario)."""
    names = []
    for path in sorted(SCENARIOS.glob("*.yaml")):
        head = path.read_text(encoding="utf-8")
        if any(line.startswith("sweep:") for line in head.splitlines()):
            continue
        names.append(path.stem)
    return names


def _finite(x: float) -> float | str:
    return float(x) if math.isfinite(x) else repr(float(x))


def digest_folder(folder: Path) -> dict[str, Any]:
    """The digest of one run folder."""
    import pandas as pd

    out: dict[str, Any] = {"files": {}}
    for name in FILES:
        path = folder / name
        if not path.exists():
            out["files"][name] = None
            continue
        data = path.read_bytes()
        entry: dict[str, Any] = {"sha256": hashlib.sha256(data).hexdigest()}
        if name.endswith(".csv"):
            frame = pd.read_csv(path)
            entry["rows"] = int(len(frame))
            cols = {}
            for col in frame.columns:
                if pd.api.types.is_numeric_dtype(frame[col]) and not pd.api.types.is_bool_dtype(frame[col]):
                    v = frame[col].astype(float)
                    cols[str(col)] = {"sum": _finite(float(v.sum())), "max_abs": _finite(float(v.abs().max()))
                                      if len(v.dropna()) else None}
            entry["columns"] = cols
        out["files"][name] = entry
    meta = json.loads((folder / "meta.json").read_text(encoding="utf-8"))
    out["status"] = meta.get("status")
    metrics = pd.read_csv(folder / "metrics.csv")
    out["metrics"] = {str(k): _finite(float(v)) for k, v in zip(metrics["metric"], metrics["value"])}
    return out


def run_and_digest(name: str) -> dict[str, Any]:
    """Run ``scenarios/<name>.yaml`` in this process into a temporary folder and digest the run folder."""
    import netsim

    with tempfile.TemporaryDirectory() as tmp:
        # allow_plugins: the shipped scenarios are trusted (dc_servo_fmu loads an FMU, which is code)
        result = netsim.run(SCENARIOS / f"{name}.yaml", out=Path(tmp) / name, allow_plugins=True)
        return digest_folder(Path(result.out_dir))


def digest_path(name: str) -> Path:
    return DIGESTS / f"{name}.json"


def write_digest(name: str) -> Path:
    DIGESTS.mkdir(parents=True, exist_ok=True)
    path = digest_path(name)
    path.write_text(json.dumps(run_and_digest(name), indent=1, sort_keys=True) + "\n", encoding="utf-8")
    return path


if __name__ == "__main__":
    for scenario in sys.argv[1:] or shipped_scenarios():
        sys.stdout.write(f"{write_digest(scenario)}\n")
