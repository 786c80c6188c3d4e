"""examples/mission.ipynb runs on a Python kernel (nbclient, ipykernel), as Jupyter runs it
from its folder, and shows what it says: the net's drawing, its verdicts and a run, as this
process computes them."""
from __future__ import annotations

import pytest

from mcl2pnml import notebook, pipeline

from helpers import ROOT

nbformat = pytest.importorskip("nbformat", reason="nbformat is in the test extra (make setup)")
nbclient = pytest.importorskip("nbclient", reason="nbclient is in the test extra (make setup)")
pytest.importorskip("ipykernel", reason="ipykernel is in the test extra (make setup)")

EXAMPLES = ROOT / "examples"
NOTEBOOK = EXAMPLES / "mission.ipynb"


def test_the_example_notebook_shows_the_drawing_and_the_verdicts():
    nb = nbformat.read(NOTEBOOK, as_version=4)
    assert not [o for c in nb.cells if c.cell_type == "code" for o in c.outputs], \
        "the notebook is kept without its outputs: they are made by running it"
    nbclient.NotebookClient(nb, timeout=120, kernel_name="python3",
                            resources={"metadata": {"path": str(EXAMPLES)}}).execute()
    outputs = [o for c in nb.cells if c.cell_type == "code" for o in c.outputs]
    assert [o.output_type for o in outputs if o.output_type in ("error", "stream")] == []
    data = [o.data for o in outputs if o.output_type == "execute_result"]
    net = pipeline.compile_file(EXAMPLES / "sauce.mcl")
    [svg] = [d["image/svg+xml"] for d in data if "image/svg+xml" in d]
    assert "<svg" in svg and f"<title>{net.name}</title>" in svg
    html = [d["text/html"] for d in data if "text/html" in d]
    assert notebook.analysis_html(pipeline.analyze(net, state_space_only=True)) in html
    run = pipeline.run_mission(EXAMPLES / "sauce.mcl")
    assert notebook.run_html(run) in html
