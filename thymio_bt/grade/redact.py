"""What a student may see of the results: a hidden variant's results without its maze, path,
start, moments or the commands that would run it, named only "hidden world N".

The grader keeps everything (results.json is the TA's); student-facing outputs (``grade
--for-students`` pages, the Gradescope file) go through :func:`for_students` first.

Example::

    >>> results = {"assignment": {"variants": [{"name": "course", "visibility": "public"},
    ...     {"name": "box", "maze": "worlds/box.yaml", "start": "0.2,0.1,0", "visibility": "hidden"}]},
    ...     "students": [{"criteria": [{"name": "stop", "feedback": "..."}], "runs": [
    ...         {"variant": "box", "seed": 0, "robot": "real", "final_pose": {"x": 0.2, "y": 0.4},
    ...          "reproduce": "thymio-bt run ...", "trajectory": [[0, 0.2, 0.1, 0]],
    ...          "criteria": {"stop": {"passed": False, "moment": {"t": 4.1, "x": 0.2, "y": 0.4},
    ...              "feedback": "stopped 7.0 cm from the wall, wanted 5.0 +- 0.5 cm", "where": "m.yaml:10"}}}]}]}
    >>> seen = for_students(results)
    >>> seen["assignment"]["variants"][1]
    {'name': 'hidden world 1', 'visibility': 'hidden'}
    >>> seen["students"][0]["runs"][0]
    ... # doctest: +NORMALIZE_WHITESPACE
    {'variant': 'hidden world 1', 'seed': 0, 'robot': 'real', 'criteria': {'stop': {'passed': False,
     'feedback': 'stopped 7.0 cm from the wall, wanted 5.0 +- 0.5 cm', 'where': 'm.yaml:10'}}}
    >>> seen["students"][0]["criteria"][0]["feedback"]
    'hidden world 1: stopped 7.0 cm from the wall, wanted 5.0 +- 0.5 cm (failed 1 of 1 runs)'
"""

from __future__ import annotations

import copy
import re
from typing import Any

#: what a run of a hidden world keeps: no pose, path, moment or command
RUN_KEPT = (
    "index",
    "variant",
    "seed",
    "robot",
    "status",
    "code",
    "reason",
    "failed_path",
    "where",
    "sim_time",
    "collisions",
    "criteria",
)
#: a position in a message ("near (0.60, 0.10)", "at (0.50, 0.30, yaw 90 deg)"): a hidden world's geometry
_POSITION = re.compile(r"\s*(?:near |at )?\(-?\d+(?:\.\d+)?, -?\d+(?:\.\d+)?[^)]*\)")


def hidden_names(results: dict[str, Any]) -> dict[str, str]:
    """Each hidden variant's name and the name students see ("hidden world 1", ...)."""
    variants = results.get("assignment", {}).get("variants", [])
    hidden = [v["name"] for v in variants if v.get("visibility") == "hidden"]
    return {name: f"hidden world {i}" for i, name in enumerate(hidden, 1)}


def for_students(results: dict[str, Any]) -> dict[str, Any]:
    """A copy of ``results`` that carries nothing of a hidden variant a student could run or draw:
    its name, maze, start, seeds' paths, poses, moments and commands are gone, and feedback about
    it reads "hidden world N: stopped 7.0 cm from the wall, wanted 5.0 +- 0.5 cm"."""
    names = hidden_names(results)
    seen = copy.deepcopy(results)
    seen.pop("similar", None)  # the TA's
    assignment = seen.get("assignment", {})
    assignment.pop("file", None)
    assignment["variants"] = [
        {"name": names[v["name"]], "visibility": "hidden"} if v["name"] in names else v
        for v in assignment.get("variants", [])
    ]
    for criterion in assignment.get("criteria", []):
        criterion["variants"] = [names.get(v, v) for v in criterion.get("variants", [])]
    for student in seen.get("students", []):
        student.pop("shape", None)
        runs = student.get("runs", [])
        for i, run in enumerate(runs):
            if run.get("variant") in names:
                runs[i] = _hidden_run(run, run["variant"], names[run["variant"]])
        for criterion in student.get("criteria", []):
            for variant in criterion.get("variants", []):
                if variant["name"] in names:
                    name, variant["name"] = variant["name"], names[variant["name"]]
                    variant["feedback"] = _unsaid(variant.get("feedback"), name, variant["name"])
            _feedback(criterion, runs, names)
    return seen


def _unsaid(text: Any, name: str, label: str) -> Any:
    """``text`` without the positions and the name of the hidden world ``name`` (``label`` instead).

    >>> _unsaid("maze 'box' has no spawn 'part2'; touched a wall near (0.60, 0.10)", "box", "hidden world 1")
    "maze 'hidden world 1' has no spawn 'part2'; touched a wall"
    """
    return _POSITION.sub("", text).replace(name, label) if isinstance(text, str) else text


def _hidden_run(run: dict[str, Any], name: str, label: str) -> dict[str, Any]:
    kept = {k: run[k] for k in RUN_KEPT if k in run}
    kept["variant"] = label
    if "reason" in kept:
        kept["reason"] = _unsaid(kept["reason"], name, label)
    kept["criteria"] = {
        criterion: {
            "passed": judged.get("passed"),
            "feedback": _unsaid(judged.get("feedback"), name, label),
            "where": judged.get("where"),
        }
        for criterion, judged in run.get("criteria", {}).items()
    }
    return kept


def _feedback(criterion: dict[str, Any], runs: list[dict[str, Any]], names: dict[str, str]) -> None:
    """The criterion's feedback again, from the first failed run as students see it."""
    judged = [(r, r["criteria"][criterion["name"]]) for r in runs if criterion["name"] in r.get("criteria", {})]
    failed = [(r, j) for r, j in judged if not j.get("passed")]
    if not failed:
        return
    run, first = failed[0]
    variant = run["variant"]
    if variant in names.values():
        criterion["feedback"] = feedback_line(variant, None, None, first.get("feedback"), len(failed), len(judged))
    else:
        said = first.get("feedback")
        criterion["feedback"] = feedback_line(
            variant, run.get("seed"), run.get("robot"), said, len(failed), len(judged)
        )


def feedback_line(
    variant: str, seed: int | None, robot: str | None, feedback: str | None, failed: int, runs: int
) -> str:
    """A criterion's feedback: its first failed run's, where it failed (its ``variant``, ``seed`` and
    ``robot``; a hidden world's by its name alone, ``seed`` and ``robot`` None), and how many failed.

    >>> feedback_line("course", 0, "course", "took no turn, wanted 4 left turns", 3, 12)
    'took no turn, wanted 4 left turns (variant course, seed 0, robot course; failed 3 of 12 runs)'
    >>> feedback_line("hidden world 1", None, None, "took no turn, wanted 4 left turns", 3, 12)
    'hidden world 1: took no turn, wanted 4 left turns (failed 3 of 12 runs)'
    """
    count = f"failed {failed} of {runs} runs"
    if seed is None and robot is None:
        return f"{variant}: {feedback} ({count})"
    return f"{feedback} (variant {variant}, seed {seed}, robot {robot}; {count})"
