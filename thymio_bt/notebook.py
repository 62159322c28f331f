"""Runs in a Jupyter notebook: ``run(...)`` gives a result that shows itself as the run's page.

``run(mission, set={...})`` runs a mission (a file, a shipped mission's name, or YAML text written in
a cell) in the simulation and returns a :class:`NotebookRun`; a notebook displays it as the run's
page (:mod:`thymio_bt.viz.page`) inline, in an iframe whose ``srcdoc`` holds the whole page: no
server, no extension. ``compare(a, b)`` shows two runs side by side with their first divergence.
The report, the recording and the page's file are there too (``.report``, ``.recording``,
``.save("run.html")``). docs/viewer.md tells more.

Example:

>>> first = run("square", seed=1)
>>> first, first.report["ticks"]
(<run square: SUCCESS after 22.7 s>, 228)
>>> first._repr_html_().startswith('<iframe class="thymio-bt-run" srcdoc="&lt;!doctype html&gt;')
True
>>> both = compare(first, run("square", seed=1, set={"side": "20cm"}))
>>> both.divergence["time"], both.divergence["reason"]  # the 20 cm side turns while the 30 cm one drives on
(2.1, 'poses 1.3 cm apart (ground truth)')
"""

from __future__ import annotations

import html
import os
import tempfile
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from thymio_bt.logs.recording import Recorder, Recording
from thymio_bt.mission import load_mission
from thymio_bt.run.divergence import first_divergence
from thymio_bt.run.result import RunResult, RunStatus
from thymio_bt.run.runner import Run
from thymio_bt.viz.page import page_html, write_page
from thymio_bt.viz.page_data import page_data

#: the inline page's height in a notebook, px: the maze, the tree and the timeline at once
HEIGHT = 720


def _iframe(page: str) -> str:
    """``page`` inline: an iframe whose ``srcdoc`` is the whole page, its scripts sandboxed."""
    return (
        f'<iframe class="thymio-bt-run" srcdoc="{html.escape(page)}" sandbox="allow-scripts" '
        f'style="box-sizing: border-box; width: 100%; height: {HEIGHT}px; border: 1px solid #d5dbe0;"></iframe>'
    )


@dataclass(repr=False)
class NotebookRun:
    """One run: its result (:class:`~thymio_bt.run.result.RunResult`) and its recording; shown in a
    notebook as its page."""

    result: RunResult
    recording: Recording
    label: str = ""

    @property
    def status(self) -> RunStatus:
        """SUCCESS, FAILURE or TIMEOUT."""
        return self.result.status

    @property
    def report(self) -> dict[str, Any]:
        """The run report, as ``run --report`` writes it."""
        return self.result.report()

    def __repr__(self) -> str:
        """One line (a notebook's plain-text view): the label, the status and the simulated time."""
        return f"<run {self.label}: {self.status} after {self.result.sim_time:.1f} s>"

    def save(self, path: str | Path) -> Path:
        """Write the run's page to ``path`` (as ``run --html`` does); the path written."""
        return write_page([self.recording], path, labels=[self.label])

    def _repr_html_(self) -> str:
        """The run's page, inline (what Jupyter shows for a cell's result)."""
        return _iframe(page_html([page_data(self.recording, self.label)]))


@dataclass(repr=False)
class Comparison:
    """Two runs side by side, aligned by simulated time, with their first divergence (None: none)."""

    a: NotebookRun
    b: NotebookRun
    divergence: dict[str, Any] | None = field(default=None)

    def __repr__(self) -> str:
        """One line: the two runs and where they part ways."""
        where = f"diverge at t = {self.divergence['time']} s" if self.divergence else "do not diverge"
        return f"<runs {self.a.label} and {self.b.label}: {where}>"

    def save(self, path: str | Path) -> Path:
        """Write the two runs' page to ``path``; the path written."""
        return write_page([self.a.recording, self.b.recording], path, self.divergence, [self.a.label, self.b.label])

    def _repr_html_(self) -> str:
        """The two runs' page, inline."""
        runs = [page_data(self.a.recording, self.a.label), page_data(self.b.recording, self.b.label)]
        return _iframe(page_html(runs, self.divergence))


def run(
    mission: str | Path,
    *,
    set: Mapping[str, Any] | None = None,  # noqa: A002  # the name of the command line's --set
    seed: int | None = None,
    maze: str | Path | None = None,
    start: str | None = None,
    label: str = "",
) -> NotebookRun:
    """Run ``mission`` in the simulation and return it, to show or to read. ``mission`` is a file,
    a shipped mission's name, or YAML text (several lines: a cell's mission, whose relative paths
    are read from the current folder); ``set`` overrides parameters as ``--set`` does."""
    overrides = {str(k): str(v) for k, v in (set or {}).items()}
    text = str(mission)
    if isinstance(mission, str) and "\n" in text:
        handle, name = tempfile.mkstemp(suffix=".yaml", prefix=".cell-", dir=".")
        try:
            with os.fdopen(handle, "w", encoding="utf-8") as file:
                file.write(text)
            spec = load_mission(name, overrides, maze=maze, start=start)
        finally:
            os.unlink(name)
    else:
        spec = load_mission(mission, overrides, maze=maze, start=start)
    recorder = Recorder(statuses=True)
    result = Run(spec, seed).run(on_tick=recorder)
    default = spec.name + "".join(f" {k}={v}" for k, v in overrides.items())
    return NotebookRun(result, recorder.finish(result), label or default)


def compare(a: NotebookRun, b: NotebookRun) -> Comparison:
    """``a`` and ``b`` side by side (shown as one page), with where they first part ways."""
    found = first_divergence(a.recording, b.recording)
    divergence = None if found is None else found.mark()
    return Comparison(a, b, divergence)


__all__ = ["Comparison", "NotebookRun", "compare", "run"]
