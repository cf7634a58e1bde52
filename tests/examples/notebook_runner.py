"""Run one notebook of examples/ in a fresh Jupyter kernel, in a given working folder (nbclient).

Used by test_notebooks.py, and runnable without pytest, e.g. with the python of a fresh venv that holds the
built wheel plus nbclient and ipykernel (issue 27, "Done when": a gallery notebook from the installed wheel)::

    python tests/examples/notebook_runner.py examples/01_dc_servo_can.ipynb /tmp/empty-folder

It exits 1 with the failing cell's traceback when a cell raises (the notebooks' own ``assert`` cells included).
"""

from __future__ import annotations

import os
import sys
from pathlib import Path

import nbformat


def execute(notebook: str | Path, folder: str | Path, timeout: float = 900) -> nbformat.NotebookNode:
    """Execute ``notebook`` top to bottom with ``folder`` as the kernel's working folder; return it with outputs.

    The kernel is the ``python3`` kernel of the running interpreter, started with this process's environment
    except ``MPLBACKEND`` (a user's fresh kernel has none; under ``Agg``, which tests/conftest.py sets, pyplot
    figures would not display inline).

    Raises
    ------
    nbclient.exceptions.CellExecutionError
        Naming the failing cell and its traceback.
    """
    from nbclient import NotebookClient

    nb = nbformat.read(Path(notebook), as_version=4)
    env = {key: value for key, value in os.environ.items() if key != "MPLBACKEND"}
    client = NotebookClient(nb, timeout=timeout, kernel_name="python3",
                            resources={"metadata": {"path": str(folder)}})
    client.execute(env=env)
    return nb


def image_count(nb: nbformat.NotebookNode) -> int:
    """How many PNG images the executed notebook's code cells display."""
    return sum("image/png" in out.get("data", {}) for cell in nb.cells if cell.cell_type == "code"
               for out in cell.outputs)


def main(argv: list[str]) -> int:
    if len(argv) != 2:
        sys.stderr.write("usage: notebook_runner.py NOTEBOOK FOLDER\n")
        return 2
    nb = execute(argv[0], argv[1])
    print(f"{argv[0]}: ran, {image_count(nb)} images")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
