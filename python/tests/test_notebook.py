"""docs/python-example.ipynb runs from start to end (two whole-video runs: a few minutes)."""

import pytest

from conftest import ROOT

NOTEBOOK = ROOT / "docs" / "python-example.ipynb"


def test_example_notebook_runs(video):
    nbformat = pytest.importorskip("nbformat")
    nbclient = pytest.importorskip("nbclient")
    nb = nbformat.read(NOTEBOOK, as_version=4)
    # Committed without outputs.
    assert all(not c.get("outputs") for c in nb.cells if c.cell_type == "code")
    client = nbclient.NotebookClient(
        nb,
        timeout=1200,
        kernel_name="python3",
        # jupyter_client starts the kernel with this interpreter (the venv with gait).
        resources={"metadata": {"path": str(NOTEBOOK.parent)}},
    )
    client.execute()
    errors = [o for c in nb.cells for o in c.get("outputs", []) if o.output_type == "error"]
    assert errors == []
    images = [
        o for c in nb.cells for o in c.get("outputs", []) if "image/png" in o.get("data", {})
    ]
    assert len(images) >= 2, "the knee curve figures"
    # The last cell: the spatiotemporal parameters of both runs side by side.
    last = nb.cells[-1].outputs[-1]["data"]["text/plain"]
    assert "cadence" in last and "mean ort" in last
