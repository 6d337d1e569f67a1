"""The example notebooks run from top to bottom (so that they cannot rot). Both run in one
kernel, one after the other with the namespace reset in between (a kernel start and the
imports cost more than the notebooks)."""
from pathlib import Path

from nbclient import NotebookClient
import nbformat
from nbformat.v4 import new_code_cell
import pytest

EXAMPLES = Path(__file__).resolve().parent.parent / "examples"
NOTEBOOKS = ("first_flight.ipynb", "cog_step.ipynb")


@pytest.mark.slow
def test_notebooks_run(tmp_path, monkeypatch):
    monkeypatch.setenv("MPLBACKEND", "Agg")
    books = [nbformat.read(EXAMPLES / name, as_version=4) for name in NOTEBOOKS]
    combined = nbformat.v4.new_notebook(metadata=books[0].metadata)
    for nb in books:
        combined.cells += [new_code_cell("%reset -f")] + nb.cells
    client = NotebookClient(combined, timeout=300, kernel_name="python3",
                            resources={"metadata": {"path": str(tmp_path)}})
    client.execute()           # raises CellExecutionError naming the cell on any error
    start = 0
    for name, nb in zip(NOTEBOOKS, books):
        cells = combined.cells[start + 1:start + 1 + len(nb.cells)]
        start += 1 + len(nb.cells)
        outputs = [o for c in cells if c.cell_type == "code" for o in c.get("outputs", [])]
        assert not [o for o in outputs if o.output_type == "error"], name
        assert [o for o in outputs if "image/png" in o.get("data", {})], f"{name}: no figure"
    # cog_step flies a law written in the notebook beside the built-in ones (its summary line)
    texts = [o.get("data", {}).get("text/plain", "") for o in outputs]
    assert any("yours (position PID)" in t and "cascade PD" in t and "adaptive FL" in t
               for t in texts), texts
    # nothing written into the repository by running them
    assert sorted(p.name for p in EXAMPLES.iterdir()) == sorted(NOTEBOOKS)


def test_notebooks_are_stored_without_outputs():
    for name in NOTEBOOKS:
        nb = nbformat.read(EXAMPLES / name, as_version=4)
        assert all(not c.get("outputs") for c in nb.cells if c.cell_type == "code"), name


def test_cog_step_writes_a_controller_of_its_own():
    """The notebook that promises "a controller of your own" has one: a Python callable
    ``(t, x, ref, c)`` written in it, flown on the python path through the CoG step against
    built-in laws (not only built-in laws with other poles)."""
    nb = nbformat.read(EXAMPLES / "cog_step.ipynb", as_version=4)
    code = "\n".join(c.source for c in nb.cells if c.cell_type == "code")
    assert "def __call__(self, t, x, ref, c):" in code
    assert '"python")' in code and "CogProfile(" in code
    assert "CascadePD(" in code and "AdaptiveFeedbackLinearization(" in code
