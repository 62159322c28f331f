"""The replays of ``grade --html``: the viewer's page (:mod:`thymio_bt.viz.page`) of the failed runs
a student's page lists, opened at the failing moment, with each missed criterion's verdict on the
timeline (an event of kind ``verdict``).

Only the first failed run of each variant and each thing that went wrong (a criterion missed, or
the run not ending in SUCCESS) is replayed, so a class costs a page per mistake, not per run. The run
is recorded where it is graded (the grader's worker, for a confined submission too: its tree's
process is never run again); :func:`replay_data` turns the recording into the page's data, which
travels in the run's message, is taken out of the results before results.json is written
(:func:`take_replays`) and written into the site as ``replays/STUDENT_VARIANT_seedN.html``. A page
for students never has a hidden variant's replay.

Example (what a failed run is replayed for, and its failing moment):

>>> from thymio_bt.grade.results import Judged, RunRecord
>>> from thymio_bt.run.result import RunStatus
>>> run = RunRecord(index=0, variant="course", seed=0, robot="course", status=RunStatus.SUCCESS, sim_time=30.0,
...     criteria={"stops 5 cm from the wall": Judged(passed=False, feedback="stopped 7.0 cm", moment={"t": 12.34}),
...               "no collision": Judged(passed=True)})
>>> went_wrong(run), failing_moment(run)
(['stops 5 cm from the wall'], 12.34)
>>> timeout = run.model_copy(update={"status": RunStatus.TIMEOUT, "criteria": {}, "sim_time": 8.0})
>>> went_wrong(timeout), failing_moment(timeout)
(['ended'], 8.0)
"""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING, Any
from urllib.parse import quote

from thymio_bt.grade.site_page import as_dict, as_list, safe_name
from thymio_bt.run.result import RunStatus

if TYPE_CHECKING:
    from thymio_bt.grade.results import ClassResults, Judged, RunRecord
    from thymio_bt.logs.recording import Recording

REPLAYS = "replays"  # the folder of the replay pages, inside DIR
#: what ``went_wrong`` calls a run that did not end in SUCCESS
ENDED = "ended"


def went_wrong(run: RunRecord) -> list[str]:
    """What ``run`` went wrong in: the criteria it missed, and :data:`ENDED` when it did not end in
    SUCCESS."""
    missed = [name for name, v in run.criteria.items() if not v.passed]
    return missed + ([ENDED] if run.status != RunStatus.SUCCESS else [])


def _moment(verdict: Judged, run: RunRecord) -> float:
    moment = (verdict.moment or {}).get("t")
    return moment if moment is not None else run.sim_time


def failing_moment(run: RunRecord) -> float:
    """The simulated time the replay opens at: the first missed criterion's moment, else the run's end."""
    missed = [run.criteria[name] for name in went_wrong(run) if name != ENDED]
    timed = [m for m in missed if (m.moment or {}).get("t") is not None]
    return _moment(timed[0], run) if timed else run.sim_time


def replay_data(recording: Recording, run: RunRecord) -> dict[str, Any]:
    """The page data of ``recording`` (the viewer's JSON, of the run ``run``), each missed criterion's
    verdict an event at its moment (the run's end when it has none), and the moment to open at."""
    from thymio_bt.viz.page_data import page_data

    data = page_data(recording, f"{run.variant} seed {run.seed}")
    verdicts = [
        {"t": round(_moment(v, run), 3), "kind": "verdict", "name": name, "reason": v.feedback}
        for name, v in run.criteria.items()
        if not v.passed
    ]
    data["events"] = sorted(data["events"] + verdicts, key=lambda e: float(e["t"]))
    data["failing"] = round(failing_moment(run), 3)
    return data


def take_replays(results: ClassResults) -> dict[tuple[str, int], dict[str, Any]]:
    """Take the replays out of ``results``' runs (they are not results.json's): by student and run index."""
    taken = {}
    for student in results.students:
        for run in student.runs:
            if run.replay is not None:
                taken[(student.name, run.index)] = run.replay
                run.replay = None
    return taken


def write_replays(
    results: dict[str, Any],
    replays: dict[tuple[str, int], dict[str, Any]],
    out_dir: Path,
    stems: list[str],
    for_students: bool = False,
) -> list[Path]:
    """Write the replay page of each run of ``results`` that has one in ``replays`` into
    ``out_dir/replays`` and set the run's ``replay_page`` (its link from a student's page, with the
    failing moment); ``for_students``: never one of a hidden variant's run. The paths written."""
    from thymio_bt.outputs import Output
    from thymio_bt.viz.page import page_html

    variants = [as_dict(v) for v in as_list(as_dict(results.get("assignment")).get("variants"))]
    hidden = {str(v.get("name")) for v in variants if v.get("visibility") != "public"} if for_students else set()
    written = []
    for student, stem in zip(as_list(results.get("students")), stems, strict=True):
        for run in as_list(as_dict(student).get("runs")):
            data = replays.get((str(student.get("name")), int(run.get("index", -1))))
            if data is None or str(run.get("variant")) in hidden:
                continue
            name = f"{stem}_{safe_name(run.get('variant'))}_seed{int(run.get('seed', 0))}.html"
            path = out_dir / REPLAYS / name
            title = f"{student.get('name')}: {run.get('variant')} seed {run.get('seed')}"
            Output(path, "--html", stdout_ok=False).write_text(page_html([data], title=title))
            run["replay_page"] = f"../{REPLAYS}/{quote(name)}#t={data['failing']:g}"
            written.append(path)
    return written
