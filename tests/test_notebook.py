"""The example notebook (issue 17 item 3) runs, and its executed copy holds the same code.

``examples/paper_section6.py`` (jupytext percent format) is converted to a notebook and
executed with nbclient in a fresh kernel; its own cells assert the paper's section 6
numbers (BECD25 = 24, FECD25 = 0.52, to the paper's two figures). The rendered
``examples/paper_section6.ipynb`` (linked from docs/api.md) must hold the same code
cells, so that the rendered notebook is never older than the tested one. Regenerate it
with ``python tests/test_notebook.py``.
"""

from __future__ import annotations

import importlib
from pathlib import Path
from typing import Any

import pytest

from tests.conftest import require

ROOT = Path(__file__).resolve().parent.parent
SOURCE = ROOT / "examples" / "paper_section6.py"
RENDERED = SOURCE.with_suffix(".ipynb")


def _code(notebook: Any) -> list[str]:
    return [cell.source.strip() for cell in notebook.cells if cell.cell_type == "code"]


def execute() -> Any:
    """The notebook of SOURCE, executed in the examples folder."""
    jupytext: Any = importlib.import_module("jupytext")
    nbclient: Any = importlib.import_module("nbclient")

    notebook = jupytext.read(SOURCE)
    client = nbclient.NotebookClient(
        notebook,
        timeout=600,
        kernel_name="python3",
        resources={"metadata": {"path": str(SOURCE.parent)}},
    )
    client.execute()
    return notebook


@pytest.mark.slow
@pytest.mark.filterwarnings("ignore::DeprecationWarning")
@pytest.mark.filterwarnings("ignore::RuntimeWarning")
def test_the_example_notebook_runs() -> None:
    require("nbclient")
    require("jupytext")
    require("ipykernel")
    notebook = execute()  # raises CellExecutionError, with the cell, if a cell fails
    outputs = [o for cell in notebook.cells for o in cell.get("outputs", [])]
    pictures = [o for o in outputs if "image/png" in o.get("data", {})]
    assert len(pictures) == 6  # Fig. 4, 5, 6, then angle, speed and torque-speed
    printed = "".join(o.get("text", "") for o in outputs if o.get("output_type") == "stream")
    assert "BECD25 = 23.65 N*m*s/rad (paper: 24)" in printed  # tests/hand.py's becd(25)


def test_the_rendered_notebook_has_the_same_code() -> None:
    jupytext = require("jupytext")
    nbformat = require("nbformat")
    rendered = nbformat.read(RENDERED, as_version=4)
    assert _code(rendered) == _code(jupytext.read(SOURCE))
    # and it was executed: every code cell has run
    assert all(
        cell.execution_count is not None for cell in rendered.cells if cell.cell_type == "code"
    )


if __name__ == "__main__":  # regenerate examples/paper_section6.ipynb
    nbformat: Any = importlib.import_module("nbformat")
    nbformat.write(execute(), RENDERED)
    print(f"wrote {RENDERED}")
