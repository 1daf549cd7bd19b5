"""Every notebook in notebooks/ executes top to bottom (small settings, in a scratch folder)
and draws its figures."""

import pathlib
import shutil

import nbformat
import pytest
from nbclient import NotebookClient


NOTEBOOK_DIR = pathlib.Path(__file__).parent.parent / "notebooks"
NOTEBOOKS = sorted(NOTEBOOK_DIR.glob("*.ipynb"))
#: the tutorials the README links to; each must exist (the glob above would silently skip one)
EXPECTED = ("quickstart.ipynb", "frf_sweep.ipynb", "bed_dynamics.ipynb", "binary_mixtures.ipynb",
            "gap_optimisation.ipynb", "envelope_design.ipynb")


def test_expected_notebooks_present():
    assert set(EXPECTED) <= {p.name for p in NOTEBOOKS}


@pytest.mark.examples  # minutes in total: `pytest -m examples` (CI's second step)
@pytest.mark.parametrize("path", NOTEBOOKS, ids=[p.name for p in NOTEBOOKS])
def test_notebook_executes(path, tmp_path):
    work = tmp_path / path.name
    shutil.copy(path, work)
    nb = nbformat.read(work, as_version=4)
    NotebookClient(nb, timeout=600, kernel_name="python3", resources={"metadata": {"path": str(tmp_path)}}).execute()
    outputs = [o for c in nb.cells if c.cell_type == "code" for o in c.get("outputs", [])]
    errors = [o for o in outputs if o.get("output_type") == "error"]
    assert not errors
    # a tutorial "with figures": at least one rendered image
    assert any("image/png" in o.get("data", {}) for o in outputs), f"{path.name} drew no figure"
