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

>>> run = {"status": "SUCCESS", "sim_time": 30.0, "criteria": {
...     "stops 5 cm from the wall": {"passed": False, "feedback": "stopped 7.0 cm", "moment": {"t": 12.34}},
...     "no collision": {"passed": True}}}
>>> went_wrong(run), failing_moment(run)
(['stops 5 cm from the wall'], 12.34)
>>> went_wrong(run | {"status": "TIMEOUT"}), failing_moment({"status": "FAILURE", "sim_time": 8.0})
(['stops 5 cm from the wall', 'ended'], 8.0)
"""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING, Any
from urllib.parse import quote

from thymio_bt.grade.site_page import as_dict, as_list, safe_name

if TYPE_CHECKING:
    from thymio_bt.logs.recording import Recording

REPLAYS = "replays"  # the folder of the replay pages, inside DIR
#: what ``went_wrong`` calls a run that did not end in SUCCESS
ENDED = "ended"


def went_wrong(run: dict[str, Any]) -> list[str]:
    """What ``run`` (a ``run`` message) went wrong in: the criteria it missed, and :data:`ENDED`
    when it did not end in SUCCESS."""
    missed = [name for name, v in as_dict(run.get("criteria")).items() if as_dict(v).get("passed") is False]
    return missed + ([ENDED] if run.get("status") != "SUCCESS" else [])


def _moment(verdict: dict[str, Any], run: dict[str, Any]) -> float:
    moment = as_dict(verdict.get("moment")).get("t")
    return float(moment) if isinstance(moment, int | float) else float(run.get("sim_time") or 0.0)


def failing_moment(run: dict[str, Any]) -> float:
    """The simulated time the replay opens at: the first missed criterion's moment, else the run's end."""
    criteria = as_dict(run.get("criteria"))
    missed = [as_dict(criteria[name]) for name in went_wrong(run) if name != ENDED]
    timed = [m for m in missed if isinstance(as_dict(m.get("moment")).get("t"), int | float)]
    return _moment(timed[0], run) if timed else float(run.get("sim_time") or 0.0)


def replay_data(recording: Recording, run: dict[str, Any]) -> dict[str, Any]:
    """The page data of ``recording`` (the run of the message ``run``), each missed criterion's verdict
    an event at its moment (the run's end when it has none), and the moment to open at."""
    from thymio_bt.viz.page_data import page_data

    data = page_data(recording, f"{run['variant']} seed {run['seed']}")
    verdicts = [
        {"t": round(_moment(as_dict(v), run), 3), "kind": "verdict", "name": name, "reason": as_dict(v).get("feedback")}
        for name, v in as_dict(run.get("criteria")).items()
        if as_dict(v).get("passed") is False
    ]
    data["events"] = sorted(data["events"] + verdicts, key=lambda e: float(e["t"]))
    data["failing"] = round(failing_moment(run), 3)
    return data


def take_replays(results: dict[str, Any]) -> dict[tuple[str, int], dict[str, Any]]:
    """Take the replays out of ``results``' runs (they are not results.json's): by student and run index."""
    taken = {}
    for student in as_list(results.get("students")):
        for run in as_list(as_dict(student).get("runs")):
            if isinstance(run, dict) and "replay" in run:
                taken[(str(student.get("name")), int(run.get("index", -1)))] = run.pop("replay")
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
