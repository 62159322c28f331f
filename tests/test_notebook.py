"""examples/notebooks/part1.ipynb run with nbclient and a real kernel, as a student would run it, and
each page it displays checked in headless Chromium like any other page: no console error, no
request, the DOM contract (and the comparison's divergence). Needs the ``notebook`` extra."""

from __future__ import annotations

import html
import re
from pathlib import Path

import pytest
from _require import module
from test_viewer import CONTRACT, artefacts, screenshot  # noqa: F401  # artefacts: a fixture

ROOT = Path(__file__).resolve().parent.parent
NOTEBOOK = ROOT / "examples" / "notebooks" / "part1.ipynb"


@pytest.fixture(scope="module")
def executed():
    """The notebook's cells and outputs after a run in a fresh kernel."""
    nbformat = module("nbformat")
    nbclient = module("nbclient")
    module("ipykernel")
    notebook = nbformat.read(NOTEBOOK, as_version=4)
    client = nbclient.NotebookClient(
        notebook, timeout=300, kernel_name="python3", resources={"metadata": {"path": str(NOTEBOOK.parent)}}
    )
    client.execute()
    return notebook


def pages(notebook) -> list[tuple[str, str]]:
    """Each displayed rich result: (its plain text, its HTML)."""
    return [
        (output["data"]["text/plain"], output["data"]["text/html"])
        for cell in notebook.cells
        if cell.cell_type == "code"
        for output in cell.outputs
        if "text/html" in output.get("data", {})
    ]


def test_the_notebook_runs_and_shows_both_runs_and_their_comparison(executed):
    errors = [o for c in executed.cells if c.cell_type == "code" for o in c.outputs if o["output_type"] == "error"]
    assert errors == []
    shown = pages(executed)
    assert [text.split(":")[0] for text, _ in shown] == [
        "<run stop 5 cm",
        "<run stop 8 cm",
        "<runs stop 5 cm and stop 8 cm",
    ]
    assert "diverge at t = " in shown[2][0]
    assert all(page.startswith('<iframe class="thymio-bt-run" srcdoc="') for _, page in shown)
    assert not list(NOTEBOOK.parent.glob(".cell-*"))  # the cell's mission file is gone


def test_every_page_the_notebook_shows_opens_cleanly(executed, browser, tmp_path):  # noqa: F811
    shown = pages(executed)
    for k, (_, output) in enumerate(shown):
        wrapper = tmp_path / f"output{k}.html"
        wrapper.write_text(f"<!doctype html><title>output {k}</title>{output}")
        tab = browser.open(wrapper.as_uri(), 1280, 800)
        assert tab.problems() == [], k
        assert tab.evaluate("document.querySelector('iframe').getBoundingClientRect().height") == 720
        if k == 2:
            screenshot(tab, artefacts(tmp_path) / "viewer_notebook_compare.png", 1280, 760)
        tab.close()
        match = re.fullmatch(r'<iframe class="thymio-bt-run" srcdoc="([^"]*)".*', output, re.S)
        assert match is not None
        page = tmp_path / f"page{k}.html"
        page.write_text(html.unescape(match.group(1)))
        tab = browser.open(page.as_uri() + "#t=1000")  # past the end: the last tick
        assert tab.problems() == [], k
        dom = tab.evaluate(CONTRACT if k < 2 else "document.documentElement.dataset.divergence")
        if k < 2:
            assert dom["nodes"] == {"part 1": "SUCCESS"} and dom["clocks"] == 1 and dom["pose"]
        else:
            assert float(dom) > 0
        tab.close()
